// `sen3bot-sim experiment crowd`: the command's errors, a small benchmark's report (parsed as
// JSON), results that do not depend on the worker count, and a recording's run. Whole firmware
// runs (about 2 s of one core each for the circle's, 6 s for the recording's, natively).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "experiment_support.hpp"
#include "sim_commands.hpp"
#include "sen3bot/json/json.hpp"

namespace sen3bot::sim {
namespace {

using namespace testing;
namespace json = sen3bot::json;

const std::string kCrowdConfig = SEN3BOT_SOURCE_DIR "/config/crowd.yaml";
const std::string kRecording = SEN3BOT_SOURCE_DIR "/data/pedestrians/uni_examples.txt";

TEST(CrowdExperiment, BadArgumentsAreOneLineErrors) {
  const std::string dir = temp_dir();
  ASSERT_FALSE(dir.empty());
  const std::string bad_file = dir + "/bad.txt";
  {
    std::FILE* f = std::fopen(bad_file.c_str(), "w");
    ASSERT_NE(f, nullptr);
    std::fputs("0 1 2.0 3.0\n10 1 2.5\n", f);
    std::fclose(f);
  }
  struct Case {
    std::vector<std::string> args;
    std::string says;
  };
  const std::vector<Case> cases = {
      {{"crowd", "--runs", "2"}, "--scene NAME"},
      {{"crowd", "--scene", "circle", "--trajectories", kRecording, "--runs", "2"}, "alternatives"},
      {{"crowd", "--scene", "hall", "--runs", "2"}, "no scene named 'hall'"},
      {{"crowd", "--scene", "circle"}, "--runs N is required"},
      {{"crowd", "--scene", "circle", "--runs", "0"}, "--runs: expected"},
      {{"crowd", "--scene", "circle", "--runs", "many"}, "--runs: expected"},
      {{"crowd", "--scene", "circle", "--runs", "2", "--people", "0"}, "--people: expected"},
      {{"crowd", "--scene", "circle", "--runs", "2", "--people", "2.5"}, "--people: expected"},
      {{"crowd", "--scene", "circle", "--runs", "2", "--seed", "-1"}, "--seed: expected"},
      {{"crowd", "--scene", "circle", "--runs", "2", "--jobs", "0"}, "--jobs: expected"},
      {{"crowd", "--scene", "circle", "--runs", "2", "--behaviour", "polite"}, "--behaviour: expected"},
      {{"crowd", "--scene", "circle", "--runs", "2", "--behaviour", "recorded"}, "needs --trajectories"},
      {{"crowd", "--scene", "circle", "--runs", "2", "--variant", "clairvoyant"},
       "no variant named 'clairvoyant' (default, no-people, perfect-perception)"},
      {{"crowd", "--scene", "circle", "--runs", "2", "--people", "100"}, "at most 64"},
      {{"crowd", "--scene", "circle", "--runs", "2", "--fast"}, "unknown or incomplete option '--fast'"},
      {{"crowd", "--trajectories", kRecording, "--runs", "2", "--people", "3"}, "--people is for the simulated scenes"},
      {{"crowd", "--trajectories", kRecording, "--runs", "2", "--behaviour", "social"}, "--behaviour social"},
      {{"crowd", "--trajectories", bad_file, "--runs", "2"}, bad_file + ":2:"},
      {{"crowd", "--trajectories", dir + "/missing.txt", "--runs", "2"}, "missing.txt"},
      {{"crowd", "--scene", "circle", "--runs", "2", "--config", dir + "/missing.yaml"}, "missing.yaml"},
  };
  for (const Case& c : cases) expect_usage_error(c.args, c.says);
  std::remove(bad_file.c_str());
}

// runs.csv holds the runs' own numbers only (no wall times): it must not depend on the workers.
TEST(CrowdExperiment, RunsDoNotDependOnTheWorkersAndTheReportParses) {
  const std::string one = temp_dir(), two = temp_dir();
  const CommandRun a = run_experiment(
      {"crowd", "--scene", "circle", "--people", "2", "--runs", "2", "--jobs", "1", "--config", kCrowdConfig, "--report", one});
  const CommandRun b = run_experiment(
      {"crowd", "--scene", "circle", "--people", "2", "--runs", "2", "--jobs", "2", "--config", kCrowdConfig, "--report", two});
  ASSERT_EQ(a.code, 0) << a.err;
  ASSERT_EQ(b.code, 0) << b.err;
  EXPECT_NE(a.out.find("6/6 runs"), std::string::npos) << a.out;
  EXPECT_NE(a.out.find("| success (95 % Wilson interval)"), std::string::npos) << a.out;
  EXPECT_NE(a.out.find("| no-people"), std::string::npos) << a.out;
  EXPECT_NE(a.out.find("| perfect-perception"), std::string::npos) << a.out;
  const std::string csv_a = read_file(one + "/runs.csv"), csv_b = read_file(two + "/runs.csv");
  ASSERT_FALSE(csv_a.empty());
  EXPECT_EQ(csv_a, csv_b);
  EXPECT_EQ(std::count(csv_a.begin(), csv_a.end(), '\n'), 7) << csv_a;  // header + 2 runs x 3 variants
  EXPECT_EQ(csv_a.rfind("variant,seed,", 0), 0u) << csv_a;
  EXPECT_GT(file_size(one + "/time_to_goal.png"), 1000);
  EXPECT_GT(file_size(one + "/sample_run.png"), 1000);
  EXPECT_GT(file_size(one + "/circle.yaml"), 0);

  const std::string text = read_file(one + "/report.json");
  auto doc = std::make_unique<json::StaticDocument<8192>>();
  ASSERT_TRUE(doc->parse(text).ok()) << text;
  const json::Value root = doc->root();
  EXPECT_TRUE(root.find("experiment").string_equals("crowd"));
  EXPECT_TRUE(root.find("scene").string_equals("circle"));
  EXPECT_EQ(*root.find("runs").number(), 2.0);
  EXPECT_EQ(*root.find("people").number(), 2.0);
  const json::Value variants = root.find("variants");
  ASSERT_EQ(variants.size(), 3u);
  for (const char* name : {"default", "no-people", "perfect-perception"}) {
    const json::Value v = variants.find(name);
    ASSERT_TRUE(v.is(json::Type::object)) << name;
    const json::Value aggregate = v.find("aggregate");
    for (const char* key : {"success", "collision", "any_contact", "timeout", "time_to_goal_s", "min_distance_m"})
      EXPECT_TRUE(aggregate.find(key).is(json::Type::object)) << name << " " << key;
    EXPECT_EQ(*aggregate.find("success").find("n").number(), 2.0);
    const json::Value runs = v.find("runs");
    ASSERT_EQ(runs.size(), 2u) << name;
    double seed = 1;
    for (const json::Value run : runs.items()) {
      EXPECT_EQ(*run.find("seed").number(), seed++);
      for (const char* key : {"reached_goal", "success", "timeout"}) EXPECT_TRUE(run.find(key).is(json::Type::boolean)) << key;
      for (const char* key : {"contacts_any", "contacts_by_robot", "cage_entries", "path_length_m", "intimate_zone_s",
                              "personal_zone_s", "danger_frequency", "mean_jerk_m_s3", "max_jerk_m_s3", "steps"})
        EXPECT_TRUE(run.find(key).is(json::Type::number)) << key;
      for (const char* key : {"time_to_goal_s", "time_ratio", "path_ratio", "min_distance_m"})
        EXPECT_TRUE(run.find(key).valid()) << key;
      EXPECT_GT(*run.find("steps").number(), 0.0);
    }
  }
}

TEST(CrowdExperiment, ARecordingRuns) {
  const CommandRun run = run_experiment(
      {"crowd", "--trajectories", kRecording, "--runs", "1", "--variant", "default", "--config", kCrowdConfig});
  ASSERT_EQ(run.code, 0) << run.err;
  EXPECT_NE(run.out.find("1/1 runs"), std::string::npos) << run.out;
  EXPECT_NE(run.out.find("| recorded, N = 1"), std::string::npos) << run.out;
}

// --realtime: the mission on the wall clock over ptys (about 25 s of wall time, little CPU). The
// run cannot take less wall time than it simulated.
TEST(CrowdExperiment, ARealTimeRunTakesItsTimeOnTheWallClock) {
  const std::string dir = temp_dir();
  const CommandRun run = run_experiment({"crowd", "--scene", "circle", "--people", "1", "--runs", "1", "--variant",
                                         "no-people", "--realtime", "--config", kCrowdConfig, "--report", dir});
  ASSERT_EQ(run.code, 0) << run.err;
  EXPECT_NE(run.out.find("real time over ptys"), std::string::npos) << run.out;
  const std::string text = read_file(dir + "/report.json");
  auto doc = std::make_unique<json::StaticDocument<8192>>();
  ASSERT_TRUE(doc->parse(text).ok()) << text;
  EXPECT_TRUE(doc->root().find("clock").string_equals("realtime"));
  for (const json::Value r : doc->root().find("variants").find("no-people").find("runs").items()) {
    EXPECT_GT(*r.find("sim_s").number(), 5.0);
    EXPECT_GE(*r.find("wall_s").number(), 0.95 * *r.find("sim_s").number()) << text;
  }
}

// The scenario's two scripted workers as social walkers: they walk their lanes back and forth,
// give way, and the cages they are in are judged as they truly moved (the judgement once
// replayed only scripts, so a crowd's people were never in a cage).
TEST(PeopleCrossingWalkers, SocialWalkersRunTheScenarioAndTheirCagesAreJudged) {
  const std::string dir = temp_dir();
  const CommandRun run = sen3bot::testing::run_command(
      sim_command, {"--scenario", "people-crossing", "--config", SEN3BOT_SOURCE_DIR "/config/sim.yaml", "--seed", "3",
                    "--walkers", "social", "--report", dir});
  ASSERT_TRUE(run.code == 0 || run.code == 3) << run.err;  // 3: a cage entered or a goal missed
  EXPECT_NE(run.out.find("walkers: social"), std::string::npos) << run.out;
  const std::string report = read_file(dir + "/report.json");
  auto doc = std::make_unique<json::StaticDocument<16384>>();
  ASSERT_TRUE(doc->parse(report).ok()) << report;
  ASSERT_EQ(doc->root().find("cases").size(), 1u);
  json::Value c;
  for (const json::Value item : doc->root().find("cases").items()) c = item;
  const double entries = *c.find("cage_entries").number() + *c.find("cage_entries_by_person").number();
  EXPECT_GE(entries, 1.0) << report;  // seed 3: three, the walkers stepping up to the robot
  EXPECT_GT(*c.find("min_person_distance_m").number(), 0.0) << report;
  EXPECT_GT(file_size(dir + "/two-workers.png"), 1000);

  const CommandRun bad = sen3bot::testing::run_command(sim_command, {"--scenario", "people-crossing", "--walkers", "polite"});
  EXPECT_EQ(bad.code, 2);
  EXPECT_NE(bad.err.find("--walkers: expected scripted, social or blind, got 'polite'"), std::string::npos) << bad.err;
}

}  // namespace
}  // namespace sen3bot::sim
