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
#include <arpa/inet.h>
#include <dirent.h>
#include <fcntl.h>
#include <netinet/in.h>
#include <pwd.h>
#include <signal.h>
#include <sys/prctl.h>
#include <sys/socket.h>
#include <sys/stat.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

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
#include "sen3bot/hal/pubsub.hpp"
#include "sen3bot/json/json.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/sim/agv.hpp"
#include "sen3bot/figure/canvas.hpp"
#include "sen3bot/sim/sim_board.hpp"
#include "sen3bot/sim/sim_config.hpp"
#include "sen3bot/ssc/service.hpp"
#include "sen3bot/json/json.hpp"
#include "sen3bot/world/world.hpp"
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

figure::Rgb area_colour(ssc::AreaType type) {
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
  figure::Canvas canvas(w, h, {255, 255, 255});
  figure::View view{map.origin_x_m(), map.origin_y_m(), px_per_m, static_cast<double>(left), static_cast<double>(h - bottom_margin)};
  const double cell_px = map.resolution_m() * px_per_m;
  for (int row = 0; row < map.height(); ++row)
    for (int col = 0; col < map.width(); ++col)
      if (map.at(col, row) > 50) {
        const figure::Px p = view(map.origin_x_m() + col * map.resolution_m(), map.origin_y_m() + (row + 1) * map.resolution_m());
        // One pixel more than a cell, so rounding never leaves gaps between cells.
        canvas.fill_rect(static_cast<int>(p.x), static_cast<int>(p.y), static_cast<int>(std::ceil(cell_px)) + 1,
                         static_cast<int>(std::ceil(cell_px)) + 1, {60, 60, 60});
      }
  for (std::size_t i = 0; i < site.site.areas.size(); ++i) {
    const ssc::Area& a = site.site.areas[i];
    std::vector<figure::Px> outline;
    for (const ssc::Point& p : a.outline) outline.push_back(view(p.x, p.y));
    canvas.outline_polygon(outline, area_colour(a.type), 3);
    canvas.text(view(a.outline[0].x + 0.1, a.outline[0].y + 0.15), site.area_names[i] + " (" + std::string(ssc::to_string(a.type)) + ")",
                {150, 60, 60}, 0.45, 1, true);
  }
  for (const AgvPlan& plan : plans) {
    std::vector<figure::Px> route;
    for (const msg::Point2D& p : plan.route) route.push_back(view(p.x_m, p.y_m));
    canvas.dashed_polyline(route, {120, 120, 255}, 2, 10, 6);
  }
  const figure::Rgb robot_colours[] = {{0, 140, 0}, {0, 110, 200}, {170, 0, 170}};
  for (std::size_t i = 0; i < robots.size(); ++i) {
    std::vector<figure::Px> trail;
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
    const figure::Px c = view(a.x_m, a.y_m);
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
  auto entry = [&](figure::Rgb colour, const std::string& text, bool square) {
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

// The plant's master control's order for one AGV: its route as a VDA 5050 order ("" when it
// does not encode).
std::string plant_order_text(const AgvPlan& plan, const ssc::SiteFile& site, std::int64_t unix_ns) {
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
    (void)node.position->map_id.assign(site.service.map_id);
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
  auto encoded = vda5050::encode_order(*order, site.service.version, text);
  if (!encoded) return {};
  return std::string(*encoded);
}

std::string plant_topic(const AgvPlan& plan, const char* leaf) { return "uagv/v2/PlantAGV/" + std::string(plan.serial) + "/" + leaf; }

// The AGV as it would have driven without the centre: its route at its speed from its order.
msg::Pose2D unadvised_pose(const AgvPlan& plan, double t_s) {
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
}

int fail(std::FILE* err, const std::string& message, int code = 2) {
  std::fprintf(err, "sen3bot-sim fleet-sim: %s\n", message.c_str());
  return code;
}


// The scenario's own checks, the same in lockstep and in real time: no AGV within 1 m of a
// person, and what the scenario is about (net-1: the advice beats the AGV's scanner; net-2: both
// robots at the blind intersection; net-3: a robot released and sent on).
std::vector<std::string> scenario_failures(const FleetScenario& scenario, const std::vector<std::string>& events, double first_advice_s,
                                           double own_sensor_s, double unadvised_sensor_s, double min_agv_person_m) {
  auto count_events = [&](const char* type, const char* area, const char* robot = nullptr) {
    std::size_t n = 0;
    for (const std::string& line : events) {
      if (line.find(std::string("\"type\":\"") + type + "\"") == std::string::npos) continue;
      if (area != nullptr && line.find(std::string("\"area\":\"") + area + "\"") == std::string::npos) continue;
      if (robot != nullptr && line.find(std::string("\"") + robot + "\"") == std::string::npos) continue;
      ++n;
    }
    return n;
  };
  std::vector<std::string> failures;
  if (min_agv_person_m < 1.0) failures.push_back("an AGV came within 1 m of a person");
  if (scenario.name == std::string("net-1")) {
    if (first_advice_s < 0) failures.push_back("the AGV was never advised");
    if (first_advice_s >= 0 && own_sensor_s >= 0 && first_advice_s >= own_sensor_s)
      failures.push_back("the advice came after the AGV's own scanner could have seen the person");
    if (unadvised_sensor_s < 0) failures.push_back("unadvised, the AGV would never have met the person: the scenario shows nothing");
    if (first_advice_s >= 0 && unadvised_sensor_s >= 0 && first_advice_s >= unadvised_sensor_s)
      failures.push_back("the advice came after the unadvised AGV's scanner would have seen the person");
  } else if (scenario.name == std::string("net-2")) {
    if (count_events("allocation", "cross", "r1") == 0 || count_events("allocation", "cross", "r2") == 0)
      failures.push_back("both robots should have gone to the blind intersection");
  } else if (scenario.name == std::string("net-3")) {
    if (count_events("release", "bench") == 0) failures.push_back("no robot was released from the workstation");
    if (count_events("allocation", "dock") == 0) failures.push_back("no robot went to the next monitoring request");
  }
  return failures;
}

// ---- --realtime: the same scenario as separate programs on a real Mosquitto ----

bool read_text(const std::string& path, std::string& text) {
  std::FILE* f = std::fopen(path.c_str(), "r");
  if (f == nullptr) return false;
  char buffer[4096];
  for (std::size_t n; (n = std::fread(buffer, 1, sizeof buffer, f)) > 0;) text.append(buffer, n);
  std::fclose(f);
  return true;
}

std::string tail(const std::string& path, std::size_t bytes = 1500) {
  std::string text;
  if (!read_text(path, text)) return "(no output)";
  return text.size() > bytes ? "..." + text.substr(text.size() - bytes) : text;
}

int free_loopback_port() {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return -1;
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  socklen_t size = sizeof address;
  int port = -1;
  if (::bind(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0 &&
      ::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &size) == 0)
    port = ntohs(address.sin_port);
  ::close(fd);
  return port;
}

bool loopback_accepts(int port) {
  const int fd = ::socket(AF_INET, SOCK_STREAM, 0);
  if (fd < 0) return false;
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_addr.s_addr = htonl(INADDR_LOOPBACK);
  address.sin_port = htons(static_cast<std::uint16_t>(port));
  const bool ok = ::connect(fd, reinterpret_cast<sockaddr*>(&address), sizeof address) == 0;
  ::close(fd);
  return ok;
}

// The programs the realtime mode starts. Each is asked to stop with SIGTERM and killed when it
// has not ended within the grace time; the destructor does it on every way out.
class Children {
 public:
  struct Child {
    std::string name;
    pid_t pid = -1;
    std::string log;
    int status = -1;  // the exit status once reaped (128 + signal when killed)
  };
  Children() = default;
  Children(const Children&) = delete;
  Children& operator=(const Children&) = delete;
  ~Children() { stop_all(5.0); }

  // Starts argv[0] with stdout and stderr in log_path. The child also gets SIGTERM should this
  // process die first, so nothing outlives a killed fleet-sim.
  bool start(const std::string& name, const std::vector<std::string>& args, const std::string& log_path) {
    std::vector<char*> argv;
    for (const std::string& a : args) argv.push_back(const_cast<char*>(a.c_str()));
    argv.push_back(nullptr);
    const pid_t parent = ::getpid();
    const pid_t pid = ::fork();
    if (pid < 0) return false;
    if (pid == 0) {
      // Only async-signal-safe calls between fork and exec: the parent has threads.
      ::prctl(PR_SET_PDEATHSIG, SIGTERM);
      if (::getppid() != parent) ::_exit(126);
      const int fd = ::open(log_path.c_str(), O_WRONLY | O_CREAT | O_TRUNC | O_CLOEXEC, 0644);
      if (fd >= 0) {
        ::dup2(fd, 1);
        ::dup2(fd, 2);
      }
      ::execvp(argv[0], argv.data());
      ::_exit(127);
    }
    children_.push_back({name, pid, log_path, -1});
    return true;
  }

  // The first child that has ended on its own, or nullptr.
  const Child* ended() {
    for (Child& c : children_) {
      if (c.pid <= 0) continue;
      int status = 0;
      if (::waitpid(c.pid, &status, WNOHANG) == c.pid) {
        c.pid = -1;
        c.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
        return &c;
      }
    }
    return nullptr;
  }

  // SIGTERM to the children from `first` on (later ones first: the broker, started first,
  // goes last), then SIGKILL to any still running after grace_s.
  void stop_from(std::size_t first, double grace_s) {
    for (std::size_t i = children_.size(); i-- > first;)
      if (children_[i].pid > 0) ::kill(children_[i].pid, SIGTERM);
    const std::int64_t deadline = firmware::clock_ns(CLOCK_MONOTONIC) + static_cast<std::int64_t>(grace_s * 1e9);
    for (;;) {
      bool running = false;
      for (std::size_t i = first; i < children_.size(); ++i) {
        Child& c = children_[i];
        if (c.pid <= 0) continue;
        int status = 0;
        if (::waitpid(c.pid, &status, WNOHANG) == c.pid) {
          c.pid = -1;
          c.status = WIFEXITED(status) ? WEXITSTATUS(status) : 128 + WTERMSIG(status);
        } else {
          running = true;
        }
      }
      if (!running) return;
      if (firmware::clock_ns(CLOCK_MONOTONIC) >= deadline) break;
      ::usleep(20'000);
    }
    for (std::size_t i = first; i < children_.size(); ++i) {
      Child& c = children_[i];
      if (c.pid <= 0) continue;
      ::kill(c.pid, SIGKILL);
      int status = 0;
      ::waitpid(c.pid, &status, 0);
      c.pid = -1;
      c.status = 128 + SIGKILL;
    }
  }
  void stop_all(double grace_s) { stop_from(0, grace_s); }
  [[nodiscard]] std::size_t size() const noexcept { return children_.size(); }
  [[nodiscard]] const Child& operator[](std::size_t i) const { return children_[i]; }

 private:
  std::vector<Child> children_;
};

// The robot's configuration for its own process: `base` (config/fleet/robot.yaml) line by line,
// so every other setting stays the one the repository ships: real time, its serial number and
// home, the real broker, the scenario's people in its world and the people pipeline on with the
// simulated detector. Paths made absolute for the copy elsewhere.
std::string realtime_robot_config(const std::string& base_text, const std::string& base_dir, const std::string& serial,
                                  const ssc::RobotHome& home, const std::string& broker_url, double duration_s,
                                  const std::vector<world::MoverScript>& people) {
  char pose[160];
  std::snprintf(pose, sizeof pose, "{ x_m: %.3f, y_m: %.3f, theta_deg: %.2f }", home.pose.x, home.pose.y, home.pose.theta * 180.0 / kPi);
  std::string out;
  std::string section;
  std::size_t start = 0;
  while (start <= base_text.size()) {
    std::size_t end = base_text.find('\n', start);
    if (end == std::string::npos) end = base_text.size();
    std::string line = base_text.substr(start, end - start);
    start = end + 1;
    const std::size_t indent = line.find_first_not_of(' ');
    const std::size_t colon = line.find(':');
    const bool keyed = indent != std::string::npos && colon != std::string::npos && line[indent] != '#' && line[indent] != '-';
    const std::string key = keyed ? line.substr(indent, colon - indent) : std::string();
    if (keyed && indent == 0) section = key;
    const std::string lead = keyed ? line.substr(0, indent) : std::string();
    if (keyed && indent == 2) {
      if (section == "run" && key == "clock") line = lead + "clock: realtime";
      else if (section == "run" && key == "duration_s") line = lead + "duration_s: " + std::to_string(static_cast<int>(std::ceil(duration_s)));
      else if (section == "sim" && key == "start_pose") line = lead + "start_pose: " + pose;
      else if (section == "navigation" && key == "initial_pose") line = lead + "initial_pose: " + pose;
      else if (section == "fleet" && key == "broker") line = lead + "broker: " + broker_url;
      else if (section == "fleet" && key == "serial_number") line = lead + "serial_number: " + serial;
      else if ((section == "sim" || section == "navigation") && key == "map") {
        std::string path = line.substr(colon + 1);
        path = path.substr(path.find_first_not_of(' '));
        if (const std::size_t hash = path.find(" #"); hash != std::string::npos) path = path.substr(0, hash);
        while (!path.empty() && path.back() == ' ') path.pop_back();
        if (!path.empty() && path[0] != '/') path = base_dir + "/" + path;
        line = lead + "map: " + path;
      }
    }
    out += line + "\n";
    if (keyed && indent == 0 && colon + 1 == line.size()) {
      if (section == "sim") {
        out += "  detector: { enabled: true }\n";
        if (!people.empty()) out += "  people:\n";
        for (const world::MoverScript& m : people) {
          out += "    - { path: [";
          for (std::size_t i = 0; i < m.path.size(); ++i) {
            char point[64];
            std::snprintf(point, sizeof point, "%s[%.3f, %.3f]", i ? ", " : "", m.path[i].x_m, m.path[i].y_m);
            out += point;
          }
          char rest[192];
          std::snprintf(rest, sizeof rest, "], speed_m_s: %.3f, size_m: %.3f, start_s: %.3f, appear_s: %.3f, accel_m_s2: %.3f }\n",
                        m.speed_m_s, m.size_m, m.start_time_s, m.appear_time_s, m.accel_m_s2);
          out += rest;
        }
      } else if (section == "navigation") {
        out += "  people: { detector: sim }\n";
      } else if (section == "tasks") {
        out += "  detector: { arena_bytes: 4KiB }\n  people: { arena_bytes: 64KiB }\n";
      }
    }
  }
  // Several programs share the host's cores: no locked memory, no idle-state requests.
  out += "\nrealtime:\n  lock_memory: false\n  max_cpu_wakeup_latency_us: -1\n";
  return out;
}

struct LatestState {
  bool known = false;
  double t_s = 0;  // when it arrived, scenario time
  double x = 0, y = 0, theta = 0, speed = 0;
};

// The members both fleet reports open with: the scenario, its failures, the closest AGV-person
// distance and the first times (null: never).
struct ReportHead {
  std::string_view scenario;
  bool realtime = false;
  const std::vector<std::string>* failures = nullptr;
  double min_agv_person_m = 0;
  double first_advice_s = -1, own_sensor_s = 0, lead_s = 0, unadvised_sensor_s = -1;
  bool never_in_range = false;
};

void write_report_head(json::Writer& w, const ReportHead& h) {
  w.begin_object().line(2).member("scenario", h.scenario);
  if (h.realtime) w.line(2).member("mode", "realtime");
  w.line(2).member_bool("ok", h.failures->empty()).line(2).key("failures").begin_array();
  for (const std::string& f : *h.failures) w.string(f);
  w.end_array().line(2).key("min_agv_person_distance_m").fixed_or_null(h.min_agv_person_m, 3);
  const auto time_or_null = [&](std::string_view key, bool known, double value) {
    w.line(2).key(key);
    if (known) w.fixed_or_null(value, 2);
    else w.null();
  };
  time_or_null("first_advice_s", h.first_advice_s >= 0, h.first_advice_s);
  time_or_null("agv_own_sensor_first_s", !h.never_in_range, h.own_sensor_s);
  time_or_null("advice_lead_s", h.first_advice_s >= 0 && !h.never_in_range, h.lead_s);
  time_or_null("unadvised_own_sensor_first_s", h.unadvised_sensor_s >= 0, h.unadvised_sensor_s);
}

// The centre's event lines (JSON objects), one a line.
void write_timeline(json::Writer& w, const std::vector<std::string>& events) {
  w.line(2).key("timeline").begin_array();
  for (const std::string& e : events) w.line(4).raw(e);
  w.line(2).end_array();
}

void write_agv_samples(json::Writer& w, const FleetScenario& scenario, const std::vector<std::vector<AgvSample>>& samples) {
  w.line(2).key("agvs").begin_array();
  for (std::size_t i = 0; i < samples.size(); ++i) {
    w.line(4).begin_object().member("serial", scenario.agvs[i].serial).key("samples").begin_array();
    for (const AgvSample& s : samples[i]) {
      w.begin_object()
          .key("t_s").fixed_or_null(s.t_s, 1)
          .key("x").fixed_or_null(s.x, 2)
          .key("y").fixed_or_null(s.y, 2)
          .key("speed_m_s").fixed_or_null(s.speed, 3)
          .member("advice", vda5050::to_string(s.advice))
          .end_object();
    }
    w.end_array().end_object();
  }
  w.line(2).end_array();
}

int fleet_realtime(const FleetScenario& scenario, const ssc::SiteFile& site, const std::string& site_path,
                   const std::string& config_path, const nav::OccupancyMap& map, const std::string& report_dir, std::FILE* out,
                   std::FILE* err) {
  // The programs sit beside this one (the build writes sen3bot, sen3bot-sim and sen3bot-centre to
  // one folder).
  char self[4096] = {};
  const ssize_t self_size = ::readlink("/proc/self/exe", self, sizeof self - 1);
  if (self_size <= 0) return fail(err, std::string("cannot read /proc/self/exe: ") + std::strerror(errno), 1);
  std::string bin_dir(self, static_cast<std::size_t>(self_size));
  bin_dir = bin_dir.substr(0, bin_dir.rfind('/'));
  const std::string sim_bin = bin_dir + "/sen3bot-sim", centre_bin = bin_dir + "/sen3bot-centre";
  for (const std::string& bin : {sim_bin, centre_bin})
    if (::access(bin.c_str(), X_OK) != 0) return fail(err, "--realtime needs " + bin + ": " + std::strerror(errno), 1);

  char temp[] = "/tmp/sen3bot-fleet-XXXXXX";
  if (::mkdtemp(temp) == nullptr) return fail(err, std::string("mkdtemp: ") + std::strerror(errno), 1);
  const std::string work = temp;
  // The temporary folder goes on every way out; the logs stay in the report folder.
  struct RemoveDir {
    std::string path;
    ~RemoveDir() {
      if (DIR* d = ::opendir(path.c_str())) {
        while (const dirent* e = ::readdir(d))
          if (e->d_name[0] != '.') ::unlink((path + "/" + e->d_name).c_str());
        ::closedir(d);
      }
      ::rmdir(path.c_str());
    }
  } remove_work{work};
  const std::string logs = report_dir.empty() ? work : report_dir;
  const std::string event_log = logs + "/events.jsonl";
  ::unlink(event_log.c_str());  // the centre appends

  std::string base_text;
  if (!read_text(config_path, base_text)) return fail(err, "--config " + config_path + ": " + std::strerror(errno), 1);
  const std::string base_dir = config_path.find('/') == std::string::npos ? "." : config_path.substr(0, config_path.rfind('/'));

  const firmware::StopOnSignal stop;
  Children children;
  const int port = free_loopback_port();
  if (port <= 0) return fail(err, "no free loopback port", 1);
  const std::string url = "mqtt://127.0.0.1:" + std::to_string(port);
  // Run as root, Mosquitto would switch to its own user, and a change of user clears the signal
  // it gets should this process die: it stays the user it was started as.
  const passwd* user = ::getpwuid(::geteuid());
  const std::string user_line = user != nullptr ? std::string("user ") + user->pw_name + "\n" : std::string();
  if (!write_text(work + "/mosquitto.conf", "listener " + std::to_string(port) +
                                                " 127.0.0.1\nallow_anonymous true\npersistence false\nlog_dest stderr\n"
                                                "log_type error\nlog_type warning\n" + user_line))
    return fail(err, "cannot write " + work + "/mosquitto.conf", 1);
  if (!children.start("mosquitto", {"mosquitto", "-c", work + "/mosquitto.conf"}, logs + "/mosquitto.log"))
    return fail(err, std::string("cannot start mosquitto: ") + std::strerror(errno), 1);
  for (int i = 0;; ++i) {
    if (loopback_accepts(port)) break;
    if (children.ended() != nullptr || i == 500)
      return fail(err, "mosquitto did not start (is it installed?): " + tail(logs + "/mosquitto.log"), 1);
    ::usleep(10'000);
  }
  std::fprintf(out, "fleet-sim %s (realtime, Mosquitto on %s): %s\n", scenario.name, url.c_str(), scenario.description);

  // The observer: the AGVs' states and connections, the centre's advisories.
  hal::PubSubOptions watch;
  watch.url = url;
  watch.client_id = "fleet-sim-observer";
  watch.subscriptions = {{"uagv/v2/PlantAGV/+/state", 0}, {"uagv/v2/+/+/connection", 1}, {"sen3bot/v1/advisory/#", 1}};
  watch.inbound_slots = 1024;
  auto observer = hal::open_mqtt(watch);
  if (!observer) return fail(err, "observer: " + std::string(observer.error().c_str()), 1);
  // The plant's master control: its own client.
  hal::PubSubOptions master;
  master.url = url;
  master.client_id = "plant-master-control";
  auto plant = hal::open_mqtt(master);
  if (!plant) return fail(err, "master control: " + std::string(plant.error().c_str()), 1);

  const double margin_s = 30;  // the programs' own --duration: a backstop should this one vanish
  const std::string duration = std::to_string(static_cast<int>(scenario.duration_s + margin_s));
  if (!children.start("ssc", {centre_bin, "ssc", "--broker", url, "--site", site_path, "--event-log", event_log, "--duration", duration},
                      logs + "/ssc.log"))
    return fail(err, "cannot start sen3bot-centre ssc", 1);
  auto fmt = [](double v) {
    char text[32];
    std::snprintf(text, sizeof text, "%.4f", v);
    return std::string(text);
  };
  for (const AgvPlan& plan : scenario.agvs) {
    const double theta = std::atan2(plan.route[1].y_m - plan.route[0].y_m, plan.route[1].x_m - plan.route[0].x_m);
    if (!children.start(plan.serial,
                        {sim_bin, "agv", "--broker", url, "--serial", plan.serial, "--map-id", site.service.map_id, "--x",
                         fmt(plan.route[0].x_m), "--y", fmt(plan.route[0].y_m), "--theta", fmt(theta), "--speed", fmt(plan.speed_m_s),
                         "--duration", duration},
                        logs + "/" + plan.serial + ".log"))
      return fail(err, std::string("cannot start the AGV ") + plan.serial, 1);
  }

  std::vector<char> topic(256);
  std::vector<std::uint8_t> payload(64 * 1024);
  auto state = std::make_unique<vda5050::State>();
  auto scratch = std::make_unique<vda5050::DecodeScratch>();
  auto advisory = std::make_unique<vda5050::AdvisoryMessage>();
  std::vector<LatestState> latest(scenario.agvs.size());
  std::vector<Advice> advice(scenario.agvs.size(), Advice::clear);
  std::vector<double> first_advice_s(scenario.agvs.size(), -1);
  std::vector<bool> agv_online(scenario.agvs.size(), false);
  std::map<std::string, double> robots_online;
  std::int64_t t0 = 0;  // scenario time 0: when the robots start
  bool started = false;
  auto scenario_s = [&] { return started ? static_cast<double>(firmware::clock_ns(CLOCK_MONOTONIC) - t0) * 1e-9 : 0.0; };
  auto agv_index = [&](std::string_view serial) -> int {
    for (std::size_t i = 0; i < scenario.agvs.size(); ++i)
      if (serial == scenario.agvs[i].serial) return static_cast<int>(i);
    return -1;
  };
  auto drain = [&]() -> std::string {
    for (;;) {
      auto m = (*observer)->receive(topic, payload);
      if (!m) return std::string("observer: ") + m.error().c_str();
      if (!m.value()) return {};
      const std::string_view t(topic.data(), m.value()->topic_size);
      const std::string_view text(reinterpret_cast<const char*>(payload.data()), m.value()->payload_size);
      // uagv/v2/MANUFACTURER/SERIAL/LEAF and sen3bot/v1/advisory/MANUFACTURER/SERIAL
      const std::size_t leaf_at = t.rfind('/');
      const std::string_view leaf = t.substr(leaf_at + 1);
      const std::string_view before = t.substr(0, leaf_at);
      const std::string_view serial = before.substr(before.rfind('/') + 1);
      if (t.starts_with("sen3bot/v1/advisory/")) {
        const int i = agv_index(leaf);
        if (i < 0 || !vda5050::decode_advisory(text, *advisory, *scratch).ok()) continue;
        advice[static_cast<std::size_t>(i)] = advisory->advice;
        if (started && first_advice_s[static_cast<std::size_t>(i)] < 0 && advisory->advice != Advice::clear)
          first_advice_s[static_cast<std::size_t>(i)] = scenario_s();
      } else if (leaf == "connection") {
        if (text.find("\"ONLINE\"") == std::string_view::npos) continue;
        if (const int i = agv_index(serial); i >= 0) agv_online[static_cast<std::size_t>(i)] = true;
        else if (started) robots_online.emplace(std::string(serial), scenario_s());
      } else if (leaf == "state") {
        const int i = agv_index(serial);
        if (i < 0 || !vda5050::decode_state(text, site.service.version, *state, *scratch).ok() || !state->agv_position) continue;
        LatestState& s = latest[static_cast<std::size_t>(i)];
        s.known = true;
        s.t_s = scenario_s();
        s.x = state->agv_position->x;
        s.y = state->agv_position->y;
        s.theta = state->agv_position->theta;
        s.speed = state->velocity ? state->velocity->vx : 0.0;
      }
    }
  };
  auto check_children = [&]() -> std::string {
    if (const Children::Child* c = children.ended())
      return c->name + " ended early (status " + std::to_string(c->status) + "): " + tail(c->log);
    if (const int s = firmware::StopOnSignal::requested(); s != 0) return "stopped by signal " + std::to_string(s);
    return {};
  };

  // The centre and the AGVs first, online before the robots start the scenario's clock.
  for (const std::int64_t deadline = firmware::clock_ns(CLOCK_MONOTONIC) + 10'000'000'000;;) {
    if (std::string problem = drain(); !problem.empty()) return fail(err, problem, 1);
    if (std::string problem = check_children(); !problem.empty()) return fail(err, problem, 1);
    if (std::all_of(agv_online.begin(), agv_online.end(), [](bool b) { return b; })) break;
    if (firmware::clock_ns(CLOCK_MONOTONIC) > deadline) return fail(err, "the AGVs did not come online within 10 s", 1);
    ::usleep(20'000);
  }
  const std::size_t first_robot = children.size();
  std::vector<std::string> robot_configs;
  for (const char* serial : scenario.robots) {
    const auto it = std::find(site.robot_serials.begin(), site.robot_serials.end(), serial);
    if (it == site.robot_serials.end()) return fail(err, std::string("the site has no robot ") + serial);
    const ssc::RobotHome& home = site.site.robots[static_cast<std::size_t>(it - site.robot_serials.begin())];
    const std::string path = work + "/robot_" + serial + ".yaml";
    if (!write_text(path, realtime_robot_config(base_text, base_dir, serial, home, url, scenario.duration_s + margin_s, scenario.people)))
      return fail(err, "cannot write " + path, 1);
    robot_configs.push_back(path);
  }
  t0 = firmware::clock_ns(CLOCK_MONOTONIC);
  started = true;
  for (std::size_t r = 0; r < scenario.robots.size(); ++r) {
    const std::string serial = scenario.robots[r];
    if (!children.start(serial, {sim_bin, "run", "--config", robot_configs[r], "--clock", "realtime"}, logs + "/robot_" + serial + ".log"))
      return fail(err, "cannot start the robot " + serial, 1);
  }

  // The scripted people as every robot's world has them, for the distances.
  world::World people_world(map);
  for (const world::MoverScript& m : scenario.people) people_world.add_mover(m);
  const std::size_t n_agvs = scenario.agvs.size();
  std::vector<bool> ordered(n_agvs, false);
  std::vector<std::vector<AgvSample>> samples(n_agvs);
  std::vector<double> own_sensor_s(n_agvs, -1), unadvised_sensor_s(n_agvs, -1);
  double min_agv_person_m = 1e9;
  constexpr double kSensorRangeM = 2.0;  // SimAgvConfig's, which `sen3bot-sim agv` keeps
  constexpr double kStateExtrapolateS = 1.0;  // the AGVs' state period
  double next_step_s = 0, next_sample_s = 0, next_progress_s = 0;
  for (;;) {
    if (std::string problem = drain(); !problem.empty()) return fail(err, problem, 1);
    if (std::string problem = check_children(); !problem.empty()) return fail(err, problem, 1);
    const double t_s = scenario_s();
    if (t_s >= scenario.duration_s) break;
    for (std::size_t i = 0; i < n_agvs; ++i)
      if (!ordered[i] && t_s >= scenario.agvs[i].order_s) {
        const std::string text = plant_order_text(scenario.agvs[i], site, firmware::clock_ns(CLOCK_REALTIME));
        if (text.empty() || !(*plant)->publish(plant_topic(scenario.agvs[i], "order"), hal::as_bytes(text), 0, false))
          return fail(err, std::string("cannot publish the order of ") + scenario.agvs[i].serial, 1);
        ordered[i] = true;
      }
    if (t_s >= next_step_s) {
      next_step_s += kAgvStepS;
      people_world.set_time(t_s);
      std::vector<msg::Point2D> people;
      for (std::size_t k = 0; k < people_world.mover_count(); ++k)
        if (people_world.mover_visible(k)) people.push_back({people_world.mover_position(k).x_m, people_world.mover_position(k).y_m});
      for (std::size_t i = 0; i < n_agvs; ++i) {
        const LatestState& s = latest[i];
        if (s.known) {
          // Between its states the AGV drives on as it last said.
          const double ahead = std::min(kStateExtrapolateS, t_s - s.t_s) * s.speed;
          const double x = s.x + ahead * std::cos(s.theta), y = s.y + ahead * std::sin(s.theta);
          for (const msg::Point2D& p : people) {
            const double d = std::hypot(p.x_m - x, p.y_m - y);
            min_agv_person_m = std::min(min_agv_person_m, d);
            const double bearing = std::remainder(std::atan2(p.y_m - y, p.x_m - x) - s.theta, 2 * kPi);
            if (own_sensor_s[i] < 0 && d < kSensorRangeM && std::abs(bearing) < kPi / 6) own_sensor_s[i] = t_s;
          }
        }
        const msg::Pose2D ghost = unadvised_pose(scenario.agvs[i], t_s);
        for (const msg::Point2D& p : people) {
          const double d = std::hypot(p.x_m - ghost.x_m, p.y_m - ghost.y_m);
          const double bearing = std::remainder(std::atan2(p.y_m - ghost.y_m, p.x_m - ghost.x_m) - ghost.theta_rad, 2 * kPi);
          if (unadvised_sensor_s[i] < 0 && ordered[i] && d < kSensorRangeM && std::abs(bearing) < kPi / 6) unadvised_sensor_s[i] = t_s;
        }
      }
    }
    if (t_s >= next_sample_s) {
      next_sample_s += 0.5;
      for (std::size_t i = 0; i < n_agvs; ++i)
        if (latest[i].known) samples[i].push_back({t_s, latest[i].x, latest[i].y, latest[i].speed, advice[i]});
    }
    if (t_s >= next_progress_s) {
      next_progress_s += 10.0;
      std::fprintf(out, "  t=%5.1f s of %.0f s", t_s, scenario.duration_s);
      for (std::size_t i = 0; i < n_agvs; ++i)
        std::fprintf(out, "  %s (%.1f, %.1f) %.2f m/s %s", scenario.agvs[i].serial, latest[i].x, latest[i].y, latest[i].speed,
                     std::string(vda5050::to_string(advice[i])).c_str());
      std::fprintf(out, "\n");
      std::fflush(out);
    }
    ::usleep(10'000);
  }
  // The robots, the AGVs and the centre stop first, then the broker.
  children.stop_from(first_robot, 10.0);
  children.stop_from(1, 5.0);
  (*observer)->close(0.5);
  (*plant)->close(0.5);
  children.stop_all(5.0);

  // The centre's event log, its times made the scenario's (it logs its monotonic clock).
  std::vector<std::string> events;
  {
    std::string text;
    (void)read_text(event_log, text);
    const double t0_s = static_cast<double>(t0) * 1e-9;
    for (std::size_t at = 0; at < text.size();) {
      std::size_t end = text.find('\n', at);
      if (end == std::string::npos) end = text.size();
      std::string line = text.substr(at, end - at);
      at = end + 1;
      if (line.empty()) continue;
      const std::string key = "\"timeS\":";
      if (const std::size_t k = line.find(key); k != std::string::npos) {
        const std::size_t from = k + key.size();
        const std::size_t to = line.find_first_of(",}", from);
        char shifted[32];
        std::snprintf(shifted, sizeof shifted, "%.3f", std::strtod(line.substr(from, to - from).c_str(), nullptr) - t0_s);
        line.replace(from, to - from, shifted);
      }
      std::fprintf(out, "  %s\n", line.c_str());
      events.push_back(std::move(line));
    }
  }
  // The centre's counters: the JSON line it writes when it stops.
  std::string centre = "null";
  {
    std::string text;
    (void)read_text(logs + "/ssc.log", text);
    const std::size_t k = text.rfind("{\"stopped_by\"");
    if (k != std::string::npos) centre = text.substr(k, text.find('\n', k) - k);
  }

  std::vector<std::string> failures;
  const bool never_in_range = own_sensor_s[0] < 0;
  const double lead_s = first_advice_s[0] < 0 || never_in_range ? 0.0 : own_sensor_s[0] - first_advice_s[0];
  if (samples[0].empty()) failures.push_back("no state from the AGV");
  for (std::string& f : scenario_failures(scenario, events, first_advice_s[0], own_sensor_s[0], unadvised_sensor_s[0], min_agv_person_m))
    failures.push_back(std::move(f));
  std::fprintf(out, "\nresult %s (realtime): %s", scenario.name, failures.empty() ? "ok" : "FAILED");
  for (const std::string& f : failures) std::fprintf(out, "; %s", f.c_str());
  auto seconds = [](double t) {
    if (t < 0) return std::string("never");
    char text[32];
    std::snprintf(text, sizeof text, "%.2f s", t);
    return std::string(text);
  };
  std::fprintf(out, "\n  first advice to the AGV %s, its own scanner first in range %s, unadvised %s, closest AGV-person %.2f m\n",
               seconds(first_advice_s[0]).c_str(), seconds(own_sensor_s[0]).c_str(), seconds(unadvised_sensor_s[0]).c_str(),
               min_agv_person_m);

  if (!report_dir.empty()) {
    std::string json;
    json::StringSink sink(json);
    json::Writer w(sink, json::Style::spaced);
    write_report_head(w, {.scenario = scenario.name,
                          .realtime = true,
                          .failures = &failures,
                          .min_agv_person_m = min_agv_person_m,
                          .first_advice_s = first_advice_s[0],
                          .own_sensor_s = own_sensor_s[0],
                          .lead_s = lead_s,
                          .unadvised_sensor_s = unadvised_sensor_s[0],
                          .never_in_range = never_in_range});
    w.line(2).key("robots_online_s").begin_object();
    for (const auto& [serial, t] : robots_online) w.key(serial).fixed_or_null(t, 2);
    w.end_object();
    write_timeline(w, events);
    write_agv_samples(w, scenario, samples);
    w.line(2).key("centre").raw(centre).line(0).end_object();
    if (auto written = w.finish(); !written) return fail(err, std::string("report.json: ") + written.error().c_str(), 1);
    json += '\n';
    if (!write_text(report_dir + "/report.json", json)) return fail(err, "cannot write " + report_dir + "/report.json", 1);
    std::fprintf(out, "report: %s/report.json, %s/events.jsonl and the programs' logs there\n", report_dir.c_str(), report_dir.c_str());
  }
  return failures.empty() ? 0 : 3;
}

}  // namespace

int fleet_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  std::string scenario_name;
  std::string site_path = SEN3BOT_SOURCE_DIR "/config/fleet/site.yaml";
  std::string config_path = SEN3BOT_SOURCE_DIR "/config/fleet/robot.yaml";
  std::string report_dir;
  std::string capture_dir;
  bool realtime = false;
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
    } else if (arg == "--realtime") {
      realtime = true;
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
  if (realtime) {
    if (!capture_dir.empty()) return fail(err, "--capture is for the lockstep mode");
    return fleet_realtime(scenario, *site, site_path, config_path, *map, report_dir, out, err);
  }

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
    const std::string text = plant_order_text(plan, *site, unix_ns);
    if (!text.empty()) broker.publish(plant_topic(plan, "order"), hal::as_bytes(text), false);
  };

  std::fprintf(out, "fleet-sim %s: %s\n", scenario.name, scenario.description);
  std::vector<bool> ordered(agvs.size(), false);
  std::vector<std::vector<AgvSample>> samples(agvs.size());
  std::vector<double> own_sensor_s(agvs.size(), -1), first_advice_s(agvs.size(), -1);
  // The AGV as it would have driven without the centre: its route at its speed from its order.
  // When its scanner would first have had a person in range is what the advice must beat.
  std::vector<double> unadvised_sensor_s(agvs.size(), -1);
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
        const msg::Pose2D ghost = unadvised_pose(scenario.agvs[i], t_s);
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
  // The advice's lead on the AGV's own scanner; the scanner may never have had a person in range.
  const bool never_in_range = own_sensor_s[0] < 0;
  const double lead_s = first_advice_s[0] < 0 || never_in_range ? 0.0 : own_sensor_s[0] - first_advice_s[0];
  for (std::string& f : scenario_failures(scenario, (*service)->event_lines(), first_advice_s[0], own_sensor_s[0],
                                          unadvised_sensor_s[0], min_agv_person_m))
    failures.push_back(std::move(f));

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
    json::StringSink sink(json);
    json::Writer w(sink, json::Style::spaced);
    write_report_head(w, {.scenario = scenario.name,
                          .failures = &failures,
                          .min_agv_person_m = min_agv_person_m,
                          .first_advice_s = first_advice_s[0],
                          .own_sensor_s = own_sensor_s[0],
                          .lead_s = lead_s,
                          .unadvised_sensor_s = unadvised_sensor_s[0],
                          .never_in_range = never_in_range});
    write_timeline(w, (*service)->event_lines());
    write_agv_samples(w, scenario, samples);
    const ssc::ServiceCounters& c = (*service)->counters();
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
