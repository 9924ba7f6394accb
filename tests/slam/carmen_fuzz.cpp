// Fuzzes the CARMEN line parser: the input is cut at newlines and each piece fed as one line. A
// scan it accepts must hold what the mapper relies on: a beam count in range, finite geometry, and
// finite ranges that are not negative.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "sen3bot/slam/carmen.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  static sen3bot::slam::LaserRecord record;
  sen3bot::slam::CarmenParser parser("fuzz.log");
  std::string_view text(reinterpret_cast<const char*>(data), size);
  std::uint64_t line = 0;
  while (!text.empty()) {
    const std::size_t eol = text.find('\n');
    const std::string_view one = text.substr(0, eol);
    text.remove_prefix(eol == std::string_view::npos ? text.size() : eol + 1);
    auto scan = parser.line(one, ++line, record);
    if (!scan.ok() || !*scan) continue;  // an error ends nothing here: the next line is parsed afresh
    if (record.count == 0 || record.count > sen3bot::slam::kMaxBeams || record.source_line != line) {
      __builtin_trap();
    }
    if (!(record.max_range_m > 0.0) || !std::isfinite(record.max_range_m)) __builtin_trap();
    if (!std::isfinite(record.start_angle_rad) || !std::isfinite(record.angle_increment_rad)) {
      __builtin_trap();
    }
    if (!std::isfinite(record.time_s) || !std::isfinite(record.odometry.theta_rad)) __builtin_trap();
    if (!std::isfinite(record.laser_mount.x_m) || !std::isfinite(record.laser_mount.theta_rad)) {
      __builtin_trap();
    }
    for (std::uint32_t i = 0; i < record.count; ++i) {
      if (!std::isfinite(record.ranges[i]) || record.ranges[i] < 0.0f) __builtin_trap();
    }
  }
  const auto& counts = parser.counts();
  if (counts.scans + counts.odometry + counts.skipped > counts.lines) __builtin_trap();
  return 0;
}
