// sen3bot-sim fleet-sim --realtime: the scenario as separate programs (robots, AGVs, the centre)
// on a Mosquitto started here, paced by the wall clock; the master control and an observer run
// in this process.
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
#include "sen3bot/world/world.hpp"
#include "sim_commands.hpp"

#include "fleet_scenario.hpp"

namespace sen3bot::sim::fleet {

namespace {

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
  std::snprintf(pose, sizeof pose, "{ x_m: %.3f, y_m: %.3f, theta_deg: %.2f }", home.pose.x_m, home.pose.y_m,
                home.pose.theta_rad * 180.0 / kPi);
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


// The temporary folder, removed with what is in it on every way out.
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
};

// The programs the scenario runs: beside this one (the build writes sen3bot, sen3bot-sim and
// sen3bot-centre to one folder).
struct Programs {
  std::string sim_bin, centre_bin;
};

int find_programs(Programs& programs, std::FILE* err) {
  char self[4096] = {};
  const ssize_t self_size = ::readlink("/proc/self/exe", self, sizeof self - 1);
  if (self_size <= 0) return fail(err, std::string("cannot read /proc/self/exe: ") + std::strerror(errno), 1);
  std::string bin_dir(self, static_cast<std::size_t>(self_size));
  bin_dir = bin_dir.substr(0, bin_dir.rfind('/'));
  programs.sim_bin = bin_dir + "/sen3bot-sim";
  programs.centre_bin = bin_dir + "/sen3bot-centre";
  for (const std::string& bin : {programs.sim_bin, programs.centre_bin})
    if (::access(bin.c_str(), X_OK) != 0) return fail(err, "--realtime needs " + bin + ": " + std::strerror(errno), 1);
  return 0;
}

// Mosquitto on the loopback port, started and accepting; 0, or the exit status of a failure.
int start_broker(Children& children, int port, const std::string& work, const std::string& logs, std::FILE* err) {
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
  return 0;
}

std::string fixed4(double v) {
  char text[32];
  std::snprintf(text, sizeof text, "%.4f", v);
  return std::string(text);
}

// The centre and one `sen3bot-sim agv` per AGV, each from the start of its route.
int start_centre_and_agvs(Children& children, const Programs& programs, const std::string& url, const FleetScenario& scenario,
                          const ssc::SiteFile& site, const std::string& site_path, const std::string& event_log,
                          const std::string& duration, const std::string& logs, std::FILE* err) {
  if (!children.start("ssc", {programs.centre_bin, "ssc", "--broker", url, "--site", site_path, "--event-log", event_log,
                              "--duration", duration},
                      logs + "/ssc.log"))
    return fail(err, "cannot start sen3bot-centre ssc", 1);
  for (const AgvPlan& plan : scenario.agvs) {
    const double theta = std::atan2(plan.route[1].y_m - plan.route[0].y_m, plan.route[1].x_m - plan.route[0].x_m);
    if (!children.start(plan.serial,
                        {programs.sim_bin, "agv", "--broker", url, "--serial", plan.serial, "--map-id", site.service.map_id,
                         "--x", fixed4(plan.route[0].x_m), "--y", fixed4(plan.route[0].y_m), "--theta", fixed4(theta),
                         "--speed", fixed4(plan.speed_m_s), "--duration", duration},
                        logs + "/" + plan.serial + ".log"))
      return fail(err, std::string("cannot start the AGV ") + plan.serial, 1);
  }
  return 0;
}

// What the observer hears: the AGVs' states and connections, the centre's advisories, the
// robots coming online; times on the scenario's clock once it has started.
class FleetWatch {
 public:
  FleetWatch(const FleetScenario& scenario, const ssc::SiteFile& site, hal::PubSub& observer)
      : latest(scenario.agvs.size()),
        advice(scenario.agvs.size(), Advice::clear),
        first_advice_s(scenario.agvs.size(), -1),
        agv_online(scenario.agvs.size(), false),
        scenario_(scenario),
        site_(site),
        observer_(observer) {}

  // Scenario time 0: when the robots start.
  void start(std::int64_t t0) {
    t0_ = t0;
    started_ = true;
  }
  [[nodiscard]] std::int64_t t0() const noexcept { return t0_; }
  [[nodiscard]] double scenario_s() const {
    return started_ ? static_cast<double>(firmware::clock_ns(CLOCK_MONOTONIC) - t0_) * 1e-9 : 0.0;
  }
  [[nodiscard]] bool agvs_online() const { return std::all_of(agv_online.begin(), agv_online.end(), [](bool b) { return b; }); }

  // Everything received so far; "" or what went wrong.
  std::string drain() {
    for (;;) {
      auto m = observer_.receive(topic_, payload_);
      if (!m) return std::string("observer: ") + m.error().c_str();
      if (!m.value()) return {};
      const std::string_view t(topic_.data(), m.value()->topic_size);
      const std::string_view text(reinterpret_cast<const char*>(payload_.data()), m.value()->payload_size);
      // uagv/v2/MANUFACTURER/SERIAL/LEAF and sen3bot/v1/advisory/MANUFACTURER/SERIAL
      const std::size_t leaf_at = t.rfind('/');
      const std::string_view leaf = t.substr(leaf_at + 1);
      const std::string_view before = t.substr(0, leaf_at);
      const std::string_view serial = before.substr(before.rfind('/') + 1);
      if (t.starts_with("sen3bot/v1/advisory/")) on_advisory(leaf, text);
      else if (leaf == "connection") on_connection(serial, text);
      else if (leaf == "state") on_state(serial, text);
    }
  }

  std::vector<LatestState> latest;
  std::vector<Advice> advice;
  std::vector<double> first_advice_s;
  std::vector<bool> agv_online;
  std::map<std::string, double> robots_online;

 private:
  int agv_index(std::string_view serial) const {
    for (std::size_t i = 0; i < scenario_.agvs.size(); ++i)
      if (serial == scenario_.agvs[i].serial) return static_cast<int>(i);
    return -1;
  }

  void on_advisory(std::string_view serial, std::string_view text) {
    const int i = agv_index(serial);
    if (i < 0 || !vda5050::decode_advisory(text, *advisory_, *scratch_).ok()) return;
    advice[static_cast<std::size_t>(i)] = advisory_->advice;
    if (started_ && first_advice_s[static_cast<std::size_t>(i)] < 0 && advisory_->advice != Advice::clear)
      first_advice_s[static_cast<std::size_t>(i)] = scenario_s();
  }

  void on_connection(std::string_view serial, std::string_view text) {
    if (text.find("\"ONLINE\"") == std::string_view::npos) return;
    if (const int i = agv_index(serial); i >= 0) agv_online[static_cast<std::size_t>(i)] = true;
    else if (started_) robots_online.emplace(std::string(serial), scenario_s());
  }

  void on_state(std::string_view serial, std::string_view text) {
    const int i = agv_index(serial);
    if (i < 0 || !vda5050::decode_state(text, site_.service.version, *state_, *scratch_).ok() || !state_->agv_position) return;
    LatestState& s = latest[static_cast<std::size_t>(i)];
    s.known = true;
    s.t_s = scenario_s();
    s.x = state_->agv_position->x;
    s.y = state_->agv_position->y;
    s.theta = state_->agv_position->theta;
    s.speed = state_->velocity ? state_->velocity->vx : 0.0;
  }

  const FleetScenario& scenario_;
  const ssc::SiteFile& site_;
  hal::PubSub& observer_;
  std::vector<char> topic_ = std::vector<char>(256);
  std::vector<std::uint8_t> payload_ = std::vector<std::uint8_t>(64 * 1024);
  std::unique_ptr<vda5050::State> state_ = std::make_unique<vda5050::State>();
  std::unique_ptr<vda5050::DecodeScratch> scratch_ = std::make_unique<vda5050::DecodeScratch>();
  std::unique_ptr<vda5050::AdvisoryMessage> advisory_ = std::make_unique<vda5050::AdvisoryMessage>();
  std::int64_t t0_ = 0;
  bool started_ = false;
};

// "" while every program runs and no stop was asked for; else why the scenario ends.
std::string check_children(Children& children) {
  if (const Children::Child* c = children.ended())
    return c->name + " ended early (status " + std::to_string(c->status) + "): " + tail(c->log);
  if (const int s = firmware::StopOnSignal::requested(); s != 0) return "stopped by signal " + std::to_string(s);
  return {};
}

// The centre and the AGVs online before the robots start the scenario's clock.
int wait_for_agvs(FleetWatch& watch, Children& children, std::FILE* err) {
  for (const std::int64_t deadline = firmware::clock_ns(CLOCK_MONOTONIC) + 10'000'000'000;;) {
    if (std::string problem = watch.drain(); !problem.empty()) return fail(err, problem, 1);
    if (std::string problem = check_children(children); !problem.empty()) return fail(err, problem, 1);
    if (watch.agvs_online()) return 0;
    if (firmware::clock_ns(CLOCK_MONOTONIC) > deadline) return fail(err, "the AGVs did not come online within 10 s", 1);
    ::usleep(20'000);
  }
}

// Each robot's configuration for its own `sen3bot-sim run`, written to the work folder.
int write_robot_configs(const FleetScenario& scenario, const ssc::SiteFile& site, const std::string& base_text,
                        const std::string& base_dir, const std::string& url, double duration_s, const std::string& work,
                        std::vector<std::string>& paths, std::FILE* err) {
  for (const char* serial : scenario.robots) {
    const auto it = std::find(site.robot_serials.begin(), site.robot_serials.end(), serial);
    if (it == site.robot_serials.end()) return fail(err, std::string("the site has no robot ") + serial);
    const ssc::RobotHome& home = site.site.robots[static_cast<std::size_t>(it - site.robot_serials.begin())];
    const std::string path = work + "/robot_" + serial + ".yaml";
    if (!write_text(path, realtime_robot_config(base_text, base_dir, serial, home, url, duration_s, scenario.people)))
      return fail(err, "cannot write " + path, 1);
    paths.push_back(path);
  }
  return 0;
}

// What the scenario measures of the AGVs against the scripted people: the closest any came,
// when each one's own scanner (2 m ahead, +-30 degrees) first had a person, and when it would
// have unadvised (its route at its speed from its order); its samples every 0.5 s.
struct Measures {
  explicit Measures(std::size_t n_agvs)
      : ordered(n_agvs, false), samples(n_agvs), own_sensor_s(n_agvs, -1), unadvised_sensor_s(n_agvs, -1) {}
  std::vector<bool> ordered;
  std::vector<std::vector<AgvSample>> samples;
  std::vector<double> own_sensor_s, unadvised_sensor_s;
  double min_agv_person_m = 1e9;
};

constexpr double kSensorRangeM = 2.0;  // SimAgvConfig's, which `sen3bot-sim agv` keeps
constexpr double kStateExtrapolateS = 1.0;  // the AGVs' state period

void measure_agvs(const FleetScenario& scenario, world::World& people_world, const std::vector<LatestState>& latest,
                  double t_s, Measures& m) {
  people_world.set_time(t_s);
  std::vector<msg::Point2D> people;
  for (std::size_t k = 0; k < people_world.mover_count(); ++k)
    if (people_world.mover_visible(k)) people.push_back({people_world.mover_position(k).x_m, people_world.mover_position(k).y_m});
  for (std::size_t i = 0; i < scenario.agvs.size(); ++i) {
    const LatestState& s = latest[i];
    if (s.known) {
      // Between its states the AGV drives on as it last said.
      const double ahead = std::min(kStateExtrapolateS, t_s - s.t_s) * s.speed;
      const double x = s.x + ahead * std::cos(s.theta), y = s.y + ahead * std::sin(s.theta);
      for (const msg::Point2D& p : people) {
        const double d = std::hypot(p.x_m - x, p.y_m - y);
        m.min_agv_person_m = std::min(m.min_agv_person_m, d);
        const double bearing = std::remainder(std::atan2(p.y_m - y, p.x_m - x) - s.theta, 2 * kPi);
        if (m.own_sensor_s[i] < 0 && d < kSensorRangeM && std::abs(bearing) < kPi / 6) m.own_sensor_s[i] = t_s;
      }
    }
    const msg::Pose2D ghost = unadvised_pose(scenario.agvs[i], t_s);
    for (const msg::Point2D& p : people) {
      const double d = std::hypot(p.x_m - ghost.x_m, p.y_m - ghost.y_m);
      const double bearing = std::remainder(std::atan2(p.y_m - ghost.y_m, p.x_m - ghost.x_m) - ghost.theta_rad, 2 * kPi);
      if (m.unadvised_sensor_s[i] < 0 && m.ordered[i] && d < kSensorRangeM && std::abs(bearing) < kPi / 6)
        m.unadvised_sensor_s[i] = t_s;
    }
  }
}

// The scenario's duration on the wall clock: the plant's orders when due, the measures every
// AGV step, the samples every 0.5 s and a progress line every 10 s; 0, or the exit status of
// a failure.
int run_scenario(const FleetScenario& scenario, const ssc::SiteFile& site, const nav::OccupancyMap& map, FleetWatch& watch,
                 Children& children, hal::PubSub& plant, Measures& m, std::FILE* out, std::FILE* err) {
  // The scripted people as every robot's world has them, for the distances.
  world::World people_world(map);
  for (const world::MoverScript& p : scenario.people) people_world.add_mover(p);
  const std::size_t n_agvs = scenario.agvs.size();
  double next_step_s = 0, next_sample_s = 0, next_progress_s = 0;
  for (;;) {
    if (std::string problem = watch.drain(); !problem.empty()) return fail(err, problem, 1);
    if (std::string problem = check_children(children); !problem.empty()) return fail(err, problem, 1);
    const double t_s = watch.scenario_s();
    if (t_s >= scenario.duration_s) return 0;
    for (std::size_t i = 0; i < n_agvs; ++i)
      if (!m.ordered[i] && t_s >= scenario.agvs[i].order_s) {
        const std::string text = plant_order_text(scenario.agvs[i], site, firmware::clock_ns(CLOCK_REALTIME));
        if (text.empty() || !plant.publish(plant_topic(scenario.agvs[i], "order"), hal::as_bytes(text), 0, false))
          return fail(err, std::string("cannot publish the order of ") + scenario.agvs[i].serial, 1);
        m.ordered[i] = true;
      }
    if (t_s >= next_step_s) {
      next_step_s += kAgvStepS;
      measure_agvs(scenario, people_world, watch.latest, t_s, m);
    }
    if (t_s >= next_sample_s) {
      next_sample_s += 0.5;
      for (std::size_t i = 0; i < n_agvs; ++i)
        if (watch.latest[i].known)
          m.samples[i].push_back({t_s, watch.latest[i].x, watch.latest[i].y, watch.latest[i].speed, watch.advice[i]});
    }
    if (t_s >= next_progress_s) {
      next_progress_s += 10.0;
      std::fprintf(out, "  t=%5.1f s of %.0f s", t_s, scenario.duration_s);
      for (std::size_t i = 0; i < n_agvs; ++i)
        std::fprintf(out, "  %s (%.1f, %.1f) %.2f m/s %s", scenario.agvs[i].serial, watch.latest[i].x, watch.latest[i].y,
                     watch.latest[i].speed, std::string(vda5050::to_string(watch.advice[i])).c_str());
      std::fprintf(out, "\n");
      std::fflush(out);
    }
    ::usleep(10'000);
  }
}

// The centre's event log, its times made the scenario's (it logs its monotonic clock), each
// line printed.
std::vector<std::string> read_events(const std::string& event_log, std::int64_t t0, std::FILE* out) {
  std::vector<std::string> events;
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
  return events;
}

// The centre's counters: the JSON line it writes when it stops ("null" without one).
std::string centre_counters(const std::string& ssc_log) {
  std::string text;
  (void)read_text(ssc_log, text);
  const std::size_t k = text.rfind("{\"stopped_by\"");
  return k != std::string::npos ? text.substr(k, text.find('\n', k) - k) : std::string("null");
}

std::string seconds_text(double t) {
  if (t < 0) return std::string("never");
  char text[32];
  std::snprintf(text, sizeof text, "%.2f s", t);
  return std::string(text);
}

// DIR/report.json: the head both fleet reports share, the robots' start, the timeline, the
// AGVs' samples and the centre's counters; 0, or the exit status of a failure.
int write_report(const std::string& report_dir, const FleetScenario& scenario, const FleetWatch& watch, const Measures& m,
                 const std::vector<std::string>& failures, const std::vector<std::string>& events, const std::string& centre,
                 std::FILE* out, std::FILE* err) {
  const bool never_in_range = m.own_sensor_s[0] < 0;
  const double lead_s = watch.first_advice_s[0] < 0 || never_in_range ? 0.0 : m.own_sensor_s[0] - watch.first_advice_s[0];
  std::string json;
  json::StringSink sink(json);
  json::Writer w(sink, json::Style::spaced);
  write_report_head(w, {.scenario = scenario.name,
                        .realtime = true,
                        .failures = &failures,
                        .min_agv_person_m = m.min_agv_person_m,
                        .first_advice_s = watch.first_advice_s[0],
                        .own_sensor_s = m.own_sensor_s[0],
                        .lead_s = lead_s,
                        .unadvised_sensor_s = m.unadvised_sensor_s[0],
                        .never_in_range = never_in_range});
  w.line(2).key("robots_online_s").begin_object();
  for (const auto& [serial, t] : watch.robots_online) w.key(serial).fixed_or_null(t, 2);
  w.end_object();
  write_timeline(w, events);
  write_agv_samples(w, scenario, m.samples);
  w.line(2).key("centre").raw(centre).line(0).end_object();
  if (auto written = w.finish(); !written) return fail(err, std::string("report.json: ") + written.error().c_str(), 1);
  json += '\n';
  if (!write_text(report_dir + "/report.json", json)) return fail(err, "cannot write " + report_dir + "/report.json", 1);
  std::fprintf(out, "report: %s/report.json, %s/events.jsonl and the programs' logs there\n", report_dir.c_str(), report_dir.c_str());
  return 0;
}

}  // namespace

int fleet_realtime(const FleetScenario& scenario, const ssc::SiteFile& site, const std::string& site_path,
                   const std::string& config_path, const nav::OccupancyMap& map, const std::string& report_dir, std::FILE* out,
                   std::FILE* err) {
  Programs programs;
  if (int rc = find_programs(programs, err); rc != 0) return rc;
  char temp[] = "/tmp/sen3bot-fleet-XXXXXX";
  if (::mkdtemp(temp) == nullptr) return fail(err, std::string("mkdtemp: ") + std::strerror(errno), 1);
  const std::string work = temp;
  const RemoveDir remove_work{work};  // the logs stay in the report folder
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
  if (int rc = start_broker(children, port, work, logs, err); rc != 0) return rc;
  std::fprintf(out, "fleet-sim %s (realtime, Mosquitto on %s): %s\n", scenario.name, url.c_str(), scenario.description);

  // The observer: the AGVs' states and connections, the centre's advisories.
  hal::PubSubOptions watch_options;
  watch_options.url = url;
  watch_options.client_id = "fleet-sim-observer";
  watch_options.subscriptions = {{"uagv/v2/PlantAGV/+/state", 0}, {"uagv/v2/+/+/connection", 1}, {"sen3bot/v1/advisory/#", 1}};
  watch_options.inbound_slots = 1024;
  auto observer = hal::open_mqtt(watch_options);
  if (!observer) return fail(err, "observer: " + std::string(observer.error().c_str()), 1);
  // The plant's master control: its own client.
  hal::PubSubOptions master;
  master.url = url;
  master.client_id = "plant-master-control";
  auto plant = hal::open_mqtt(master);
  if (!plant) return fail(err, "master control: " + std::string(plant.error().c_str()), 1);

  const double margin_s = 30;  // the programs' own --duration: a backstop should this one vanish
  const std::string duration = std::to_string(static_cast<int>(scenario.duration_s + margin_s));
  if (int rc = start_centre_and_agvs(children, programs, url, scenario, site, site_path, event_log, duration, logs, err); rc != 0)
    return rc;
  FleetWatch watch(scenario, site, **observer);
  if (int rc = wait_for_agvs(watch, children, err); rc != 0) return rc;
  const std::size_t first_robot = children.size();
  std::vector<std::string> robot_configs;
  if (int rc = write_robot_configs(scenario, site, base_text, base_dir, url, scenario.duration_s + margin_s, work,
                                   robot_configs, err);
      rc != 0)
    return rc;
  watch.start(firmware::clock_ns(CLOCK_MONOTONIC));
  for (std::size_t r = 0; r < scenario.robots.size(); ++r) {
    const std::string serial = scenario.robots[r];
    if (!children.start(serial, {programs.sim_bin, "run", "--config", robot_configs[r], "--clock", "realtime"},
                        logs + "/robot_" + serial + ".log"))
      return fail(err, "cannot start the robot " + serial, 1);
  }

  Measures m(scenario.agvs.size());
  if (int rc = run_scenario(scenario, site, map, watch, children, **plant, m, out, err); rc != 0) return rc;
  // The robots, the AGVs and the centre stop first, then the broker.
  children.stop_from(first_robot, 10.0);
  children.stop_from(1, 5.0);
  (*observer)->close(0.5);
  (*plant)->close(0.5);
  children.stop_all(5.0);

  const std::vector<std::string> events = read_events(event_log, watch.t0(), out);
  const std::string centre = centre_counters(logs + "/ssc.log");
  std::vector<std::string> failures;
  if (m.samples[0].empty()) failures.push_back("no state from the AGV");
  for (std::string& f : scenario_failures(scenario, events, watch.first_advice_s[0], m.own_sensor_s[0], m.unadvised_sensor_s[0],
                                          m.min_agv_person_m))
    failures.push_back(std::move(f));
  std::fprintf(out, "\nresult %s (realtime): %s", scenario.name, failures.empty() ? "ok" : "FAILED");
  for (const std::string& f : failures) std::fprintf(out, "; %s", f.c_str());
  std::fprintf(out, "\n  first advice to the AGV %s, its own scanner first in range %s, unadvised %s, closest AGV-person %.2f m\n",
               seconds_text(watch.first_advice_s[0]).c_str(), seconds_text(m.own_sensor_s[0]).c_str(),
               seconds_text(m.unadvised_sensor_s[0]).c_str(), m.min_agv_person_m);
  if (!report_dir.empty())
    if (int rc = write_report(report_dir, scenario, watch, m, failures, events, centre, out, err); rc != 0) return rc;
  return failures.empty() ? 0 : 3;
}

}  // namespace sen3bot::sim::fleet
