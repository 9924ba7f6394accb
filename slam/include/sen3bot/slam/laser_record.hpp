#pragma once
// One laser scan of a recorded or live drive, as every mapping input gives it: the ranges with
// their beam geometry, and the odometry pose at the scan's time. The mapper takes nothing else,
// so a CARMEN log, a wire capture and the firmware's bus feed it alike.
#include <array>
#include <cstddef>
#include <cstdint>

#include "sen3bot/nav/geometry.hpp"

namespace sen3bot::slam {

// The LMS200 sends at most 401 beams (100° at 0.25°) or 361 (180° at 0.5°); CARMEN logs of other
// scanners hold up to 1081 (270° at 0.25°).
inline constexpr std::size_t kMaxBeams = 1081;

struct LaserRecord {
  std::uint64_t source_line = 0;  // where it came from (a log's line, a capture's record), for messages
  double time_s = 0.0;            // the recording's clock; used for order, never for speed
  nav::Pose2D odometry;           // the robot's odometry pose at the scan
  nav::Pose2D laser_mount;        // the scanner's pose in the robot frame
  double start_angle_rad = 0.0;   // beam i points at start + i * increment, in the scanner's frame
  double angle_increment_rad = 0.0;
  double max_range_m = 0.0;       // readings at or beyond it, or at or below 0, are no return
  std::uint32_t count = 0;        // beams used in `ranges`
  std::array<float, kMaxBeams> ranges{};
};

}  // namespace sen3bot::slam
