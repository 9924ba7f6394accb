#include "sen3bot/formation/unicycle.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

namespace sen3bot::formation {
namespace {

TEST(PointOffset, ThePointMovesAsAskedForAnyHeading) {
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> any(-3.0, 3.0), angle(-4.0, 4.0), offset(0.02, 0.5);
  for (int i = 0; i < 10'000; ++i) {
    const Pose pose{any(rng), any(rng), angle(rng)};
    const double l = offset(rng);
    const Vec2 u{any(rng), any(rng)};
    const Unicycle c = to_unicycle(pose, u, l);
    // The closed form of P' for (v, w): [cos, -L sin; sin, L cos] [v; w].
    const double px = std::cos(pose.theta_rad) * c.v - l * std::sin(pose.theta_rad) * c.w;
    const double py = std::sin(pose.theta_rad) * c.v + l * std::cos(pose.theta_rad) * c.w;
    ASSERT_NEAR(px, u.x_m, 1e-12);
    ASSERT_NEAR(py, u.y_m, 1e-12);
    const Vec2 back = point_velocity(pose, c, l);
    ASSERT_NEAR(back.x_m, u.x_m, 1e-12);
    ASSERT_NEAR(back.y_m, u.y_m, 1e-12);
  }
}

TEST(PointOffset, IntegratedUnicycleCarriesPAlongTheAskedVelocity) {
  // A constant u asked of P through eq. 1.9 at every instant: P goes straight at u even though
  // the robot starts facing away and turns on the way.
  const double l = 0.1;
  Pose pose{0.0, 0.0, 2.5};
  const Vec2 p0 = point_p(pose, l);
  const Vec2 u{0.2, -0.1};
  const double dt = 1e-4;
  for (int k = 0; k < 50'000; ++k) {  // 5 s, RK4 on (x, y, theta)
    const auto f = [&](const Pose& q) {
      const Unicycle c = to_unicycle(q, u, l);
      return Pose{c.v * std::cos(q.theta_rad), c.v * std::sin(q.theta_rad), c.w};
    };
    const Pose k1 = f(pose);
    const Pose k2 = f({pose.x_m + 0.5 * dt * k1.x_m, pose.y_m + 0.5 * dt * k1.y_m, pose.theta_rad + 0.5 * dt * k1.theta_rad});
    const Pose k3 = f({pose.x_m + 0.5 * dt * k2.x_m, pose.y_m + 0.5 * dt * k2.y_m, pose.theta_rad + 0.5 * dt * k2.theta_rad});
    const Pose k4 = f({pose.x_m + dt * k3.x_m, pose.y_m + dt * k3.y_m, pose.theta_rad + dt * k3.theta_rad});
    pose.x_m += dt / 6.0 * (k1.x_m + 2 * k2.x_m + 2 * k3.x_m + k4.x_m);
    pose.y_m += dt / 6.0 * (k1.y_m + 2 * k2.y_m + 2 * k3.y_m + k4.y_m);
    pose.theta_rad += dt / 6.0 * (k1.theta_rad + 2 * k2.theta_rad + 2 * k3.theta_rad + k4.theta_rad);
  }
  const Vec2 p = point_p(pose, l);
  EXPECT_NEAR(p.x_m, p0.x_m + 5.0 * u.x_m, 1e-6);
  EXPECT_NEAR(p.y_m, p0.y_m + 5.0 * u.y_m, 1e-6);
  // The heading has turned towards u (the zero dynamics of P's single integrator).
  EXPECT_NEAR(std::remainder(pose.theta_rad - std::atan2(u.y_m, u.x_m), 2.0 * std::numbers::pi), 0.0, 0.01);
}

TEST(CommonScale, KeepsEveryRobotWithinHalfItsLimitsAndItsDirection) {
  std::mt19937_64 rng(11);
  std::uniform_real_distribution<double> v(-3.0, 3.0), w(-8.0, 8.0);
  const double v_max = 0.5, w_max = 1.5;
  for (int trial = 0; trial < 2000; ++trial) {
    std::vector<Unicycle> c(1 + trial % 8);
    for (Unicycle& x : c) x = {v(rng), w(rng)};
    const double f = common_scale(c, v_max, w_max);
    ASSERT_GT(f, 0.0);
    ASSERT_LE(f, 1.0);
    double top_v = 0, top_w = 0;
    for (const Unicycle& x : c) {
      const Unicycle s{f * x.v, f * x.w};
      ASSERT_LE(std::fabs(s.v), v_max / 2.0 + 1e-12);
      ASSERT_LE(std::fabs(s.w), w_max / 2.0 + 1e-12);
      // The same direction of motion: one positive factor on both inputs.
      ASSERT_EQ(std::signbit(s.v), std::signbit(x.v));
      ASSERT_EQ(std::signbit(s.w), std::signbit(x.w));
      ASSERT_NEAR(s.v * x.w, s.w * x.v, 1e-9);
      top_v = std::max(top_v, std::fabs(s.v));
      top_w = std::max(top_w, std::fabs(s.w));
    }
    // As large as the limits allow: one of them is reached when F < 1.
    if (f < 1.0) {
      ASSERT_TRUE(std::fabs(top_v - v_max / 2.0) < 1e-9 || std::fabs(top_w - w_max / 2.0) < 1e-9);
    }
  }
}

TEST(CommonScale, SlowCommandsAreLeftAloneAndNonsenseStopsTheTeam) {
  const std::vector<Unicycle> slow = {{0.1, 0.2}, {-0.2, 0.0}};
  EXPECT_EQ(common_scale(slow, 0.5, 1.5), 1.0);
  EXPECT_EQ(common_scale(std::vector<Unicycle>{{0.0, 0.0}}, 0.5, 1.5), 1.0);
  EXPECT_EQ(common_scale(std::vector<Unicycle>{{0.1, 0.0}, {NAN, 0.0}}, 0.5, 1.5), 0.0);
  EXPECT_EQ(common_scale(std::vector<Unicycle>{{0.1, INFINITY}}, 0.5, 1.5), 0.0);
  // The factor 2: a robot at exactly its limit is halved.
  EXPECT_DOUBLE_EQ(common_scale(std::vector<Unicycle>{{0.5, 0.0}}, 0.5, 1.5), 0.5);
}

}  // namespace
}  // namespace sen3bot::formation
