#pragma once
// Navigation's messages: the pose estimate, goals and paths, the controller's state and the
// velocity commands with the safety filter's reasons.
#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <type_traits>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/msg/geometry.hpp"

namespace sen3bot::msg {

struct PoseEstimate {
  Pose2D pose;                  // map frame
  double cov_xx = 0.0;          // m^2
  double cov_xy = 0.0;
  double cov_yy = 0.0;
  double cov_tt = 0.0;          // rad^2
  std::uint32_t particles = 0;
  std::uint32_t updates = 0;
  bool valid = false;           // initialised
  bool lost = false;            // position spread above the filter's limit, or relocalising
  bool relocalizing = false;    // the likelihood dropped: random particles are being injected
  // The mean beam likelihood (pz) of the last update, and its slow and fast running averages;
  // injection draws a random particle with probability max(0, 1 - fast / slow).
  float likelihood = 0.0f;
  float likelihood_slow = 0.0f;
  float likelihood_fast = 0.0f;
  float injection = 0.0f;       // share of random particles at the last resampling
  hal::Nanos stamp_ns = 0;
  // Where the robot was when the newest scan the filter was given was taken (map frame), and
  // that scan's stamp (0: none). The costmaps place that scan from here, not from pose.
  Pose2D scan_pose;
  hal::Nanos scan_stamp_ns = 0;
};
static_assert(std::is_trivially_copyable_v<PoseEstimate>);

struct NavGoal {
  double x_m = 0.0;  // map frame
  double y_m = 0.0;
  std::uint32_t id = 0;  // a new id means a new goal: plan at once
  bool active = false;   // false: stop and drop the path
  // Straight there, without the supervised safe path's waypoints: a goal near the robot that
  // moves as it goes (follow-me).
  bool direct = false;
};
static_assert(std::is_trivially_copyable_v<NavGoal>);

// float: a path point needs centimetres, and the path message stays half the size.
struct PathPoint {
  float x_m = 0.0f;
  float y_m = 0.0f;
};
static_assert(std::is_trivially_copyable_v<PathPoint>);

enum class PlanStatus : std::uint8_t {
  ok,
  start_outside,   // start not on the costmap
  goal_outside,
  start_blocked,   // start cell impassable
  goal_blocked,
  no_path,         // the reachable region does not contain the goal
  expansion_cap,   // gave up after max_expansions
  path_too_long,   // the path does not fit the output buffer
  too_large,       // the costmap or waypoint list exceeds what the planner was sized for
};

inline const char* to_string(PlanStatus status) noexcept {
  switch (status) {
    case PlanStatus::ok: return "ok";
    case PlanStatus::start_outside: return "start outside the costmap";
    case PlanStatus::goal_outside: return "goal outside the costmap";
    case PlanStatus::start_blocked: return "start cell is blocked";
    case PlanStatus::goal_blocked: return "goal cell is blocked";
    case PlanStatus::no_path: return "no path";
    case PlanStatus::expansion_cap: return "expansion cap reached";
    case PlanStatus::path_too_long: return "path longer than the output buffer";
    case PlanStatus::too_large: return "costmap or waypoints larger than configured";
  }
  return "?";
}

struct PathMessage {
  static constexpr std::size_t kMaxPoints = 1024;  // 51 m of path at 0.05 m cells
  std::array<PathPoint, kMaxPoints> points{};      // map frame, start first
  std::uint16_t count = 0;
  std::uint32_t plan_id = 0;    // increments with every plan (ok or not)
  std::uint32_t goal_id = 0;
  PlanStatus status = PlanStatus::no_path;
  std::uint32_t expansions = 0;
  std::uint16_t waypoints_passed = 0;
  double length_m = 0.0;
  double plan_time_ms = 0.0;    // wall time of the search (telemetry only)
};
static_assert(std::is_trivially_copyable_v<PathMessage>);

enum class DwaStatus : std::uint8_t {
  idle,         // no path
  tracking,
  reached,      // within goal tolerance: commanding zero
  waiting,      // recovery 1
  rotating,     // recovery 2
  backing_off,  // recovery 3
  failed,       // recoveries exhausted
  localizing,   // localization is lost: standing still until it is not
  yielding,     // letting a tracked mover pass: slowing or standing by choice, not a recovery
  braking,      // no way on at this speed: stopping under control, then choosing again
};

inline const char* to_string(DwaStatus status) noexcept {
  switch (status) {
    case DwaStatus::idle: return "idle";
    case DwaStatus::tracking: return "tracking";
    case DwaStatus::reached: return "reached";
    case DwaStatus::waiting: return "waiting";
    case DwaStatus::rotating: return "rotating";
    case DwaStatus::backing_off: return "backing_off";
    case DwaStatus::failed: return "failed";
    case DwaStatus::localizing: return "localizing";
    case DwaStatus::yielding: return "yielding";
    case DwaStatus::braking: return "braking";
  }
  return "?";
}

struct RecoveryCounts {
  std::uint32_t waits = 0;
  std::uint32_t rotations = 0;
  std::uint32_t backoffs = 0;
  [[nodiscard]] std::uint32_t total() const noexcept { return waits + rotations + backoffs; }
};
static_assert(std::is_trivially_copyable_v<RecoveryCounts>);

// The crossing gate's choice this cycle (nav/crossings.hpp).
enum class CrossingAction : std::uint8_t {
  clear,   // no walker's predicted way crosses the path ahead
  go,      // one does, and the robot driving on clears it first
  wait,    // the robot stops before it, and before any lane that holds it (speed capped)
  commit,  // too late to stop before it: left to the DWA's mover check and the safety filter
};
// The controller moving out of a walker's way (nav/crossings.hpp, make_way).
enum class MakeWayAction : std::uint8_t {
  none,      // nobody's way covers where the robot stands
  forward,   // out of it ahead, on its way
  backward,  // out of it the way it came
  stay,      // no way out in time: it stands still
};


inline const char* to_string(CrossingAction c) noexcept {
  switch (c) {
    case CrossingAction::clear: return "clear";
    case CrossingAction::go: return "go";
    case CrossingAction::wait: return "wait";
    case CrossingAction::commit: return "commit";
  }
  return "?";
}

struct ControllerStatus {
  DwaStatus status = DwaStatus::idle;
  CrossingAction crossing = CrossingAction::clear;
  double crossing_cap_m_s = 0.0;  // wait: the speed cap; infinity when the gate ran and caps nothing
  std::uint32_t crossing_waits = 0;  // cycles the gate lowered the DWA's speed, since start
  MakeWayAction making_way = MakeWayAction::none;
  std::uint32_t ways_made = 0;  // cycles the robot moved out of a walker's way, since start
  RecoveryCounts recoveries;
  double distance_to_goal_m = 0.0;
  std::uint32_t admissible = 0;
  std::uint32_t plan_id = 0;  // the path being followed
  // The request is the centre's formation command, not the DWA's (which did not run: status is
  // idle); the safety filter still applies.
  bool formation = false;
};
static_assert(std::is_trivially_copyable_v<ControllerStatus>);

struct VelocityCommand {
  double v_m_s = 0.0;
  double w_rad_s = 0.0;
  hal::Nanos stamp_ns = 0;
};
static_assert(std::is_trivially_copyable_v<VelocityCommand>);

// A velocity from the centre's formation controller, as the fleet task took it: the controller
// requests it instead of its own for hold_s after received_ns, then falls back (the safety
// filter after it still applies).
struct FormationCommand {
  double v_m_s = 0.0;
  double w_rad_s = 0.0;
  double hold_s = 0.0;
  hal::Nanos received_ns = 0;  // the robot's clock when the fleet task took it
  std::uint32_t header_id = 0;
};
static_assert(std::is_trivially_copyable_v<FormationCommand>);

// Why the safety filter lowered a command (bits of SafetyOutput::reasons).
enum SafetyReason : std::uint32_t {
  kSafetyNone = 0,
  kSafetyScanStale = 1u << 0,
  kSafetyOdomStale = 1u << 1,
  kSafetyEstop = 1u << 2,
  kSafetyMotorsOff = 1u << 3,
  kSafetyLocalizationLost = 1u << 4,
  kSafetyObstacle = 1u << 5,       // stopped for a point in the stop zone
  kSafetySlowed = 1u << 6,         // scaled down in the slow zone
  kSafetyReverseCapped = 1u << 7,
  kSafetyMoverApproach = 1u << 8,  // stopped: moving on would meet a tracked mover that braking avoids
  kSafetyCage = 1u << 9,           // stopped: moving on would take the body into a person's cage
  // The safety I/O (msg::SafetyIo). Each holds the robot until its cause is gone and a reset
  // was requested after that (SafetyLatch).
  kSafetyEstopChain = 1u << 10,    // the e-stop chain is open
  kSafetyBumper = 1u << 11,        // a bumper is pressed
  kSafetyIoLost = 1u << 12,        // no current inputs: the node is lost, the bus is off
  kSafetyResetNeeded = 1u << 13,   // the cause is gone; waiting for a reset
  kSafetySonar = 1u << 14,         // stopped reversing: a sonar echo behind, within the stop zone
  kSafetySeparation = 1u << 15,    // slowed to keep the separation from a person (ISO/TS 15066 SSM)
};

struct SafetyOutput {
  VelocityCommand command;
  std::uint32_t reasons = kSafetyNone;
  double nearest_ahead_m = 0.0;  // free travel along the commanded arc (+inf: clear to the slow zone's end)
  double stop_distance_m = 0.0;  // the stop zone's depth used for this decision
  double scan_age_s = 0.0;       // age of the scan that decision used (0: none)
  double closing_speed_m_s = 0.0;  // of the nearest tracked mover ahead, towards the robot
  // Speed and separation: the speed limit the most constraining person set (+inf: none did)
  // and its terms, the gap from the body to their cage's edge and their approach speed as
  // counted (measured plus the prediction's spread), for the live view and the reports.
  double separation_cap_m_s = std::numeric_limits<double>::infinity();
  double separation_gap_m = std::numeric_limits<double>::infinity();
  double separation_approach_m_s = 0.0;
};
static_assert(std::is_trivially_copyable_v<SafetyOutput>);

// A moving obstacle tracked by the dynamic obstacle layer, predicted to the message's stamp
// (map frame). Only confirmed tracks are published.
// The base's sonar ring: the newest reading of each transducer, its time and where it sits on
// the body. A transducer never read has stamp -1.
struct Sonar {
  static constexpr std::size_t kMax = 16;
  std::array<double, kMax> range_m{};
  std::array<hal::Nanos, kMax> stamp_ns{};
  std::array<Pose2D, kMax> mount{};  // body frame: x forward, heading along the beam
  std::uint8_t count = 0;            // transducers on this robot
  double max_range_m = 5.0;          // a reading this long saw nothing
};
static_assert(std::is_trivially_copyable_v<Sonar>);

struct MovingObstacle {
  std::uint32_t id = 0;
  double x_m = 0.0;
  double y_m = 0.0;
  double vx_m_s = 0.0;
  double vy_m_s = 0.0;
  double radius_m = 0.0;          // from the extent of its blobs
  double position_var_m2 = 0.0;   // trace of the position covariance / 2
  double velocity_var_m2_s2 = 0.0;
};
static_assert(std::is_trivially_copyable_v<MovingObstacle>);

struct MovingObstacles {
  static constexpr std::size_t kMax = 16;
  std::array<MovingObstacle, kMax> items{};
  std::uint8_t count = 0;
  // After the movers, items[count, count + candidate_count): confirmed tracks moving at speed
  // that have not yet left where they were first seen. A walker coming out from behind a door
  // jamb is one for about half a second before it is a mover; only the safety filter's
  // approach check reads them.
  std::uint8_t candidate_count = 0;
  hal::Nanos stamp_ns = 0;  // the time the positions are predicted to
};
static_assert(std::is_trivially_copyable_v<MovingObstacles>);

// The local planner's costmap for the live view, published by the controller row only when a
// view reads it. A costmap with more cells is coarsened by an integer factor, keeping each
// block's highest cost. Row 0 is the lowest y; origin is the corner of cell (0, 0).
struct CostmapSnapshot {
  static constexpr std::size_t kMaxCells = 160 * 160;  // 8 x 8 m at 0.05 m
  std::array<std::uint8_t, kMaxCells> cells{};
  std::uint16_t columns = 0;
  std::uint16_t rows = 0;
  double resolution_m = 0.0;
  double origin_x_m = 0.0;
  double origin_y_m = 0.0;
};
static_assert(std::is_trivially_copyable_v<CostmapSnapshot>);

}  // namespace sen3bot::msg
