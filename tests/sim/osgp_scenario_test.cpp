// The online-SGP cases through the whole firmware, lockstep: the simulated detector sends the
// people's boxes over the detector channel, the people task places and cages them, and the
// planner's trigger decides. A person beside the safe path re-plans once and is passed outside
// their cage; a person far away is caged and never re-plans; a box where the person stood is
// passed by the local planner alone.
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

// The value of key in the case object that starts at `"name": "NAME"`.
std::string case_field(const std::string& json, const std::string& name, const std::string& key) {
  const std::size_t from = json.find("\"name\": \"" + name + "\"");
  if (from == std::string::npos) return {};
  const std::size_t at = json.find("\"" + key + "\": ", from);
  if (at == std::string::npos) return {};
  const std::size_t begin = at + key.size() + 4;
  return json.substr(begin, json.find_first_of(",}", begin) - begin);
}

struct ScenarioRun {
  int code = -1;
  std::string json;
};

ScenarioRun run_osgp(int seed) {
  char dir_template[] = "/tmp/sen3bot-osgp-XXXXXX";
  if (::mkdtemp(dir_template) == nullptr) return {};
  std::string report = dir_template;
  std::string config = SEN3BOT_SOURCE_DIR "/config/sim.yaml";
  std::string seed_text = std::to_string(seed);
  std::vector<char*> argv = {const_cast<char*>("--scenario"), const_cast<char*>("osgp"),
                             const_cast<char*>("--config"),   config.data(),
                             const_cast<char*>("--seed"),     seed_text.data(),
                             const_cast<char*>("--report"),   report.data()};
  std::FILE* out = std::tmpfile();
  std::FILE* err = std::tmpfile();
  ScenarioRun run;
  run.code = sim_command(static_cast<int>(argv.size()), argv.data(), out, err);
  std::fclose(out);
  std::fclose(err);
  run.json = read_file(report + "/report.json");
  return run;
}

TEST(OsgpScenario, TheSourcesThreeCases) {
  for (const int seed : {1, 2, 3}) {
    const ScenarioRun run = run_osgp(seed);
    ASSERT_FALSE(run.json.empty()) << "seed " << seed;
    EXPECT_EQ(run.code, 0) << "seed " << seed << ": a goal missed, a contact or a cage entered";
    for (const char* name : {"person-on-path", "person-far", "box-on-path"}) {
      EXPECT_EQ(case_field(run.json, name, "reached"), "true") << name << ", seed " << seed;
      EXPECT_EQ(case_field(run.json, name, "collisions"), "0") << name << ", seed " << seed;
      EXPECT_EQ(case_field(run.json, name, "cage_entries"), "0") << name << ", seed " << seed;
      std::printf("seed %d %-15s replans %s, closest person %s m, %s s\n", seed, name,
                  case_field(run.json, name, "replans_triggered").c_str(),
                  case_field(run.json, name, "min_person_distance_m").c_str(),
                  case_field(run.json, name, "time_s").c_str());
    }
    // The person pushed the robot off its safe path: re-planned from where it was.
    EXPECT_GE(std::atoi(case_field(run.json, "person-on-path", "replans_triggered").c_str()), 1) << seed;
    EXPECT_NE(case_field(run.json, "person-on-path", "person_boxes_located"), "0") << seed;
    // Caged, but no reason to re-plan.
    EXPECT_EQ(case_field(run.json, "person-far", "replans_triggered"), "0") << seed;
    EXPECT_NE(case_field(run.json, "person-far", "person_boxes_located"), "0") << seed;
    // An obstacle is not a person.
    EXPECT_EQ(case_field(run.json, "box-on-path", "replans_triggered"), "0") << seed;
  }
}

}  // namespace
}  // namespace sen3bot::sim
