// LMS200 command-line entry points: decode lms200, lms200-emulator, scan.
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
#include "sen3bot/hal/serial.hpp"
#include "sen3bot/lms200/capture_decode.hpp"
#include "sen3bot/lms200/device.hpp"
#include "sen3bot/lms200/emulator.hpp"
#include "sen3bot/lms200/pty_runner.hpp"
#include "sen3bot/lms200/task.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/world/world.hpp"

namespace sen3bot::firmware {

namespace {

std::atomic<bool> g_lms200_stop{false};
void on_lms200_signal(int) { g_lms200_stop.store(true); }

// SIGINT/SIGTERM set g_lms200_stop while this object lives.
class StopSignals {
 public:
  StopSignals() {
    g_lms200_stop.store(false);
    struct sigaction action {};
    action.sa_handler = on_lms200_signal;
    sigemptyset(&action.sa_mask);
    sigaction(SIGINT, &action, &old_int_);
    sigaction(SIGTERM, &action, &old_term_);
  }
  ~StopSignals() {
    sigaction(SIGINT, &old_int_, nullptr);
    sigaction(SIGTERM, &old_term_, nullptr);
  }
  StopSignals(const StopSignals&) = delete;
  StopSignals& operator=(const StopSignals&) = delete;

 private:
  struct sigaction old_int_ {};
  struct sigaction old_term_ {};
};

bool parse_u32(std::string_view text, std::uint32_t& out) {
  const std::string s(text);
  char* end = nullptr;
  errno = 0;
  const unsigned long v = std::strtoul(s.c_str(), &end, 0);
  if (errno != 0 || end == s.c_str() || *end != '\0' || v > 0xFFFFFFFFul) return false;
  out = static_cast<std::uint32_t>(v);
  return true;
}

bool parse_double(std::string_view text, double& out) {
  const std::string s(text);
  char* end = nullptr;
  errno = 0;
  out = std::strtod(s.c_str(), &end);
  return errno == 0 && end != s.c_str() && *end == '\0' && std::isfinite(out);
}

// "180/0.5" -> {180, 50}
bool parse_variant(std::string_view text, lms200::Variant& out) {
  const std::size_t slash = text.find('/');
  if (slash == std::string_view::npos) return false;
  std::uint32_t angle = 0;
  double res_deg = 0;
  if (!parse_u32(text.substr(0, slash), angle) || !parse_double(text.substr(slash + 1), res_deg)) return false;
  out.angle_deg = static_cast<std::uint16_t>(angle);
  out.resolution_cdeg = static_cast<std::uint16_t>(std::lround(res_deg * 100));
  return lms200::valid_variant(out);
}

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

void print_scan_json(const lms200::LaserScan& s, std::FILE* out) {
  std::fprintf(out,
               "{\"t_s\":%.6f,\"seq\":%llu,\"angle_min_rad\":%.6f,\"angle_increment_rad\":%.8f,\"units\":\"%s\","
               "\"baud\":%u,\"count\":%u,\"ranges_m\":[",
               hal::to_seconds(s.stamp_ns), static_cast<unsigned long long>(s.sequence), s.angle_min_rad,
               s.angle_increment_rad, lms200::to_string(static_cast<lms200::Units>(s.units)).data(), s.baud, s.count);
  for (std::size_t i = 0; i < s.count; ++i) {
    if (i) std::fputc(',', out);
    if (s.valid(i)) {
      std::fprintf(out, "%.3f", s.ranges_m[i]);
    } else {
      std::fputs("null", out);
    }
  }
  std::fputs("]}\n", out);
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

int lms200_emulator_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  std::string link;
  std::string map_path;
  double pose[3] = {0, 0, 0};
  bool have_pose = false;
  lms200::EmulatorOptions options;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    if (i + 1 >= argc) {
      std::fprintf(err, "sen3bot lms200-emulator: %s needs a value\n", argv[i]);
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
        std::fprintf(err, "sen3bot lms200-emulator: --pose: expected X,Y,TH (m, m, rad), got '%s'\n", v.c_str());
        return 2;
      }
      have_pose = true;
    } else if (arg == "--status" && parse_u32(value, number) && number <= 0xFF) {
      options.status = static_cast<std::uint8_t>(number);
    } else if (arg == "--baud" && parse_u32(value, number) && lms200::baud_mode(number)) {
      options.initial_baud = number;
    } else {
      std::fprintf(err, "sen3bot lms200-emulator: bad option '%s %s' (see sen3bot --help)\n", argv[i - 1], argv[i]);
      return 2;
    }
  }
  if (link.empty()) {
    std::fprintf(err, "sen3bot lms200-emulator: --pty LINK is required\n");
    return 2;
  }
  std::unique_ptr<lms200::RangeSource> world;
  if (!map_path.empty()) {
    Result<nav::OccupancyMap> map = nav::load_map(map_path);
    if (!map) {
      std::fprintf(err, "sen3bot lms200-emulator: %s\n", map.error().c_str());
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
    std::fprintf(err, "sen3bot lms200-emulator: %s\n", runner.error().c_str());
    return 1;
  }
  if (Status s = (*runner)->link(link); !s) {
    std::fprintf(err, "sen3bot lms200-emulator: %s\n", s.error().c_str());
    return 1;
  }
  StopSignals signals;
  (*runner)->start();
  const lms200::SensorPose p = world->sensor_pose();
  std::fprintf(out, "lms200 emulator on %s -> %.*s at %u baud, status 0x%02x, %s, pose %.3f,%.3f,%.3f; until SIGINT\n",
               link.c_str(), static_cast<int>((*runner)->slave_path().size()), (*runner)->slave_path().data(),
               options.initial_baud, options.status, map_path.empty() ? "built-in room" : map_path.c_str(), p.x_m,
               p.y_m, p.theta_rad);
  std::fflush(out);
  hal::PosixClock clock;
  while (!g_lms200_stop.load()) clock.sleep_until(clock.now() + hal::millis(50));
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
      ok = parse_variant(value, config.variant);
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
  Result<std::unique_ptr<hal::ByteStream>> stream = hal::open_byte_stream(config.port, config.baud);
  if (!stream) {
    std::fprintf(err, "sen3bot scan: %s\n", stream.error().c_str());
    return 1;
  }
  std::unique_ptr<lms200::SerialLineControl> line;
  if (auto* serial = dynamic_cast<hal::SerialPort*>(stream->get())) line = std::make_unique<lms200::SerialLineControl>(*serial);
  lms200::Lms200Device device(config, **stream, line.get());
  StopSignals signals;
  hal::PosixClock clock;
  const hal::Nanos give_up = clock.now() + static_cast<hal::Nanos>(timeout_s * 1e9);
  device.start(clock.now());
  std::uint32_t printed = 0;
  lms200::LaserScan scan;
  while (printed < count && clock.now() < give_up && !g_lms200_stop.load()) {
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
