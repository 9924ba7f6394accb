// The bus vocabulary: value semantics a Topic relies on, and the small inline math.
#include <gtest/gtest.h>

#include <cmath>
#include <cstring>
#include <numbers>
#include <type_traits>

#include "sen3bot/msg/messages.hpp"

namespace sen3bot::msg {
namespace {

template <typename T>
constexpr bool kBusValue = std::is_trivially_copyable_v<T> && std::is_standard_layout_v<T>;

static_assert(kBusValue<Point2D> && kBusValue<Pose2D> && kBusValue<SensorMount>);
static_assert(kBusValue<ScanMessage> && kBusValue<Odometry> && kBusValue<BaseFlags>);
static_assert(kBusValue<PoseEstimate> && kBusValue<NavGoal> && kBusValue<PathPoint> && kBusValue<PathMessage>);
static_assert(kBusValue<RecoveryCounts> && kBusValue<ControllerStatus> && kBusValue<VelocityCommand> && kBusValue<FormationCommand>);
static_assert(kBusValue<SafetyOutput>);

TEST(Messages, CopyByBytesKeepsEveryField) {
  ScanMessage scan;
  scan.count = 3;
  scan.ranges_m[2] = 1.5f;
  scan.stamp_ns = 42;
  ScanMessage copy;
  std::memcpy(&copy, &scan, sizeof scan);
  EXPECT_EQ(copy.count, 3);
  EXPECT_EQ(copy.ranges_m[2], 1.5f);
  EXPECT_EQ(copy.stamp_ns, 42);

  PathMessage path;
  path.count = 2;
  path.points[1] = {3.0f, -1.0f};
  path.status = PlanStatus::ok;
  PathMessage path_copy;
  std::memcpy(&path_copy, &path, sizeof path);
  EXPECT_EQ(path_copy.points[1].y_m, -1.0f);
  EXPECT_EQ(path_copy.status, PlanStatus::ok);
}

TEST(Messages, ScanViewCoversTheFilledBeamsOnly) {
  ScanMessage scan;
  scan.count = 5;
  scan.range_max_m = 8.0f;
  EXPECT_EQ(scan.view().ranges_m.size(), 5u);
  EXPECT_EQ(scan.view().range_max_m, 8.0f);
  scan.count = 60000;  // a corrupt count cannot read past the array
  EXPECT_EQ(scan.view().ranges_m.size(), ScanMessage::kMaxBeams);
}

TEST(Geometry, NormalizeAngleWrapsIntoMinusPiToPi) {
  EXPECT_DOUBLE_EQ(normalize_angle(0.5), 0.5);
  EXPECT_NEAR(normalize_angle(2.0 * std::numbers::pi + 0.25), 0.25, 1e-12);
  EXPECT_NEAR(normalize_angle(-2.0 * std::numbers::pi - 0.25), -0.25, 1e-12);
  EXPECT_NEAR(normalize_angle(3.0 * std::numbers::pi / 2.0), -std::numbers::pi / 2.0, 1e-12);
  EXPECT_NEAR(normalize_angle(std::numbers::pi), -std::numbers::pi, 1e-12);
}

TEST(Geometry, ComposePlacesTheSensorInTheRobotsFrame) {
  const Pose2D robot{1.0, 2.0, std::numbers::pi / 2.0};
  const Pose2D laser = compose(robot, SensorMount{0.2, 0.1, 0.3});
  // Facing +y, the mount's forward 0.2 m is +y and its left 0.1 m is -x.
  EXPECT_NEAR(laser.x_m, 0.9, 1e-12);
  EXPECT_NEAR(laser.y_m, 2.2, 1e-12);
  EXPECT_NEAR(laser.theta_rad, std::numbers::pi / 2.0 + 0.3, 1e-12);
}

TEST(Messages, StatusNames) {
  EXPECT_STREQ(to_string(PlanStatus::no_path), "no path");
  EXPECT_STREQ(to_string(DwaStatus::backing_off), "backing_off");
  EXPECT_EQ(RecoveryCounts({1, 2, 3}).total(), 6u);
}

}  // namespace
}  // namespace sen3bot::msg
