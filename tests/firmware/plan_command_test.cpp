// `sen3bot plan`: lengths on the bare occupancy grid equal the Moving AI benchmark optima, the
// output is one JSON object, and bad command lines are rejected with exit status 2.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cstdio>
#include <cstdlib>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "command_capture.hpp"
#include "commands.hpp"

namespace sen3bot::firmware {
namespace {

using Outcome = testing::CommandOutcome;

Outcome plan(std::vector<std::string> args) { return testing::run_command(plan_command, std::move(args)); }

double number_field(const std::string& json, const std::string& key) {
  const std::size_t at = json.find("\"" + key + "\": ");
  if (at == std::string::npos) return -1.0;
  return std::strtod(json.c_str() + at + key.size() + 4, nullptr);
}

// A Moving AI map as a map_server PGM + YAML at 1 m per cell, origin (0, 0): Moving AI cell
// (x, y) (y down from the top) is then the point (x + 0.5, height - y - 0.5) m.
struct ConvertedMap {
  std::string dir;
  std::string yaml;
  int width = 0;
  int height = 0;
  ~ConvertedMap() {
    std::remove((dir + "/map.pgm").c_str());
    std::remove(yaml.c_str());
    ::rmdir(dir.c_str());
  }
};

bool convert(const std::string& movingai_path, ConvertedMap& out) {
  std::ifstream in(movingai_path);
  std::string word;
  while (in >> word && word != "map") {
    if (word == "height") in >> out.height;
    if (word == "width") in >> out.width;
    if (word == "type") in >> word;
  }
  std::string row;
  std::getline(in, row);
  std::vector<std::string> rows;
  while (static_cast<int>(rows.size()) < out.height && std::getline(in, row)) rows.push_back(row);
  if (out.width <= 0 || static_cast<int>(rows.size()) != out.height) return false;
  char dir_template[] = "/tmp/sen3bot-plan-XXXXXX";
  if (::mkdtemp(dir_template) == nullptr) return false;
  out.dir = dir_template;
  std::ofstream pgm(out.dir + "/map.pgm", std::ios::binary);
  pgm << "P5\n" << out.width << " " << out.height << "\n255\n";
  for (const std::string& r : rows)
    for (int c = 0; c < out.width; ++c) {
      const char ch = r[static_cast<std::size_t>(c)];
      pgm.put(static_cast<char>((ch == '.' || ch == 'G' || ch == 'S') ? 254 : 0));
    }
  out.yaml = out.dir + "/map.yaml";
  std::ofstream yaml(out.yaml);
  yaml << "image: map.pgm\nresolution: 1.0\norigin: [0.0, 0.0, 0.0]\noccupied_thresh: 0.65\nfree_thresh: 0.25\nnegate: 0\n";
  return pgm.good() && yaml.good();
}

std::string point(const ConvertedMap& m, int x, int y) {
  char text[64];
  std::snprintf(text, sizeof text, "%.1f,%.1f", x + 0.5, m.height - y - 0.5);
  return text;
}

TEST(PlanCommand, UnitCostLengthsEqualMovingAiOptima) {
  for (const char* name : {"random-32-32-10.map", "maze-32-32-2.map", "warehouse-64-32.map"}) {
    ConvertedMap m;
    ASSERT_TRUE(convert(std::string(SEN3BOT_SOURCE_DIR "/tests/data/movingai/") + name, m)) << name;
    std::ifstream scen(std::string(SEN3BOT_SOURCE_DIR "/tests/data/movingai/") + name + ".scen");
    std::string line;
    std::getline(scen, line);  // version
    int checked = 0;
    while (std::getline(scen, line) && checked < 8) {
      std::istringstream fields(line);
      int bucket = 0, w = 0, h = 0, sx = 0, sy = 0, gx = 0, gy = 0;
      std::string map;
      double optimal = 0;
      if (!(fields >> bucket >> map >> w >> h >> sx >> sy >> gx >> gy >> optimal)) continue;
      const Outcome o = plan({"--map", m.yaml, "--start", point(m, sx, sy), "--goal", point(m, gx, gy), "--unit-cost"});
      ASSERT_EQ(o.code, 0) << name << ": " << line << "\n" << o.err;
      EXPECT_NEAR(number_field(o.out, "length_m"), optimal, 1e-3) << name << ": " << line;
      EXPECT_GE(number_field(o.out, "expansions"), 1.0);
      EXPECT_GE(number_field(o.out, "time_ms"), 0.0);
      EXPECT_EQ(o.out.front(), '{');
      EXPECT_EQ(o.out.substr(o.out.size() - 3), "]}\n");
      ++checked;
    }
    EXPECT_EQ(checked, 8) << name;
  }
}

TEST(PlanCommand, LabMapWithWaypointsAndInflation) {
  const std::string lab = SEN3BOT_SOURCE_DIR "/config/maps/lab.yaml";
  const Outcome o = plan({"--map", lab, "--start", "4,7", "--goal", "2.5,2", "--waypoints",
                          SEN3BOT_SOURCE_DIR "/config/maps/lab_waypoints_thesis.txt"});
  ASSERT_EQ(o.code, 0) << o.err;
  EXPECT_GT(number_field(o.out, "length_m"), 5.0);
  EXPECT_LT(number_field(o.out, "length_m"), 7.0);
  EXPECT_NE(o.out.find("\"path\": [[4.025, 7.025], "), std::string::npos) << o.out.substr(0, 200);
  const Outcome bare = plan({"--map", lab, "--start", "4,7", "--goal", "2.5,2", "--unit-cost"});
  ASSERT_EQ(bare.code, 0) << bare.err;
  EXPECT_LE(number_field(bare.out, "length_m"), number_field(o.out, "length_m"));
}

TEST(PlanCommand, RejectsBadArguments) {
  const std::string lab = SEN3BOT_SOURCE_DIR "/config/maps/lab.yaml";
  EXPECT_EQ(plan({}).code, 2);
  EXPECT_EQ(plan({"--map", lab, "--start", "4,7"}).code, 2);                             // no goal
  EXPECT_EQ(plan({"--map", lab, "--start", "4,7", "--goal"}).code, 2);                   // incomplete
  EXPECT_EQ(plan({"--map", lab, "--start", "4;7", "--goal", "2.5,2"}).code, 2);          // bad point
  EXPECT_EQ(plan({"--map", lab, "--start", "4,7,1", "--goal", "2.5,2"}).code, 2);
  EXPECT_EQ(plan({"--map", lab, "--start", "nan,7", "--goal", "2.5,2"}).code, 2);
  EXPECT_EQ(plan({"--map", lab, "--start", "4,7", "--goal", "2.5,2", "--fast"}).code, 2);  // unknown option
  EXPECT_EQ(plan({"--map", "/nonexistent/map.yaml", "--start", "4,7", "--goal", "2.5,2"}).code, 2);
  EXPECT_EQ(plan({"--map", lab, "--start", "4,7", "--goal", "2.5,2", "--waypoints", "/nonexistent.txt"}).code, 2);
  Outcome o = plan({"--map", lab, "--start", "40,7", "--goal", "2.5,2"});                 // off the map
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("start outside"), std::string::npos) << o.err;
  o = plan({"--map", lab, "--start", "0.02,0.02", "--goal", "2.5,2", "--unit-cost"});      // in the outer wall
  EXPECT_EQ(o.code, 2);
  EXPECT_NE(o.err.find("blocked"), std::string::npos) << o.err;
}

}  // namespace
}  // namespace sen3bot::firmware
