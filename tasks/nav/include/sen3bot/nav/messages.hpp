#pragma once
// Navigation bus messages: fixed-size and trivially copyable, one Topic each.
//   ScanMessage, Odometry       (scan.hpp)         laser and odometry in
//   PoseEstimate                (localization.hpp) LocalizationTask out
//   NavGoal                                        goal in (mission / command line)
//   PathMessage                                    PlannerTask out
//   VelocityCommand             (safety.hpp)       ControllerTask out (requested), SafetyTask out (to the base)
//   ControllerStatus                               ControllerTask out
//   BaseFlags                                      base driver out: e-stop and motor state
//   SafetyOutput                (safety.hpp)       SafetyTask out (reasons)
#include <array>
#include <cstdint>
#include <type_traits>

#include "sen3bot/nav/global_planner.hpp"
#include "sen3bot/nav/local_planner.hpp"
#include "sen3bot/nav/localization.hpp"
#include "sen3bot/nav/safety.hpp"
#include "sen3bot/nav/scan.hpp"

namespace sen3bot::nav {

struct NavGoal {
  double x_m = 0.0;  // map frame
  double y_m = 0.0;
  std::uint32_t id = 0;  // a new id means a new goal: plan at once
  bool active = false;   // false: stop and drop the path
};
static_assert(std::is_trivially_copyable_v<NavGoal>);

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

struct ControllerStatus {
  DwaStatus status = DwaStatus::idle;
  RecoveryCounts recoveries;
  double distance_to_goal_m = 0.0;
  std::uint32_t admissible = 0;
  std::uint32_t plan_id = 0;  // the path being followed
};
static_assert(std::is_trivially_copyable_v<ControllerStatus>);

struct BaseFlags {
  bool estop = false;
  bool motors_enabled = false;
};
static_assert(std::is_trivially_copyable_v<BaseFlags>);

}  // namespace sen3bot::nav
