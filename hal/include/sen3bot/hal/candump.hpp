#pragma once
// The log format of can-utils' `candump -l` (and `canplayer`), one frame a line:
//   (1700000000.123456) can0 181#0100000000000000
// The time is the kernel's receive time in seconds; the id has 3 hex digits for a standard
// frame and 8 for an extended one; "R" after '#' is a remote request (an optional digit after
// it is the requested length). An error frame is logged with an 8-digit id carrying the
// kernel's CAN_ERR_FLAG (0x20000000): its low bits are the error classes (bus-off, controller
// state, restarted) and its data the details. CAN FD lines ("##") are refused: the robot's
// bus is classic CAN.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "sen3bot/hal/can.hpp"
#include "sen3bot/hal/result.hpp"

namespace sen3bot::hal {

// Linux's error frame classes (linux/can/error.h), as logged in the id's low bits.
namespace can_error {
constexpr std::uint32_t kFlag = 0x2000'0000;  // CAN_ERR_FLAG: the frame is an error frame
constexpr std::uint32_t kTxTimeout = 0x001;
constexpr std::uint32_t kLostArbitration = 0x002;
constexpr std::uint32_t kController = 0x004;  // data[1]: the controller's state
constexpr std::uint32_t kProtocol = 0x008;
constexpr std::uint32_t kTransceiver = 0x010;
constexpr std::uint32_t kNoAck = 0x020;
constexpr std::uint32_t kBusOff = 0x040;
constexpr std::uint32_t kBusError = 0x080;
constexpr std::uint32_t kRestarted = 0x100;
// data[1] with kController
constexpr std::uint8_t kRxOverflow = 0x01;
constexpr std::uint8_t kTxOverflow = 0x02;
constexpr std::uint8_t kRxWarning = 0x04;
constexpr std::uint8_t kTxWarning = 0x08;
constexpr std::uint8_t kRxPassive = 0x10;
constexpr std::uint8_t kTxPassive = 0x20;
constexpr std::uint8_t kActive = 0x40;  // back to error active
}  // namespace can_error

struct CandumpLine {
  static constexpr std::size_t kMaxInterface = 15;  // IFNAMSIZ less its terminator

  std::int64_t unix_ns = 0;
  std::array<char, kMaxInterface + 1> interface{};  // NUL-terminated
  CanFrame frame;         // for an error frame: id = the error classes, extended, dlc 8
  bool error_frame = false;

  [[nodiscard]] std::string_view interface_name() const noexcept { return interface.data(); }
};

// One line (without or with its newline). Errc::protocol names the column and what it
// expected; Errc::not_supported for a CAN FD line.
[[nodiscard]] Result<CandumpLine> parse_candump_line(std::string_view line);

// The longest line format_candump_line writes, newline included.
constexpr std::size_t kMaxCandumpLine = 64;
// Writes the line and its newline into out (kMaxCandumpLine chars are always enough); returns
// the length, or 0 when out is too small or the line does not hold a valid frame.
std::size_t format_candump_line(const CandumpLine& line, std::span<char> out) noexcept;

}  // namespace sen3bot::hal
