#include <gtest/gtest.h>

#include <cstdio>
#include <string>

#include "config.hpp"
#include "firmware.hpp"
#include "sim_rig.hpp"
#include "task_table.hpp"

namespace sen3bot::firmware {
namespace {

FirmwareConfig sim_config() { return testing::load_sim_rig().config; }

TEST(TaskTable, RowsAreValidAndNamesUnique) {
  for (std::size_t i = 0; i < kTaskTable.size(); ++i) {
    const auto& row = kTaskTable[i];
    EXPECT_GT(row.period_us, 0) << row.name;
    EXPECT_GT(row.budget_us, 0) << row.name;
    EXPECT_LE(row.budget_us, row.period_us) << row.name;
    for (std::size_t j = i + 1; j < kTaskTable.size(); ++j) EXPECT_NE(row.name, kTaskTable[j].name);
  }
}

// config/sim.yaml's robot has every device but a camera, no person detector (the detector's,
// the people's and the on-board detector's rows), its mission's goals instead of a fleet, and no
// collaborative mode (the cobot, qr and recognition rows), no live view and no map building.
constexpr std::size_t kSimulatedRows = kTaskTable.size() - 10;

TEST(Firmware, InitBuildsTheWholeTableWithinBudgets) {
  FirmwareConfig config = sim_config();
  testing::SimRig rig = testing::load_sim_rig();
  Firmware fw(config, *rig.board, stdout);
  ASSERT_TRUE(fw.init());
  ASSERT_EQ(fw.scheduler().task_count(), kSimulatedRows);
  for (std::size_t i = 0; i < fw.scheduler().task_count(); ++i) {
    EXPECT_EQ(fw.arena(i).name(), fw.scheduler().spec(i).name);
    EXPECT_NE(fw.scheduler().spec(i).name, "camera");
    EXPECT_LE(fw.arena(i).used_bytes(), fw.arena(i).capacity_bytes());
  }
}

TEST(Firmware, AnExceededBudgetFailsInitNamingTaskArenaAndKey) {
  FirmwareConfig config = sim_config();
  config.tasks["telemetry"].arena_bytes = 64;  // its line buffer needs 512 B
  testing::SimRig rig = testing::load_sim_rig();
  Firmware fw(config, *rig.board, stdout);
  const Status s = fw.init();
  ASSERT_FALSE(s);
  const std::string m(s.error().message());
  EXPECT_EQ(s.error().code(), Errc::capacity);
  EXPECT_NE(m.find("task 'telemetry' init failed"), std::string::npos) << m;
  EXPECT_NE(m.find("budget 64 B exceeded: request of 512 B"), std::string::npos) << m;
  EXPECT_NE(m.find("tasks.telemetry.arena_bytes"), std::string::npos) << m;
}

TEST(Firmware, TheSupervisoryPlannerChecksItsCurveAtInit) {
  FirmwareConfig config = sim_config();
  config.navigation.waypoints_path.clear();
  config.navigation.safe_curve_path = SEN3BOT_SOURCE_DIR "/config/maps/lab_curve.yaml";
  {
    testing::SimRig rig = testing::load_sim_rig();
    Firmware fw(config, *rig.board, stdout);
    ASSERT_TRUE(fw.init());
    ASSERT_NE(fw.planner(), nullptr);
    ASSERT_NE(fw.planner()->sgp(), nullptr);
    EXPECT_EQ(fw.planner()->sgp()->obstacles().size(), 31u);  // every wall, rack and the pillar of lab.yaml
    EXPECT_TRUE(fw.safe_path().empty());                      // until a goal comes
  }
  // A circle through the upper racks: refused at init, naming the task, the ellipse and the place.
  const std::string bad = ::testing::TempDir() + "through_racks.yaml";
  std::FILE* f = std::fopen(bad.c_str(), "w");
  ASSERT_NE(f, nullptr);
  std::fputs("shape: circle\ncentre: [1.6, 7.0]\nradius_m: 0.8\n", f);
  std::fclose(f);
  config.navigation.safe_curve_path = bad;
  testing::SimRig rig = testing::load_sim_rig();
  Firmware fw(config, *rig.board, stdout);
  const Status s = fw.init();
  ASSERT_FALSE(s);
  const std::string m(s.error().message());
  EXPECT_NE(m.find("planner task: safe curve: the safe curve crosses obstacle ellipse"), std::string::npos) << m;
  EXPECT_NE(m.find("centre (1.60, 6.25) m"), std::string::npos) << m;
  // A file that is not there: the configuration key says which.
  config.navigation.safe_curve_path = ::testing::TempDir() + "none.yaml";
  testing::SimRig rig2 = testing::load_sim_rig();
  Firmware fw2(config, *rig2.board, stdout);
  const Status missing = fw2.init();
  ASSERT_FALSE(missing);
  EXPECT_NE(std::string(missing.error().message()).find("navigation.safe_curve: "), std::string::npos)
      << missing.error().c_str();
}

TEST(Firmware, ACameraBudgetWithoutACameraIsAConfigurationError) {
  FirmwareConfig config = sim_config();
  config.tasks["camera"].arena_bytes = 1024;
  testing::SimRig rig = testing::load_sim_rig();
  Firmware fw(config, *rig.board, stdout);
  const Status s = fw.init();
  ASSERT_FALSE(s);
  EXPECT_NE(std::string(s.error().message()).find("tasks.camera: this task is not enabled by the configuration (needs devices.camera)"),
            std::string::npos)
      << s.error().c_str();
}

// The on-board detector reads the camera's frames: without a camera it cannot be chosen, and a
// vision budget without it is named.
TEST(Firmware, TheOnBoardDetectorNeedsTheCamera) {
  FirmwareConfig config = sim_config();
  config.navigation.people_enabled = true;
  config.navigation.people_detector = "onboard";
  config.tasks["people"].arena_bytes = 64 * 1024;
  testing::SimRig rig = testing::load_sim_rig();
  Firmware fw(config, *rig.board, stdout);
  const Status s = fw.init();
  ASSERT_FALSE(s);
#ifdef SEN3BOT_HAS_HOG
  EXPECT_NE(std::string(s.error().message()).find("navigation.people.detector: onboard needs devices.camera"),
            std::string::npos)
      << s.error().c_str();
#else
  EXPECT_NE(std::string(s.error().message()).find("this build has no on-board detector"), std::string::npos)
      << s.error().c_str();
#endif
  FirmwareConfig remote = sim_config();
  remote.tasks["vision"].arena_bytes = 1024;
  testing::SimRig rig2 = testing::load_sim_rig();
  Firmware fw2(remote, *rig2.board, stdout);
  const Status s2 = fw2.init();
  ASSERT_FALSE(s2);
  EXPECT_NE(std::string(s2.error().message()).find("tasks.vision: this task is not enabled by the configuration (needs "
                                                   "navigation.people.detector: onboard)"),
            std::string::npos)
      << s2.error().c_str();
}

TEST(Firmware, ATaskWithoutABudgetOrAnUnknownTaskIsAConfigurationError) {
  FirmwareConfig config = sim_config();
  config.tasks.erase("health");
  testing::SimRig rig = testing::load_sim_rig();
  {
    Firmware fw(config, *rig.board, stdout);
    const Status s = fw.init();
    ASSERT_FALSE(s);
    EXPECT_NE(std::string(s.error().message()).find("tasks.health.arena_bytes: missing"), std::string::npos);
  }
  config = sim_config();
  config.tasks["navigator"].arena_bytes = 1024;
  {
    Firmware fw(config, *rig.board, stdout);
    const Status s = fw.init();
    ASSERT_FALSE(s);
    EXPECT_NE(std::string(s.error().message()).find("tasks.navigator: no such task"), std::string::npos);
  }
  config = sim_config();
  config.threads["gpu"] = ThreadConfig{};
  {
    Firmware fw(config, *rig.board, stdout);
    const Status s = fw.init();
    ASSERT_FALSE(s);
    EXPECT_NE(std::string(s.error().message()).find("threads.gpu: no task runs on this thread"), std::string::npos);
  }
}

TEST(Firmware, ASimulatedMinuteKeepsEveryRateExactly) {
  FirmwareConfig config = sim_config();
  std::FILE* sink = std::fopen("/dev/null", "w");
  testing::SimRig rig = testing::load_sim_rig();
  Firmware fw(config, *rig.board, sink);
  ASSERT_TRUE(fw.init());
  ASSERT_TRUE(fw.scheduler().run_lockstep(rig.clock(), hal::seconds(60)));
  ASSERT_EQ(fw.scheduler().task_count(), kSimulatedRows);
  for (std::size_t i = 0; i < fw.scheduler().task_count(); ++i) {
    const tasks::TaskStats s = fw.scheduler().stats(i);
    EXPECT_EQ(s.runs, static_cast<std::uint64_t>(60'000'000 / s.period_us)) << s.name;
    EXPECT_EQ(s.overruns + s.slips + s.skips, 0u) << s.name;
  }
  tasks::Sample<tasks::HealthReport> health;
  ASSERT_TRUE(fw.bus().health.read(health));
  EXPECT_TRUE(health.value.ok);
  fw.shutdown();
  std::fclose(sink);
}

}  // namespace
}  // namespace sen3bot::firmware
