#pragma once
// The scenario of tests/data/can/io_node_estop.log: the master and the emulated CiA 401 I/O
// node on one bus, recorded as `candump -l can0` would have written it. The generator
// (canopen_generate_estop_log) writes the log from these constants; the replay test reads it
// and checks the master's timeline against them.
//
//   0.000 s  the master's first cycle: NMT reset communication to the node (not powered yet)
//   0.300 s  the node powers up: boot-up, the master configures it over SDO and starts it
//   3.000 s  the e-stop is pressed: input 1 goes low (the chain is active-low: closed = 1)
//   4.500 s  the node sends an EMCY (0x2310, current at the outputs: the buzzer's driver)
//   6.000 s  the e-stop is released: input 1 high again
//   8.000 s  the node's cable is pulled: nothing more from it; the master declares it lost
//   9.000 s  the log ends
//
// The robot's application, as the replay repeats it: the status light is green (output 2)
// while the inputs are valid and the e-stop chain is closed, red (output 3) otherwise.
#include <cstdint>
#include <string>

#include "sen3bot/canopen/io_node.hpp"
#include "sen3bot/hal/clock.hpp"

namespace sen3bot::canopen::estop_log {

// 2024-06-03 09:00:00 UTC: the master's first 10 ms cycle; its cycles follow on that grid.
constexpr std::int64_t kStartUnixNs = 1'717'405'200'000'000'000;
constexpr std::uint8_t kNode = 0x10;
constexpr const char* kInterface = "can0";

constexpr hal::Nanos kMasterCycle = hal::millis(10);
constexpr hal::Nanos kPowerUp = hal::millis(300);
constexpr hal::Nanos kPress = hal::millis(3000);
constexpr hal::Nanos kEmergency = hal::millis(4500);
constexpr hal::Nanos kRelease = hal::millis(6000);
constexpr hal::Nanos kUnplug = hal::millis(8000);
constexpr hal::Nanos kEnd = hal::millis(9000);

constexpr std::uint8_t kInputsNormal = 0x01;   // e-stop chain closed
constexpr std::uint8_t kInputsPressed = 0x00;  // chain open: input 1 low
constexpr std::uint8_t kGreen = 0x02;          // output 2
constexpr std::uint8_t kRed = 0x04;            // output 3
constexpr std::uint16_t kEmergencyCode = 0x2310;
constexpr std::uint8_t kEmergencyRegister = 0x03;  // generic error + current

// Green only while the node's inputs are current and the e-stop chain is closed.
[[nodiscard]] inline std::uint8_t light_for(const IoNodeMaster& master) noexcept {
  return master.inputs_valid() && (master.inputs() & 0x01) != 0 ? kGreen : kRed;
}

// The whole log, one candump line per frame (deterministic: the same text on every run).
[[nodiscard]] std::string make_log();

}  // namespace sen3bot::canopen::estop_log
