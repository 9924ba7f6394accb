#include <gtest/gtest.h>

#include <string>

#include "sen3bot/nav/waypoints.hpp"

namespace sen3bot::nav {
namespace {

TEST(Waypoints, ParsesPairsCommentsAndBlankLines) {
  auto w = parse_waypoints("# route\n1.5 2\n\n  3, -4.25  # comma works too\n", "w.txt");
  ASSERT_TRUE(w.ok()) << w.error().c_str();
  ASSERT_EQ(w->size(), 2u);
  EXPECT_DOUBLE_EQ((*w)[1].x_m, 3.0);
  EXPECT_DOUBLE_EQ((*w)[1].y_m, -4.25);
}

TEST(Waypoints, ErrorsNameFileAndLine) {
  for (const char* bad : {"1\n", "1 2 3\n", "x y\n", "1 nan\n"}) {
    auto w = parse_waypoints(std::string("0 0\n") + bad, "route.txt");
    ASSERT_FALSE(w.ok()) << bad;
    EXPECT_NE(std::string(w.error().message()).find("route.txt:2"), std::string::npos) << w.error().c_str();
  }
  EXPECT_FALSE(load_waypoints("/nonexistent/route.txt").ok());
}

TEST(Waypoints, ShippedLabRouteLoads) {
  auto w = load_waypoints(SEN3BOT_SOURCE_DIR "/config/maps/lab_waypoints.txt");
  ASSERT_TRUE(w.ok()) << w.error().c_str();
  EXPECT_GT(w->size(), 10u);
}

}  // namespace
}  // namespace sen3bot::nav
