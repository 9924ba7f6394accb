#pragma once
// Simple polygons (the site's areas) as spans of corners in order, either winding, the last
// corner joined to the first.
#include <algorithm>
#include <cmath>
#include <cstddef>
#include <limits>
#include <span>

#include "sen3bot/msg/geometry.hpp"

namespace sen3bot::cobot {

// Even-odd crossing test. A point exactly on an edge may fall either way; callers that need a
// margin use inside_by().
[[nodiscard]] inline bool inside_polygon(std::span<const msg::Point2D> polygon, msg::Point2D p) noexcept {
  const std::size_t n = polygon.size();
  if (n < 3) return false;
  bool inside = false;
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) {
    const msg::Point2D a = polygon[i];
    const msg::Point2D b = polygon[j];
    if ((a.y_m > p.y_m) != (b.y_m > p.y_m)) {
      const double x_cross = a.x_m + (p.y_m - a.y_m) * (b.x_m - a.x_m) / (b.y_m - a.y_m);
      if (p.x_m < x_cross) inside = !inside;
    }
  }
  return inside;
}

[[nodiscard]] inline double distance_to_segment(msg::Point2D a, msg::Point2D b, msg::Point2D p) noexcept {
  const double ex = b.x_m - a.x_m;
  const double ey = b.y_m - a.y_m;
  const double len2 = ex * ex + ey * ey;
  double t = len2 > 0.0 ? ((p.x_m - a.x_m) * ex + (p.y_m - a.y_m) * ey) / len2 : 0.0;
  t = std::clamp(t, 0.0, 1.0);
  return std::hypot(a.x_m + t * ex - p.x_m, a.y_m + t * ey - p.y_m);
}

// Distance from p to the nearest edge (infinity for fewer than two corners).
[[nodiscard]] inline double distance_to_edges(std::span<const msg::Point2D> polygon, msg::Point2D p) noexcept {
  double d = std::numeric_limits<double>::infinity();
  const std::size_t n = polygon.size();
  if (n < 2) return d;
  for (std::size_t i = 0, j = n - 1; i < n; j = i++) d = std::min(d, distance_to_segment(polygon[j], polygon[i], p));
  return d;
}

// Inside the polygon shrunk by margin_m: inside, and at least margin_m from every edge (a
// round robot of that radius centred at p lies wholly in the polygon).
[[nodiscard]] inline bool inside_by(std::span<const msg::Point2D> polygon, msg::Point2D p, double margin_m) noexcept {
  return inside_polygon(polygon, p) && distance_to_edges(polygon, p) >= margin_m;
}

}  // namespace sen3bot::cobot
