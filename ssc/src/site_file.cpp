// The site file: YAML, every key checked, every error naming the file and the key.
#include <yaml-cpp/yaml.h>

#include <algorithm>
#include <cmath>
#include <fstream>
#include <sstream>
#include <stdexcept>
#include <string_view>

#include "sen3bot/ssc/site_file.hpp"

namespace sen3bot::ssc {

namespace {

struct SiteError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

class Reader {
 public:
  Reader(YAML::Node node, std::string file, std::string path) : node_(std::move(node)), file_(std::move(file)), path_(std::move(path)) {}
  [[noreturn]] void fail(const std::string& key, const std::string& problem) const {
    const YAML::Mark mark = node_.Mark();
    throw SiteError(file_ + ": " + full(key) + ": " + problem +
                    (mark.line >= 0 ? " (line " + std::to_string(mark.line + 1) + ")" : std::string()));
  }
  void allow_only(std::initializer_list<std::string_view> keys) const {
    if (!node_.IsMap()) fail("", "expected a mapping");
    for (const auto& kv : node_) {
      const std::string name = kv.first.as<std::string>();
      if (std::find(keys.begin(), keys.end(), name) == keys.end()) fail(name, "unknown key");
    }
  }
  [[nodiscard]] bool has(const std::string& key) const { return node_[key].IsDefined() && !node_[key].IsNull(); }
  [[nodiscard]] Reader child(const std::string& key) const {
    if (!has(key)) fail(key, "missing");
    return Reader(node_[key], file_, full(key));
  }
  [[nodiscard]] std::string text(const std::string& key) const {
    if (!has(key) || !node_[key].IsScalar()) fail(key, "missing or not a value");
    return node_[key].Scalar();
  }
  [[nodiscard]] double number(const std::string& key, double lo, double hi) const {
    const std::string t = text(key);
    char* end = nullptr;
    const double v = std::strtod(t.c_str(), &end);
    if (end == t.c_str() || *end != '\0' || !std::isfinite(v)) fail(key, "expected a number, got '" + t + "'");
    if (v < lo || v > hi) fail(key, "out of range [" + std::to_string(lo) + ", " + std::to_string(hi) + "]");
    return v;
  }
  [[nodiscard]] bool boolean(const std::string& key) const {
    const std::string t = text(key);
    if (t == "true") return true;
    if (t == "false") return false;
    fail(key, "expected true or false");
  }
  [[nodiscard]] std::vector<Reader> sequence(const std::string& key) const {
    if (!has(key) || !node_[key].IsSequence()) fail(key, "expected a list");
    std::vector<Reader> out;
    for (std::size_t i = 0; i < node_[key].size(); ++i) out.emplace_back(node_[key][i], file_, full(key) + "[" + std::to_string(i) + "]");
    return out;
  }
  // [x, y] or [x, y, theta_deg]
  [[nodiscard]] std::vector<double> numbers_here(std::size_t min, std::size_t max) const {
    if (!node_.IsSequence() || node_.size() < min || node_.size() > max)
      fail("", "expected a list of " + std::to_string(min) + (min == max ? "" : " to " + std::to_string(max)) + " numbers");
    std::vector<double> out;
    for (std::size_t i = 0; i < node_.size(); ++i) {
      const std::string t = node_[i].Scalar();
      char* end = nullptr;
      const double v = std::strtod(t.c_str(), &end);
      if (end == t.c_str() || *end != '\0' || !std::isfinite(v)) fail("", "expected numbers, got '" + t + "'");
      out.push_back(v);
    }
    return out;
  }
  [[nodiscard]] std::string full(const std::string& key) const {
    if (key.empty()) return path_.empty() ? "(top level)" : path_;
    return path_.empty() ? key : path_ + "." + key;
  }

 private:
  YAML::Node node_;
  std::string file_;
  std::string path_;
};

Pose pose_of(const Reader& r) {
  const std::vector<double> v = r.numbers_here(2, 3);
  return Pose{v[0], v[1], v.size() > 2 ? v[2] * 3.14159265358979323846 / 180.0 : 0.0};
}

SiteFile read(const Reader& top) {
  SiteFile f;
  top.allow_only({"map_id", "version", "interface_name", "robot_manufacturer", "areas", "robots", "centre", "agv_cc"});
  f.service.map_id = top.text("map_id");
  if (top.has("version")) {
    const auto v = vda5050::parse_version(top.text("version"));
    if (!v) top.fail("version", "expected 2.1.0 or 2.0.0");
    f.service.version = *v;
  }
  if (top.has("interface_name")) f.service.interface_name = top.text("interface_name");
  if (top.has("robot_manufacturer")) f.service.robot_manufacturer = top.text("robot_manufacturer");
  for (const Reader& a : top.sequence("areas")) {
    a.allow_only({"name", "type", "outline", "sentries"});
    Area area;
    area.id = static_cast<AreaId>(f.area_names.size());
    const std::string name = a.text("name");
    area.name.assign(name);
    const std::string type = a.text("type");
    if (type == "1.1") {
      area.type = AreaType::blind_intersection;
    } else if (type == "1.2") {
      area.type = AreaType::transition;
    } else if (type == "2") {
      area.type = AreaType::workstation;
    } else if (type == "3") {
      area.type = AreaType::not_monitored;
    } else {
      a.fail("type", "expected \"1.1\", \"1.2\", \"2\" or \"3\", got '" + type + "'");
    }
    for (const Reader& p : a.sequence("outline")) {
      const std::vector<double> v = p.numbers_here(2, 2);
      if (!area.outline.push_back(Point{v[0], v[1]})) a.fail("outline", "at most " + std::to_string(kMaxVertices) + " vertices");
    }
    if (a.has("sentries"))
      for (const Reader& p : a.sequence("sentries"))
        if (!area.sentries.push_back(pose_of(p))) a.fail("sentries", "at most " + std::to_string(kMaxSentryPoses) + " poses");
    for (const std::string& other : f.area_names)
      if (other == name) a.fail("name", "'" + name + "' is used twice");
    if (!f.site.areas.push_back(area)) top.fail("areas", "at most " + std::to_string(kMaxAreas) + " areas");
    f.area_names.push_back(name);
  }
  for (const Reader& r : top.sequence("robots")) {
    r.allow_only({"serial", "home", "overlooks"});
    RobotHome home;
    home.robot = static_cast<RobotId>(f.robot_serials.size());
    const std::string serial = r.text("serial");
    home.name.assign(serial);
    home.pose = pose_of(r.child("home"));
    if (r.has("overlooks")) {
      const std::string area = r.text("overlooks");
      const auto it = std::find(f.area_names.begin(), f.area_names.end(), area);
      if (it == f.area_names.end()) r.fail("overlooks", "no area named '" + area + "'");
      home.overlooks = static_cast<AreaId>(it - f.area_names.begin());
    }
    for (const std::string& other : f.robot_serials)
      if (other == serial) r.fail("serial", "'" + serial + "' is used twice");
    if (!f.site.robots.push_back(home)) top.fail("robots", "at most " + std::to_string(kMaxRobots) + " robots");
    f.robot_serials.push_back(serial);
  }
  if (top.has("centre")) {
    const Reader c = top.child("centre");
    c.allow_only({"slow_distance_m", "stop_distance_m", "slow_speed_factor", "low_battery_pct", "charged_pct",
                  "dynamic_distance_m", "people_gate_m", "people_timeout_s"});
    CentreConfig& cc = f.centre;
    if (c.has("slow_distance_m")) cc.slow_distance = c.number("slow_distance_m", 0, 1000);
    if (c.has("stop_distance_m")) cc.stop_distance = c.number("stop_distance_m", 0, 1000);
    if (c.has("slow_speed_factor")) cc.slow_speed_factor = c.number("slow_speed_factor", 0, 1);
    if (c.has("low_battery_pct")) cc.standing.low_battery = c.number("low_battery_pct", 0, 100);
    if (c.has("charged_pct")) cc.standing.charged = c.number("charged_pct", 0, 100);
    if (c.has("dynamic_distance_m")) cc.people.dynamic_distance = c.number("dynamic_distance_m", 0.05, 100);
    if (c.has("people_gate_m")) cc.people.gate = c.number("people_gate_m", 0.05, 10);
    if (c.has("people_timeout_s")) cc.people.timeout = static_cast<hal::Nanos>(c.number("people_timeout_s", 0.1, 600) * 1e9);
    if (cc.stop_distance > cc.slow_distance) c.fail("stop_distance_m", "must not exceed slow_distance_m");
  }
  if (top.has("agv_cc")) {
    const Reader a = top.child("agv_cc");
    a.allow_only({"direct_pause", "advisory_repeat_s"});
    if (a.has("direct_pause")) f.service.direct_pause = a.boolean("direct_pause");
    if (a.has("advisory_repeat_s")) f.service.advisory_repeat_s = a.number("advisory_repeat_s", 0.1, 3600);
  }
  if (Status s = f.site.validate(); !s) top.fail("", s.error().c_str());
  return f;
}

}  // namespace

Result<SiteFile> parse_site(const std::string& yaml_text, const std::string& source_name) {
  try {
    const YAML::Node root = YAML::Load(yaml_text);
    return read(Reader(root, source_name, ""));
  } catch (const SiteError& e) {
    return Error(Errc::config, e.what());
  } catch (const YAML::Exception& e) {
    return Error::format(Errc::config, "%s: %s", source_name.c_str(), e.what());
  }
}

Result<SiteFile> load_site(const std::string& path) {
  std::ifstream in(path);
  if (!in) return Error::format(Errc::not_found, "%s: cannot open the site file", path.c_str());
  std::stringstream text;
  text << in.rdbuf();
  return parse_site(text.str(), path);
}

}  // namespace sen3bot::ssc
