#pragma once
// The robot's safety I/O (a CANopen I/O node on the robot: the e-stop chain, bumpers, a reset
// button, the status light and buzzer), as the CAN I/O task reads it, and the operating mode
// the status light shows.
#include <cstdint>
#include <type_traits>

#include "sen3bot/hal/clock.hpp"

namespace sen3bot::msg {

struct SafetyIo {
  // The node is operational with current inputs, on a bus that is not off. Anything else is
  // treated as an open e-stop chain.
  bool healthy = false;
  bool ever_healthy = false;  // since start-up
  bool estop = false;         // the chain is open: pressed, or a wire cut (inputs valid only)
  bool bumper = false;        // a bumper is pressed (inputs valid only)
  std::uint32_t resets = 0;   // reset requests so far (rising edges of the reset input)
  std::uint8_t inputs = 0;    // raw levels, bit i = input i + 1
  std::uint8_t outputs = 0;   // what the task asked the node for
  hal::Nanos inputs_ns = -1;  // when the node last sent its inputs
};
static_assert(std::is_trivially_copyable_v<SafetyIo>);

// What the robot is doing, as the status light shows it: wait4col is the collaborative
// mode's waiting state; fault means a safety stop holds the robot.
enum class LightMode : std::uint8_t { off, idle, driving, wait4col, fault };
[[nodiscard]] constexpr const char* to_string(LightMode mode) noexcept {
  switch (mode) {
    case LightMode::off: return "off";
    case LightMode::idle: return "idle";
    case LightMode::driving: return "driving";
    case LightMode::wait4col: return "wait4col";
    case LightMode::fault: return "fault";
  }
  return "unknown";
}

// Requests from the collaborative mode that the rest of the robot shows.
struct OperatingMode {
  bool wait4col = false;
};
static_assert(std::is_trivially_copyable_v<OperatingMode>);

}  // namespace sen3bot::msg
