// The operations file: the shipped one loads and holds what the recognizer and the planner need;
// every mistake is refused naming the key.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <filesystem>
#include <string>
#include <vector>

#include "sen3bot/cobot/operations.hpp"
#include "sen3bot/geometry/point_math.hpp"

namespace sen3bot::cobot {
namespace {

const std::string kShipped = SEN3BOT_SOURCE_DIR "/config/cobot/operations.yaml";


TEST(OperationsFile, ShippedFileLoads) {
  Result<OperationsConfig> c = load_operations(kShipped);
  ASSERT_TRUE(c.ok()) << c.error().c_str();
  EXPECT_GE(c->operations.size(), 5u);
  EXPECT_EQ(c->grid.cols, 16);
  EXPECT_EQ(c->grid.rows, 19);
  EXPECT_DOUBLE_EQ(c->grid.cell_m, 0.5);
  // The map path is resolved against the operations file's folder.
  EXPECT_TRUE(std::filesystem::exists(c->map_path)) << c->map_path;
  // Two operations visit the same stations in opposite orders.
  bool reversed_pair = false;
  for (const Operation& a : c->operations)
    for (const Operation& b : c->operations)
      reversed_pair = reversed_pair || (&a != &b && std::equal(a.stations.begin(), a.stations.end(), b.stations.rbegin(),
                                                               b.stations.rend()));
  EXPECT_TRUE(reversed_pair);
  // Every operation has the robot's route, from its first station to its last.
  for (const Operation& op : c->operations) {
    ASSERT_GE(op.reference.size(), 2u) << op.name;
    EXPECT_LT(geometry::distance(op.reference.front(), c->stations[op.stations.front()].position), 0.01) << op.name;
    EXPECT_LT(geometry::distance(op.reference.back(), c->stations[op.stations.back()].position), 0.01) << op.name;
  }
  EXPECT_EQ(c->find_operation("kitting"), 0);
  EXPECT_EQ(c->find_operation("nothing"), -1);
  EXPECT_GE(c->find_station("bench-north"), 0);
}

TEST(OperationsFile, MissingFileIsNotFound) {
  Result<OperationsConfig> c = load_operations("/nonexistent/operations.yaml");
  ASSERT_FALSE(c.ok());
  EXPECT_EQ(c.error().code(), Errc::not_found);
}

constexpr const char* kMinimal =
    "map: lab.yaml\n"
    "grid: {origin: [0, 0], cell_m: 0.5, cols: 4, rows: 4}\n"
    "stations:\n"
    "  - {name: a, position: [0.5, 0.5]}\n"
    "  - {name: b, position: [1.5, 1.5], radius_m: 0.3}\n"
    "operations:\n"
    "  - {name: ab, stations: [a, b]}\n"
    "  - {name: ba, stations: [b, a]}\n";

TEST(OperationsFile, MinimalFileParses) {
  Result<OperationsConfig> c = parse_operations(kMinimal, "minimal");
  ASSERT_TRUE(c.ok()) << c.error().c_str();
  EXPECT_EQ(c->map_path, "lab.yaml");
  ASSERT_EQ(c->stations.size(), 2u);
  EXPECT_DOUBLE_EQ(c->stations[0].radius_m, 0.4);  // the default
  EXPECT_DOUBLE_EQ(c->stations[1].radius_m, 0.3);
  ASSERT_EQ(c->operations.size(), 2u);
  EXPECT_EQ(c->operations[1].stations, (std::vector<std::size_t>{1, 0}));
  EXPECT_TRUE(c->operations[0].reference.empty());
}

struct Mistake {
  std::string from;     // text in kMinimal
  std::string to;       // what it becomes
  std::string message;  // a part of the error
};

TEST(OperationsFile, MistakesNameTheKey) {
  const std::vector<Mistake> mistakes = {
      {"map: lab.yaml\n", "", "map: missing"},
      {"cell_m: 0.5", "cell_m: 0.01", "grid.cell_m: expected at least 0.05 m"},
      {"cell_m: 0.5", "cell_m: half", "grid.cell_m: expected a number, got 'half'"},
      {"cols: 4", "cols: 0", "grid.cols: value 0 is outside [1, 1024]"},
      {"cols: 4, rows: 4", "cols: 64, rows: 64", "grid: cols x rows is 4096 cells, more than 1024"},
      {"origin: [0, 0]", "origin: [0]", "grid.origin: expected [x, y]"},
      {"map: lab.yaml\n", "map: lab.yaml\nmaps: x\n", "maps: unknown key"},
      {"{name: a, position: [0.5, 0.5]}", "{name: a, place: [0.5, 0.5]}", "stations[0].place: unknown key"},
      {"{name: b, position", "{name: a, position", "stations[1].name: 'a' is already a station"},
      {"radius_m: 0.3", "radius_m: -1", "stations[1].radius_m: expected a positive radius"},
      {"[b, a]", "[b, c]", "operations[1].stations[1]: no station named 'c'"},
      {"[b, a]", "[b, b]", "operations[1].stations[1]: 'b' twice in a row"},
      {"[b, a]", "[b]", "operations[1].stations: expected a list of at least two station names"},
      {"{name: ba", "{name: ab", "operations[1].name: 'ab' is already an operation"},
      {"  - {name: ba, stations: [b, a]}\n", "", "operations: expected a list of at least two operations"},
      {"operations:", "references: {ab: [[0, 0], [1, 1]], zz: [[0, 0], [1, 1]]}\noperations:",
       "references.zz: no operation named 'zz'"},
      {"operations:", "references: {ab: [[0, 0]]}\noperations:", "references.ab: expected a list of at least two"},
      {"operations:", "references: {ab: [[0, 0], [1]]}\noperations:", "references.ab[1]: expected [x, y]"},
  };
  for (const Mistake& m : mistakes) {
    std::string text = kMinimal;
    const std::size_t at = text.find(m.from);
    ASSERT_NE(at, std::string::npos) << m.from;
    text.replace(at, m.from.size(), m.to);
    Result<OperationsConfig> c = parse_operations(text, "ops.yaml");
    ASSERT_FALSE(c.ok()) << "accepted: " << text;
    const std::string error = c.error().c_str();
    EXPECT_EQ(c.error().code(), Errc::config);
    EXPECT_NE(error.find("ops.yaml: "), std::string::npos) << error;
    EXPECT_NE(error.find(m.message), std::string::npos) << "expected '" << m.message << "' in: " << error;
    EXPECT_NE(error.find("(line "), std::string::npos) << error;
  }
}

TEST(OperationsFile, NotYamlOrEmpty) {
  EXPECT_FALSE(parse_operations("", "e").ok());
  Result<OperationsConfig> c = parse_operations("map: [unclosed", "broken.yaml");
  ASSERT_FALSE(c.ok());
  EXPECT_NE(std::string(c.error().c_str()).find("broken.yaml: not valid YAML"), std::string::npos) << c.error().c_str();
  EXPECT_FALSE(parse_operations("- just\n- a list\n", "list").ok());
}

TEST(OperationsFile, EncodingNames) {
  FeatureEncoding e = FeatureEncoding::occupancy;
  EXPECT_TRUE(parse_encoding("occupancy_order", e));
  EXPECT_EQ(e, FeatureEncoding::occupancy_order);
  EXPECT_TRUE(parse_encoding(to_string(FeatureEncoding::occupancy), e));
  EXPECT_EQ(e, FeatureEncoding::occupancy);
  EXPECT_FALSE(parse_encoding("order", e));
}

}  // namespace
}  // namespace sen3bot::cobot
