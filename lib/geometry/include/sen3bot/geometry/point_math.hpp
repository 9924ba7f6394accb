#pragma once
// Point2D as a plane vector: the arithmetic that models of motion (walkers, collision avoidance,
// recognition's workers) write their formulas in, and distances to segments and polygons. Kept
// apart from geometry.hpp, which every message includes, so the messages stay plain values.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <span>

#include "sen3bot/geometry/geometry.hpp"

namespace sen3bot::geometry {

[[nodiscard]] constexpr Point2D operator+(Point2D a, Point2D b) noexcept { return {a.x_m + b.x_m, a.y_m + b.y_m}; }
[[nodiscard]] constexpr Point2D operator-(Point2D a, Point2D b) noexcept { return {a.x_m - b.x_m, a.y_m - b.y_m}; }
[[nodiscard]] constexpr Point2D operator-(Point2D a) noexcept { return {-a.x_m, -a.y_m}; }
[[nodiscard]] constexpr Point2D operator*(double k, Point2D a) noexcept { return {k * a.x_m, k * a.y_m}; }
[[nodiscard]] constexpr Point2D operator*(Point2D a, double k) noexcept { return {k * a.x_m, k * a.y_m}; }
constexpr Point2D& operator+=(Point2D& a, Point2D b) noexcept { return a = a + b; }
constexpr Point2D& operator-=(Point2D& a, Point2D b) noexcept { return a = a - b; }
[[nodiscard]] constexpr double dot(Point2D a, Point2D b) noexcept { return a.x_m * b.x_m + a.y_m * b.y_m; }
// The z component of a x b: positive when b is counter-clockwise of a.
[[nodiscard]] constexpr double cross(Point2D a, Point2D b) noexcept { return a.x_m * b.y_m - a.y_m * b.x_m; }
[[nodiscard]] inline double norm(Point2D a) noexcept { return std::hypot(a.x_m, a.y_m); }
[[nodiscard]] constexpr double norm_squared(Point2D a) noexcept { return dot(a, a); }
[[nodiscard]] inline double distance(Point2D a, Point2D b) noexcept { return norm(a - b); }
// a rotated by +90 degrees.
[[nodiscard]] constexpr Point2D perpendicular(Point2D a) noexcept { return {-a.y_m, a.x_m}; }
// a / |a|, or `fallback` for a (near) zero vector.
[[nodiscard]] inline Point2D unit_or(Point2D a, Point2D fallback) noexcept {
  const double n = norm(a);
  return n > 1e-12 ? (1.0 / n) * a : fallback;
}

// Distance from q to the segment a-b (a point when a == b).
[[nodiscard]] inline double segment_distance(Point2D q, Point2D a, Point2D b) noexcept {
  const Point2D e = b - a;
  const double len2 = norm_squared(e);
  const double t = len2 > 0.0 ? std::clamp(dot(q - a, e) / len2, 0.0, 1.0) : 0.0;
  return norm(q - (a + t * e));
}

// Distance from q to a convex polygon (either winding), 0 on or inside it. Fewer than 3
// vertices: the distance to the point or segment; none: infinity.
[[nodiscard]] inline double convex_polygon_distance(std::span<const Point2D> polygon, Point2D q) noexcept {
  if (polygon.empty()) return std::numeric_limits<double>::infinity();
  if (polygon.size() == 1) return norm(q - polygon[0]);
  // Inside, q is on the same side of every edge whatever the winding. At least one strict side
  // is required, so a flat polygon is never "around" q.
  bool left = false;
  bool right = false;
  double d = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < polygon.size(); ++i) {
    const Point2D a = polygon[i];
    const Point2D b = polygon[(i + 1) % polygon.size()];
    const double side = cross(b - a, q - a);
    left = left || side > 0.0;
    right = right || side < 0.0;
    d = std::min(d, segment_distance(q, a, b));
  }
  if (polygon.size() >= 3 && left != right) return 0.0;
  return d;
}

// Even-odd crossing test over a simple polygon (corners in order, either winding, the last
// joined to the first). A point exactly on an edge may fall either way.
[[nodiscard]] inline bool inside_polygon(std::span<const Point2D> polygon, Point2D p) noexcept {
  const std::size_t n = polygon.size();
  if (n < 3) return false;
  bool inside = false;
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    const Point2D a = polygon[i];
    const Point2D b = polygon[j];
    if ((a.y_m > p.y_m) != (b.y_m > p.y_m)) {
      const double x_cross = a.x_m + (p.y_m - a.y_m) * (b.x_m - a.x_m) / (b.y_m - a.y_m);
      if (p.x_m < x_cross) inside = !inside;
    }
  }
  return inside;
}

// Distance from p to the polygon's nearest edge (infinity for fewer than two corners).
[[nodiscard]] inline double polygon_edge_distance(std::span<const Point2D> polygon, Point2D p) noexcept {
  double d = std::numeric_limits<double>::infinity();
  const std::size_t n = polygon.size();
  if (n < 2) return d;
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) d = std::min(d, segment_distance(p, polygon[j], polygon[i]));
  return d;
}

}  // namespace sen3bot::geometry
