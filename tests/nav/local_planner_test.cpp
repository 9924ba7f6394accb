#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/mem/budget_arena.hpp"
#include "sen3bot/nav/costmap.hpp"
#include "sen3bot/nav/local_planner.hpp"
#include "sen3bot/world/world.hpp"

namespace sen3bot::nav {
namespace {

// 8 x 4 m corridor room with walls; a 0.4 m box sits on the straight line y = 2.
OccupancyMap corridor(bool with_box) {
  OccupancyMap m(160, 80, 0.05, 0.0, 0.0);
  for (int c = 0; c < 160; ++c) {
    m.set(c, 0, 100);
    m.set(c, 79, 100);
  }
  for (int r = 0; r < 80; ++r) {
    m.set(0, r, 100);
    m.set(159, r, 100);
  }
  if (with_box) {
    for (int r = 36; r < 44; ++r)
      for (int c = 76; c < 84; ++c) m.set(c, r, 100);
  }
  return m;
}

struct DriveResult {
  bool reached = false;
  bool collided = false;
  int steps = 0;
  Pose2D final_pose;
  DwaStatus last = DwaStatus::idle;
};

// The map as a costmap (static and inflation layers), updated once.
struct MapCostmap {
  explicit MapCostmap(const OccupancyMap& map) : st(map) {
    EXPECT_TRUE(cm.add_layer(st));
    EXPECT_TRUE(cm.add_layer(infl));
    EXPECT_TRUE(cm.init_over_map(map, arena));
    cm.update({});
  }
  [[nodiscard]] const Costmap2D& costmap() const { return cm.costmap(); }
  mem::BudgetArena arena{"costmap", 1 << 20};
  StaticLayer st;
  InflationLayer infl;
  LayeredCostmap cm;
};

DriveResult drive(const OccupancyMap& map, DwaPlanner& dwa, Pose2D pose, int max_steps) {
  const MapCostmap cm(map);
  const world::World truth(map);
  DriveResult run;
  double v = 0.0;
  double w = 0.0;
  const double dt = dwa.config().control_period_s;
  for (; run.steps < max_steps; ++run.steps) {
    const DwaCommand cmd = dwa.compute(pose, v, w, cm.costmap());
    run.last = cmd.status;
    run.final_pose = pose;
    if (std::getenv("DWA_TRACE") != nullptr && run.steps % 5 == 0) std::printf("%d %.2f %.2f %.2f v %.2f w %.2f %s adm %u\n", run.steps, pose.x_m, pose.y_m, pose.theta_rad, cmd.v_m_s, cmd.w_rad_s, to_string(cmd.status), cmd.admissible);
    if (cmd.status == DwaStatus::reached) {
      run.reached = true;
      break;
    }
    v = cmd.v_m_s;
    w = cmd.w_rad_s;
    pose.x_m += v * dt * std::cos(pose.theta_rad + w * dt / 2.0);
    pose.y_m += v * dt * std::sin(pose.theta_rad + w * dt / 2.0);
    pose.theta_rad = normalize_angle(pose.theta_rad + w * dt);
    if (truth.collides(pose, dwa.config().footprint)) {
      if (std::getenv("DWA_TRACE") != nullptr) std::printf("collision at %.3f %.3f %.3f clearance %.3f\n", pose.x_m, pose.y_m, pose.theta_rad, truth.clearance_m(pose, dwa.config().footprint, 1.0));
      run.collided = true;
    }
  }
  return run;
}

std::vector<PathPoint> straight(double x0, double x1, double y) {
  std::vector<PathPoint> path;
  for (double x = x0; x <= x1 + 1e-9; x += 0.05) path.push_back({static_cast<float>(x), static_cast<float>(y)});
  return path;
}

TEST(Dwa, FollowsAFreePathToTheGoal) {
  mem::BudgetArena arena("dwa", 1 << 18);
  DwaPlanner dwa;
  ASSERT_TRUE(dwa.init({}, arena));
  const auto path = straight(1.0, 7.0, 2.0);
  dwa.set_path(path);
  const DriveResult run = drive(corridor(false), dwa, {1.0, 2.0, 0.3}, 400);
  EXPECT_TRUE(run.reached);
  EXPECT_FALSE(run.collided);
  EXPECT_LT(run.steps, 200);  // 6 m at up to 0.5 m/s
  EXPECT_EQ(dwa.recoveries().total(), 0u);
}

TEST(Dwa, AvoidsABoxOnThePathAndReachesTheGoal) {
  mem::BudgetArena arena("dwa", 1 << 18);
  DwaPlanner dwa;
  ASSERT_TRUE(dwa.init({}, arena));
  const auto path = straight(1.0, 7.0, 2.0);  // the global path goes straight through the box
  dwa.set_path(path);
  const DriveResult run = drive(corridor(true), dwa, {1.0, 2.0, 0.0}, 600);
  EXPECT_TRUE(run.reached) << run.final_pose.x_m << "," << run.final_pose.y_m << " " << to_string(run.last)
                           << " recoveries " << dwa.recoveries().total();
  EXPECT_FALSE(run.collided);
}

TEST(Dwa, RecoversWhenBlockedAndCountsIt) {
  mem::BudgetArena arena("dwa", 1 << 18);
  DwaConfig cfg;
  cfg.max_recovery_cycles = 1;
  DwaPlanner dwa;
  ASSERT_TRUE(dwa.init(cfg, arena));
  // Walled in: a full wall across the corridor right ahead.
  OccupancyMap map = corridor(false);
  for (int r = 0; r < 80; ++r) map.set(30, r, 100);
  dwa.set_path(straight(1.0, 7.0, 2.0));
  const DriveResult run = drive(map, dwa, {1.1, 2.0, 0.0}, 300);
  EXPECT_FALSE(run.reached);
  EXPECT_FALSE(run.collided);
  EXPECT_GE(dwa.recoveries().waits, 1u);
  EXPECT_GE(dwa.recoveries().total(), 2u);
}

TEST(Dwa, ComputeAllocatesNothing) {
  mem::BudgetArena arena("dwa", 1 << 20);
  DwaPlanner dwa;
  ASSERT_TRUE(dwa.init({}, arena));
  const OccupancyMap map = corridor(true);
  const MapCostmap cm(map);
  const auto path = straight(1.0, 7.0, 2.0);
  dwa.set_path(path);
  mem::testing::AllocationScope scope;
  for (int i = 0; i < 100; ++i) (void)dwa.compute({1.0 + 0.01 * i, 2.0, 0.0}, 0.2, 0.0, cm.costmap());
  EXPECT_EQ(scope.allocations(), 0u);
}

// A box crossing the robot's way, as the dynamic obstacle layer would report it.
struct CrossingBox {
  double x_m;       // its lane
  double y0_m;      // where it is at t = 0
  double vy_m_s;
  [[nodiscard]] msg::MovingObstacle at(double t_s) const {
    return {1, x_m, y0_m + vy_m_s * t_s, 0.0, vy_m_s, 0.15, 0.0, 0.0};
  }
};

// Drives the open corridor with a box crossing (seen perfectly); true when the robot's padded
// body ever came within the box's radius.
struct CrossingRun {
  bool reached = false;
  bool contact = false;
  int yielding_steps = 0;
  std::uint32_t recoveries = 0;
  double max_turn_rad = 0.0;  // the largest heading away from the corridor's direction
};

CrossingRun drive_across(DwaPlanner& dwa, const CrossingBox& box, double max_time_s, double start_x_m = 1.0) {
  const OccupancyMap map = corridor(false);
  const MapCostmap cm(map);
  dwa.set_path(straight(start_x_m, 7.0, 2.0));
  CrossingRun run;
  Pose2D pose{start_x_m, 2.0, 0.0};
  double v = 0.0;
  double w = 0.0;
  const double dt = dwa.config().control_period_s;
  const Footprint body = dwa.config().footprint;
  for (double t = 0.0; t < max_time_s; t += dt) {
    const msg::MovingObstacle m = box.at(t);
    const DwaCommand cmd = dwa.compute(pose, v, w, cm.costmap(), std::span<const msg::MovingObstacle>(&m, 1));
    if (cmd.status == DwaStatus::reached) {
      run.reached = true;
      break;
    }
    if (cmd.status == DwaStatus::yielding) ++run.yielding_steps;
    if (std::getenv("DWA_TRACE") != nullptr)
      std::printf("t %.1f pose %.2f %.2f %.2f v %.2f w %.2f %s adm %u refused %u box y %.2f\n", t, pose.x_m, pose.y_m,
                  pose.theta_rad, cmd.v_m_s, cmd.w_rad_s, to_string(cmd.status), cmd.admissible, cmd.mover_rejected, m.y_m);
    v = cmd.v_m_s;
    w = cmd.w_rad_s;
    pose.x_m += v * dt * std::cos(pose.theta_rad + w * dt / 2.0);
    pose.y_m += v * dt * std::sin(pose.theta_rad + w * dt / 2.0);
    pose.theta_rad = normalize_angle(pose.theta_rad + w * dt);
    run.max_turn_rad = std::max(run.max_turn_rad, std::abs(pose.theta_rad));
    // The box as a disc against the body rectangle.
    const msg::MovingObstacle now = box.at(t + dt);
    const double c = std::cos(pose.theta_rad);
    const double s = std::sin(pose.theta_rad);
    const double bx = c * (now.x_m - pose.x_m) + s * (now.y_m - pose.y_m);
    const double by = -s * (now.x_m - pose.x_m) + c * (now.y_m - pose.y_m);
    const double ex = std::max(0.0, std::abs(bx) - body.vertices[0].x_m);
    const double ey = std::max(0.0, std::abs(by) - body.vertices[0].y_m);
    if (std::hypot(ex, ey) < now.radius_m) run.contact = true;
  }
  run.recoveries = dwa.recoveries().total();
  return run;
}

TEST(DwaMovers, TimeToContactFollowsTheRolloutAndTheMoverInTime) {
  mem::BudgetArena arena("dwa", 1 << 18);
  DwaConfig cfg;
  cfg.mover_margin_m = 0.0;
  DwaPlanner dwa;
  ASSERT_TRUE(dwa.init(cfg, arena));
  const double front = cfg.footprint.vertices[0].x_m + cfg.footprint_padding_m;
  // A mover standing on the robot's line 2 m ahead is not a mover (too slow) ...
  msg::MovingObstacle m{1, 2.0, 0.0, 0.0, 0.0, 0.1, 0.0, 0.0};
  EXPECT_TRUE(std::isinf(dwa.time_to_contact({0, 0, 0}, 0.5, 0.0, std::span(&m, 1))));
  // ... coming head-on at 0.5 m/s it is met where the gap of 2 - front - 0.1 m closes at 1 m/s.
  m.vx_m_s = -0.5;
  const double expected = 2.0 - front - 0.1;
  const double ttc = dwa.time_to_contact({0, 0, 0}, 0.5, 0.0, std::span(&m, 1));
  EXPECT_NEAR(ttc, expected, cfg.sim_step_s + 1e-9);
  EXPECT_GE(ttc, expected - 1e-9);
  // Standing still, the robot is met later; a mover passing 1 m to the side never meets it.
  EXPECT_GT(dwa.time_to_contact({0, 0, 0}, 0.0, 0.0, std::span(&m, 1)), ttc);
  m.y_m = 1.0;
  EXPECT_TRUE(std::isinf(dwa.time_to_contact({0, 0, 0}, 0.5, 0.0, std::span(&m, 1))));
  // A crossing mover: met when driving on, missed when waiting for it to pass.
  msg::MovingObstacle crossing{2, 1.2, -1.2, 0.0, 0.8, 0.1, 0.0, 0.0};
  EXPECT_LT(dwa.time_to_contact({0, 0, 0}, 0.5, 0.0, std::span(&crossing, 1)), cfg.mover_horizon_s);
  EXPECT_TRUE(std::isinf(dwa.time_to_contact({0, 0, 0}, 0.0, 0.0, std::span(&crossing, 1))));
}

TEST(DwaMovers, TheBroadPhaseNeverChangesATimeToContact) {
  // The broad phase only skips times at which a mover cannot be within reach: over random
  // crowds, arcs and motions (movers across several batches too) its answer is the full
  // check's to the bit, and it does skip (a crowd far off is never stepped through).
  mem::BudgetArena arena("dwa", 1 << 19);
  DwaConfig with;
  DwaConfig without;
  without.mover_broad_phase = false;
  DwaPlanner fast;
  DwaPlanner full;
  ASSERT_TRUE(fast.init(with, arena));
  ASSERT_TRUE(full.init(without, arena));
  std::srand(35);
  const auto uniform = [](double lo, double hi) { return lo + (hi - lo) * std::rand() / static_cast<double>(RAND_MAX); };
  std::vector<msg::MovingObstacle> crowd;
  int finite = 0;
  int cases = 0;
  for (int trial = 0; trial < 400; ++trial) {
    crowd.clear();
    const int n = trial % 10 == 0 ? 40 : 1 + trial % 16;
    for (int i = 0; i < n; ++i) {
      crowd.push_back({static_cast<std::uint32_t>(i + 1), uniform(-6.0, 6.0), uniform(-6.0, 6.0), uniform(-1.5, 1.5),
                       uniform(-1.5, 1.5), uniform(0.1, 0.4), 0.0, 0.0});
    }
    const Pose2D pose{uniform(-1.0, 1.0), uniform(-1.0, 1.0), uniform(-3.1, 3.1)};
    for (const double v : {0.0, 0.01, 0.2, 0.5, -0.1}) {
      for (const double w : {0.0, 0.6, -1.2}) {
        for (const auto motion : {DwaPlanner::MoverMotion::hold, DwaPlanner::MoverMotion::brake,
                                  DwaPlanner::MoverMotion::speed_up}) {
          for (const auto reach : {DwaPlanner::MoverReach::margin, DwaPlanner::MoverReach::touching}) {
            const double a = fast.time_to_contact(pose, v, w, crowd, motion, reach);
            const double b = full.time_to_contact(pose, v, w, crowd, motion, reach);
            ++cases;
            finite += std::isfinite(b) ? 1 : 0;
            ASSERT_EQ(a, b) << "trial " << trial << " v " << v << " w " << w << " motion "
                            << static_cast<int>(motion);
          }
        }
      }
    }
  }
  // Both kinds of answer occur often enough for the comparison to mean something.
  EXPECT_GT(finite, cases / 10);
  EXPECT_LT(finite, cases - cases / 10);
}

TEST(DwaMovers, LetsACrossingBoxPassInsteadOfDrivingIntoIt) {
  // The box crosses y = 2 at x = 3.0 about 4.4 s in, when a robot at full speed is there.
  const CrossingBox box{3.0, -1.5, 0.8};
  {
    mem::BudgetArena arena("dwa", 1 << 18);
    DwaConfig cfg;
    cfg.mover_prediction = false;
    DwaPlanner blind;
    ASSERT_TRUE(blind.init(cfg, arena));
    const CrossingRun run = drive_across(blind, box, 30.0);
    EXPECT_TRUE(run.contact) << "the scene must be a collision course without prediction";
  }
  mem::BudgetArena arena("dwa", 1 << 18);
  DwaPlanner dwa;
  ASSERT_TRUE(dwa.init({}, arena));
  const CrossingRun run = drive_across(dwa, box, 30.0);
  EXPECT_FALSE(run.contact);
  EXPECT_TRUE(run.reached);
  EXPECT_EQ(run.recoveries, 0u);
  // It waits facing its way: no loop in front of the lane, no turning away from the box.
  EXPECT_LT(run.max_turn_rad, 0.5);
}

TEST(DwaMovers, StandingInALaneItSpeedsUpOutOfIt) {
  // The robot starts at rest in the middle of a lane; its box comes down from 2.4 m away at
  // 0.8 m/s. Braking or creeping, it is hit; speeding up all the way, it clears the lane.
  const CrossingBox box{1.0, 3.7, -0.8};
  mem::BudgetArena arena("dwa", 1 << 18);
  DwaPlanner dwa;
  ASSERT_TRUE(dwa.init({}, arena));
  const CrossingRun run = drive_across(dwa, box, 30.0, 1.0);
  EXPECT_FALSE(run.contact);
  EXPECT_TRUE(run.reached);
}

TEST(DwaMovers, AMoversPresentCellsDoNotRefuseARolloutThatPassesBehindIt) {
  // The laser's marks of a box 0.8 m ahead, on the robot's line; the box is leaving it sideways
  // at 1 m/s and is long gone when the robot gets there.
  OccupancyMap map = corridor(false);
  for (int r = 38; r < 42; ++r)
    for (int c = 36; c < 40; ++c) map.set(c, r, 100);
  const MapCostmap cm(map);
  const msg::MovingObstacle box{1, 1.9, 2.0, 0.0, 1.0, 0.15, 0.0, 0.0};
  mem::BudgetArena arena("dwa", 1 << 20);
  DwaPlanner dwa;
  ASSERT_TRUE(dwa.init({}, arena));
  dwa.set_path(straight(1.0, 7.0, 2.0));
  const Pose2D pose{1.0, 2.0, 0.0};
  // Known only as marks, the box closes every arc in the window: the robot cannot go on.
  const DwaCommand still = dwa.compute(pose, 0.5, 0.0, cm.costmap());
  // Known as a mover, its marks are its present: the time check lets the robot drive on.
  const DwaCommand moving = dwa.compute(pose, 0.5, 0.0, cm.costmap(), std::span(&box, 1));
  EXPECT_GT(moving.admissible, still.admissible);
  EXPECT_GE(moving.v_m_s, 0.45);
  EXPECT_LT(std::abs(moving.w_rad_s), 0.25);
  EXPECT_LT(still.v_m_s, 0.1);
}

TEST(DwaMovers, WhenEveryWayGrazesTheMarginItDoesNotBrakeForNothing) {
  // A box keeping pace beside the robot, inside its margin but clear of its body: every
  // rollout meets the margin at once, holding or braking, and none touches the box.
  mem::BudgetArena arena("dwa", 1 << 20);
  DwaConfig cfg;
  DwaPlanner dwa;
  ASSERT_TRUE(dwa.init(cfg, arena));
  const OccupancyMap map = corridor(false);
  const MapCostmap cm(map);
  dwa.set_path(straight(1.0, 7.0, 2.0));
  const double side = cfg.footprint.vertices[0].y_m + cfg.footprint_padding_m;
  const msg::MovingObstacle beside{1, 1.0, 2.0 + side + 0.15 + 0.05, 0.5, 0.0, 0.15, 0.0, 0.0};
  const Pose2D pose{1.0, 2.0, 0.0};
  const DwaCommand cmd = dwa.compute(pose, 0.5, 0.0, cm.costmap(), std::span(&beside, 1));
  ASSERT_EQ(cmd.mover_rejected, cmd.admissible) << "the scene must refuse every rollout at the margin";
  EXPECT_TRUE(std::isinf(dwa.time_to_contact(pose, cmd.v_m_s, cmd.w_rad_s, std::span(&beside, 1),
                                             DwaPlanner::MoverMotion::hold, DwaPlanner::MoverReach::touching)));
  EXPECT_GE(cmd.v_m_s, 0.45);
  // Whatever it does, it does not turn into the box.
  EXPECT_LE(cmd.w_rad_s, 0.0);
}

TEST(DwaMovers, ComputeWithMoversAllocatesNothing) {
  mem::BudgetArena arena("dwa", 1 << 20);
  DwaPlanner dwa;
  ASSERT_TRUE(dwa.init({}, arena));
  const OccupancyMap map = corridor(false);
  const MapCostmap cm(map);
  dwa.set_path(straight(1.0, 7.0, 2.0));
  const CrossingBox box{3.0, 0.5, 0.8};
  mem::testing::AllocationScope scope;
  for (int i = 0; i < 50; ++i) {
    const msg::MovingObstacle m = box.at(0.1 * i);
    (void)dwa.compute({1.0 + 0.01 * i, 2.0, 0.0}, 0.2, 0.0, cm.costmap(), std::span(&m, 1));
  }
  EXPECT_EQ(scope.allocations(), 0u);
}

TEST(DwaMovers, StandingInAMoversWayCountsItComingBack) {
  mem::BudgetArena arena("dwa", 1 << 20);
  DwaConfig cfg;
  cfg.mover_margin_m = 0.0;
  DwaPlanner dwa;
  ASSERT_TRUE(dwa.init(cfg, arena));
  // A box 2 m to the robot's left, going away along a lane through the robot.
  const msg::MovingObstacle away{1, 0.0, 2.0, 0.0, 0.6, 0.1, 0.0, 0.0};
  // Standing: it may turn and come back: met when it has come the 2 m less the reaches back.
  const double back = dwa.time_to_contact({0, 0, 0}, 0.0, 0.0, std::span(&away, 1));
  const double gap = 2.0 - 0.1 - (cfg.footprint.vertices[0].y_m + cfg.footprint_padding_m);
  EXPECT_NEAR(back, gap / 0.6, cfg.sim_step_s + 1e-9);
  // Driving out of its lane at speed: it is never met.
  EXPECT_TRUE(std::isinf(dwa.time_to_contact({0, 0, 0}, 0.5, 0.0, std::span(&away, 1))));
  // Without the assumption, standing there is safe.
  cfg.mover_may_return = false;
  DwaPlanner trusting;
  ASSERT_TRUE(trusting.init(cfg, arena));
  EXPECT_TRUE(std::isinf(trusting.time_to_contact({0, 0, 0}, 0.0, 0.0, std::span(&away, 1))));
}

TEST(DwaMovers, BrakesUnderControlWhenNothingIsAdmissibleAtSpeed) {
  mem::BudgetArena arena("dwa", 1 << 20);
  DwaPlanner dwa;
  ASSERT_TRUE(dwa.init({}, arena));
  // A wall across the corridor 0.7 m ahead of a robot at full speed: every arc at 0.44 m/s
  // or more reaches it within the rollout, but braking from 0.5 m/s stops 0.21 m on.
  OccupancyMap map = corridor(false);
  for (int r = 0; r < 80; ++r) map.set(34, r, 100);
  const MapCostmap cm(map);
  dwa.set_path(straight(1.0, 7.0, 2.0));
  // A box crossing far behind the robot: movers are about.
  const msg::MovingObstacle behind{1, -2.0, 0.0, 0.0, 0.6, 0.1, 0.0, 0.0};
  const DwaCommand c = dwa.compute({1.0, 2.0, 0.0}, 0.5, 0.0, cm.costmap(), std::span(&behind, 1));
  EXPECT_EQ(c.admissible, 0u);
  EXPECT_EQ(c.status, DwaStatus::braking);
  EXPECT_NEAR(c.v_m_s, 0.5 - dwa.config().acc_v_m_s2 * dwa.config().control_period_s, 1e-9);
  EXPECT_EQ(dwa.recoveries().total(), 0u);
  // Among still obstacles only, the recoveries keep their timing.
  DwaPlanner plain;
  ASSERT_TRUE(plain.init({}, arena));
  plain.set_path(straight(1.0, 7.0, 2.0));
  EXPECT_EQ(plain.compute({1.0, 2.0, 0.0}, 0.5, 0.0, cm.costmap()).status, DwaStatus::waiting);
  // Braking is for a moving robot only: standing, it samples the crawl the window allows.
  const DwaCommand stopped = dwa.compute({1.0, 2.0, 0.0}, 0.0, 0.0, cm.costmap());
  EXPECT_NE(stopped.status, DwaStatus::braking);
}

}  // namespace
}  // namespace sen3bot::nav
