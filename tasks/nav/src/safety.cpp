#include "sen3bot/nav/safety.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sen3bot::nav {

SafetyFilter::SafetyFilter(const SafetyConfig& config) noexcept : config_(config) {
  const Footprint& fp = config.footprint;
  if (fp.vertex_count == 0) {
    front_m_ = fp.circle_radius_m;
    half_width_m_ = fp.circle_radius_m;
  } else {
    for (std::size_t i = 0; i < fp.vertex_count; ++i) {
      front_m_ = std::max(front_m_, fp.vertices[i].x_m);
      half_width_m_ = std::max(half_width_m_, std::abs(fp.vertices[i].y_m));
    }
  }
  turn_radius_m_ = fp.circumscribed_radius_m() + config.lateral_margin_m;
}

SafetyOutput SafetyFilter::filter(const SafetyInputs& in) const noexcept {
  SafetyOutput out;
  out.command = in.requested;
  out.nearest_ahead_m = std::numeric_limits<double>::infinity();
  const double stale_scan_ns = config_.stale_scan_periods * config_.scan_period_s * 1e9;
  if (in.scan == nullptr || static_cast<double>(in.now_ns - in.scan->stamp_ns) > stale_scan_ns) out.reasons |= kSafetyScanStale;
  if (in.odom_stamp_ns < 0 || static_cast<double>(in.now_ns - in.odom_stamp_ns) > config_.odom_timeout_s * 1e9) {
    out.reasons |= kSafetyOdomStale;
  }
  if (in.estop) out.reasons |= kSafetyEstop;
  if (!in.motors_enabled) out.reasons |= kSafetyMotorsOff;
  if (in.localization_lost) out.reasons |= kSafetyLocalizationLost;
  if (out.reasons != kSafetyNone || !std::isfinite(in.requested.v_mps) || !std::isfinite(in.requested.w_radps)) {
    out.command.v_mps = 0.0;
    out.command.w_radps = 0.0;
    return out;
  }

  // Laser points in the robot frame: the free distance ahead in the corridor, and whether
  // anything is inside the turning circle.
  bool inside_turn_circle = false;
  const ScanView& scan = *in.scan;
  const double mc = std::cos(config_.laser_mount.theta_rad);
  const double ms = std::sin(config_.laser_mount.theta_rad);
  const double corridor = half_width_m_ + config_.lateral_margin_m;
  for (std::size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double r = scan.ranges_m[i];
    if (!std::isfinite(r) || r < scan.range_min_m || r >= scan.range_max_m) continue;
    const double a = scan.angle_min_rad + static_cast<double>(i) * scan.increment_rad;
    const double sx = r * std::cos(a);
    const double sy = r * std::sin(a);
    const double x = config_.laser_mount.x_m + mc * sx - ms * sy;
    const double y = config_.laser_mount.y_m + ms * sx + mc * sy;
    if (std::hypot(x, y) < turn_radius_m_) inside_turn_circle = true;
    if (std::abs(y) <= corridor && x >= 0.0) out.nearest_ahead_m = std::min(out.nearest_ahead_m, std::max(0.0, x - front_m_));
  }

  double v = in.requested.v_mps;
  double w = in.requested.w_radps;
  const double speed = std::max({0.0, in.measured_v_mps, v});
  const double stop = config_.stop_distance_m + speed * config_.reaction_s + speed * speed / (2.0 * config_.decel_mps2);
  out.stop_distance_m = stop;
  if (v > 0.0) {
    if (out.nearest_ahead_m <= stop) {
      v = 0.0;
      out.reasons |= kSafetyObstacle;
    } else if (out.nearest_ahead_m < stop + config_.slow_distance_m) {
      const double scale = (out.nearest_ahead_m - stop) / config_.slow_distance_m;
      v *= scale;
      out.reasons |= kSafetySlowed;
    }
  } else if (v < -config_.max_reverse_mps) {
    v = -config_.max_reverse_mps;
    out.reasons |= kSafetyReverseCapped;
  }
  if (w != 0.0 && inside_turn_circle && std::abs(v) < 1e-9) {
    w = 0.0;
    out.reasons |= kSafetyObstacle;
  }
  out.command.v_mps = v;
  out.command.w_radps = w;
  return out;
}

}  // namespace sen3bot::nav
