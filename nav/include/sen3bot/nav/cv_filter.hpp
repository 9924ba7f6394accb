#pragma once
// The tracking kit's constant-velocity Kalman filter in the plane (beside assignment.hpp): the
// one filter of the moving-obstacle tracker and the people tracker. State x, y, vx, vy (metres,
// m/s, world frame); the measurements are positions. Plain arrays: a track is copied, stored in
// arenas and predicted for every reader, and no header that includes it pays for Eigen.
#include <array>
#include <cstddef>
#include <cstdint>

#include "sen3bot/geometry/geometry.hpp"

namespace sen3bot::nav {

// How the unknown acceleration enters between two updates (Bar-Shalom, Li and Kirubarajan,
// "Estimation with Applications to Tracking and Navigation", 6.2 and 6.3), with sigma the
// acceleration's spread:
// - piecewise_constant: one acceleration held over each interval, Q = sigma^2 [dt^4/4 dt^3/2;
//   dt^3/2 dt^2]: for a tracker updated once a scan (the moving-obstacle layer);
// - continuous: white acceleration of density sigma^2, Q = sigma^2 [dt^3/3 dt^2/2; dt^2/2 dt]:
//   for fixes at irregular intervals and long coasts (people), where the spread it predicts
//   must not depend on how the time was cut into steps.
enum class ProcessNoise : std::uint8_t { piecewise_constant, continuous };

struct CvFilter {
  std::array<double, 4> x{};   // x, y, vx, vy
  std::array<double, 16> P{};  // covariance, row-major

  [[nodiscard]] geometry::Point2D position() const noexcept { return {x[0], x[1]}; }
  [[nodiscard]] geometry::Point2D velocity() const noexcept { return {x[2], x[3]}; }
  [[nodiscard]] double cov(int row, int col) const noexcept { return P[static_cast<std::size_t>(row * 4 + col)]; }
  [[nodiscard]] bool finite() const noexcept;

  // At `at` moving at `v`, the position and velocity spreads independent.
  void reset(geometry::Point2D at, geometry::Point2D v, double position_var, double velocity_var) noexcept;
  // x += v dt and P = F P F' + Q(dt). A dt that is not positive leaves it as it is.
  void predict(double dt, double accel_sigma, ProcessNoise noise) noexcept;
  // Weighs a position fix whose covariance is [r00 r01; r01 r11] (Joseph form: P stays
  // symmetric and positive). False, and nothing changed, when the innovation's covariance is
  // not positive definite (a broken state or fix): the caller starts the track again.
  bool correct(geometry::Point2D z, double r00, double r01, double r11) noexcept;
};

}  // namespace sen3bot::nav
