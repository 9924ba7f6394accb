#pragma once
// Laser scans: the fixed-size bus message and the small view the navigation cores read.
#include <algorithm>
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <type_traits>

#include "sen3bot/hal/clock.hpp"

namespace sen3bot::msg {

// One planar scan in the sensor frame: beam i points at angle_min + i * increment.
struct ScanView {
  std::span<const float> ranges_m;
  float angle_min_rad = 0.0f;
  float increment_rad = 0.0f;
  float range_min_m = 0.0f;
  float range_max_m = 0.0f;  // readings >= this are "no return"
  hal::Nanos stamp_ns = 0;
};

// A scan as a fixed-size bus message (LMS200: at most 401 beams at 0.25 deg over 100 deg,
// 361 at 0.5 deg over 180 deg). NaN ranges are unreadable beams.
struct ScanMessage {
  static constexpr std::size_t kMaxBeams = 401;
  std::array<float, kMaxBeams> ranges_m{};
  std::uint16_t count = 0;
  float angle_min_rad = 0.0f;
  float increment_rad = 0.0f;
  float range_min_m = 0.0f;
  float range_max_m = 0.0f;
  hal::Nanos stamp_ns = 0;

  [[nodiscard]] ScanView view() const noexcept {
    return {std::span<const float>(ranges_m.data(), std::min<std::size_t>(count, kMaxBeams)), angle_min_rad,
            increment_rad, range_min_m, range_max_m, stamp_ns};
  }
};
static_assert(std::is_trivially_copyable_v<ScanMessage>);

}  // namespace sen3bot::msg
