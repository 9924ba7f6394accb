#pragma once
// Point2D as a plane vector: the arithmetic that models of motion (walkers, collision avoidance,
// recognition's workers) write their formulas in. Kept apart from geometry.hpp, which every
// message includes, so the messages stay plain values.
#include <cmath>

#include "sen3bot/msg/geometry.hpp"

namespace sen3bot::msg {

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
// a rotated by +90 degrees.
[[nodiscard]] constexpr Point2D perpendicular(Point2D a) noexcept { return {-a.y_m, a.x_m}; }
// a / |a|, or `fallback` for a (near) zero vector.
[[nodiscard]] inline Point2D unit_or(Point2D a, Point2D fallback) noexcept {
  const double n = norm(a);
  return n > 1e-12 ? (1.0 / n) * a : fallback;
}

}  // namespace sen3bot::msg
