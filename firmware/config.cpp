#include "config.hpp"

#include <algorithm>
#include <climits>
#include <cstdio>
#include <fstream>
#include <numbers>

#include "config_reader.hpp"

namespace sen3bot::firmware {

namespace config {

Result<std::string> read_text(const std::string& path) {
  // A configuration is a few kilobytes; anything far larger is the wrong file.
  constexpr std::size_t kMaxConfigBytes = 1 << 20;
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error::format(Errc::not_found, "%s: cannot open the configuration file", path.c_str());
  std::string text(kMaxConfigBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > kMaxConfigBytes)
    return Error::format(Errc::config, "%s: larger than %zu bytes; not a configuration file", path.c_str(), kMaxConfigBytes);
  return text;
}

}  // namespace config

namespace {

using config::Reader;
using config::millis;
using config::read_pose;
using config::relative_to;

void read_camera(const Reader& r, FirmwareConfig& c) {
  r.allow_only({"url", "transport", "max_width_px", "max_height_px", "format", "downscale", "frames"});
  camera::CameraConfig& p = c.devices.camera;
  c.devices.has_camera = true;
  p.rtsp.url = r.text("url");
  if (p.rtsp.url.rfind("rtsp://", 0) != 0) r.fail("url", "expected rtsp://[user:pass@]host[:port]/path", YAML::Node());
  if (r.has("transport")) {
    const std::string t = r.text("transport");
    if (t == "tcp") p.rtsp.transport = camera::RtpTransport::tcp_interleaved;
    else if (t == "udp") p.rtsp.transport = camera::RtpTransport::udp;
    else r.fail("transport", "expected tcp or udp, got '" + t + "'", YAML::Node());
  }
  if (r.has("max_width_px")) p.max_width_px = static_cast<std::uint32_t>(r.integer("max_width_px", 16, 4096));
  if (r.has("max_height_px")) p.max_height_px = static_cast<std::uint32_t>(r.integer("max_height_px", 16, 4096));
  if (r.has("format")) {
    const std::string f = r.text("format");
    if (f == "bgr8") p.format = camera::PixelFormat::bgr8;
    else if (f == "gray8") p.format = camera::PixelFormat::gray8;
    else r.fail("format", "expected bgr8 or gray8, got '" + f + "'", YAML::Node());
  }
  if (r.has("downscale")) {
    const std::int64_t d = r.integer("downscale", 1, 4);
    if (d == 3) r.fail("downscale", "expected 1, 2 or 4", YAML::Node());
    p.downscale = static_cast<int>(d);
  }
  if (r.has("frames")) p.frame_pool_slots = static_cast<std::size_t>(r.integer("frames", 3, 64));
}

// devices.io_node: the CANopen safety I/O node (can_io_task.hpp).
void read_io_node(const Reader& r, FirmwareConfig& c) {
  r.allow_only({"interface", "node", "heartbeat_ms", "heartbeat_timeout_s", "inputs_period_ms", "inputs", "outputs",
                "reset_at_start"});
  CanIoConfig& p = c.devices.io_node;
  c.devices.has_io_node = true;
  p.interface = r.text("interface");
  p.master.node = static_cast<std::uint8_t>(r.integer("node", 1, 127));
  if (r.has("heartbeat_ms")) p.master.heartbeat_ms = static_cast<std::uint16_t>(r.integer("heartbeat_ms", 10, 10'000));
  if (r.has("heartbeat_timeout_s")) p.master.heartbeat_timeout_s = r.number("heartbeat_timeout_s", 0.02, 60.0);
  if (r.has("inputs_period_ms"))
    p.master.inputs_period_ms = static_cast<std::uint16_t>(r.integer("inputs_period_ms", 10, 10'000));
  if (r.has("reset_at_start")) p.reset_at_start = r.boolean("reset_at_start");
  if (r.has("inputs")) {
    const Reader in = r.child("inputs");
    in.allow_only({"estop", "estop_active_low", "reset", "bumpers", "bumpers_active_low"});
    if (in.has("estop")) p.estop_input = static_cast<std::uint8_t>(in.integer("estop", 1, 8));
    if (in.has("estop_active_low")) p.estop_active_low = in.boolean("estop_active_low");
    if (in.has("reset")) p.reset_input = static_cast<std::uint8_t>(in.integer("reset", 0, 8));
    if (in.has("bumpers")) {
      p.bumper_inputs = 0;
      for (const Reader& b : in.sequence("bumpers")) p.bumper_inputs |= static_cast<std::uint8_t>(1u << (b.integer_here(1, 8) - 1));
    }
    if (in.has("bumpers_active_low")) p.bumpers_active_low = in.boolean("bumpers_active_low");
  }
  if (r.has("outputs")) {
    const Reader out = r.child("outputs");
    out.allow_only({"idle", "driving", "wait4col", "fault", "buzzer", "buzzer_period_s"});
    const char* modes[] = {"idle", "driving", "wait4col", "fault"};
    for (std::size_t m = 0; m < 4; ++m)
      if (out.has(modes[m])) p.light_outputs[m + 1] = static_cast<std::uint8_t>(out.integer(modes[m], 0, 8));
    if (out.has("buzzer")) p.buzzer_output = static_cast<std::uint8_t>(out.integer("buzzer", 0, 8));
    if (out.has("buzzer_period_s")) p.buzzer_period_s = out.number("buzzer_period_s", 0.05, 60.0);
  }
  if (Status s = check(p); !s) r.fail_here(s.error().c_str());
}

void read_devices(const Reader& r, FirmwareConfig& c) {
  r.allow_only({"base", "laser", "camera", "io_node"});
  if (r.has("camera")) read_camera(r.child("camera"), c);
  if (r.has("io_node")) read_io_node(r.child("io_node"), c);
  if (r.has("base")) {
    const Reader b = r.child("base");
    b.allow_only({"port", "baud", "probe_bauds", "switch_to_baud", "link_timeout_s", "command_timeout_s",
                  "request_encoders", "trans_decel_m_s2", "max_v_m_s", "max_omega_rad_s", "dist_conv_mm_per_unit", "vel_conv_mm_s_per_unit",
                  "diff_conv_rad_per_mm"});
    p2os::P2osConfig& p = c.devices.base;
    c.devices.has_base = true;
    p.port = b.text("port");
    if (b.has("baud")) p.baud = static_cast<std::uint32_t>(b.integer("baud", 50, 4'000'000));
    if (b.has("probe_bauds")) p.probe_bauds = b.boolean("probe_bauds");
    if (b.has("switch_to_baud")) p.switch_to_baud = static_cast<std::uint32_t>(b.integer("switch_to_baud", 0, 4'000'000));
    if (b.has("link_timeout_s")) p.link_timeout_ms = static_cast<int>(millis(b, "link_timeout_s", 100, 60'000));
    if (b.has("command_timeout_s")) p.command_timeout_ms = static_cast<int>(millis(b, "command_timeout_s", 50, 60'000));
    if (b.has("request_encoders")) p.request_encoders = b.boolean("request_encoders");
    if (b.has("trans_decel_m_s2"))
      p.trans_decel_mm_s2 = static_cast<std::int32_t>(std::lround(b.number("trans_decel_m_s2", 0.05, 2.0) * 1000.0));
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
    p.port = l.text("port");
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

// navigation.dynamic_obstacles: every constant of the layer (dynamic_obstacles.hpp).
void read_dynamic_obstacles(const Reader& r, nav::DynamicObstacleConfig& d) {
  r.allow_only({"enabled", "alpha_fast", "alpha_slow", "beta", "c1", "c2", "static_mask_radius_m", "min_blob_cells",
                "max_blob_cells", "max_tracks", "gate_m", "confirm_hits", "camera_vouches", "max_coast_s", "max_coast_unseen_s",
                "accel_sigma_m_s2", "measurement_sigma_m", "axis_memory_m", "axis_min_travel_m", "axis_max_angle_deg",
                "cutoff", "sigma2_front_x_m2", "sigma2_front_y_m2", "sigma2_back_x_m2", "sigma2_back_y_m2",
                "max_speed_m_s", "front_horizon_s", "lethal_radius_m", "min_speed_m_s"});
  if (r.has("enabled")) d.enabled = r.boolean("enabled");
  nav::DolDetectorConfig& det = d.detector;
  if (r.has("alpha_fast")) det.alpha_fast = r.number("alpha_fast", 0.0, 1.0);
  if (r.has("alpha_slow")) det.alpha_slow = r.number("alpha_slow", 0.0, 1.0);
  if (!(det.alpha_slow < det.alpha_fast)) r.fail("alpha_slow", "must be smaller than alpha_fast", YAML::Node());
  if (r.has("beta")) det.beta = r.number("beta", 0.0, 1.0);
  if (r.has("c1")) det.c1 = r.number("c1", 0.0, 255.0);
  if (r.has("c2")) det.c2 = r.number("c2", 0.0, 255.0);
  if (r.has("static_mask_radius_m")) det.static_mask_radius_m = r.number("static_mask_radius_m", 0.0, 2.0);
  if (r.has("min_blob_cells")) det.min_blob_cells = static_cast<int>(r.integer("min_blob_cells", 1, 100'000));
  if (r.has("max_blob_cells")) det.max_blob_cells = static_cast<int>(r.integer("max_blob_cells", 1, 100'000));
  if (det.max_blob_cells < det.min_blob_cells) r.fail("max_blob_cells", "must be at least min_blob_cells", YAML::Node());
  nav::DolTrackerConfig& t = d.tracker;
  if (r.has("max_tracks")) t.max_tracks = static_cast<std::size_t>(r.integer("max_tracks", 1, msg::MovingObstacles::kMax));
  if (r.has("gate_m")) t.gate_m = r.number("gate_m", 0.05, 10.0);
  if (r.has("confirm_hits")) t.confirm_hits = static_cast<int>(r.integer("confirm_hits", 1, 100));
  if (r.has("camera_vouches")) t.camera_vouches = r.boolean("camera_vouches");
  if (r.has("max_coast_s")) t.max_coast_s = r.number("max_coast_s", 0.0, 60.0);
  if (r.has("max_coast_unseen_s")) t.max_coast_unseen_s = r.number("max_coast_unseen_s", 0.0, 600.0);
  if (r.has("accel_sigma_m_s2")) t.accel_sigma_m_s2 = r.number("accel_sigma_m_s2", 0.001, 100.0);
  if (r.has("measurement_sigma_m")) t.measurement_sigma_m = r.number("measurement_sigma_m", 0.001, 10.0);
  if (r.has("axis_memory_m")) t.axis_memory_m = r.number("axis_memory_m", 0.1, 100.0);
  if (r.has("axis_min_travel_m")) t.axis_min_travel_m = r.number("axis_min_travel_m", 0.0, 100.0);
  if (r.has("axis_max_angle_deg"))
    t.axis_max_angle_rad = r.number("axis_max_angle_deg", 0.0, 90.0) * std::numbers::pi / 180.0;
  nav::DolCostConfig& k = d.cost;
  if (r.has("cutoff")) k.cutoff = r.number("cutoff", 1.0, 252.0);
  if (r.has("sigma2_front_x_m2")) k.sigma2_front_x_m2 = r.number("sigma2_front_x_m2", 1e-4, 100.0);
  if (r.has("sigma2_front_y_m2")) k.sigma2_front_y_m2 = r.number("sigma2_front_y_m2", 1e-4, 100.0);
  if (r.has("sigma2_back_x_m2")) k.sigma2_back_x_m2 = r.number("sigma2_back_x_m2", 1e-4, 100.0);
  if (r.has("sigma2_back_y_m2")) k.sigma2_back_y_m2 = r.number("sigma2_back_y_m2", 1e-4, 100.0);
  if (r.has("max_speed_m_s")) k.max_speed_m_s = r.number("max_speed_m_s", 0.1, 20.0);
  if (r.has("front_horizon_s")) k.front_horizon_s = r.number("front_horizon_s", 0.0, 10.0);
  if (r.has("lethal_radius_m")) k.lethal_radius_m = r.number("lethal_radius_m", 0.0, 2.0);
  if (r.has("min_speed_m_s")) k.min_speed_m_s = r.number("min_speed_m_s", 0.0, 10.0);
}

// navigation.people.keep_out: the safety filter's cage check.
void read_keep_out(const Reader& o, NavigationSection& n) {
  o.allow_only({"enabled", "margin_m", "movers"});
  if (o.has("enabled") && !o.boolean("enabled")) n.safety.cage_margin_m = -1.0;
  if (o.has("margin_m")) n.safety.cage_margin_m = o.number("margin_m", 0.0, 2.0);
  if (o.has("movers")) n.cage_movers = o.boolean("movers");
}

// navigation.people.hidden: people kept while out of sight until their place is seen empty.
void read_hidden(const Reader& o, nav::PersonTrackerConfig& t) {
  o.allow_only({"enabled", "max_s", "max_sigma_m", "cage_growth_m", "wander_m2_s"});
  if (o.has("enabled")) t.keep_hidden = o.boolean("enabled");
  if (o.has("max_s")) t.hidden_max_s = o.number("max_s", 0.1, 600.0);
  if (o.has("max_sigma_m")) t.hidden_max_sigma_m = o.number("max_sigma_m", 0.05, 10.0);
  if (o.has("cage_growth_m")) t.hidden_cage_growth_m = o.number("cage_growth_m", 0.0, 2.0);
  if (o.has("wander_m2_s")) t.hidden_wander_m2_s = o.number("wander_m2_s", 0.0, 10.0);
}

// navigation.people.onboard: the on-board detector's search (detector: onboard).
void read_onboard(const Reader& o, NavigationSection& n) {
  o.allow_only({"rate_hz", "scale", "threshold", "min_height_px"});
  if (o.has("rate_hz")) n.onboard_rate_hz = o.number("rate_hz", 0.05, 30.0);
  if (o.has("scale")) n.onboard_hog.scale = o.number("scale", 0.1, 2.0);
  if (o.has("threshold")) n.onboard_hog.hit_threshold = o.number("threshold", -5.0, 10.0);
  if (o.has("min_height_px")) n.onboard_hog.min_height_px = o.number("min_height_px", 0.0, 4096.0);
}

// navigation.people.online_sgp: re-running the supervisory planner when a person pushed the
// robot off its safe path.
void read_online_sgp(const Reader& o, NavigationSection& n) {
  o.allow_only({"enabled", "trigger_distance_m", "deviation_m", "delay_s", "cooldown_s", "person_timeout_s"});
  if (o.has("enabled")) n.osgp_enabled = o.boolean("enabled");
  if (o.has("trigger_distance_m")) n.osgp.trigger_distance_m = o.number("trigger_distance_m", 0.1, 20.0);
  if (o.has("deviation_m")) n.osgp.deviation_m = o.number("deviation_m", 0.05, 10.0);
  if (o.has("delay_s")) n.osgp.delay_s = o.number("delay_s", 0.0, 60.0);
  if (o.has("cooldown_s")) n.osgp.cooldown_s = o.number("cooldown_s", 0.0, 600.0);
  if (o.has("person_timeout_s")) n.osgp.person_timeout_s = o.number("person_timeout_s", 0.0, 60.0);
}

// navigation.people: camera-laser fusion and the cages (docs/people.md).
void read_people(const Reader& p, NavigationSection& n) {
  p.allow_only({"detector", "safety_radius_m", "dynamic_after_m", "expire_s", "match_window_s", "max_age_s",
                "min_confidence", "confirm_boxes", "laser_follow_s", "follow_gate_m", "max_body_radius_m",
                "robot_clearance_m", "online_sgp", "onboard", "keep_out", "hidden"});
  n.people_enabled = true;
  n.people_detector = p.text("detector");
  if (p.has("safety_radius_m")) n.person_tracker.safety_radius_m = p.number("safety_radius_m", 0.0, 3.0);
  if (p.has("dynamic_after_m")) n.person_tracker.dynamic_after_m = p.number("dynamic_after_m", 0.0, 20.0);
  if (p.has("expire_s")) n.person_tracker.expire_s = n.cages.expire_s = p.number("expire_s", 0.1, 60.0);
  if (p.has("match_window_s")) n.fusion.match_window_s = p.number("match_window_s", 0.0, 2.0);
  if (p.has("max_age_s")) n.detection_max_age_s = p.number("max_age_s", 0.05, 10.0);
  if (p.has("min_confidence")) n.fusion.min_confidence = static_cast<float>(p.number("min_confidence", 0.0, 1.0));
  if (p.has("confirm_boxes"))
    n.person_tracker.confirm_hits = static_cast<std::uint32_t>(p.integer("confirm_boxes", 1, 100));
  if (p.has("laser_follow_s")) n.person_tracker.laser_follow_s = p.number("laser_follow_s", 0.0, 60.0);
  if (p.has("follow_gate_m")) n.person_tracker.follow_gate_m = p.number("follow_gate_m", 0.05, 2.0);
  if (p.has("max_body_radius_m")) n.fusion.max_body_radius_m = p.number("max_body_radius_m", 0.0, 1.0);
  if (p.has("robot_clearance_m")) n.cages.robot_clearance_m = p.number("robot_clearance_m", 0.0, 2.0);
  if (p.has("keep_out")) read_keep_out(p.child("keep_out"), n);
  if (p.has("hidden")) read_hidden(p.child("hidden"), n.person_tracker);
  if (p.has("onboard")) read_onboard(p.child("onboard"), n);
  if (p.has("online_sgp")) read_online_sgp(p.child("online_sgp"), n);
}

// navigation.sgp: the supervisory planner's integration (sgp.hpp); used with safe_curve.
void read_sgp(const Reader& p, nav::SgpConfig& sgp) {
  p.allow_only({"step_m", "max_steps", "waypoint_spacing_m", "barrier_k", "zeta", "on_curve_m", "max_waypoints"});
  if (p.has("step_m")) sgp.step_m = p.number("step_m", 0.001, 0.5);
  if (p.has("max_steps")) sgp.max_steps = static_cast<int>(p.integer("max_steps", 10, 1'000'000));
  if (p.has("waypoint_spacing_m")) sgp.waypoint_spacing_m = p.number("waypoint_spacing_m", 0.02, 5.0);
  if (p.has("barrier_k")) sgp.barrier_k = p.number("barrier_k", 0.0, 100.0);
  if (p.has("zeta")) sgp.zeta = p.number("zeta", 0.01, 100.0);
  if (p.has("on_curve_m")) sgp.on_curve_m = p.number("on_curve_m", 0.005, 1.0);
  if (p.has("max_waypoints")) sgp.max_waypoints = static_cast<std::size_t>(p.integer("max_waypoints", 2, 65'536));
  if (sgp.waypoint_spacing_m < sgp.step_m) p.fail("waypoint_spacing_m", "is shorter than step_m", YAML::Node());
}

// navigation.particles and navigation.recovery: the particle filter's size and its
// random-particle injection (AMCL's recovery_alpha_slow/fast; 0 for either turns it off).
void read_particles(const Reader& p, nav::MclConfig& mcl) {
  p.allow_only({"min", "max"});
  mcl.min_particles = static_cast<std::size_t>(p.integer("min", 10, 100'000));
  mcl.max_particles = static_cast<std::size_t>(p.integer("max", 10, 100'000));
  if (mcl.max_particles < mcl.min_particles) p.fail("max", "must be at least min", YAML::Node());
}

void read_recovery(const Reader& p, nav::MclConfig& mcl) {
  p.allow_only({"alpha_slow", "alpha_fast", "lost_ratio", "headings"});
  if (p.has("alpha_slow")) mcl.recovery_alpha_slow = p.number("alpha_slow", 0.0, 1.0);
  if (p.has("alpha_fast")) mcl.recovery_alpha_fast = p.number("alpha_fast", 0.0, 1.0);
  if (p.has("lost_ratio")) mcl.lost_likelihood_ratio = p.number("lost_ratio", 0.0, 0.99);
  if (p.has("headings")) mcl.injection_headings = static_cast<std::size_t>(p.integer("headings", 1, 360));
  if (mcl.recovery_alpha_slow > 0.0 && mcl.recovery_alpha_fast > 0.0 &&
      !(mcl.recovery_alpha_slow < mcl.recovery_alpha_fast))
    p.fail("alpha_fast", "must be larger than alpha_slow (or 0 for either to turn recovery off)", YAML::Node());
}

// navigation.approach: the safety filter's check against tracked movers coming from the side
// (safety.hpp).
void read_approach(const Reader& p, nav::SafetyConfig& safety) {
  p.allow_only({"horizon_s", "margin_m", "min_speed_m_s", "candidates"});
  if (p.has("horizon_s")) safety.approach_horizon_s = p.number("horizon_s", 0.0, 5.0);
  if (p.has("margin_m")) safety.approach_margin_m = p.number("margin_m", 0.0, 1.0);
  if (p.has("min_speed_m_s")) safety.approach_min_speed_m_s = p.number("min_speed_m_s", 0.0, 3.0);
  if (p.has("candidates")) safety.approach_candidates = p.boolean("candidates");
}

// navigation.make_way: moving out of a walker's way when the robot would stand in it
// (crossings.hpp).
void read_make_way(const Reader& p, nav::MakeWayConfig& m) {
  p.allow_only({"enabled", "horizon_s", "forward_m_s", "reverse_m_s", "slack_s"});
  if (p.has("enabled")) m.enabled = p.boolean("enabled");
  if (p.has("horizon_s")) m.horizon_s = p.number("horizon_s", 0.5, 20.0);
  if (p.has("forward_m_s")) m.forward_m_s = p.number("forward_m_s", 0.05, 2.0);
  if (p.has("reverse_m_s")) m.reverse_m_s = p.number("reverse_m_s", 0.05, 1.0);
  if (p.has("slack_s")) m.slack_s = p.number("slack_s", 0.0, 5.0);
}

// navigation.separation: the safety filter's speed and separation limit near people
// (safety.hpp).
void read_separation(const Reader& p, nav::SafetyConfig& safety) {
  p.allow_only({"enabled", "spread_m_s"});
  const bool on = !p.has("enabled") || p.boolean("enabled");
  if (p.has("spread_m_s")) safety.separation_spread_m_s = p.number("spread_m_s", 0.0, 2.0);
  if (!on) safety.separation_spread_m_s = -1.0;
}

// navigation.crossings: the crossing gate and the lanes (nav/crossings.hpp).
void read_crossings(const Reader& p, NavigationSection& n) {
  p.allow_only({"enabled", "lookahead_m", "horizon_s", "spread_m_s", "margin_m", "go_share", "lane_decay_s",
                "lane_band_weight"});
  nav::CrossingConfig& x = n.crossings;
  if (p.has("enabled")) x.enabled = p.boolean("enabled");
  if (p.has("lookahead_m")) x.lookahead_m = p.number("lookahead_m", 0.5, 12.0);
  if (p.has("horizon_s")) x.horizon_s = p.number("horizon_s", 0.5, 12.0);
  if (p.has("spread_m_s")) x.spread_m_s = p.number("spread_m_s", 0.0, 2.0);
  if (p.has("margin_m")) x.margin_m = p.number("margin_m", 0.0, 2.0);
  if (p.has("go_share")) x.go_share = p.number("go_share", 0.1, 1.0);
  if (p.has("lane_decay_s")) n.lanes.decay_s = p.number("lane_decay_s", 1.0, 3600.0);
  if (p.has("lane_band_weight")) n.lanes.band_weight = p.number("lane_band_weight", 0.01, 0.99);
}

// navigation.local_costmap: a larger window with longer marking sees movers earlier (costing
// memory and time).
void read_local_costmap(const Reader& p, NavigationSection& n) {
  p.allow_only({"size_m", "obstacle_range_m", "raytrace_range_m", "sonar_clearing"});
  if (p.has("size_m")) n.local_costmap_size_m = p.number("size_m", 2.0, 20.0);
  if (p.has("obstacle_range_m")) n.local_obstacles.obstacle_max_range_m = p.number("obstacle_range_m", 0.5, 10.0);
  if (p.has("raytrace_range_m")) n.local_obstacles.raytrace_max_range_m = p.number("raytrace_range_m", 0.5, 10.0);
  // The base's sonar echoes clear marks the laser cannot see any more (beside and behind).
  if (p.has("sonar_clearing")) n.local_obstacles.sonar_clearing = p.boolean("sonar_clearing");
  if (n.local_obstacles.raytrace_max_range_m < n.local_obstacles.obstacle_max_range_m)
    p.fail("raytrace_range_m", "must be at least obstacle_range_m (a mark must be clearable)", YAML::Node());
  if (n.local_obstacles.raytrace_max_range_m > n.local_costmap_size_m / 2.0)
    p.fail("raytrace_range_m", "reaches beyond the window (size_m / 2)", YAML::Node());
}

// navigation.mover_prediction: the DWA's time-aware check against the tracked movers
// (local_planner.hpp).
void read_mover_prediction(const Reader& p, nav::DwaConfig& dwa) {
  p.allow_only({"enabled", "horizon_s", "stay_horizon_s", "margin_m", "weight", "max_yield_s", "brake_delay_s",
                "brake_decel_m_s2", "may_return"});
  if (p.has("enabled")) dwa.mover_prediction = p.boolean("enabled");
  if (p.has("horizon_s")) dwa.mover_horizon_s = p.number("horizon_s", 0.1, 10.0);
  if (p.has("margin_m")) dwa.mover_margin_m = p.number("margin_m", 0.0, 2.0);
  if (p.has("stay_horizon_s")) dwa.mover_stay_horizon_s = p.number("stay_horizon_s", 0.0, 60.0);
  if (p.has("brake_delay_s")) dwa.mover_brake_delay_s = p.number("brake_delay_s", 0.0, 2.0);
  if (p.has("brake_decel_m_s2")) dwa.mover_brake_decel_m_s2 = p.number("brake_decel_m_s2", 0.05, 5.0);
  if (p.has("may_return")) dwa.mover_may_return = p.boolean("may_return");
  if (p.has("weight")) dwa.mover_weight = p.number("weight", 0.0, 100.0);
  if (p.has("max_yield_s")) dwa.max_yield_s = p.number("max_yield_s", 0.0, 600.0);
}

void read_navigation(const Reader& r, FirmwareConfig& c) {
  r.allow_only({"map", "waypoints", "initial_pose", "initial_std_m", "particles", "recovery", "max_v_m_s", "max_w_rad_s",
                "goal_tolerance_m", "stop_distance_m", "approach", "goals", "start_delay_s", "goal_timeout_s",
                "dynamic_obstacles", "mover_prediction", "local_costmap", "safe_curve", "sgp", "people", "crossings",
                "separation", "make_way"});
  NavigationSection& n = c.navigation;
  n.enabled = true;
  n.map_path = relative_to(r.file(), r.text("map"));
  if (r.has("waypoints")) n.waypoints_path = relative_to(r.file(), r.text("waypoints"));
  if (r.has("safe_curve")) {
    if (r.has("waypoints"))
      r.fail("safe_curve", "waypoints and safe_curve are alternatives: a fixed path, or the supervisory planner's",
             YAML::Node());
    n.safe_curve_path = relative_to(r.file(), r.text("safe_curve"));
  }
  if (r.has("people")) read_people(r.child("people"), n);
  if (r.has("sgp")) read_sgp(r.child("sgp"), n.sgp);
  if (r.has("initial_pose")) n.mcl.initial_pose = read_pose(r.child("initial_pose"));
  if (r.has("initial_std_m")) n.mcl.initial_std_xy_m = r.number("initial_std_m", 0.0, 10.0);
  if (r.has("particles")) read_particles(r.child("particles"), n.mcl);
  if (r.has("recovery")) read_recovery(r.child("recovery"), n.mcl);
  if (r.has("max_v_m_s")) n.dwa.max_v_m_s = r.number("max_v_m_s", 0.05, 2.0);
  if (r.has("max_w_rad_s")) n.dwa.max_w_rad_s = r.number("max_w_rad_s", 0.1, 5.0);
  if (r.has("goal_tolerance_m")) n.dwa.goal_tolerance_m = r.number("goal_tolerance_m", 0.02, 2.0);
  if (r.has("stop_distance_m")) n.safety.stop_distance_m = r.number("stop_distance_m", 0.05, 3.0);
  if (r.has("approach")) read_approach(r.child("approach"), n.safety);
  if (r.has("make_way")) read_make_way(r.child("make_way"), n.make_way);
  if (r.has("separation")) read_separation(r.child("separation"), n.safety);
  if (r.has("dynamic_obstacles")) read_dynamic_obstacles(r.child("dynamic_obstacles"), n.dynamic_obstacles);
  if (r.has("crossings")) read_crossings(r.child("crossings"), n);
  if (r.has("local_costmap")) read_local_costmap(r.child("local_costmap"), n);
  if (r.has("mover_prediction")) read_mover_prediction(r.child("mover_prediction"), n.dwa);
  // Optional here: with a `fleet` section the goals come from the fleet's orders instead.
  if (r.has("goals")) {
    const std::vector<Reader> goals = r.sequence("goals");
    if (goals.empty() || goals.size() > MissionConfig::kMaxGoals)
      r.fail("goals", "expected 1 to " + std::to_string(MissionConfig::kMaxGoals) + " points", YAML::Node());
    for (std::size_t i = 0; i < goals.size(); ++i) n.mission.goals[i] = goals[i].point();
    n.mission.goal_count = goals.size();
  }
  if (r.has("start_delay_s")) n.mission.start_delay_s = r.number("start_delay_s", 0.0, 600.0);
  if (r.has("goal_timeout_s")) n.mission.goal_timeout_s = r.number("goal_timeout_s", 1.0, 86400.0);
}

// fleet: the robot as a VDA 5050 vehicle (fleet_task.hpp, docs/fleet.md).
void read_fleet(const Reader& r, FirmwareConfig& c) {
  r.allow_only({"broker", "interface_name", "version", "manufacturer", "serial_number", "map_id", "username",
                "password_file", "ca_file", "cert_file", "key_file", "keepalive_s", "state_period_s",
                "visualization_period_s", "people_period_s", "deviation_xy_m", "battery_empty_v", "battery_full_v"});
  FleetConfig& f = c.fleet;
  c.has_fleet = true;
  f.broker = r.text("broker");
  f.serial_number = r.text("serial_number");
  if (r.has("interface_name")) f.interface_name = r.text("interface_name");
  if (r.has("version")) {
    const std::string version = r.text("version");
    const auto parsed = vda5050::parse_version(version);
    if (!parsed) r.fail("version", "expected 2.1.0 or 2.0.0, got '" + version + "'", YAML::Node());
    f.version = *parsed;
  }
  if (r.has("manufacturer")) f.manufacturer = r.text("manufacturer");
  if (r.has("map_id")) f.map_id = r.text("map_id");
  if (r.has("username")) f.username = r.text("username");
  if (r.has("password_file")) f.password_file = r.text("password_file");
  if (r.has("ca_file")) f.ca_file = r.text("ca_file");
  if (r.has("cert_file")) f.cert_file = r.text("cert_file");
  if (r.has("key_file")) f.key_file = r.text("key_file");
  if (r.has("keepalive_s")) f.keepalive_s = static_cast<int>(r.integer("keepalive_s", 5, 3600));
  if (r.has("state_period_s")) f.state_period_s = r.number("state_period_s", 0.01, 30.0);
  if (r.has("visualization_period_s")) f.visualization_period_s = r.number("visualization_period_s", 0.0, 60.0);
  if (r.has("people_period_s")) f.people_period_s = r.number("people_period_s", 0.0, 60.0);
  if (r.has("deviation_xy_m")) f.deviation_xy_m = r.number("deviation_xy_m", 0.01, 10.0);
  if (r.has("battery_empty_v")) f.battery_empty_v = r.number("battery_empty_v", 0.0, 100.0);
  if (r.has("battery_full_v")) f.battery_full_v = r.number("battery_full_v", 0.0, 100.0);
  if (Status s = check(f); !s) r.fail_here(s.error().c_str());
}

// cobot: the collaborative mode (cobot_task.hpp, docs/cobot.md).
void read_cobot(const Reader& r, FirmwareConfig& c) {
  r.allow_only({"site", "operators", "operator_safety_radius_m", "wait4col", "reach_m", "in_way_m", "qr", "trigger",
                "follow", "path", "recognition"});
  CobotSection& k = c.cobot;
  CobotTaskConfig& t = k.task;
  k.enabled = true;
  k.site_path = relative_to(r.file(), r.text("site"));
  for (const Reader& id : r.sequence("operators")) {
    const auto v = static_cast<std::uint32_t>(id.integer_here(1, 999'999));
    if (!t.trigger.operators.push_back(v))
      r.fail("operators", "at most " + std::to_string(cobot::TriggerConfig::kMaxOperators) + " operators", YAML::Node());
  }
  if (t.trigger.operators.empty()) r.fail("operators", "expected at least one trained operator's id", YAML::Node());
  if (r.has("operator_safety_radius_m")) k.operator_safety_radius_m = r.number("operator_safety_radius_m", 0.0, 2.0);
  if (r.has("wait4col")) t.mode.wait4col_enabled = r.boolean("wait4col");
  if (r.has("reach_m")) t.reach_m = r.number("reach_m", 0.5, 10.0);
  if (r.has("in_way_m")) t.in_way_m = r.number("in_way_m", 0.0, 5.0);
  if (r.has("qr")) {
    const Reader q = r.child("qr");
    q.allow_only({"rate_hz", "reach_m", "tag_side_m", "band_height_m", "whole_frame"});
    if (q.has("rate_hz")) k.qr_rate_hz = q.number("rate_hz", 0.1, 30.0);
    if (q.has("reach_m")) k.qr_reach_m = q.number("reach_m", 0.5, 10.0);
    if (q.has("tag_side_m")) k.tag_side_m = q.number("tag_side_m", 0.02, 0.5);
    if (q.has("band_height_m")) t.band_height_m = q.number("band_height_m", 0.0, 2.0);
    if (q.has("whole_frame")) k.qr_whole_frame = q.boolean("whole_frame");
  }
  if (r.has("trigger")) {
    const Reader q = r.child("trigger");
    q.allow_only({"min_distance_m", "max_distance_m", "front_min_s", "front_max_s", "back_min_s", "back_max_s",
                  "max_turn_s", "max_sighting_gap_s", "max_frame_delay_s", "standing_speed_m_s"});
    cobot::TriggerConfig& g = t.trigger;
    if (q.has("min_distance_m")) g.min_distance_m = q.number("min_distance_m", 0.0, 5.0);
    if (q.has("max_distance_m")) g.max_distance_m = q.number("max_distance_m", 0.0, 5.0);
    if (q.has("front_min_s")) g.front_min_s = q.number("front_min_s", 0.0, 30.0);
    if (q.has("front_max_s")) g.front_max_s = q.number("front_max_s", 0.0, 30.0);
    if (q.has("back_min_s")) g.back_min_s = q.number("back_min_s", 0.0, 30.0);
    if (q.has("back_max_s")) g.back_max_s = q.number("back_max_s", 0.0, 30.0);
    if (q.has("max_turn_s")) g.max_turn_s = q.number("max_turn_s", 0.0, 30.0);
    if (q.has("max_sighting_gap_s")) g.max_sighting_gap_s = q.number("max_sighting_gap_s", 0.01, 10.0);
    if (q.has("max_frame_delay_s")) g.max_frame_delay_s = q.number("max_frame_delay_s", 0.0, 10.0);
    if (q.has("standing_speed_m_s")) g.standing_speed_m_s = q.number("standing_speed_m_s", 0.0, 5.0);
  }
  if (r.has("follow")) {
    const Reader q = r.child("follow");
    q.allow_only({"distance_m", "min_step_m", "trail_capacity", "stop_speed_m_s", "stop_after_s", "lost_s",
                  "robot_radius_m", "goal_step_m"});
    cobot::FollowConfig& f = t.follow;
    if (q.has("distance_m")) f.distance_m = q.number("distance_m", 0.3, 5.0);
    if (q.has("min_step_m")) f.min_step_m = q.number("min_step_m", 0.01, 1.0);
    if (q.has("trail_capacity")) f.trail_capacity = static_cast<std::size_t>(q.integer("trail_capacity", 2, 4096));
    if (q.has("stop_speed_m_s")) f.stop_speed_m_s = q.number("stop_speed_m_s", 0.0, 2.0);
    if (q.has("stop_after_s")) f.stop_after_s = q.number("stop_after_s", 0.01, 60.0);
    if (q.has("lost_s")) f.lost_s = q.number("lost_s", 0.01, 60.0);
    if (q.has("robot_radius_m")) f.robot_radius_m = q.number("robot_radius_m", 0.0, 2.0);
    if (q.has("goal_step_m")) t.goal_step_m = q.number("goal_step_m", 0.01, 5.0);
  }
  if (r.has("path")) {
    const Reader q = r.child("path");
    q.allow_only({"capacity", "min_spacing_m", "depth_band_m"});
    cobot::PathConfig& p = t.path;
    if (q.has("capacity")) p.capacity = static_cast<std::size_t>(q.integer("capacity", 3, msg::WorkerPath::kMax));
    if (q.has("min_spacing_m")) p.min_spacing_m = q.number("min_spacing_m", 0.001, 5.0);
    if (q.has("depth_band_m")) p.depth_band_m = q.number("depth_band_m", 0.01, 5.0);
  }
  if (r.has("recognition")) {
    const Reader q = r.child("recognition");
    q.allow_only({"operations", "model", "rate_hz"});
    k.recognition = true;
    k.operations_path = relative_to(q.file(), q.text("operations"));
    k.model_path = relative_to(q.file(), q.text("model"));
    if (q.has("rate_hz")) k.recognition_rate_hz = q.number("rate_hz", 0.01, 10.0);
  }
  const cobot::TriggerConfig& g = t.trigger;
  if (!(g.min_distance_m < g.max_distance_m && g.front_min_s <= g.front_max_s && g.back_min_s <= g.back_max_s))
    r.fail("trigger", "each window's minimum must be below its maximum", YAML::Node());
}

// view: the live view's server (view_task.hpp, docs/view.md).
void read_view(const Reader& r, FirmwareConfig& c) {
  r.allow_only({"enabled", "address", "port", "token", "token_file", "max_clients", "channels", "camera"});
  ViewSection& v = c.view;
  v.enabled = r.has("enabled") ? r.boolean("enabled") : true;
  view::ServerConfig& server = v.task.server;
  if (r.has("address")) server.address = r.text("address");
  if (r.has("port")) server.port = static_cast<int>(r.integer("port", 0, 65535));
  if (r.has("token") && r.has("token_file")) r.fail("token_file", "give token or token_file, not both", YAML::Node());
  if (r.has("token")) server.token = r.text("token");
  if (r.has("token_file")) {
    const std::string path = relative_to(r.file(), r.text("token_file"));
    std::FILE* f = std::fopen(path.c_str(), "r");
    if (f == nullptr) r.fail("token_file", "cannot read " + path, YAML::Node());
    char line[256] = {};
    const bool got = std::fgets(line, sizeof line, f) != nullptr;
    std::fclose(f);
    std::string token = got ? line : "";
    while (!token.empty() && (token.back() == '\n' || token.back() == '\r' || token.back() == ' ')) token.pop_back();
    if (token.empty()) r.fail("token_file", path + " holds no token", YAML::Node());
    server.token = token;
  }
  if (r.has("max_clients"))
    server.max_clients = static_cast<std::size_t>(r.integer("max_clients", 1, static_cast<long long>(view::Server::kMaxClients)));
  if (r.has("channels")) {
    const Reader q = r.child("channels");
    std::vector<std::string_view> names;
    for (std::size_t i = 0; i < kViewChannels; ++i) names.push_back(channel_key(static_cast<ViewChannel>(i)));
    q.allow_only(names);
    for (std::size_t i = 0; i < kViewChannels; ++i) {
      const std::string key(names[i]);
      if (q.has(key)) v.task.period_s[i] = q.number(key, 0.0, 3600.0);
    }
  }
  if (r.has("camera")) {
    const Reader q = r.child("camera");
    q.allow_only({"max_width_px", "quality"});
    if (q.has("max_width_px")) v.task.camera_max_width_px = static_cast<std::uint32_t>(q.integer("max_width_px", 16, 4096));
    if (q.has("quality")) v.task.camera_quality = static_cast<int>(q.integer("quality", 1, 100));
  }
  if (v.enabled && !view::is_loopback_address(server.address) && server.token.empty())
    r.fail("address", server.address + " is reachable from other machines: set token or token_file", YAML::Node());
}

// mapping: map building on the robot (mapping_task.hpp, docs/mapping.md).
void read_mapping(const Reader& r, FirmwareConfig& c) {
  r.allow_only({"out", "max_scans", "beams", "resolution_m", "scans_per_submap", "max_range_m", "finished_submap_bytes",
                "start_pose"});
  MappingConfig& m = c.mapping.task;
  c.mapping.enabled = true;
  m.out_path = relative_to(r.file(), r.text("out"));
  if (r.has("max_scans")) m.max_scans = static_cast<std::size_t>(r.integer("max_scans", 1, 1'000'000));
  if (r.has("beams")) m.beams = static_cast<std::size_t>(r.integer("beams", 16, static_cast<long long>(slam::kMaxBeams)));
  if (r.has("resolution_m")) m.mapper.resolution_m = r.number("resolution_m", 0.01, 0.5);
  if (r.has("scans_per_submap")) m.mapper.scans_per_submap = static_cast<int>(r.integer("scans_per_submap", 2, 1000));
  if (r.has("max_range_m")) m.mapper.max_range_m = r.number("max_range_m", 1.0, 80.0);
  if (r.has("finished_submap_bytes")) m.finished_submap_bytes = r.bytes("finished_submap_bytes");
  if (r.has("start_pose")) m.start_pose = read_pose(r.child("start_pose"));
}

FirmwareConfig read(const Reader& top, const std::string& source, std::span<const std::string_view> board_sections) {
  FirmwareConfig c;
  c.source_path = source;
  std::vector<std::string_view> keys = {"robot", "run", "realtime", "threads", "tasks", "board", "devices", "navigation", "fleet", "cobot", "view", "mapping"};
  keys.insert(keys.end(), board_sections.begin(), board_sections.end());
  if (top.has("sim") && std::find(keys.begin(), keys.end(), "sim") == keys.end())
    top.fail("sim", "a simulated robot: run this configuration with sen3bot-sim", YAML::Node());
  top.allow_only(keys);

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
    rt.allow_only({"lock_memory", "max_cpu_wakeup_latency_us", "prefault_stack_bytes", "thread_stack_bytes"});
    if (rt.has("lock_memory")) c.lock_memory = rt.boolean("lock_memory");
    if (rt.has("max_cpu_wakeup_latency_us"))
      c.max_cpu_wakeup_latency_us = static_cast<int>(rt.integer("max_cpu_wakeup_latency_us", -1, 1'000'000));
    if (rt.has("prefault_stack_bytes")) c.prefault_stack_bytes = rt.bytes("prefault_stack_bytes");
    if (rt.has("thread_stack_bytes")) c.thread_stack_bytes = rt.bytes("thread_stack_bytes");
    // The prefault and the scheduler's 64 KiB safety margin must fit in every row's stack.
    if (c.thread_stack_bytes != 0 && c.thread_stack_bytes < c.prefault_stack_bytes + 128 * 1024)
      rt.fail("thread_stack_bytes", "expected 0 or at least prefault_stack_bytes + 128KiB", YAML::Node());
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

  if (top.has("board")) {
    const Reader b = top.child("board");
    b.allow_only({"estop_input", "light_output"});
    if (b.has("estop_input")) c.board.estop_input = b.text("estop_input");
    if (b.has("light_output")) c.board.light_output = b.text("light_output");
  }
  if (top.has("devices")) read_devices(top.child("devices"), c);
  if (top.has("navigation")) read_navigation(top.child("navigation"), c);
  if (top.has("fleet")) {
    read_fleet(top.child("fleet"), c);
    if (!c.navigation.enabled) top.fail("fleet", "the fleet drives the robot through its navigation: needs a navigation section", YAML::Node());
    if (c.navigation.mission.goal_count > 0)
      top.fail("navigation", "goals: the fleet's orders give the goals; remove navigation.goals or the fleet section", YAML::Node());
  } else if (c.navigation.enabled && c.navigation.mission.goal_count == 0) {
    top.fail("navigation", "goals: missing (1 to " + std::to_string(MissionConfig::kMaxGoals) + " points, or a fleet section)", YAML::Node());
  }
  if (top.has("view")) read_view(top.child("view"), c);
  if (top.has("mapping")) read_mapping(top.child("mapping"), c);
  if (top.has("cobot")) {
    read_cobot(top.child("cobot"), c);
    if (!c.navigation.enabled || !c.navigation.people_enabled)
      top.fail("cobot", "the collaborative mode follows people: needs navigation with navigation.people", YAML::Node());
  }
  return c;
}

}  // namespace

Result<FirmwareConfig> parse_config(std::string_view yaml_text, const std::string& source_name,
                                    std::span<const std::string_view> board_sections) {
  return config::parse<FirmwareConfig>(yaml_text, source_name,
                                       [&](const Reader& top) { return read(top, source_name, board_sections); });
}

Result<FirmwareConfig> load_config(const std::string& path, std::span<const std::string_view> board_sections) {
  Result<std::string> text = config::read_text(path);
  if (!text) return text.error();
  return parse_config(*text, path, board_sections);
}

}  // namespace sen3bot::firmware
