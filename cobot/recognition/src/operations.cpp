// The operations file, read with lib/yaml: every error names the file, the key and the line.
#include "sen3bot/cobot/operations.hpp"

#include <fstream>
#include <sstream>
#include <string>

#include "sen3bot/yaml/reader.hpp"

namespace sen3bot::cobot {

namespace {

using yaml::Reader;

// Grids finer than this would not be "coarse": the classifier's input grows with the cells.
constexpr double kMinCellM = 0.05;
constexpr double kMaxCoordinateM = 1e5;  // a site is far smaller; keeps arithmetic finite

// Names and paths: an empty one names nothing.
std::string name_of(const Reader& r, const std::string& key) {
  std::string text = r.text(key);
  if (text.empty()) r.fail(key, "expected a non-empty string");
  return text;
}

GridSpec read_grid(const Reader& r) {
  r.allow_only({"origin", "cell_m", "cols", "rows"});
  GridSpec g;
  const msg::Point2D origin = r.child("origin").point(kMaxCoordinateM);
  g.origin_x_m = origin.x_m;
  g.origin_y_m = origin.y_m;
  g.cell_m = r.number("cell_m", -kMaxCoordinateM, kMaxCoordinateM);
  if (g.cell_m < kMinCellM) r.fail("cell_m", "expected at least 0.05 m");
  g.cols = static_cast<int>(r.integer("cols", 1, static_cast<std::int64_t>(kMaxGridCells)));
  g.rows = static_cast<int>(r.integer("rows", 1, static_cast<std::int64_t>(kMaxGridCells)));
  if (g.cells() > kMaxGridCells)
    r.fail_here("cols x rows is " + std::to_string(g.cells()) + " cells, more than " + std::to_string(kMaxGridCells));
  return g;
}

OperationsConfig read(const Reader& top) {
  OperationsConfig c;
  c.source = top.file();
  top.allow_only({"map", "grid", "stations", "operations", "references"});
  c.map_path = name_of(top, "map");
  c.grid = read_grid(top.child("grid"));

  const std::vector<Reader> stations = top.sequence("stations");
  if (stations.empty()) top.fail("stations", "expected a list of workstations");
  if (stations.size() > kMaxWorkstations)
    top.fail("stations", "more than " + std::to_string(kMaxWorkstations) + " workstations");
  for (const Reader& s : stations) {
    s.allow_only({"name", "position", "radius_m"});
    Workstation w;
    w.name = name_of(s, "name");
    if (c.find_station(w.name) >= 0) s.fail("name", "'" + w.name + "' is already a station");
    w.position = s.child("position").point(kMaxCoordinateM);
    if (s.has("radius_m")) {
      w.radius_m = s.number("radius_m", -kMaxCoordinateM, kMaxCoordinateM);
      if (w.radius_m <= 0) s.fail("radius_m", "expected a positive radius");
    }
    c.stations.push_back(std::move(w));
  }

  const std::vector<Reader> operations = top.sequence("operations");
  if (operations.size() < 2)
    top.fail("operations", "expected a list of at least two operations (one cannot be told from anything)");
  if (operations.size() > kMaxOperations)
    top.fail("operations", "more than " + std::to_string(kMaxOperations) + " operations");
  for (const Reader& o : operations) {
    o.allow_only({"name", "description", "stations"});
    Operation op;
    op.name = name_of(o, "name");
    if (c.find_operation(op.name) >= 0) o.fail("name", "'" + op.name + "' is already an operation");
    if (o.has("description")) op.description = name_of(o, "description");
    const std::vector<Reader> visits = o.sequence("stations");
    if (visits.size() < 2) o.fail("stations", "expected a list of at least two station names");
    if (visits.size() > kMaxVisits) o.fail("stations", "more than " + std::to_string(kMaxVisits) + " visits");
    for (const Reader& v : visits) {
      const std::string name = v.text_here();
      const int station = c.find_station(name);
      if (station < 0) v.fail_here("no station named '" + name + "'");
      if (!op.stations.empty() && op.stations.back() == static_cast<std::size_t>(station))
        v.fail_here("'" + name + "' twice in a row");
      op.stations.push_back(static_cast<std::size_t>(station));
    }
    c.operations.push_back(std::move(op));
  }

  if (top.has("references")) {
    top.child("references").for_each_entry([&](const std::string& name, const Reader& route) {
      const int op = c.find_operation(name);
      if (op < 0) route.fail_here("no operation named '" + name + "'");
      const std::vector<Reader> points = route.sequence_here();
      if (points.size() < 2) route.fail_here("expected a list of at least two [x, y] points");
      if (points.size() > kMaxPathPoints) route.fail_here("more than " + std::to_string(kMaxPathPoints) + " points");
      std::vector<msg::Point2D>& out = c.operations[static_cast<std::size_t>(op)].reference;
      for (const Reader& p : points) out.push_back(p.point(kMaxCoordinateM));
    });
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
  return yaml::parse<OperationsConfig>(text, std::string(source), [](const Reader& top) { return read(top); });
}

Result<OperationsConfig> load_operations(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error::format(Errc::not_found, "%s: cannot open", path.c_str());
  std::ostringstream text;
  text << in.rdbuf();
  Result<OperationsConfig> c = parse_operations(text.str(), path);
  if (c) c->map_path = yaml::relative_to(path, c->map_path);
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
