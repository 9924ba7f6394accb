// The kidnapped robot through the whole firmware, in lockstep: on its way back from (4, 7) m the
// simulated robot is carried into the lower work area without its odometry knowing. The
// firmware must notice (the likelihood drops), stand still while it relocalises by random-particle
// injection, and still reach its goal; the referee times the relocalisation from the truth.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
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

std::string field(const std::string& json, const std::string& key) {
  const std::size_t at = json.find("\"" + key + "\": ");
  if (at == std::string::npos) return {};
  const std::size_t begin = at + key.size() + 4;
  return json.substr(begin, json.find_first_of(",}", begin) - begin);
}

struct KidnapRun {
  int code = -1;
  std::string json;
};

// The shipped sim.yaml, with the maps at absolute paths and `recovery_line` in place of its
// recovery line.
KidnapRun run_kidnapped(const std::string& recovery_line) {
  char dir_template[] = "/tmp/sen3bot-kidnapped-XXXXXX";
  if (::mkdtemp(dir_template) == nullptr) return {};
  const std::string dir = dir_template;
  std::string yaml = read_file(SEN3BOT_SOURCE_DIR "/config/sim.yaml");
  for (std::size_t at = yaml.find(" maps/"); at != std::string::npos; at = yaml.find(" maps/", at + 1))
    yaml.replace(at + 1, 5, SEN3BOT_SOURCE_DIR "/config/maps/");
  const std::size_t line = yaml.find("  recovery:");
  EXPECT_NE(line, std::string::npos) << "config/sim.yaml has no navigation.recovery line";
  if (line == std::string::npos) return {};
  yaml.replace(line, yaml.find('\n', line) - line, recovery_line);
  std::string config = dir + "/sim.yaml";
  std::ofstream(config) << yaml;
  std::string report = dir;
  std::vector<char*> argv = {const_cast<char*>("--scenario"), const_cast<char*>("kidnapped"),
                             const_cast<char*>("--config"), config.data(),
                             const_cast<char*>("--report"), report.data()};
  std::FILE* out = std::tmpfile();
  std::FILE* err = std::tmpfile();
  KidnapRun run;
  run.code = sim_command(static_cast<int>(argv.size()), argv.data(), out, err);
  std::fclose(out);
  std::fclose(err);
  run.json = read_file(dir + "/report.json");
  return run;
}

TEST(Kidnapped, RelocalisesAndReachesTheGoal) {
  const KidnapRun run = run_kidnapped("  recovery: { alpha_slow: 0.001, alpha_fast: 0.1 }");
  ASSERT_FALSE(run.json.empty());
  EXPECT_EQ(run.code, 0) << "not reached, or a collision";
  EXPECT_EQ(field(run.json, "reached"), "true");
  EXPECT_EQ(field(run.json, "collisions"), "0");
  const std::string relocalization = field(run.json, "relocalization_s");
  ASSERT_FALSE(relocalization.empty()) << "the report has no relocalization_s";
  ASSERT_NE(relocalization, "null") << "never back within 0.3 m and 10 degrees of the truth";
  const double seconds = std::strtod(relocalization.c_str(), nullptr);
  std::printf("relocalization_s %.2f\n", seconds);
  EXPECT_GT(seconds, 0.0);
  // Seed 1 takes 2.2 s, seeds 2, 4 and 5 3.2-7.0 s: the first update after the jump fits badly,
  // then every scan (5 per second) updates until an injected particle near the truth wins.
  // Beyond 10 s the robot has driven up to 5 m on a belief from the wrong room, which is what
  // this test is to catch.
  EXPECT_LT(seconds, 10.0);
}

// The shipped configuration leaves recovery off; the scenario turns it on for itself.
TEST(Kidnapped, TheScenarioTurnsRecoveryOnWhenTheConfigurationLeavesItOff) {
  const KidnapRun run = run_kidnapped("  recovery: { alpha_slow: 0, alpha_fast: 0 }");
  ASSERT_FALSE(run.json.empty());
  EXPECT_EQ(run.code, 0);
  EXPECT_NE(field(run.json, "relocalization_s"), "null");
}

}  // namespace
}  // namespace sen3bot::sim
