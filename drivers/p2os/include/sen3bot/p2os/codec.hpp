#pragma once
// Pure P2OS codec: checksum, a resynchronising frame parser, packet encoders for both
// roles, and decoders for the server packets (SIP, CONFIGpac, ENCODERpac, SYNC2 reply) and
// the client commands. Nothing here allocates or touches I/O.
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/p2os/protocol.hpp"

namespace sen3bot::p2os {

// Checksum over type + payload (the bytes between N and the checksum).
std::uint16_t checksum(std::span<const std::uint8_t> body) noexcept;

// One encoded frame, header to checksum.
struct Packet {
  std::array<std::uint8_t, kMaxFrameBytes> bytes{};
  std::uint16_t size = 0;

  [[nodiscard]] std::span<const std::uint8_t> view() const noexcept { return {bytes.data(), size}; }
  [[nodiscard]] std::span<const std::uint8_t> body() const noexcept {
    return size >= kHeaderBytes + 1 + kChecksumBytes ? std::span<const std::uint8_t>{bytes.data() + kHeaderBytes,
                                                                                    size - kHeaderBytes - kChecksumBytes}
                                                     : std::span<const std::uint8_t>{};
  }
};

// Builds a frame around `type` + `payload`. Payloads longer than the frame allows are cut
// at kMaxBodyBytes - 1 (callers keep below kMaxEmitFrameBytes).
Packet make_packet(std::uint8_t type, std::span<const std::uint8_t> payload) noexcept;

// Client command encoders.
Packet encode_command(Command command) noexcept;  // no argument
// ARGINT for value >= 0, ARGNINT with the magnitude otherwise; clamped to +-65535.
Packet encode_command_int(Command command, std::int32_t value) noexcept;
// ARGSTR: length byte then bytes (no NUL), cut at kMaxStringArgBytes.
Packet encode_command_string(Command command, std::span<const std::uint8_t> text) noexcept;
// VEL2 the way Player sends it: ARGINT with the raw bytes (low = right, high = left) in
// Vel2Divisor units.
Packet encode_vel2(std::int8_t left_units, std::int8_t right_units) noexcept;

// A view of one received frame; valid only during the parser callback.
struct Frame {
  std::uint8_t type = 0;
  std::span<const std::uint8_t> payload;  // after the type byte
  std::span<const std::uint8_t> body;     // type + payload (what the checksum covers)
  std::span<const std::uint8_t> raw;      // FA FB .. checksum
};

struct ParserStats {
  std::uint64_t frames = 0;          // valid frames delivered
  std::uint64_t bad_checksums = 0;   // complete frames with a wrong checksum
  std::uint64_t bad_lengths = 0;     // N < 3
  std::uint64_t gap_timeouts = 0;    // partial frames dropped after an inter-byte gap
  std::uint64_t discarded_bytes = 0;  // bytes that were not part of a delivered frame
};

// Byte-stream to frames. Hunts FA FB, never trusts N beyond one frame: after a bad checksum
// or N < 3 it drops one byte and rescans what it already holds, so a frame hidden behind a
// corrupt header is still found. A partial frame older than the inter-byte gap is dropped.
class FrameParser {
 public:
  explicit FrameParser(hal::Nanos max_gap_ns = hal::millis(kInterByteGapMs)) noexcept : max_gap_ns_(max_gap_ns) {}

  // Feeds bytes received at `now_ns`; calls on_frame(const Frame&) for each valid frame.
  template <typename OnFrame>
  void feed(std::span<const std::uint8_t> bytes, hal::Nanos now_ns, OnFrame&& on_frame) {
    if (size_ > 0 && now_ns - last_byte_ns_ > max_gap_ns_) {
      stats_.gap_timeouts += 1;
      stats_.discarded_bytes += size_;
      size_ = 0;
    }
    if (!bytes.empty()) last_byte_ns_ = now_ns;
    for (const std::uint8_t b : bytes) {
      buffer_[size_++] = b;
      extract(on_frame);
    }
  }

  void reset() noexcept { size_ = 0; }
  [[nodiscard]] const ParserStats& stats() const noexcept { return stats_; }
  [[nodiscard]] std::size_t pending_bytes() const noexcept { return size_; }

 private:
  template <typename OnFrame>
  void extract(OnFrame& on_frame) {
    for (;;) {
      if (size_ == 0) return;
      if (buffer_[0] != kHeader1) {
        drop(1);
        continue;
      }
      if (size_ < 2) return;
      if (buffer_[1] != kHeader2) {
        drop(1);
        continue;
      }
      if (size_ < 3) return;
      const std::size_t count = buffer_[2];
      if (count < kMinCount) {
        stats_.bad_lengths += 1;
        drop(1);
        continue;
      }
      const std::size_t total = count + kHeaderBytes;
      if (size_ < total) return;
      const std::span<const std::uint8_t> body(buffer_.data() + kHeaderBytes, count - kChecksumBytes);
      const std::uint16_t expected =
          static_cast<std::uint16_t>((buffer_[total - 2] << 8) | buffer_[total - 1]);
      if (checksum(body) != expected) {
        stats_.bad_checksums += 1;
        drop(1);
        continue;
      }
      Frame frame;
      frame.type = body[0];
      frame.payload = body.subspan(1);
      frame.body = body;
      frame.raw = std::span<const std::uint8_t>(buffer_.data(), total);
      stats_.frames += 1;
      on_frame(static_cast<const Frame&>(frame));
      consume(total);
      // After a rescan the buffer may already hold the next frame.
    }
  }
  void drop(std::size_t n) noexcept {
    stats_.discarded_bytes += n;
    consume(n);
  }
  void consume(std::size_t n) noexcept;

  std::array<std::uint8_t, kMaxFrameBytes> buffer_{};
  std::size_t size_ = 0;
  hal::Nanos last_byte_ns_ = 0;
  hal::Nanos max_gap_ns_;
  ParserStats stats_;
};

// ---- Client command decoding (emulator side; lenient like ARCOS) ----

enum class ArgKind : std::uint8_t { none, integer, string };

struct CommandArgument {
  ArgKind kind = ArgKind::none;
  std::int32_t value = 0;                // integer: missing value bytes read as 0
  std::span<const std::uint8_t> text;    // string: bytes present, at most the length byte says
};

// The argument after the command byte. An unknown type byte, or nothing, is `none`.
CommandArgument decode_argument(std::span<const std::uint8_t> payload) noexcept;

// VEL2's packed argument back to wheel units: accepts both ARIA's 0x1B + magnitude of the
// packed short and Player's raw bytes under 0x3B.
struct Vel2Units {
  std::int8_t left = 0;
  std::int8_t right = 0;
};
Vel2Units decode_vel2(const CommandArgument& argument) noexcept;

// ---- Server packet decoding (driver side) ----

inline constexpr std::size_t kMaxSonarPerSip = 32;

struct SonarReading {
  std::uint8_t disc = 0;
  std::uint16_t range_mm = 0;
};

// A standard SIP, raw units. Optional tail fields carry has_* flags.
struct Sip {
  bool moving = false;  // type 0x33
  std::uint16_t x_raw = 0;  // 15 LS bits
  std::uint16_t y_raw = 0;
  std::int16_t theta_raw = 0;
  std::int16_t left_vel_mm_s = 0;
  std::int16_t right_vel_mm_s = 0;
  std::uint8_t battery_dv = 0;
  std::uint16_t stall_bumpers = 0;
  std::int16_t control_raw = 0;
  std::uint16_t flags = 0;
  std::uint8_t compass_2deg = 0;
  std::uint8_t sonar_count = 0;  // readings in this SIP (capped at kMaxSonarPerSip)
  std::array<SonarReading, kMaxSonarPerSip> sonar{};
  std::uint8_t grip_state = 0;
  std::uint8_t anport = 0;
  std::uint8_t analog = 0;
  std::uint8_t digin = 0;
  std::uint8_t digout = 0;
  bool has_battery_x10 = false;
  std::uint16_t battery_x10 = 0;
  bool has_charge_state = false;
  std::int8_t charge_state = 0;
  bool has_rot_vel = false;
  std::int16_t rot_vel_ddeg_s = 0;  // tenths of a degree per second
  bool has_fault_flags = false;
  std::uint16_t fault_flags = 0;
  bool has_lat_vel = false;
  std::int16_t lat_vel_mm_s = 0;
  bool has_temperature = false;
  std::int8_t temperature_c = 0;
  bool has_soc = false;
  std::uint8_t soc_pct = 0;
};

// nullopt for a wrong type or a body too short for the fixed part, the sonar readings it
// announces and the five grip/IO bytes.
std::optional<Sip> decode_sip(const Frame& frame) noexcept;
// Encodes a SIP with every tail field whose has_* flag is set (in order; a field is only
// written if all before it are). Sonar readings beyond what fits in 200 bytes are dropped.
Packet encode_sip(const Sip& sip) noexcept;

struct SyncReply {
  static constexpr std::size_t kFieldBytes = 32;
  std::array<char, kFieldBytes> name{};      // NUL-terminated, cut if longer
  std::array<char, kFieldBytes> robot_class{};
  std::array<char, kFieldBytes> subclass{};
};
// The SYNC2 reply: type 2 with three NUL-terminated strings. nullopt if not type 2.
// Missing strings read as empty (lenient, as ARIA).
std::optional<SyncReply> decode_sync2_reply(const Frame& frame) noexcept;
// Encodes name/class/subclass (each cut at 19 characters for Player/ROS's 20-byte buffers).
Packet encode_sync2_reply(std::string_view name, std::string_view robot_class, std::string_view subclass) noexcept;

// CONFIGpac (0x20), fields in wire order. Missing trailing fields read as 0 (ARIA does the
// same), so short packets from simulators decode.
struct ConfigPacket {
  static constexpr std::size_t kStringBytes = 24;
  std::array<char, kStringBytes> robot_class{};
  std::array<char, kStringBytes> subclass{};
  std::array<char, kStringBytes> serial{};
  std::uint8_t four_motors = 0;
  std::uint16_t rot_vel_top_deg_s = 0;
  std::uint16_t trans_vel_top_mm_s = 0;
  std::uint16_t rot_acc_top_deg_s2 = 0;
  std::uint16_t trans_acc_top_mm_s2 = 0;
  std::uint16_t pwm_max = 0;
  std::array<char, kStringBytes> name{};
  std::uint8_t sip_cycle_ms = 0;
  std::uint8_t host_baud_code = 0;
  std::uint8_t aux1_baud_code = 0;
  std::uint16_t has_gripper = 0;
  std::uint16_t front_sonar = 0;
  std::uint8_t rear_sonar = 0;
  std::uint16_t low_battery_dv = 0;
  std::uint16_t rev_count = 0;
  std::uint16_t watchdog_ms = 0;
  std::uint8_t normal_mpacs = 0;
  std::uint16_t stall_val = 0;
  std::uint16_t stall_count = 0;
  std::uint16_t joy_vel_mm_s = 0;
  std::uint16_t joy_rot_vel_deg_s = 0;
  std::uint16_t rot_vel_max_deg_s = 0;
  std::uint16_t trans_vel_max_mm_s = 0;
  std::uint16_t rot_accel_deg_s2 = 0;
  std::uint16_t rot_decel_deg_s2 = 0;
  std::uint16_t rot_kp = 0;
  std::uint16_t rot_kv = 0;
  std::uint16_t rot_ki = 0;
  std::uint16_t trans_accel_mm_s2 = 0;
  std::uint16_t trans_decel_mm_s2 = 0;
  std::uint16_t trans_kp = 0;
  std::uint16_t trans_kv = 0;
  std::uint16_t trans_ki = 0;
  std::uint8_t front_bumps = 0;
  std::uint8_t rear_bumps = 0;
  std::uint8_t charger = 0;
  std::uint8_t sonar_cycle_ms = 0;
  std::uint8_t auto_baud = 0;  // 2: the client may switch with HOSTBAUD
  std::uint8_t has_gyro = 0;
  std::int16_t drift_factor = 0;
  std::uint8_t aux2_baud_code = 0;
  std::uint8_t aux3_baud_code = 0;
  std::uint16_t ticks_mm = 0;
  std::uint16_t shutdown_dv = 0;
  std::array<char, kStringBytes> firmware_version{};
  std::uint16_t gyro_cw = 0;
  std::uint16_t gyro_ccw = 0;
  std::uint8_t kinematics_delay = 0;
  std::uint16_t lat_vel_top = 0;
  std::uint16_t lat_accel_top = 0;
  std::uint16_t lat_vel_max = 0;
  std::uint16_t lat_accel = 0;
  std::uint16_t lat_decel = 0;
  std::uint16_t charge_threshold = 0;
  std::uint8_t pdb_port = 0;
  std::uint16_t gyro_rate_limit = 0;
  std::int8_t high_temperature_shutdown_c = 0;
};
std::optional<ConfigPacket> decode_config(const Frame& frame) noexcept;
Packet encode_config(const ConfigPacket& config) noexcept;

struct EncoderPacket {
  std::int32_t left_ticks = 0;
  std::int32_t right_ticks = 0;
};
std::optional<EncoderPacket> decode_encoder(const Frame& frame) noexcept;
Packet encode_encoder(const EncoderPacket& encoder) noexcept;

// Human-readable names for logs and the decoder.
std::string_view command_name(std::uint8_t command) noexcept;
std::string_view server_type_name(std::uint8_t type) noexcept;

}  // namespace sen3bot::p2os
