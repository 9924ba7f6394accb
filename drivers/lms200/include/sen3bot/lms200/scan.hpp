#pragma once
// The laser scan as the rest of the firmware sees it: fixed size and trivially copyable, so
// it travels on the bus (tasks::Topic) by copy. Angles follow the robot convention: 0 rad
// straight ahead, counter-clockwise positive; the LMS scans from right to left, so index 0
// is the rightmost beam at angle_min_rad.
#include <array>
#include <cstdint>
#include <type_traits>

#include "sen3bot/hal/clock.hpp"

namespace sen3bot::lms200 {

enum class LinkState : std::uint8_t {
  idle = 0,         // not started
  probing = 1,      // looking for the scanner's baud rate
  configuring = 2,  // baud switch, variant, units, measuring mode
  streaming = 3,    // continuous scans arriving
  error = 4,        // waiting to restart the sequence (see last error)
  stopped = 5,      // cleanly stopped on request
};

// Per-value flags (LaserScan::flags); the same bits as protocol.hpp value_flag.
namespace scan_flag {
inline constexpr std::uint8_t kValid = 0x01;    // ranges_m holds a distance
inline constexpr std::uint8_t kFieldA = 0x02;   // object in evaluation field A
inline constexpr std::uint8_t kFieldB = 0x04;
inline constexpr std::uint8_t kFieldC = 0x08;
inline constexpr std::uint8_t kDazzle = 0x10;   // the beam was dazzled
inline constexpr std::uint8_t kReflectorShift = 5;  // bits 5-7: reflector level (modes 01/03/05)
}  // namespace scan_flag

struct LaserScan {
  static constexpr std::size_t kMaxRanges = 401;

  // Estimated end of the sweep: arrival of the telegram's last byte minus its transmission
  // time at the current baud (10 bits per byte).
  hal::Nanos stamp_ns = 0;
  hal::Nanos received_ns = 0;   // when the last byte was read
  std::uint64_t sequence = 0;   // scans delivered since start, 1 for the first

  float angle_min_rad = 0;
  float angle_increment_rad = 0;
  float scan_period_s = 0;      // mirror time for one complete scan (1/75, 2/75, 4/75 s)
  float range_max_m = 0;        // largest distance the units and mode can express
  std::uint16_t count = 0;      // values in ranges_m / flags / invalid_reason
  std::uint8_t units = 0;       // lms200::Units as sent in the telegram
  std::uint8_t measuring_mode = 0;
  std::uint8_t status = 0;      // the telegram's status byte
  LinkState link_state = LinkState::idle;
  std::uint8_t device_status = 0;  // B1 device status from start-up: 0 OK, otherwise a fault
  bool scanner_fault = false;      // device_status, or level error/fatal in `status` (Lms200Device::scanner_fault)
  std::uint32_t baud = 0;

  // Device counters at the time of this scan.
  std::uint32_t crc_errors = 0;
  std::uint32_t dropped_bytes = 0;  // garbage + abandoned partial telegrams
  std::uint32_t restarts = 0;
  std::uint32_t stale_events = 0;

  std::array<float, kMaxRanges> ranges_m{};            // NaN where not valid
  std::array<std::uint8_t, kMaxRanges> flags{};         // scan_flag bits
  std::array<std::uint8_t, kMaxRanges> invalid_reason{};  // lms200::InvalidReason, 0 if valid

  [[nodiscard]] bool valid(std::size_t i) const noexcept { return (flags[i] & scan_flag::kValid) != 0; }
  [[nodiscard]] float angle_rad(std::size_t i) const noexcept {
    return angle_min_rad + static_cast<float>(i) * angle_increment_rad;
  }
};

static_assert(std::is_trivially_copyable_v<LaserScan>, "LaserScan crosses threads by copy");

}  // namespace sen3bot::lms200
