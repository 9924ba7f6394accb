#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstring>
#include <numbers>
#include <random>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/mem/budget_arena.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/nav/map_ellipses.hpp"
#include "sen3bot/nav/waypoints.hpp"

namespace sen3bot::nav {
namespace {


Ellipse fit_points(const std::vector<Point2D>& points) {
  std::vector<double> work(points.size());
  Ellipse e;
  EXPECT_TRUE(enclosing_ellipse(points, work, 1e-6, 100000, e));
  return e;
}

std::vector<Point2D> rectangle(double cx, double cy, double length, double width, double angle) {
  std::vector<Point2D> out;
  const double c = std::cos(angle);
  const double s = std::sin(angle);
  for (const double a : {-0.5, 0.5}) {
    for (const double b : {-0.5, 0.5}) {
      const double x = a * length;
      const double y = b * width;
      out.push_back({cx + c * x - s * y, cy + s * x + c * y});
    }
  }
  return out;
}

void expect_contains(const Ellipse& e, const std::vector<Point2D>& points) {
  for (const Point2D& p : points) EXPECT_LE(e.value(p.x_m, p.y_m), 1e-9) << p.x_m << ", " << p.y_m;
}

TEST(EnclosingEllipse, RectanglesAndRotatedBarsAreWithinAHairOfTheirMinimum) {
  // A rectangle's minimal enclosing ellipse has the semi-axes l / sqrt 2 and w / sqrt 2: area
  // pi l w / 2, its major axis along the rectangle's.
  for (const double angle : {0.0, 0.3, std::numbers::pi / 4.0, 1.2, -0.7}) {
    for (const auto& [l, w] : {std::pair{2.0, 1.0}, std::pair{4.0, 0.1}, std::pair{1.0, 1.0}}) {
      const auto corners = rectangle(3.0, -2.0, l, w, angle);
      const Ellipse e = fit_points(corners);
      expect_contains(e, corners);
      EXPECT_LE(e.area_m2(), 1.10 * std::numbers::pi * l * w / 2.0);
      EXPECT_NEAR(e.area_m2(), std::numbers::pi * l * w / 2.0, 1e-3 * l * w);
      EXPECT_NEAR(e.cx_m, 3.0, 1e-3);
      EXPECT_NEAR(e.cy_m, -2.0, 1e-3);
      if (l > w) {
        EXPECT_NEAR(e.semi_major_m, l / std::sqrt(2.0), 1e-3 * l);
        EXPECT_NEAR(e.semi_minor_m, w / std::sqrt(2.0), 1e-3 * l);
        // The major axis along the bar (an axis has no sign).
        const double off = std::remainder(e.angle_rad - angle, std::numbers::pi);
        EXPECT_NEAR(off, 0.0, 1e-3);
      }
    }
  }
}

TEST(EnclosingEllipse, ADiscIsItsOwnEllipse) {
  std::vector<Point2D> points;
  std::mt19937 rng(3);
  std::uniform_real_distribution<double> u(0.0, 1.0);
  for (int i = 0; i < 64; ++i) {
    const double a = 2.0 * std::numbers::pi * i / 64.0;
    points.push_back({1.0 + 0.5 * std::cos(a), 2.0 + 0.5 * std::sin(a)});
  }
  for (int i = 0; i < 200; ++i) {  // and points inside, which change nothing
    const double a = 2.0 * std::numbers::pi * u(rng);
    const double r = 0.5 * std::sqrt(u(rng));
    points.push_back({1.0 + r * std::cos(a), 2.0 + r * std::sin(a)});
  }
  const Ellipse e = fit_points(points);
  expect_contains(e, points);
  EXPECT_NEAR(e.area_m2(), std::numbers::pi * 0.25, 0.01 * std::numbers::pi * 0.25);
  EXPECT_NEAR(e.semi_major_m, 0.5, 0.005);
  EXPECT_NEAR(e.semi_minor_m, 0.5, 0.005);
}

TEST(EnclosingEllipse, TooFewOrCollinearPointsAreRefused) {
  std::vector<double> work(8);
  Ellipse e;
  const std::vector<Point2D> two = {{0, 0}, {1, 1}};
  EXPECT_FALSE(enclosing_ellipse(two, work, 1e-6, 1000, e));
  const std::vector<Point2D> line = {{0, 0}, {1, 1}, {2, 2}, {3, 3}};
  EXPECT_FALSE(enclosing_ellipse(line, work, 1e-6, 1000, e));
}

TEST(EllipseForm, ValueAndGradientAgreeWithFiniteDifferences) {
  const Ellipse e = Ellipse::from_axes(1.0, -1.0, 2.0, 0.5, 0.6);
  EXPECT_NEAR(e.value(1.0 + 2.0 * std::cos(0.6), -1.0 + 2.0 * std::sin(0.6)), 0.0, 1e-12);
  EXPECT_NEAR(e.value(1.0 - 0.5 * std::sin(0.6), -1.0 + 0.5 * std::cos(0.6)), 0.0, 1e-12);
  EXPECT_DOUBLE_EQ(e.value(1.0, -1.0), -1.0);
  constexpr double h = 1e-6;
  for (const auto& [x, y] : {std::pair{0.3, 0.2}, std::pair{-2.0, 1.5}, std::pair{4.0, -3.0}}) {
    const Point2D g = e.gradient(x, y);
    EXPECT_NEAR(g.x_m, (e.value(x + h, y) - e.value(x - h, y)) / (2 * h), 1e-5);
    EXPECT_NEAR(g.y_m, (e.value(x, y + h) - e.value(x, y - h)) / (2 * h), 1e-5);
  }
}

// --- From the map --------------------------------------------------------------------------------

struct Fitter {
  explicit Fitter(MapEllipsesConfig c = {}) : config(c), arena("ellipses", MapEllipses::storage_bytes(c)) {
    EXPECT_TRUE(ellipses.init(config, arena));
  }
  MapEllipsesConfig config;
  mem::BudgetArena arena;
  MapEllipses ellipses;
};

OccupancyMap empty_map(int w, int h) {
  OccupancyMap m(w, h, 0.05, -1.0, 2.0);
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) m.set(c, r, 0);
  return m;
}

// Every corner of every occupied cell inside one of the ellipses.
void expect_cells_inside(const OccupancyMap& map, std::span<const Ellipse> ellipses) {
  const GridGeometry& g = map.geometry();
  for (int r = 0; r < map.height(); ++r) {
    for (int c = 0; c < map.width(); ++c) {
      if (map.at(c, r) < 65) continue;
      for (const double dc : {0.0, 1.0}) {
        for (const double dr : {0.0, 1.0}) {
          double x = 0.0;
          double y = 0.0;
          g.grid_to_world(c + dc, r + dr, x, y);
          bool inside = false;
          for (const Ellipse& e : ellipses) inside = inside || e.value(x, y) <= 1e-9;
          EXPECT_TRUE(inside) << "cell " << c << ", " << r;
        }
      }
    }
  }
}

TEST(MapEllipses, ABlockAndAWallAreOneEllipseEach) {
  OccupancyMap map = empty_map(120, 100);
  for (int r = 20; r < 40; ++r)
    for (int c = 10; c < 30; ++c) map.set(c, r, 100);  // a 1 x 1 m block
  for (int c = 50; c < 110; ++c) map.set(c, 70, 100);  // a 3 m wall, one cell thick
  Fitter f;
  ASSERT_TRUE(f.ellipses.fit(map));
  ASSERT_EQ(f.ellipses.ellipses().size(), 2u);
  expect_cells_inside(map, f.ellipses.ellipses());
  const Ellipse& block = f.ellipses.ellipses()[0];
  const Ellipse& wall = f.ellipses.ellipses()[1];
  EXPECT_EQ(block.cells, 400u);
  EXPECT_NEAR(block.area_m2(), std::numbers::pi * 1.0 * 1.0 / 2.0, 0.01);
  EXPECT_EQ(wall.cells, 60u);
  EXPECT_NEAR(wall.area_m2(), std::numbers::pi * 3.0 * 0.05 / 2.0, 0.01);
  EXPECT_NEAR(std::remainder(wall.angle_rad, std::numbers::pi), 0.0, 1e-3);  // along x
  EXPECT_EQ(f.ellipses.splits(), 0u);
}

TEST(MapEllipses, ARasterisedRotatedBarStaysCloseToTheBarsMinimum) {
  OccupancyMap map = empty_map(160, 160);
  const double angle = 0.5;
  const double length = 5.0;
  const double width = 0.6;
  const GridGeometry& g = map.geometry();
  for (int r = 0; r < map.height(); ++r) {
    for (int c = 0; c < map.width(); ++c) {
      double x = 0.0;
      double y = 0.0;
      g.cell_to_world(c, r, x, y);
      const double dx = x - 3.0;
      const double dy = y - 6.0;
      const double along = std::cos(angle) * dx + std::sin(angle) * dy;
      const double across = -std::sin(angle) * dx + std::cos(angle) * dy;
      if (std::abs(along) <= length / 2 && std::abs(across) <= width / 2) map.set(c, r, 100);
    }
  }
  Fitter f;
  ASSERT_TRUE(f.ellipses.fit(map));
  ASSERT_EQ(f.ellipses.ellipses().size(), 1u);
  expect_cells_inside(map, f.ellipses.ellipses());
  const Ellipse& e = f.ellipses.ellipses()[0];
  // The raster's cells reach up to half a cell diagonal past the bar: the minimum for the bar
  // grown by that much.
  const double grow = 0.05 * std::sqrt(2.0);
  EXPECT_LE(e.area_m2(), 1.10 * std::numbers::pi * (length + grow) * (width + grow) / 2.0);
  EXPECT_GE(e.area_m2(), std::numbers::pi * length * width / 2.0);
  EXPECT_NEAR(std::remainder(e.angle_rad - angle, std::numbers::pi), 0.0, 0.02);
}

TEST(MapEllipses, AnLShapedRackIsSplitSoTheCornerStaysFree) {
  OccupancyMap map = empty_map(120, 120);
  for (int c = 20; c < 100; ++c)
    for (int r = 20; r < 26; ++r) map.set(c, r, 100);  // 4 m along x
  for (int r = 26; r < 100; ++r)
    for (int c = 20; c < 26; ++c) map.set(c, r, 100);  // 3.7 m up y
  Fitter f;
  ASSERT_TRUE(f.ellipses.fit(map));
  const auto es = f.ellipses.ellipses();
  EXPECT_GE(es.size(), 2u);
  EXPECT_GE(f.ellipses.splits(), 1u);
  expect_cells_inside(map, es);
  // The free corner inside the L is outside every ellipse.
  double x = 0.0;
  double y = 0.0;
  map.geometry().cell_to_world(70, 70, x, y);
  for (const Ellipse& e : es) EXPECT_GT(e.value(x, y), 0.0);
  // No ellipse is mostly free space.
  std::uint32_t cells = 0;
  for (const Ellipse& e : es) cells += e.cells;
  EXPECT_EQ(cells, 80u * 6u + 74u * 6u);
}

TEST(MapEllipses, TheWallsAroundARoomBecomeAChainThatLeavesTheRoomFree) {
  OccupancyMap map = empty_map(100, 80);
  for (int c = 0; c < 100; ++c) {
    map.set(c, 0, 100);
    map.set(c, 79, 100);
  }
  for (int r = 0; r < 80; ++r) {
    map.set(0, r, 100);
    map.set(99, r, 100);
  }
  Fitter f;
  ASSERT_TRUE(f.ellipses.fit(map));
  const auto es = f.ellipses.ellipses();
  EXPECT_GE(es.size(), 4u);
  expect_cells_inside(map, es);
  // The room's middle, and a point 0.4 m inside each wall, are free of every ellipse.
  for (const auto& [c, r] : {std::pair{50, 40}, std::pair{50, 8}, std::pair{50, 71}, std::pair{8, 40}, std::pair{91, 40}}) {
    double x = 0.0;
    double y = 0.0;
    map.geometry().cell_to_world(c, r, x, y);
    for (const Ellipse& e : es) EXPECT_GT(e.value(x, y), 0.0) << c << ", " << r;
  }
}

TEST(MapEllipses, TheSameMapGivesTheSameEllipsesAndFitAllocatesNothing) {
  OccupancyMap map = empty_map(100, 100);
  std::mt19937 rng(9);
  std::uniform_int_distribution<int> at(5, 90);
  for (int k = 0; k < 12; ++k) {
    const int c0 = at(rng);
    const int r0 = at(rng);
    for (int r = r0; r < r0 + 5; ++r)
      for (int c = c0; c < c0 + (k % 3 == 0 ? 9 : 3); ++c) map.set(c, r, 100);
  }
  Fitter a;
  Fitter b;
  ASSERT_TRUE(a.ellipses.fit(map));
  mem::testing::AllocationScope scope;
  ASSERT_TRUE(b.ellipses.fit(map));
  EXPECT_EQ(scope.allocations(), 0u);
  ASSERT_EQ(a.ellipses.ellipses().size(), b.ellipses.ellipses().size());
  for (std::size_t i = 0; i < a.ellipses.ellipses().size(); ++i) {
    const Ellipse& x = a.ellipses.ellipses()[i];
    const Ellipse& y = b.ellipses.ellipses()[i];
    EXPECT_EQ(std::memcmp(&x, &y, sizeof x), 0) << i;
  }
  expect_cells_inside(map, a.ellipses.ellipses());
}

TEST(MapEllipses, TooLargeAMapOrTooManyEllipsesIsAClearError) {
  MapEllipsesConfig small;
  small.max_map_cells = 50 * 50;
  small.max_map_rows = 50;
  small.max_ellipses = 2;
  Fitter f(small);
  const OccupancyMap big = empty_map(60, 60);
  const Status too_big = f.ellipses.fit(big);
  ASSERT_FALSE(too_big);
  EXPECT_EQ(too_big.error().code(), Errc::capacity);
  OccupancyMap three = empty_map(40, 40);
  for (const int c : {5, 15, 25}) three.set(c, 20, 100);
  const Status too_many = f.ellipses.fit(three);
  ASSERT_FALSE(too_many);
  EXPECT_NE(std::string(too_many.error().c_str()).find("more than 2 ellipses"), std::string::npos);
  EXPECT_TRUE(f.ellipses.ellipses().empty());
  // Exactly as many occupied cells as there is room for fit; one more does not.
  MapEllipsesConfig tight;
  tight.max_obstacle_cells = 12;
  Fitter g(tight);
  OccupancyMap bars = empty_map(40, 40);
  for (int c = 5; c < 11; ++c) {
    bars.set(c, 10, 100);
    bars.set(c, 30, 100);
  }
  ASSERT_TRUE(g.ellipses.fit(bars));
  EXPECT_EQ(g.ellipses.ellipses().size(), 2u);
  bars.set(20, 20, 100);
  const Status full = g.ellipses.fit(bars);
  ASSERT_FALSE(full);
  EXPECT_NE(std::string(full.error().c_str()).find("more than 12 occupied cells"), std::string::npos);
}

TEST(MapEllipses, TheLabsObstaclesLeaveItsSafePathsFree) {
  // The lab map of the thesis cases, and their hand-made safe paths: every waypoint, and every
  // point between two, outside every ellipse; every occupied cell inside one.
  Result<OccupancyMap> map = load_map(SEN3BOT_SOURCE_DIR "/config/maps/lab.yaml");
  ASSERT_TRUE(map) << map.error().c_str();
  Fitter f;
  ASSERT_TRUE(f.ellipses.fit(*map));
  const auto es = f.ellipses.ellipses();
  expect_cells_inside(*map, es);
  std::printf("lab: %zu ellipses from %zu splits\n", es.size(), f.ellipses.splits());
  for (const char* file : {"/config/maps/lab_waypoints.txt", "/config/maps/lab_waypoints_thesis.txt"}) {
    Result<std::vector<Point2D>> path = load_waypoints(std::string(SEN3BOT_SOURCE_DIR) + file);
    ASSERT_TRUE(path) << path.error().c_str();
    for (std::size_t i = 0; i + 1 < path->size(); ++i) {
      for (int k = 0; k <= 10; ++k) {
        const double x = (*path)[i].x_m + 0.1 * k * ((*path)[i + 1].x_m - (*path)[i].x_m);
        const double y = (*path)[i].y_m + 0.1 * k * ((*path)[i + 1].y_m - (*path)[i].y_m);
        for (const Ellipse& e : es) EXPECT_GT(e.value(x, y), 0.0) << file << " at " << x << ", " << y;
      }
    }
  }
}

}  // namespace
}  // namespace sen3bot::nav
