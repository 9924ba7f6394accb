// The formation examples end to end (sen3bot-sim formation): whole firmwares on simulated boards
// and the centre's formation service on one in-process broker, judged from the ground truth;
// and what the team does when the centre falls silent, when a message is malformed and when a
// robot's pose goes stale.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "formation_sim.hpp"
#include "sen3bot/json/json.hpp"
#include "sim_commands.hpp"
#include "text_file.hpp"

namespace sen3bot::sim {
namespace {

namespace json = sen3bot::json;
using testing::read_file;

constexpr double kHoldS = 0.5;
constexpr double kStandingMS = 0.01;  // true forward speed below this: standing

bool exists(const std::string& path) {
  struct stat st {};
  return ::stat(path.c_str(), &st) == 0 && st.st_size > 0;
}

// sen3bot-sim formation --example N --report DIR, judged from DIR/formation.json.
void run_example(int number) {
  char dir[] = "/tmp/sen3bot-formation-XXXXXX";
  ASSERT_NE(::mkdtemp(dir), nullptr);
  std::string example = std::to_string(number);
  std::vector<char*> argv = {const_cast<char*>("--example"), example.data(), const_cast<char*>("--report"), dir};
  std::FILE* out = std::tmpfile();
  std::FILE* err = std::tmpfile();
  const int code = formation_command(static_cast<int>(argv.size()), argv.data(), out, err);
  std::fclose(out);
  std::fclose(err);
  const std::string base = std::string(dir) + "/";
  for (const char* file : {"formation.json", "trajectories.png", "distances.png", "distances.csv"})
    EXPECT_TRUE(exists(base + file)) << file;
  const std::string text = read_file(base + "formation.json");
  auto doc = std::make_unique<json::StaticDocument<8192>>();
  ASSERT_TRUE(doc->parse(text).ok()) << text;
  const json::Value root = doc->root();
  EXPECT_EQ(*root.find("example").number(), number);
  EXPECT_DOUBLE_EQ(*root.find("robot_radius_m").number(), 0.3);
  const json::Value summary = root.find("summary");
  for (const char* key : {"min_robot_distance_m", "obstacle_contacts", "targets_reached", "formation_error_m", "converge_s", "runs"})
    EXPECT_TRUE(summary.find(key).is(json::Type::number)) << key;
  std::size_t runs = 0;
  for (json::Value run : root.find("runs").items()) {
    ++runs;
    for (const char* key : {"min_robot_distance_m", "obstacle_contacts", "targets_reached", "formation_error_m", "converge_s",
                            "min_scale", "commands_sent"})
      EXPECT_TRUE(run.find(key).is(json::Type::number)) << key;
    EXPECT_TRUE(run.find("switches_s").is(json::Type::array));
  }
  EXPECT_EQ(runs, 1u);
  const FormationExample& ex = *formation_example(number);
  EXPECT_GE(*summary.find("min_robot_distance_m").number(), 2 * kFormationRadiusM);
  EXPECT_EQ(*summary.find("obstacle_contacts").number(), 0.0);
  if (ex.config.task == formation::TaskKind::targets) {
    EXPECT_EQ(*summary.find("targets_reached").number(), 4.0);
  }
  EXPECT_LE(*summary.find("formation_error_m").number(), kFormationErrorBoundM);
  EXPECT_GE(*summary.find("converge_s").number(), 0.0);
  EXPECT_LT(*summary.find("converge_s").number(), ex.duration_s);
  EXPECT_EQ(code, 0);
  const std::string csv = read_file(base + "distances.csv");
  EXPECT_EQ(csv.rfind("t_s,d_f1-f2_m,", 0), 0u) << csv.substr(0, 80);
}

TEST(FormationExamples, Example1FourRobotsReachTheirTargets) { run_example(1); }
TEST(FormationExamples, Example2ThreeRobotsPatrolTheEllipse) { run_example(2); }
TEST(FormationExamples, Example3FollowersKeepTheirOffsetsFromTheLeader) { run_example(3); }

std::unique_ptr<FormationRig> rig_for(int number) {
  const FormationExample& ex = *formation_example(number);
  auto rig = FormationRig::create(ex, ex.starts, FormationRunOptions{});
  EXPECT_TRUE(rig.ok()) << (rig.ok() ? "" : rig.error().c_str());
  return rig.ok() ? std::move(rig.value()) : nullptr;
}

double fastest(FormationRig& rig) {
  double v = 0;
  for (std::size_t i = 0; i < rig.robots(); ++i) v = std::max(v, std::abs(rig.board(i).simulation().truth().speed_m_s));
  return v;
}

// The team drives at most half the robot's 0.5 m/s (the common scaling); the base brakes at
// 0.6 m/s^2 (devices.base.trans_decel_m_s2), so stopping takes up to this long once a
// robot's hold has run out.
constexpr double kBrakingS = 0.25 / 0.6;

// Runs on until `until_s`. A robot's hold ends `hold_ends_s` at the latest: 0.3 s later every
// robot must be braking (slower than when the commands stopped), and once braked (kBrakingS
// more) standing. Returns the time the last robot stopped.
double run_and_watch(FormationRig& rig, double hold_ends_s, double until_s) {
  double last_moving_s = rig.t_s();
  double v_hold_end = -1.0;  // the fastest robot's speed when the holds run out
  bool braking_checked = false;
  while (rig.t_s() < until_s) {
    EXPECT_TRUE(rig.advance().ok());
    const double v = fastest(rig);
    if (v >= kStandingMS) last_moving_s = rig.t_s();
    if (v_hold_end < 0 && rig.t_s() >= hold_ends_s) v_hold_end = v;
    if (!braking_checked && rig.t_s() >= hold_ends_s + 0.3) {
      braking_checked = true;
      // Robots drive their last command to the end of the hold, faster or slower; from there
      // they brake (0.6 m/s^2 less the controller's period to notice).
      EXPECT_TRUE(v < kStandingMS || v < v_hold_end - 0.05) << "not braking at " << rig.t_s() << " s: " << v << " m/s, "
                                                           << v_hold_end << " m/s when the holds ran out";
    }
    if (rig.t_s() >= hold_ends_s + kBrakingS + 0.3 && v >= kStandingMS)
      ADD_FAILURE() << "moving at " << v << " m/s at " << rig.t_s() << " s";
  }
  return last_moving_s;
}

TEST(FormationFaults, ACentreThatStopsSteppingLeavesEveryRobotStanding) {
  auto rig = rig_for(1);
  ASSERT_NE(rig, nullptr);
  ASSERT_TRUE(rig->run_for(4.0).ok());
  ASSERT_GT(fastest(*rig), 0.05) << "the team should be driving when the centre falls silent";
  rig->set_centre_stepping(false);
  const double last_command_s = rig->last_command_s();
  const double stopped_s = run_and_watch(*rig, last_command_s + kHoldS, last_command_s + 4.0);
  std::printf("centre silent after %.2f s: the last robot stood at %.2f s (%.2f s after the last command)\n", last_command_s,
              stopped_s, stopped_s - last_command_s);
  rig->shutdown();
}

TEST(FormationFaults, ACentreCutOffTheBrokerLeavesEveryRobotStanding) {
  auto rig = rig_for(2);
  ASSERT_NE(rig, nullptr);
  ASSERT_TRUE(rig->run_for(8.0).ok());
  ASSERT_GT(fastest(*rig), 0.05);
  // The last step before the cut is the last command the robots get.
  const double cut_s = rig->t_s();
  const double last_command_s = rig->last_command_s();
  rig->broker().set_reachable(kFormationCentreId, false);
  const double stopped_s = run_and_watch(*rig, last_command_s + kHoldS, cut_s + 4.0);
  EXPECT_GT(rig->service().link().stats().publish_dropped + rig->service().counters().publish_failures, 0u);
  std::printf("centre cut off at %.2f s (last command %.2f s): the last robot stood at %.2f s\n", cut_s, last_command_s, stopped_s);
  // Back on the broker, the centre drives the team again.
  rig->broker().set_reachable(kFormationCentreId, true);
  ASSERT_TRUE(rig->run_for(3.0).ok());
  EXPECT_GT(fastest(*rig), 0.05);
  rig->shutdown();
}

TEST(FormationFaults, AMalformedVisualizationIsCountedAndDoesNotDisturbTheRun) {
  auto rig = rig_for(2);
  ASSERT_NE(rig, nullptr);
  ASSERT_TRUE(rig->run_for(5.0).ok());
  rig->broker().publish("uagv/v2/Sen3Bot/f1/visualization", hal::as_bytes("{\"headerId\": 1, \"agvPosition\": {\"x\": "), false);
  rig->broker().publish("uagv/v2/Sen3Bot/f2/visualization", hal::as_bytes("not json"), false);
  const std::uint64_t stale_before = rig->service().counters().stale_steps;
  ASSERT_TRUE(rig->run_for(formation_example(2)->duration_s - 5.0).ok());
  rig->shutdown();
  EXPECT_EQ(rig->service().counters().rejected, 2u);
  EXPECT_EQ(rig->service().counters().stale_steps, stale_before);
  const FormationMetrics m = rig->metrics();
  EXPECT_TRUE(m.passed) << (m.failures.empty() ? "" : m.failures.front());
}

TEST(FormationFaults, ARobotWhosePoseGoesStaleMakesTheCentreStopTheTeam) {
  auto rig = rig_for(3);
  ASSERT_NE(rig, nullptr);
  ASSERT_TRUE(rig->run_for(10.0).ok());
  ASSERT_GT(fastest(*rig), 0.05);
  // f2's link goes down: its poses stop coming, and the centre's commands no longer reach it.
  const double cut_s = rig->t_s();
  const std::uint64_t stale_before = rig->service().counters().stale_steps;
  rig->broker().set_reachable("f2", false);
  // Stale after the 0.5 s timeout; the next step (0.1 s) sends stop, which the others take at
  // once and which f2 never gets: it stops when its last command's hold ends.
  const double stopped_s = run_and_watch(*rig, cut_s + 0.5 + 0.1 + kHoldS, cut_s + 4.0);
  EXPECT_GE(rig->service().counters().stale_steps - stale_before, 30u);
  for (std::size_t i = 0; i < rig->robots(); ++i) {
    EXPECT_EQ(rig->service().commands()[i].v, 0.0);
    EXPECT_EQ(rig->service().commands()[i].w, 0.0);
  }
  std::printf("f2 cut off at %.2f s: the last robot stood at %.2f s\n", cut_s, stopped_s);
  rig->broker().set_reachable("f2", true);
  ASSERT_TRUE(rig->run_for(3.0).ok());
  EXPECT_GT(fastest(*rig), 0.05);
  rig->shutdown();
}

}  // namespace
}  // namespace sen3bot::sim
