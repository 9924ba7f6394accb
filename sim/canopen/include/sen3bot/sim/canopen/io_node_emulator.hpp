#pragma once
// A CiA 401 digital I/O node as the robot's CAN module behaves, for lockstep tests and the
// simulated robot: an object dictionary answered over expedited SDO, the NMT state machine,
// a heartbeat producer (0x1017), 8 inputs sent in TPDO1 when they change and at TPDO1's event
// timer (0x1800:5; operational only),
// 8 outputs set by RPDO1, and the outputs' error behaviour (0x6206/0x6207) when the node
// loses its master. Faults can be injected: silence, a reboot in the middle of operation, an
// EMCY, a refused configuration write and malformed frames.
#include <cstddef>
#include <cstdint>
#include <span>

#include "sen3bot/canopen/codec.hpp"
#include "sen3bot/hal/clock.hpp"

namespace sen3bot::canopen {

struct IoNodeEmulatorConfig {
  std::uint8_t node = 0x10;
  std::uint16_t heartbeat_ms = 0;  // 0x1017 at power-up (0: silent until configured)
  std::uint32_t device_type = 0x000F0191;  // 0x1000: CiA 401, digital inputs and outputs
  std::uint32_t vendor_id = 0x0000053E;    // 0x1018:1
};

class IoNodeEmulator {
 public:
  explicit IoNodeEmulator(const IoNodeEmulatorConfig& config) noexcept : config_(config) {}

  // Power-up: the node boots, sends its boot-up and enters pre-operational.
  void power_up(hal::Nanos now_ns) noexcept;
  void on_frame(const CanFrame& frame, hal::Nanos now_ns) noexcept;
  // Writes what the node sends by now_ns (at most out.size(); more at the next call).
  std::size_t poll(hal::Nanos now_ns, std::span<CanFrame> out) noexcept;

  // The wiring: the inputs' levels (bit i = input i + 1); a change is sent at the next poll.
  void set_inputs(std::uint8_t inputs) noexcept { inputs_ = inputs; }
  [[nodiscard]] std::uint8_t outputs() const noexcept { return outputs_; }
  [[nodiscard]] NmtState state() const noexcept { return state_; }
  [[nodiscard]] std::uint16_t heartbeat_ms() const noexcept { return heartbeat_ms_; }

  // --- Faults ---
  // Sends nothing (and answers nothing) while silent: a cut cable or a dead node.
  void set_silent(bool silent) noexcept { silent_ = silent; }
  // Resets in the middle of operation: boot-up, pre-operational, configuration gone.
  void reboot(hal::Nanos now_ns) noexcept { power_up(now_ns); }
  // Queues an EMCY (code 0: error reset).
  void raise_emergency(std::uint16_t code, std::uint8_t error_register) noexcept;
  // The next SDO write to this index is refused with this abort code.
  void refuse_write(std::uint16_t index, std::uint32_t code) noexcept {
    refused_index_ = index;
    refused_code_ = code;
  }
  // Queues a heartbeat frame with no data and a TPDO1 with no data.
  void send_malformed() noexcept { malformed_pending_ = true; }
  // The node lost its master (its own bus error, or a heartbeat it consumes): the outputs
  // take their error values.
  void communication_error() noexcept;

 private:
  [[nodiscard]] Result<CanFrame> answer(const Sdo& request) noexcept;

  IoNodeEmulatorConfig config_;
  NmtState state_ = NmtState::boot_up;
  bool powered_ = false;
  bool silent_ = false;
  bool boot_pending_ = false;
  hal::Nanos next_heartbeat_ns_ = -1;
  std::uint16_t heartbeat_ms_ = 0;
  std::uint8_t inputs_ = 0;
  std::uint8_t inputs_sent_ = 0;
  bool inputs_ever_sent_ = false;
  std::uint16_t tpdo_event_ms_ = 0;
  hal::Nanos next_tpdo_ns_ = -1;
  std::uint8_t outputs_ = 0;
  std::uint8_t error_mode_ = 0xFF;
  std::uint8_t error_value_ = 0x00;
  bool sdo_answer_pending_ = false;
  CanFrame sdo_answer_;
  bool emcy_pending_ = false;
  Emergency emcy_;
  bool malformed_pending_ = false;
  std::uint16_t refused_index_ = 0;
  std::uint32_t refused_code_ = 0;
};

}  // namespace sen3bot::canopen
