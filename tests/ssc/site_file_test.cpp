// The site file: the shipped plant site loads, and every mistake is refused naming the key.
#include <gtest/gtest.h>

#include <string>

#include "sen3bot/ssc/service.hpp"

namespace sen3bot::ssc {
namespace {

const std::string kMinimal = R"(
map_id: hall
areas:
  - { name: cross, type: "1.1", outline: [[0, 0], [2, 0], [2, 2], [0, 2]], sentries: [[1, 3, -90]] }
robots:
  - { serial: r1, home: [5, 5, 90], overlooks: cross }
)";

TEST(SiteFile, TheShippedPlantSiteLoads) {
  Result<SiteFile> site = load_site(SEN3BOT_SOURCE_DIR "/config/fleet/site.yaml");
  ASSERT_TRUE(site.ok()) << site.error().c_str();
  EXPECT_EQ(site->service.map_id, "plant");
  ASSERT_EQ(site->area_names.size(), 3u);
  EXPECT_EQ(site->area_names[0], "cross");
  EXPECT_EQ(site->site.areas[0].type, AreaType::blind_intersection);
  EXPECT_EQ(site->site.areas[1].type, AreaType::transition);
  ASSERT_EQ(site->robot_serials.size(), 3u);
  EXPECT_EQ(site->site.robots[0].overlooks, 0);
  EXPECT_EQ(site->site.robots[1].overlooks, kNone);
  EXPECT_NEAR(site->site.robots[0].pose.theta_rad, -3.14159265358979 / 2, 1e-9);
  EXPECT_DOUBLE_EQ(site->centre.slow_speed_factor, 0.3);
}

TEST(SiteFile, AMinimalSiteTakesTheDefaults) {
  Result<SiteFile> site = parse_site(kMinimal, "min.yaml");
  ASSERT_TRUE(site.ok()) << site.error().c_str();
  EXPECT_EQ(site->service.version, vda5050::Version::v2_1_0);
  EXPECT_FALSE(site->service.direct_pause);
  EXPECT_EQ(site->service.robot_manufacturer, "Sen3Bot");
}

TEST(SiteFile, MistakesAreRefusedNamingTheKey) {
  struct Case {
    const char* what;
    std::string yaml;
    const char* expect;
  };
  auto replace = [](std::string text, const std::string& from, const std::string& to) {
    text.replace(text.find(from), from.size(), to);
    return text;
  };
  const Case cases[] = {
      {"unknown top key", kMinimal + "colour: red\n", "colour"},
      {"no map id", replace(kMinimal, "map_id: hall", ""), "map_id"},
      {"bad area type", replace(kMinimal, "type: \"1.1\"", "type: \"4\""), "areas[0].type"},
      {"two-vertex outline", replace(kMinimal, "[[0, 0], [2, 0], [2, 2], [0, 2]]", "[[0, 0], [2, 0]]"), "three vertices"},
      {"not a number", replace(kMinimal, "[5, 5, 90]", "[5, five, 90]"), "robots[0].home"},
      {"unknown overlooked area", replace(kMinimal, "overlooks: cross", "overlooks: dock"), "dock"},
      {"bad version", "version: 3.0.0\n" + kMinimal, "version"},
      {"stop beyond slow", kMinimal + "centre: { slow_distance_m: 2, stop_distance_m: 5 }\n", "stop_distance_m"},
      {"factor out of range", kMinimal + "centre: { slow_speed_factor: 2 }\n", "slow_speed_factor"},
      {"unknown agv_cc key", kMinimal + "agv_cc: { pause: true }\n", "agv_cc.pause"},
      {"duplicate serial", kMinimal + "  - { serial: r1, home: [1, 1] }\n", "r1"},
      {"not YAML", "areas: [", "min.yaml"},
  };
  for (const Case& c : cases) {
    SCOPED_TRACE(c.what);
    Result<SiteFile> site = parse_site(c.yaml, "min.yaml");
    ASSERT_FALSE(site.ok());
    EXPECT_EQ(site.error().code(), Errc::config);
    EXPECT_NE(std::string(site.error().c_str()).find(c.expect), std::string::npos) << site.error().c_str();
  }
  EXPECT_EQ(load_site("/nonexistent/site.yaml").error().code(), Errc::not_found);
}

}  // namespace
}  // namespace sen3bot::ssc
