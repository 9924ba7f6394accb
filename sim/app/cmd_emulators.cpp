// The device emulators as standalone programs, for other clients (ARIA, MobileSim-style TCP
// clients, MRPT, sicktoolbox): sen3bot-sim p2os-emulator and sen3bot-sim lms200-emulator.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <string_view>

#include "cli_util.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/lms200/protocol.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/sim/lms200/emulator.hpp"
#include "sen3bot/sim/lms200/pty_runner.hpp"
#include "sen3bot/sim/p2os/emulator_runner.hpp"
#include "sen3bot/world/world.hpp"
#include "sim_commands.hpp"

namespace sen3bot::sim {

using firmware::parse_u32;
using firmware::StopOnSignal;

namespace {

// A sen3bot::world ray caster (ROS map_server map) as the emulator's range source.
class MapRanges final : public lms200::RangeSource {
 public:
  explicit MapRanges(const nav::OccupancyMap& map) : world_(map) {}
  void ranges(hal::Nanos, const lms200::ScanGeometry& g, std::span<float> out_m) override {
    const lms200::SensorPose p = sensor_pose();
    world_.scan({p.x_m, p.y_m, p.theta_rad}, g.angle_min_rad, g.angle_increment_rad, g.count, g.range_max_m + 1.0,
                out_m);
    // World reports max_range for "nothing hit"; the scanner reports that as out of range.
    for (std::size_t i = 0; i < std::min(g.count, out_m.size()); ++i)
      if (out_m[i] > g.range_max_m) out_m[i] = INFINITY;
  }

 private:
  world::World world_;
};

}  // namespace

int p2os_emulator_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  std::string pty_link;
  long tcp_port = -1;
  p2os::EmulatorConfig config;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (i + 1 >= argc) {
      std::fprintf(err, "sen3bot-sim p2os-emulator: %s needs a value\n", argv[i]);
      return 2;
    }
    const char* value = argv[++i];
    if (arg == "--pty") {
      pty_link = value;
    } else if (arg == "--tcp") {
      std::uint32_t port = 0;
      if (!parse_u32(value, port) || port > 65535) {
        std::fprintf(err, "sen3bot-sim p2os-emulator: --tcp: expected a port 0..65535, got '%s'\n", value);
        return 2;
      }
      tcp_port = port;
    } else if (arg == "--name") {
      config.name = value;
    } else if (arg == "--watchdog") {
      const std::string_view mode = value;
      if (mode != "stop" && mode != "resume") {
        std::fprintf(err, "sen3bot-sim p2os-emulator: --watchdog: expected 'stop' or 'resume', got '%s'\n", value);
        return 2;
      }
      config.watchdog_resumes = mode == "resume";
    } else {
      std::fprintf(err, "sen3bot-sim p2os-emulator: unknown option '%s'\n", argv[i - 1]);
      return 2;
    }
  }
  if (pty_link.empty() == (tcp_port < 0)) {
    std::fprintf(err,
                 "usage: sen3bot-sim p2os-emulator (--pty LINK | --tcp PORT) [--name NAME] [--watchdog stop|resume]\n");
    return 2;
  }
  StopOnSignal stop;
  std::unique_ptr<p2os::EmulatorRunner> runner;
  if (!pty_link.empty()) {
    auto started = p2os::PtyEmulatorRunner::start(config, pty_link);
    if (!started) {
      std::fprintf(err, "sen3bot-sim p2os-emulator: %s\n", started.error().c_str());
      return 1;
    }
    std::fprintf(out, "p2os emulator '%s' on %s (%s), until SIGINT\n", config.name.c_str(), pty_link.c_str(),
                 (*started)->slave_path().c_str());
    runner = std::move(*started);
  } else {
    auto started = p2os::TcpEmulatorRunner::start(config, static_cast<std::uint16_t>(tcp_port), "");
    if (!started) {
      std::fprintf(err, "sen3bot-sim p2os-emulator: %s\n", started.error().c_str());
      return 1;
    }
    std::fprintf(out, "p2os emulator '%s' on tcp port %u, until SIGINT\n", config.name.c_str(),
                 static_cast<unsigned>((*started)->port()));
    runner = std::move(*started);
  }
  std::fflush(out);
  hal::PosixClock clock;
  while (!StopOnSignal::requested() != 0) clock.sleep_until(clock.now() + hal::millis(50));
  runner->stop();
  const p2os::EmulatorStats stats = runner->with_emulator([](p2os::P2osEmulator& e) { return e.stats(); });
  std::fprintf(out,
               "stopped: %llu packets received, %llu bad checksums, %llu SIPs sent, %llu sessions (%llu closed by "
               "the client), %llu watchdog stops\n",
               static_cast<unsigned long long>(stats.packets_received),
               static_cast<unsigned long long>(stats.bad_checksums), static_cast<unsigned long long>(stats.sips_sent),
               static_cast<unsigned long long>(stats.sessions_opened),
               static_cast<unsigned long long>(stats.sessions_closed),
               static_cast<unsigned long long>(stats.watchdog_stops));
  return 0;
}

int lms200_emulator_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  std::string link;
  std::string map_path;
  double pose[3] = {0, 0, 0};
  bool have_pose = false;
  lms200::EmulatorOptions options;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (i + 1 >= argc) {
      std::fprintf(err, "sen3bot-sim lms200-emulator: %s needs a value\n", argv[i]);
      return 2;
    }
    const std::string_view value = argv[++i];
    std::uint32_t number = 0;
    if (arg == "--pty") {
      link = value;
    } else if (arg == "--map") {
      map_path = value;
    } else if (arg == "--pose") {
      const std::string v(value);
      if (std::sscanf(v.c_str(), "%lf,%lf,%lf", &pose[0], &pose[1], &pose[2]) != 3) {
        std::fprintf(err, "sen3bot-sim lms200-emulator: --pose: expected X,Y,TH (m, m, rad), got '%s'\n", v.c_str());
        return 2;
      }
      have_pose = true;
    } else if (arg == "--status" && parse_u32(value, number) && number <= 0xFF) {
      options.status = static_cast<std::uint8_t>(number);
    } else if (arg == "--baud" && parse_u32(value, number) && lms200::baud_mode(number)) {
      options.initial_baud = number;
    } else {
      std::fprintf(err, "sen3bot-sim lms200-emulator: bad option '%s %s' (see sen3bot-sim --help)\n", argv[i - 1], argv[i]);
      return 2;
    }
  }
  if (link.empty()) {
    std::fprintf(err, "sen3bot-sim lms200-emulator: --pty LINK is required\n");
    return 2;
  }
  std::unique_ptr<lms200::RangeSource> world;
  if (!map_path.empty()) {
    Result<nav::OccupancyMap> map = nav::load_map(map_path);
    if (!map) {
      std::fprintf(err, "sen3bot-sim lms200-emulator: %s\n", map.error().c_str());
      return 2;
    }
    world = std::make_unique<MapRanges>(*map);
  } else {
    // The built-in test room: 8 m x 6 m with a 1 m box; the sensor at its centre.
    world = std::make_unique<lms200::WallWorld>(lms200::WallWorld::room_with_box(8.0, 6.0, 6.0, 3.0, 1.0));
  }
  if (have_pose) world->set_sensor_pose(pose[0], pose[1], pose[2]);

  Result<std::unique_ptr<lms200::Lms200PtyRunner>> runner = lms200::Lms200PtyRunner::open(options, *world);
  if (!runner) {
    std::fprintf(err, "sen3bot-sim lms200-emulator: %s\n", runner.error().c_str());
    return 1;
  }
  if (Status s = (*runner)->link(link); !s) {
    std::fprintf(err, "sen3bot-sim lms200-emulator: %s\n", s.error().c_str());
    return 1;
  }
  StopOnSignal signals;
  (*runner)->start();
  const lms200::SensorPose p = world->sensor_pose();
  std::fprintf(out, "lms200 emulator on %s -> %.*s at %u baud, status 0x%02x, %s, pose %.3f,%.3f,%.3f; until SIGINT\n",
               link.c_str(), static_cast<int>((*runner)->slave_path().size()), (*runner)->slave_path().data(),
               options.initial_baud, options.status, map_path.empty() ? "built-in room" : map_path.c_str(), p.x_m,
               p.y_m, p.theta_rad);
  std::fflush(out);
  hal::PosixClock clock;
  while (!StopOnSignal::requested() != 0) clock.sleep_until(clock.now() + hal::millis(50));
  (*runner)->stop();
  (*runner)->with_emulator([out](lms200::Lms200Emulator& e) {
    const lms200::EmulatorCounters& c = e.counters();
    std::fprintf(out, "requests %llu, scans sent %llu (skipped %llu), baud changes %llu, config writes %llu\n",
                 static_cast<unsigned long long>(c.requests), static_cast<unsigned long long>(c.scans_sent),
                 static_cast<unsigned long long>(c.scans_skipped), static_cast<unsigned long long>(c.baud_changes),
                 static_cast<unsigned long long>(c.config_writes));
  });
  return 0;
}

}  // namespace sen3bot::sim
