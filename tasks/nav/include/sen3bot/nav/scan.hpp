#pragma once
// Laser and odometry inputs of the navigation cores. The cores take these small views so they
// stay pure; adapting a driver's message to them is a few assignments at composition time.
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <type_traits>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/nav/geometry.hpp"

namespace sen3bot::nav {

// One planar scan in the sensor frame: beam i points at angle_min + i * increment.
struct ScanView {
  std::span<const float> ranges_m;
  float angle_min_rad = 0.0f;
  float increment_rad = 0.0f;
  float range_min_m = 0.0f;
  float range_max_m = 0.0f;  // readings >= this are "no return"
  hal::Nanos stamp_ns = 0;
};

// A scan as a fixed-size bus message (LMS200: at most 401 beams at 0.25 deg over 100 deg,
// 361 at 0.5 deg over 180 deg).
struct ScanMessage {
  static constexpr std::size_t kMaxBeams = 401;
  std::array<float, kMaxBeams> ranges_m{};
  std::uint16_t count = 0;
  float angle_min_rad = 0.0f;
  float increment_rad = 0.0f;
  float range_min_m = 0.0f;
  float range_max_m = 0.0f;
  hal::Nanos stamp_ns = 0;

  [[nodiscard]] ScanView view() const noexcept {
    return {std::span<const float>(ranges_m.data(), std::min<std::size_t>(count, kMaxBeams)), angle_min_rad,
            increment_rad, range_min_m, range_max_m, stamp_ns};
  }
};
static_assert(std::is_trivially_copyable_v<ScanMessage>);

// Wheel odometry: pose in the odometry frame and body velocities.
struct Odometry {
  double x_m = 0.0;
  double y_m = 0.0;
  double theta_rad = 0.0;
  double v_m_s = 0.0;
  double w_rad_s = 0.0;
  hal::Nanos stamp_ns = 0;
  bool valid = false;
};
static_assert(std::is_trivially_copyable_v<Odometry>);

// Pose of the laser on the robot (robot frame).
struct SensorMount {
  double x_m = 0.0;
  double y_m = 0.0;
  double theta_rad = 0.0;
};

inline Pose2D compose(const Pose2D& a, const SensorMount& b) noexcept {
  const double c = std::cos(a.theta_rad);
  const double s = std::sin(a.theta_rad);
  return {a.x_m + c * b.x_m - s * b.y_m, a.y_m + s * b.x_m + c * b.y_m, normalize_angle(a.theta_rad + b.theta_rad)};
}

}  // namespace sen3bot::nav
