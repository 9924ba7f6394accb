#pragma once
// A Pioneer 3-DX controller (ARCOS) on the other end of a byte stream: handshake, SIPs every
// SipCycle with sonar, CONFIGpac, ENCODERpac, unicycle kinematics with acceleration limits,
// the 2 s watchdog, "already open" after a client vanished, lenient argument parsing, and
// fault injection. A pure step(now) core: the pty/TCP runners and lockstep tests drive it.
#include <array>
#include <cstddef>
#include <cstdint>
#include <string>

#include "sen3bot/hal/byte_stream.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/p2os/codec.hpp"
#include "sen3bot/p2os/odometry.hpp"

namespace sen3bot::p2os {

// Asks the simulated world about the robot's surroundings. Default: empty space.
class EmulatorWorld {
 public:
  virtual ~EmulatorWorld() = default;
  // True if moving the robot body from `from` to `to` (world frame) hits something; the
  // robot then stalls (stays at `from`, stall bits set).
  virtual bool motion_blocked(const Pose2& from, const Pose2& to) {
    (void)from;
    (void)to;
    return false;
  }
  // Range seen by a sonar disc at `sensor` (world frame, pointing along theta), in m.
  virtual double sonar_range_m(const Pose2& sensor, double max_range_m) {
    (void)sensor;
    return max_range_m;
  }
};

struct EmulatorConfig {
  std::string name = "Sen3Bot";  // SYNC2 reply and CONFIGpac; <= 19 characters
  std::string robot_class = "Pioneer";
  std::string subclass = "p3dx-sh";
  std::string serial = "EMU";
  std::string firmware_version = "E.1";
  int sip_cycle_ms = 100;
  int watchdog_ms = 2000;
  // After a watchdog stop: false (default) drops the setpoints, so only a fresh motion command
  // moves the robot again; true resumes them on the next packet, PULSE included, as the ARCOS
  // manual describes (a reconnecting client's SYNC0 then restarts the dead client's motion).
  bool watchdog_resumes = false;
  bool follow_client_sync = false;  // out-of-sequence SYNC: follow it (AMRISim) or restart (ARCOS)
  std::uint8_t auto_baud = 2;       // CONFIGpac AutoBaud; 2 makes ARIA send HOSTBAUD
  std::uint8_t host_baud_code = 0;  // 9600
  std::uint16_t battery_dv = 130;
  // Limits and working values (CONFIGpac; what ARIA re-sends at connect).
  std::uint16_t trans_vel_top_mm_s = 2200;
  std::uint16_t rot_vel_top_deg_s = 500;
  std::uint16_t trans_acc_top_mm_s2 = 2000;
  std::uint16_t rot_acc_top_deg_s2 = 500;
  std::uint16_t trans_vel_max_mm_s = 1200;
  std::uint16_t rot_vel_max_deg_s = 300;
  std::uint16_t trans_accel_mm_s2 = 300;
  std::uint16_t trans_decel_mm_s2 = 300;
  std::uint16_t rot_accel_deg_s2 = 100;
  std::uint16_t rot_decel_deg_s2 = 100;
  std::uint16_t ticks_mm = 128;
  std::uint16_t rev_count = 16570;
  bool sonar_enabled = true;
  int sonar_count = 16;
  double sonar_max_range_m = 5.0;
  // ARCOS fires one disc of each bank every sonar_cycle_ms (0: every disc in every SIP).
  int sonar_cycle_ms = 40;
  double sonar_miss_rate = 0.02;  // a reading lost to a glancing surface reads as max range
  double diff_conv_rad_per_mm = 0.0056;  // wheel speeds <-> yaw rate
  std::uint32_t noise_seed = 1;          // fault-injection noise is deterministic
  // The odometry's systematic errors (a wheel diameter and a wheel base a little off): the
  // distance it counts is (1 + scale) times the true one, a turn (1 + turn) times. 0: exact.
  double odometry_scale_error = 0.0;
  double odometry_turn_error = 0.0;
};

enum class EmulatorState : std::uint8_t {
  sync_wait,  // waiting for SYNC0/1/2 (echoes, SYNC2 reply)
  synced,     // SYNC2 answered, waiting for OPEN
  open,       // SIPs flowing
};

struct ReceivedCommand {
  hal::Nanos t_ns = 0;
  std::uint8_t command = 0;
  ArgKind kind = ArgKind::none;
  std::int32_t value = 0;
};

struct EmulatorStats {
  std::uint64_t packets_received = 0;
  std::uint64_t bad_checksums = 0;  // client frames with a wrong checksum (should stay 0)
  std::uint64_t sips_sent = 0;
  std::uint64_t bytes_dropped = 0;  // output lost because the client did not read
  std::uint64_t watchdog_stops = 0;
  std::uint64_t sessions_opened = 0;
  std::uint64_t sessions_closed = 0;  // CLOSE received while open
  std::array<std::uint32_t, 256> command_counts{};
};

class P2osEmulator {
 public:
  static constexpr std::size_t kTxBufferBytes = 8192;
  static constexpr std::size_t kCommandLogDepth = 128;

  explicit P2osEmulator(const EmulatorConfig& config = {});

  // One non-blocking pass over `stream`: read commands, advance the robot to now, send what
  // is due. The stream may change between calls (a new TCP client). Returns the stream's
  // error when it failed (the client or device went away); the robot keeps its state.
  Status step(hal::ByteStream& stream, hal::Nanos now_ns) noexcept;

  // A new session, as at power-on or on a new TCP connection: sync-wait, motors off,
  // setpoints cleared, odometry and wheel counters zeroed. The ground truth is untouched.
  void reset_session() noexcept;

  // True once after the client's CLOSE ended an open session (cleared by this call and by
  // reset_session()); a TCP runner then closes the connection, as AMRISim does.
  [[nodiscard]] bool take_session_closed() noexcept;
  // When the last valid client packet arrived (the watchdog's reference).
  [[nodiscard]] hal::Nanos last_packet_ns() const noexcept { return last_packet_ns_; }

  // Ground truth in the world frame (m, rad); independent of the controller's odometry.
  [[nodiscard]] Pose2 ground_truth() const noexcept { return truth_; }
  void set_ground_truth(const Pose2& pose) noexcept { truth_ = pose; }
  // The controller's own odometry (what the SIPs report), m and rad.
  [[nodiscard]] Pose2 odometry_pose() const noexcept;
  void set_world(EmulatorWorld* world) noexcept { world_ = world; }

  // ---- Fault injection ----
  void inject_bad_checksums(int packets) noexcept { bad_checksum_packets_ = packets; }
  void inject_truncations(int packets) noexcept { truncate_packets_ = packets; }
  void inject_noise(std::size_t bytes) noexcept { noise_bytes_ += bytes; }
  void drop_sips(int count) noexcept { drop_sips_ = count; }
  // Silent: reads and discards input, sends nothing, the robot coasts to a stop as ARCOS does.
  void set_silent(bool silent) noexcept { silent_ = silent; }
  void inject_reset() noexcept { reset_pending_ = true; }
  void set_stalled(bool stalled) noexcept { forced_stall_ = stalled; }
  // Someone pushes the robot at (v, w) while its motors are off (disabled, or the e-stop): the
  // wheels turn freely, so the robot moves and its encoders count, as a Pioneer pushed by hand
  // does. (0, 0): nobody pushes. Ignored while the motors drive.
  void set_push(double v_m_s, double w_rad_s) noexcept {
    push_v_mm_s_ = v_m_s * 1000.0;
    push_w_deg_s_ = w_rad_s * 57.29577951308232;
  }
  void set_estop(bool pressed) noexcept;
  void set_bumpers(std::uint8_t front_bits, std::uint8_t rear_bits) noexcept {
    front_bumpers_ = front_bits & 0x7F;
    rear_bumpers_ = rear_bits & 0x7F;
  }
  void set_battery_dv(std::uint16_t battery_dv) noexcept { battery_dv_ = battery_dv; }

  // ---- Inspection ----
  [[nodiscard]] EmulatorState state() const noexcept { return state_; }
  [[nodiscard]] bool motors_enabled() const noexcept { return motors_enabled_; }
  [[nodiscard]] double velocity_m_s() const noexcept { return v_mm_s_ * 1e-3; }
  [[nodiscard]] double omega_rad_s() const noexcept;
  [[nodiscard]] const EmulatorStats& stats() const noexcept { return stats_; }
  [[nodiscard]] bool watchdog_tripped() const noexcept { return watchdog_tripped_; }
  [[nodiscard]] std::uint32_t requested_host_baud() const noexcept { return requested_host_baud_; }
  // The HOST port's current rate: the FLASH rate, or what HOSTBAUD selected (reverting to the
  // FLASH rate if no valid packet arrives at the new rate within 500 ms, and on reset).
  [[nodiscard]] std::uint32_t host_baud() const noexcept { return host_baud_; }
  // The last commands received, oldest first (i < command_log_size()).
  [[nodiscard]] std::size_t command_log_size() const noexcept;
  [[nodiscard]] const ReceivedCommand& command_log(std::size_t i) const noexcept;
  [[nodiscard]] std::uint64_t command_log_total() const noexcept { return log_total_; }

 private:
  void on_packet(const Frame& frame, hal::Nanos now_ns) noexcept;
  void handle_command(const Frame& frame, hal::Nanos now_ns) noexcept;
  void advance(hal::Nanos now_ns) noexcept;
  void send(const Packet& packet, bool is_sip = false) noexcept;
  void send_raw(std::span<const std::uint8_t> bytes) noexcept;
  void send_sip() noexcept;
  void send_config() noexcept;
  void send_encoder() noexcept;
  Status flush(hal::ByteStream& stream) noexcept;
  void stop_motion() noexcept;
  [[nodiscard]] double heading_rate_deg_s(double dt_s) const noexcept;
  [[nodiscard]] std::uint32_t flash_baud() const noexcept;
  std::uint8_t next_noise_byte() noexcept;
  // The SIP's sonar readings: the discs fired since the last SIP, each the nearest echo in its
  // cone (kSonarBeamDeg), some lost (sonar_miss_rate).
  void fire_sonar(Sip& s) noexcept;
  [[nodiscard]] double sonar_echo_m(std::size_t disc) noexcept;

  EmulatorConfig config_;
  EmulatorWorld default_world_;
  EmulatorWorld* world_ = &default_world_;
  FrameParser parser_;
  EmulatorState state_ = EmulatorState::sync_wait;
  int expected_sync_ = 0;

  // Robot state.
  Pose2 truth_{};
  double odom_x_mm_ = 0;
  double odom_y_mm_ = 0;
  double odom_theta_rad_ = 0;
  double left_ticks_ = 0;
  double right_ticks_ = 0;
  double v_mm_s_ = 0;
  double w_deg_s_ = 0;
  double target_v_mm_s_ = 0;
  double target_w_deg_s_ = 0;
  bool heading_mode_ = false;
  bool move_mode_ = false;          // MOVE: translate a distance, then stop
  double move_remaining_mm_ = 0;    // signed
  double target_heading_rad_ = 0;  // controller odometry frame
  double max_v_mm_s_ = 0;
  double max_w_deg_s_ = 0;
  double accel_mm_s2_ = 0;
  double decel_mm_s2_ = 0;
  double rot_accel_deg_s2_ = 0;
  double rot_decel_deg_s2_ = 0;
  bool motors_enabled_ = false;
  bool sonar_on_ = true;
  bool stalled_now_ = false;
  int encoder_mode_ = 0;
  std::uint16_t battery_dv_ = 130;
  std::uint32_t requested_host_baud_ = 0;
  std::uint32_t host_baud_ = 9600;
  bool verifying_baud_ = false;
  hal::Nanos baud_verify_deadline_ns_ = 0;
  int next_sonar_ = 0;     // the disc within each bank that fires next
  int sonar_credit_ms_ = 0;  // time since the last firing, carried from SIP to SIP
  std::uint32_t sonar_noise_ = 0x9E3779B9u;  // xorshift state for lost echoes

  // Timing.
  bool started_ = false;
  hal::Nanos last_advance_ns_ = 0;
  hal::Nanos next_sip_ns_ = 0;
  hal::Nanos last_packet_ns_ = 0;
  bool watchdog_tripped_ = false;
  bool session_closed_ = false;

  // Faults.
  int bad_checksum_packets_ = 0;
  int truncate_packets_ = 0;
  std::size_t noise_bytes_ = 0;
  int drop_sips_ = 0;
  bool silent_ = false;
  bool reset_pending_ = false;
  bool forced_stall_ = false;
  double push_v_mm_s_ = 0.0;
  double push_w_deg_s_ = 0.0;
  bool estop_ = false;
  std::uint8_t front_bumpers_ = 0;
  std::uint8_t rear_bumpers_ = 0;
  std::uint32_t noise_state_ = 1;

  // Output ring and command log.
  std::array<std::uint8_t, kTxBufferBytes> tx_{};
  std::size_t tx_head_ = 0;  // next byte to write to the stream
  std::size_t tx_size_ = 0;
  std::array<ReceivedCommand, kCommandLogDepth> log_{};
  std::uint64_t log_total_ = 0;
  std::array<std::uint8_t, 512> read_buffer_{};
  EmulatorStats stats_;
};

}  // namespace sen3bot::p2os
