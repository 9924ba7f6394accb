#pragma once
// A crowd of one behaviour for the simulator: the people of a scene moved by one model, stepped
// at a fixed period, each person's state read per world step.
//
//   recorded  a Recording replayed (every track is a person); never reacts to anything
//   social    the social force model; walkers see the robot and give way to it
//   blind     the same walkers with the robot invisible (CrowdNav's invisible-robot setting):
//             they still avoid walls and each other, and walk through the robot's place
//   orca      ORCA humans as in CrowdNav: they avoid each other, never the robot, and ignore walls
//
// The simulated behaviours advance in whole model steps of step_s, so the result depends only
// on how many steps were taken, never on how the world's calls split them: stepping to 10 s in
// one call is bit-identical to stepping there in 0.01 s increments. Everything is allocated in
// create(); advance() and state() never allocate.
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <string_view>
#include <vector>

#include "sen3bot/crowd/orca.hpp"
#include "sen3bot/crowd/recording.hpp"
#include "sen3bot/crowd/replay.hpp"
#include "sen3bot/crowd/social_force.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/msg/point_math.hpp"

namespace sen3bot::crowd {

enum class Behaviour : std::uint8_t { recorded, social, blind, orca };

// "recorded", "social", "blind", "orca" (and parse_behaviour takes exactly those back).
[[nodiscard]] const char* to_string(Behaviour behaviour) noexcept;
[[nodiscard]] std::optional<Behaviour> parse_behaviour(std::string_view text) noexcept;

// A simulated person (social, blind, orca).
struct Person {
  Point2D start;
  std::array<Point2D, kMaxGoals> goals{};  // the route, goals[0] first
  std::size_t goal_count = 0;              // 0: stands at start
  double desired_speed_m_s = 1.3;          // ORCA: also the speed limit
  double radius_m = 0.25;
  double appear_s = 0.0;       // not in the scene before this crowd time (enters at start)
  bool leave_at_goal = false;  // vanishes once past its last goal (walked out of the scene)
  bool loop = false;           // after the last goal, walks the route again from goals[0]
  std::uint32_t group = 0;     // > 0: walks with the others of this group (social, blind)
};

struct CrowdConfig {
  Behaviour behaviour = Behaviour::social;
  std::vector<Person> people;                  // social, blind, orca
  std::vector<Wall> walls;                     // social and blind (ORCA ignores walls)
  std::shared_ptr<const Recording> recording;  // recorded: every track is a person
  Point2D recording_offset;                    // added to recorded positions (the scene frame)
  double recording_start_s = 0.0;              // the recording's time at the crowd's time 0
  double radius_m = 0.25;                      // body radius of recorded people
  double step_s = 0.05;                        // model update period (social, blind, orca)
  // goal_reach_m is also where ORCA humans pass a goal, so both models follow routes alike.
  SocialForceModel::Params social;
  OrcaParams orca;
};

// An invisible person (not yet appeared, gone, or outside its recorded track) has zero position
// and velocity: nothing of it may be used.
struct PersonState {
  Point2D position;
  Point2D velocity;
  double radius_m = 0.0;
  bool visible = false;
};

class Crowd {
 public:
  // Checks the config (a positive finite step and model parameters; every person's start,
  // goals, speed, radius and appearance time finite, speed and radius positive, at most kMaxGoals
  // goals, a leaver with a goal to leave at; at most kMaxWalkers people for social and blind,
  // kMaxOrcaAgents for ORCA; walls with finite ends; a recorded crowd needs a recording whose
  // tracks are non-empty with strictly increasing finite times and positions finite once offset)
  // and allocates everything the crowd will use. Fields another behaviour uses are ignored. Errors
  // name the person, wall or track by index. The crowd starts at time 0 with the people whose
  // appear_s is not after it.
  [[nodiscard]] static Result<std::unique_ptr<Crowd>> create(const CrowdConfig& config);

  Crowd(const Crowd&) = delete;
  Crowd& operator=(const Crowd&) = delete;

  // People (recorded: tracks).
  [[nodiscard]] std::size_t size() const noexcept { return states_.size(); }

  // Advances to crowd time `time_s`. Simulated people take every whole step of step_s up to it
  // (the k-th ends at k * step_s; 1e-9 s of slack absorbs a caller's rounding), none when time_s
  // is not past the next step; the robot, as a disc standing where given for those steps, is seen
  // by social walkers only (blind walkers and ORCA humans never react to it); null means no
  // robot. Someone appears at the first step end at or after their appear_s. Recorded people are
  // replayed at exactly time_s and ignore the robot. A time going backwards, or not finite,
  // changes nothing. Never allocates.
  void advance(double time_s, const RobotDisc* robot) noexcept;

  // Person i as of time_s(); invisible for an index out of range.
  [[nodiscard]] PersonState state(std::size_t i) const noexcept;
  // The time the states are for: the last whole step's end (recorded: the last time advanced to).
  [[nodiscard]] double time_s() const noexcept { return time_s_; }

 private:
  // A simulated person's life in the scene.
  enum class Phase : std::uint8_t { waiting, present, gone };

  explicit Crowd(const CrowdConfig& config);

  void step(const RobotDisc* robot) noexcept;
  void step_orca() noexcept;
  // Brings in the waiting people due by time t and drops the present leavers who arrived.
  void enter_and_leave(double t) noexcept;
  void publish() noexcept;

  Behaviour behaviour_;
  double step_s_;
  SocialForceModel model_;
  OrcaParams orca_;
  double goal_reach_m_;

  std::vector<Person> people_;
  std::vector<Phase> phases_;
  std::vector<Walker> walkers_;         // social, blind
  std::vector<Wall> walls_;             // social, blind
  std::vector<OrcaAgent> agents_;       // orca
  std::vector<std::size_t> next_goal_;  // orca: index into people_[i].goals

  std::optional<Replay> replay_;  // recorded
  Point2D offset_;
  double recording_start_s_;
  double recorded_radius_m_;

  std::vector<PersonState> states_;
  std::uint64_t steps_ = 0;
  double time_s_ = 0.0;
};

}  // namespace sen3bot::crowd
