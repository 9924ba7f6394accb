#include "sen3bot/sim/sim_config.hpp"

#include "config_reader.hpp"

namespace sen3bot::sim {

namespace {

using firmware::config::Reader;
using firmware::config::read_pose;
using firmware::config::relative_to;

world::MoverScript read_mover(const Reader& r, bool person) {
  r.allow_only({"path", "speed_m_s", "accel_m_s2", "size_m", "loop", "start_s", "appear_s", "shape"});
  world::MoverScript m;
  m.person = person;
  m.shape = person ? world::MoverShape::circle : world::MoverShape::square;
  for (const Reader& point : r.sequence("path")) m.path.push_back(point.point());
  if (m.path.empty()) r.fail("path", "needs at least one point", YAML::Node());
  if (r.has("speed_m_s")) m.speed_m_s = r.number("speed_m_s", 0.0, 5.0);
  if (r.has("size_m")) m.size_m = r.number("size_m", 0.05, 5.0);
  if (r.has("loop")) m.loop = r.boolean("loop");
  if (r.has("accel_m_s2")) m.accel_m_s2 = r.number("accel_m_s2", 0.0, 20.0);
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

// sim.io_node: the CAN I/O node and what happens to it.
void read_io_node(const Reader& r, SimIoNodeConfig& n) {
  r.allow_only({"node", "inputs", "events"});
  n.enabled = true;
  if (r.has("node")) n.node = static_cast<std::uint8_t>(r.integer("node", 1, 127));
  if (r.has("inputs")) n.inputs = static_cast<std::uint8_t>(r.integer("inputs", 0, 255));
  if (!r.has("events")) return;
  for (const Reader& e : r.sequence("events")) {
    e.allow_only({"at_s", "inputs", "silent", "reboot", "bus_off"});
    SimIoEvent event;
    event.at_s = e.number("at_s", 0.0, 1e7);
    if (!n.events.empty() && event.at_s < n.events.back().at_s) e.fail("at_s", "events must be in time order", YAML::Node());
    const int whats = int{e.has("inputs")} + int{e.has("silent")} + int{e.has("reboot")} + int{e.has("bus_off")};
    if (whats != 1) e.fail_here("expected exactly one of inputs, silent, reboot, bus_off");
    if (e.has("inputs")) {
      event.what = SimIoEvent::What::inputs;
      event.inputs = static_cast<std::uint8_t>(e.integer("inputs", 0, 255));
    } else if (e.has("silent")) {
      event.what = e.boolean("silent") ? SimIoEvent::What::silent : SimIoEvent::What::talking;
    } else if (e.has("reboot")) {
      if (!e.boolean("reboot")) e.fail("reboot", "only `reboot: true` means something", YAML::Node());
      event.what = SimIoEvent::What::reboot;
    } else {
      event.what = e.boolean("bus_off") ? SimIoEvent::What::bus_off : SimIoEvent::What::bus_on;
    }
    n.events.push_back(event);
  }
}

void read_sim(const Reader& r, SimulationConfig& w) {
  r.allow_only({"map", "start_pose", "seed", "range_noise_m", "laser_max_range_m", "people", "boxes", "laser_status",
                "detector", "io_node", "push", "odometry_error"});
  if (r.has("push")) {
    // Someone pushes the robot with its motors off along a path (mapping a site by hand).
    const Reader p = r.child("push");
    p.allow_only({"path", "speed_m_s", "start_s"});
    for (const Reader& point : p.sequence("path")) w.push_path.push_back(point.point());
    if (w.push_path.empty()) p.fail("path", "needs at least one point", YAML::Node());
    if (p.has("speed_m_s")) w.push_speed_m_s = p.number("speed_m_s", 0.05, 1.5);
    if (p.has("start_s")) w.push_start_s = p.number("start_s", 0.0, 1e6);
  }
  if (r.has("odometry_error")) {
    // The wheels' odometry off the truth: a scale error of the distance and of the turns.
    const Reader o = r.child("odometry_error");
    o.allow_only({"scale", "turn"});
    if (o.has("scale")) w.base.odometry_scale_error = o.number("scale", -0.2, 0.2);
    if (o.has("turn")) w.base.odometry_turn_error = o.number("turn", -0.2, 0.2);
  }
  if (r.has("io_node")) read_io_node(r.child("io_node"), w.io_node);
  w.map_path = relative_to(r.file(), r.text("map"));
  if (r.has("start_pose")) w.start_pose = read_pose(r.child("start_pose"));
  if (r.has("seed")) w.seed = static_cast<std::uint64_t>(r.integer("seed", 0, INT64_MAX));
  if (r.has("range_noise_m")) w.range_noise_sigma_m = r.number("range_noise_m", 0.0, 1.0);
  if (r.has("laser_max_range_m")) w.laser_max_range_m = r.number("laser_max_range_m", 1.0, 80.0);
  if (r.has("people"))
    for (const Reader& m : r.sequence("people")) w.movers.push_back(read_mover(m, true));
  if (r.has("boxes"))
    for (const Reader& m : r.sequence("boxes")) w.movers.push_back(read_mover(m, false));
  if (r.has("laser_status")) w.laser.status = static_cast<std::uint8_t>(r.integer("laser_status", 0, 255));
  if (r.has("detector")) {
    // The simulated remote person detector (sim_detector.hpp) on the "detector" channel.
    const Reader d = r.child("detector");
    d.allow_only({"enabled", "rate_hz", "latency_s", "noise_px", "miss_rate", "false_positive_rate", "max_range_m",
                  "laser_height_m"});
    SimDetectorConfig& c = w.detector;
    c.enabled = d.has("enabled") ? d.boolean("enabled") : true;
    if (d.has("rate_hz")) c.rate_hz = d.number("rate_hz", 0.5, 60.0);
    if (d.has("latency_s")) c.latency_s = d.number("latency_s", 0.0, 2.0);
    if (d.has("noise_px")) c.noise_px = d.number("noise_px", 0.0, 100.0);
    if (d.has("miss_rate")) c.miss_rate = d.number("miss_rate", 0.0, 1.0);
    if (d.has("false_positive_rate")) c.false_positive_rate = d.number("false_positive_rate", 0.0, 1.0);
    if (d.has("max_range_m")) c.max_range_m = d.number("max_range_m", 0.5, 30.0);
    if (d.has("laser_height_m")) c.laser_height_m = d.number("laser_height_m", 0.0, 2.0);
  }
  w.base.noise_seed = static_cast<std::uint32_t>(w.seed);
}

}  // namespace

Result<SimulationConfig> parse_sim_config(std::string_view yaml_text, const std::string& source_name,
                                          const nav::Pose2D& laser_mount) {
  return firmware::config::parse<SimulationConfig>(yaml_text, source_name, [&](const Reader& top) {
    SimulationConfig w;
    read_sim(top.child(std::string(kSimSection)), w);
    w.laser_mount = laser_mount;
    return w;
  });
}

Result<SimulatedRobot> load_simulated_robot(const std::string& path) {
  Result<std::string> text = firmware::config::read_text(path);
  if (!text) return text.error();
  const std::string_view sections[] = {kSimSection};
  Result<firmware::FirmwareConfig> config = firmware::parse_config(*text, path, sections);
  if (!config) return config.error();
  Result<SimulationConfig> world = parse_sim_config(*text, path, config->laser_mount);
  if (!world) return world.error();
  return SimulatedRobot{std::move(*config), std::move(*world)};
}

}  // namespace sen3bot::sim
