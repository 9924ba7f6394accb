// Command-line tools for the Pioneer base: decode a capture, and a drive smoke test against a
// real robot or a simulator.
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
#include "cli_util.hpp"
#include "sen3bot/json/json.hpp"
#include "sen3bot/hal/board.hpp"

namespace sen3bot::firmware {

namespace {

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
    } else if (arg == "--vel" && parse_double(value, number)) {
      vel_m_s = number;
    } else if (arg == "--rvel" && parse_double(value, number)) {
      rvel_rad_s = number;
    } else if (arg == "--seconds" && parse_double(value, number) && number >= 0) {
      seconds = number;
    } else if (arg == "--baud" && parse_double(value, number) && number > 0) {
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
  hal::PosixBoard board;
  auto link = board.open_link("base", hal::LinkRequest{config.port, config.baud, config.connect_timeout_ms});
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
    if (!driver.attached() || clock.now() > connect_deadline || StopOnSignal::requested() != 0) {
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
  while (clock.now() < end && StopOnSignal::requested() == 0) {
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
      json::FileSink sink(out);
      json::Writer(sink)
          .begin_object()
          .key("t_s").fixed_or_null(hal::to_seconds(now - start), 3)
          .key("x_m").fixed_or_null(s.x_m, 4)
          .key("y_m").fixed_or_null(s.y_m, 4)
          .key("theta_rad").fixed_or_null(s.theta_rad, 4)
          .key("v_m_s").fixed_or_null(s.v_m_s, 3)
          .key("battery_v").fixed_or_null(s.battery_v, 1)
          .end_object();
      std::fputc('\n', out);
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
