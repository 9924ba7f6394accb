#pragma once
// Plain plane geometry values: points and poses (metres, radians), a sensor's mount on the
// robot, and the little inline math every reader of them needs. The bus's messages carry these
// (msg/geometry.hpp names them there).
#include <cmath>
#include <numbers>
#include <type_traits>

namespace sen3bot::geometry {

struct Point2D {
  double x_m = 0.0;
  double y_m = 0.0;
  friend constexpr bool operator==(const Point2D&, const Point2D&) = default;
};
static_assert(std::is_trivially_copyable_v<Point2D>);

struct Pose2D {
  double x_m = 0.0;
  double y_m = 0.0;
  double theta_rad = 0.0;
  friend constexpr bool operator==(const Pose2D&, const Pose2D&) = default;
};
static_assert(std::is_trivially_copyable_v<Pose2D>);

// Both coordinates are numbers (not NaN, not infinite): what a reader checks first.
[[nodiscard]] inline bool finite(const Point2D& p) noexcept { return std::isfinite(p.x_m) && std::isfinite(p.y_m); }

// Where the pose stands, without its heading.
[[nodiscard]] constexpr Point2D position(const Pose2D& pose) noexcept { return {pose.x_m, pose.y_m}; }

// Pose of a sensor on the robot (robot frame: x forward, y left).
struct SensorMount {
  double x_m = 0.0;
  double y_m = 0.0;
  double theta_rad = 0.0;
};
static_assert(std::is_trivially_copyable_v<SensorMount>);

// Wraps to [-pi, pi).
inline double normalize_angle(double a_rad) noexcept {
  a_rad = std::fmod(a_rad + std::numbers::pi, 2.0 * std::numbers::pi);
  if (a_rad < 0.0) a_rad += 2.0 * std::numbers::pi;
  return a_rad - std::numbers::pi;
}

// The sensor's pose in the frame the robot pose a is given in.
inline Pose2D compose(const Pose2D& a, const SensorMount& b) noexcept {
  const double c = std::cos(a.theta_rad);
  const double s = std::sin(a.theta_rad);
  return {a.x_m + c * b.x_m - s * b.y_m, a.y_m + s * b.x_m + c * b.y_m, normalize_angle(a.theta_rad + b.theta_rad)};
}

}  // namespace sen3bot::geometry
