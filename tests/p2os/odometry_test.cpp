// Odometry: 15-bit x/y unwrapping across the +-32.768 m wrap, heading across +-pi with the
// exact 2*pi/4096 unit.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>

#include "sen3bot/p2os/odometry.hpp"

namespace sen3bot::p2os {
namespace {

Sip sip_at(std::int64_t x_mm, std::int64_t y_mm, std::int64_t theta_units) {
  Sip s;
  s.x_raw = static_cast<std::uint16_t>(x_mm & kPositionMask);
  s.y_raw = static_cast<std::uint16_t>(y_mm & kPositionMask);
  std::int64_t t = ((theta_units % 4096) + 4096) % 4096;
  if (t >= 2048) t -= 4096;
  s.theta_raw = static_cast<std::int16_t>(t);
  return s;
}

TEST(P2osOdometry, PositionDeltaIsModular) {
  EXPECT_EQ(Odometry::position_delta(5, 0x7FFB), 10);
  EXPECT_EQ(Odometry::position_delta(0x7FFB, 5), -10);
  EXPECT_EQ(Odometry::position_delta(100, 100), 0);
  EXPECT_EQ(Odometry::theta_delta(-2040, 2040), 16);
  EXPECT_EQ(Odometry::theta_delta(2040, -2040), -16);
}

TEST(P2osOdometry, DrivesAcrossTheCounterWrapBothWays) {
  Odometry odo;
  // Start at x = 30 m (raw wraps every 32.768 m), y just inside the negative wrap; drive
  // +5 m in x (10 mm per SIP) while y runs down 3.5 m, then 12 m back in x alone.
  std::int64_t x_mm = 30000;
  std::int64_t y_mm = -32000;
  odo.update(sip_at(x_mm, y_mm, 0));
  const double x0 = odo.pose().x_m;
  const double y0 = odo.pose().y_m;
  for (int i = 0; i < 500; ++i) {
    x_mm += 10;
    y_mm -= 7;
    odo.update(sip_at(x_mm, y_mm, 0));
  }
  EXPECT_NEAR(odo.pose().x_m - x0, 5.0, 1e-9);
  EXPECT_NEAR(odo.pose().y_m - y0, -3.5, 1e-9);
  for (int i = 0; i < 1200; ++i) {
    x_mm -= 10;
    odo.update(sip_at(x_mm, y_mm, 0));
  }
  EXPECT_NEAR(odo.pose().x_m - x0, -7.0, 1e-9);
  EXPECT_NEAR(odo.pose().y_m - y0, -3.5, 1e-9);
  EXPECT_NEAR(odo.distance_m(), 500 * std::hypot(0.010, 0.007) + 12.0, 1e-6);
}

TEST(P2osOdometry, FirstSipSeedsFromSignExtendedCounters) {
  Odometry odo;
  odo.update(sip_at(-250, 1200, 1024));
  EXPECT_NEAR(odo.pose().x_m, -0.25, 1e-12);
  EXPECT_NEAR(odo.pose().y_m, 1.2, 1e-12);
  EXPECT_NEAR(odo.pose().theta_rad, std::numbers::pi / 2, 1e-12);
}

TEST(P2osOdometry, RebaseKeepsThePoseWhenTheCountersRestart) {
  Odometry odo;
  odo.update(sip_at(1000, 2000, 512));
  odo.update(sip_at(1500, 2000, 512));  // +0.5 m
  odo.rebase();
  odo.update(sip_at(0, 0, 0));  // a new session: counters back at zero
  EXPECT_NEAR(odo.pose().x_m, 1.5, 1e-12);
  EXPECT_NEAR(odo.pose().y_m, 2.0, 1e-12);
  EXPECT_NEAR(odo.pose().theta_rad, std::numbers::pi / 4, 1e-12);
  odo.update(sip_at(100, 0, 0));  // deltas from the new reference
  EXPECT_NEAR(odo.pose().x_m, 1.6, 1e-12);
  EXPECT_NEAR(odo.distance_m(), 0.6, 1e-12);
  Odometry fresh;  // before the first SIP there is nothing to keep: it seeds as usual
  fresh.rebase();
  fresh.update(sip_at(-250, 0, 0));
  EXPECT_NEAR(fresh.pose().x_m, -0.25, 1e-12);
}

TEST(P2osOdometry, HeadingAcrossPiUsesExactUnit) {
  Odometry odo;
  std::int64_t units = 2000;
  odo.update(sip_at(0, 0, units));
  // Turn CCW through +pi: 200 units more.
  for (int i = 0; i < 20; ++i) {
    units += 10;
    odo.update(sip_at(0, 0, units));
  }
  const double expected = std::remainder(2200 * 2 * std::numbers::pi / 4096, 2 * std::numbers::pi);
  EXPECT_NEAR(odo.pose().theta_rad, expected, 1e-12);
  EXPECT_LT(odo.pose().theta_rad, 0);  // wrapped to the negative side
  // Back CW through -pi / +pi again.
  for (int i = 0; i < 40; ++i) {
    units -= 10;
    odo.update(sip_at(0, 0, units));
  }
  EXPECT_NEAR(odo.pose().theta_rad, 1800 * 2 * std::numbers::pi / 4096, 1e-12);
  // A full revolution in small steps comes back to the same heading.
  for (int i = 0; i < 4096; ++i) odo.update(sip_at(0, 0, ++units));
  EXPECT_NEAR(odo.pose().theta_rad, 1800 * 2 * std::numbers::pi / 4096, 1e-9);
}

TEST(P2osOdometry, WrapAngle) {
  EXPECT_NEAR(wrap_angle_rad(3 * std::numbers::pi), std::numbers::pi, 1e-12);
  EXPECT_NEAR(wrap_angle_rad(-std::numbers::pi), std::numbers::pi, 1e-12);
  EXPECT_NEAR(wrap_angle_rad(-3 * std::numbers::pi / 2), std::numbers::pi / 2, 1e-12);
}

TEST(P2osOdometry, OldP3dxDistanceFactor) {
  ConversionFactors k;
  k.dist_conv_mm_per_unit = 0.485;
  Odometry odo(k);
  odo.update(sip_at(0, 0, 0));
  odo.update(sip_at(1000, 0, 0));
  EXPECT_NEAR(odo.pose().x_m, 0.485, 1e-12);
}

}  // namespace
}  // namespace sen3bot::p2os
