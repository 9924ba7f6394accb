#include "config.hpp"

#include <yaml-cpp/yaml.h>

#include "sen3bot/mem/byte_size.hpp"

#include <cctype>
#include <climits>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <initializer_list>
#include <numbers>
#include <sstream>
#include <stdexcept>
#include <vector>

namespace sen3bot::firmware {

namespace {

// Thrown inside the loader only; load_config() turns it into an Error.
struct ConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::string where(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  if (mark.line < 0) return "";
  return " (line " + std::to_string(mark.line + 1) + ", column " + std::to_string(mark.column + 1) + ")";
}

// A node plus its dotted key path, so every message can say exactly which key is wrong.
class Reader {
 public:
  Reader(YAML::Node node, std::string file, std::string path)
      : node_(std::move(node)), file_(std::move(file)), path_(std::move(path)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& problem, const YAML::Node& at) const {
    throw ConfigError(file_ + ": " + full(key) + ": " + problem + where(at));
  }
  [[noreturn]] void fail_here(const std::string& problem) const {
    throw ConfigError(file_ + ": " + (path_.empty() ? std::string("(top level)") : path_) + ": " + problem + where(node_));
  }

  [[nodiscard]] bool has(const std::string& key) const { return node_[key].IsDefined() && !node_[key].IsNull(); }

  void require_map() const {
    if (!node_.IsMap()) fail_here("expected a mapping of keys");
  }

  // Unknown keys are errors: a misspelt key must not silently fall back to a default.
  void allow_only(std::initializer_list<std::string_view> keys) const {
    require_map();
    for (const auto& kv : node_) {
      const std::string name = kv.first.as<std::string>();
      bool known = false;
      for (std::string_view k : keys) known = known || k == name;
      if (!known) {
        std::string list;
        for (std::string_view k : keys) list += (list.empty() ? "" : ", ") + std::string(k);
        fail(name, "unknown key (expected one of: " + list + ")", kv.first);
      }
    }
  }

  [[nodiscard]] Reader child(const std::string& key) const {
    const YAML::Node n = node_[key];
    if (!n.IsDefined() || n.IsNull()) fail(key, "missing", node_);
    return Reader(n, file_, full(key));
  }

  [[nodiscard]] std::string text(const std::string& key) const {
    const YAML::Node n = scalar(key);
    return n.Scalar();
  }

  [[nodiscard]] std::int64_t integer(const std::string& key, std::int64_t min, std::int64_t max) const {
    const YAML::Node n = scalar(key);
    std::int64_t v = 0;
    if (!YAML::convert<std::int64_t>::decode(n, v))
      fail(key, "expected an integer, got '" + n.Scalar() + "'", n);
    if (v < min || v > max)
      fail(key, "value " + std::to_string(v) + " is outside [" + std::to_string(min) + ", " + std::to_string(max) + "]", n);
    return v;
  }

  [[nodiscard]] double number(const std::string& key, double min, double max) const {
    const YAML::Node n = scalar(key);
    double v = 0;
    if (!YAML::convert<double>::decode(n, v) || !std::isfinite(v))
      fail(key, "expected a number, got '" + n.Scalar() + "'", n);
    if (v < min || v > max) {
      std::ostringstream msg;
      msg << "value " << v << " is outside [" << min << ", " << max << "]";
      fail(key, msg.str(), n);
    }
    return v;
  }

  [[nodiscard]] bool boolean(const std::string& key) const {
    const YAML::Node n = scalar(key);
    bool v = false;
    if (!YAML::convert<bool>::decode(n, v)) fail(key, "expected true or false, got '" + n.Scalar() + "'", n);
    return v;
  }

  [[nodiscard]] std::size_t bytes(const std::string& key) const {
    const YAML::Node n = scalar(key);
    Result<std::size_t> r = mem::parse_byte_size(n.Scalar());
    if (!r) fail(key, std::string(r.error().message()), n);
    return *r;
  }

  // Elements of a sequence under `key`, each as a Reader named key[i].
  [[nodiscard]] std::vector<Reader> sequence(const std::string& key) const {
    const YAML::Node n = node_[key];
    if (!n.IsDefined() || n.IsNull()) fail(key, "missing", node_);
    if (!n.IsSequence()) fail(key, "expected a list", n);
    std::vector<Reader> items;
    for (std::size_t i = 0; i < n.size(); ++i)
      items.emplace_back(n[i], file_, full(key) + "[" + std::to_string(i) + "]");
    return items;
  }

  // This node as a list of two numbers [x, y].
  [[nodiscard]] nav::Point2D point() const {
    if (!node_.IsSequence() || node_.size() != 2) fail_here("expected a point [x_m, y_m]");
    double v[2];
    for (std::size_t i = 0; i < 2; ++i)
      if (!YAML::convert<double>::decode(node_[i], v[i]) || !std::isfinite(v[i])) fail_here("expected two numbers");
    return {v[0], v[1]};
  }

  [[nodiscard]] const std::string& file() const { return file_; }

  template <typename F>
  void for_each_entry(F&& f) const {
    require_map();
    for (const auto& kv : node_) {
      const std::string name = kv.first.as<std::string>();
      f(name, Reader(kv.second, file_, full(name)));
    }
  }

 private:
  [[nodiscard]] std::string full(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  [[nodiscard]] YAML::Node scalar(const std::string& key) const {
    const YAML::Node n = node_[key];
    if (!n.IsDefined() || n.IsNull()) fail(key, "missing", node_);
    if (!n.IsScalar()) fail(key, "expected a single value", n);
    return n;
  }

  YAML::Node node_;
  std::string file_;
  std::string path_;
};

// {x_m, y_m, theta_deg}; a missing key is 0.
nav::Pose2D read_pose(const Reader& r) {
  r.allow_only({"x_m", "y_m", "theta_deg"});
  nav::Pose2D p;
  if (r.has("x_m")) p.x_m = r.number("x_m", -1e4, 1e4);
  if (r.has("y_m")) p.y_m = r.number("y_m", -1e4, 1e4);
  if (r.has("theta_deg")) p.theta_rad = r.number("theta_deg", -360.0, 360.0) * std::numbers::pi / 180.0;
  return p;
}

// A path relative to the configuration file's folder, as ROS map YAMLs do for their image.
std::string relative_to(const std::string& file, const std::string& path) {
  if (path.empty() || path.front() == '/') return path;
  const std::size_t slash = file.find_last_of('/');
  return slash == std::string::npos ? path : file.substr(0, slash + 1) + path;
}

std::int64_t millis(const Reader& r, const std::string& key, std::int64_t min_ms, std::int64_t max_ms) {
  return static_cast<std::int64_t>(std::llround(r.number(key, static_cast<double>(min_ms) / 1000.0,
                                                          static_cast<double>(max_ms) / 1000.0) * 1000.0));
}

world::MoverScript read_mover(const Reader& r, bool person) {
  r.allow_only({"path", "speed_m_s", "size_m", "loop", "start_s", "appear_s", "shape"});
  world::MoverScript m;
  m.person = person;
  m.shape = person ? world::MoverShape::circle : world::MoverShape::square;
  for (const Reader& point : r.sequence("path")) m.path.push_back(point.point());
  if (m.path.empty()) r.fail("path", "needs at least one point", YAML::Node());
  if (r.has("speed_m_s")) m.speed_m_s = r.number("speed_m_s", 0.0, 5.0);
  if (r.has("size_m")) m.size_m = r.number("size_m", 0.05, 5.0);
  if (r.has("loop")) m.loop = r.boolean("loop");
  if (r.has("start_s")) m.start_time_s = r.number("start_s", 0.0, 1e7);
  if (r.has("appear_s")) m.appear_time_s = r.number("appear_s", 0.0, 1e7);
  if (r.has("shape")) {
    const std::string shape = r.text("shape");
    if (shape == "circle") m.shape = world::MoverShape::circle;
    else if (shape == "square") m.shape = world::MoverShape::square;
    else r.fail("shape", "expected circle or square, got '" + shape + "'", YAML::Node());
  }
  return m;
}

void read_sim(const Reader& r, FirmwareConfig& c) {
  r.allow_only({"map", "start_pose", "seed", "range_noise_m", "people", "boxes", "laser_status"});
  sim::SimulationConfig& w = c.sim.world;
  c.sim.enabled = true;
  w.map_path = relative_to(r.file(), r.text("map"));
  if (r.has("start_pose")) w.start_pose = read_pose(r.child("start_pose"));
  if (r.has("seed")) w.seed = static_cast<std::uint64_t>(r.integer("seed", 0, INT64_MAX));
  if (r.has("range_noise_m")) w.range_noise_sigma_m = r.number("range_noise_m", 0.0, 1.0);
  if (r.has("people"))
    for (const Reader& m : r.sequence("people")) w.movers.push_back(read_mover(m, true));
  if (r.has("boxes"))
    for (const Reader& m : r.sequence("boxes")) w.movers.push_back(read_mover(m, false));
  if (r.has("laser_status")) w.laser.status = static_cast<std::uint8_t>(r.integer("laser_status", 0, 255));
  w.base.noise_seed = static_cast<std::uint32_t>(w.seed);
}

// `port: sim` is only meaningful with a simulated robot to connect to.
bool read_port(const Reader& r, const FirmwareConfig& c, std::string& port) {
  port = r.text("port");
  if (port != "sim") return false;
  if (!c.sim.enabled) r.fail("port", "'sim' needs a top-level sim section (the simulated robot)", YAML::Node());
  return true;
}

void read_devices(const Reader& r, FirmwareConfig& c) {
  r.allow_only({"base", "laser"});
  if (r.has("base")) {
    const Reader b = r.child("base");
    b.allow_only({"port", "baud", "probe_bauds", "switch_to_baud", "link_timeout_s", "command_timeout_s",
                  "request_encoders", "max_v_m_s", "max_omega_rad_s", "dist_conv_mm_per_unit", "vel_conv_mm_s_per_unit",
                  "diff_conv_rad_per_mm"});
    p2os::P2osConfig& p = c.devices.base;
    c.devices.has_base = true;
    c.devices.base_simulated = read_port(b, c, p.port);
    if (b.has("baud")) p.baud = static_cast<std::uint32_t>(b.integer("baud", 50, 4'000'000));
    if (b.has("probe_bauds")) p.probe_bauds = b.boolean("probe_bauds");
    if (b.has("switch_to_baud")) p.switch_to_baud = static_cast<std::uint32_t>(b.integer("switch_to_baud", 0, 4'000'000));
    if (b.has("link_timeout_s")) p.link_timeout_ms = static_cast<int>(millis(b, "link_timeout_s", 100, 60'000));
    if (b.has("command_timeout_s")) p.command_timeout_ms = static_cast<int>(millis(b, "command_timeout_s", 50, 60'000));
    if (b.has("request_encoders")) p.request_encoders = b.boolean("request_encoders");
    if (b.has("max_v_m_s")) p.max_v_m_s = b.number("max_v_m_s", 0.0, 2.2);
    if (b.has("max_omega_rad_s")) p.max_omega_rad_s = b.number("max_omega_rad_s", 0.0, 8.8);
    if (b.has("dist_conv_mm_per_unit")) p.conversion.dist_conv_mm_per_unit = b.number("dist_conv_mm_per_unit", 0.01, 100.0);
    if (b.has("vel_conv_mm_s_per_unit")) p.conversion.vel_conv_mm_s_per_unit = b.number("vel_conv_mm_s_per_unit", 0.01, 100.0);
    if (b.has("diff_conv_rad_per_mm")) p.conversion.diff_conv_rad_per_mm = b.number("diff_conv_rad_per_mm", 1e-5, 1.0);
  }
  if (r.has("laser")) {
    const Reader l = r.child("laser");
    l.allow_only({"port", "baud", "variant", "units", "probe_bauds", "stale_scan_periods"});
    lms200::Lms200Config& p = c.devices.laser;
    c.devices.has_laser = true;
    c.devices.laser_simulated = read_port(l, c, p.port);
    if (l.has("baud")) {
      const std::int64_t baud = l.integer("baud", 9600, 500'000);
      if (baud != 9600 && baud != 19200 && baud != 38400 && baud != 500000)
        l.fail("baud", "the LMS200 speaks 9600, 19200, 38400 or 500000 baud", YAML::Node());
      p.baud = static_cast<std::uint32_t>(baud);
    }
    if (l.has("variant")) {
      // "180/0.5": scan angle in degrees / resolution in degrees.
      const std::string text = l.text("variant");
      unsigned angle = 0;
      double resolution = 0;
      char tail = 0;
      lms200::Variant v;
      if (std::sscanf(text.c_str(), "%u/%lf%c", &angle, &resolution, &tail) == 2) {
        v.angle_deg = static_cast<std::uint16_t>(angle);
        v.resolution_cdeg = static_cast<std::uint16_t>(std::lround(resolution * 100.0));
      }
      if (!lms200::valid_variant(v) || v.angle_deg != angle)
        l.fail("variant", "expected one of 180/1, 180/0.5, 100/1, 100/0.5, 100/0.25, got '" + text + "'", YAML::Node());
      p.variant = v;
    }
    if (l.has("units")) {
      const std::string units = l.text("units");
      if (units == "cm") p.units = lms200::Units::cm;
      else if (units == "mm") p.units = lms200::Units::mm;
      else l.fail("units", "expected cm or mm, got '" + units + "'", YAML::Node());
    }
    if (l.has("probe_bauds")) p.probe_bauds = l.boolean("probe_bauds");
    if (l.has("stale_scan_periods")) p.stale_scan_periods = static_cast<int>(l.integer("stale_scan_periods", 2, 100));
  }
}

void read_navigation(const Reader& r, FirmwareConfig& c) {
  r.allow_only({"map", "waypoints", "initial_pose", "initial_std_m", "particles", "max_v_m_s", "max_w_rad_s",
                "goal_tolerance_m", "stop_distance_m", "goals", "start_delay_s", "goal_timeout_s"});
  NavigationSection& n = c.navigation;
  n.enabled = true;
  n.map_path = relative_to(r.file(), r.text("map"));
  if (r.has("waypoints")) n.waypoints_path = relative_to(r.file(), r.text("waypoints"));
  if (r.has("initial_pose")) n.initial_pose = read_pose(r.child("initial_pose"));
  if (r.has("initial_std_m")) n.initial_std_xy_m = r.number("initial_std_m", 0.0, 10.0);
  if (r.has("particles")) {
    const Reader p = r.child("particles");
    p.allow_only({"min", "max"});
    n.min_particles = static_cast<std::size_t>(p.integer("min", 10, 100'000));
    n.max_particles = static_cast<std::size_t>(p.integer("max", 10, 100'000));
    if (n.max_particles < n.min_particles) p.fail("max", "must be at least min", YAML::Node());
  }
  if (r.has("max_v_m_s")) n.max_v_m_s = r.number("max_v_m_s", 0.05, 2.0);
  if (r.has("max_w_rad_s")) n.max_w_rad_s = r.number("max_w_rad_s", 0.1, 5.0);
  if (r.has("goal_tolerance_m")) n.goal_tolerance_m = r.number("goal_tolerance_m", 0.02, 2.0);
  if (r.has("stop_distance_m")) n.stop_distance_m = r.number("stop_distance_m", 0.05, 3.0);
  const std::vector<Reader> goals = r.sequence("goals");
  if (goals.empty() || goals.size() > MissionConfig::kMaxGoals)
    r.fail("goals", "expected 1 to " + std::to_string(MissionConfig::kMaxGoals) + " points", YAML::Node());
  for (std::size_t i = 0; i < goals.size(); ++i) n.mission.goals[i] = goals[i].point();
  n.mission.goal_count = goals.size();
  if (r.has("start_delay_s")) n.mission.start_delay_s = r.number("start_delay_s", 0.0, 600.0);
  if (r.has("goal_timeout_s")) n.mission.goal_timeout_s = r.number("goal_timeout_s", 1.0, 86400.0);
}

FirmwareConfig read(const Reader& top, const std::string& source) {
  FirmwareConfig c;
  c.source_path = source;
  top.allow_only({"robot", "run", "realtime", "threads", "tasks", "devices", "sim", "navigation"});

  const Reader robot = top.child("robot");
  robot.allow_only({"name", "laser_mount"});
  c.robot_name = robot.text("name");
  if (robot.has("laser_mount")) c.laser_mount = read_pose(robot.child("laser_mount"));

  const Reader run = top.child("run");
  run.allow_only({"clock", "duration_s"});
  const std::string clock = run.text("clock");
  if (clock == "lockstep") {
    c.clock = ClockMode::lockstep;
  } else if (clock == "realtime") {
    c.clock = ClockMode::realtime;
  } else {
    run.fail("clock", "expected 'lockstep' or 'realtime', got '" + clock + "'", YAML::Node());
  }
  c.duration_s = run.number("duration_s", 0.0, 1e7);

  if (top.has("realtime")) {
    const Reader rt = top.child("realtime");
    rt.allow_only({"lock_memory", "prefault_stack_bytes"});
    if (rt.has("lock_memory")) c.lock_memory = rt.boolean("lock_memory");
    if (rt.has("prefault_stack_bytes")) c.prefault_stack_bytes = rt.bytes("prefault_stack_bytes");
  }

  if (top.has("threads")) {
    top.child("threads").for_each_entry([&](const std::string& name, const Reader& t) {
      t.allow_only({"cpu", "realtime"});
      ThreadConfig tc;
      if (t.has("cpu")) tc.cpu = static_cast<int>(t.integer("cpu", -1, 1023));
      if (t.has("realtime")) tc.realtime = t.boolean("realtime");
      c.threads[name] = tc;
    });
  }

  top.child("tasks").for_each_entry([&](const std::string& name, const Reader& t) {
    TaskConfig tc;
    if (name == "health") {
      t.allow_only({"arena_bytes", "stall_periods"});
      if (t.has("stall_periods")) c.health_stall_periods = static_cast<int>(t.integer("stall_periods", 1, 1000));
    } else if (name == "telemetry") {
      t.allow_only({"arena_bytes", "status_period_s"});
      if (t.has("status_period_s"))
        c.telemetry_status_period_ms = static_cast<std::int64_t>(std::llround(t.number("status_period_s", 0.0, 86400.0) * 1000.0));
    } else {
      t.allow_only({"arena_bytes"});
    }
    tc.arena_bytes = t.bytes("arena_bytes");
    c.tasks[name] = tc;
  });

  if (top.has("sim")) read_sim(top.child("sim"), c);
  if (top.has("devices")) read_devices(top.child("devices"), c);
  if (top.has("navigation")) read_navigation(top.child("navigation"), c);
  c.sim.world.laser_mount = c.laser_mount;
  return c;
}

}  // namespace

Result<FirmwareConfig> parse_config(std::string_view yaml_text, const std::string& source_name) {
  try {
    const YAML::Node root = YAML::Load(std::string(yaml_text));
    if (!root.IsDefined() || root.IsNull()) return Error::format(Errc::config, "%s: the file is empty", source_name.c_str());
    return read(Reader(root, source_name, ""), source_name);
  } catch (const ConfigError& e) {
    return Error(Errc::config, e.what());
  } catch (const YAML::Exception& e) {
    return Error::format(Errc::config, "%s: not valid YAML: %s", source_name.c_str(), e.what());
  }
}

Result<FirmwareConfig> load_config(const std::string& path) {
  // A configuration is a few kilobytes; anything far larger is the wrong file.
  constexpr std::size_t kMaxConfigBytes = 1 << 20;
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error::format(Errc::not_found, "%s: cannot open the configuration file", path.c_str());
  std::string text(kMaxConfigBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > kMaxConfigBytes)
    return Error::format(Errc::config, "%s: larger than %zu bytes; not a configuration file", path.c_str(), kMaxConfigBytes);
  return parse_config(text, path);
}

}  // namespace sen3bot::firmware
