#pragma once
// The geometry kit's plane-vector arithmetic and distances (lib/geometry), named in msg for
// the code that writes its formulas over the bus's points.
#include "sen3bot/geometry/point_math.hpp"
#include "sen3bot/msg/geometry.hpp"

namespace sen3bot::msg {

using geometry::operator+;
using geometry::operator-;
using geometry::operator*;
using geometry::operator+=;
using geometry::operator-=;
using geometry::convex_polygon_distance;
using geometry::cross;
using geometry::distance;
using geometry::dot;
using geometry::inside_polygon;
using geometry::norm;
using geometry::norm_squared;
using geometry::perpendicular;
using geometry::polygon_edge_distance;
using geometry::segment_distance;
using geometry::unit_or;

}  // namespace sen3bot::msg
