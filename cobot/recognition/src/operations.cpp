// The operations file. yaml-cpp throws; everything here is caught at the edge and turned into
// an Error that names the file, the key and the line.
#include "sen3bot/cobot/operations.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string>

namespace sen3bot::cobot {

namespace {

// Grids finer than this would not be "coarse": the classifier's input grows with the cells.
constexpr double kMinCellM = 0.05;
constexpr double kMaxCoordinateM = 1e5;  // a site is far smaller; keeps arithmetic finite

struct LoadError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::string where(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  if (mark.line < 0) return "";
  return " (line " + std::to_string(mark.line + 1) + ")";
}

[[noreturn]] void fail(const std::string& key, const std::string& problem, const YAML::Node& at) {
  throw LoadError(key + ": " + problem + where(at));
}

YAML::Node require(const YAML::Node& parent, const std::string& key, const std::string& path) {
  const YAML::Node node = parent[key];
  if (!node.IsDefined() || node.IsNull()) fail(path, "missing", parent);
  return node;
}

void allow_only(const YAML::Node& map, std::initializer_list<const char*> keys, const std::string& path) {
  if (!map.IsMap()) fail(path.empty() ? "(top level)" : path, "expected a mapping of keys", map);
  for (const auto& kv : map) {
    const std::string name = kv.first.Scalar();
    bool known = false;
    std::string list;
    for (const char* k : keys) {
      known = known || name == k;
      list += (list.empty() ? "" : ", ") + std::string(k);
    }
    if (!known) fail(path.empty() ? name : path + "." + name, "unknown key (expected one of: " + list + ")", kv.first);
  }
}

double number(const YAML::Node& node, const std::string& path) {
  if (!node.IsScalar()) fail(path, "expected a number", node);
  try {
    const double v = node.as<double>();
    if (!std::isfinite(v) || std::fabs(v) > kMaxCoordinateM) fail(path, "expected a finite number", node);
    return v;
  } catch (const YAML::Exception&) {
    fail(path, "expected a number, got '" + node.Scalar() + "'", node);
  }
}

int count(const YAML::Node& node, const std::string& path, int lo, int hi) {
  if (!node.IsScalar()) fail(path, "expected an integer", node);
  long long v = 0;
  try {
    v = node.as<long long>();
  } catch (const YAML::Exception&) {
    fail(path, "expected an integer, got '" + node.Scalar() + "'", node);
  }
  if (v < lo || v > hi) fail(path, "expected an integer from " + std::to_string(lo) + " to " + std::to_string(hi), node);
  return static_cast<int>(v);
}

std::string text(const YAML::Node& node, const std::string& path) {
  if (!node.IsScalar() || node.Scalar().empty()) fail(path, "expected a non-empty string", node);
  return node.Scalar();
}

msg::Point2D point(const YAML::Node& node, const std::string& path) {
  if (!node.IsSequence() || node.size() != 2) fail(path, "expected [x, y] in metres", node);
  return {number(node[0], path + "[0]"), number(node[1], path + "[1]")};
}

GridSpec read_grid(const YAML::Node& node) {
  allow_only(node, {"origin", "cell_m", "cols", "rows"}, "grid");
  GridSpec g;
  const msg::Point2D origin = point(require(node, "origin", "grid.origin"), "grid.origin");
  g.origin_x_m = origin.x_m;
  g.origin_y_m = origin.y_m;
  const YAML::Node cell = require(node, "cell_m", "grid.cell_m");
  g.cell_m = number(cell, "grid.cell_m");
  if (g.cell_m < kMinCellM) fail("grid.cell_m", "expected at least 0.05 m", cell);
  g.cols = count(require(node, "cols", "grid.cols"), "grid.cols", 1, static_cast<int>(kMaxGridCells));
  const YAML::Node rows = require(node, "rows", "grid.rows");
  g.rows = count(rows, "grid.rows", 1, static_cast<int>(kMaxGridCells));
  if (g.cells() > kMaxGridCells)
    fail("grid", "cols x rows is " + std::to_string(g.cells()) + " cells, more than " + std::to_string(kMaxGridCells),
         rows);
  return g;
}

std::string resolve(const std::string& file, const std::string& relative) {
  if (relative.empty() || relative.front() == '/') return relative;
  const std::size_t slash = file.find_last_of('/');
  return slash == std::string::npos ? relative : file.substr(0, slash + 1) + relative;
}

OperationsConfig read(const YAML::Node& root, std::string_view source) {
  OperationsConfig c;
  c.source = std::string(source);
  allow_only(root, {"map", "grid", "stations", "operations", "references"}, "");
  c.map_path = text(require(root, "map", "map"), "map");
  c.grid = read_grid(require(root, "grid", "grid"));

  const YAML::Node stations = require(root, "stations", "stations");
  if (!stations.IsSequence() || stations.size() == 0) fail("stations", "expected a list of workstations", stations);
  if (stations.size() > kMaxWorkstations)
    fail("stations", "more than " + std::to_string(kMaxWorkstations) + " workstations", stations);
  for (std::size_t i = 0; i < stations.size(); ++i) {
    const std::string path = "stations[" + std::to_string(i) + "]";
    const YAML::Node s = stations[i];
    allow_only(s, {"name", "position", "radius_m"}, path);
    Workstation w;
    w.name = text(require(s, "name", path + ".name"), path + ".name");
    if (c.find_station(w.name) >= 0) fail(path + ".name", "'" + w.name + "' is already a station", s["name"]);
    w.position = point(require(s, "position", path + ".position"), path + ".position");
    if (s["radius_m"].IsDefined()) {
      w.radius_m = number(s["radius_m"], path + ".radius_m");
      if (w.radius_m <= 0) fail(path + ".radius_m", "expected a positive radius", s["radius_m"]);
    }
    c.stations.push_back(std::move(w));
  }

  const YAML::Node operations = require(root, "operations", "operations");
  if (!operations.IsSequence() || operations.size() < 2)
    fail("operations", "expected a list of at least two operations (one cannot be told from anything)", operations);
  if (operations.size() > kMaxOperations)
    fail("operations", "more than " + std::to_string(kMaxOperations) + " operations", operations);
  for (std::size_t i = 0; i < operations.size(); ++i) {
    const std::string path = "operations[" + std::to_string(i) + "]";
    const YAML::Node o = operations[i];
    allow_only(o, {"name", "description", "stations"}, path);
    Operation op;
    op.name = text(require(o, "name", path + ".name"), path + ".name");
    if (c.find_operation(op.name) >= 0) fail(path + ".name", "'" + op.name + "' is already an operation", o["name"]);
    if (o["description"].IsDefined()) op.description = text(o["description"], path + ".description");
    const YAML::Node visits = require(o, "stations", path + ".stations");
    if (!visits.IsSequence() || visits.size() < 2)
      fail(path + ".stations", "expected a list of at least two station names", visits);
    if (visits.size() > kMaxVisits) fail(path + ".stations", "more than " + std::to_string(kMaxVisits) + " visits", visits);
    for (std::size_t k = 0; k < visits.size(); ++k) {
      const std::string vpath = path + ".stations[" + std::to_string(k) + "]";
      const std::string name = text(visits[k], vpath);
      const int station = c.find_station(name);
      if (station < 0) fail(vpath, "no station named '" + name + "'", visits[k]);
      if (!op.stations.empty() && op.stations.back() == static_cast<std::size_t>(station))
        fail(vpath, "'" + name + "' twice in a row", visits[k]);
      op.stations.push_back(static_cast<std::size_t>(station));
    }
    c.operations.push_back(std::move(op));
  }

  if (const YAML::Node refs = root["references"]; refs.IsDefined() && !refs.IsNull()) {
    if (!refs.IsMap()) fail("references", "expected a mapping from operation names to routes", refs);
    for (const auto& kv : refs) {
      const std::string name = kv.first.Scalar();
      const std::string path = "references." + name;
      const int op = c.find_operation(name);
      if (op < 0) fail(path, "no operation named '" + name + "'", kv.first);
      const YAML::Node route = kv.second;
      if (!route.IsSequence() || route.size() < 2) fail(path, "expected a list of at least two [x, y] points", route);
      if (route.size() > kMaxPathPoints) fail(path, "more than " + std::to_string(kMaxPathPoints) + " points", route);
      std::vector<msg::Point2D>& out = c.operations[static_cast<std::size_t>(op)].reference;
      for (std::size_t k = 0; k < route.size(); ++k) out.push_back(point(route[k], path + "[" + std::to_string(k) + "]"));
    }
  }
  return c;
}

}  // namespace

int OperationsConfig::find_operation(std::string_view name) const noexcept {
  for (std::size_t i = 0; i < operations.size(); ++i)
    if (operations[i].name == name) return static_cast<int>(i);
  return -1;
}

int OperationsConfig::find_station(std::string_view name) const noexcept {
  for (std::size_t i = 0; i < stations.size(); ++i)
    if (stations[i].name == name) return static_cast<int>(i);
  return -1;
}

Result<OperationsConfig> parse_operations(std::string_view text, std::string_view source) {
  try {
    const YAML::Node root = YAML::Load(std::string(text));
    if (!root.IsDefined() || root.IsNull()) return Error::format(Errc::config, "%.*s: empty file", static_cast<int>(source.size()), source.data());
    return read(root, source);
  } catch (const LoadError& e) {
    return Error::format(Errc::config, "%.*s: %s", static_cast<int>(source.size()), source.data(), e.what());
  } catch (const YAML::Exception& e) {
    return Error::format(Errc::config, "%.*s: not YAML: %s", static_cast<int>(source.size()), source.data(), e.what());
  }
}

Result<OperationsConfig> load_operations(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error::format(Errc::not_found, "%s: cannot open", path.c_str());
  std::ostringstream text;
  text << in.rdbuf();
  Result<OperationsConfig> c = parse_operations(text.str(), path);
  if (c) c->map_path = resolve(path, c->map_path);
  return c;
}

const char* to_string(FeatureEncoding encoding) noexcept {
  return encoding == FeatureEncoding::occupancy ? "occupancy" : "occupancy_order";
}

bool parse_encoding(std::string_view text, FeatureEncoding& encoding) noexcept {
  if (text == "occupancy") {
    encoding = FeatureEncoding::occupancy;
    return true;
  }
  if (text == "occupancy_order") {
    encoding = FeatureEncoding::occupancy_order;
    return true;
  }
  return false;
}

}  // namespace sen3bot::cobot
