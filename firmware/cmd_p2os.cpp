// Command-line tools for the Pioneer base: decode a capture, run the emulator standalone,
// and a drive smoke test against a real robot or a simulator.
#include <pthread.h>
#include <signal.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <string>
#include <string_view>

#include "commands.hpp"
#include "sen3bot/capture/reader.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/p2os/describe.hpp"
#include "sen3bot/p2os/driver.hpp"
#include "sen3bot/p2os/emulator_runner.hpp"
#include "sen3bot/p2os/task.hpp"

namespace sen3bot::firmware {

namespace {

bool parse_number(const char* text, double& out) {
  char* end = nullptr;
  errno = 0;
  out = std::strtod(text, &end);
  return errno == 0 && end != text && *end == '\0' && std::isfinite(out);
}

std::atomic<bool> g_stop{false};
void on_signal(int) { g_stop.store(true); }

// SIGINT/SIGTERM set g_stop for the life of this object.
class StopOnSignal {
 public:
  StopOnSignal() {
    g_stop.store(false);
    struct sigaction action {};
    action.sa_handler = on_signal;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, &old_int_);
    sigaction(SIGTERM, &action, &old_term_);
  }
  ~StopOnSignal() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  StopOnSignal(const StopOnSignal&) = delete;
  StopOnSignal& operator=(const StopOnSignal&) = delete;

 private:
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
};

}  // namespace

int decode_p2os_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  if (argc != 1) {
    std::fprintf(err, "usage: sen3bot decode p2os CAPTURE\n");
    return 2;
  }
  auto capture = capture::CaptureFile::load(argv[0]);
  if (!capture) {
    std::fprintf(err, "sen3bot decode p2os: %s\n", capture.error().c_str());
    return 1;
  }
  const Status s = p2os::decode_capture(*capture, "", [&](const std::string& line) {
    std::fputs(line.c_str(), out);
    std::fputc('\n', out);
  });
  if (!s) {
    std::fprintf(err, "sen3bot decode p2os: %s\n", s.error().c_str());
    return 1;
  }
  return 0;
}

int p2os_emulator_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  std::string pty_link;
  long tcp_port = -1;
  p2os::EmulatorConfig config;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (i + 1 >= argc) {
      std::fprintf(err, "sen3bot p2os-emulator: %s needs a value\n", argv[i]);
      return 2;
    }
    const char* value = argv[++i];
    if (arg == "--pty") {
      pty_link = value;
    } else if (arg == "--tcp") {
      char* end = nullptr;
      tcp_port = std::strtol(value, &end, 10);
      if (end == value || *end != '\0' || tcp_port < 0 || tcp_port > 65535) {
        std::fprintf(err, "sen3bot p2os-emulator: --tcp: expected a port 0..65535, got '%s'\n", value);
        return 2;
      }
    } else if (arg == "--name") {
      config.name = value;
    } else {
      std::fprintf(err, "sen3bot p2os-emulator: unknown option '%s'\n", argv[i - 1]);
      return 2;
    }
  }
  if (pty_link.empty() == (tcp_port < 0)) {
    std::fprintf(err, "usage: sen3bot p2os-emulator (--pty LINK | --tcp PORT) [--name NAME]\n");
    return 2;
  }
  StopOnSignal stop;
  std::unique_ptr<p2os::EmulatorRunner> runner;
  if (!pty_link.empty()) {
    auto started = p2os::PtyEmulatorRunner::start(config, pty_link);
    if (!started) {
      std::fprintf(err, "sen3bot p2os-emulator: %s\n", started.error().c_str());
      return 1;
    }
    std::fprintf(out, "p2os emulator '%s' on %s (%s), until SIGINT\n", config.name.c_str(), pty_link.c_str(),
                 (*started)->slave_path().c_str());
    runner = std::move(*started);
  } else {
    auto started = p2os::TcpEmulatorRunner::start(config, static_cast<std::uint16_t>(tcp_port), "");
    if (!started) {
      std::fprintf(err, "sen3bot p2os-emulator: %s\n", started.error().c_str());
      return 1;
    }
    std::fprintf(out, "p2os emulator '%s' on tcp port %u, until SIGINT\n", config.name.c_str(),
                 static_cast<unsigned>((*started)->port()));
    runner = std::move(*started);
  }
  std::fflush(out);
  hal::PosixClock clock;
  while (!g_stop.load()) clock.sleep_until(clock.now() + hal::millis(50));
  runner->stop();
  const p2os::EmulatorStats stats = runner->with_emulator([](p2os::P2osEmulator& e) { return e.stats(); });
  std::fprintf(out, "stopped: %llu packets received, %llu bad checksums, %llu SIPs sent, %llu sessions\n",
               static_cast<unsigned long long>(stats.packets_received),
               static_cast<unsigned long long>(stats.bad_checksums), static_cast<unsigned long long>(stats.sips_sent),
               static_cast<unsigned long long>(stats.sessions_opened));
  return 0;
}

int drive_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  p2os::P2osConfig config;
  config.port.clear();
  double vel_m_s = 0;
  double rvel_rad_s = 0;
  double seconds = -1;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (i + 1 >= argc) {
      std::fprintf(err, "sen3bot drive: %s needs a value\n", argv[i]);
      return 2;
    }
    const char* value = argv[++i];
    double number = 0;
    if (arg == "--port") {
      config.port = value;
    } else if (arg == "--vel" && parse_number(value, number)) {
      vel_m_s = number;
    } else if (arg == "--rvel" && parse_number(value, number)) {
      rvel_rad_s = number;
    } else if (arg == "--seconds" && parse_number(value, number) && number >= 0) {
      seconds = number;
    } else if (arg == "--baud" && parse_number(value, number) && number > 0) {
      config.baud = static_cast<std::uint32_t>(number);
    } else {
      std::fprintf(err, "sen3bot drive: bad option or value '%s %s'\n", argv[i - 1], value);
      return 2;
    }
  }
  if (config.port.empty() || seconds < 0) {
    std::fprintf(err,
                 "usage: sen3bot drive --port DEV|tcp://HOST:PORT --vel M_S --rvel RAD_S --seconds S [--baud B]\n");
    return 2;
  }
  auto link = p2os::open_p2os_link(config);
  if (!link) {
    std::fprintf(err, "sen3bot drive: %s\n", link.error().c_str());
    return 1;
  }
  StopOnSignal stop;
  hal::PosixClock clock;
  p2os::P2osDriver driver(config);
  driver.attach(*link->stream, clock.now(), link->baud_control, link->baud);
  constexpr hal::Nanos kLoopNs = hal::millis(2);
  constexpr hal::Nanos kConnectTimeoutNs = hal::seconds(10);
  const hal::Nanos connect_deadline = clock.now() + kConnectTimeoutNs;
  while (driver.state().link != p2os::LinkState::connected) {
    if (!driver.attached() || clock.now() > connect_deadline || g_stop.load()) {
      const auto& e = driver.stream_error();
      std::fprintf(err, "sen3bot drive: no robot answered on %s%s%s\n", config.port.c_str(), e ? ": " : "",
                   e ? e->c_str() : "");
      return 1;
    }
    driver.step(clock.now());
    clock.sleep_until(clock.now() + kLoopNs);
  }
  const hal::Nanos start = clock.now();
  const hal::Nanos end = start + static_cast<hal::Nanos>(seconds * 1e9);
  (void)driver.take_new_sip();
  int rc = 0;
  while (clock.now() < end && !g_stop.load()) {
    const hal::Nanos now = clock.now();
    driver.set_setpoint(p2os::BaseSetpoint{vel_m_s, rvel_rad_s, true}, now);
    driver.step(now);
    if (!driver.attached()) {
      std::fprintf(err, "sen3bot drive: link failed: %s\n", driver.stream_error() ? driver.stream_error()->c_str() : "");
      rc = 1;
      break;
    }
    if (driver.take_new_sip()) {
      const p2os::BaseState& s = driver.state();
      std::fprintf(out, "{\"t_s\":%.3f,\"x_m\":%.4f,\"y_m\":%.4f,\"theta_rad\":%.4f,\"v_m_s\":%.3f,\"battery_v\":%.1f}\n",
                   hal::to_seconds(now - start), s.x_m, s.y_m, s.theta_rad, s.v_m_s, s.battery_v);
      std::fflush(out);
    }
    clock.sleep_until(now + kLoopNs);
  }
  // Stop, disable, close; wait for the packets to go out.
  driver.request_close(clock.now());
  const hal::Nanos give_up = clock.now() + hal::seconds(2);
  while (!driver.closed() && driver.attached() && clock.now() < give_up) {
    driver.step(clock.now());
    clock.sleep_until(clock.now() + kLoopNs);
  }
  return rc;
}

}  // namespace sen3bot::firmware
