// `sen3bot-sim experiment dol` running missions: a small experiment's report, the layer
// crossing the arena without contact, a result that does not depend on the worker count, and a
// crashed worker named with its seed. Whole firmware runs: labelled slow.
#include <gtest/gtest.h>

#include <regex>
#include <string>

#include "experiment_support.hpp"

namespace sen3bot::sim {
namespace {

using namespace testing;

TEST(ExperimentCommand, SmallExperimentWritesItsReport) {
  const std::string dir = temp_dir() + "/report";
  const CommandRun run = run_experiment({"dol", "--speed", "0.6", "--runs", "2", "--jobs", "2", "--no-baseline", "--seed", "5",
                              "--config", kConfig, "--report", dir});
  ASSERT_EQ(run.code, 0) << run.err;
  EXPECT_NE(run.out.find("2/2 runs"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("| smooth navigations"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("| successful"), std::string::npos) << run.out;
  const std::string json = read_file(dir + "/report.json");
  ASSERT_FALSE(json.empty());
  EXPECT_NE(json.find("\"experiment\": \"dol\""), std::string::npos);
  EXPECT_NE(json.find("\"runs\": 2,"), std::string::npos);
  EXPECT_NE(json.find("\"seed\": 5,"), std::string::npos);
  EXPECT_NE(json.find("\"dol\": {"), std::string::npos);
  EXPECT_EQ(json.find("\"no_dol\""), std::string::npos) << "--no-baseline";
  const long smooth = count(json, "smooth"), waits = count(json, "wait_recoveries"), collisions = count(json, "collisions"),
             timeouts = count(json, "timeouts"), successful = count(json, "successful");
  ASSERT_GE(smooth, 0);
  ASSERT_GE(waits, 0);
  ASSERT_GE(collisions, 0);
  ASSERT_GE(timeouts, 0);
  EXPECT_EQ(smooth + waits + collisions + timeouts, 2);
  EXPECT_EQ(successful, smooth + waits);
  EXPECT_NE(json.find("\"travel_time_s\": {"), std::string::npos);
  EXPECT_NE(json.find("{\"seed\": 5,"), std::string::npos);
  EXPECT_NE(json.find("{\"seed\": 6,"), std::string::npos);
  EXPECT_GT(file_size(dir + "/travel_times.png"), 1000);
  EXPECT_GT(file_size(dir + "/sample_run.png"), 1000);
}

// The closed loop through the whole firmware: a few seeds of the arena at 0.6 m/s, each
// reaching the goal without touching a box, and the same seeds without the layer colliding
// at least once (so the scene is a real test of it).
TEST(ExperimentCommand, TheLayerCrossesTheArenaWithoutContact) {
  const std::string dir = temp_dir() + "/report";
  const CommandRun run =
      run_experiment({"dol", "--speed", "0.6", "--runs", "6", "--jobs", "2", "--seed", "1", "--config", kConfig, "--report", dir});
  ASSERT_EQ(run.code, 0) << run.err;
  const std::string json = read_file(dir + "/report.json");
  const std::size_t baseline = json.find("\"no_dol\": {");
  ASSERT_NE(baseline, std::string::npos);
  const std::string with_layer = json.substr(0, baseline);
  const std::string without = json.substr(baseline);
  EXPECT_EQ(count(with_layer, "collisions"), 0) << run.out;
  EXPECT_EQ(count(with_layer, "successful"), 6) << run.out;
  EXPECT_GE(count(without, "collisions"), 1) << run.out;
}

// The missions of a report without their wall times.
std::string missions(const std::string& json) {
  const std::size_t at = json.find("\"missions\": [");
  if (at == std::string::npos) return {};
  return std::regex_replace(json.substr(at), std::regex("\"wall_s\": [0-9.]+"), "");
}

TEST(ExperimentCommand, AResultDoesNotDependOnTheWorkers) {
  const std::string one = temp_dir(), two = temp_dir();
  const CommandRun a = run_experiment({"dol", "--speed", "0.8", "--runs", "2", "--jobs", "1", "--no-baseline", "--seed", "11", "--config",
                            kConfig, "--report", one});
  const CommandRun b = run_experiment({"dol", "--speed", "0.8", "--runs", "2", "--jobs", "2", "--no-baseline", "--seed", "11", "--config",
                            kConfig, "--report", two});
  ASSERT_EQ(a.code, 0) << a.err;
  ASSERT_EQ(b.code, 0) << b.err;
  const std::string ma = missions(read_file(one + "/report.json")), mb = missions(read_file(two + "/report.json"));
  ASSERT_FALSE(ma.empty());
  EXPECT_EQ(ma, mb);
}

TEST(ExperimentCommand, ACrashedWorkerNamesItsSeed) {
  ::setenv("SEN3BOT_EXPERIMENT_CRASH_SEED", "22", 1);
  const CommandRun run = run_experiment({"dol", "--speed", "0.6", "--runs", "2", "--jobs", "2", "--no-baseline", "--seed", "21",
                              "--config", kConfig});
  ::unsetenv("SEN3BOT_EXPERIMENT_CRASH_SEED");
  EXPECT_EQ(run.code, 1);
  EXPECT_NE(run.err.find("seed 22"), std::string::npos) << run.err;
  EXPECT_NE(run.err.find("signal"), std::string::npos) << run.err;
}

}  // namespace
}  // namespace sen3bot::sim
