#pragma once
// The CANopen master's side of one CiA 401 digital I/O node, as a state machine with no bus
// and no clock: frames and the time go in, frames to send come out. It brings the node up,
// configures it over SDO, starts it, keeps its inputs (TPDO1) and drives its outputs (RPDO1),
// and watches its heartbeat.
//
//   waiting_boot --boot-up or any heartbeat--> configuring --all SDO writes confirmed--> starting
//   starting --heartbeat "operational"--> operational
//   any state --heartbeat silent for heartbeat_timeout_s--> lost (then waiting_boot again:
//       the node's next heartbeat or boot-up restarts the sequence)
//   any state --boot-up--> configuring (the node reset: its configuration is gone)
//   configuring --SDO abort or no answer after the retries--> fault (retried after
//       fault_retry_s from the reset)
//
// The inputs are valid only in `operational` with a TPDO1 received since it began; whoever
// uses them (the e-stop) must treat anything else as unsafe. Every event is counted.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "sen3bot/canopen/codec.hpp"
#include "sen3bot/hal/clock.hpp"

namespace sen3bot::canopen {

struct IoNodeConfig {
  std::uint8_t node = 0x10;
  // Written to the node's 0x1017 (producer heartbeat time); the master declares the node lost
  // when no heartbeat came for heartbeat_timeout_s.
  std::uint16_t heartbeat_ms = 100;
  double heartbeat_timeout_s = 0.35;
  // Written to TPDO1's event timer (0x1800:5): the inputs come on change and at least this
  // often, so the master has them as soon as the node is started.
  std::uint16_t inputs_period_ms = 100;
  double sdo_timeout_s = 0.1;
  std::uint8_t sdo_retries = 2;
  // What the outputs do when the node loses the master (CiA 401 0x6206 error mode: the outputs
  // that switch, 0x6207 error value: to what): all off by default.
  std::uint8_t outputs_error_mode = 0xFF;
  std::uint8_t outputs_error_value = 0x00;
  // Outputs go out on change and again at this period (a node that rebooted gets them back).
  double outputs_refresh_s = 0.5;
  double fault_retry_s = 2.0;
};

enum class IoNodeState : std::uint8_t { waiting_boot, configuring, starting, operational, lost, fault };
[[nodiscard]] const char* to_string(IoNodeState state) noexcept;

enum class IoNodeEvent : std::uint8_t {
  boot_up,            // the node reset
  heartbeat_lost,
  configured,
  sdo_abort,          // the node refused a configuration write
  sdo_timeout,        // no answer after the retries
  emergency,          // an EMCY with a code other than 0 (error reset)
  emergency_reset,
  unexpected_frame,   // a malformed frame from the node, or an SDO answer nobody asked for
};
constexpr std::size_t kIoNodeEvents = 8;
[[nodiscard]] const char* to_string(IoNodeEvent event) noexcept;

class IoNodeMaster {
 public:
  // Errc::config for a node id outside 1..127 or timings that cannot work (a timeout not
  // longer than the heartbeat period, non-positive times).
  static Status check(const IoNodeConfig& config);
  explicit IoNodeMaster(const IoNodeConfig& config) noexcept;

  // A frame from the bus (any: the node's are picked out) received at now_ns.
  void on_frame(const CanFrame& frame, hal::Nanos now_ns) noexcept;
  // Advances the timers to now_ns and writes the frames to send into out; returns how many.
  // out needs room for 2 frames (more are sent at the next call).
  std::size_t poll(hal::Nanos now_ns, std::span<CanFrame> out) noexcept;

  void set_outputs(std::uint8_t outputs) noexcept { outputs_ = outputs; }
  [[nodiscard]] std::uint8_t outputs() const noexcept { return outputs_; }

  [[nodiscard]] IoNodeState state() const noexcept { return state_; }
  // The 8 inputs (bit i = input i + 1) and whether they are current.
  [[nodiscard]] bool inputs_valid() const noexcept { return state_ == IoNodeState::operational && inputs_seen_; }
  [[nodiscard]] std::uint8_t inputs() const noexcept { return inputs_; }
  [[nodiscard]] hal::Nanos inputs_ns() const noexcept { return inputs_ns_; }
  [[nodiscard]] NmtState node_state() const noexcept { return node_state_; }
  [[nodiscard]] std::uint64_t count(IoNodeEvent event) const noexcept {
    return counts_[static_cast<std::size_t>(event)];
  }
  [[nodiscard]] const Emergency& last_emergency() const noexcept { return last_emergency_; }
  [[nodiscard]] std::uint32_t last_abort() const noexcept { return last_abort_; }
  [[nodiscard]] SdoAddress last_abort_at() const noexcept { return last_abort_at_; }

 private:
  struct Write {
    SdoAddress at;
    std::uint32_t value;
    std::uint8_t size;
  };
  static constexpr std::size_t kWrites = 4;

  void enter(IoNodeState state, hal::Nanos now_ns) noexcept;
  void note(IoNodeEvent event) noexcept { ++counts_[static_cast<std::size_t>(event)]; }
  void begin_configuration(hal::Nanos now_ns) noexcept;

  IoNodeConfig config_;
  std::array<Write, kWrites> writes_{};
  IoNodeState state_ = IoNodeState::waiting_boot;
  hal::Nanos state_since_ns_ = 0;
  hal::Nanos last_heartbeat_ns_ = -1;
  hal::Nanos reset_sent_ns_ = -1;
  NmtState node_state_ = NmtState::boot_up;
  bool heard_ = false;  // a heartbeat or boot-up since the last loss
  // Configuration: the write in flight, when it went out, how often it was sent.
  std::size_t write_index_ = 0;
  bool write_pending_ = false;  // to be sent at the next poll
  hal::Nanos write_sent_ns_ = -1;
  std::uint8_t write_attempts_ = 0;
  bool start_pending_ = false;
  // I/O
  std::uint8_t inputs_ = 0;
  bool inputs_seen_ = false;
  hal::Nanos inputs_ns_ = -1;
  std::uint8_t outputs_ = 0;
  std::uint8_t outputs_sent_ = 0;
  bool outputs_ever_sent_ = false;
  hal::Nanos outputs_sent_ns_ = -1;
  Emergency last_emergency_;
  std::uint32_t last_abort_ = 0;
  SdoAddress last_abort_at_;
  std::array<std::uint64_t, kIoNodeEvents> counts_{};
};

}  // namespace sen3bot::canopen
