// sen3bot-sim fleet-sim: the source's three fleet scenarios in lockstep. Several whole robots
// (each its firmware over its own simulated board, with the same scripted people in every
// robot's world), plant AGVs speaking VDA 5050, the Sensors Synergy Centre, and the plant's
// master control giving the AGVs their orders, all on one in-process broker with MQTT
// semantics. The report: the centre's event log as a timeline, the AGVs' speeds, the closest
// any AGV came to a person, when the centre's advice reached the AGV against when its own
// scanner could first have seen the person, and figures of the site at the key moments.
//
// What is not simulated: the robots and the AGVs do not see one another (each robot's laser sees
// its world's map and people only); the AGVs follow straight edges without a map.
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstring>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "config.hpp"
#include "firmware.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/sim/agv.hpp"
#include "sen3bot/sim/report/canvas.hpp"
#include "sen3bot/sim/sim_board.hpp"
#include "sen3bot/sim/sim_config.hpp"
#include "sen3bot/ssc/service.hpp"
#include "sen3bot/vda5050/json.hpp"
#include "sim_commands.hpp"

namespace sen3bot::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr hal::Nanos kSliceNs = hal::millis(10);
constexpr double kAgvStepS = 0.05;
constexpr double kCentreStepS = 0.05;  // as the centre's program steps
constexpr std::int64_t kEpochUnixNs = hal::SimClock::kEpochUnixNs;

struct AgvPlan {
  const char* serial;
  std::vector<msg::Point2D> route;
  double speed_m_s;
  double order_s;  // when the plant's master control sends its order
};

struct FleetScenario {
  const char* name;
  const char* description;
  std::vector<const char*> robots;  // serial numbers of the site's robots that take part
  std::vector<AgvPlan> agvs;
  std::vector<world::MoverScript> people;
  double duration_s;
};

world::MoverScript walker(std::vector<world::Point2D> path, double speed, double start_s, double vanish_s) {
  world::MoverScript m;
  m.path = std::move(path);
  m.speed_m_s = speed;
  m.size_m = 0.45;
  m.start_time_s = start_s;
  m.vanish_time_s = vanish_s;
  m.accel_m_s2 = 1.0;
  m.person = true;
  return m;
}

world::MoverScript stander(double x, double y) {
  world::MoverScript m;
  m.path = {{x, y}};
  m.size_m = 0.45;
  m.person = true;
  return m;
}

std::vector<FleetScenario> scenarios() {
  return {
      {"net-1",
       "One AGV and one Sen3Bot: a worker comes down the cross aisle towards the AGV lane, hidden "
       "from the AGV by the racks; the robot at the intersection sees the worker and the centre "
       "advises the AGV before the AGV's own scanner could have seen the worker.",
       {"r1"},
       {{"agv1", {{1.5, 2.0}, {12.0, 2.0}, {22.5, 2.0}}, 0.8, 6.0}},
       {walker({{11.4, 9.0}, {11.4, 0.9}}, 0.8, 4.0, 26.0)},
       55.0},
      {"net-2",
       "A 1.1 area with a moving person: two robots go to the blind intersection and both stay "
       "while the AGV's route crosses it; the AGV is stopped until the person has left.",
       {"r1", "r2"},
       {{"agv1", {{1.5, 2.0}, {12.0, 2.0}, {22.5, 2.0}}, 0.6, 5.0}},
       {walker({{11.3, 3.1}, {11.3, 0.8}}, 0.5, 2.0, 70.0)},
       110.0},
      {"net-3",
       "A workstation behind racks treated as 1.2 with static people: two robots go, one is "
       "released (p = 2) once the people are known to be static, and is then sent to the next "
       "monitoring request on the AGV's route.",
       {"r1", "r3"},
       {{"agv1", {{23.0, 8.3}, {17.0, 8.3}, {11.8, 8.3}, {11.8, 11.5}}, 0.6, 20.0}},
       {stander(19.0, 11.1), stander(20.2, 11.1)},
       140.0},
  };
}

struct RobotRun {
  std::string serial;
  firmware::FirmwareConfig config;
  std::unique_ptr<SimBoard> board;
  std::unique_ptr<firmware::Firmware> fw;
  std::vector<msg::Point2D> trail;
};

struct AgvSample {
  double t_s;
  double x, y, speed;
  Advice advice;
};

struct Snapshot {
  double t_s = -1;
  std::string label;
  std::vector<msg::Pose2D> robots;
  std::vector<msg::Pose2D> agvs;
  std::vector<msg::Point2D> people;
};

bool write_text(const std::string& path, const std::string& text) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return false;
  const bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  return std::fclose(f) == 0 && ok;
}

report::Rgb area_colour(ssc::AreaType type) {
  switch (type) {
    case ssc::AreaType::blind_intersection: return {255, 200, 200};
    case ssc::AreaType::transition: return {255, 230, 180};
    case ssc::AreaType::workstation: return {210, 230, 255};
    case ssc::AreaType::not_monitored: return {230, 230, 230};
  }
  return {230, 230, 230};
}

// The site at one moment: the map, the areas, the robots' trails and poses, the AGVs with their
// routes, the people; axes in metres, a legend and a title.
bool draw_site(const std::string& path, const std::string& title, const nav::OccupancyMap& map, const ssc::SiteFile& site,
               const std::vector<RobotRun>& robots, const std::vector<AgvPlan>& plans, const Snapshot& shot) {
  const double px_per_m = 40;
  const double width_m = map.width() * map.resolution_m(), height_m = map.height() * map.resolution_m();
  const int left = 70, bottom_margin = 60, top = 70, legend_w = 230;
  const int w = left + static_cast<int>(width_m * px_per_m) + legend_w, h = top + static_cast<int>(height_m * px_per_m) + bottom_margin;
  report::Canvas canvas(w, h, {255, 255, 255});
  report::View view{map.origin_x_m(), map.origin_y_m(), px_per_m, static_cast<double>(left), static_cast<double>(h - bottom_margin)};
  const double cell_px = map.resolution_m() * px_per_m;
  for (int row = 0; row < map.height(); ++row)
    for (int col = 0; col < map.width(); ++col)
      if (map.at(col, row) > 50) {
        const report::Px p = view(map.origin_x_m() + col * map.resolution_m(), map.origin_y_m() + (row + 1) * map.resolution_m());
        // One pixel more than a cell, so rounding never leaves gaps between cells.
        canvas.fill_rect(static_cast<int>(p.x), static_cast<int>(p.y), static_cast<int>(std::ceil(cell_px)) + 1,
                         static_cast<int>(std::ceil(cell_px)) + 1, {60, 60, 60});
      }
  for (std::size_t i = 0; i < site.site.areas.size(); ++i) {
    const ssc::Area& a = site.site.areas[i];
    std::vector<report::Px> outline;
    for (const ssc::Point& p : a.outline) outline.push_back(view(p.x, p.y));
    canvas.outline_polygon(outline, area_colour(a.type), 3);
    canvas.text(view(a.outline[0].x + 0.1, a.outline[0].y + 0.15), site.area_names[i] + " (" + std::string(ssc::to_string(a.type)) + ")",
                {150, 60, 60}, 0.45, 1, true);
  }
  for (const AgvPlan& plan : plans) {
    std::vector<report::Px> route;
    for (const msg::Point2D& p : plan.route) route.push_back(view(p.x_m, p.y_m));
    canvas.dashed_polyline(route, {120, 120, 255}, 2, 10, 6);
  }
  const report::Rgb robot_colours[] = {{0, 140, 0}, {0, 110, 200}, {170, 0, 170}};
  for (std::size_t i = 0; i < robots.size(); ++i) {
    std::vector<report::Px> trail;
    for (const msg::Point2D& p : robots[i].trail) trail.push_back(view(p.x_m, p.y_m));
    if (trail.size() > 1) canvas.polyline(trail, robot_colours[i % 3], 2);
    if (i < shot.robots.size()) {
      const msg::Pose2D& r = shot.robots[i];
      canvas.disc(view(r.x_m, r.y_m), 0.26 * px_per_m, robot_colours[i % 3]);
      canvas.line(view(r.x_m, r.y_m), view(r.x_m + 0.4 * std::cos(r.theta_rad), r.y_m + 0.4 * std::sin(r.theta_rad)), {255, 255, 255}, 2);
      canvas.text(view(r.x_m + 0.3, r.y_m + 0.3), robots[i].serial, robot_colours[i % 3], 0.45, 1, true);
    }
  }
  for (std::size_t i = 0; i < shot.agvs.size(); ++i) {
    const msg::Pose2D& a = shot.agvs[i];
    const report::Px c = view(a.x_m, a.y_m);
    canvas.fill_rect(static_cast<int>(c.x - 0.5 * px_per_m), static_cast<int>(c.y - 0.35 * px_per_m), static_cast<int>(px_per_m),
                     static_cast<int>(0.7 * px_per_m), {60, 60, 230});
    canvas.text(view(a.x_m - 0.4, a.y_m + 0.5), plans[i].serial, {60, 60, 230}, 0.45, 1, true);
  }
  for (const msg::Point2D& p : shot.people) canvas.disc(view(p.x_m, p.y_m), 0.22 * px_per_m, {230, 120, 0});
  // Axes in metres.
  canvas.line(view(0, 0), view(width_m, 0), {0, 0, 0}, 1);
  canvas.line(view(0, 0), view(0, height_m), {0, 0, 0}, 1);
  for (int x = 0; x <= static_cast<int>(width_m); x += 2) {
    canvas.line(view(x, 0), {view(x, 0).x, view(x, 0).y + 6}, {0, 0, 0}, 1);
    canvas.text({view(x, 0).x - 6, view(x, 0).y + 22}, std::to_string(x), {0, 0, 0}, 0.4);
  }
  for (int y = 0; y <= static_cast<int>(height_m); y += 2) {
    canvas.line(view(0, y), {view(0, y).x - 6, view(0, y).y}, {0, 0, 0}, 1);
    canvas.text({view(0, y).x - 30, view(0, y).y + 5}, std::to_string(y), {0, 0, 0}, 0.4);
  }
  canvas.text({view(width_m / 2, 0).x - 20, static_cast<double>(h - 12)}, "x (m)", {0, 0, 0}, 0.5);
  canvas.text({8, static_cast<double>(top) - 10}, "y (m)", {0, 0, 0}, 0.5);
  canvas.text({static_cast<double>(left), 28}, title, {0, 0, 0}, 0.6, 1);
  char when[64];
  std::snprintf(when, sizeof when, "t = %.1f s: %s", shot.t_s, shot.label.c_str());
  canvas.text({static_cast<double>(left), 54}, when, {60, 60, 60}, 0.5);
  // Legend.
  const double lx = left + width_m * px_per_m + 20;
  double ly = top + 20;
  auto entry = [&](report::Rgb colour, const std::string& text, bool square) {
    if (square) {
      canvas.fill_rect(static_cast<int>(lx), static_cast<int>(ly - 10), 20, 14, colour);
    } else {
      canvas.disc({lx + 10, ly - 4}, 8, colour);
    }
    canvas.text({lx + 30, ly}, text, {0, 0, 0}, 0.42);
    ly += 26;
  };
  entry({0, 140, 0}, "Sen3Bot (and trail)", false);
  entry({60, 60, 230}, "AGV", true);
  entry({120, 120, 255}, "AGV route (dashed)", true);
  entry({230, 120, 0}, "person", false);
  entry({255, 200, 200}, "area 1.1 (critical)", true);
  entry({255, 230, 180}, "area 1.2 (critical)", true);
  entry({210, 230, 255}, "area 2 (workstation)", true);
  entry({60, 60, 60}, "walls and racks", true);
  return canvas.write_png(path);
}

int fail(std::FILE* err, const std::string& message, int code = 2) {
  std::fprintf(err, "sen3bot-sim fleet-sim: %s\n", message.c_str());
  return code;
}

}  // namespace

int fleet_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  std::string scenario_name;
  std::string site_path = SEN3BOT_SOURCE_DIR "/config/fleet/site.yaml";
  std::string config_path = SEN3BOT_SOURCE_DIR "/config/fleet/robot.yaml";
  std::string report_dir;
  std::string capture_dir;
  for (int i = 0; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) return {};
      return argv[++i];
    };
    if (arg == "--scenario") {
      scenario_name = value();
    } else if (arg == "--site") {
      site_path = value();
    } else if (arg == "--config") {
      config_path = value();
    } else if (arg == "--report") {
      report_dir = value();
    } else if (arg == "--capture") {
      capture_dir = value();
    } else if (arg == "--list") {
      for (const FleetScenario& s : scenarios()) std::fprintf(out, "%-6s %s\n", s.name, s.description);
      return 0;
    } else if (arg == "--help" || arg == "-h") {
      std::fprintf(out, "usage: sen3bot-sim fleet-sim --scenario net-1|net-2|net-3 [--report DIR] [--capture DIR] [--site FILE] "
                   "[--config FILE] | --list\n");
      return 0;
    } else {
      return fail(err, "unknown argument '" + arg + "' (try --help)");
    }
  }
  const std::vector<FleetScenario> all = scenarios();
  const auto found = std::find_if(all.begin(), all.end(), [&](const FleetScenario& s) { return scenario_name == s.name; });
  if (found == all.end()) return fail(err, "--scenario: expected net-1, net-2 or net-3, got '" + scenario_name + "'");
  const FleetScenario& scenario = *found;
  if (!report_dir.empty() && ::mkdir(report_dir.c_str(), 0755) != 0 && errno != EEXIST)
    return fail(err, "--report: cannot create " + report_dir + ": " + std::strerror(errno), 1);
  if (!capture_dir.empty() && ::mkdir(capture_dir.c_str(), 0755) != 0 && errno != EEXIST)
    return fail(err, "--capture: cannot create " + capture_dir + ": " + std::strerror(errno), 1);

  Result<ssc::SiteFile> site = ssc::load_site(site_path);
  if (!site) return fail(err, site.error().c_str());
  Result<SimulatedRobot> base = load_simulated_robot(config_path);
  if (!base) return fail(err, base.error().c_str());
  Result<nav::OccupancyMap> map = nav::load_map(base->world.map_path);
  if (!map) return fail(err, map.error().c_str(), 1);

  hal::MemoryBroker broker;
  std::FILE* quiet = std::fopen("/dev/null", "w");
  std::vector<RobotRun> robots;
  robots.reserve(scenario.robots.size());
  for (const char* serial : scenario.robots) {
    const auto it = std::find(site->robot_serials.begin(), site->robot_serials.end(), serial);
    if (it == site->robot_serials.end()) return fail(err, std::string("the site has no robot ") + serial);
    const ssc::RobotHome& home = site->site.robots[static_cast<std::size_t>(it - site->robot_serials.begin())];
    RobotRun& run = robots.emplace_back();
    run.serial = serial;
    run.config = base->firmware;
    run.config.fleet.serial_number = serial;
    run.config.navigation.mcl.initial_pose = {home.pose.x, home.pose.y, home.pose.theta};
    run.config.navigation.people_enabled = true;
    run.config.navigation.people_detector = "sim";
    run.config.tasks["detector"].arena_bytes = 4 * 1024;
    run.config.tasks["people"].arena_bytes = 64 * 1024;
    SimulationConfig world = base->world;
    world.start_pose = {home.pose.x, home.pose.y, home.pose.theta};
    world.movers = scenario.people;
    world.detector.enabled = true;
    auto board = SimBoard::create(world, true);
    if (!board) return fail(err, board.error().c_str(), 1);
    run.board = std::move(board.value());
    run.board->set_site_broker(&broker);
    run.fw = std::make_unique<firmware::Firmware>(run.config, *run.board, quiet);
    if (Status s = run.fw->init(); !s) return fail(err, std::string(serial) + ": " + s.error().c_str(), 1);
  }

  std::FILE* event_log = report_dir.empty() ? nullptr : std::fopen((report_dir + "/events.jsonl").c_str(), "w");
  hal::PubSubOptions centre_link;
  centre_link.client_id = "ssc";
  centre_link.subscriptions = ssc::Service::subscriptions(site->service);
  centre_link.inbound_slots = 1024;
  auto centre_client = broker.connect(centre_link);
  if (!centre_client) return fail(err, centre_client.error().c_str(), 1);
  auto service = ssc::Service::create(*site, std::move(centre_client.value()), event_log);
  if (!service) return fail(err, service.error().c_str(), 1);

  std::vector<std::unique_ptr<SimAgv>> agvs;
  for (const AgvPlan& plan : scenario.agvs) {
    SimAgvConfig c;
    c.serial_number = plan.serial;
    c.map_id = site->service.map_id;
    c.version = site->service.version;
    c.x = plan.route.front().x_m;
    c.y = plan.route.front().y_m;
    c.theta = std::atan2(plan.route[1].y_m - plan.route[0].y_m, plan.route[1].x_m - plan.route[0].x_m);
    c.speed_m_s = plan.speed_m_s;
    hal::PubSubOptions link;
    link.client_id = plan.serial;
    link.subscriptions = SimAgv::subscriptions(c);
    auto client = broker.connect(link);
    if (!client) return fail(err, client.error().c_str(), 1);
    agvs.push_back(std::make_unique<SimAgv>(c, std::move(client.value())));
  }

  // --capture: every message on the broker, as TOPIC.N.json (TOPIC its last level, or people /
  // advisory), for checking against the schemas.
  std::unique_ptr<hal::PubSub> capture;
  std::map<std::string, int> captured;
  std::vector<char> capture_topic(256);
  std::vector<std::uint8_t> capture_payload(64 * 1024);
  if (!capture_dir.empty()) {
    hal::PubSubOptions everything;
    everything.client_id = "capture";
    everything.subscriptions = {{"#", 1}};
    everything.inbound_slots = 1024;
    everything.max_payload = 16 * 1024;
    auto client = broker.connect(everything);
    if (!client) return fail(err, client.error().c_str(), 1);
    capture = std::move(client.value());
  }
  auto drain_capture = [&] {
    if (!capture) return;
    for (;;) {
      auto m = capture->receive(capture_topic, capture_payload);
      if (!m || !m.value()) return;
      const std::string topic(capture_topic.data(), m.value()->topic_size);
      std::string leaf = topic.substr(topic.rfind('/') + 1);
      if (topic.starts_with("sen3bot/v1/people/")) leaf = "people";
      if (topic.starts_with("sen3bot/v1/advisory/")) leaf = "advisory";
      const std::string path = capture_dir + "/" + leaf + "." + std::to_string(++captured[leaf]) + ".json";
      (void)write_text(path, std::string(reinterpret_cast<const char*>(capture_payload.data()), m.value()->payload_size));
    }
  };

  // The plant's master control: each AGV's order, as a VDA 5050 order of its route.
  auto send_agv_order = [&](const AgvPlan& plan, std::int64_t unix_ns) {
    auto order = std::make_unique<vda5050::Order>();
    order->header.timestamp = vda5050::iso8601(unix_ns);
    (void)order->header.manufacturer.assign("PlantAGV");
    (void)order->header.serial_number.assign(plan.serial);
    (void)order->order_id.assign(std::string("plant-") + plan.serial);
    for (std::size_t i = 0; i < plan.route.size(); ++i) {
      vda5050::Node node;
      (void)node.node_id.assign("p" + std::to_string(i));
      node.sequence_id = static_cast<std::uint32_t>(2 * i);
      node.released = true;
      node.position = vda5050::NodePosition{plan.route[i].x_m, plan.route[i].y_m, std::nullopt, 0.1, 0.0, {}};
      (void)node.position->map_id.assign(site->service.map_id);
      (void)order->nodes.push_back(node);
      if (i + 1 < plan.route.size()) {
        vda5050::Edge edge;
        (void)edge.edge_id.assign("e" + std::to_string(i));
        edge.sequence_id = static_cast<std::uint32_t>(2 * i + 1);
        edge.released = true;
        (void)edge.start_node_id.assign("p" + std::to_string(i));
        (void)edge.end_node_id.assign("p" + std::to_string(i + 1));
        (void)order->edges.push_back(edge);
      }
    }
    std::vector<char> text(64 * 1024);
    auto encoded = vda5050::encode_order(*order, site->service.version, text);
    if (!encoded) return;
    broker.publish("uagv/v2/PlantAGV/" + std::string(plan.serial) + "/order",
                   hal::as_bytes(*encoded), false);
  };

  std::fprintf(out, "fleet-sim %s: %s\n", scenario.name, scenario.description);
  std::vector<bool> ordered(agvs.size(), false);
  std::vector<std::vector<AgvSample>> samples(agvs.size());
  std::vector<double> own_sensor_s(agvs.size(), -1), first_advice_s(agvs.size(), -1);
  // The AGV as it would have driven without the centre: its route at its speed from its order.
  // When its scanner would first have had a person in range is what the advice must beat.
  std::vector<double> unadvised_sensor_s(agvs.size(), -1);
  auto unadvised_pose = [&](std::size_t i, double t_s) {
    const AgvPlan& plan = scenario.agvs[i];
    double left = std::max(0.0, t_s - plan.order_s) * plan.speed_m_s;
    for (std::size_t k = 0; k + 1 < plan.route.size(); ++k) {
      const msg::Point2D a = plan.route[k], b = plan.route[k + 1];
      const double length = std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
      const double heading = std::atan2(b.y_m - a.y_m, b.x_m - a.x_m);
      if (left <= length || k + 2 == plan.route.size()) {
        const double f = std::min(1.0, left / length);
        return msg::Pose2D{a.x_m + f * (b.x_m - a.x_m), a.y_m + f * (b.y_m - a.y_m), heading};
      }
      left -= length;
    }
    return msg::Pose2D{plan.route.front().x_m, plan.route.front().y_m, 0.0};
  };
  double min_agv_person_m = 1e9;
  std::vector<Snapshot> shots;
  auto snapshot = [&](double t_s, const std::string& label) {
    Snapshot s;
    s.t_s = t_s;
    s.label = label;
    for (const RobotRun& r : robots) {
      const nav::Pose2D p = r.board->simulation().truth().pose;
      s.robots.push_back({p.x_m, p.y_m, p.theta_rad});
    }
    for (const auto& a : agvs) s.agvs.push_back({a->x(), a->y(), a->theta()});
    const GroundTruth& truth = robots.front().board->simulation().truth();
    for (std::size_t i = 0; i < truth.people_count; ++i) s.people.push_back({truth.people[i].x_m, truth.people[i].y_m});
    shots.push_back(std::move(s));
  };
  std::size_t events_seen = 0;
  bool shot_coalition = false, shot_advice = false;
  double next_agv_s = 0, next_centre_s = 0, next_sample_s = 0, next_progress_s = 0;
  hal::Nanos now = 0;
  const auto steps = static_cast<std::int64_t>(scenario.duration_s * 1e9 / static_cast<double>(kSliceNs));
  for (std::int64_t step = 0; step < steps; ++step) {
    for (RobotRun& r : robots) {
      if (Status s = r.fw->scheduler().run_lockstep(*r.board->lockstep_clock(), kSliceNs); !s)
        return fail(err, r.serial + ": " + s.error().c_str(), 1);
    }
    now += kSliceNs;
    const double t_s = static_cast<double>(now) * 1e-9;
    const std::int64_t unix_ns = kEpochUnixNs + now;
    for (std::size_t i = 0; i < agvs.size(); ++i)
      if (!ordered[i] && t_s >= scenario.agvs[i].order_s) {
        send_agv_order(scenario.agvs[i], unix_ns);
        ordered[i] = true;
      }
    const GroundTruth& truth = robots.front().board->simulation().truth();
    std::vector<msg::Point2D> people;
    for (std::size_t i = 0; i < truth.people_count; ++i) people.push_back({truth.people[i].x_m, truth.people[i].y_m});
    if (t_s + 1e-9 >= next_agv_s) {
      next_agv_s += kAgvStepS;
      for (std::size_t i = 0; i < agvs.size(); ++i) {
        SimAgv& a = *agvs[i];
        a.step(now, unix_ns, kAgvStepS, people);
        for (const msg::Point2D& p : people) {
          const double d = std::hypot(p.x_m - a.x(), p.y_m - a.y());
          min_agv_person_m = std::min(min_agv_person_m, d);
          // When the AGV's own scanner could first have seen a person: within its range, ahead.
          const double bearing = std::remainder(std::atan2(p.y_m - a.y(), p.x_m - a.x()) - a.theta(), 2 * kPi);
          if (own_sensor_s[i] < 0 && d < a.config().sensor_range_m && std::abs(bearing) < kPi / 6) own_sensor_s[i] = t_s;
        }
        if (first_advice_s[i] < 0 && a.advice() != Advice::clear) first_advice_s[i] = t_s;
        const msg::Pose2D ghost = unadvised_pose(i, t_s);
        for (const msg::Point2D& p : people) {
          const double d = std::hypot(p.x_m - ghost.x_m, p.y_m - ghost.y_m);
          const double bearing = std::remainder(std::atan2(p.y_m - ghost.y_m, p.x_m - ghost.x_m) - ghost.theta_rad, 2 * kPi);
          if (unadvised_sensor_s[i] < 0 && ordered[i] && d < a.config().sensor_range_m && std::abs(bearing) < kPi / 6)
            unadvised_sensor_s[i] = t_s;
        }
      }
    }
    if (t_s + 1e-9 >= next_centre_s) {
      next_centre_s += kCentreStepS;
      (*service)->step(now, unix_ns);
      for (; events_seen < (*service)->event_lines().size(); ++events_seen) {
        const std::string& line = (*service)->event_lines()[events_seen];
        std::fprintf(out, "  %s\n", line.c_str());
        if (!shot_coalition && line.find("\"type\":\"coalition\"") != std::string::npos) {
          snapshot(t_s, "a coalition forms");
          shot_coalition = true;
        }
      }
    }
    for (std::size_t i = 0; i < agvs.size(); ++i)
      if (!shot_advice && first_advice_s[i] >= 0) {
        snapshot(t_s, "the AGV gets the centre's advice");
        shot_advice = true;
      }
    drain_capture();
    if (t_s + 1e-9 >= next_sample_s) {
      next_sample_s += 0.5;
      for (std::size_t i = 0; i < agvs.size(); ++i)
        samples[i].push_back({t_s, agvs[i]->x(), agvs[i]->y(), agvs[i]->speed(), agvs[i]->advice()});
      for (RobotRun& r : robots) {
        const nav::Pose2D p = r.board->simulation().truth().pose;
        r.trail.push_back({p.x_m, p.y_m});
      }
    }
    if (t_s + 1e-9 >= next_progress_s) {
      next_progress_s += 10.0;
      std::fprintf(out, "  t=%5.1f s of %.0f s", t_s, scenario.duration_s);
      for (std::size_t i = 0; i < agvs.size(); ++i)
        std::fprintf(out, "  %s (%.1f, %.1f) %.2f m/s %s", scenario.agvs[i].serial, agvs[i]->x(), agvs[i]->y(), agvs[i]->speed(),
                     std::string(vda5050::to_string(agvs[i]->advice())).c_str());
      std::fprintf(out, "\n");
      std::fflush(out);
    }
  }
  snapshot(scenario.duration_s, "the end");
  for (RobotRun& r : robots) r.fw->shutdown();
  if (event_log != nullptr) std::fclose(event_log);
  std::fclose(quiet);

  // Results and the scenario's own checks.
  std::vector<std::string> failures;
  auto count_events = [&](const char* type, const char* area, const char* robot = nullptr) {
    std::size_t n = 0;
    for (const std::string& line : (*service)->event_lines()) {
      if (line.find(std::string("\"type\":\"") + type + "\"") == std::string::npos) continue;
      if (area != nullptr && line.find(std::string("\"area\":\"") + area + "\"") == std::string::npos) continue;
      if (robot != nullptr && line.find(std::string("\"") + robot + "\"") == std::string::npos) continue;
      ++n;
    }
    return n;
  };
  // The advice's lead on the AGV's own scanner; the scanner may never have had a person in range.
  const bool never_in_range = own_sensor_s[0] < 0;
  const double lead_s = first_advice_s[0] < 0 || never_in_range ? 0.0 : own_sensor_s[0] - first_advice_s[0];
  if (min_agv_person_m < 1.0) failures.push_back("an AGV came within 1 m of a person");
  if (scenario.name == std::string("net-1")) {
    if (first_advice_s[0] < 0) failures.push_back("the AGV was never advised");
    if (first_advice_s[0] >= 0 && own_sensor_s[0] >= 0 && first_advice_s[0] >= own_sensor_s[0])
      failures.push_back("the advice came after the AGV's own scanner could have seen the person");
    if (unadvised_sensor_s[0] < 0) failures.push_back("unadvised, the AGV would never have met the person: the scenario shows nothing");
    if (first_advice_s[0] >= 0 && unadvised_sensor_s[0] >= 0 && first_advice_s[0] >= unadvised_sensor_s[0])
      failures.push_back("the advice came after the unadvised AGV's scanner would have seen the person");
  } else if (scenario.name == std::string("net-2")) {
    if (count_events("allocation", "cross", "r1") == 0 || count_events("allocation", "cross", "r2") == 0)
      failures.push_back("both robots should have gone to the blind intersection");
  } else if (scenario.name == std::string("net-3")) {
    if (count_events("release", "bench") == 0) failures.push_back("no robot was released from the workstation");
    if (count_events("allocation", "dock") == 0) failures.push_back("no robot went to the next monitoring request");
  }

  std::fprintf(out, "\nresult %s: %s", scenario.name, failures.empty() ? "ok" : "FAILED");
  for (const std::string& f : failures) std::fprintf(out, "; %s", f.c_str());
  if (unadvised_sensor_s[0] >= 0)
    std::fprintf(out, "  without the advice its scanner would first have had the person in range at %.1f s (the advice led by %.1f s)\n",
                 unadvised_sensor_s[0], unadvised_sensor_s[0] - first_advice_s[0]);
  if (never_in_range) {
    std::fprintf(out, "\n  first advice to the AGV %.1f s; no person ever came within its own scanner's range; closest AGV-person %.2f m\n",
                 first_advice_s[0], min_agv_person_m);
  } else {
    std::fprintf(out, "\n  first advice to the AGV %.1f s, its own scanner first in range %.1f s (lead %.1f s), closest AGV-person %.2f m\n",
                 first_advice_s[0], own_sensor_s[0], lead_s, min_agv_person_m);
  }

  if (!report_dir.empty()) {
    std::string json;
    json.reserve(64 * 1024);
    json += "{\n  \"scenario\": \"" + std::string(scenario.name) + "\",\n  \"ok\": " + (failures.empty() ? "true" : "false") + ",\n";
    json += "  \"failures\": [";
    for (std::size_t i = 0; i < failures.size(); ++i) json += (i ? ", \"" : "\"") + failures[i] + "\"";
    json += "],\n";
    char line[512];
    auto number_or_null = [](bool known, double value) {
      if (!known) return std::string("null");
      char text[32];
      std::snprintf(text, sizeof text, "%.2f", value);
      return std::string(text);
    };
    std::snprintf(line, sizeof line, "  \"min_agv_person_distance_m\": %.3f,\n", min_agv_person_m);
    json += line;
    // null: never (no advice; no person within the AGV's own scanner's range).
    json += "  \"first_advice_s\": " + number_or_null(first_advice_s[0] >= 0, first_advice_s[0]) + ",\n";
    json += "  \"agv_own_sensor_first_s\": " + number_or_null(!never_in_range, own_sensor_s[0]) + ",\n";
    json += "  \"advice_lead_s\": " + number_or_null(first_advice_s[0] >= 0 && !never_in_range, lead_s) + ",\n";
    json += "  \"unadvised_own_sensor_first_s\": " + number_or_null(unadvised_sensor_s[0] >= 0, unadvised_sensor_s[0]) + ",\n";
    json += "  \"timeline\": [\n";
    const auto& lines = (*service)->event_lines();
    for (std::size_t i = 0; i < lines.size(); ++i) json += "    " + lines[i] + (i + 1 < lines.size() ? ",\n" : "\n");
    json += "  ],\n  \"agvs\": [\n";
    for (std::size_t i = 0; i < agvs.size(); ++i) {
      json += "    {\"serial\": \"" + std::string(scenario.agvs[i].serial) + "\", \"samples\": [";
      for (std::size_t k = 0; k < samples[i].size(); ++k) {
        const AgvSample& s = samples[i][k];
        std::snprintf(line, sizeof line, "%s{\"t_s\": %.1f, \"x\": %.2f, \"y\": %.2f, \"speed_m_s\": %.3f, \"advice\": \"%s\"}",
                      k ? ", " : "", s.t_s, s.x, s.y, s.speed, std::string(vda5050::to_string(s.advice)).c_str());
        json += line;
      }
      json += std::string("]}") + (i + 1 < agvs.size() ? ",\n" : "\n");
    }
    json += "  ],\n";
    const ssc::ServiceCounters& c = (*service)->counters();
    std::snprintf(line, sizeof line,
                  "  \"centre\": {\"states\": %llu, \"people_reports\": %llu, \"orders_sent\": %llu, \"cancels_sent\": %llu, "
                  "\"advisories_sent\": %llu, \"rejected\": %llu}\n}\n",
                  static_cast<unsigned long long>(c.states), static_cast<unsigned long long>(c.people_reports),
                  static_cast<unsigned long long>(c.orders_sent), static_cast<unsigned long long>(c.cancels_sent),
                  static_cast<unsigned long long>(c.advisories_sent), static_cast<unsigned long long>(c.rejected));
    json += line;
    if (!write_text(report_dir + "/report.json", json)) return fail(err, "cannot write " + report_dir + "/report.json", 1);
    for (std::size_t i = 0; i < shots.size(); ++i) {
      const std::string png = report_dir + "/site_" + std::to_string(i + 1) + ".png";
      if (!draw_site(png, std::string("fleet-sim ") + scenario.name, *map, *site, robots, scenario.agvs, shots[i]))
        return fail(err, "cannot write " + png, 1);
    }
    std::fprintf(out, "report: %s/report.json, %s/events.jsonl, %zu figures\n", report_dir.c_str(), report_dir.c_str(), shots.size());
  }
  return failures.empty() ? 0 : 3;
}

}  // namespace sen3bot::sim
