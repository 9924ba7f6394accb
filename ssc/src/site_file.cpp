// The site file: YAML, every key checked, every error naming the file and the key (lib/yaml).
#include <algorithm>
#include <fstream>
#include <numbers>
#include <sstream>
#include <string_view>

#include "sen3bot/ssc/site_file.hpp"
#include "sen3bot/yaml/reader.hpp"

namespace sen3bot::ssc {

namespace {

using yaml::Reader;

Pose pose_of(const Reader& r) {
  const std::vector<double> v = r.numbers_here("[x, y] or [x, y, theta_deg]", 2, 3);
  return Pose{v[0], v[1], v.size() > 2 ? v[2] * std::numbers::pi / 180.0 : 0.0};
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
    constexpr AreaType kTypes[] = {AreaType::blind_intersection, AreaType::transition, AreaType::workstation,
                                   AreaType::not_monitored};
    area.type = kTypes[a.choice("type", {"1.1", "1.2", "2", "3"})];
    for (const Reader& p : a.sequence("outline")) {
      if (!area.outline.push_back(p.point())) a.fail("outline", "at most " + std::to_string(kMaxVertices) + " vertices");
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
  if (Status s = f.site.validate(); !s) top.fail_here(s.error().c_str());
  return f;
}

}  // namespace

Result<SiteFile> parse_site(const std::string& yaml_text, const std::string& source_name) {
  return yaml::parse<SiteFile>(yaml_text, source_name, [](const Reader& top) { return read(top); });
}

Result<SiteFile> load_site(const std::string& path) {
  std::ifstream in(path);
  if (!in) return Error::format(Errc::not_found, "%s: cannot open the site file", path.c_str());
  std::stringstream text;
  text << in.rdbuf();
  return parse_site(text.str(), path);
}

}  // namespace sen3bot::ssc
