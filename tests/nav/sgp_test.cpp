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
#include "sen3bot/nav/sgp.hpp"

namespace sen3bot::nav {
namespace {

constexpr double kH = 1e-6;

void expect_gradient(const SafeCurve& p, double x, double y) {
  const Point2D g = p.gradient(x, y);
  EXPECT_NEAR(g.x_m, (p.value(x + kH, y) - p.value(x - kH, y)) / (2 * kH), 1e-5 * (1.0 + std::abs(g.x_m)));
  EXPECT_NEAR(g.y_m, (p.value(x, y + kH) - p.value(x, y - kH)) / (2 * kH), 1e-5 * (1.0 + std::abs(g.y_m)));
}

TEST(SafeCurve, NamedShapesVanishOnTheirCurveAndAreDistancesNearIt) {
  const SafeCurve line = SafeCurve::line({1.0, 1.0}, {4.0, 5.0});
  EXPECT_NEAR(line.value(2.5, 3.0), 0.0, 1e-12);
  EXPECT_NEAR(std::abs(line.value(1.0 + 0.8, 1.0 - 0.6)), 1.0, 1e-12);  // 1 m along the normal
  const SafeCurve circle = SafeCurve::circle({2.0, -1.0}, 1.5);
  for (int k = 0; k < 8; ++k) {
    const double a = k * std::numbers::pi / 4.0;
    EXPECT_NEAR(circle.value(2.0 + 1.5 * std::cos(a), -1.0 + 1.5 * std::sin(a)), 0.0, 1e-12);
    // 5 cm outside: p about +5 cm; grad p of length 1 on V.
    EXPECT_NEAR(circle.value(2.0 + 1.55 * std::cos(a), -1.0 + 1.55 * std::sin(a)), 0.05, 1e-3);
    const Point2D g = circle.gradient(2.0 + 1.5 * std::cos(a), -1.0 + 1.5 * std::sin(a));
    EXPECT_NEAR(std::hypot(g.x_m, g.y_m), 1.0, 1e-12);
  }
  const SafeCurve ellipse = SafeCurve::ellipse({0.5, 0.5}, 3.0, 1.0, 0.4);
  for (int k = 0; k < 8; ++k) {
    const double a = k * std::numbers::pi / 4.0;
    const double u = 3.0 * std::cos(a);
    const double v = 1.0 * std::sin(a);
    EXPECT_NEAR(ellipse.value(0.5 + std::cos(0.4) * u - std::sin(0.4) * v, 0.5 + std::sin(0.4) * u + std::cos(0.4) * v), 0.0,
                1e-12);
  }
  EXPECT_LT(ellipse.value(0.5, 0.5), 0.0);
}

TEST(SafeCurve, GradientsMatchFiniteDifferences) {
  SafeCurve general;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> c(-1.0, 1.0);
  for (int i = 0; i <= SafeCurve::kMaxDegree; ++i)
    for (int j = 0; i + j <= SafeCurve::kMaxDegree; ++j) general.set_coefficient(i, j, c(rng));
  for (const SafeCurve& p : {general, SafeCurve::line({0, 0}, {1, 2}), SafeCurve::circle({1, 1}, 2.0),
                             SafeCurve::ellipse({-1, 2}, 2.0, 0.7, 1.0)}) {
    for (const auto& [x, y] : {std::pair{0.3, -0.7}, std::pair{1.5, 2.0}, std::pair{-2.0, 0.4}}) expect_gradient(p, x, y);
  }
}

struct Planner {
  explicit Planner(SgpConfig c = {}) : config(c) { EXPECT_TRUE(sgp.init(config, arena)); }
  SgpConfig config;
  mem::BudgetArena arena{"sgp", 1 << 20};
  SupervisoryPlanner sgp;
};

TEST(Sgp, BarrierAndItsGradientMatchFiniteDifferences) {
  Planner p;
  const std::vector<Ellipse> es = {Ellipse::from_axes(0.0, 0.0, 1.0, 0.3, 0.2), Ellipse::from_axes(3.0, 1.0, 0.5, 0.5, 0.0),
                                   Ellipse::from_axes(-2.0, 3.0, 2.0, 0.05, 1.3)};
  ASSERT_TRUE(p.sgp.set_obstacles(es));
  EXPECT_EQ(p.sgp.barrier(0.0, 0.0), 0.0);  // inside
  EXPECT_NEAR(p.sgp.barrier(1.0 * std::cos(0.2), 1.0 * std::sin(0.2)), 0.0, 1e-12);  // on a boundary
  for (const auto& [x, y] : {std::pair{1.5, -1.0}, std::pair{0.0, 2.0}, std::pair{5.0, 5.0}, std::pair{2.2, 1.1}}) {
    const double b = p.sgp.barrier(x, y);
    EXPECT_GT(b, 0.0);
    EXPECT_LT(b, 1.0);
    const Point2D g = p.sgp.barrier_gradient(x, y);
    EXPECT_NEAR(g.x_m, (p.sgp.barrier(x + kH, y) - p.sgp.barrier(x - kH, y)) / (2 * kH), 1e-6);
    EXPECT_NEAR(g.y_m, (p.sgp.barrier(x, y + kH) - p.sgp.barrier(x, y - kH)) / (2 * kH), 1e-6);
  }
}

TEST(Sgp, WithoutObstaclesAPathConvergesOntoACircleFromInsideAndOutsideAndRunsAlongIt) {
  const Point2D centre{5.0, 5.0};
  const double r = 2.0;
  const Point2D goal{5.0, 7.5};  // its foot on V: the circle's top
  for (const Point2D start : {Point2D{5.5, 5.0}, Point2D{9.5, 6.0}}) {
    double lengths[2] = {};
    for (const int direction : {1, -1}) {
      Planner p;
      p.sgp.set_curve(SafeCurve::circle(centre, r));
      const SgpResult res = p.sgp.plan(start, goal, direction);
      const auto path = p.sgp.waypoints();
      ASSERT_GE(path.size(), 3u);
      EXPECT_EQ(res.stop, SgpStop::nearest_to_goal) << to_string(res.stop);
      EXPECT_TRUE(res.on_curve);
      EXPECT_NEAR(path.back().x_m, 5.0, 0.08);
      EXPECT_NEAR(path.back().y_m, 7.0, 0.08);
      // Once on V it stays within 5 cm of it, going round the way zeta's sign says.
      std::size_t first_on = path.size();
      for (std::size_t i = 0; i < path.size(); ++i) {
        const double off = std::hypot(path[i].x_m - centre.x_m, path[i].y_m - centre.y_m) - r;
        if (first_on == path.size() && std::abs(off) < 0.05) first_on = i;
        if (first_on < path.size()) {
          EXPECT_LT(std::abs(off), 0.05) << i;
        }
      }
      ASSERT_LT(first_on + 2, path.size());
      for (std::size_t i = first_on + 1; i < path.size(); ++i) {
        const double a0 = std::atan2(path[i - 1].y_m - centre.y_m, path[i - 1].x_m - centre.x_m);
        const double a1 = std::atan2(path[i].y_m - centre.y_m, path[i].x_m - centre.x_m);
        EXPECT_GT(direction * std::remainder(a1 - a0, 2.0 * std::numbers::pi), 0.0) << i;
      }
      lengths[direction > 0 ? 0 : 1] = res.length_m;
    }
    // Left to choose, the planner takes the shorter way round.
    Planner p;
    p.sgp.set_curve(SafeCurve::circle(centre, r));
    const SgpResult chosen = p.sgp.plan(start, goal);
    EXPECT_DOUBLE_EQ(chosen.length_m, std::min(lengths[0], lengths[1]));
  }
}

TEST(Sgp, AlongALineItGoesTowardsTheGoalAndStopsAtItsFoot) {
  for (const double gx : {9.0, 1.0}) {
    Planner p;
    p.sgp.set_curve(SafeCurve::line({0.0, 2.0}, {10.0, 2.0}));
    const SgpResult res = p.sgp.plan({5.0, 4.0}, {gx, 3.0});
    EXPECT_EQ(res.stop, SgpStop::nearest_to_goal) << to_string(res.stop);
    const auto path = p.sgp.waypoints();
    EXPECT_NEAR(path.back().x_m, gx, 0.08);
    EXPECT_NEAR(path.back().y_m, 2.0, 0.05);
    for (std::size_t i = 1; i < path.size(); ++i) EXPECT_GT((gx - 5.0) * (path[i].x_m - path[i - 1].x_m), 0.0) << i;
    // The waypoints are spaced as configured (the last may be closer).
    for (std::size_t i = 1; i + 1 < path.size(); ++i)
      EXPECT_NEAR(std::hypot(path[i].x_m - path[i - 1].x_m, path[i].y_m - path[i - 1].y_m), 0.25, 0.03) << i;
  }
}

TEST(Sgp, TheBarrierKeepsAPathAimedAtAnObstacleOutsideItsEllipse) {
  // V: the line y = 0. An obstacle straight between the start and V.
  const Ellipse rock = Ellipse::from_axes(3.0, 1.2, 1.5, 0.4, 0.0);
  Planner p;
  ASSERT_TRUE(p.sgp.set_obstacles(std::span(&rock, 1)));
  p.sgp.set_curve(SafeCurve::line({0.0, 0.0}, {10.0, 0.0}));
  const SgpResult res = p.sgp.plan({3.0, 3.0}, {8.0, 0.0});
  EXPECT_EQ(res.stop, SgpStop::nearest_to_goal) << to_string(res.stop);
  EXPECT_GT(res.min_barrier, 0.0);
  const auto path = p.sgp.waypoints();
  for (const Point2D& q : path) EXPECT_GT(rock.value(q.x_m, q.y_m), 0.0) << q.x_m << ", " << q.y_m;
  EXPECT_NEAR(path.back().x_m, 8.0, 0.06);
  EXPECT_NEAR(path.back().y_m, 0.0, 0.05);
  // Without the barrier's weight the field goes straight for V and meets the rock.
  SgpConfig blind_config;
  blind_config.barrier_k = 0.0;
  Planner blind(blind_config);
  ASSERT_TRUE(blind.sgp.set_obstacles(std::span(&rock, 1)));
  blind.sgp.set_curve(SafeCurve::line({0.0, 0.0}, {10.0, 0.0}));
  const SgpResult bumped = blind.sgp.plan({3.0, 3.0}, {8.0, 0.0});
  EXPECT_NE(bumped.stop, SgpStop::nearest_to_goal) << to_string(bumped.stop);
}

TEST(Sgp, TheSameInputsGiveTheSameBytesAndPlanAllocatesNothing) {
  const std::vector<Ellipse> es = {Ellipse::from_axes(3.0, 1.2, 0.8, 0.4, 0.3), Ellipse::from_axes(6.0, -1.5, 1.0, 0.2, -0.5)};
  Planner a;
  Planner b;
  for (Planner* p : {&a, &b}) {
    ASSERT_TRUE(p->sgp.set_obstacles(es));
    p->sgp.set_curve(SafeCurve::ellipse({5.0, 0.0}, 4.0, 2.5, 0.1));
  }
  const SgpResult ra = a.sgp.plan({1.0, 3.5}, {9.0, -1.0});
  mem::testing::AllocationScope scope;
  const SgpResult rb = b.sgp.plan({1.0, 3.5}, {9.0, -1.0});
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(ra.steps, rb.steps);
  ASSERT_EQ(a.sgp.waypoints().size(), b.sgp.waypoints().size());
  EXPECT_EQ(std::memcmp(a.sgp.waypoints().data(), b.sgp.waypoints().data(), a.sgp.waypoints().size_bytes()), 0);
}

TEST(Sgp, AStartInsideAnObstacleOrTooManyEllipsesIsReported) {
  SgpConfig small;
  small.max_ellipses = 1;
  Planner p(small);
  const std::vector<Ellipse> two = {Ellipse::from_axes(0, 0, 1, 1, 0), Ellipse::from_axes(5, 0, 1, 1, 0)};
  const Status s = p.sgp.set_obstacles(two);
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code(), Errc::capacity);
  ASSERT_TRUE(p.sgp.set_obstacles(std::span(two).first(1)));
  p.sgp.set_curve(SafeCurve::circle({0, 0}, 3.0));
  EXPECT_EQ(p.sgp.plan({0.2, 0.1}, {3.0, 0.0}).stop, SgpStop::start_inside);
  EXPECT_EQ(p.sgp.waypoints().size(), 1u);
}

TEST(SgpSite, ACurveThroughAnEllipseIsRefusedWithThePlace) {
  // A 2 m bar along y = 1 around x = 3; the line x = 3.5 passes through its ellipse at y = 1.
  const Ellipse bar = Ellipse::from_axes(3.0, 1.0, 1.4, 0.15, 0.0);
  const CurveBounds bounds{0.0, -2.0, 8.0, 4.0};
  const Status s = check_curve(SafeCurve::line({3.5, -5.0}, {3.5, 5.0}), bounds, std::span(&bar, 1));
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code(), Errc::config);
  const std::string message = s.error().c_str();
  EXPECT_NE(message.find("crosses obstacle ellipse 0"), std::string::npos) << message;
  EXPECT_NE(message.find("centre (3.00, 1.00) m"), std::string::npos) << message;
  // The place: on the line, within the bar's ellipse.
  double x = 0, y = 0;
  ASSERT_EQ(std::sscanf(message.c_str() + message.rfind(" at ("), " at (%lf, %lf)", &x, &y), 2) << message;
  EXPECT_NEAR(x, 3.5, 1e-6);
  EXPECT_LT(bar.value(x, y), 1e-6);
  // Clear of it, or with bounds that leave the crossing out, the curve is accepted.
  EXPECT_TRUE(check_curve(SafeCurve::line({5.0, -5.0}, {5.0, 5.0}), bounds, std::span(&bar, 1)));
  EXPECT_TRUE(check_curve(SafeCurve::line({3.5, -5.0}, {3.5, 5.0}), CurveBounds{0.0, -2.0, 8.0, 0.5}, std::span(&bar, 1)));
  // A curve that merely grazes the ellipse (tangent at its top) is refused too.
  const Status graze = check_curve(SafeCurve::line({0.0, 1.15}, {8.0, 1.15}), bounds, std::span(&bar, 1));
  EXPECT_FALSE(graze);
  // A circle wholly outside the bounds is not there at all.
  const Status away = check_curve(SafeCurve::circle({20.0, 20.0}, 1.0), bounds, {});
  ASSERT_FALSE(away);
  EXPECT_NE(std::string(away.error().c_str()).find("does not pass through its bounds"), std::string::npos);
}

TEST(SgpSite, OnlyEllipsesReachingTheBoundsCountAndAPathStopsAtThem) {
  Planner p;
  const std::vector<Ellipse> es = {Ellipse::from_axes(2.0, 2.0, 0.5, 0.3, 0.0), Ellipse::from_axes(20.0, 2.0, 0.5, 0.3, 0.0)};
  const CurveBounds bounds{0.0, 0.0, 6.0, 4.0};
  ASSERT_TRUE(p.sgp.set_site(SafeCurve::line({-10.0, 1.0}, {10.0, 1.0}), bounds, es));
  ASSERT_EQ(p.sgp.obstacles().size(), 1u);
  EXPECT_EQ(p.sgp.obstacles()[0].cx_m, 2.0);
  // The goal's foot (9, 1) lies beyond the bounds: the path ends at their edge, on V.
  const SgpResult r = p.sgp.plan({1.0, 3.0}, {9.0, 1.0});
  EXPECT_EQ(r.stop, SgpStop::left_bounds) << to_string(r.stop);
  EXPECT_TRUE(r.on_curve);
  EXPECT_GT(p.sgp.waypoints().back().x_m, 6.0 - 0.03);
  EXPECT_NEAR(p.sgp.waypoints().back().y_m, 1.0, 0.05);
  for (const Point2D& q : p.sgp.waypoints()) EXPECT_TRUE(bounds.contains(q.x_m, q.y_m));
  // A start outside them has no path.
  EXPECT_EQ(p.sgp.plan({7.0, 2.0}, {9.0, 1.0}).stop, SgpStop::left_bounds);
  EXPECT_EQ(p.sgp.waypoints().size(), 1u);
}

TEST(SgpSite, AScaledPolynomialIsOnItsCurveByDistanceNotByValue) {
  // p = 40 (y - 1): |p| reaches 0.05 at 1.25 mm from V; on V is |p| / |grad p| < on_curve_m.
  SafeCurve steep;
  steep.set_coefficient(0, 1, 40.0);
  steep.set_coefficient(0, 0, -40.0);
  Planner p;
  p.sgp.set_curve(steep);
  const SgpResult r = p.sgp.plan({0.0, 3.0}, {5.0, 0.0});
  EXPECT_EQ(r.stop, SgpStop::nearest_to_goal) << to_string(r.stop);
  EXPECT_NEAR(p.sgp.waypoints().back().x_m, 5.0, 0.08);
  EXPECT_NEAR(p.sgp.waypoints().back().y_m, 1.0, 0.05);
}

TEST(SgpSite, TheMapExtentCoversARotatedMap) {
  OccupancyMap map(40, 20, 0.05, 1.0, 2.0, std::numbers::pi / 2);  // 2 m x 1 m, turned a quarter
  const CurveBounds b = map_extent(map);
  EXPECT_NEAR(b.x0_m, 0.0, 1e-9);
  EXPECT_NEAR(b.x1_m, 1.0, 1e-9);
  EXPECT_NEAR(b.y0_m, 2.0, 1e-9);
  EXPECT_NEAR(b.y1_m, 4.0, 1e-9);
}

}  // namespace
}  // namespace sen3bot::nav
