#include <gtest/gtest.h>

#include <cmath>
#include <memory_resource>
#include <random>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/mem/budget_arena.hpp"
#include "sen3bot/nav/costmap.hpp"

namespace sen3bot::nav {
namespace {

OccupancyMap random_map(int w, int h, double density, unsigned seed) {
  OccupancyMap m(w, h, 0.05, 0.0, 0.0);
  std::mt19937 rng(seed);
  std::bernoulli_distribution occupied(density);
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c) m.set(c, r, occupied(rng) ? 100 : 0);
  return m;
}

TEST(Inflation, CostFormulaMatchesNav2) {
  InflationLayerConfig cfg;
  cfg.inscribed_radius_m = 0.2;
  cfg.inflation_radius_m = 0.6;
  cfg.cost_scaling_factor = 10.0;
  EXPECT_EQ(InflationLayer::cost_at(0.0, cfg), kLethalCost);
  EXPECT_EQ(InflationLayer::cost_at(0.2, cfg), kInscribedCost);
  EXPECT_EQ(InflationLayer::cost_at(0.3, cfg), static_cast<int>(252 * std::exp(-1.0)));
  EXPECT_EQ(InflationLayer::cost_at(0.61, cfg), kFreeCost);
}

TEST(Inflation, MatchesDoublePrecisionReferenceWithinOne) {
  for (unsigned seed = 1; seed <= 4; ++seed) {
    const OccupancyMap map = random_map(70, 55, 0.02 * seed, seed);
    mem::BudgetArena arena("test", 1 << 20);
    StaticLayer st(map);
    InflationLayerConfig icfg;
    icfg.inflation_radius_m = 0.55;
    icfg.cost_scaling_factor = 3.0 * seed;
    InflationLayer infl(icfg);
    LayeredCostmap cm;
    ASSERT_TRUE(cm.add_layer(st));
    ASSERT_TRUE(cm.add_layer(infl));
    ASSERT_TRUE(cm.init_over_map(map, arena));
    cm.update({});
    const Costmap2D& g = cm.costmap();
    for (int r = 0; r < g.height(); ++r) {
      for (int c = 0; c < g.width(); ++c) {
        double best = 1e300;
        for (int rr = 0; rr < g.height(); ++rr)
          for (int cc = 0; cc < g.width(); ++cc)
            if (map.at(cc, rr) == 100) best = std::min(best, std::hypot(cc - c, rr - r) * 0.05);
        int expect = 0;
        if (best == 0.0) {
          expect = 254;
        } else if (best <= icfg.inscribed_radius_m) {
          expect = 253;
        } else if (best <= icfg.inflation_radius_m) {
          expect = static_cast<int>(252.0 * std::exp(-icfg.cost_scaling_factor * (best - icfg.inscribed_radius_m)));
        }
        ASSERT_NEAR(g.at(c, r), expect, 1) << c << "," << r << " seed " << seed;
      }
    }
  }
}

ScanMessage ring_scan(double range_m, std::size_t count) {
  ScanMessage s;
  s.count = static_cast<std::uint16_t>(count);
  s.angle_min_rad = static_cast<float>(-M_PI / 2);
  s.increment_rad = static_cast<float>(M_PI / static_cast<double>(count - 1));
  s.range_max_m = 8.0f;
  for (std::size_t i = 0; i < count; ++i) s.ranges_m[i] = static_cast<float>(range_m);
  return s;
}

TEST(ObstacleLayer, MarksEndpointsAndClearsAlongRays) {
  mem::BudgetArena arena("test", 1 << 20);
  ObstacleLayer obs;
  LayeredCostmap cm;
  ASSERT_TRUE(cm.add_layer(obs));
  CostmapConfig cfg;
  cfg.rolling = true;
  ASSERT_TRUE(cm.init(cfg, arena));
  ScanMessage msg = ring_scan(1.0, 181);
  ProjectedScan view;
  view.assign(msg.view(), {});
  CostmapInputs in{{10.02, 10.02, 0.0}, {10.02, 10.02, 0.0}, &view};  // off cell boundaries
  cm.update(in);
  const Costmap2D& g = cm.costmap();
  EXPECT_EQ(g.width(), 120);
  int c = 0;
  int r = 0;
  ASSERT_TRUE(g.world_to_cell(11.02, 10.02, c, r));
  EXPECT_EQ(g.at(c, r), kLethalCost);
  ASSERT_TRUE(g.world_to_cell(10.52, 10.02, c, r));
  EXPECT_EQ(g.at(c, r), kFreeCost);
  // The obstacle goes away: the same beams now report far returns and clear it.
  msg = ring_scan(2.0, 181);
  view.assign(msg.view(), {});
  cm.update(in);
  ASSERT_TRUE(g.world_to_cell(11.02, 10.02, c, r));
  EXPECT_EQ(g.at(c, r), kFreeCost);
  ASSERT_TRUE(g.world_to_cell(12.02, 10.02, c, r));
  EXPECT_EQ(g.at(c, r), kLethalCost);
  // Beyond obstacle_max_range (2.5 m): not marked.
  msg = ring_scan(2.8, 181);
  view.assign(msg.view(), {});
  cm.update(in);
  ASSERT_TRUE(g.world_to_cell(12.82, 10.02, c, r));
  EXPECT_EQ(g.at(c, r), kFreeCost);
}

TEST(ObstacleLayer, MarksStayInPlaceWhenTheWindowRolls) {
  mem::BudgetArena arena("test", 1 << 20);
  ObstacleLayer obs;
  LayeredCostmap cm;
  ASSERT_TRUE(cm.add_layer(obs));
  CostmapConfig cfg;
  cfg.rolling = true;
  ASSERT_TRUE(cm.init(cfg, arena));
  ScanMessage msg = ring_scan(1.0, 3);
  ProjectedScan view;
  view.assign(msg.view(), {});
  cm.update({{10.02, 10.02, 0.0}, {10.02, 10.02, 0.0}, &view});
  cm.update({{10.73, 9.61, 0.0}, {10.73, 9.61, 0.0}, nullptr});
  int c = 0;
  int r = 0;
  ASSERT_TRUE(cm.costmap().world_to_cell(11.02, 10.02, c, r));
  EXPECT_EQ(cm.costmap().at(c, r), kLethalCost);
  ASSERT_TRUE(cm.costmap().world_to_cell(10.02, 11.02, c, r));
  EXPECT_EQ(cm.costmap().at(c, r), kLethalCost);
}

TEST(ObstacleLayer, ASonarEchoClearsAMarkTheLaserCannotSeeAnyMore) {
  // Someone walked past the robot's side: the laser marked them ahead of its mount, and the
  // mark, now behind the laser's plane, is never raytraced away. A rear transducer's echo from
  // farther away says its cone is empty up to there.
  mem::BudgetArena arena("test", 1 << 20);
  ObstacleLayer obs;
  LayeredCostmap cm;
  ASSERT_TRUE(cm.add_layer(obs));
  CostmapConfig cfg;
  cfg.rolling = true;
  ASSERT_TRUE(cm.init(cfg, arena));
  ScanMessage msg = ring_scan(0.5, 181);
  ProjectedScan view;
  view.assign(msg.view(), {});
  // Facing +y: the beam to the right ends at (10.52, 10.02).
  const Pose2D up{10.02, 10.02, M_PI / 2};
  cm.update({up, up, &view, 1'000'000'000});
  const Costmap2D& g = cm.costmap();
  int c = 0;
  int r = 0;
  ASSERT_TRUE(g.world_to_cell(10.52, 10.02, c, r));
  ASSERT_EQ(g.at(c, r), kLethalCost);
  // Turned to face -x, the laser sees 2 m of free space ahead; the mark is behind it.
  const Pose2D back{10.02, 10.02, M_PI};
  msg = ring_scan(2.0, 181);
  view.assign(msg.view(), {});
  const hal::Nanos now = 2'000'000'000;
  msg::Sonar sonar;
  sonar.count = 1;
  sonar.mount[0] = {-0.2, 0.0, M_PI};  // the rear disc looking back, 0.3 m short of the mark
  const auto update_with = [&](double range_m, hal::Nanos stamp_ns) {
    sonar.range_m[0] = range_m;
    sonar.stamp_ns[0] = stamp_ns;
    CostmapInputs in{back, back, &view, now};
    in.sonar = &sonar;
    cm.update(in);
    return g.at(c, r);
  };
  cm.update({back, back, &view, now});
  EXPECT_EQ(g.at(c, r), kLethalCost) << "without the sonar the mark stays";
  EXPECT_EQ(update_with(5.0, now), kLethalCost) << "a reading at the maximum may be a miss";
  EXPECT_EQ(update_with(1.5, now - 600'000'000), kLethalCost) << "a stale echo";
  EXPECT_EQ(update_with(0.32, now), kLethalCost) << "an echo from the mark itself";
  EXPECT_EQ(update_with(1.5, now), kFreeCost) << "an echo from beyond it";
  // The laser's own new marks stand even inside a cone that echoes from farther away.
  sonar.mount[0] = {0.2, 0.0, 0.0};  // a front disc looking along the laser
  msg = ring_scan(1.0, 181);
  view.assign(msg.view(), {});
  (void)update_with(3.0, now);
  ASSERT_TRUE(g.world_to_cell(9.02, 10.02, c, r));
  EXPECT_EQ(g.at(c, r), kLethalCost);
}

TEST(LayeredCostmap, RollingWindowCopiesTheStaticMapAndInflates) {
  OccupancyMap map(200, 200, 0.05, -1.0, -2.0);
  for (int r = 0; r < 200; ++r) map.set(100, r, 100);  // wall at x in [4.0, 4.05)
  mem::BudgetArena arena("test", 1 << 20);
  StaticLayer st(map);
  ObstacleLayer obs;
  InflationLayer infl;
  LayeredCostmap cm;
  ASSERT_TRUE(cm.add_layer(st));
  ASSERT_TRUE(cm.add_layer(obs));
  ASSERT_TRUE(cm.add_layer(infl));
  CostmapConfig cfg;
  cfg.rolling = true;
  cfg.lattice_x_m = -1.0;
  cfg.lattice_y_m = -2.0;
  ASSERT_TRUE(cm.init(cfg, arena));
  ScanMessage msg = ring_scan(3.0, 361);
  ProjectedScan view;
  view.assign(msg.view(), {});
  const CostmapInputs in{{3.0, 3.0, 0.0}, {3.0, 3.0, 0.0}, &view};
  cm.update(in);
  const Costmap2D& g = cm.costmap();
  int c = 0;
  int r = 0;
  ASSERT_TRUE(g.world_to_cell(4.02, 3.0, c, r));
  EXPECT_EQ(g.at(c, r), kLethalCost);
  ASSERT_TRUE(g.world_to_cell(3.87, 3.0, c, r));
  EXPECT_EQ(g.at(c, r), kInscribedCost);
  ASSERT_TRUE(g.world_to_cell(3.0, 3.0, c, r));
  EXPECT_EQ(g.at(c, r), kFreeCost);
  // Steady-state updates allocate nothing.
  mem::testing::AllocationScope scope;
  for (int i = 0; i < 200; ++i) {
    CostmapInputs moving = in;
    moving.robot_pose.x_m += 0.01 * i;
    moving.scan_pose.x_m += 0.01 * i;
    cm.update(moving);
  }
  EXPECT_EQ(scope.allocations(), 0u);
}

}  // namespace
}  // namespace sen3bot::nav
