// The Sensors Synergy Centre under a fleet's load, through a real Mosquitto on loopback.
//
//   sen3bot_fleet_load [--robots 50] [--agvs 100] [--seconds 60] [--step-hz 20]
//                      [--people-hz 10] [--robot-state-hz 1] [--agv-state-hz 1]
//                      [--threads 4] [--seed 1]
//
// One process: the broker as a child process (tests/support/mosquitto_broker.hpp, plain
// listener), the centre (ssc::Service over hal::open_mqtt, stepping on a thread of its own
// as firmware/cmd_ssc.cpp does), one MQTT client per robot and per AGV (each with the network
// thread hal::open_mqtt gives it) driven by a few publisher threads, and an advisory subscriber
// standing in for the plant's AGV coordination centre.
//
// Robots send their people report (QoS 1, 10 Hz) and their VDA 5050 state (1 Hz); most
// report nobody or a person walking near their home, away from every area. A precomputed,
// seeded timeline of incidents puts a person inside an area, reported by one of the robots
// nearest to it, for 1 to 2 s; the next incident at the same area waits until the centre's
// track has timed out. AGVs send VDA 5050 state (QoS 1, 1 Hz) with a route of nodeStates
// through one area, coming and going 2 to 6 m before it.
//
// Printed: (a) end to end, from the people message that first holds an incident's person
// (taken just before publish()) to the subscriber taking the advisory about that area for each
// AGV whose route crosses it; (b) the Service's own advisory_latencies(); (c) messages sent
// and taken by the centre; (d) CPU of the centre's thread, of its link's network thread and of
// the broker, over the measured window.
#include <dirent.h>
#include <pthread.h>
#include <sys/resource.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <fstream>
#include <map>
#include <memory>
#include <mutex>
#include <random>
#include <set>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "mosquitto_broker.hpp"
#include "sen3bot/hal/pubsub.hpp"
#include "sen3bot/ssc/service.hpp"
#include "sen3bot/vda5050/codec.hpp"
#include "sen3bot/vda5050/extensions.hpp"

namespace {

using namespace sen3bot;
using Clock = std::chrono::steady_clock;
constexpr double kPi = 3.14159265358979323846;

std::int64_t steady_ns() {
  return std::chrono::duration_cast<std::chrono::nanoseconds>(Clock::now().time_since_epoch()).count();
}
std::int64_t unix_ns() {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}
double thread_cpu_s() {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<double>(ts.tv_sec) + static_cast<double>(ts.tv_nsec) * 1e-9;
}

// utime + stime (s) of a process or of one of our threads, from /proc.
double proc_cpu_s(const std::string& stat_path) {
  std::ifstream in(stat_path);
  std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  const std::size_t close = text.rfind(')');
  if (close == std::string::npos) return -1;
  std::istringstream rest(text.substr(close + 2));
  std::string field;
  std::vector<std::string> fields;
  while (rest >> field) fields.push_back(field);
  if (fields.size() < 13) return -1;  // fields[0] is state (field 3); utime is field 14
  const double ticks = static_cast<double>(sysconf(_SC_CLK_TCK));
  return (std::stod(fields[11]) + std::stod(fields[12])) / ticks;
}

std::set<int> own_threads() {
  std::set<int> out;
  if (DIR* dir = opendir("/proc/self/task")) {
    while (dirent* e = readdir(dir))
      if (e->d_name[0] != '.') out.insert(std::atoi(e->d_name));
    closedir(dir);
  }
  return out;
}

// Our child named mosquitto.
int broker_pid() {
  const int self = getpid();
  int found = -1;
  if (DIR* dir = opendir("/proc")) {
    while (dirent* e = readdir(dir)) {
      if (e->d_name[0] < '0' || e->d_name[0] > '9') continue;
      std::ifstream in(std::string("/proc/") + e->d_name + "/stat");
      std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
      const std::size_t open = text.find('('), close = text.rfind(')');
      if (open == std::string::npos || close == std::string::npos) continue;
      int ppid = 0;
      char state = 0;
      if (std::sscanf(text.c_str() + close + 2, "%c %d", &state, &ppid) != 2) continue;
      if (ppid == self && text.substr(open + 1, close - open - 1) == "mosquitto") found = std::atoi(e->d_name);
    }
    closedir(dir);
  }
  return found;
}

struct Percentiles {
  std::size_t n = 0;
  double p50 = 0, p95 = 0, p99 = 0, max = 0, mean = 0;
};
Percentiles percentiles(std::vector<double> v) {
  Percentiles p;
  p.n = v.size();
  if (v.empty()) return p;
  std::sort(v.begin(), v.end());
  auto rank = [&](double q) { return v[std::min(v.size() - 1, static_cast<std::size_t>(std::ceil(q * static_cast<double>(v.size()))) - 1)]; };
  p.p50 = rank(0.50);
  p.p95 = rank(0.95);
  p.p99 = rank(0.99);
  p.max = v.back();
  double sum = 0;
  for (double x : v) sum += x;
  p.mean = sum / static_cast<double>(v.size());
  return p;
}
void print_ms(const char* what, const Percentiles& p) {
  std::printf("  %-44s n=%-6zu p50 %7.2f  p95 %7.2f  p99 %7.2f  max %7.2f  mean %7.2f ms\n", what, p.n, p.p50 * 1e3,
              p.p95 * 1e3, p.p99 * 1e3, p.max * 1e3, p.mean * 1e3);
}

struct Options {
  int robots = 50;
  int agvs = 100;
  double seconds = 60;
  double step_hz = 20;
  double people_hz = 10;
  double robot_state_hz = 1;
  double agv_state_hz = 1;
  int threads = 4;
  unsigned seed = 1;
};

// --- the site -------------------------------------------------------------------------------

constexpr double kHallY = 150;  // m; homes and areas spread over 300 m x 150 m
constexpr int kAreas = 8;
constexpr double kAreaHalf = 3;  // areas are 6 m x 6 m squares

struct AreaPlan {
  std::string name;
  double cx = 0, cy = 0;
  std::vector<int> near_robots;  // the three nearest homes: who reports its incidents
  std::vector<int> agvs;         // AGVs whose route crosses it first
};
struct RobotPlan {
  std::string serial;
  double x = 0, y = 0, theta = 0;
  bool walker = false;  // reports a person walking near its home, outside every area
  double walk_phase = 0;
  std::vector<int> incidents;
};
struct AgvPlan {
  std::string serial;
  int area = 0;
  double dx = 1, dy = 0;  // direction of travel, through the area's centre
  double phase = 0;
};
struct Incident {
  int area = 0;
  int robot = 0;
  std::int64_t start_ns = 0;  // from t0
  std::int64_t end_ns = 0;
  double px = 0, py = 0;
  std::uint32_t local_track = 0;
  std::atomic<std::int64_t> first_sent{0};  // steady ns of the first message holding the person
};

struct Plan {
  std::vector<AreaPlan> areas;
  std::vector<RobotPlan> robots;
  std::vector<AgvPlan> agvs;
  std::vector<std::unique_ptr<Incident>> incidents;
};

Plan make_plan(const Options& o) {
  Plan plan;
  std::mt19937 rng(o.seed);
  std::uniform_real_distribution<double> u01(0, 1);
  for (int i = 0; i < kAreas; ++i) {
    AreaPlan a;
    a.name = "area-" + std::to_string(i);
    a.cx = 37.5 + 75.0 * (i % 4);
    a.cy = 37.5 + 75.0 * (i / 4);
    plan.areas.push_back(a);
  }
  const int cols = 10;
  const int rows = (o.robots + cols - 1) / cols;
  for (int r = 0; r < o.robots; ++r) {
    RobotPlan rp;
    char serial[32];
    std::snprintf(serial, sizeof serial, "s3b-%03d", r);
    rp.serial = serial;
    rp.x = 15 + 30.0 * (r % cols);
    rp.y = (kHallY / rows) * (r / cols + 0.5);
    rp.theta = 0;
    rp.walker = u01(rng) < 0.2;
    rp.walk_phase = 2 * kPi * u01(rng);
    plan.robots.push_back(rp);
  }
  for (AreaPlan& a : plan.areas) {
    std::vector<std::pair<double, int>> by_distance;
    for (int r = 0; r < o.robots; ++r) by_distance.emplace_back(std::hypot(plan.robots[r].x - a.cx, plan.robots[r].y - a.cy), r);
    std::sort(by_distance.begin(), by_distance.end());
    for (std::size_t k = 0; k < 3 && k < by_distance.size(); ++k) a.near_robots.push_back(by_distance[k].second);
  }
  for (int g = 0; g < o.agvs; ++g) {
    AgvPlan ap;
    char serial[32];
    std::snprintf(serial, sizeof serial, "agv-%03d", g);
    ap.serial = serial;
    ap.area = g % kAreas;
    const double heading = 2 * kPi * u01(rng);
    ap.dx = std::cos(heading);
    ap.dy = std::sin(heading);
    ap.phase = 2 * kPi * u01(rng);
    plan.areas[static_cast<std::size_t>(ap.area)].agvs.push_back(g);
    plan.agvs.push_back(ap);
  }
  // Incidents: per area, idle 0.5-2.5 s, a person for 1-2 s, then 3 s for the track to time out
  // (people_timeout_s 2) and the CLEAR to go out before the next one may start.
  const auto ns = [](double s) { return static_cast<std::int64_t>(s * 1e9); };
  std::uint32_t local = 1000;
  for (int i = 0; i < kAreas; ++i) {
    double t = 1.0 + 2.0 * u01(rng);
    for (;;) {
      const double start = t + 0.5 + 2.0 * u01(rng);
      const double length = 1.0 + u01(rng);
      if (start + length + 3.0 > o.seconds) break;
      auto inc = std::make_unique<Incident>();
      inc->area = i;
      const AreaPlan& a = plan.areas[static_cast<std::size_t>(i)];
      inc->robot = a.near_robots[static_cast<std::size_t>(rng() % a.near_robots.size())];
      inc->start_ns = ns(start);
      inc->end_ns = ns(start + length);
      inc->px = a.cx + (u01(rng) - 0.5) * 3.0;
      inc->py = a.cy + (u01(rng) - 0.5) * 3.0;
      inc->local_track = local++;
      plan.robots[static_cast<std::size_t>(inc->robot)].incidents.push_back(static_cast<int>(plan.incidents.size()));
      plan.incidents.push_back(std::move(inc));
      t = start + length + 3.0;
    }
  }
  return plan;
}

std::string site_yaml(const Plan& plan) {
  std::ostringstream y;
  y << "map_id: map\nversion: 2.1.0\nrobot_manufacturer: Sen3Bot\nareas:\n";
  static const char* kTypes[] = {"\"1.1\"", "\"1.2\"", "\"2\""};
  for (std::size_t i = 0; i < plan.areas.size(); ++i) {
    const AreaPlan& a = plan.areas[i];
    y << "  - name: " << a.name << "\n    type: " << kTypes[i % 3] << "\n    outline: [[" << a.cx - kAreaHalf << ", "
      << a.cy - kAreaHalf << "], [" << a.cx + kAreaHalf << ", " << a.cy - kAreaHalf << "], [" << a.cx + kAreaHalf << ", "
      << a.cy + kAreaHalf << "], [" << a.cx - kAreaHalf << ", " << a.cy + kAreaHalf << "]]\n    sentries: [[" << a.cx + 5
      << ", " << a.cy << ", 180], [" << a.cx - 5 << ", " << a.cy << ", 0]]\n";
  }
  y << "robots:\n";
  for (const RobotPlan& r : plan.robots) y << "  - serial: " << r.serial << "\n    home: [" << r.x << ", " << r.y << ", 0]\n";
  y << "centre:\n  people_timeout_s: 2\n  slow_distance_m: 12\n  stop_distance_m: 3\n";
  return y.str();
}

// Where AGV g stands at time t (s): 5 to 9 m before its area's centre, coming and going.
void agv_pose(const Plan& plan, int g, double t, double& x, double& y, double& d) {
  const AgvPlan& a = plan.agvs[static_cast<std::size_t>(g)];
  const AreaPlan& area = plan.areas[static_cast<std::size_t>(a.area)];
  d = 7.0 + 2.0 * std::sin(2 * kPi * t / 20.0 + a.phase);
  x = area.cx - a.dx * d;
  y = area.cy - a.dy * d;
}
// The nodes still ahead: 4 m before the centre, the centre, 8 m and 15 m past it.
std::vector<ssc::Point> agv_route(const Plan& plan, int g) {
  const AgvPlan& a = plan.agvs[static_cast<std::size_t>(g)];
  const AreaPlan& area = plan.areas[static_cast<std::size_t>(a.area)];
  std::vector<ssc::Point> route;
  for (double s : {-4.0, 0.0, 8.0, 15.0}) route.push_back({area.cx + a.dx * s, area.cy + a.dy * s});
  return route;
}

// --- messages ---------------------------------------------------------------------------------

struct Encoder {
  vda5050::State state;
  vda5050::PeopleMessage people;
  vda5050::Connection connection;
  std::array<char, 16 * 1024> out{};
};

std::span<const std::uint8_t> bytes(std::string_view text) {
  return {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()};
}

std::string_view encode_robot_state(Encoder& e, const RobotPlan& r, std::uint32_t header) {
  vda5050::State& s = e.state;
  s = vda5050::State{};
  s.header.header_id = header;
  s.header.timestamp = vda5050::iso8601(unix_ns());
  (void)s.header.manufacturer.assign("Sen3Bot");
  (void)s.header.serial_number.assign(r.serial);
  vda5050::AgvPosition p;
  p.position_initialized = true;
  p.x = r.x;
  p.y = r.y;
  p.theta = r.theta;
  (void)p.map_id.assign("map");
  s.agv_position = p;
  s.battery.battery_charge = 90;
  auto text = vda5050::encode_state(s, vda5050::Version::v2_1_0, e.out);
  return text ? *text : std::string_view();
}

std::string_view encode_agv_state(Encoder& e, const Plan& plan, int g, double t, std::uint32_t header) {
  const AgvPlan& a = plan.agvs[static_cast<std::size_t>(g)];
  vda5050::State& s = e.state;
  s = vda5050::State{};
  s.header.header_id = header;
  s.header.timestamp = vda5050::iso8601(unix_ns());
  (void)s.header.manufacturer.assign("PlantAGV");
  (void)s.header.serial_number.assign(a.serial);
  (void)s.order_id.assign("plant-" + a.serial);
  (void)s.last_node_id.assign("n0");
  const std::vector<ssc::Point> route = agv_route(plan, g);
  for (std::size_t i = 0; i < route.size(); ++i) {
    vda5050::NodeState n;
    char id[32];
    std::snprintf(id, sizeof id, "n%zu", i + 1);
    (void)n.node_id.assign(id);
    n.sequence_id = static_cast<std::uint32_t>(2 * (i + 1));
    n.released = true;
    n.position = vda5050::NodePosition{route[i].x_m, route[i].y_m, std::nullopt, 0.1, 0.0, {}};
    (void)n.position->map_id.assign("map");
    (void)s.node_states.push_back(n);
  }
  double x = 0, y = 0, d = 0;
  agv_pose(plan, g, t, x, y, d);
  vda5050::AgvPosition p;
  p.position_initialized = true;
  p.x = x;
  p.y = y;
  p.theta = std::atan2(a.dy, a.dx);
  (void)p.map_id.assign("map");
  s.agv_position = p;
  s.velocity = vda5050::Velocity{0.6, 0, 0};
  s.driving = true;
  s.battery.battery_charge = 80;
  auto text = vda5050::encode_state(s, vda5050::Version::v2_1_0, e.out);
  return text ? *text : std::string_view();
}

// A robot's people report at time t (s from t0); *first_of collects incidents seen for the first time.
std::string_view encode_people(Encoder& e, const Plan& plan, int r, double t, std::int64_t t_ns, std::uint32_t header,
                               std::vector<int>& showing) {
  const RobotPlan& rp = plan.robots[static_cast<std::size_t>(r)];
  vda5050::PeopleMessage& m = e.people;
  m = vda5050::PeopleMessage{};
  m.header_id = header;
  m.timestamp = vda5050::iso8601(unix_ns());
  (void)m.manufacturer.assign("Sen3Bot");
  (void)m.serial_number.assign(rp.serial);
  (void)m.map_id.assign("map");
  m.robot_valid = true;
  m.robot_x = rp.x;
  m.robot_y = rp.y;
  m.robot_theta = rp.theta;
  if (rp.walker) {
    // Round a 1 m circle 3 m from home, at 0.5 m/s: outside every area.
    const double w = 0.5, a = w * t + rp.walk_phase;
    vda5050::PersonReport p;
    p.id = 1;
    p.x = rp.x + 3.0 + std::cos(a);
    p.y = rp.y + std::sin(a);
    p.vx = -w * std::sin(a);
    p.vy = w * std::cos(a);
    p.width = 0.5;
    p.cage_radius = 0.8;
    p.dynamic = true;
    p.laser_points = 12;
    (void)m.people.push_back(p);
  }
  showing.clear();
  for (int i : rp.incidents) {
    const Incident& inc = *plan.incidents[static_cast<std::size_t>(i)];
    if (t_ns < inc.start_ns || t_ns >= inc.end_ns) continue;
    vda5050::PersonReport p;
    p.id = inc.local_track;
    p.x = inc.px;
    p.y = inc.py;
    p.width = 0.5;
    p.cage_radius = 0.6;
    p.laser_points = 9;
    if (m.people.push_back(p)) showing.push_back(i);
  }
  auto text = vda5050::encode_people(m, e.out);
  return text ? *text : std::string_view();
}

std::string_view encode_online(Encoder& e, const std::string& manufacturer, const std::string& serial) {
  vda5050::Connection& c = e.connection;
  c = vda5050::Connection{};
  c.header.timestamp = vda5050::iso8601(unix_ns());
  (void)c.header.manufacturer.assign(manufacturer);
  (void)c.header.serial_number.assign(serial);
  c.state = vda5050::ConnectionState::online;
  auto text = vda5050::encode_connection(c, vda5050::Version::v2_1_0, e.out);
  return text ? *text : std::string_view();
}

// --- the decision step alone, every capacity full ---------------------------------------------

// kMaxRobots robots online, kMaxAgvs AGVs with kMaxRouteNodes-node routes zigzagging over a
// grid of kMaxAreas areas, kMaxTracks people (a quarter inside areas): Centre::step's time.
void full_capacity_step(unsigned seed) {
  using namespace ssc;
  std::mt19937 rng(seed);
  std::uniform_real_distribution<double> u01(0, 1);
  Site site;
  const int cols = 8;
  for (std::size_t i = 0; i < kMaxAreas; ++i) {
    Area a;
    a.id = static_cast<AreaId>(i);
    a.name.format("a%zu", i);
    a.type = static_cast<AreaType>(i % 3);
    const double cx = 20.0 + 30.0 * static_cast<double>(i % cols), cy = 20.0 + 30.0 * static_cast<double>(i / cols);
    for (int k = 0; k < 8; ++k) {  // octagons
      const double ang = 2 * kPi * k / 8;
      (void)a.outline.push_back({cx + 4 * std::cos(ang), cy + 4 * std::sin(ang)});
    }
    (void)a.sentries.push_back({cx + 6, cy, kPi});
    (void)site.areas.push_back(a);
  }
  for (std::size_t r = 0; r < kMaxRobots; ++r) {
    RobotHome h;
    h.robot = static_cast<RobotId>(r);
    h.name.format("r%zu", r);
    h.pose = {5.0 + 3.7 * static_cast<double>(r), 5.0 + 60.0 * static_cast<double>(r % 3), 0};
    (void)site.robots.push_back(h);
  }
  auto centre = Centre::create(site);
  if (!centre) {
    std::fprintf(stderr, "full capacity: %s\n", centre.error().c_str());
    return;
  }
  Centre& c = *centre.value();
  for (std::size_t r = 0; r < kMaxRobots; ++r) {
    (void)c.set_online(static_cast<RobotId>(r), true, 0);
    RobotReport rr;
    rr.robot = static_cast<RobotId>(r);
    rr.pose = site.robots[r].pose;
    rr.battery = 90;
    (void)c.update_robot(rr);
  }
  auto report = std::make_unique<AgvReport>();
  for (std::size_t g = 0; g < kMaxAgvs; ++g) {
    *report = AgvReport{};
    report->agv = static_cast<AgvId>(g);
    report->name.format("g%zu", g);
    double x = 240 * u01(rng), y = 120 * u01(rng);
    report->pose = {x, y, 0};
    for (std::size_t k = 0; k < kMaxRouteNodes; ++k) {
      x = std::clamp(x + 20 * (u01(rng) - 0.5), 0.0, 240.0);
      y = std::clamp(y + 20 * (u01(rng) - 0.5), 0.0, 120.0);
      (void)report->route.push_back({x, y});
    }
    (void)c.update_agv(*report);
  }
  // kMaxTracks people, one per robot report slot: two per robot, a quarter inside areas.
  std::vector<PersonObservation> people;
  for (std::size_t i = 0; i < kMaxTracks; ++i) {
    if (i % 4 == 0) {
      const Area& a = site.areas[i % kMaxAreas];
      const Point mid = centroid(a.outline.as_span());
      people.push_back({mid.x_m + u01(rng), mid.y_m + u01(rng), 0, 0, static_cast<std::uint32_t>(i)});
    } else {
      people.push_back({240 * u01(rng), 120 * u01(rng), 0, 0, static_cast<std::uint32_t>(i)});
    }
  }
  auto pr = std::make_unique<PeopleReport>();
  std::vector<double> times, feed;
  for (int step = 0; step < 300; ++step) {
    const Nanos now = hal::Nanos{step} * 100'000'000;
    const std::int64_t f0 = steady_ns();
    for (std::size_t r = 0; r < kMaxRobots; ++r) {
      *pr = PeopleReport{};
      pr->robot = static_cast<RobotId>(r);
      pr->stamp = now;
      for (std::size_t i = r; i < people.size(); i += kMaxRobots) (void)pr->people.push_back(people[i]);
      c.add_people(*pr);
    }
    const std::int64_t t0 = steady_ns();
    (void)c.step(now);
    const std::int64_t t1 = steady_ns();
    if (step >= 10) {
      times.push_back(static_cast<double>(t1 - t0) * 1e-9);
      feed.push_back(static_cast<double>(t0 - f0) * 1e-9);
    }
  }
  std::printf("Centre::step at full capacity: %zu robots, %zu AGVs with %zu-node routes, %zu areas (octagons), %zu tracks (%zu people)\n",
              kMaxRobots, kMaxAgvs, kMaxRouteNodes, kMaxAreas, c.people().tracks().size(), people.size());
  print_ms("Centre::step", percentiles(times));
  print_ms("PeopleMap: one report from every robot", percentiles(feed));
  std::printf("  coalitions %zu; the centre object is %zu KiB\n", c.coalitions().size(), sizeof(Centre) / 1024);
}

// --- the run ----------------------------------------------------------------------------------

enum class Kind { people, robot_state, agv_state };
struct Emitter {
  Kind kind;
  int index;           // robot or AGV
  hal::PubSub* link;
  std::string topic;
  std::int64_t period_ns;
  std::int64_t next_ns;  // steady
  std::uint32_t header = 0;
  std::uint64_t sent = 0;
  std::uint64_t refused = 0;
};

struct Advised {
  std::mutex mutex;
  std::vector<double> latencies;            // s
  std::vector<std::vector<double>> by_incident;  // s, per incident
  std::vector<std::vector<bool>> matched;   // [agv][incident]
  std::uint64_t advisories = 0, clears = 0, not_clear = 0, unmatched = 0, again = 0, undecodable = 0;
};

bool parse(int argc, char** argv, Options& o) {
  for (int i = 1; i < argc; ++i) {
    const std::string a = argv[i];
    if (i + 1 >= argc) return false;
    const char* v = argv[++i];
    if (a == "--robots") o.robots = std::atoi(v);
    else if (a == "--agvs") o.agvs = std::atoi(v);
    else if (a == "--seconds") o.seconds = std::atof(v);
    else if (a == "--step-hz") o.step_hz = std::atof(v);
    else if (a == "--people-hz") o.people_hz = std::atof(v);
    else if (a == "--robot-state-hz") o.robot_state_hz = std::atof(v);
    else if (a == "--agv-state-hz") o.agv_state_hz = std::atof(v);
    else if (a == "--threads") o.threads = std::atoi(v);
    else if (a == "--seed") o.seed = static_cast<unsigned>(std::atoi(v));
    else return false;
  }
  return o.robots > 0 && o.robots <= static_cast<int>(ssc::kMaxRobots) && o.agvs > 0 && o.agvs <= static_cast<int>(ssc::kMaxAgvs) &&
         o.seconds >= 10 && o.step_hz > 0 && o.people_hz > 0 && o.threads > 0;
}

int run(const Options& o) {
  Plan plan = make_plan(o);

  // The site file, as the centre's host would load it.
  char dir[] = "/tmp/sen3bot-fleet-load-XXXXXX";
  if (mkdtemp(dir) == nullptr) return 1;
  const std::string site_path = std::string(dir) + "/site.yaml";
  std::ofstream(site_path) << site_yaml(plan);
  auto site = ssc::load_site(site_path);
  std::remove(site_path.c_str());
  rmdir(dir);
  if (!site) {
    std::fprintf(stderr, "site: %s\n", site.error().c_str());
    return 1;
  }
  // Every AGV's route must meet its own area first, within the slow distance.
  for (int g = 0; g < o.agvs; ++g) {
    double x = 0, y = 0, d = 0;
    std::vector<ssc::Point> path{{0, 0}};
    for (double t : {0.0, 5.0, 10.0, 15.0}) {
      agv_pose(plan, g, t, x, y, d);
      path[0] = {x, y};
      path.resize(1);
      for (const ssc::Point& p : agv_route(plan, g)) path.push_back(p);
      const ssc::Crossings c = ssc::crossings(site->site, path);
      if (c.empty() || c[0].area != static_cast<ssc::AreaId>(plan.agvs[static_cast<std::size_t>(g)].area) ||
          c[0].entry > site->centre.slow_distance) {
        std::fprintf(stderr, "plan: AGV %d's route does not meet its area first within the slow distance\n", g);
        return 1;
      }
    }
  }
  // Every message we send must decode as the centre decodes it.
  {
    Encoder e;
    vda5050::DecodeScratch scratch;
    auto decoded = std::make_unique<vda5050::State>();
    auto people = std::make_unique<vda5050::PeopleMessage>();
    std::vector<int> showing;
    const std::string agv(encode_agv_state(e, plan, 0, 0, 0));
    const std::string robot(encode_robot_state(e, plan.robots[0], 0));
    const std::string report(encode_people(e, plan, 0, 0, plan.incidents.empty() ? 0 : plan.incidents[0]->start_ns, 0, showing));
    if (agv.empty() || robot.empty() || report.empty() || !vda5050::decode_state(agv, vda5050::Version::v2_1_0, *decoded, scratch) ||
        !vda5050::decode_state(robot, vda5050::Version::v2_1_0, *decoded, scratch) || !vda5050::decode_people(report, *people, scratch)) {
      std::fprintf(stderr, "a generated message does not decode\n");
      return 1;
    }
    std::printf("message sizes: people report %zu B, robot state %zu B, AGV state %zu B\n", report.size(),
                robot.size(), agv.size());
  }

  full_capacity_step(o.seed);
  std::fflush(stdout);  // before the broker's fork
  auto broker = testing::MosquittoBroker::plain();
  broker.start();
  const int mosquitto = broker_pid();

  // The centre's link, configured as firmware/cmd_ssc.cpp configures it, but subscribing to
  // states at QoS 1 too (Service::subscriptions asks QoS 0 for states, as VDA 5050 does).
  hal::PubSubOptions centre_options;
  centre_options.url = broker.url();
  centre_options.client_id = "ssc";
  centre_options.subscriptions = ssc::Service::subscriptions(site->service);
  for (auto& s : centre_options.subscriptions) s.qos = 1;
  centre_options.inbound_slots = 512;
  centre_options.outbound_slots = 256;
  const std::set<int> before = own_threads();
  auto centre_link = hal::open_mqtt(centre_options);
  if (!centre_link) {
    std::fprintf(stderr, "centre link: %s\n", centre_link.error().c_str());
    return 1;
  }
  int centre_net_tid = -1;
  for (int tid : own_threads())
    if (!before.contains(tid)) centre_net_tid = tid;
  auto created = ssc::Service::create(*site, std::move(centre_link.value()), nullptr);
  if (!created) {
    std::fprintf(stderr, "service: %s\n", created.error().c_str());
    return 1;
  }
  ssc::Service& service = **created;

  // The AGV coordination centre's side: every advisory.
  hal::PubSubOptions sub_options;
  sub_options.url = broker.url();
  sub_options.client_id = "agvcc";
  sub_options.subscriptions = {{"sen3bot/v1/advisory/+/+", 1}};
  sub_options.inbound_slots = 1024;
  auto sub_link = hal::open_mqtt(sub_options);
  if (!sub_link) return 1;

  // One client per robot and per AGV.
  std::vector<std::unique_ptr<hal::PubSub>> links;
  std::vector<Emitter> emitters;
  std::mt19937 rng(o.seed + 7);
  const auto period = [](double hz) { return static_cast<std::int64_t>(1e9 / hz); };
  for (int r = 0; r < o.robots; ++r) {
    hal::PubSubOptions c;
    c.url = broker.url();
    c.client_id = plan.robots[static_cast<std::size_t>(r)].serial;
    c.inbound_slots = 1;
    c.outbound_slots = 16;
    c.max_payload = 16 * 1024;
    auto l = hal::open_mqtt(c);
    if (!l) return 1;
    const std::string& serial = plan.robots[static_cast<std::size_t>(r)].serial;
    emitters.push_back({Kind::people, r, l.value().get(), vda5050::people_topic("Sen3Bot", serial), period(o.people_hz), 0, 0, 0, 0});
    if (o.robot_state_hz > 0)
      emitters.push_back({Kind::robot_state, r, l.value().get(), "uagv/v2/Sen3Bot/" + serial + "/state", period(o.robot_state_hz), 0, 0, 0, 0});
    links.push_back(std::move(l.value()));
  }
  for (int g = 0; g < o.agvs; ++g) {
    hal::PubSubOptions c;
    c.url = broker.url();
    c.client_id = plan.agvs[static_cast<std::size_t>(g)].serial;
    c.inbound_slots = 1;
    c.outbound_slots = 16;
    c.max_payload = 16 * 1024;
    auto l = hal::open_mqtt(c);
    if (!l) return 1;
    emitters.push_back({Kind::agv_state, g, l.value().get(), "uagv/v2/PlantAGV/" + plan.agvs[static_cast<std::size_t>(g)].serial + "/state",
                        period(o.agv_state_hz), 0, 0, 0, 0});
    links.push_back(std::move(l.value()));
  }
  // Everyone connected, then ONLINE (retained, QoS 1) from every vehicle.
  const std::int64_t connect_deadline = steady_ns() + 20'000'000'000;
  for (;;) {
    bool all = service.link().state() == hal::PubSubState::connected && sub_link.value()->state() == hal::PubSubState::connected;
    for (const auto& l : links) all = all && l->state() == hal::PubSubState::connected;
    if (all) break;
    if (steady_ns() > connect_deadline) {
      std::fprintf(stderr, "not every client connected within 20 s\n");
      return 1;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  {
    Encoder e;
    for (int r = 0; r < o.robots; ++r)
      (void)links[static_cast<std::size_t>(r)]->publish("uagv/v2/Sen3Bot/" + plan.robots[static_cast<std::size_t>(r)].serial + "/connection",
                                                        bytes(encode_online(e, "Sen3Bot", plan.robots[static_cast<std::size_t>(r)].serial)), 1, true);
    for (int g = 0; g < o.agvs; ++g)
      (void)links[static_cast<std::size_t>(o.robots + g)]->publish(
          "uagv/v2/PlantAGV/" + plan.agvs[static_cast<std::size_t>(g)].serial + "/connection",
          bytes(encode_online(e, "PlantAGV", plan.agvs[static_cast<std::size_t>(g)].serial)), 1, true);
  }

  // t0: incidents are timed from here; publishers start 2 s before, so the centre knows every
  // vehicle and has sent its first CLEARs when the measured window opens.
  const std::int64_t warmup = 2'000'000'000;
  const std::int64_t t0 = steady_ns() + warmup + 200'000'000;
  const std::int64_t t_end = t0 + static_cast<std::int64_t>(o.seconds * 1e9);
  std::atomic<bool> stop_publishers{false}, stop_centre{false}, stop_sub{false};

  // The centre, as the host program runs it: step, sleep to the next period, skip missed ones.
  std::vector<double> step_s;
  step_s.reserve(static_cast<std::size_t>(o.seconds * o.step_hz * 1.5) + 200);
  double cpu0 = -1, cpu1 = -1;
  std::int64_t cpu0_at = 0, cpu1_at = 0;
  std::uint64_t overruns = 0;
  std::atomic<std::uint64_t> taken_people{0}, taken_states{0};  // the centre's counters, for the main thread
  std::thread centre([&] {
    pthread_setname_np(pthread_self(), "ssc-centre");
    const std::int64_t p = period(o.step_hz);
    std::int64_t next = steady_ns();
    while (!stop_centre.load()) {
      const std::int64_t now = steady_ns();
      if (cpu0 < 0 && now >= t0) {
        cpu0 = thread_cpu_s();
        cpu0_at = now;
      }
      if (cpu1 < 0 && now >= t_end) {
        cpu1 = thread_cpu_s();
        cpu1_at = now;
      }
      service.step(now, unix_ns());
      const std::int64_t done = steady_ns();
      taken_people.store(service.counters().people_reports);
      taken_states.store(service.counters().states);
      if (now >= t0 && now < t_end) step_s.push_back(static_cast<double>(done - now) * 1e-9);
      next += p;
      if (done > next) {
        ++overruns;
        next = done + p - (done - next) % p;
      }
      std::this_thread::sleep_until(Clock::time_point(std::chrono::nanoseconds(next)));
    }
  });

  // The subscriber.
  Advised advised;
  advised.by_incident.assign(plan.incidents.size(), {});
  advised.matched.assign(static_cast<std::size_t>(o.agvs), std::vector<bool>(plan.incidents.size(), false));
  std::map<std::string, int> agv_of;
  for (int g = 0; g < o.agvs; ++g) agv_of[plan.agvs[static_cast<std::size_t>(g)].serial] = g;
  std::map<std::string, int> area_of;
  for (int i = 0; i < kAreas; ++i) area_of[plan.areas[static_cast<std::size_t>(i)].name] = i;
  std::vector<std::vector<int>> incidents_of(kAreas);
  for (std::size_t i = 0; i < plan.incidents.size(); ++i) incidents_of[static_cast<std::size_t>(plan.incidents[i]->area)].push_back(static_cast<int>(i));
  std::thread subscriber([&] {
    hal::PubSub& l = *sub_link.value();
    std::vector<char> topic(256);
    std::vector<std::uint8_t> payload(64 * 1024);
    vda5050::DecodeScratch scratch;
    auto m = std::make_unique<vda5050::AdvisoryMessage>();
    while (!stop_sub.load()) {
      auto got = l.receive(topic, payload);
      if (!got || !got.value()) {
        std::this_thread::sleep_for(std::chrono::microseconds(500));
        continue;
      }
      const std::int64_t arrived = steady_ns();
      const std::string_view text(reinterpret_cast<const char*>(payload.data()), got.value()->payload_size);
      std::lock_guard<std::mutex> lock(advised.mutex);
      ++advised.advisories;
      if (!vda5050::decode_advisory(text, *m, scratch).ok()) {
        ++advised.undecodable;
        continue;
      }
      if (m->advice == vda5050::AdviceKind::clear) {
        ++advised.clears;
        continue;
      }
      ++advised.not_clear;
      const auto g = agv_of.find(std::string(m->agv_serial_number.view()));
      const auto a = area_of.find(std::string(m->area_id.view()));
      if (g == agv_of.end() || a == area_of.end()) {
        ++advised.unmatched;
        continue;
      }
      // The latest incident at that area whose person has been sent.
      int latest = -1;
      for (int i : incidents_of[static_cast<std::size_t>(a->second)]) {
        const std::int64_t sent = plan.incidents[static_cast<std::size_t>(i)]->first_sent.load();
        if (sent != 0 && sent <= arrived) latest = i;
      }
      if (latest < 0) {
        ++advised.unmatched;
        continue;
      }
      std::vector<bool>& matched = advised.matched[static_cast<std::size_t>(g->second)];
      if (matched[static_cast<std::size_t>(latest)]) {
        ++advised.again;
        continue;
      }
      matched[static_cast<std::size_t>(latest)] = true;
      const double latency = static_cast<double>(arrived - plan.incidents[static_cast<std::size_t>(latest)]->first_sent.load()) * 1e-9;
      advised.latencies.push_back(latency);
      advised.by_incident[static_cast<std::size_t>(latest)].push_back(latency);
    }
  });

  // Publishers: emitters spread over a few threads, each first sent at a random phase.
  std::uniform_int_distribution<std::int64_t> phase(0, 999'999'999);
  for (Emitter& e : emitters) e.next_ns = t0 - warmup + phase(rng) % e.period_ns;
  std::vector<std::thread> publishers;
  for (int k = 0; k < o.threads; ++k) {
    publishers.emplace_back([&, k] {
      Encoder enc;
      std::vector<int> showing;
      std::vector<Emitter*> mine;
      for (std::size_t i = static_cast<std::size_t>(k); i < emitters.size(); i += static_cast<std::size_t>(o.threads)) mine.push_back(&emitters[i]);
      while (!stop_publishers.load()) {
        std::int64_t soonest = INT64_MAX;
        for (Emitter* e : mine) {
          const std::int64_t now = steady_ns();
          if (now >= e->next_ns) {
            const double t = static_cast<double>(now - t0) * 1e-9;
            std::string_view text;
            switch (e->kind) {
              case Kind::people: text = encode_people(enc, plan, e->index, t, now - t0, e->header, showing); break;
              case Kind::robot_state: text = encode_robot_state(enc, plan.robots[static_cast<std::size_t>(e->index)], e->header); break;
              case Kind::agv_state: text = encode_agv_state(enc, plan, e->index, t, e->header); break;
            }
            ++e->header;
            const std::int64_t sent_at = steady_ns();
            if (!text.empty() && e->link->publish(e->topic, bytes(text), 1, false)) {
              ++e->sent;
              for (int i : showing) {
                std::int64_t expected = 0;
                (void)plan.incidents[static_cast<std::size_t>(i)]->first_sent.compare_exchange_strong(expected, sent_at);
              }
            } else {
              ++e->refused;
            }
            e->next_ns += e->period_ns;
            if (e->next_ns < now) e->next_ns = now + e->period_ns;  // late: never a burst
          }
          soonest = std::min(soonest, e->next_ns);
        }
        // At most 50 ms, so a thread with nothing to send still sees the stop.
        std::this_thread::sleep_until(Clock::time_point(std::chrono::nanoseconds(std::min(soonest, steady_ns() + 50'000'000))));
      }
    });
  }

  // The measured window.
  std::this_thread::sleep_until(Clock::time_point(std::chrono::nanoseconds(t0)));
  rusage self0{};
  getrusage(RUSAGE_SELF, &self0);
  const double broker0 = mosquitto > 0 ? proc_cpu_s("/proc/" + std::to_string(mosquitto) + "/stat") : -1;
  const double net0 = centre_net_tid > 0 ? proc_cpu_s("/proc/self/task/" + std::to_string(centre_net_tid) + "/stat") : -1;
  const std::int64_t w0 = steady_ns();
  std::this_thread::sleep_until(Clock::time_point(std::chrono::nanoseconds(t_end)));
  const std::int64_t w1 = steady_ns();
  const double broker1 = mosquitto > 0 ? proc_cpu_s("/proc/" + std::to_string(mosquitto) + "/stat") : -1;
  const double net1 = centre_net_tid > 0 ? proc_cpu_s("/proc/self/task/" + std::to_string(centre_net_tid) + "/stat") : -1;
  rusage self1{};
  getrusage(RUSAGE_SELF, &self1);

  // Stop sending; every client hands over what it queued (QoS 1: until acknowledged).
  stop_publishers.store(true);
  for (std::thread& t : publishers) t.join();
  std::uint64_t client_losses = 0;
  for (const auto& l : links) client_losses += l->stats().connection_losses;  // before close() counts its own disconnect
  for (auto& l : links) l->close(5.0);
  std::uint64_t sent_people = 0, sent_states = 0, refused = 0;
  for (const Emitter& e : emitters) {
    (e.kind == Kind::people ? sent_people : sent_states) += e.sent;
    refused += e.refused;
  }
  std::uint64_t client_dropped = 0, client_acked = 0;
  for (const auto& l : links) {
    const hal::PubSubStats s = l->stats();
    client_dropped += s.publish_dropped + s.publish_refused;
    client_acked += s.published;
  }
  // Let the centre take the last of them.
  const std::int64_t drain_deadline = steady_ns() + 5'000'000'000;
  while (steady_ns() < drain_deadline) {
    if (taken_people.load() >= sent_people && taken_states.load() >= sent_states) break;
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  stop_centre.store(true);
  centre.join();
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  stop_sub.store(true);
  subscriber.join();

  const ssc::ServiceCounters counters = service.counters();
  const hal::PubSubStats centre_stats = service.link().stats();
  const std::uint64_t online_messages = static_cast<std::uint64_t>(o.robots + o.agvs);

  // --- report ---
  const double window = static_cast<double>(w1 - w0) * 1e-9;
  std::printf("\nSensors Synergy Centre under load: %d robots (people %.0f Hz, state %.0f Hz), %d AGVs (state %.0f Hz), "
              "centre step %.0f Hz; %.0f s measured; %d publisher threads, %zu MQTT clients; Mosquitto on loopback\n",
              o.robots, o.people_hz, o.robot_state_hz, o.agvs, o.agv_state_hz, o.step_hz, window, o.threads, links.size() + 2);
  std::size_t started = 0;
  std::size_t expected = 0, missed = 0;
  for (std::size_t i = 0; i < plan.incidents.size(); ++i) {
    const Incident& inc = *plan.incidents[i];
    if (inc.first_sent.load() == 0) continue;
    ++started;
    for (int g : plan.areas[static_cast<std::size_t>(inc.area)].agvs) {
      ++expected;
      if (!advised.matched[static_cast<std::size_t>(g)][i]) ++missed;
    }
  }
  std::printf("(a) end to end, first people message holding the person -> advisory at the subscriber\n");
  std::printf("  incidents %zu, advisories expected %zu, received %zu, missed %zu\n", started, expected, advised.latencies.size(), missed);
  print_ms("people message -> advisory, every AGV", percentiles(advised.latencies));
  std::vector<double> first_agv, last_agv;
  for (const auto& v : advised.by_incident) {
    if (v.empty()) continue;
    first_agv.push_back(*std::min_element(v.begin(), v.end()));
    last_agv.push_back(*std::max_element(v.begin(), v.end()));
  }
  print_ms("per incident, its first AGV advised", percentiles(first_agv));
  print_ms("per incident, its last AGV advised", percentiles(last_agv));
  std::printf("  advisories received %llu (CLEAR %llu, SLOW/STOP %llu; again for the same incident %llu, about no incident %llu, "
              "undecodable %llu)\n",
              static_cast<unsigned long long>(advised.advisories), static_cast<unsigned long long>(advised.clears),
              static_cast<unsigned long long>(advised.not_clear), static_cast<unsigned long long>(advised.again),
              static_cast<unsigned long long>(advised.unmatched), static_cast<unsigned long long>(advised.undecodable));
  std::printf("(b) the Service's advisory_latencies() (newest report with people, robot timestamp in 10 ms steps -> publish)\n");
  print_ms("Service::advisory_latencies()", percentiles(service.advisory_latencies()));
  std::printf("(c) messages, QoS 1 publish and subscribe\n");
  std::printf("  people reports: sent %llu, decoded by the centre %llu, lost %lld\n", static_cast<unsigned long long>(sent_people),
              static_cast<unsigned long long>(counters.people_reports),
              static_cast<long long>(sent_people) - static_cast<long long>(counters.people_reports));
  std::printf("  states (robots and AGVs): sent %llu, decoded by the centre %llu, lost %lld\n",
              static_cast<unsigned long long>(sent_states), static_cast<unsigned long long>(counters.states),
              static_cast<long long>(sent_states) - static_cast<long long>(counters.states));
  std::printf("  rejected by the centre %llu; publishers: refused %llu, queue drops %llu, acknowledged %llu (%llu ONLINE included), connection losses %llu\n",
              static_cast<unsigned long long>(counters.rejected), static_cast<unsigned long long>(refused),
              static_cast<unsigned long long>(client_dropped), static_cast<unsigned long long>(client_acked),
              static_cast<unsigned long long>(online_messages),
              static_cast<unsigned long long>(client_losses));
  std::printf("  centre link: received %llu, inbound queue drops %llu, publish drops %llu, connection losses %llu; advisories sent %llu, "
              "orders %llu, cancels %llu\n",
              static_cast<unsigned long long>(centre_stats.received), static_cast<unsigned long long>(centre_stats.receive_dropped),
              static_cast<unsigned long long>(centre_stats.publish_dropped),
              static_cast<unsigned long long>(centre_stats.connection_losses),
              static_cast<unsigned long long>(counters.advisories_sent), static_cast<unsigned long long>(counters.orders_sent),
              static_cast<unsigned long long>(counters.cancels_sent));
  std::printf("(d) CPU over the window, %% of one core\n");
  const double centre_wall = static_cast<double>(cpu1_at - cpu0_at) * 1e-9;
  if (cpu0 >= 0 && cpu1 >= 0 && centre_wall > 0)
    std::printf("  centre thread (Service::step)        %6.2f %%  (%.3f s CPU in %.1f s)\n", 100 * (cpu1 - cpu0) / centre_wall,
                cpu1 - cpu0, centre_wall);
  print_ms("Service::step duration", percentiles(step_s));
  std::printf("  steps late (overran their period)    %llu\n", static_cast<unsigned long long>(overruns));
  if (net0 >= 0 && net1 >= 0)
    std::printf("  centre link's network thread         %6.2f %%  (libmosquitto, 10 ms clock ticks)\n", 100 * (net1 - net0) / window);
  if (broker0 >= 0 && broker1 >= 0)
    std::printf("  mosquitto (pid %d)                 %6.2f %%\n", mosquitto, 100 * (broker1 - broker0) / window);
  const auto tv = [](const timeval& t) { return static_cast<double>(t.tv_sec) + static_cast<double>(t.tv_usec) * 1e-6; };
  std::printf("  this whole process (load generator, 150 client threads, centre) %6.2f %%\n",
              100 * (tv(self1.ru_utime) + tv(self1.ru_stime) - tv(self0.ru_utime) - tv(self0.ru_stime)) / window);
  double load[3] = {0, 0, 0};
  if (getloadavg(load, 3) == 3) std::printf("  machine load average at the end: %.2f %.2f %.2f (%ld cores)\n", load[0], load[1], load[2], sysconf(_SC_NPROCESSORS_ONLN));

  sub_link.value()->close(0.5);
  return missed == 0 && sent_people == counters.people_reports && sent_states == counters.states ? 0 : 3;
}

}  // namespace

int main(int argc, char** argv) {
  Options o;
  if (!parse(argc, argv, o)) {
    std::fprintf(stderr,
                 "usage: %s [--robots N<=%zu] [--agvs N<=%zu] [--seconds S>=10] [--step-hz HZ] [--people-hz HZ] "
                 "[--robot-state-hz HZ] [--agv-state-hz HZ] [--threads N] [--seed N]\n",
                 argv[0], ssc::kMaxRobots, ssc::kMaxAgvs);
    return 2;
  }
  try {
    return run(o);
  } catch (const std::exception& e) {
    std::fprintf(stderr, "%s\n", e.what());
    return 1;
  }
}
