#pragma once
// Reads Moving AI .map/.scen files (format notes in tests/data/movingai/README.md) into a
// costmap: blocked cells 254, passable 0; row = the file's y (top row 0).
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "sen3bot/nav/costmap.hpp"
#include "sen3bot/nav/global_planner.hpp"

namespace sen3bot::nav::testing {

struct MovingAiMap {
  int width = 0;
  int height = 0;
  std::vector<std::string> rows;
};

struct MovingAiScenario {
  GridCell start;
  GridCell goal;
  double optimal = 0.0;
};

inline bool load_movingai_map(const std::string& path, MovingAiMap& out) {
  std::ifstream in(path);
  std::string word;
  while (in >> word && word != "map") {
    if (word == "height") in >> out.height;
    if (word == "width") in >> out.width;
    if (word == "type") in >> word;
  }
  std::string row;
  std::getline(in, row);
  while (static_cast<int>(out.rows.size()) < out.height && std::getline(in, row)) out.rows.push_back(row);
  return out.width > 0 && static_cast<int>(out.rows.size()) == out.height;
}

inline std::vector<MovingAiScenario> load_movingai_scen(const std::string& path) {
  std::vector<MovingAiScenario> out;
  std::ifstream in(path);
  std::string line;
  std::getline(in, line);  // version
  while (std::getline(in, line)) {
    std::istringstream fields(line);
    int bucket = 0;
    std::string map;
    int w = 0;
    int h = 0;
    MovingAiScenario s;
    if (fields >> bucket >> map >> w >> h >> s.start.col >> s.start.row >> s.goal.col >> s.goal.row >> s.optimal) {
      out.push_back(s);
    }
  }
  return out;
}

inline void fill_costmap(const MovingAiMap& map, Costmap2D& costmap) {
  for (int r = 0; r < map.height; ++r) {
    for (int c = 0; c < map.width; ++c) {
      const char ch = map.rows[static_cast<std::size_t>(r)][static_cast<std::size_t>(c)];
      costmap.set(c, r, (ch == '.' || ch == 'G' || ch == 'S') ? kFreeCost : kLethalCost);
    }
  }
}

}  // namespace sen3bot::nav::testing
