// The thesis' three supervised-planning cases through the whole firmware: the real P2OS and
// LMS200 drivers against their wire-exact emulators, localization, the global planner with
// waypoint attraction following the supervisory planner's waypoints, the DWA and the safety
// filter, in lockstep simulated time. Each case must reach (2.5, 2) m from (4, 7) m without
// touching anything while moving.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "sim_commands.hpp"

namespace sen3bot::firmware {
namespace {

struct CaseLine {
  std::string name;
  bool reached = false;
  long collisions = -1;
  double time_s = 0;
};

// The report writes one object per case on its own line: pick out the fields we assert on.
std::vector<CaseLine> parse_cases(const std::string& json) {
  std::vector<CaseLine> cases;
  std::istringstream in(json);
  std::string line;
  const auto field = [](const std::string& l, const std::string& key) -> std::string {
    const std::size_t at = l.find("\"" + key + "\": ");
    if (at == std::string::npos) return {};
    const std::size_t begin = at + key.size() + 4;
    const std::size_t end = l.find_first_of(",}", begin);
    return l.substr(begin, end - begin);
  };
  while (std::getline(in, line)) {
    if (line.find("\"reached\"") == std::string::npos) continue;
    CaseLine c;
    c.name = field(line, "name");
    c.reached = field(line, "reached") == "true";
    c.collisions = std::strtol(field(line, "collisions").c_str(), nullptr, 10);
    c.time_s = std::strtod(field(line, "time_s").c_str(), nullptr);
    cases.push_back(c);
  }
  return cases;
}

TEST(ThesisCases, AllThreeReachTheGoalWithoutCollision) {
  char dir_template[] = "/tmp/sen3bot-thesis-XXXXXX";
  ASSERT_NE(::mkdtemp(dir_template), nullptr);
  const std::string dir = dir_template;
  std::string config = SEN3BOT_SOURCE_DIR "/config/sim.yaml";
  std::string report = dir;
  std::vector<char*> argv = {const_cast<char*>("--scenario"), const_cast<char*>("thesis-sgp"),
                             const_cast<char*>("--config"), config.data(),
                             const_cast<char*>("--report"), report.data()};
  std::FILE* out = std::tmpfile();
  std::FILE* err = std::tmpfile();
  const int code = sim::sim_command(static_cast<int>(argv.size()), argv.data(), out, err);
  std::fclose(out);
  std::fclose(err);
  EXPECT_EQ(code, 0) << "a case was not reached or collided (sen3bot-sim sim exits 3 then)";

  std::ifstream file(dir + "/report.json");
  ASSERT_TRUE(file.good());
  std::stringstream text;
  text << file.rdbuf();
  const std::vector<CaseLine> cases = parse_cases(text.str());
  ASSERT_EQ(cases.size(), 3u);
  // Each case's waypoints came from the supervisory planner, which reached the lab's safe curve
  // where it passes closest to the goal.
  std::size_t from_sgp = 0;
  for (std::size_t at = 0; (at = text.str().find("\"safe_path\": {\"source\": \"sgp\", \"runs\": 1, \"stop\": \"nearest_to_goal\"", at)) != std::string::npos; ++at)
    ++from_sgp;
  EXPECT_EQ(from_sgp, 3u) << text.str();
  EXPECT_EQ(cases[0].name, "\"no-obstacle\"");
  EXPECT_EQ(cases[1].name, "\"obstacle-before-planning\"");
  EXPECT_EQ(cases[2].name, "\"obstacle-during-motion\"");
  for (const CaseLine& c : cases) {
    EXPECT_TRUE(c.reached) << c.name;
    EXPECT_EQ(c.collisions, 0) << c.name;
    EXPECT_GT(c.time_s, 5.0) << c.name;   // 5.3 m of route at 0.5 m/s at best
    EXPECT_LT(c.time_s, 40.0) << c.name;  // no long detours or recovery loops
  }
  for (const char* name : {"report.json", "no-obstacle.png", "obstacle-before-planning.png", "obstacle-during-motion.png"})
    std::remove((dir + "/" + name).c_str());
  ::rmdir(dir.c_str());
}

}  // namespace
}  // namespace sen3bot::firmware
