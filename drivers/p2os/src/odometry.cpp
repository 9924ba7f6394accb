#include "sen3bot/p2os/odometry.hpp"

#include <cmath>

namespace sen3bot::p2os {

double wrap_angle_rad(double angle_rad) noexcept {
  constexpr double kTwoPi = 2.0 * std::numbers::pi;
  double a = std::fmod(angle_rad, kTwoPi);
  if (a <= -std::numbers::pi) a += kTwoPi;
  if (a > std::numbers::pi) a -= kTwoPi;
  return a;
}

std::int32_t Odometry::position_delta(std::uint16_t now_raw, std::uint16_t last_raw) noexcept {
  std::int32_t d = static_cast<std::int32_t>(now_raw & kPositionMask) - static_cast<std::int32_t>(last_raw & kPositionMask);
  // Half the modulus: the shorter way round the 15-bit circle.
  if (d > kPositionModulus / 2) d -= kPositionModulus;
  if (d <= -kPositionModulus / 2) d += kPositionModulus;
  return d;
}

std::int32_t Odometry::theta_delta(std::int16_t now_raw, std::int16_t last_raw) noexcept {
  std::int32_t d = (static_cast<std::int32_t>(now_raw) - static_cast<std::int32_t>(last_raw)) % kThetaUnitsPerRev;
  if (d >= kThetaUnitsPerRev / 2) d -= kThetaUnitsPerRev;
  if (d < -kThetaUnitsPerRev / 2) d += kThetaUnitsPerRev;
  return d;
}

void Odometry::update(const Sip& sip) noexcept {
  if (!seeded_) {
    // Sign-extend the 15-bit counters so a robot just behind its origin starts near zero.
    auto extend = [](std::uint16_t raw) {
      const std::int32_t v = raw & kPositionMask;
      return v >= kPositionModulus / 2 ? v - kPositionModulus : v;
    };
    pose_.x_m = extend(sip.x_raw) * factors_.dist_conv_mm_per_unit * 1e-3;
    pose_.y_m = extend(sip.y_raw) * factors_.dist_conv_mm_per_unit * 1e-3;
    theta_unwrapped_rad_ = sip.theta_raw * factors_.angle_conv_rad_per_unit;
    pose_.theta_rad = wrap_angle_rad(theta_unwrapped_rad_);
    last_x_ = sip.x_raw;
    last_y_ = sip.y_raw;
    last_theta_ = sip.theta_raw;
    distance_m_ = 0;
    seeded_ = true;
    return;
  }
  if (rebase_) {
    last_x_ = sip.x_raw;
    last_y_ = sip.y_raw;
    last_theta_ = sip.theta_raw;
    rebase_ = false;
    return;
  }
  const double dx_m = position_delta(sip.x_raw, last_x_) * factors_.dist_conv_mm_per_unit * 1e-3;
  const double dy_m = position_delta(sip.y_raw, last_y_) * factors_.dist_conv_mm_per_unit * 1e-3;
  pose_.x_m += dx_m;
  pose_.y_m += dy_m;
  distance_m_ += std::hypot(dx_m, dy_m);
  theta_unwrapped_rad_ += theta_delta(sip.theta_raw, last_theta_) * factors_.angle_conv_rad_per_unit;
  pose_.theta_rad = wrap_angle_rad(theta_unwrapped_rad_);
  last_x_ = sip.x_raw;
  last_y_ = sip.y_raw;
  last_theta_ = sip.theta_raw;
}

}  // namespace sen3bot::p2os
