// LMS200 command-line entry points: decode lms200, scan.
#include <signal.h>

#include <atomic>
#include <cerrno>
#include <cmath>
#include <cstdlib>
#include <cstring>
#include <memory>
#include <string>
#include <string_view>

#include "commands.hpp"
#include "sen3bot/capture/reader.hpp"
#include "sen3bot/hal/board.hpp"
#include "sen3bot/lms200/capture_decode.hpp"
#include "sen3bot/lms200/device.hpp"
#include "cli_util.hpp"
#include "sen3bot/json/json.hpp"

namespace sen3bot::firmware {

namespace {

void print_scan_json(const lms200::LaserScan& s, std::FILE* out) {
  char status[8];
  std::snprintf(status, sizeof status, "0x%02x", static_cast<unsigned>(s.status));
  json::FileSink sink(out);
  json::Writer w(sink);
  w.begin_object()
      .key("t_s").fixed_or_null(hal::to_seconds(s.stamp_ns), 6)
      .member_uint64("seq", s.sequence)
      .key("angle_min_rad").fixed_or_null(s.angle_min_rad, 6)
      .key("angle_increment_rad").fixed_or_null(s.angle_increment_rad, 8)
      .member("units", lms200::to_string(static_cast<lms200::Units>(s.units)))
      .member_uint32("baud", s.baud)
      .member("status", status)
      .member_uint32("device_status", s.device_status)
      .member_bool("fault", s.scanner_fault)
      .member_uint32("count", s.count)
      .key("ranges_m").begin_array();
  for (std::size_t i = 0; i < s.count; ++i) {
    if (s.valid(i)) w.fixed_or_null(s.ranges_m[i], 3);
    else w.null();
  }
  w.end_array().end_object();
  std::fputc('\n', out);
  std::fflush(out);
}

}  // namespace

int decode_lms200_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  if (argc != 1) {
    std::fprintf(err, "usage: sen3bot decode lms200 CAPTURE\n");
    return 2;
  }
  Result<capture::CaptureFile> file = capture::CaptureFile::load(argv[0]);
  if (!file) {
    std::fprintf(err, "sen3bot decode lms200: %s\n", file.error().c_str());
    return 1;
  }
  Result<lms200::CaptureDecodeSummary> summary = lms200::decode_capture_json(*file, "", out);
  if (!summary) {
    std::fprintf(err, "sen3bot decode lms200: %s\n", summary.error().c_str());
    return 1;
  }
  std::fprintf(err, "%zu requests, %zu replies (%zu scans), %zu ACK, %zu NAK, %llu CRC errors, %llu garbage bytes\n",
               summary->requests, summary->replies, summary->scans, summary->acks, summary->naks,
               static_cast<unsigned long long>(summary->crc_errors),
               static_cast<unsigned long long>(summary->garbage_bytes));
  return 0;
}

int scan_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  lms200::Lms200Config config;
  std::uint32_t count = 1;
  double timeout_s = 30;
  bool have_port = false;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (i + 1 >= argc) {
      std::fprintf(err, "sen3bot scan: %s needs a value\n", argv[i]);
      return 2;
    }
    const std::string_view value = argv[++i];
    std::uint32_t number = 0;
    bool ok = true;
    if (arg == "--port") {
      config.port = value;
      have_port = true;
    } else if (arg == "--baud") {
      ok = parse_u32(value, number) && lms200::baud_mode(number).ok();
      config.baud = number;
    } else if (arg == "--variant") {
      ok = parse_lms200_variant(value, config.variant);
    } else if (arg == "--units") {
      ok = value == "cm" || value == "mm";
      config.units = value == "mm" ? lms200::Units::mm : lms200::Units::cm;
    } else if (arg == "--mode") {
      ok = parse_u32(value, number) && number <= 0xFF && lms200::valid_measuring_mode(static_cast<std::uint8_t>(number));
      config.measuring_mode = static_cast<lms200::MeasuringMode>(number);
    } else if (arg == "--count") {
      ok = parse_u32(value, count) && count > 0;
    } else if (arg == "--timeout") {
      ok = parse_double(value, timeout_s) && timeout_s > 0;
    } else {
      ok = false;
    }
    if (!ok) {
      std::fprintf(err, "sen3bot scan: bad option '%s %s' (see sen3bot --help)\n", argv[i - 1], argv[i]);
      return 2;
    }
  }
  if (!have_port) {
    std::fprintf(err, "sen3bot scan: --port DEV is required\n");
    return 2;
  }
  hal::PosixBoard board;
  Result<hal::Link> link = board.open_link("laser", hal::LinkRequest{config.port, config.baud});
  if (!link) {
    std::fprintf(err, "sen3bot scan: %s\n", link.error().c_str());
    return 1;
  }
  lms200::Lms200Device device(config, *link->stream, link->baud_control);
  StopOnSignal signals;
  hal::PosixClock clock;
  const hal::Nanos give_up = clock.now() + static_cast<hal::Nanos>(timeout_s * 1e9);
  device.start(clock.now());
  std::uint32_t printed = 0;
  lms200::LaserScan scan;
  while (printed < count && clock.now() < give_up && StopOnSignal::requested() == 0) {
    device.step(clock.now());
    if (device.take_new_scan(scan)) {
      print_scan_json(scan, out);
      ++printed;
    }
    clock.sleep_until(clock.now() + hal::millis(1));
  }
  const bool streamed = printed == count;
  const hal::Nanos stop_by = clock.now() + hal::seconds(2);
  device.request_stop(clock.now());
  while (device.phase() != lms200::Lms200Device::Phase::stopped && clock.now() < stop_by) {
    device.step(clock.now());
    clock.sleep_until(clock.now() + hal::millis(1));
  }
  if (!streamed) {
    std::fprintf(err, "sen3bot scan: %u of %u scans (%s%s%s)\n", printed, count, device.phase_name(),
                 device.has_error() ? ": " : "", device.has_error() ? device.last_error().c_str() : "");
    return 1;
  }
  return 0;
}

}  // namespace sen3bot::firmware
