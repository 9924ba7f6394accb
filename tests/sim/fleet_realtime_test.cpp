// net-1 with --realtime: the robot, the AGV and the centre as their own programs on a real
// Mosquitto (started by fleet-sim), paced by the wall clock; judged from report.json.
#include <gtest/gtest.h>
#include <stdlib.h>

#include <array>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>

#include "sen3bot/json/json.hpp"
#include "text_file.hpp"

namespace sen3bot::sim {
namespace {

namespace json = sen3bot::json;

TEST(FleetRealtime, Net1TheAgvIsAdvisedBeforeItsOwnScannerCouldHaveSeenThePerson) {
  if (std::system("command -v mosquitto >/dev/null 2>&1") != 0) GTEST_SKIP() << "mosquitto is not installed";
  char dir[] = "/tmp/sen3bot-fleet-rt-XXXXXX";
  ASSERT_NE(::mkdtemp(dir), nullptr);
  const std::string command = std::string(SEN3BOT_SIM_BIN) + " fleet-sim --scenario net-1 --realtime --report " + dir + " > " + dir +
                              "/fleet-sim.out 2>&1";
  const int status = std::system(command.c_str());
  const std::string output = testing::read_file(std::string(dir) + "/fleet-sim.out");
  EXPECT_TRUE(WIFEXITED(status) && WEXITSTATUS(status) == 0) << output;
  const std::string text = testing::read_file(std::string(dir) + "/report.json");
  auto doc = std::make_unique<json::StaticDocument<32768>>();
  const Status parsed = doc->parse(text);
  ASSERT_TRUE(parsed.ok()) << output;
  auto number = [&](const char* key) {
    const json::Value v = doc->root().find(key);
    return v.is(json::Type::number) ? *v.number() : -1.0;
  };
  std::array<char, 32> mode{};
  const auto mode_size = doc->root().find("mode").string(mode);
  ASSERT_TRUE(mode_size);
  EXPECT_EQ(std::string(mode.data(), *mode_size), "realtime");
  const double advised = number("first_advice_s");
  const double unadvised = number("unadvised_own_sensor_first_s");
  ASSERT_GT(advised, 0) << output;
  ASSERT_GT(unadvised, 0) << output;
  EXPECT_LT(advised, unadvised) << output;
  EXPECT_GE(number("min_agv_person_distance_m"), 1.0) << output;
  EXPECT_GT(doc->root().find("timeline").size(), 0u) << output;
  std::system((std::string("rm -rf ") + dir).c_str());
}

}  // namespace
}  // namespace sen3bot::sim
