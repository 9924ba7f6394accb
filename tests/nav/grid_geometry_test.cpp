#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "sen3bot/nav/costmap.hpp"
#include "sen3bot/nav/grid_geometry.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/mem/budget_arena.hpp"

namespace sen3bot::nav {
namespace {

TEST(GridGeometry, CellEdgesBelongToTheHigherCell) {
  const GridGeometry g(10, 5, 0.5, 0.0, 0.0);
  int c = -7;
  int r = -7;
  ASSERT_TRUE(g.world_to_cell(0.0, 0.0, c, r));
  EXPECT_EQ(c, 0);
  EXPECT_EQ(r, 0);
  ASSERT_TRUE(g.world_to_cell(0.5, 0.49, c, r));
  EXPECT_EQ(c, 1);
  EXPECT_EQ(r, 0);
  ASSERT_TRUE(g.world_to_cell(4.999, 2.499, c, r));
  EXPECT_EQ(c, 9);
  EXPECT_EQ(r, 4);
  // The far edges are outside: cell (c, r) spans [c, c + 1).
  EXPECT_FALSE(g.world_to_cell(5.0, 1.0, c, r));
  EXPECT_EQ(c, 10);
  EXPECT_FALSE(g.world_to_cell(1.0, 2.5, c, r));
  EXPECT_EQ(r, 5);
}

TEST(GridGeometry, NegativeOriginAndCoordinatesFloorDownwards) {
  const GridGeometry g(8, 8, 0.25, -1.0, -2.0);
  int c = 0;
  int r = 0;
  ASSERT_TRUE(g.world_to_cell(-1.0, -2.0, c, r));
  EXPECT_EQ(c, 0);
  EXPECT_EQ(r, 0);
  ASSERT_TRUE(g.world_to_cell(-0.1, -1.76, c, r));
  EXPECT_EQ(c, 3);
  EXPECT_EQ(r, 0);
  // Just below the origin is cell -1, not 0 (floor, not truncation).
  EXPECT_FALSE(g.world_to_cell(-1.01, -1.5, c, r));
  EXPECT_EQ(c, -1);
  EXPECT_EQ(r, 2);
  EXPECT_FALSE(g.world_to_cell(-3.1, -2.01, c, r));
  EXPECT_EQ(c, -9);
  EXPECT_EQ(r, -1);
}

TEST(GridGeometry, FarAndInvalidPointsAreOutsideWithoutOverflow) {
  const GridGeometry g(8, 8, 0.05, 0.0, 0.0);
  int c = 0;
  int r = 0;
  EXPECT_FALSE(g.world_to_cell(1e30, -1e30, c, r));
  EXPECT_GT(c, 8);
  EXPECT_LT(r, 0);
  EXPECT_FALSE(g.world_to_cell(std::numeric_limits<double>::quiet_NaN(), 0.1, c, r));
  EXPECT_FALSE(g.world_to_cell(0.1, std::numeric_limits<double>::infinity(), c, r));
}

TEST(GridGeometry, CellCentresRoundTrip) {
  const GridGeometry g(12, 7, 0.1, -0.55, 3.2);
  for (int r = -1; r <= 7; ++r) {
    for (int c = -1; c <= 12; ++c) {
      double x = 0.0;
      double y = 0.0;
      g.cell_to_world(c, r, x, y);
      EXPECT_NEAR(x, -0.55 + (c + 0.5) * 0.1, 1e-12);
      EXPECT_NEAR(y, 3.2 + (r + 0.5) * 0.1, 1e-12);
      int c2 = 0;
      int r2 = 0;
      EXPECT_EQ(g.world_to_cell(x, y, c2, r2), g.in_bounds(c, r));
      EXPECT_EQ(c2, c);
      EXPECT_EQ(r2, r);
    }
  }
}

TEST(GridGeometry, YawRotatesAboutTheOrigin) {
  const GridGeometry g(4, 4, 1.0, 10.0, 20.0, std::numbers::pi / 2.0);
  // Grid +x points along map +y: cell (2, 0)'s centre is 2.5 m up from the origin and
  // 0.5 m to its left.
  double x = 0.0;
  double y = 0.0;
  g.cell_to_world(2, 0, x, y);
  EXPECT_NEAR(x, 9.5, 1e-12);
  EXPECT_NEAR(y, 22.5, 1e-12);
  double gx = 0.0;
  double gy = 0.0;
  g.world_to_grid(9.5, 22.5, gx, gy);
  EXPECT_NEAR(gx, 2.5, 1e-12);
  EXPECT_NEAR(gy, 0.5, 1e-12);
}

TEST(GridGeometry, IndexIsRowMajorAndOriginMoves) {
  GridGeometry g(5, 3, 0.05, 0.0, 0.0);
  EXPECT_EQ(g.cell_count(), 15u);
  EXPECT_EQ(g.index(0, 0), 0u);
  EXPECT_EQ(g.index(4, 0), 4u);
  EXPECT_EQ(g.index(0, 1), 5u);
  EXPECT_EQ(g.index(4, 2), 14u);
  g.set_origin(1.0, -1.0);
  int c = 0;
  int r = 0;
  ASSERT_TRUE(g.world_to_cell(1.01, -0.99, c, r));
  EXPECT_EQ(c, 0);
  EXPECT_EQ(r, 0);
  EXPECT_EQ(g.width(), 5);
  EXPECT_EQ(g.resolution_m(), 0.05);
}

TEST(GridGeometry, MapAndCostmapShareIt) {
  const OccupancyMap map(30, 20, 0.05, -0.75, 0.5);
  mem::BudgetArena arena("test", 1 << 12);
  Costmap2D costmap;
  ASSERT_TRUE(costmap.init(30, 20, 0.05, arena));
  costmap.set_origin(-0.75, 0.5);
  for (const double x : {-0.8, -0.75, -0.01, 0.0, 0.724, 0.75}) {
    for (const double y : {0.45, 0.5, 1.0, 1.49, 1.5}) {
      int mc = 0;
      int mr = 0;
      int cc = 0;
      int cr = 0;
      EXPECT_EQ(map.world_to_cell(x, y, mc, mr), costmap.world_to_cell(x, y, cc, cr));
      EXPECT_EQ(mc, cc);
      EXPECT_EQ(mr, cr);
    }
  }
}

}  // namespace
}  // namespace sen3bot::nav
