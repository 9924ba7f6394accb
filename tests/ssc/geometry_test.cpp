#include <gtest/gtest.h>

#include <array>

#include "fixtures.hpp"
#include "sen3bot/ssc/site.hpp"

namespace sen3bot::ssc {
namespace {

using testing::area;
using testing::home;
using testing::rect;

TEST(SscGeometry, PointInPolygonCountsTheBoundaryAsInside) {
  const Polygon square = rect(0, 0, 2, 2);
  EXPECT_TRUE(contains(square.as_span(), {1, 1}));
  EXPECT_TRUE(contains(square.as_span(), {0, 1}));  // on an edge
  EXPECT_TRUE(contains(square.as_span(), {2, 2}));  // on a corner
  EXPECT_FALSE(contains(square.as_span(), {2.01, 1}));
  EXPECT_FALSE(contains(square.as_span(), {-1, -1}));
  // A concave L: the notch is outside.
  const std::array<Point, 6> l{{{0, 0}, {3, 0}, {3, 1}, {1, 1}, {1, 3}, {0, 3}}};
  EXPECT_TRUE(contains(l, {0.5, 2.5}));
  EXPECT_TRUE(contains(l, {2.5, 0.5}));
  EXPECT_FALSE(contains(l, {2, 2}));
  EXPECT_DOUBLE_EQ(distance_to(l, {2, 2}), 1.0);
  EXPECT_DOUBLE_EQ(distance_to(l, {0.5, 0.5}), 0.0);
}

TEST(SscGeometry, SegmentAgainstPolygon) {
  const Polygon square = rect(0, 0, 2, 2);
  // Straight through: enters at x = 0, leaves at x = 2 on a segment from -2 to 4.
  const auto through = segment_span(square.as_span(), {-2, 1}, {4, 1});
  ASSERT_TRUE(through);
  EXPECT_NEAR(through->first, 2.0 / 6, 1e-9);
  EXPECT_NEAR(through->last, 4.0 / 6, 1e-9);
  // Starts inside, ends outside.
  const auto out = segment_span(square.as_span(), {1, 1}, {5, 1});
  ASSERT_TRUE(out);
  EXPECT_DOUBLE_EQ(out->first, 0);
  EXPECT_NEAR(out->last, 0.25, 1e-9);
  // Wholly inside.
  const auto inside = segment_span(square.as_span(), {0.5, 0.5}, {1.5, 1.5});
  ASSERT_TRUE(inside);
  EXPECT_DOUBLE_EQ(inside->first, 0);
  EXPECT_DOUBLE_EQ(inside->last, 1);
  // Misses, and grazes along an edge.
  EXPECT_FALSE(intersects(square.as_span(), {-1, 3}, {3, 3}));
  EXPECT_FALSE(intersects(square.as_span(), {3, -1}, {3, 5}));
  EXPECT_TRUE(intersects(square.as_span(), {-1, 2}, {3, 2}));
  // Diagonal across a corner.
  EXPECT_TRUE(intersects(square.as_span(), {1, 3}, {3, 1}));
  EXPECT_FALSE(intersects(square.as_span(), {2.5, 3}, {3, 2.5}));
}

TEST(SscGeometry, RouteCrossesAreasInRouteOrderWithDistances) {
  Site site;
  (void)site.areas.push_back(area(1, "far", AreaType::blind_intersection, rect(20, -1, 22, 1), {{21, 2, 0}}));
  (void)site.areas.push_back(area(2, "near", AreaType::workstation, rect(5, -1, 7, 1), {{6, 2, 0}}));
  (void)site.areas.push_back(area(3, "aside", AreaType::transition, rect(5, 5, 7, 7), {{6, 8, 0}}));
  (void)site.areas.push_back(area(4, "store", AreaType::not_monitored, rect(10, -1, 12, 1)));
  ASSERT_TRUE(site.validate());

  // An L-shaped route: along x to 25, then up.
  const std::array<Point, 3> route{{{0, 0}, {25, 0}, {25, 10}}};
  const Crossings hits = crossings(site, route);
  ASSERT_EQ(hits.size(), 2u);
  EXPECT_EQ(hits[0].area, 2);
  EXPECT_NEAR(hits[0].entry, 5, 1e-9);
  EXPECT_NEAR(hits[0].exit, 7, 1e-9);
  EXPECT_EQ(hits[1].area, 1);
  EXPECT_NEAR(hits[1].entry, 20, 1e-9);
  EXPECT_NEAR(hits[1].exit, 22, 1e-9);

  const Crossings all = crossings(site, route, /*include_unmonitored=*/true);
  ASSERT_EQ(all.size(), 3u);
  EXPECT_EQ(all[1].area, 4);

  // Standing inside an area, and a route that starts inside.
  const std::array<Point, 1> standing{{{6, 0}}};
  ASSERT_EQ(crossings(site, standing).size(), 1u);
  EXPECT_EQ(crossings(site, standing)[0].entry, 0);
  const std::array<Point, 2> leaving{{{6, 0}, {6, -5}}};
  ASSERT_EQ(crossings(site, leaving).size(), 1u);
  EXPECT_NEAR(crossings(site, leaving)[0].exit, 1, 1e-9);
  EXPECT_TRUE(crossings(site, std::span<const Point>{}).empty());

  // The second leg only: distances count from the route's own start.
  const std::array<Point, 3> detour{{{6, 10}, {6, 3}, {6, -3}}};
  const Crossings d = crossings(site, detour);
  ASSERT_EQ(d.size(), 2u);
  EXPECT_EQ(d[0].area, 3);
  EXPECT_NEAR(d[0].entry, 3, 1e-9);
  EXPECT_EQ(d[1].area, 2);
  EXPECT_NEAR(d[1].entry, 9, 1e-9);
}

TEST(SscGeometry, SiteValidation) {
  Site site;
  (void)site.areas.push_back(area(1, "x", AreaType::blind_intersection, rect(0, 0, 1, 1)));
  EXPECT_FALSE(site.validate());  // monitored, no sentry pose, no home overlooking it
  (void)site.robots.push_back(home(0, "r0", {0, -1, 0}, 1));
  EXPECT_TRUE(site.validate());
  (void)site.robots.push_back(home(1, "r1", {0, -1, 0}, 9));
  EXPECT_FALSE(site.validate());  // overlooks an unknown area
  site.robots.pop_back();
  (void)site.areas.push_back(area(1, "dup", AreaType::not_monitored, rect(0, 0, 1, 1)));
  EXPECT_FALSE(site.validate());
  site.areas.back().id = 2;
  site.areas.back().outline = rect(0, 0, 1, 0);  // no surface
  EXPECT_FALSE(site.validate());
  EXPECT_EQ(to_string(AreaType::transition), "1.2");
}

}  // namespace
}  // namespace sen3bot::ssc
