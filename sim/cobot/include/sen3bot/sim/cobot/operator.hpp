#pragma once
// A trained operator in the simulated world: where they are and which way their front faces at
// any time, scripted as walks, stands and turns, and the attempts at the collaboration request
// (valid ones and each kind of failure) planned in front of a waiting robot with human variety:
// where they stop, how long they show each tag, how squarely they face the robot.
#include <cstdint>
#include <random>
#include <string_view>
#include <vector>

#include "sen3bot/nav/geometry.hpp"
#include "sen3bot/world/world.hpp"

namespace sen3bot::sim::cobot {

// facing_rad: the direction the operator's front faces, map frame. The front tag faces that
// way, the back tag the other.
class OperatorScript {
 public:
  // Each piece starts where and when the previous one ended (the first at its own place).
  void start(double t_s, nav::Point2D at, double facing_rad);
  void walk_to(nav::Point2D to, double speed_m_s);  // facing along the walk
  void stand(double duration_s);
  void turn_to(double facing_rad, double duration_s);  // duration_s for half a turn, less for less

  [[nodiscard]] nav::Point2D at(double t_s) const noexcept;
  [[nodiscard]] double facing(double t_s) const noexcept;
  [[nodiscard]] double end_s() const noexcept { return times_.empty() ? 0.0 : times_.back(); }
  [[nodiscard]] nav::Point2D end_at() const noexcept { return points_.empty() ? nav::Point2D{} : points_.back(); }
  [[nodiscard]] double end_facing() const noexcept { return facing_.empty() ? 0.0 : facing_.back(); }
  // The world's mover: a person of this width on the timed walk.
  [[nodiscard]] world::MoverScript mover(double size_m) const;
  // The keyframes, for passing a script written as the run goes to the world.
  [[nodiscard]] std::size_t keyframes() const noexcept { return times_.size(); }
  [[nodiscard]] double keyframe_time(std::size_t i) const noexcept { return times_[i]; }
  [[nodiscard]] nav::Point2D keyframe_at(std::size_t i) const noexcept { return points_[i]; }

 private:
  void add(double t_s, nav::Point2D at, double facing_rad);
  std::vector<double> times_;
  std::vector<nav::Point2D> points_;
  std::vector<double> facing_;
};

enum class AttemptKind : std::uint8_t {
  valid,              // a known operator, the sequence as trained
  too_far,            // stops with their legs 1.2-1.4 m away (farther, the tags are not read reliably)
  too_short,          // the front tag for about 1.1-1.7 s only
  wrong_order,        // the back tag first, then the front
  unknown_operator,   // tags of an id not on the robot's list
  person_in_the_way,  // a valid sequence with another person standing closer to the robot
};
inline constexpr std::size_t kAttemptKinds = 6;
[[nodiscard]] std::string_view to_string(AttemptKind kind) noexcept;

// What one attempt did, for the report.
struct AttemptPlan {
  AttemptKind kind = AttemptKind::valid;
  std::uint32_t operator_id = 0;
  double start_s = 0;
  double end_s = 0;            // walked out of view again
  double stand_distance_m = 0; // laser to the operator's centre while showing (legs ~0.2 m nearer)
  double front_s = 0;          // how long each tag was held towards the robot
  double back_s = 0;
  bool bystander = false;      // a second person stood in the way
  nav::Point2D bystander_at;
};

struct AttemptOptions {
  double walk_speed_m_s = 0.9;
  double approach_m = 2.0;       // where the operator comes from: this far out, to the side
  double approach_bearing_rad = 0.87;  // off the robot's axis (50 degrees)
  double turn_s = 0.8;           // turning round between the tags
  double facing_error_rad = 0.2; // how squarely they face the robot (uniform +-)
  // After the sequence, turn back to the robot and show it again: a request and the request back.
  bool twice = false;
  bool leave = true;  // walk off to the other side at the end (false: stand there, back turned)
};

// Plans one attempt of `kind` by `operator_id`, in front of a robot whose laser is at `laser`
// (map frame), starting at t0_s: appends it to `op` (which must have been started). A
// person_in_the_way attempt also gives where the bystander stands. Draws from rng.
AttemptPlan plan_attempt(OperatorScript& op, AttemptKind kind, std::uint32_t operator_id, const nav::Pose2D& laser,
                         double t0_s, const AttemptOptions& options, std::mt19937_64& rng);

}  // namespace sen3bot::sim::cobot
