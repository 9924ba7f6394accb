#include "sen3bot/crowd/legs.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace sen3bot::crowd {
namespace {

constexpr double kCadenceScaleHz = 1.6;  // f at 1 m/s
constexpr double kCadenceExponent = 0.58;

}  // namespace

double step_length_m(double speed_m_s) noexcept {
  if (!(speed_m_s > 0.0)) return 0.0;
  const double v = std::min(speed_m_s, kGaitMaxSpeedM_S);
  return std::pow(v, 1.0 - kCadenceExponent) / kCadenceScaleHz;
}

double step_frequency_hz(double speed_m_s) noexcept {
  return speed_m_s > 0.0 ? speed_m_s / step_length_m(speed_m_s) : 0.0;
}

void advance(Gait& gait, Point2D velocity, double dt_s) noexcept {
  const double speed = norm(velocity);
  if (speed > kHeadingMinSpeedM_S) gait.heading_rad = std::atan2(velocity.y_m, velocity.x_m);
  if (!(speed > 0.0) || !(dt_s > 0.0)) return;
  const double phase = gait.phase_rad + std::numbers::pi * speed * dt_s / step_length_m(speed);
  gait.phase_rad = std::fmod(phase, 2.0 * std::numbers::pi);
}

std::array<Point2D, 2> leg_centres(Point2D centre, const Gait& gait, double speed_m_s) noexcept {
  const Point2D forward{std::cos(gait.heading_rad), std::sin(gait.heading_rad)};
  const Point2D left = perpendicular(forward);
  const double swing = 0.5 * step_length_m(speed_m_s) * std::sin(gait.phase_rad);
  return {centre + swing * forward + kLegSpreadM * left, centre - swing * forward - kLegSpreadM * left};
}

}  // namespace sen3bot::crowd
