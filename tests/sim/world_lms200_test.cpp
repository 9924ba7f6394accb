#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "sen3bot/world/lms200_range_source.hpp"

namespace sen3bot::world {
namespace {

TEST(WorldRangeSource, RangesAtTheSensorPoseWithInfinityForNoReturn) {
  nav::OccupancyMap m(80, 80, 0.05, 0.0, 0.0);
  for (int r = 0; r < 80; ++r) m.set(79, r, 100);  // one wall at x in [3.95, 4.0)
  World w(m);
  WorldRangeSource source(w);
  source.set_sensor_pose(2.0, 2.0, 0.0);
  lms200::ScanGeometry g;
  g.angle_min_rad = -M_PI / 2.0;
  g.angle_increment_rad = M_PI / 2.0;
  g.count = 3;
  g.range_max_m = 8.0;
  std::vector<float> out(3);
  source.ranges(0, g, out);
  EXPECT_TRUE(std::isinf(out[0]));
  EXPECT_NEAR(out[1], 1.95, 1e-6);
  EXPECT_TRUE(std::isinf(out[2]));
}

}  // namespace
}  // namespace sen3bot::world
