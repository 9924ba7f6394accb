#pragma once
// Geometry shared by the navigation pieces and the simulated world: pose arithmetic and the
// robot footprint. The value types themselves are the bus vocabulary's (msg/geometry.hpp).
#include <algorithm>
#include <array>
#include <cmath>
#include <cstddef>

#include "sen3bot/msg/geometry.hpp"

namespace sen3bot::nav {

using msg::compose;
using msg::normalize_angle;
using msg::Point2D;
using msg::Pose2D;
using msg::SensorMount;

// a^-1 * b: the motion from pose a to pose b, in a's frame.
inline Pose2D relative_pose(const Pose2D& a, const Pose2D& b) noexcept {
  const double c = std::cos(a.theta_rad);
  const double s = std::sin(a.theta_rad);
  const double dx = b.x_m - a.x_m;
  const double dy = b.y_m - a.y_m;
  return {c * dx + s * dy, -s * dx + c * dy, normalize_angle(b.theta_rad - a.theta_rad)};
}

// a * d: pose a moved by d (given in a's frame).
inline Pose2D apply_motion(const Pose2D& a, const Pose2D& d) noexcept {
  const double c = std::cos(a.theta_rad);
  const double s = std::sin(a.theta_rad);
  return {a.x_m + c * d.x_m - s * d.y_m, a.y_m + s * d.x_m + c * d.y_m, normalize_angle(a.theta_rad + d.theta_rad)};
}

// Pose p driven at a constant (v, w) for dt: along the exact arc (straight for w near 0).
inline void advance_arc(Pose2D& p, double v, double w, double dt) noexcept {
  if (std::abs(w) < 1e-6) {
    p.x_m += v * dt * std::cos(p.theta_rad);
    p.y_m += v * dt * std::sin(p.theta_rad);
  } else {
    const double th = p.theta_rad + w * dt;
    p.x_m += v / w * (std::sin(th) - std::sin(p.theta_rad));
    p.y_m -= v / w * (std::cos(th) - std::cos(p.theta_rad));
    p.theta_rad = th;
  }
}

// The robot outline in the robot frame (x forward, y left): a convex polygon of up to
// kMaxVertices corners, or a circle when vertex_count is 0.
struct Footprint {
  static constexpr std::size_t kMaxVertices = 16;
  std::array<Point2D, kMaxVertices> vertices{};
  std::size_t vertex_count = 0;
  double circle_radius_m = 0.0;  // used when vertex_count == 0

  static Footprint circle(double radius_m) noexcept {
    Footprint f;
    f.circle_radius_m = radius_m;
    return f;
  }
  static Footprint rectangle(double length_m, double width_m) noexcept {
    Footprint f;
    const double hx = length_m / 2.0;
    const double hy = width_m / 2.0;
    f.vertices[0] = {hx, hy};
    f.vertices[1] = {-hx, hy};
    f.vertices[2] = {-hx, -hy};
    f.vertices[3] = {hx, -hy};
    f.vertex_count = 4;
    return f;
  }
  // Pioneer 3-DX body (navigation.md): 0.455 m long, 0.381 m wide, centred on the axle.
  static Footprint pioneer() noexcept { return rectangle(0.455, 0.381); }

  // Distance from the centre to the nearest edge (the inscribed radius).
  [[nodiscard]] double inscribed_radius_m() const noexcept {
    if (vertex_count == 0) return circle_radius_m;
    double r = 1e300;
    for (std::size_t i = 0; i < vertex_count; ++i) {
      const Point2D a = vertices[i];
      const Point2D b = vertices[(i + 1) % vertex_count];
      const double ex = b.x_m - a.x_m;
      const double ey = b.y_m - a.y_m;
      const double len = std::hypot(ex, ey);
      if (len <= 0.0) continue;
      r = std::min(r, std::abs(ex * a.y_m - ey * a.x_m) / len);
    }
    return r;
  }
  // Distance from the centre to the farthest corner (the circumscribed radius).
  [[nodiscard]] double circumscribed_radius_m() const noexcept {
    if (vertex_count == 0) return circle_radius_m;
    double r = 0.0;
    for (std::size_t i = 0; i < vertex_count; ++i) r = std::max(r, std::hypot(vertices[i].x_m, vertices[i].y_m));
    return r;
  }
};

// The eigenvalues of the symmetric 2 x 2 matrix [[a, b], [b, c]] and the direction of the
// larger one's eigenvector (a scatter's principal axis, an ellipse's minor axis).
struct SymmetricEigen {
  double larger = 0.0;
  double smaller = 0.0;
  double larger_angle_rad = 0.0;
};
[[nodiscard]] inline SymmetricEigen symmetric_eigen(double a, double b, double c) noexcept {
  const double half_sum = 0.5 * (a + c);
  const double root = std::hypot(0.5 * (a - c), b);
  return {half_sum + root, half_sum - root, 0.5 * std::atan2(2.0 * b, a - c)};
}

}  // namespace sen3bot::nav
