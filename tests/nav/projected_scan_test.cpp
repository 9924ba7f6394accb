#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <numbers>

#include "alloc_counter.hpp"
#include "sen3bot/nav/projected_scan.hpp"

namespace sen3bot::nav {
namespace {

ScanMessage five_beams() {
  ScanMessage msg;
  msg.count = 5;
  msg.angle_min_rad = static_cast<float>(-std::numbers::pi / 2.0);
  msg.increment_rad = static_cast<float>(std::numbers::pi / 4.0);
  msg.range_min_m = 0.1f;
  msg.range_max_m = 8.0f;
  msg.stamp_ns = 123;
  msg.ranges_m = {};
  msg.ranges_m[0] = 2.0f;                                     // -90 deg: a return
  msg.ranges_m[1] = std::numeric_limits<float>::quiet_NaN();  // unreadable
  msg.ranges_m[2] = 8.0f;                                     // at range_max: no return
  msg.ranges_m[3] = 0.05f;                                    // below range_min
  msg.ranges_m[4] = 1.0f;                                     // +90 deg: a return
  return msg;
}

TEST(ProjectedScan, SortsBeamsIntoReturnsNoReturnsAndUnreadable) {
  const ScanMessage msg = five_beams();
  ProjectedScan scan;
  scan.assign(msg.view(), {});
  ASSERT_EQ(scan.size(), 5u);
  EXPECT_EQ(scan.stamp_ns(), 123);
  EXPECT_TRUE(scan.valid(0));
  EXPECT_FALSE(scan.valid(1));
  EXPECT_FALSE(scan.no_return(1));  // NaN must not clear anything
  EXPECT_FALSE(scan.valid(2));
  EXPECT_TRUE(scan.no_return(2));
  EXPECT_FALSE(scan.valid(3));
  EXPECT_FALSE(scan.no_return(3));
  EXPECT_TRUE(scan.valid(4));
  EXPECT_FALSE(scan.no_return(4));
  EXPECT_EQ(scan.range_m(4), 1.0f);
  ASSERT_EQ(scan.points().size(), 2u);
}

TEST(ProjectedScan, ProjectsThroughTheMount) {
  const ScanMessage msg = five_beams();
  ProjectedScan scan;
  // Laser 0.2 m ahead and 0.1 m left of the centre, turned 90 deg to the left.
  const SensorMount mount{0.2, 0.1, std::numbers::pi / 2.0};
  scan.assign(msg.view(), mount);
  // Beam 0 looks along the sensor's -y: the robot's +x.
  EXPECT_NEAR(scan.end(0).x_m, 2.2, 1e-6);
  EXPECT_NEAR(scan.end(0).y_m, 0.1, 1e-6);
  // Beam 4 looks along the sensor's +y: the robot's -x.
  EXPECT_NEAR(scan.end(4).x_m, -0.8, 1e-6);
  EXPECT_NEAR(scan.end(4).y_m, 0.1, 1e-6);
  // The no-return beam looks along the sensor's +x: the robot's +y.
  EXPECT_NEAR(scan.direction(2).x_m, 0.0, 1e-6);
  EXPECT_NEAR(scan.direction(2).y_m, 1.0, 1e-6);
  // points() are the valid end points in beam order.
  EXPECT_EQ(scan.points()[0].x_m, scan.end(0).x_m);
  EXPECT_EQ(scan.points()[1].y_m, scan.end(4).y_m);
  EXPECT_EQ(scan.mount().x_m, 0.2);
}

TEST(ProjectedScan, EndPointIsTheMountPlusRangeAlongTheDirection) {
  ScanMessage msg;
  msg.count = 181;
  msg.angle_min_rad = static_cast<float>(-std::numbers::pi / 2.0);
  msg.increment_rad = static_cast<float>(std::numbers::pi / 180.0);
  msg.range_max_m = 8.0f;
  for (std::size_t i = 0; i < msg.count; ++i) msg.ranges_m[i] = 0.5f + 0.03f * static_cast<float>(i);
  const SensorMount mount{0.16, -0.02, 0.1};
  ProjectedScan scan;
  scan.assign(msg.view(), mount);
  for (std::size_t i = 0; i < scan.size(); ++i) {
    ASSERT_TRUE(scan.valid(i));
    const double r = scan.range_m(i);
    EXPECT_NEAR(scan.end(i).x_m, mount.x_m + r * scan.direction(i).x_m, 1e-9);
    EXPECT_NEAR(scan.end(i).y_m, mount.y_m + r * scan.direction(i).y_m, 1e-9);
    EXPECT_NEAR(std::hypot(scan.direction(i).x_m, scan.direction(i).y_m), 1.0, 1e-12);
  }
}

TEST(ProjectedScan, ReassigningForgetsTheOldScanAndAllocatesNothing) {
  ScanMessage full;
  full.count = ScanMessage::kMaxBeams;
  full.range_max_m = 8.0f;
  full.increment_rad = 0.004f;
  for (float& r : full.ranges_m) r = 3.0f;
  const ScanMessage small = five_beams();
  ProjectedScan scan;
  mem::testing::AllocationScope scope;
  for (int i = 0; i < 100; ++i) {
    scan.assign(full.view(), {});
    ASSERT_EQ(scan.points().size(), ScanMessage::kMaxBeams);
    scan.assign(small.view(), {});
    ASSERT_EQ(scan.size(), 5u);
    ASSERT_EQ(scan.points().size(), 2u);
  }
  EXPECT_EQ(scope.allocations(), 0u);
}

}  // namespace
}  // namespace sen3bot::nav
