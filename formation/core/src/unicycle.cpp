#include "sen3bot/formation/unicycle.hpp"

#include <algorithm>
#include <cmath>

namespace sen3bot::formation {

Vec2 point_p(const Pose& pose, double offset_m) noexcept {
  return {pose.x_m + offset_m * std::cos(pose.theta_rad), pose.y_m + offset_m * std::sin(pose.theta_rad)};
}

Unicycle to_unicycle(const Pose& pose, Vec2 u, double offset_m) noexcept {
  const double c = std::cos(pose.theta_rad);
  const double s = std::sin(pose.theta_rad);
  return {c * u.x_m + s * u.y_m, (-s * u.x_m + c * u.y_m) / offset_m};
}

Vec2 point_velocity(const Pose& pose, Unicycle command, double offset_m) noexcept {
  const double c = std::cos(pose.theta_rad);
  const double s = std::sin(pose.theta_rad);
  return {c * command.v - offset_m * s * command.w, s * command.v + offset_m * c * command.w};
}

double common_scale(std::span<const Unicycle> commands, double v_max, double w_max) noexcept {
  double top_v = 0.0;
  double top_w = 0.0;
  for (const Unicycle& c : commands) {
    if (!std::isfinite(c.v) || !std::isfinite(c.w)) return 0.0;
    top_v = std::max(top_v, std::fabs(c.v));
    top_w = std::max(top_w, std::fabs(c.w));
  }
  double f = 1.0;
  if (top_v > 0.0) f = std::min(f, v_max / (2.0 * top_v));
  if (top_w > 0.0) f = std::min(f, w_max / (2.0 * top_w));
  return std::max(f, 0.0);
}

}  // namespace sen3bot::formation
