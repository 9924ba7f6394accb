// The worker's path from synthetic LMS200 scans: a person as a circle of returns, with things
// nearer and farther inside and outside the person's box.
#include "sen3bot/cobot/path_recorder.hpp"
#include "sen3bot/geometry/point_math.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <limits>
#include <memory_resource>
#include <numbers>
#include <vector>

#include "alloc_counter.hpp"

namespace sen3bot::cobot {
namespace {

using msg::Point2D;
using msg::Pose2D;

struct Circle {
  Point2D centre;
  double radius_m;
};
struct Segment {
  Point2D a;
  Point2D b;
};

// 361 beams over 180 degrees, as the LMS200 at 0.5 degrees.
class World {
 public:
  std::vector<Circle> circles;
  std::vector<Segment> walls;

  msg::ScanView scan(const Pose2D& laser) {
    for (std::size_t i = 0; i < ranges.size(); ++i) {
      const double a = laser.theta_rad + kMin + static_cast<double>(i) * kIncrement;
      const double dx = std::cos(a);
      const double dy = std::sin(a);
      double best = kMax;
      for (const Circle& c : circles) {
        // |o + t d - c|^2 = r^2
        const double ox = laser.x_m - c.centre.x_m;
        const double oy = laser.y_m - c.centre.y_m;
        const double b = ox * dx + oy * dy;
        const double disc = b * b - (ox * ox + oy * oy - c.radius_m * c.radius_m);
        if (disc < 0.0) continue;
        const double t = -b - std::sqrt(disc);
        if (t > 0.0) best = std::min(best, t);
      }
      for (const Segment& w : walls) {
        const double ex = w.b.x_m - w.a.x_m;
        const double ey = w.b.y_m - w.a.y_m;
        const double den = dx * ey - dy * ex;
        if (std::abs(den) < 1e-12) continue;
        const double wx = w.a.x_m - laser.x_m;
        const double wy = w.a.y_m - laser.y_m;
        const double t = (wx * ey - wy * ex) / den;
        const double u = (wx * dy - wy * dx) / den;
        if (t > 0.0 && u >= 0.0 && u <= 1.0) best = std::min(best, t);
      }
      ranges[i] = static_cast<float>(best);
    }
    return {std::span<const float>(ranges), static_cast<float>(kMin), static_cast<float>(kIncrement), 0.05f,
            static_cast<float>(kMax), 0};
  }

  std::array<float, 361> ranges{};

 private:
  static constexpr double kMin = -std::numbers::pi / 2.0;
  static constexpr double kIncrement = std::numbers::pi / 360.0;
  static constexpr double kMax = 8.0;
};

// A point at range r and bearing b (laser frame) on the map.
Point2D from_laser(const Pose2D& laser, double r, double b) {
  return {laser.x_m + r * std::cos(laser.theta_rad + b), laser.y_m + r * std::sin(laser.theta_rad + b)};
}


class PathRecorderTest : public ::testing::Test {
 protected:
  void SetUp() override {
    ASSERT_TRUE(recorder.init(config, arena));
    recorder.reset(42);
  }
  std::array<std::byte, 32 * 1024> buffer{};
  std::pmr::monotonic_buffer_resource arena{buffer.data(), buffer.size(), std::pmr::null_memory_resource()};
  PathConfig config;
  PathRecorder recorder;
  const Pose2D laser{1.0, 2.0, 0.5};
  static constexpr double kBodyRadius = 0.2;
};

TEST_F(PathRecorderTest, RecordsTheNearestReturnOfTheBody) {
  World world;
  const Point2D person = from_laser(laser, 2.0, 0.1);
  world.circles.push_back({person, kBodyRadius});
  // In the person's box: a thin pole 0.8 m nearer (outside the depth band) and a wall behind.
  world.circles.push_back({from_laser(laser, 1.2, 0.2), 0.03});
  world.walls.push_back({from_laser(laser, 3.6, -0.4), from_laser(laser, 3.6, 0.6)});
  // Outside the box, at a range inside the band and nearer than the body.
  world.circles.push_back({from_laser(laser, 1.75, 0.45), 0.05});
  msg::ScanView scan = world.scan(laser);
  // An unreadable beam on the body.
  const std::size_t on_body = static_cast<std::size_t>(std::lround((0.1 + std::numbers::pi / 2.0) / (std::numbers::pi / 360.0)));
  world.ranges[on_body + 1] = std::numeric_limits<float>::quiet_NaN();

  ASSERT_TRUE(recorder.add_scan(scan, laser, person, 2.0 * kBodyRadius));
  ASSERT_EQ(recorder.size(), 1u);
  const Point2D expected = from_laser(laser, 2.0 - kBodyRadius, 0.1);
  EXPECT_LT(geometry::distance(recorder.point(0), expected), 0.01);
}

TEST_F(PathRecorderTest, NothingInTheBoxRecordsNothing) {
  World world;
  world.walls.push_back({from_laser(laser, 4.0, -0.5), from_laser(laser, 4.0, 0.5)});
  const msg::ScanView scan = world.scan(laser);
  EXPECT_FALSE(recorder.add_scan(scan, laser, from_laser(laser, 2.0, 0.0), 0.4));
  EXPECT_EQ(recorder.size(), 0u);
}

TEST_F(PathRecorderTest, StandingStillAddsNothing) {
  World world;
  world.circles.push_back({from_laser(laser, 2.0, 0.0), kBodyRadius});
  ASSERT_TRUE(recorder.add_scan(world.scan(laser), laser, from_laser(laser, 2.0, 0.0), 0.4));
  // Swaying by a few centimetres, under the spacing.
  for (int k = 0; k < 50; ++k) {
    const Point2D at = from_laser(laser, 2.0 + 0.02 * std::sin(k), 0.01 * std::cos(k));
    world.circles[0].centre = at;
    EXPECT_FALSE(recorder.add_scan(world.scan(laser), laser, at, 0.4)) << k;
  }
  EXPECT_EQ(recorder.size(), 1u);
}

TEST_F(PathRecorderTest, WalkingAddsAPointPerSpacing) {
  World world;
  world.circles.push_back({{}, kBodyRadius});
  for (int k = 0; k < 20; ++k) {
    const Point2D at = from_laser(laser, 2.0, -0.5 + 0.05 * k);  // 0.1 m apart at 2 m
    world.circles[0].centre = at;
    EXPECT_TRUE(recorder.add_scan(world.scan(laser), laser, at, 0.4)) << k;
  }
  EXPECT_EQ(recorder.size(), 20u);
}

TEST_F(PathRecorderTest, AFullPathIsHalvedKeepingBothEnds) {
  config.capacity = 16;
  ASSERT_TRUE(recorder.init(config, arena));
  recorder.reset(3);
  World world;
  world.circles.push_back({{}, kBodyRadius});
  Point2D first{};
  Point2D last{};
  for (int k = 0; k < 100; ++k) {
    // Across in front of the laser, 6 cm a scan.
    const Point2D at{laser.x_m + 2.0 * std::cos(laser.theta_rad) - (-3.0 + 0.06 * k) * std::sin(laser.theta_rad),
                     laser.y_m + 2.0 * std::sin(laser.theta_rad) + (-3.0 + 0.06 * k) * std::cos(laser.theta_rad)};
    world.circles[0].centre = at;
    const msg::ScanView scan = world.scan(laser);
    Point2D sample;
    ASSERT_TRUE(recorder.nearest_return(scan, laser, at, 0.4, sample));
    if (k == 0) first = sample;
    if (recorder.add_scan(scan, laser, at, 0.4)) last = sample;
    ASSERT_LE(recorder.size(), 16u);
  }
  EXPECT_GT(recorder.spacing_m(), config.min_spacing_m);
  EXPECT_LT(geometry::distance(recorder.point(0), first), 1e-12);
  EXPECT_LT(geometry::distance(recorder.point(recorder.size() - 1), last), 1e-12);
  // The newest point is where the walk ended, within the current spacing.
  EXPECT_LT(geometry::distance(last, recorder.point(recorder.size() - 1)), recorder.spacing_m());
  // Still in walking order along the line.
  for (std::size_t i = 1; i < recorder.size(); ++i) {
    const double along_prev = -(recorder.point(i - 1).x_m - laser.x_m) * std::sin(laser.theta_rad) +
                               (recorder.point(i - 1).y_m - laser.y_m) * std::cos(laser.theta_rad);
    const double along = -(recorder.point(i).x_m - laser.x_m) * std::sin(laser.theta_rad) +
                         (recorder.point(i).y_m - laser.y_m) * std::cos(laser.theta_rad);
    EXPECT_GT(along, along_prev) << i;
  }
  EXPECT_GT(recorder.size(), 4u);
}

TEST_F(PathRecorderTest, FillsTheBusMessage) {
  World world;
  world.circles.push_back({{}, kBodyRadius});
  for (int k = 0; k < 5; ++k) {
    const Point2D at = from_laser(laser, 2.0, 0.1 * k);
    world.circles[0].centre = at;
    ASSERT_TRUE(recorder.add_scan(world.scan(laser), laser, at, 0.4));
  }
  msg::WorkerPath path;
  recorder.fill(path);
  EXPECT_EQ(path.count, 5u);
  EXPECT_EQ(path.track, 42u);
  EXPECT_FLOAT_EQ(path.xy[8], static_cast<float>(recorder.point(4).x_m));
  EXPECT_FLOAT_EQ(path.xy[9], static_cast<float>(recorder.point(4).y_m));
  const std::uint32_t version = path.version;
  recorder.reset(43);
  recorder.fill(path);
  EXPECT_EQ(path.count, 0u);
  EXPECT_EQ(path.track, 43u);
  EXPECT_NE(path.version, version);
}

TEST_F(PathRecorderTest, ConfigurationIsChecked) {
  PathRecorder r;
  PathConfig c;
  c.capacity = msg::WorkerPath::kMax + 1;
  EXPECT_FALSE(r.init(c, arena));
  c = PathConfig{};
  c.min_spacing_m = 0.0;
  EXPECT_FALSE(r.init(c, arena));
}

TEST_F(PathRecorderTest, ScansAllocateNothing) {
  World world;
  world.circles.push_back({{}, kBodyRadius});
  std::vector<msg::ScanView> scans;
  std::vector<Point2D> people;
  std::vector<std::array<float, 361>> ranges(200);
  for (int k = 0; k < 200; ++k) {
    const Point2D at = from_laser(laser, 2.0 + std::sin(0.05 * k), 0.3 * std::cos(0.07 * k));
    world.circles[0].centre = at;
    msg::ScanView scan = world.scan(laser);
    ranges[static_cast<std::size_t>(k)] = world.ranges;
    scan.ranges_m = ranges[static_cast<std::size_t>(k)];
    scans.push_back(scan);
    people.push_back(at);
  }
  std::size_t added = 0;
  mem::testing::AllocationScope scope;
  for (std::size_t k = 0; k < scans.size(); ++k) added += recorder.add_scan(scans[k], laser, people[k], 0.4) ? 1 : 0;
  msg::WorkerPath path;
  recorder.fill(path);
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_GT(added, 50u);
}

}  // namespace
}  // namespace sen3bot::cobot
