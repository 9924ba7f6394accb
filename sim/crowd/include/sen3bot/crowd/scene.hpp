#pragma once
// The scenes of the crowd-navigation benchmark: everything one run needs besides the firmware
// (the floor and its walls, where the robot starts and must go, how long it has, and the
// people), each a pure function of its options and a seed. Built once per run, off the
// real-time path (they allocate).
//
// Scene frames are metres; the walls lie on the border of the free floor (`area`). People are
// drawn with unit_uniform and friends (random.hpp), so a seed gives the same scene on every
// platform. Conventions shared by the simulated scenes:
//
//   robot        a disc of kSceneRobotRadiusM (CrowdNav's robot; the Pioneer's footprint has a
//                circumscribed radius of 0.297 m); it starts facing its goal
//   time limit   3 times the straight path at 0.5 m/s (the local planner's top speed), as
//                CrowdNav's 25 s is about 3 times its 8 m at its robot's 1 m/s; circle keeps
//                CrowdNav's 25 s
//   walkers      (crossing, corridor, square) bodies of 0.25 m radius (Helbing 2000's 0.5 to
//                0.7 m shoulder width), desired speeds normal about 1.3 m/s with sd 0.26 m/s
//                (Moussaïd et al. 2009's free walking speed; the spread of Weidmann 1993's
//                1.34 +- 0.26 m/s), drawn again outside [0.5, 2.0] m/s. They start 0.5 m
//                inside a wall, appear at uniform times while the robot would cross the
//                scene at 0.5 m/s (so they keep coming during its run) and vanish at their
//                goals, 0.5 m inside the opposite wall (walked out of the scene).
//   spacing      as CrowdNav: a walker is drawn again (start, goal and appearance time; the
//                speed is kept) when its start or goal is within r_i + r_j + 0.2 m (the
//                discomfort distance) of the robot's start or goal. Walkers appear over time,
//                so they are also drawn again when one would appear within that distance of
//                another's straight walk while that one nominally passes there: between its
//                times at 1.3 times (the model's speed cap) and 0.7 times its desired speed,
//                widened by twice the time either needs to walk the distance from rest. This
//                covers two starts at once, and an arrival on a start. (Walkers held up by
//                others, or by the robot, may still meet someone appearing; social walkers
//                then push apart.) Circle humans, all there at once, keep the distance from
//                every other start and goal (CrowdNav).
// circle    CrowdNav's circle_crossing (Chen, Liu, Kreiss & Alahi, "Crowd-robot interaction:
//           crowd-aware robot navigation with attention-based deep reinforcement learning",
//           ICRA 2019; vita-epfl/CrowdNav crowd_sim.py, env.config): N humans (default 5) of
//           radius 0.3 m at a preferred speed of 1 m/s on a circle of radius 4 m. Each draws
//           a uniform angle, adds U(-0.5, 0.5) x v_pref to each coordinate, and walks to the
//           opposite point -p (the goal is the jittered start mirrored through the centre);
//           a start within r_i + r_j + 0.2 m of a placed human's start or goal, or of the
//           robot's start or goal, is drawn again. The robot drives (0, -4) -> (0, 4) within
//           25 s. ORCA by default with the robot invisible (CrowdNav's setting); humans stand
//           at their goals. The floor is [-6, 6]^2 m: walls far from everyone, for the
//           simulator's map (ORCA ignores them).
// crossing  an open hall of 12 x 8 m, [0, 12] x [0, 8]; the robot along the long side,
//           (1, 4) -> (11, 4), 60 s. N walkers cross the hall across the robot's path: from
//           the wall at y = 0 to the one at y = 8 or back (a coin), starting at x in
//           [1.5, 10.5] and aiming at most 1.5 m to either side of that (about 12 degrees
//           off the perpendicular); they appear within 20 s. Social by default.
// corridor  a corridor of 20 x 3 m, [0, 20] x [0, 3]; the robot along its middle,
//           (2, 1.5) -> (18, 1.5), 96 s. N walkers walk its length either way (a coin), from
//           one end to the other at any y in [0.5, 2.5]; they appear within 32 s. Social.
// square    an open square of 10 x 10 m, [0, 10]^2; the robot across the diagonal,
//           (1, 1) -> (9, 9), 68 s. N walkers walk between uniform points 0.5 m inside the
//           border, from any side to any other side, at least 2 m apart; they appear within
//           22.6 s. Social.
// recorded  a Recording replayed as it was (recording_scene below); its name is the
//           recording's.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "sen3bot/crowd/crowd.hpp"
#include "sen3bot/crowd/recording.hpp"
#include "sen3bot/crowd/social_force.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/msg/geometry.hpp"

namespace sen3bot::crowd {

inline constexpr double kSceneRobotRadiusM = 0.3;  // CrowdNav's robot
inline constexpr double kDiscomfortM = 0.2;        // CrowdNav's discomfort distance
inline constexpr double kRobotSpeedM_s = 0.5;      // the local planner's top speed: time limits
// Simulated walkers (crossing, corridor, square, and the crowds matched to a recording).
inline constexpr double kWalkerRadiusM = 0.25;     // Helbing 2000
inline constexpr double kWallGapM = 0.5;           // starts, goals and robot ends this far inside a wall

// A walker's desired speed: normal, 1.3 +- 0.26 m/s (Moussaid et al. 2009; Weidmann 1993's
// spread), drawn again outside [0.5, 2.0] m/s (clamping would pile people on the ends).
[[nodiscard]] double draw_walker_speed(std::mt19937_64& rng) noexcept;

struct Scene {
  std::string name;         // "circle", "crossing", "corridor", "square", or the recording's name
  Extent area;              // the free floor, metres (walls on its border)
  std::vector<Wall> walls;  // the border (and any wall inside)
  msg::Pose2D robot_start;  // facing the goal
  Point2D robot_goal;
  double time_limit_s = 0.0;
  CrowdConfig crowd;  // behaviour, people or recording (+ offset and start time); walls = walls
};

struct SceneOptions {
  std::string name;                  // circle, crossing, corridor, square or recorded
  std::size_t people = 0;            // simulated scenes: 1.. (default_people()); recorded: 0
  std::optional<Behaviour> behaviour;  // overrides the scene's; simulated: social, blind or orca
  std::shared_ptr<const Recording> recording;  // recorded only
};

// The scenes make_scene knows, in the order above.
inline constexpr std::string_view kSceneNames[] = {"circle", "crossing", "corridor", "square", "recorded"};

// A sensible count for a simulated scene (circle: CrowdNav's 5; the others 10, our choice); 0
// for recorded or an unknown name.
[[nodiscard]] std::size_t default_people(std::string_view name) noexcept;

// The scene `options.name` for `seed`. Errors (invalid_argument unless said): an unknown name; a
// simulated scene with no people, more than kMaxWalkers (social, blind) or kMaxOrcaAgents (orca)
// of them (capacity), a recording or the recorded behaviour; recorded without a recording, with
// people or another behaviour; and what recording_scene() refuses. A scene whose people cannot
// all be placed with the spacing above within 1000 draws each is a capacity error naming how
// many were.
[[nodiscard]] Result<Scene> make_scene(const SceneOptions& options, std::uint64_t seed);

struct RecordingSceneOptions {
  double margin_m = 2.0;   // the floor is the recording's extent grown by this on every side
  double clear_m = 1.0;    // no annotated person this near the robot's start or goal at time 0
  double cell_m = 1.0;     // busiest_point()'s grid
};

// The recording as it was, around a robot crossing its busiest place. The floor is the extent of
// every annotation grown by margin_m and rounded outwards to 0.5 m, walls on its border; the
// recording keeps its own frame (no offset). The robot's straight path runs through
// busiest_point() at a uniform angle and ends 0.5 m inside the walls; the time limit is the
// rule above for that path; the run starts at a uniform moment of the recording within
// [start, end - time limit]. Angle and moment are drawn again until no person the replay
// shows at that moment is within clear_m of the robot's start or goal (1000 draws at most).
// Errors: a recording with no samples or whose tracks are not what parse_recording() builds, a
// non-finite or negative option, a recording shorter than the time limit, no clear draw.
[[nodiscard]] Result<Scene> recording_scene(std::shared_ptr<const Recording> recording, std::uint64_t seed,
                                            const RecordingSceneOptions& options = {});

// Writes the scene's floor as a ROS map_server map, `<dir>/<name>.pgm` and `<dir>/<name>.yaml`
// (name: the scene's file name without directory and extension, characters other than letters,
// digits, '-' and '_' made '_'), creating dir. Cells whose centre is off the floor are occupied (the border walls:
// a ring at least 2 cells and 0.1 m thick around it); a wall not on the border occupies every
// cell it touches. Free 254, occupied 0, as map_saver writes them; origin at the ring's lower
// left corner, trinary thresholds 0.65 / 0.196 (config/maps/arena.yaml's). Returns the YAML's
// path. Errors: a resolution not positive and finite, an empty or non-finite floor, a map larger
// than nav::load_map accepts (capacity), a file that cannot be written (io).
[[nodiscard]] Result<std::string> write_scene_map(const Scene& scene, const std::string& dir,
                                                  double resolution_m = 0.05);

}  // namespace sen3bot::crowd
