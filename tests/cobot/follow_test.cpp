// Follow-me with a walking operator and a robot that drives to each target at its top speed.
#include "sen3bot/cobot/follow.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <memory_resource>
#include <numbers>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/cobot/polygon.hpp"

namespace sen3bot::cobot {
namespace {

using msg::Point2D;
using msg::Pose2D;

constexpr hal::Nanos kFollowCycle = hal::millis(100);
constexpr double kDt = 0.1;
constexpr double kRobotSpeed = 1.2;  // m/s, faster than the operator walks

// A large room as the type-2 area.
const std::array<Point2D, 4> kRoom{{{-10.0, -10.0}, {10.0, -10.0}, {10.0, 10.0}, {-10.0, 10.0}}};

class FollowTest : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_TRUE(follow.init(config, arena)); }

  // One cycle: the operator (seen, at p with velocity v), then the robot drives toward the
  // command's target for one cycle.
  FollowCommand step(bool seen, Point2D p, double vx, double vy, std::span<const Point2D> area) {
    now += kFollowCycle;
    FollowInput in;
    in.now_ns = now;
    in.operator_seen = seen;
    in.operator_at = p;
    in.operator_vx_m_s = vx;
    in.operator_vy_m_s = vy;
    in.robot = robot;
    in.area = area;
    const FollowCommand cmd = follow.update(in);
    if (cmd.go) {
      const double dx = cmd.target.x_m - robot.x_m;
      const double dy = cmd.target.y_m - robot.y_m;
      const double d = std::hypot(dx, dy);
      const double move = std::min(d, kRobotSpeed * kDt);
      if (d > 0.0) {
        robot.x_m += dx / d * move;
        robot.y_m += dy / d * move;
      }
      robot.theta_rad = cmd.heading_rad;
    }
    return cmd;
  }

  std::array<std::byte, 64 * 1024> buffer{};
  std::pmr::monotonic_buffer_resource arena{buffer.data(), buffer.size(), std::pmr::null_memory_resource()};
  FollowConfig config;
  FollowMe follow;
  Pose2D robot{0.0, 0.0, 0.0};
  hal::Nanos now = hal::seconds(50);
};

// The operator walks a quarter circle of radius 3 m at 0.8 m/s, then straight on.
Point2D walk(double t_s, double& vx, double& vy) {
  constexpr double kSpeed = 0.8;
  constexpr double kRadius = 3.0;
  const double s = kSpeed * t_s;
  const double arc = kRadius * std::numbers::pi / 2.0;
  if (s < arc) {
    const double a = s / kRadius;
    vx = kSpeed * std::cos(a);
    vy = kSpeed * std::sin(a);
    return {0.9 + kRadius * std::sin(a), kRadius - kRadius * std::cos(a)};
  }
  vx = 0.0;
  vy = kSpeed;
  return {0.9 + kRadius, kRadius + (s - arc)};
}

TEST_F(FollowTest, KeepsItsDistanceAlongACurvedTrail) {
  double vx = 0.0;
  double vy = 0.0;
  follow.start(now, robot, walk(0.0, vx, vy));
  int going = 0;
  for (int k = 1; k <= 120; ++k) {
    const Point2D p = walk(k * kDt, vx, vy);
    const FollowCommand cmd = step(true, p, vx, vy, kRoom);
    going += cmd.go ? 1 : 0;
    if (k * kDt >= 2.0) {
      EXPECT_NEAR(cmd.gap_m, config.distance_m, 0.15) << "t = " << k * kDt;
      EXPECT_GE(std::hypot(p.x_m - robot.x_m, p.y_m - robot.y_m), config.distance_m - 0.15) << "t = " << k * kDt;
    }
    if (cmd.go) {
      // The target lies on the operator's way: on the circle (or the straight after it).
      const double on_circle = std::abs(std::hypot(cmd.target.x_m - 0.9, cmd.target.y_m - 3.0) - 3.0);
      const double on_straight = std::abs(cmd.target.x_m - 3.9);
      if (cmd.target.x_m > 0.9) {
        EXPECT_LT(std::min(on_circle, on_straight), 0.02) << "t = " << k * kDt;
      }
    }
  }
  EXPECT_GT(going, 60);
  // Facing along the way: at the end, walking straight up (+y).
  EXPECT_NEAR(robot.theta_rad, std::numbers::pi / 2.0, 0.05);
}

TEST_F(FollowTest, StandsWhileTheOperatorIsWithinTheDistance) {
  follow.start(now, robot, {0.8, 0.0});
  const FollowCommand cmd = step(true, {0.8, 0.0}, 0.3, 0.0, kRoom);
  EXPECT_FALSE(cmd.go);
  EXPECT_EQ(cmd.reason, FollowHold::close_enough);
  EXPECT_NEAR(cmd.gap_m, 0.8, 1e-9);
}

TEST_F(FollowTest, HoldsWhenTheOperatorStops) {
  double vx = 0.0;
  double vy = 0.0;
  follow.start(now, robot, walk(0.0, vx, vy));
  Point2D p;
  for (int k = 1; k <= 40; ++k) p = walk(k * kDt, vx, vy), (void)step(true, p, vx, vy, kRoom);
  // Standing from now on: the robot closes up to the distance, then holds once the operator has
  // stood for stop_after_s.
  FollowCommand cmd;
  for (int k = 1; k <= 9; ++k) cmd = step(true, p, 0.0, 0.0, kRoom);
  EXPECT_NE(cmd.reason, FollowHold::operator_stopped);
  for (int k = 0; k < 5; ++k) cmd = step(true, p, 0.02, 0.0, kRoom);
  EXPECT_FALSE(cmd.go);
  EXPECT_EQ(cmd.reason, FollowHold::operator_stopped);
  const Pose2D parked = robot;
  for (int k = 0; k < 20; ++k) (void)step(true, p, 0.0, 0.0, kRoom);
  EXPECT_EQ(robot.x_m, parked.x_m);
  EXPECT_EQ(robot.y_m, parked.y_m);
  // Walking on: it follows again.
  double t = 4.0;
  for (int k = 0; k < 15; ++k) p = walk(t += kDt, vx, vy), cmd = step(true, p, vx, vy, kRoom);
  EXPECT_TRUE(cmd.go);
  EXPECT_EQ(cmd.reason, FollowHold::none);
}

TEST_F(FollowTest, HoldsWhenTheOperatorIsLost) {
  double vx = 0.0;
  double vy = 0.0;
  follow.start(now, robot, walk(0.0, vx, vy));
  Point2D p;
  for (int k = 1; k <= 30; ++k) p = walk(k * kDt, vx, vy), (void)step(true, p, vx, vy, kRoom);
  FollowCommand cmd;
  for (int k = 1; k <= 10; ++k) cmd = step(false, {}, 0.0, 0.0, kRoom);
  EXPECT_NE(cmd.reason, FollowHold::operator_lost);  // 1.0 s unseen is not yet lost
  cmd = step(false, {}, 0.0, 0.0, kRoom);
  EXPECT_FALSE(cmd.go);
  EXPECT_EQ(cmd.reason, FollowHold::operator_lost);
}

TEST_F(FollowTest, StopsAtTheAreasBorderAndNeverAimsOutsideIt) {
  // A corridor-shaped area, 6 m long; the operator walks out of its far end and on.
  const std::array<Point2D, 6> area{{{-1.0, -1.5}, {6.0, -1.5}, {6.0, 1.5}, {3.0, 1.5}, {3.0, 3.0}, {-1.0, 3.0}}};
  follow.start(now, robot, {0.9, 0.0});
  FollowCommand cmd;
  int border_cycles = 0;
  for (int k = 1; k <= 150; ++k) {
    const Point2D p{0.9 + 0.08 * k, 0.0};
    cmd = step(true, p, 0.8, 0.0, area);
    if (cmd.go) {
      EXPECT_TRUE(inside_by(area, cmd.target, config.robot_radius_m)) << k;
    }
    EXPECT_TRUE(inside_by(area, {robot.x_m, robot.y_m}, config.robot_radius_m)) << k;
    border_cycles += cmd.reason == FollowHold::area_border ? 1 : 0;
  }
  EXPECT_GT(border_cycles, 50);
  EXPECT_FALSE(cmd.go);
  EXPECT_EQ(cmd.reason, FollowHold::area_border);
  // At the last crumb inside: the crumbs are 0.16 m apart here (two of the operator's steps),
  // so within that of the shrunk border (x = 5.7).
  EXPECT_GT(robot.x_m, 5.7 - 0.17);
}

TEST_F(FollowTest, ComesBackInsideWhenTheOperatorDoes) {
  const std::array<Point2D, 4> area{{{-1.0, -2.0}, {4.0, -2.0}, {4.0, 2.0}, {-1.0, 2.0}}};
  follow.start(now, robot, {0.9, 0.0});
  Point2D p{0.9, 0.0};
  for (int k = 0; k < 70; ++k) p.x_m += 0.08, (void)step(true, p, 0.8, 0.0, area);  // out to x = 6.5
  ASSERT_LT(robot.x_m, 3.71);
  // Back in, sideways and down: the trail's way out and back is closed, the straight way is not.
  FollowCommand cmd;
  for (int k = 0; k < 25; ++k) p.x_m -= 0.08, p.y_m -= 0.06, cmd = step(true, p, -0.8, -0.6, area);
  for (int k = 0; k < 50; ++k) p.x_m -= 0.08, cmd = step(true, p, -0.8, 0.0, area);
  ASSERT_TRUE(inside_by(area, p, config.robot_radius_m));
  EXPECT_TRUE(cmd.go);
  EXPECT_EQ(cmd.reason, FollowHold::none);
  EXPECT_LT(std::hypot(p.x_m - robot.x_m, p.y_m - robot.y_m), 1.2);
  EXPECT_TRUE(inside_by(area, {robot.x_m, robot.y_m}, config.robot_radius_m));
}

TEST_F(FollowTest, TheTrailKeepsItsNewestCrumbsWhenFull) {
  config.trail_capacity = 8;
  ASSERT_TRUE(follow.init(config, arena));
  follow.start(now, robot, {1.0, 0.0});
  for (int k = 1; k <= 30; ++k) (void)step(true, {1.0 + 0.2 * k, 0.0}, 2.0, 0.0, kRoom);
  ASSERT_EQ(follow.trail_size(), 8u);
  EXPECT_NEAR(follow.trail_point(7).x_m, 7.0, 1e-9);
  EXPECT_NEAR(follow.trail_point(0).x_m, 5.6, 1e-9);
}

TEST_F(FollowTest, ConfigurationAndMemoryAreChecked) {
  FollowConfig bad;
  bad.distance_m = 0.0;
  FollowMe f;
  EXPECT_FALSE(f.init(bad, arena));
  std::array<std::byte, 64> small{};
  std::pmr::monotonic_buffer_resource tiny{small.data(), small.size(), std::pmr::null_memory_resource()};
  const Status s = f.init(FollowConfig{}, tiny);
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code(), Errc::capacity);
}

TEST_F(FollowTest, UpdatesAllocateNothing) {
  double vx = 0.0;
  double vy = 0.0;
  follow.start(now, robot, walk(0.0, vx, vy));
  int going = 0;
  mem::testing::AllocationScope scope;
  for (int k = 1; k <= 150; ++k) {
    const Point2D p = walk(k * kDt, vx, vy);
    going += step(true, p, vx, vy, kRoom).go ? 1 : 0;
  }
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_GT(going, 120);
}

}  // namespace
}  // namespace sen3bot::cobot
