#include "runner.hpp"

#include <pthread.h>

#include <atomic>
#include <chrono>
#include <csignal>
#include <ctime>
#include <string_view>

#include "cli_util.hpp"
#include "sen3bot/hal/rt_setup.hpp"

#ifndef SEN3BOT_VERSION
#define SEN3BOT_VERSION "unknown"
#endif

namespace sen3bot::firmware {

StopSignalsBlocked::StopSignalsBlocked() {
  sigemptyset(&set_);
  sigaddset(&set_, SIGINT);
  sigaddset(&set_, SIGTERM);
  pthread_sigmask(SIG_BLOCK, &set_, &previous_);
}

StopSignalsBlocked::~StopSignalsBlocked() { pthread_sigmask(SIG_SETMASK, &previous_, nullptr); }

namespace {

std::atomic<tasks::Scheduler*> g_signal_target{nullptr};
std::atomic<int> g_stop_signal{0};

void on_stop_signal(int sig) {
  // Only atomic stores: async-signal-safe.
  g_stop_signal.store(sig);
  if (tasks::Scheduler* s = g_signal_target.load()) s->request_stop();
}

std::string duration_text(double duration_s) {
  if (duration_s <= 0) return "until SIGINT/SIGTERM";
  char text[48];
  std::snprintf(text, sizeof text, "for %.1f s", duration_s);
  return text;
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

}  // namespace

int parse_run_options(int argc, char** argv, const char* program, RunOptions& options, std::FILE* err) {
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    auto value = [&](const char* what) -> const char* {
      if (i + 1 >= argc) {
        std::fprintf(err, "%s run: %s needs a value\n", program, what);
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
        std::fprintf(err, "%s run: --duration: expected seconds >= 0, got '%s'\n", program, v);
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
        std::fprintf(err, "%s run: --clock: expected lockstep or realtime, got '%s'\n", program, v);
        return 2;
      }
      options.have_clock = true;
    } else {
      std::fprintf(err, "%s run: unknown option '%s' (see %s --help)\n", program, argv[i], program);
      return 2;
    }
  }
  if (options.config_path.empty()) {
    std::fprintf(err, "%s run: --config FILE is required (see %s --help)\n", program, program);
    return 2;
  }

  return 0;
}

void apply(const RunOptions& options, FirmwareConfig& config) {
  if (options.have_duration) config.duration_s = options.duration_s;
  if (options.have_clock) config.clock = options.clock;
}

int run_firmware(Firmware& fw, hal::Board& board, const FirmwareConfig& config, std::FILE* out, std::FILE* err) {
  hal::SimClock* lockstep = board.lockstep_clock();
  std::fprintf(out, "sen3bot %s: robot '%s' on the %.*s board, %s clock, %s\n", SEN3BOT_VERSION,
               config.robot_name.c_str(), static_cast<int>(board.name().size()), board.name().data(),
               lockstep == nullptr ? "real-time" : "lockstep simulated", duration_text(config.duration_s).c_str());

  if (lockstep == nullptr && config.lock_memory) {
    if (config.thread_stack_bytes != 0) {
      if (Status s = hal::set_default_thread_stack(config.thread_stack_bytes); !s)
        std::fprintf(err, "sen3bot: warning: %s (continuing with the default)\n", s.error().c_str());
    }
    if (Status s = hal::lock_memory(); !s)
      std::fprintf(err, "sen3bot: warning: %s (continuing without it)\n", s.error().c_str());
  }
  hal::CpuLatencyRequest wakeup_latency;  // held until the run ends
  if (lockstep == nullptr && config.max_cpu_wakeup_latency_us >= 0) {
    Result<hal::CpuLatencyRequest> held = hal::CpuLatencyRequest::hold(config.max_cpu_wakeup_latency_us);
    if (held)
      wakeup_latency = std::move(*held);
    else
      std::fprintf(err, "sen3bot: warning: %s (continuing without it)\n", held.error().c_str());
  }
  if (Status s = board.start(); !s) {
    std::fprintf(err, "sen3bot: %s\n", s.error().c_str());
    return 1;
  }
  if (Status s = fw.init(); !s) {
    std::fprintf(err, "sen3bot: %s\n", s.error().c_str());
    board.stop();
    return 1;
  }
  fw.print_memory(out);
  std::fflush(out);

  int rc = lockstep == nullptr ? run_realtime(fw, config, out, err) : run_lockstep(fw, *lockstep, config, out, err);
  fw.shutdown();
  board.stop();
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

}  // namespace sen3bot::firmware
