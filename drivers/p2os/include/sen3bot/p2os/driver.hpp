#pragma once
// The P2OS client state machine: handshake, keep-alive, setpoints, odometry. Non-blocking
// and time-driven: step(now) reads what is there, advances timers and writes what is due,
// over any hal::ByteStream, so it runs the same in real time and in lockstep simulation.
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string>

#include "sen3bot/hal/byte_stream.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/mem/ring_buffer.hpp"
#include "sen3bot/p2os/codec.hpp"
#include "sen3bot/p2os/odometry.hpp"
#include "sen3bot/p2os/types.hpp"

namespace sen3bot::p2os {

// Rates a client tries when probing, in ARIA/Player order.
inline constexpr std::array<std::uint32_t, 5> kProbeBauds = {9600, 38400, 19200, 115200, 57600};

// Everything the driver and its task need; plain values with working defaults for a P3-DX.
struct P2osConfig {
  // Device path ("/dev/ttyUSB0", a pty symlink) or "tcp://host:port" (MobileSim/AMRISim, 8101).
  std::string port = "/dev/ttyS0";
  // Serial rate to open at; ARCOS powers up at its FLASH HostBaud, 9600 on a P3.
  std::uint32_t baud = 9600;
  // Try the kProbeBauds rates in turn when the robot does not answer SYNC0 (serial only).
  bool probe_bauds = false;
  // Missed SYNC replies at one rate before moving to the next probe rate.
  int sync_misses_per_baud = 2;
  // After CONFIGpac says AutoBaud == 2, switch the link up to this rate with HOSTBAUD
  // (serial only; 0 = stay at `baud`). Reverts if the robot stays silent at the new rate.
  std::uint32_t switch_to_baud = 0;
  // How long to wait for a packet after switching baud before reverting.
  int baud_switch_timeout_ms = 900;
  // Wait per handshake step (SYNC0, SYNC1, SYNC2, OPEN -> first SIP) before retrying.
  int sync_timeout_ms = 1000;
  // No SIP for this long while connected: the link is reported lost and re-synced.
  int link_timeout_ms = 600;
  // PULSE when nothing was sent for this long (ARIA: 500 ms; the robot's watchdog is 2 s).
  int pulse_interval_ms = 500;
  // A non-zero velocity setpoint is re-sent at least this often.
  int setpoint_refresh_ms = 500;
  // No fresh setpoint from the planner for this long: stop (rosaria's cmd_vel_timeout).
  int command_timeout_ms = 600;
  // Minimum gap between two command packets (the manual asks for 3-5 ms).
  int command_spacing_ms = 4;
  // A stream that failed is reopened after this delay (by the task).
  int reopen_delay_ms = 500;
  // TCP connect timeout for the first open (in the task's init, where blocking is fine).
  int connect_timeout_ms = 2000;
  // TCP connect timeout when the task reopens from step(): bounds how long a step can block
  // while a simulator or bridge is unreachable.
  int reopen_connect_timeout_ms = 20;
  // Ask for CONFIGpac after OPEN (limits and AutoBaud).
  bool request_config = true;
  // Ask for continuous ENCODERpacs after OPEN.
  bool request_encoders = false;
  // BUMPSTALL mode to send after OPEN: -1 leave as is, 0 none, 1 front, 2 rear, 3 both.
  int bumpstall = -1;
  // Braking deceleration to set with SETA after OPEN (0: leave the robot's own, 300 mm/s^2 on a
  // P3-DX as it powers up). The safety filter's stop zone is sized with the same number.
  std::int32_t trans_decel_mm_s2 = 0;
  // Setpoint limits applied before encoding (P3-DX: 2.2 m/s, 500 deg/s absolute maxima).
  double max_v_m_s = 1.5;
  double max_omega_rad_s = 5.0;
  // SIP unit conversions (DistConvFactor etc. of the robot's parameter file).
  ConversionFactors conversion;
};

// Lets the driver change the link rate (baud probing, HOSTBAUD). Implemented over a
// SerialPort by the task; absent for TCP, pty-less tests and replays.
using BaudControl = hal::BaudControl;

class P2osDriver {
 public:
  // Commands waiting to be paced out.
  static constexpr std::size_t kQueueDepth = 16;
  static constexpr std::size_t kReadChunkBytes = 256;

  explicit P2osDriver(const P2osConfig& config);

  // Starts talking to a robot over `stream` (kept by reference until detach()).
  void attach(hal::ByteStream& stream, hal::Nanos now_ns, BaudControl* baud_control = nullptr,
              std::uint32_t current_baud = 0) noexcept;
  void detach() noexcept;
  [[nodiscard]] bool attached() const noexcept { return stream_ != nullptr; }

  // One non-blocking pass: read, parse, run timers, write what is due.
  void step(hal::Nanos now_ns) noexcept;

  // A fresh setpoint from the planner (resets the command timeout).
  void set_setpoint(const BaseSetpoint& setpoint, hal::Nanos now_ns) noexcept;

  // Starts a clean shutdown: zero velocity, ENABLE 0, CLOSE; closed() once all were sent.
  void request_close(hal::Nanos now_ns) noexcept;
  [[nodiscard]] bool closed() const noexcept { return state_.link == LinkState::closed; }

  [[nodiscard]] const BaseState& state() const noexcept { return state_; }
  // True once per SIP parsed since the last call.
  bool take_new_sip() noexcept {
    const bool fresh = new_sip_;
    new_sip_ = false;
    return fresh;
  }
  // The stream failed (disconnected or I/O error); the owner should reopen and attach.
  [[nodiscard]] const std::optional<Error>& stream_error() const noexcept { return stream_error_; }
  [[nodiscard]] const SyncReply& robot_identity() const noexcept { return identity_; }
  [[nodiscard]] const std::optional<ConfigPacket>& robot_config() const noexcept { return config_packet_; }
  [[nodiscard]] const Sip& last_sip() const noexcept { return last_sip_; }
  [[nodiscard]] const ParserStats& parser_stats() const noexcept { return parser_.stats(); }
  [[nodiscard]] std::uint32_t current_baud() const noexcept { return baud_; }
  // When the last connect completed and how long its handshake took.
  [[nodiscard]] hal::Nanos last_connect_duration_ns() const noexcept { return connect_duration_ns_; }
  [[nodiscard]] std::uint64_t packets_sent() const noexcept { return packets_sent_; }
  [[nodiscard]] std::uint64_t commands_dropped() const noexcept { return commands_dropped_; }

 private:
  enum class Phase : std::uint8_t {
    idle,
    sync0,
    sync1,
    sync2,
    dislodge,  // robot still open from an earlier client: CLOSE sent, letting it settle
    opening,   // OPEN sent, waiting for the first SIP
    running,
    closing,
    closed,
  };
  enum class BaudSwitch : std::uint8_t { none, hostbaud_queued, settle, verify, done };

  void on_frame(const Frame& frame, hal::Nanos now_ns) noexcept;
  void on_sip(const Frame& frame, hal::Nanos now_ns) noexcept;
  void enter_sync(hal::Nanos now_ns) noexcept;
  void send_sync(int n, hal::Nanos now_ns) noexcept;
  void handshake_miss(hal::Nanos now_ns) noexcept;
  void link_lost(hal::Nanos now_ns) noexcept;
  void run_timers(hal::Nanos now_ns) noexcept;
  void run_baud_switch(hal::Nanos now_ns) noexcept;
  void update_setpoints(hal::Nanos now_ns) noexcept;
  void queue(const Packet& packet) noexcept;
  void flush_tx(hal::Nanos now_ns) noexcept;
  void fail_stream(const Error& error) noexcept;

  P2osConfig config_;
  hal::ByteStream* stream_ = nullptr;
  BaudControl* baud_control_ = nullptr;
  std::uint32_t baud_ = 0;
  std::uint32_t open_baud_ = 0;
  std::size_t probe_index_ = 0;
  FrameParser parser_;
  Odometry odometry_;
  BaseState state_;
  Sip last_sip_{};
  SyncReply identity_{};
  std::optional<ConfigPacket> config_packet_;
  std::optional<Error> stream_error_;

  Phase phase_ = Phase::idle;
  hal::Nanos phase_deadline_ns_ = 0;
  hal::Nanos sync_started_ns_ = 0;
  hal::Nanos connect_duration_ns_ = 0;
  int misses_ = 0;
  bool ever_connected_ = false;
  bool new_sip_ = false;
  hal::Nanos last_sip_ns_ = 0;

  BaudSwitch baud_switch_ = BaudSwitch::none;
  hal::Nanos baud_switch_deadline_ns_ = 0;
  std::uint32_t baud_before_switch_ = 0;
  hal::Nanos last_rx_frame_ns_ = 0;

  // Setpoints, in wire units.
  BaseSetpoint setpoint_{};
  hal::Nanos setpoint_stamp_ns_ = 0;
  bool have_setpoint_ = false;
  std::int32_t sent_vel_mm_s_ = 0;
  std::int32_t sent_rvel_deg_s_ = 0;
  bool sent_enable_ = false;
  hal::Nanos last_velocity_sent_ns_ = 0;
  // Velocity packets are coalesced: only the latest value goes out when the link is free.
  bool vel_dirty_ = false;
  bool rvel_dirty_ = false;

  mem::RingBuffer<Packet, kQueueDepth> queue_;
  Packet in_flight_{};
  std::size_t in_flight_offset_ = 0;
  bool have_in_flight_ = false;
  hal::Nanos last_tx_ns_ = 0;
  hal::Nanos last_packet_start_ns_ = 0;
  std::uint64_t packets_sent_ = 0;
  std::uint64_t commands_dropped_ = 0;
  std::array<std::uint8_t, kReadChunkBytes> read_buffer_{};
};

}  // namespace sen3bot::p2os
