#pragma once
// Simple polygons (the site's areas) as spans of corners in order, either winding, the last
// corner joined to the first.
#include <span>

#include "sen3bot/msg/geometry.hpp"
#include "sen3bot/msg/point_math.hpp"

namespace sen3bot::cobot {

// The geometry kit's even-odd test and edge distance (a point exactly on an edge may fall
// either way; callers that need a margin use inside_by()).
using msg::inside_polygon;

// Distance from p to the nearest edge (infinity for fewer than two corners).
[[nodiscard]] inline double distance_to_edges(std::span<const msg::Point2D> polygon, msg::Point2D p) noexcept {
  return msg::polygon_edge_distance(polygon, p);
}

// Inside the polygon shrunk by margin_m: inside, and at least margin_m from every edge (a
// round robot of that radius centred at p lies wholly in the polygon).
[[nodiscard]] inline bool inside_by(std::span<const msg::Point2D> polygon, msg::Point2D p, double margin_m) noexcept {
  return inside_polygon(polygon, p) && distance_to_edges(polygon, p) >= margin_m;
}

}  // namespace sen3bot::cobot
