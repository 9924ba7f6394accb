#include "cli.hpp"

#include <pthread.h>

#include <atomic>
#include <cerrno>
#include <chrono>
#include <csignal>
#include <cstdlib>
#include <cstring>
#include <ctime>
#include <string>
#include <string_view>

#include "commands.hpp"
#include "config.hpp"
#include "firmware.hpp"
#include "sen3bot/capture/dump.hpp"
#include "sen3bot/hal/rt_setup.hpp"

#ifndef SEN3BOT_VERSION
#define SEN3BOT_VERSION "unknown"
#endif

namespace sen3bot::firmware {

namespace {

constexpr const char* kUsage =
    "usage: sen3bot <command> [options]\n"
    "\n"
    "Real-time controller firmware for the Sen3Bot mobile robot (Pioneer 3-DX base,\n"
    "SICK LMS200 laser, ONVIF/RTSP camera).\n"
    "\n"
    "commands:\n"
    "  run --config FILE [--duration S] [--clock lockstep|realtime]\n"
    "        Load the configuration, build the task table and run it until SIGINT or\n"
    "        SIGTERM, the configured duration or the end of the mission, then print the\n"
    "        mission report (with a navigation section) and task statistics.\n"
    "        --duration overrides run.duration_s (0: until a signal); --clock overrides\n"
    "        run.clock: 'realtime' runs on the monotonic clock with one thread per task\n"
    "        group, 'lockstep' runs simulated time as fast as the CPU allows.\n"
    "  sim --scenario NAME [--config FILE] [--realtime] [--seed N] [--report DIR]\n"
    "        Run a named scenario on the simulated robot (sen3bot sim --list shows\n"
    "        them), each case a whole firmware run from config/sim.yaml; with --report\n"
    "        write DIR/report.json and a PNG per case (map, safe path, plan, driven\n"
    "        path, obstacles). Exit status 3 when a case misses its goal or collides.\n"
    "  sim --list\n"
    "        List the scenarios and their cases.\n"
    "  plan --map MAP.yaml --start X,Y --goal X,Y [--waypoints FILE] [--unit-cost]\n"
    "        One global plan (A* with waypoint attraction) on the map's costmap, as\n"
    "        JSON: length_m, cells, expansions, time_ms, path [[x, y], ...] in metres.\n"
    "        --unit-cost plans on the bare occupancy grid (no inflation, no footprint).\n"
    "  capture dump FILE\n"
    "        Print a wire capture (.s3bcap) as a timestamped hex listing.\n"
    "  decode p2os CAPTURE\n"
    "        Decode the Pioneer base packets of a wire capture as JSON lines (time,\n"
    "        direction, type, fields).\n"
    "  p2os-emulator (--pty LINK | --tcp PORT) [--name NAME]\n"
    "        Run the Pioneer 3-DX (ARCOS) emulator until SIGINT: on a pseudo-terminal\n"
    "        whose slave is symlinked at LINK, or on a TCP port (MobileSim style).\n"
    "  drive --port DEV|tcp://HOST:PORT --vel M_S --rvel RAD_S --seconds S [--baud B]\n"
    "        Connect to the base, enable the motors, drive at the given velocities, print\n"
    "        odometry as JSON lines, then stop, disable and close.\n"
    "  decode lms200 CAPTURE\n"
    "        Decode the SICK LMS200 telegrams of a wire capture as JSON lines (time,\n"
    "        direction, code, decoded fields; scans with ranges_m, null where invalid).\n"
    "  lms200-emulator --pty LINK [--map MAP.yaml --pose X,Y,TH] [--status 0x10] [--baud B]\n"
    "        Run the LMS200 emulator until SIGINT on a pseudo-terminal symlinked at LINK;\n"
    "        ranges from a ROS map_server map (default: a built-in 8 m x 6 m room).\n"
    "  scan --port DEV --baud B --variant 180/0.5 --units cm|mm --count N [--timeout S]\n"
    "        Connect to an LMS200 (probing its baud rate), print N scans as JSON lines\n"
    "        (t_s, angle_min_rad, angle_increment_rad, ranges_m, units, baud), then stop.\n"
    "  camera discover [--timeout S]\n"
    "        WS-Discovery probe for ONVIF cameras; prints them as a JSON array.\n"
    "  camera ptz onvif://user:pass@host[:port] --pan P --tilt T --zoom Z --seconds S\n"
    "        ONVIF ContinuousMove (velocities in [-1, 1]) for S seconds, then Stop.\n"
    "  camera probe URL [--transport tcp|udp] [--frames N] [--save DIR] [--timeout S]\n"
    "        Connect to a camera (rtsp://[user:pass@]host[:port]/path, or\n"
    "        onvif://user:pass@host[:port] to ask ONVIF for the stream URI), decode N\n"
    "        frames (default 30) and end with one JSON line: codec, width, height,\n"
    "        transport, frames_decoded, frames_dropped, fps, latency_ms_p50. --save\n"
    "        writes each frame seen as PNG. Exit status 1 when no frame was decoded.\n"
    "  version\n"
    "        Print the firmware version.\n"
    "  --help, -h\n"
    "        Print this text.\n"
    "\n"
    "exit status: 0 success, 1 run-time failure, 2 bad command line or configuration,\n"
    "3 the mission failed (a goal not reached).\n";

std::atomic<tasks::Scheduler*> g_signal_target{nullptr};
std::atomic<int> g_stop_signal{0};

void on_stop_signal(int sig) {
  // Only atomic stores: async-signal-safe.
  g_stop_signal.store(sig);
  if (tasks::Scheduler* s = g_signal_target.load()) s->request_stop();
}

// SIGINT/SIGTERM stay blocked (pending) from the start of `run` until the run loop is ready
// for them, so a stop request during start-up is never lost nor kills the process.
class StopSignalsBlocked {
 public:
  StopSignalsBlocked() {
    sigemptyset(&set_);
    sigaddset(&set_, SIGINT);
    sigaddset(&set_, SIGTERM);
    pthread_sigmask(SIG_BLOCK, &set_, &previous_);
  }
  ~StopSignalsBlocked() { pthread_sigmask(SIG_SETMASK, &previous_, nullptr); }
  StopSignalsBlocked(const StopSignalsBlocked&) = delete;
  StopSignalsBlocked& operator=(const StopSignalsBlocked&) = delete;

 private:
  sigset_t set_;
  sigset_t previous_;
};

struct RunOptions {
  std::string config_path;
  bool have_duration = false;
  double duration_s = 0;
  bool have_clock = false;
  ClockMode clock = ClockMode::lockstep;
};

std::string duration_text(double duration_s) {
  if (duration_s <= 0) return "until SIGINT/SIGTERM";
  char text[48];
  std::snprintf(text, sizeof text, "for %.1f s", duration_s);
  return text;
}

bool parse_double(const char* text, double& out) {
  char* end = nullptr;
  errno = 0;
  out = std::strtod(text, &end);
  return errno == 0 && end != text && *end == '\0';
}

void print_warnings(const tasks::Scheduler& scheduler, std::FILE* err) {
  for (std::size_t i = 0; i < scheduler.warning_count(); ++i)
    std::fprintf(err, "sen3bot: warning: %s (continuing without it)\n", scheduler.warning(i).c_str());
}

int run_realtime(Firmware& fw, const FirmwareConfig& config, std::FILE* out, std::FILE* err) {
  tasks::Scheduler& scheduler = fw.scheduler();
  // Block the stop signals before any thread starts so every thread inherits the mask and
  // only this thread receives them, synchronously.
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  sigset_t previous;
  pthread_sigmask(SIG_BLOCK, &stop_signals, &previous);

  if (Status s = scheduler.start(); !s) {
    pthread_sigmask(SIG_SETMASK, &previous, nullptr);
    std::fprintf(err, "sen3bot: %s\n", s.error().c_str());
    return 1;
  }
  const auto started = std::chrono::steady_clock::now();
  int signal_number = 0;
  for (;;) {
    timespec poll{0, 100'000'000};
    const int sig = sigtimedwait(&stop_signals, nullptr, &poll);
    if (sig > 0) {
      signal_number = sig;
      break;
    }
    const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - started).count();
    if (config.duration_s > 0 && elapsed >= config.duration_s) break;
    if (fw.mission() != nullptr && fw.mission()->finished()) break;
  }
  scheduler.request_stop();
  scheduler.join();
  pthread_sigmask(SIG_SETMASK, &previous, nullptr);
  print_warnings(scheduler, err);
  if (signal_number != 0) std::fprintf(out, "stopped by %s\n", signal_number == SIGINT ? "SIGINT" : "SIGTERM");
  return 0;
}

int run_lockstep(Firmware& fw, hal::SimClock& clock, const FirmwareConfig& config, std::FILE* out, std::FILE* err) {
  tasks::Scheduler& scheduler = fw.scheduler();
  g_signal_target.store(&scheduler);
  struct sigaction action {};
  action.sa_handler = on_stop_signal;
  sigemptyset(&action.sa_mask);
  struct sigaction old_int {};
  struct sigaction old_term {};
  sigaction(SIGINT, &action, &old_int);
  sigaction(SIGTERM, &action, &old_term);
  g_stop_signal.store(0);
  sigset_t stop_signals;
  sigemptyset(&stop_signals);
  sigaddset(&stop_signals, SIGINT);
  sigaddset(&stop_signals, SIGTERM);
  pthread_sigmask(SIG_UNBLOCK, &stop_signals, nullptr);  // a pending stop is delivered here

  const hal::Nanos duration =
      config.duration_s > 0 ? static_cast<hal::Nanos>(config.duration_s * 1e9) : INT64_MAX / 2;
  const auto wall_start = std::chrono::steady_clock::now();
  // Simulated time in one-second slices, so the end of the mission is seen within a second; a
  // stop signal cuts the current slice short (the handler asks the scheduler to stop).
  const hal::Nanos end_ns = clock.now() + duration;
  Status s = Status::success();
  while (s && g_stop_signal.load() == 0 && clock.now() < end_ns && (fw.mission() == nullptr || !fw.mission()->finished()))
    s = scheduler.run_lockstep(clock, std::min<hal::Nanos>(end_ns - clock.now(), hal::seconds(1)));
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  pthread_sigmask(SIG_BLOCK, &stop_signals, nullptr);

  sigaction(SIGINT, &old_int, nullptr);
  sigaction(SIGTERM, &old_term, nullptr);
  g_signal_target.store(nullptr);
  if (!s) {
    std::fprintf(err, "sen3bot: %s\n", s.error().c_str());
    return 1;
  }
  if (const int sig = g_stop_signal.load(); sig != 0) std::fprintf(out, "stopped by %s\n", sig == SIGINT ? "SIGINT" : "SIGTERM");
  const double sim_s = hal::to_seconds(clock.now() - scheduler.start_time_ns());
  std::fprintf(out, "simulated %.3f s in %.3f s of wall time (%.0fx real time)\n", sim_s, wall_s,
               wall_s > 0 ? sim_s / wall_s : 0.0);
  return 0;
}

int run_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  const StopSignalsBlocked blocked;
  RunOptions options;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    auto value = [&](const char* what) -> const char* {
      if (i + 1 >= argc) {
        std::fprintf(err, "sen3bot run: %s needs a value\n", what);
        return nullptr;
      }
      return argv[++i];
    };
    if (arg == "--config") {
      const char* v = value("--config");
      if (!v) return 2;
      options.config_path = v;
    } else if (arg == "--duration") {
      const char* v = value("--duration");
      if (!v) return 2;
      if (!parse_double(v, options.duration_s) || options.duration_s < 0) {
        std::fprintf(err, "sen3bot run: --duration: expected seconds >= 0, got '%s'\n", v);
        return 2;
      }
      options.have_duration = true;
    } else if (arg == "--clock") {
      const char* v = value("--clock");
      if (!v) return 2;
      const std::string_view c = v;
      if (c == "lockstep") {
        options.clock = ClockMode::lockstep;
      } else if (c == "realtime") {
        options.clock = ClockMode::realtime;
      } else {
        std::fprintf(err, "sen3bot run: --clock: expected lockstep or realtime, got '%s'\n", v);
        return 2;
      }
      options.have_clock = true;
    } else {
      std::fprintf(err, "sen3bot run: unknown option '%s' (see sen3bot --help)\n", argv[i]);
      return 2;
    }
  }
  if (options.config_path.empty()) {
    std::fprintf(err, "sen3bot run: --config FILE is required (see sen3bot --help)\n");
    return 2;
  }

  Result<FirmwareConfig> loaded = load_config(options.config_path);
  if (!loaded) {
    std::fprintf(err, "sen3bot: %s\n", loaded.error().c_str());
    return 2;
  }
  FirmwareConfig& config = *loaded;
  if (options.have_duration) config.duration_s = options.duration_s;
  if (options.have_clock) config.clock = options.clock;
  const bool realtime = config.clock == ClockMode::realtime;

  std::fprintf(out, "sen3bot %s: robot '%s', %s clock, %s\n", SEN3BOT_VERSION, config.robot_name.c_str(),
               realtime ? "real-time" : "lockstep simulated",
               duration_text(config.duration_s).c_str());

  if (realtime && config.lock_memory) {
    if (Status s = hal::lock_memory(); !s)
      std::fprintf(err, "sen3bot: warning: %s (continuing without it)\n", s.error().c_str());
  }

  hal::PosixClock posix_clock;
  hal::SimClock sim_clock;
  hal::Clock& clock = realtime ? static_cast<hal::Clock&>(posix_clock) : static_cast<hal::Clock&>(sim_clock);
  Firmware fw(config, clock, out);
  if (Status s = fw.init(); !s) {
    std::fprintf(err, "sen3bot: %s\n", s.error().c_str());
    return 1;
  }
  fw.print_memory(out);
  std::fflush(out);

  int rc = realtime ? run_realtime(fw, config, out, err) : run_lockstep(fw, sim_clock, config, out, err);
  fw.shutdown();
  if (const MissionTask* mission = fw.mission(); mission != nullptr) {
    std::fprintf(out, "\n");
    mission->print_report(out);
    // A mission that ran to its end and failed is a failed run; one stopped early is not.
    if (mission->report().state == MissionState::failed && rc == 0) rc = 3;
  }
  std::fprintf(out, "\ntask statistics:\n");
  fw.scheduler().print_stats(out);
  std::fflush(out);
  return rc;
}

int capture_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  if (argc == 2 && std::string_view(argv[0]) == "dump") {
    if (Status s = capture::dump(argv[1], out); !s) {
      std::fprintf(err, "sen3bot capture dump: %s\n", s.error().c_str());
      return 1;
    }
    return 0;
  }
  std::fprintf(err, "usage: sen3bot capture dump FILE\n");
  return 2;
}

}  // namespace

int cli_main(int argc, char** argv, std::FILE* out, std::FILE* err) {
  if (argc < 2) {
    std::fputs(kUsage, err);
    return 2;
  }
  const std::string_view command = argv[1];
  if (command == "--help" || command == "-h" || command == "help") {
    std::fputs(kUsage, out);
    return 0;
  }
  if (command == "version" || command == "--version") {
    std::fprintf(out, "sen3bot %s\n", SEN3BOT_VERSION);
    return 0;
  }
  if (command == "run") return run_command(argc - 2, argv + 2, out, err);
  if (command == "capture") return capture_command(argc - 2, argv + 2, out, err);
  if (command == "decode" && argc >= 3 && std::string_view(argv[2]) == "p2os")
    return decode_p2os_command(argc - 3, argv + 3, out, err);
  if (command == "p2os-emulator") return p2os_emulator_command(argc - 2, argv + 2, out, err);
  if (command == "decode" && argc >= 3 && std::string_view(argv[2]) == "lms200")
    return decode_lms200_command(argc - 3, argv + 3, out, err);
  if (command == "lms200-emulator") return lms200_emulator_command(argc - 2, argv + 2, out, err);
  if (command == "scan") return scan_command(argc - 2, argv + 2, out, err);
  if (command == "drive") return drive_command(argc - 2, argv + 2, out, err);
  if (command == "camera") return camera_command(argc - 2, argv + 2, out, err);
  if (command == "sim") return sim_command(argc - 2, argv + 2, out, err);
  if (command == "plan") return plan_command(argc - 2, argv + 2, out, err);
  std::fprintf(err, "sen3bot: unknown command '%s'\n\n%s", argv[1], kUsage);
  return 2;
}

}  // namespace sen3bot::firmware
