// The geometry kit (lib/geometry): the polygon tests the safety filter, the collaborative
// mode's areas and the experiment's overlap check share.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>

#include "sen3bot/geometry/point_math.hpp"

namespace sen3bot::geometry {
namespace {

constexpr std::array<Point2D, 4> kSquare = {{{0, 0}, {2, 0}, {2, 2}, {0, 2}}};
// An L, clockwise: the notch at the top right is outside.
constexpr std::array<Point2D, 6> kEll = {{{0, 0}, {0, 2}, {1, 2}, {1, 1}, {2, 1}, {2, 0}}};

TEST(Geometry, InsidePolygonEitherWindingAndConcave) {
  EXPECT_TRUE(inside_polygon(kSquare, {1, 1}));
  EXPECT_FALSE(inside_polygon(kSquare, {2.5, 1}));
  EXPECT_FALSE(inside_polygon(kSquare, {1, -0.1}));
  EXPECT_TRUE(inside_polygon(kEll, {0.5, 1.5}));
  EXPECT_TRUE(inside_polygon(kEll, {1.5, 0.5}));
  EXPECT_FALSE(inside_polygon(kEll, {1.5, 1.5}));  // the notch
  const std::array<Point2D, 2> segment = {{{0, 0}, {1, 1}}};
  EXPECT_FALSE(inside_polygon(segment, {0.5, 0.5}));  // fewer than three corners: no inside
}

TEST(Geometry, PolygonEdgeDistance) {
  EXPECT_DOUBLE_EQ(polygon_edge_distance(kSquare, {1, 1}), 1.0);
  EXPECT_DOUBLE_EQ(polygon_edge_distance(kSquare, {3, 1}), 1.0);
  EXPECT_DOUBLE_EQ(polygon_edge_distance(kSquare, {3, 3}), std::sqrt(2.0));
  EXPECT_DOUBLE_EQ(polygon_edge_distance(kEll, {1.5, 1.5}), 0.5);  // the notch's corner
  const std::array<Point2D, 1> point = {{{0, 0}}};
  EXPECT_EQ(polygon_edge_distance(point, {1, 0}), std::numeric_limits<double>::infinity());
}

TEST(Geometry, SegmentDistanceClampsToTheEnds) {
  EXPECT_DOUBLE_EQ(segment_distance({1, 1}, {0, 0}, {2, 0}), 1.0);
  EXPECT_DOUBLE_EQ(segment_distance({3, 0}, {0, 0}, {2, 0}), 1.0);
  EXPECT_DOUBLE_EQ(segment_distance({-3, 4}, {0, 0}, {2, 0}), 5.0);
  EXPECT_DOUBLE_EQ(segment_distance({1, 1}, {0, 0}, {0, 0}), std::sqrt(2.0));  // a point
}

}  // namespace
}  // namespace sen3bot::geometry
