#include <gtest/gtest.h>

#include <cmath>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "movingai.hpp"
#include "sen3bot/mem/budget_arena.hpp"
#include "sen3bot/nav/global_planner.hpp"

namespace sen3bot::nav {
namespace {

struct Fixture {
  mem::BudgetArena arena{"planner", 4 << 20};
  GlobalPlanner planner;
  std::vector<GridCell> path = std::vector<GridCell>(20000);
};

class MovingAi : public ::testing::TestWithParam<const char*> {};

TEST_P(MovingAi, ReproducesOptimalLengths) {
  const std::string base = std::string(SEN3BOT_SOURCE_DIR) + "/tests/data/movingai/" + GetParam();
  testing::MovingAiMap map;
  ASSERT_TRUE(testing::load_movingai_map(base + ".map", map)) << base;
  const auto scenarios = testing::load_movingai_scen(base + ".map.scen");
  ASSERT_GE(scenarios.size(), 20u);
  Fixture fx;
  Costmap2D costmap;
  ASSERT_TRUE(costmap.init(map.width, map.height, 1.0, fx.arena));
  testing::fill_costmap(map, costmap);
  GlobalPlannerConfig cfg;
  cfg.unit_cost = true;
  cfg.max_cells = costmap.size();
  ASSERT_TRUE(fx.planner.init(cfg, fx.arena));
  for (const auto& s : scenarios) {
    const PlanResult r = fx.planner.plan(costmap, s.start, s.goal, {}, fx.path);
    ASSERT_TRUE(r.ok()) << to_string(r.status);
    EXPECT_NEAR(r.length_m, s.optimal, 1e-3) << s.start.col << "," << s.start.row << " -> " << s.goal.col << "," << s.goal.row;
    // The path is connected, 8-connected and never cuts a corner.
    for (std::size_t i = 1; i < r.cells; ++i) {
      const GridCell a = fx.path[i - 1];
      const GridCell b = fx.path[i];
      ASSERT_LE(std::abs(a.col - b.col), 1);
      ASSERT_LE(std::abs(a.row - b.row), 1);
      ASSERT_LT(costmap.at(b.col, b.row), kInscribedCost);
      if (a.col != b.col && a.row != b.row) {
        ASSERT_LT(costmap.at(b.col, a.row), kInscribedCost);
        ASSERT_LT(costmap.at(a.col, b.row), kInscribedCost);
      }
    }
  }
}

INSTANTIATE_TEST_SUITE_P(Maps, MovingAi,
                         ::testing::Values("random-32-32-10", "random-64-64-20", "maze-32-32-2", "room-32-32-4",
                                           "warehouse-64-32"));

// A 60 x 40 open room at 0.05 m with a wall segment in the middle.
Costmap2D& room(Fixture& fx, Costmap2D& costmap) {
  EXPECT_TRUE(costmap.init(60, 40, 0.05, fx.arena));
  costmap.fill(kFreeCost);
  for (int r = 10; r < 30; ++r) costmap.set(30, r, kLethalCost);
  return costmap;
}

TEST(GlobalPlanner, FailuresAreClearResults) {
  Fixture fx;
  Costmap2D costmap;
  room(fx, costmap);
  GlobalPlannerConfig cfg;
  cfg.max_cells = costmap.size();
  ASSERT_TRUE(fx.planner.init(cfg, fx.arena));
  EXPECT_EQ(fx.planner.plan(costmap, {-1, 0}, {5, 5}, {}, fx.path).status, PlanStatus::start_outside);
  EXPECT_EQ(fx.planner.plan(costmap, {1, 1}, {60, 5}, {}, fx.path).status, PlanStatus::goal_outside);
  EXPECT_EQ(fx.planner.plan(costmap, {30, 15}, {5, 5}, {}, fx.path).status, PlanStatus::start_blocked);
  EXPECT_EQ(fx.planner.plan(costmap, {1, 1}, {30, 20}, {}, fx.path).status, PlanStatus::goal_blocked);
  std::vector<GridCell> tiny(3);
  EXPECT_EQ(fx.planner.plan(costmap, {1, 1}, {50, 30}, {}, tiny).status, PlanStatus::path_too_long);
  for (int r = 0; r < 40; ++r) costmap.set(30, r, kLethalCost);
  EXPECT_EQ(fx.planner.plan(costmap, {1, 1}, {50, 30}, {}, fx.path).status, PlanStatus::no_path);
  GlobalPlanner capped;
  cfg.max_expansions = 10;
  ASSERT_TRUE(capped.init(cfg, fx.arena));
  EXPECT_EQ(capped.plan(costmap, {1, 1}, {20, 30}, {}, fx.path).status, PlanStatus::expansion_cap);
}

TEST(GlobalPlanner, CostAwareAndBitIdentical) {
  Fixture fx;
  Costmap2D costmap;
  room(fx, costmap);
  // A costly band the cheapest path goes around.
  for (int c = 10; c < 20; ++c)
    for (int r = 0; r < 15; ++r) costmap.set(c, r, kMaxNonObstacleCost);
  GlobalPlannerConfig cfg;
  cfg.max_cells = costmap.size();
  ASSERT_TRUE(fx.planner.init(cfg, fx.arena));
  const PlanResult a = fx.planner.plan(costmap, {2, 5}, {50, 5}, {}, fx.path);
  ASSERT_TRUE(a.ok());
  const std::vector<GridCell> first(fx.path.begin(), fx.path.begin() + static_cast<long>(a.cells));
  bool went_around = false;
  for (const auto& c : first) went_around |= c.row >= 15;
  EXPECT_TRUE(went_around);
  for (int i = 0; i < 5; ++i) {
    mem::testing::AllocationScope scope;
    const PlanResult b = fx.planner.plan(costmap, {2, 5}, {50, 5}, {}, fx.path);
    EXPECT_EQ(scope.allocations(), 0u);
    ASSERT_EQ(b.cells, a.cells);
    EXPECT_EQ(b.cost, a.cost);
    EXPECT_EQ(std::vector<GridCell>(fx.path.begin(), fx.path.begin() + static_cast<long>(b.cells)), first);
  }
}

TEST(GlobalPlanner, FollowsWaypointsInOrderWhenStartedOnThePath) {
  Fixture fx;
  Costmap2D costmap;
  ASSERT_TRUE(costmap.init(80, 60, 0.05, fx.arena));
  costmap.fill(kFreeCost);
  GlobalPlannerConfig cfg;
  cfg.max_cells = costmap.size();
  ASSERT_TRUE(fx.planner.init(cfg, fx.arena));
  // An arc bulging away from the straight line start -> goal, one waypoint every ~4 cells.
  std::vector<GridCell> waypoints;
  for (int i = 0; i <= 16; ++i) {
    const double t = i / 16.0;
    waypoints.push_back({static_cast<int>(std::lround(10 + 60 * t)),
                         static_cast<int>(std::lround(10 + 35 * std::sin(M_PI * t)))});
  }
  const GridCell start = waypoints.front();
  const GridCell goal = waypoints.back();
  const PlanResult r = fx.planner.plan(costmap, start, goal, waypoints, fx.path);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r.waypoints_passed, waypoints.size());
  std::size_t next = 0;
  for (std::size_t i = 0; i < r.cells && next < waypoints.size(); ++i) {
    const GridCell p = fx.path[i];
    if (std::abs(p.col - waypoints[next].col) <= 1 && std::abs(p.row - waypoints[next].row) <= 1) ++next;
  }
  EXPECT_EQ(next, waypoints.size()) << "passed within one cell of every waypoint, in order";
  const PlanResult plain = fx.planner.plan(costmap, start, goal, {}, fx.path);
  EXPECT_GT(r.length_m, plain.length_m * 1.3);  // it really followed the arc
}

TEST(GlobalPlanner, EqualsPlainAStarFarFromTheWaypoints) {
  Fixture fx;
  Costmap2D costmap;
  room(fx, costmap);
  GlobalPlannerConfig cfg;
  cfg.max_cells = costmap.size();
  ASSERT_TRUE(fx.planner.init(cfg, fx.arena));
  const PlanResult plain = fx.planner.plan(costmap, {5, 35}, {55, 35}, {}, fx.path);
  ASSERT_TRUE(plain.ok());
  const std::vector<GridCell> expected(fx.path.begin(), fx.path.begin() + static_cast<long>(plain.cells));
  const std::vector<GridCell> far_waypoints = {{5, 2}, {20, 2}, {40, 2}, {55, 2}};
  const PlanResult with = fx.planner.plan(costmap, {5, 35}, {55, 35}, far_waypoints, fx.path);
  ASSERT_TRUE(with.ok());
  EXPECT_EQ(with.waypoints_passed, 0);
  EXPECT_EQ(std::vector<GridCell>(fx.path.begin(), fx.path.begin() + static_cast<long>(with.cells)), expected);
}

}  // namespace
}  // namespace sen3bot::nav

namespace sen3bot::nav {
namespace {

// Two walls with a 0.5 m gap between them (x 1.0-1.5 m at 0.05 m) across a 3 x 2 m room,
// inflated as the planner task does: the gap is wide enough for the inscribed radius but not
// for the padded footprint, so a clearance bar of 0.28 m sends the plan around.
struct GapRoom {
  mem::BudgetArena arena{"gap", 4 << 20};
  Costmap2D costmap;
  InflationLayerConfig inflation;
  GapRoom() {
    EXPECT_TRUE(costmap.init(60, 40, 0.05, arena));
    costmap.fill(kFreeCost);
    for (int c = 0; c < 60; ++c) {
      if (c >= 20 && c < 30) continue;  // the 0.5 m gap
      if (c < 45) costmap.set(c, 20, kLethalCost);  // the wall stops 0.75 m short of the right side
    }
    InflationLayer layer(inflation);
    EXPECT_TRUE(layer.init(costmap, arena));
    layer.inflate(costmap);
  }
};

TEST(GlobalPlanner, ClearanceBandKeepsPlansOutOfNarrowGaps) {
  GapRoom room;
  Fixture fx;
  GlobalPlannerConfig cfg;
  cfg.max_cells = room.costmap.size();
  ASSERT_TRUE(fx.planner.init(cfg, fx.arena));
  const PlanResult through = fx.planner.plan(room.costmap, {25, 5}, {25, 35}, {}, fx.path);
  ASSERT_TRUE(through.ok());
  EXPECT_LT(through.length_m, 1.7);  // straight through the gap
  // The same with the task's clearance bar: around the end of the wall instead.
  cfg.blocked_cost = InflationLayer::cost_at(0.28, room.inflation);
  ASSERT_TRUE(fx.planner.init(cfg, fx.arena));
  const PlanResult around = fx.planner.plan(room.costmap, {25, 5}, {25, 35}, {}, fx.path);
  ASSERT_TRUE(around.ok()) << to_string(around.status);
  EXPECT_GT(around.length_m, 2.5);
  for (std::size_t i = 0; i < around.cells; ++i)
    if (fx.path[i].row == 20) {
      EXPECT_GE(fx.path[i].col, 45) << i;  // crosses the wall's line past its end
    }
  // Its cost, re-evaluated along the path, is the search's own.
  EXPECT_NEAR(fx.planner.path_cost(room.costmap, std::span<const GridCell>(fx.path.data(), around.cells)), around.cost,
              1e-3 * around.cost);
}

TEST(GlobalPlanner, EscapesFromAStartInsideTheClearanceBand) {
  GapRoom room;
  Fixture fx;
  GlobalPlannerConfig cfg;
  cfg.max_cells = room.costmap.size();
  cfg.blocked_cost = InflationLayer::cost_at(0.28, room.inflation);
  ASSERT_TRUE(fx.planner.init(cfg, fx.arena));
  // 0.2 m below the wall: inside the band, not in collision.
  const GridCell start{10, 16};
  ASSERT_GE(room.costmap.at(start.col, start.row), cfg.blocked_cost);
  ASSERT_LT(room.costmap.at(start.col, start.row), kInscribedCost);
  const PlanResult r = fx.planner.plan(room.costmap, start, {10, 2}, {}, fx.path);
  ASSERT_TRUE(r.ok()) << to_string(r.status);
  // Out of the band downhill, never climbing it.
  for (std::size_t i = 1; i < r.cells; ++i) {
    const std::uint8_t before = room.costmap.at(fx.path[i - 1].col, fx.path[i - 1].row);
    const std::uint8_t now = room.costmap.at(fx.path[i].col, fx.path[i].row);
    if (now >= cfg.blocked_cost) {
      EXPECT_LE(now, before) << i;
    }
  }
  // A path through a lethal cell, or not 8-connected, has no cost.
  std::vector<GridCell> bad = {{25, 18}, {25, 19}, {25, 20}, {25, 21}};
  room.costmap.set(25, 20, kLethalCost);
  EXPECT_TRUE(std::isinf(fx.planner.path_cost(room.costmap, bad)));
  std::vector<GridCell> jump = {{40, 5}, {42, 5}};
  EXPECT_TRUE(std::isinf(fx.planner.path_cost(room.costmap, jump)));
}

}  // namespace
}  // namespace sen3bot::nav
