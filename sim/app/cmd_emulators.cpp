// The device emulators as standalone programs, for other clients (ARIA, MobileSim-style TCP
// clients, MRPT, sicktoolbox): sen3bot-sim p2os-emulator and sen3bot-sim lms200-emulator.
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <string_view>

#include "cli_util.hpp"
#include "lms200_emulator_options.hpp"
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
  while (StopOnSignal::requested() == 0) clock.sleep_until(clock.now() + hal::millis(50));
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

namespace {

constexpr const char* kLms200Command = "sen3bot-sim lms200-emulator";

// Faults that recur every N streamed scans, and those that are on or off.
struct CountFault {
  std::string_view name;
  std::uint32_t lms200::FaultPlan::*field;
};
constexpr CountFault kCountFaults[] = {
    {"crc", &lms200::FaultPlan::corrupt_crc_every},
    {"truncate", &lms200::FaultPlan::truncate_every},
    {"false-header", &lms200::FaultPlan::false_header_every},
    {"oversize-len", &lms200::FaultPlan::oversize_len_every},
    {"invalid-values", &lms200::FaultPlan::invalid_values_every},
    {"dazzle", &lms200::FaultPlan::dazzle_every},
};
struct FlagFault {
  std::string_view name;
  bool lms200::FaultPlan::*field;
};
constexpr FlagFault kFlagFaults[] = {
    {"silent", &lms200::FaultPlan::silent},
    {"no-ack", &lms200::FaultPlan::suppress_ack},
    {"device-fault", &lms200::FaultPlan::device_fault},
};

// "crc=10", "no-ack", ...
bool parse_fault(std::string_view text, lms200::FaultPlan& plan, std::FILE* err) {
  const std::size_t eq = text.find('=');
  const std::string_view name = text.substr(0, eq);
  for (const CountFault& f : kCountFaults) {
    if (f.name != name) continue;
    std::uint32_t every = 0;
    if (eq == std::string_view::npos || !firmware::parse_u32(text.substr(eq + 1), every) || every == 0) {
      std::fprintf(err, "%s: --fault %.*s needs a period, e.g. %.*s=10 (every 10th scan), got '%.*s'\n",
                   kLms200Command, static_cast<int>(name.size()), name.data(), static_cast<int>(name.size()),
                   name.data(), static_cast<int>(text.size()), text.data());
      return false;
    }
    plan.*f.field = every;
    return true;
  }
  for (const FlagFault& f : kFlagFaults) {
    if (f.name != name) continue;
    if (eq != std::string_view::npos) {
      std::fprintf(err, "%s: --fault %.*s takes no value, got '%.*s'\n", kLms200Command,
                   static_cast<int>(name.size()), name.data(), static_cast<int>(text.size()), text.data());
      return false;
    }
    plan.*f.field = true;
    return true;
  }
  std::fprintf(err,
               "%s: --fault: unknown fault '%.*s' (crc=N, truncate=N, false-header=N, oversize-len=N, "
               "invalid-values=N, dazzle=N, silent, no-ack, device-fault)\n",
               kLms200Command, static_cast<int>(name.size()), name.data());
  return false;
}

}  // namespace

int parse_lms200_emulator_args(int argc, char** argv, Lms200EmulatorArgs& args, std::FILE* err) {
  lms200::EmulatorOptions& options = args.options;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (i + 1 >= argc) {
      std::fprintf(err, "%s: %s needs a value\n", kLms200Command, argv[i]);
      return 2;
    }
    const std::string_view value = argv[++i];
    std::uint32_t number = 0;
    const char* expected = nullptr;  // set when the value is bad
    if (arg == "--pty") {
      args.pty_link = value;
    } else if (arg == "--map") {
      args.map_path = value;
    } else if (arg == "--pose") {
      const std::string v(value);
      if (std::sscanf(v.c_str(), "%lf,%lf,%lf", &args.pose[0], &args.pose[1], &args.pose[2]) != 3) {
        expected = "X,Y,TH (m, m, rad)";
      } else {
        args.have_pose = true;
      }
    } else if (arg == "--status") {
      if (parse_u32(value, number) && number <= 0xFF) {
        options.status = static_cast<std::uint8_t>(number);
      } else {
        expected = "a status byte 0..0xFF";
      }
    } else if (arg == "--baud") {
      if (parse_u32(value, number) && lms200::baud_mode(number)) {
        options.initial_baud = number;
      } else {
        expected = "a power-on rate: 9600, 19200, 38400 or 500000";
      }
    } else if (arg == "--variant") {
      if (!firmware::parse_lms200_variant(value, options.variant))
        expected = "a variant: 180/1, 180/0.5, 100/1, 100/0.5 or 100/0.25 (degrees)";
    } else if (arg == "--units") {
      if (value == "cm" || value == "mm") {
        options.units = value == "mm" ? lms200::Units::mm : lms200::Units::cm;
      } else {
        expected = "cm or mm";
      }
    } else if (arg == "--mode") {
      if (parse_u32(value, number) && number <= 0xFF &&
          lms200::valid_measuring_mode(static_cast<std::uint8_t>(number))) {
        options.measuring_mode = static_cast<lms200::MeasuringMode>(number);
      } else {
        expected = "a measuring mode: 0x00 to 0x06, 0x0F or 0x3F";
      }
    } else if (arg == "--indices") {
      if (value == "on" || value == "off") {
        options.availability = static_cast<std::uint8_t>(value == "on" ? lms200::kAvailabilityRealTimeIndices : 0);
      } else {
        expected = "on or off";
      }
    } else if (arg == "--fault") {
      if (!parse_fault(value, options.faults, err)) return 2;
    } else {
      std::fprintf(err, "%s: unknown option '%s' (see sen3bot-sim --help)\n", kLms200Command, argv[i - 1]);
      return 2;
    }
    if (expected != nullptr) {
      std::fprintf(err, "%s: %s: expected %s, got '%s'\n", kLms200Command, argv[i - 1], expected, argv[i]);
      return 2;
    }
  }
  if (args.pty_link.empty()) {
    std::fprintf(err, "%s: --pty LINK is required\n", kLms200Command);
    return 2;
  }
  return 0;
}

int lms200_emulator_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  Lms200EmulatorArgs args;
  if (const int status = parse_lms200_emulator_args(argc, argv, args, err); status != 0) return status;
  const std::string& link = args.pty_link;
  const std::string& map_path = args.map_path;
  const lms200::EmulatorOptions& options = args.options;
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
  if (args.have_pose) world->set_sensor_pose(args.pose[0], args.pose[1], args.pose[2]);

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
  std::fprintf(out,
               "lms200 emulator on %s -> %.*s at %u baud, %u/%u, %s, status 0x%02x%s, %s, pose %.3f,%.3f,%.3f; "
               "until SIGINT\n",
               link.c_str(), static_cast<int>((*runner)->slave_path().size()), (*runner)->slave_path().data(),
               options.initial_baud, options.variant.angle_deg, options.variant.resolution_cdeg,
               lms200::to_string(options.units).data(), options.status,
               options.faults.device_fault ? " (device fault)" : "",
               map_path.empty() ? "built-in room" : map_path.c_str(), p.x_m, p.y_m, p.theta_rad);
  std::fflush(out);
  hal::PosixClock clock;
  while (StopOnSignal::requested() == 0) clock.sleep_until(clock.now() + hal::millis(50));
  (*runner)->stop();
  (*runner)->with_emulator([out](lms200::Lms200Emulator& e) {
    const lms200::EmulatorCounters& c = e.counters();
    std::fprintf(out, "requests %llu, scans sent %llu (skipped %llu), baud changes %llu, config writes %llu\n",
                 static_cast<unsigned long long>(c.requests), static_cast<unsigned long long>(c.scans_sent),
                 static_cast<unsigned long long>(c.scans_skipped), static_cast<unsigned long long>(c.baud_changes),
                 static_cast<unsigned long long>(c.config_writes));
  });
  std::fflush(out);
  return 0;
}

}  // namespace sen3bot::sim
