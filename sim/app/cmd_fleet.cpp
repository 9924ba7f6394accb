// sen3bot-sim fleet-sim: the source's three fleet scenarios in lockstep. Several whole robots
// (each its firmware over its own simulated board, with the same scripted people in every
// robot's world), plant AGVs speaking VDA 5050, the Sensors Synergy Centre, and the plant's
// master control giving the AGVs their orders, all on one in-process broker with MQTT
// semantics. The report: the centre's event log as a timeline, the AGVs' speeds, the closest
// any AGV came to a person, when the centre's advice reached the AGV against when its own
// scanner could first have seen the person, and figures of the site at the key moments.
//
// --realtime: the same scenario as separate programs (robots, AGVs, the centre) on a Mosquitto
// started here, paced by the wall clock; the master control and an observer run in this process.
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

#include "cli_util.hpp"
#include "config.hpp"
#include "firmware.hpp"
#include "fleet_scenario.hpp"
#include "sen3bot/hal/pubsub.hpp"
#include "sen3bot/json/json.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/sim/agv.hpp"
#include "sen3bot/sim/sim_board.hpp"
#include "sen3bot/sim/sim_config.hpp"
#include "sen3bot/ssc/service.hpp"
#include "sen3bot/world/world.hpp"
#include "sim_commands.hpp"

namespace sen3bot::sim {

using namespace fleet;

namespace {

struct FleetOptions {
  std::string scenario_name;
  std::string site_path = SEN3BOT_SOURCE_DIR "/config/fleet/site.yaml";
  std::string config_path = SEN3BOT_SOURCE_DIR "/config/fleet/robot.yaml";
  std::string report_dir;
  std::string capture_dir;
  bool realtime = false;
};

// -1: go on; otherwise the command's exit status (--list, --help, a bad argument).
int parse_options(int argc, char** argv, std::FILE* out, std::FILE* err, FleetOptions& o) {
  for (int i = 0; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&]() -> std::string {
      if (i + 1 >= argc) return {};
      return argv[++i];
    };
    if (arg == "--scenario") {
      o.scenario_name = value();
    } else if (arg == "--site") {
      o.site_path = value();
    } else if (arg == "--config") {
      o.config_path = value();
    } else if (arg == "--report") {
      o.report_dir = value();
    } else if (arg == "--capture") {
      o.capture_dir = value();
    } else if (arg == "--realtime") {
      o.realtime = true;
    } else if (arg == "--list") {
      for (const FleetScenario& s : scenarios()) std::fprintf(out, "%-6s %s\n", s.name, s.description);
      return 0;
    } else if (arg == "--help" || arg == "-h") {
      std::fprintf(out, "usage: sen3bot-sim fleet-sim --scenario net-1|net-2|net-3 [--realtime] [--report DIR] [--capture DIR] "
                   "[--site FILE] [--config FILE] | --list\n");
      return 0;
    } else {
      return fail(err, "unknown argument '" + arg + "' (try --help)");
    }
  }
  return -1;
}

// Each of the scenario's robots: its firmware over its own simulated board, from its home on
// the site, with the scenario's people in its world, on the site's broker. 0, or the exit status.
int start_robots(const FleetScenario& scenario, const ssc::SiteFile& site, const SimulatedRobot& base,
                 hal::MemoryBroker& broker, std::FILE* quiet, std::vector<RobotRun>& robots, std::FILE* err) {
  robots.reserve(scenario.robots.size());
  for (const char* serial : scenario.robots) {
    const auto it = std::find(site.robot_serials.begin(), site.robot_serials.end(), serial);
    if (it == site.robot_serials.end()) return fail(err, std::string("the site has no robot ") + serial);
    const ssc::RobotHome& home = site.site.robots[static_cast<std::size_t>(it - site.robot_serials.begin())];
    RobotRun& run = robots.emplace_back();
    run.serial = serial;
    run.config = base.firmware;
    run.config.fleet.serial_number = serial;
    run.config.navigation.mcl.initial_pose = home.pose;
    run.config.navigation.people_enabled = true;
    run.config.navigation.people_detector = "sim";
    run.config.tasks["detector"].arena_bytes = 4 * 1024;
    run.config.tasks["people"].arena_bytes = 64 * 1024;
    SimulationConfig world = base.world;
    world.start_pose = home.pose;
    world.movers = scenario.people;
    world.detector.enabled = true;
    auto board = SimBoard::create(world, true);
    if (!board) return fail(err, board.error().c_str(), 1);
    run.board = std::move(board.value());
    run.board->set_site_broker(&broker);
    run.fw = std::make_unique<firmware::Firmware>(run.config, *run.board, quiet);
    if (Status s = run.fw->init(); !s) return fail(err, std::string(serial) + ": " + s.error().c_str(), 1);
  }
  return 0;
}

// The plant's AGVs, each at the start of its route, on the broker. 0, or the exit status.
int start_agvs(const FleetScenario& scenario, const ssc::SiteFile& site, hal::MemoryBroker& broker,
               std::vector<std::unique_ptr<SimAgv>>& agvs, std::FILE* err) {
  for (const AgvPlan& plan : scenario.agvs) {
    SimAgvConfig c;
    c.serial_number = plan.serial;
    c.map_id = site.service.map_id;
    c.version = site.service.version;
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
  return 0;
}

// --capture: every message on the broker, as DIR/TOPIC.N.json (TOPIC its last level, or people /
// advisory), for checking against the schemas.
class BrokerCapture {
 public:
  Status open(hal::MemoryBroker& broker, const std::string& dir) {
    dir_ = dir;
    hal::PubSubOptions everything;
    everything.client_id = "capture";
    everything.subscriptions = {{"#", 1}};
    everything.inbound_slots = 1024;
    everything.max_payload = 16 * 1024;
    auto client = broker.connect(everything);
    if (!client) return client.error();
    client_ = std::move(client.value());
    return Status::success();
  }
  void drain() {
    if (!client_) return;
    for (;;) {
      auto m = client_->receive(topic_, payload_);
      if (!m || !m.value()) return;
      const std::string topic(topic_.data(), m.value()->topic_size);
      std::string leaf = topic.substr(topic.rfind('/') + 1);
      if (topic.starts_with("sen3bot/v1/people/")) leaf = "people";
      if (topic.starts_with("sen3bot/v1/advisory/")) leaf = "advisory";
      const std::string path = dir_ + "/" + leaf + "." + std::to_string(++captured_[leaf]) + ".json";
      (void)write_text(path, std::string(reinterpret_cast<const char*>(payload_.data()), m.value()->payload_size));
    }
  }

 private:
  std::string dir_;
  std::unique_ptr<hal::PubSub> client_;
  std::map<std::string, int> captured_;
  std::vector<char> topic_ = std::vector<char>(256);
  std::vector<std::uint8_t> payload_ = std::vector<std::uint8_t>(64 * 1024);
};

// What the scenario judges of each AGV: when its own scanner could first have seen a person
// (within range, ahead), when the centre's advice first reached it, when its scanner would first
// have had a person in range had it driven unadvised, and the closest it came to anyone.
struct AgvWatch {
  std::vector<double> own_sensor_s, first_advice_s, unadvised_sensor_s;
  double min_agv_person_m = 1e9;

  explicit AgvWatch(std::size_t agvs) : own_sensor_s(agvs, -1), first_advice_s(agvs, -1), unadvised_sensor_s(agvs, -1) {}

  void observe(std::size_t i, const SimAgv& a, const AgvPlan& plan, bool ordered, const std::vector<msg::Point2D>& people,
               double t_s) {
    const auto ahead_in_range = [&](double x, double y, double theta, const msg::Point2D& p) {
      const double d = std::hypot(p.x_m - x, p.y_m - y);
      const double bearing = std::remainder(std::atan2(p.y_m - y, p.x_m - x) - theta, 2 * kPi);
      return d < a.config().sensor_range_m && std::abs(bearing) < kPi / 6;
    };
    for (const msg::Point2D& p : people) {
      min_agv_person_m = std::min(min_agv_person_m, std::hypot(p.x_m - a.x(), p.y_m - a.y()));
      if (own_sensor_s[i] < 0 && ahead_in_range(a.x(), a.y(), a.theta(), p)) own_sensor_s[i] = t_s;
    }
    if (first_advice_s[i] < 0 && a.advice() != Advice::clear) first_advice_s[i] = t_s;
    const msg::Pose2D ghost = unadvised_pose(plan, t_s);
    for (const msg::Point2D& p : people)
      if (unadvised_sensor_s[i] < 0 && ordered && ahead_in_range(ghost.x_m, ghost.y_m, ghost.theta_rad, p))
        unadvised_sensor_s[i] = t_s;
  }
};

Snapshot take_snapshot(double t_s, const std::string& label, const std::vector<RobotRun>& robots,
                       const std::vector<std::unique_ptr<SimAgv>>& agvs) {
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
  return s;
}

void print_result(const FleetScenario& scenario, const std::vector<std::string>& failures, const AgvWatch& watch,
                  std::FILE* out) {
  const bool never_in_range = watch.own_sensor_s[0] < 0;
  const double first_advice_s = watch.first_advice_s[0];
  std::fprintf(out, "\nresult %s: %s", scenario.name, failures.empty() ? "ok" : "FAILED");
  for (const std::string& f : failures) std::fprintf(out, "; %s", f.c_str());
  if (watch.unadvised_sensor_s[0] >= 0)
    std::fprintf(out, "  without the advice its scanner would first have had the person in range at %.1f s (the advice led by %.1f s)\n",
                 watch.unadvised_sensor_s[0], watch.unadvised_sensor_s[0] - first_advice_s);
  if (never_in_range) {
    std::fprintf(out, "\n  first advice to the AGV %.1f s; no person ever came within its own scanner's range; closest AGV-person %.2f m\n",
                 first_advice_s, watch.min_agv_person_m);
  } else {
    const double lead_s = first_advice_s < 0 ? 0.0 : watch.own_sensor_s[0] - first_advice_s;
    std::fprintf(out, "\n  first advice to the AGV %.1f s, its own scanner first in range %.1f s (lead %.1f s), closest AGV-person %.2f m\n",
                 first_advice_s, watch.own_sensor_s[0], lead_s, watch.min_agv_person_m);
  }
}

// report.json (the scenario's result, the centre's timeline, the AGVs' samples and the centre's
// counters) and one site figure per snapshot. 0, or the exit status.
int write_lockstep_report(const std::string& dir, const FleetScenario& scenario, const std::vector<std::string>& failures,
                          const AgvWatch& watch, const ssc::Service& service,
                          const std::vector<std::vector<AgvSample>>& samples, const std::vector<Snapshot>& shots,
                          const nav::OccupancyMap& map, const ssc::SiteFile& site, const std::vector<RobotRun>& robots,
                          std::FILE* out, std::FILE* err) {
  const bool never_in_range = watch.own_sensor_s[0] < 0;
  std::string json;
  json.reserve(64 * 1024);
  json::StringSink sink(json);
  json::Writer w(sink, json::Style::spaced);
  write_report_head(w, {.scenario = scenario.name,
                        .failures = &failures,
                        .min_agv_person_m = watch.min_agv_person_m,
                        .first_advice_s = watch.first_advice_s[0],
                        .own_sensor_s = watch.own_sensor_s[0],
                        .lead_s = watch.first_advice_s[0] < 0 || never_in_range
                                      ? 0.0
                                      : watch.own_sensor_s[0] - watch.first_advice_s[0],
                        .unadvised_sensor_s = watch.unadvised_sensor_s[0],
                        .never_in_range = never_in_range});
  write_timeline(w, service.event_lines());
  write_agv_samples(w, scenario, samples);
  const ssc::ServiceCounters& c = service.counters();
  w.line(2).key("centre").begin_object()
      .member_uint64("states", c.states)
      .member_uint64("people_reports", c.people_reports)
      .member_uint64("orders_sent", c.orders_sent)
      .member_uint64("cancels_sent", c.cancels_sent)
      .member_uint64("advisories_sent", c.advisories_sent)
      .member_uint64("rejected", c.rejected)
      .end_object()
      .line(0)
      .end_object();
  if (auto written = w.finish(); !written) return fail(err, std::string("report.json: ") + written.error().c_str(), 1);
  json += '\n';
  if (!write_text(dir + "/report.json", json)) return fail(err, "cannot write " + dir + "/report.json", 1);
  for (std::size_t i = 0; i < shots.size(); ++i) {
    const std::string png = dir + "/site_" + std::to_string(i + 1) + ".png";
    if (!draw_site(png, std::string("fleet-sim ") + scenario.name, map, site, robots, scenario.agvs, shots[i]))
      return fail(err, "cannot write " + png, 1);
  }
  std::fprintf(out, "report: %s/report.json, %s/events.jsonl, %zu figures\n", dir.c_str(), dir.c_str(), shots.size());
  return 0;
}

}  // namespace

int fleet_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  FleetOptions o;
  if (const int rc = parse_options(argc, argv, out, err, o); rc >= 0) return rc;
  const std::vector<FleetScenario> all = scenarios();
  const auto found = std::find_if(all.begin(), all.end(), [&](const FleetScenario& s) { return o.scenario_name == s.name; });
  if (found == all.end()) return fail(err, "--scenario: expected net-1, net-2 or net-3, got '" + o.scenario_name + "'");
  const FleetScenario& scenario = *found;
  if (!o.report_dir.empty() && ::mkdir(o.report_dir.c_str(), 0755) != 0 && errno != EEXIST)
    return fail(err, "--report: cannot create " + o.report_dir + ": " + std::strerror(errno), 1);
  if (!o.capture_dir.empty() && ::mkdir(o.capture_dir.c_str(), 0755) != 0 && errno != EEXIST)
    return fail(err, "--capture: cannot create " + o.capture_dir + ": " + std::strerror(errno), 1);

  Result<ssc::SiteFile> site = ssc::load_site(o.site_path);
  if (!site) return fail(err, site.error().c_str());
  Result<SimulatedRobot> base = load_simulated_robot(o.config_path);
  if (!base) return fail(err, base.error().c_str());
  Result<nav::OccupancyMap> map = nav::load_map(base->world.map_path);
  if (!map) return fail(err, map.error().c_str(), 1);
  if (o.realtime) {
    if (!o.capture_dir.empty()) return fail(err, "--capture is for the lockstep mode");
    return fleet_realtime(scenario, *site, o.site_path, o.config_path, *map, o.report_dir, out, err);
  }

  hal::MemoryBroker broker;
  std::FILE* quiet = std::fopen("/dev/null", "w");
  std::vector<RobotRun> robots;
  if (const int rc = start_robots(scenario, *site, *base, broker, quiet, robots, err); rc != 0) return rc;
  std::FILE* event_log = o.report_dir.empty() ? nullptr : std::fopen((o.report_dir + "/events.jsonl").c_str(), "w");
  hal::PubSubOptions centre_link;
  centre_link.client_id = "ssc";
  centre_link.subscriptions = ssc::Service::subscriptions(site->service);
  centre_link.inbound_slots = 1024;
  auto centre_client = broker.connect(centre_link);
  if (!centre_client) return fail(err, centre_client.error().c_str(), 1);
  auto service = ssc::Service::create(*site, std::move(centre_client.value()), event_log);
  if (!service) return fail(err, service.error().c_str(), 1);
  std::vector<std::unique_ptr<SimAgv>> agvs;
  if (const int rc = start_agvs(scenario, *site, broker, agvs, err); rc != 0) return rc;
  BrokerCapture capture;
  if (!o.capture_dir.empty())
    if (Status s = capture.open(broker, o.capture_dir); !s) return fail(err, s.error().c_str(), 1);

  std::fprintf(out, "fleet-sim %s: %s\n", scenario.name, scenario.description);
  std::vector<bool> ordered(agvs.size(), false);
  std::vector<std::vector<AgvSample>> samples(agvs.size());
  AgvWatch watch(agvs.size());
  std::vector<Snapshot> shots;
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
    // The plant's master control: each AGV's order, as a VDA 5050 order of its route.
    for (std::size_t i = 0; i < agvs.size(); ++i)
      if (!ordered[i] && t_s >= scenario.agvs[i].order_s) {
        const std::string text = plant_order_text(scenario.agvs[i], *site, unix_ns);
        if (!text.empty()) broker.publish(plant_topic(scenario.agvs[i], "order"), hal::as_bytes(text), false);
        ordered[i] = true;
      }
    const GroundTruth& truth = robots.front().board->simulation().truth();
    std::vector<msg::Point2D> people;
    for (std::size_t i = 0; i < truth.people_count; ++i) people.push_back({truth.people[i].x_m, truth.people[i].y_m});
    if (t_s + 1e-9 >= next_agv_s) {
      next_agv_s += kAgvStepS;
      for (std::size_t i = 0; i < agvs.size(); ++i) {
        agvs[i]->step(now, unix_ns, kAgvStepS, people);
        watch.observe(i, *agvs[i], scenario.agvs[i], ordered[i], people, t_s);
      }
    }
    if (t_s + 1e-9 >= next_centre_s) {
      next_centre_s += kCentreStepS;
      (*service)->step(now, unix_ns);
      for (; events_seen < (*service)->event_lines().size(); ++events_seen) {
        const std::string& line = (*service)->event_lines()[events_seen];
        std::fprintf(out, "  %s\n", line.c_str());
        if (!shot_coalition && line.find("\"type\":\"coalition\"") != std::string::npos) {
          shots.push_back(take_snapshot(t_s, "a coalition forms", robots, agvs));
          shot_coalition = true;
        }
      }
    }
    for (std::size_t i = 0; i < agvs.size(); ++i)
      if (!shot_advice && watch.first_advice_s[i] >= 0) {
        shots.push_back(take_snapshot(t_s, "the AGV gets the centre's advice", robots, agvs));
        shot_advice = true;
      }
    capture.drain();
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
  shots.push_back(take_snapshot(scenario.duration_s, "the end", robots, agvs));
  for (RobotRun& r : robots) r.fw->shutdown();
  if (event_log != nullptr) std::fclose(event_log);
  std::fclose(quiet);

  // Results and the scenario's own checks.
  const std::vector<std::string> failures =
      scenario_failures(scenario, (*service)->event_lines(), watch.first_advice_s[0], watch.own_sensor_s[0],
                        watch.unadvised_sensor_s[0], watch.min_agv_person_m);
  print_result(scenario, failures, watch, out);
  if (!o.report_dir.empty())
    if (const int rc = write_lockstep_report(o.report_dir, scenario, failures, watch, **service, samples, shots, *map, *site,
                                             robots, out, err);
        rc != 0)
      return rc;
  return failures.empty() ? 0 : 3;
}

}  // namespace sen3bot::sim
