// The wiring the rows' factories declare (firmware/wiring.hpp): the graph is the flow the
// firmware runs, each topic has a single writer (a Topic's rule), and what a running row reads
// someone writes.
#include <gtest/gtest.h>

#include <cstdio>
#include <map>
#include <string>
#include <vector>

#include "config.hpp"
#include "firmware.hpp"
#include "sim_rig.hpp"
#include "task_table.hpp"

namespace sen3bot::firmware {
namespace {

struct Ends {
  std::vector<std::string> writers, readers;
};

std::map<std::string, Ends> topic_ends(const Firmware& fw) {
  std::map<std::string, Ends> ends;
  for (const RowWiring& r : fw.wiring()) {
    if (!r.absent.empty()) continue;
    for (const std::string& t : r.writes) ends[t].writers.emplace_back(r.name);
    for (const std::string& t : r.reads) ends[t].readers.emplace_back(r.name);
  }
  return ends;
}

const RowWiring& row_wiring(const Firmware& fw, std::string_view name) {
  for (const RowWiring& r : fw.wiring())
    if (r.name == name) return r;
  ADD_FAILURE() << "no row " << name;
  return fw.wiring()[0];
}

bool has(const std::vector<std::string>& list, const char* name) {
  for (const std::string& s : list)
    if (s == name) return true;
  return false;
}

// The simulated robot's whole table: the path from the laser's bytes to the base's command.
TEST(Wiring, TheMissionsPathFromTheLaserToTheWheelsIsDeclared) {
  testing::SimRig rig = testing::load_sim_rig();
  Firmware fw(rig.config, *rig.board, stdout);
  ASSERT_TRUE(fw.wire());
  const RowWiring& laser = row_wiring(fw, "laser");
  ASSERT_TRUE(laser.absent.empty());
  EXPECT_TRUE(has(laser.writes, "scan"));
  ASSERT_FALSE(laser.devices.empty());
  EXPECT_EQ(laser.devices[0].rfind("<- LMS200", 0), 0u) << laser.devices[0];
  const RowWiring& safety = row_wiring(fw, "safety");
  EXPECT_TRUE(has(safety.reads, "scan"));
  EXPECT_TRUE(has(safety.reads, "request"));
  EXPECT_TRUE(has(safety.reads, "safety_io"));  // sim.yaml has the CAN node
  EXPECT_TRUE(has(safety.writes, "command"));
  const RowWiring& base = row_wiring(fw, "base");
  EXPECT_TRUE(has(base.reads, "command"));
  EXPECT_TRUE(has(base.writes, "odometry"));
  EXPECT_EQ(row_wiring(fw, "camera").absent, "needs devices.camera");

  // Every topic a running row reads has exactly one writer; none has two.
  for (const auto& [topic, ends] : topic_ends(fw)) {
    EXPECT_EQ(ends.writers.size(), 1u) << topic;
    EXPECT_FALSE(ends.readers.empty()) << topic << " is written and read by no row";
  }
}

// With the collaborative mode the mission's goals go to the cobot row, which writes the
// planner's: still one writer per topic; with a fleet the fleet writes them instead.
TEST(Wiring, EachTopicHasOneWriterWithTheCobotOrTheFleet) {
  for (const bool fleet : {false, true}) {
    testing::SimRig rig = testing::load_sim_rig();
    FirmwareConfig config = rig.config;
    config.navigation.people_enabled = true;
    config.navigation.people_detector = "sim";
    config.cobot.enabled = true;
    config.cobot.site_path = std::string(SEN3BOT_SOURCE_DIR) + "/config/cobot/lab_site.yaml";
    config.has_fleet = fleet;
    if (fleet) config.fleet.broker = "sim";
    config.view.enabled = true;
    Firmware fw(config, *rig.board, stdout);
    ASSERT_TRUE(fw.wire());
    const auto ends = topic_ends(fw);
    for (const auto& [topic, e] : ends) EXPECT_LE(e.writers.size(), 1u) << topic << (fleet ? " (fleet)" : "");
    EXPECT_EQ(ends.at("goal").writers, std::vector<std::string>{"cobot"});
    EXPECT_EQ(ends.at("cooperative_goal").writers, std::vector<std::string>{fleet ? "fleet" : "mission"});
    EXPECT_EQ(row_wiring(fw, fleet ? "mission" : "fleet").absent.empty(), false);
    // The view reads the planner's and the mission's state in place: declared as such.
    EXPECT_TRUE(has(row_wiring(fw, "view").uses, "planner"));
  }
}

// The graph names the camera's stream without its credentials.
TEST(Wiring, TheCamerasCredentialsStayOutOfTheGraph) {
  testing::SimRig rig = testing::load_sim_rig();
  FirmwareConfig config = rig.config;
  config.devices.has_camera = true;
  config.devices.camera.rtsp.url = "rtsp://operator:s3cret@10.0.0.5:554/live@main";
  Firmware fw(config, *rig.board, stdout);
  ASSERT_TRUE(fw.wire());
  const RowWiring& camera = row_wiring(fw, "camera");
  ASSERT_FALSE(camera.devices.empty());
  EXPECT_EQ(camera.devices[0].find("RTSP/RTP from rtsp://10.0.0.5:554/live@main:"), 3u) << camera.devices[0];
  for (const std::string& d : camera.devices) EXPECT_EQ(d.find("s3cret"), std::string::npos) << d;
}

// A row the configuration leaves out says why, and a budget for it is refused with that reason.
TEST(Wiring, ARowLeftOutSaysWhy) {
  testing::SimRig rig = testing::load_sim_rig();
  FirmwareConfig config = rig.config;
  config.tasks["fleet"].arena_bytes = 1024;
  Firmware fw(config, *rig.board, stdout);
  const Status s = fw.init();
  ASSERT_FALSE(s);
  EXPECT_NE(std::string(s.error().message()).find("tasks.fleet: this task is not enabled by the configuration (needs a "
                                                  "fleet section)"),
            std::string::npos)
      << s.error().c_str();
}

}  // namespace
}  // namespace sen3bot::firmware
