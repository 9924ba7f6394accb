// `sen3bot-sim sim --scenario estop`: every case of the safety I/O stops the robot while it
// drives, and the mission still completes once the reset button was pressed. The report says
// when the robot stood and how far it went: from 0.5 m/s at the base's 0.6 m/s^2 it stands in
// about 0.83 s and 0.21 m, later by the heartbeat timeout when the node falls silent.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "text_file.hpp"
#include "sim_commands.hpp"

namespace sen3bot::sim {
namespace {

using sen3bot::testing::read_file;

// The value of `key` in the n-th case of the report.
double field(const std::string& json, const std::string& key, int n) { return sen3bot::testing::json_number(json, key, n); }

TEST(EstopScenario, EveryCaseStopsTheRobotAndTheMissionCompletesAfterTheReset) {
  char dir_template[] = "/tmp/sen3bot-estop-XXXXXX";
  ASSERT_NE(::mkdtemp(dir_template), nullptr);
  std::string report = dir_template;
  std::string config = SEN3BOT_SOURCE_DIR "/config/sim.yaml";
  std::vector<char*> argv = {const_cast<char*>("--scenario"), const_cast<char*>("estop"),
                             const_cast<char*>("--config"), config.data(),
                             const_cast<char*>("--report"), report.data()};
  std::FILE* out = std::tmpfile();
  std::FILE* err = std::tmpfile();
  const int code = sim_command(static_cast<int>(argv.size()), argv.data(), out, err);
  std::fclose(out);
  std::fclose(err);
  EXPECT_EQ(code, 0) << "a case did not complete, or collided";
  const std::string json = read_file(report + "/report.json");
  ASSERT_NE(json.find("\"scenario\": \"estop\""), std::string::npos);
  const char* cases[] = {"estop-pressed", "bumper-hit", "node-silent", "bus-off", "node-reboot"};
  for (int i = 0; i < 5; ++i) {
    SCOPED_TRACE(cases[i]);
    EXPECT_NE(json.find(cases[i]), std::string::npos);
    EXPECT_EQ(field(json, "trips", i), 1.0);
    EXPECT_GT(field(json, "speed_at_event_m_s", i), 0.3) << "the event should come while the robot drives";
    const double stop_s = field(json, "stop_s", i);
    EXPECT_GT(stop_s, 0.0);
    // Braking from at most 0.5 m/s at 0.6 m/s^2 takes 0.83 s; the wire adds at most two control
    // periods, a silent node its heartbeat timeout (0.35 s).
    EXPECT_LT(stop_s, i == 2 ? 0.83 + 0.35 + 0.05 : 0.83 + 0.05);
    EXPECT_LT(field(json, "stop_distance_m", i), i == 2 ? 0.40 : 0.25);
    // Held until the reset, not longer than the reset plus the node's start-up.
    EXPECT_GT(field(json, "held_s", i), 1.5);
  }
}

}  // namespace
}  // namespace sen3bot::sim
