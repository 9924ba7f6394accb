#include "sen3bot/p2os/codec.hpp"

#include <algorithm>
#include <cstring>

namespace sen3bot::p2os {

std::uint16_t checksum(std::span<const std::uint8_t> body) noexcept {
  std::uint32_t sum = 0;
  std::size_t i = 0;
  for (; i + 1 < body.size(); i += 2) sum = (sum + ((body[i] << 8) | body[i + 1])) & 0xFFFFu;
  if (i < body.size()) sum ^= body[i];
  return static_cast<std::uint16_t>(sum);
}

void FrameParser::consume(std::size_t n) noexcept {
  if (n >= size_) {
    size_ = 0;
    return;
  }
  std::memmove(buffer_.data(), buffer_.data() + n, size_ - n);
  size_ -= n;
}

namespace {

// A little-endian cursor that reads zeros past the end, like ARIA's bufTo* helpers.
class Reader {
 public:
  explicit Reader(std::span<const std::uint8_t> bytes) noexcept : bytes_(bytes) {}
  [[nodiscard]] std::size_t remaining() const noexcept { return bytes_.size() - pos_; }
  std::uint8_t u8() noexcept { return pos_ < bytes_.size() ? bytes_[pos_++] : 0; }
  std::uint16_t u16() noexcept {
    const std::uint8_t lo = u8();
    const std::uint8_t hi = u8();
    return static_cast<std::uint16_t>(lo | (hi << 8));
  }
  std::int16_t i16() noexcept { return static_cast<std::int16_t>(u16()); }
  std::int32_t i32() noexcept {
    std::uint32_t v = u16();
    v |= static_cast<std::uint32_t>(u16()) << 16;
    return static_cast<std::int32_t>(v);
  }
  template <std::size_t N>
  void cstring(std::array<char, N>& out) noexcept {
    std::size_t n = 0;
    while (pos_ < bytes_.size()) {
      const char c = static_cast<char>(bytes_[pos_++]);
      if (c == '\0') break;
      if (n + 1 < N) out[n++] = c;
    }
    out[n] = '\0';
  }

 private:
  std::span<const std::uint8_t> bytes_;
  std::size_t pos_ = 0;
};

// Builds a body in a fixed buffer; silently stops at the emit limit.
class Writer {
 public:
  explicit Writer(std::uint8_t type) noexcept { body_[size_++] = type; }
  void u8(std::uint8_t v) noexcept {
    if (size_ < kCapacity) body_[size_++] = v;
  }
  void u16(std::uint16_t v) noexcept {
    u8(static_cast<std::uint8_t>(v));
    u8(static_cast<std::uint8_t>(v >> 8));
  }
  void i16(std::int16_t v) noexcept { u16(static_cast<std::uint16_t>(v)); }
  void i32(std::int32_t v) noexcept {
    const auto u = static_cast<std::uint32_t>(v);
    u16(static_cast<std::uint16_t>(u));
    u16(static_cast<std::uint16_t>(u >> 16));
  }
  void cstring(std::string_view s) noexcept {
    for (const char c : s) {
      if (c == '\0') break;
      u8(static_cast<std::uint8_t>(c));
    }
    u8(0);
  }
  template <std::size_t N>
  void cstring(const std::array<char, N>& s) noexcept {
    cstring(std::string_view(s.data(), strnlen(s.data(), N)));
  }
  [[nodiscard]] Packet finish() const noexcept {
    return make_packet(body_[0], std::span<const std::uint8_t>(body_.data() + 1, size_ - 1));
  }

 private:
  static constexpr std::size_t kCapacity = kMaxEmitFrameBytes - kHeaderBytes - kChecksumBytes;
  std::array<std::uint8_t, kCapacity> body_{};
  std::size_t size_ = 0;
};

}  // namespace

Packet make_packet(std::uint8_t type, std::span<const std::uint8_t> payload) noexcept {
  Packet p;
  const std::size_t payload_bytes = std::min(payload.size(), kMaxBodyBytes - 1);
  p.bytes[0] = kHeader1;
  p.bytes[1] = kHeader2;
  p.bytes[2] = static_cast<std::uint8_t>(1 + payload_bytes + kChecksumBytes);
  p.bytes[3] = type;
  if (payload_bytes > 0) std::memcpy(p.bytes.data() + 4, payload.data(), payload_bytes);
  const std::size_t body_bytes = 1 + payload_bytes;
  const std::uint16_t sum = checksum(std::span<const std::uint8_t>(p.bytes.data() + kHeaderBytes, body_bytes));
  p.bytes[kHeaderBytes + body_bytes] = static_cast<std::uint8_t>(sum >> 8);
  p.bytes[kHeaderBytes + body_bytes + 1] = static_cast<std::uint8_t>(sum & 0xFF);
  p.size = static_cast<std::uint16_t>(kHeaderBytes + body_bytes + kChecksumBytes);
  return p;
}

Packet encode_command(Command command) noexcept {
  return make_packet(static_cast<std::uint8_t>(command), {});
}

Packet encode_command_int(Command command, std::int32_t value) noexcept {
  const std::int32_t clamped = std::clamp<std::int32_t>(value, -0xFFFF, 0xFFFF);
  const auto magnitude = static_cast<std::uint16_t>(clamped < 0 ? -clamped : clamped);
  const std::uint8_t arg[3] = {clamped < 0 ? kArgNegInt : kArgInt, static_cast<std::uint8_t>(magnitude & 0xFF),
                               static_cast<std::uint8_t>(magnitude >> 8)};
  return make_packet(static_cast<std::uint8_t>(command), arg);
}

Packet encode_command_string(Command command, std::span<const std::uint8_t> text) noexcept {
  std::array<std::uint8_t, 2 + kMaxStringArgBytes> arg{};
  const std::size_t n = std::min(text.size(), kMaxStringArgBytes);
  arg[0] = kArgString;
  arg[1] = static_cast<std::uint8_t>(n);
  if (n > 0) std::memcpy(arg.data() + 2, text.data(), n);
  return make_packet(static_cast<std::uint8_t>(command), std::span<const std::uint8_t>(arg.data(), n + 2));
}

Packet encode_vel2(std::int8_t left_units, std::int8_t right_units) noexcept {
  const std::uint8_t arg[3] = {kArgInt, static_cast<std::uint8_t>(right_units), static_cast<std::uint8_t>(left_units)};
  return make_packet(static_cast<std::uint8_t>(Command::vel2), arg);
}

CommandArgument decode_argument(std::span<const std::uint8_t> payload) noexcept {
  CommandArgument arg;
  if (payload.empty()) return arg;
  const std::uint8_t kind = payload[0];
  if (kind == kArgInt || kind == kArgNegInt) {
    // Missing value bytes read as 0 (ROS p2os sends SETO as a bare 0x3B).
    const std::uint32_t lo = payload.size() > 1 ? payload[1] : 0;
    const std::uint32_t hi = payload.size() > 2 ? payload[2] : 0;
    const auto magnitude = static_cast<std::int32_t>(lo | (hi << 8));
    arg.kind = ArgKind::integer;
    arg.value = kind == kArgNegInt ? -magnitude : magnitude;
  } else if (kind == kArgString) {
    const std::size_t declared = payload.size() > 1 ? payload[1] : 0;
    const std::size_t available = payload.size() > 2 ? payload.size() - 2 : 0;
    arg.kind = ArgKind::string;
    arg.text = payload.size() > 2 ? payload.subspan(2, std::min(declared, available)) : std::span<const std::uint8_t>{};
  }
  return arg;
}

Vel2Units decode_vel2(const CommandArgument& argument) noexcept {
  // Both encodings rebuild the same 16-bit pattern: ARIA sends -(packed) as 0x1B + magnitude.
  const auto packed = static_cast<std::uint16_t>(static_cast<std::int16_t>(argument.value));
  return Vel2Units{static_cast<std::int8_t>(packed >> 8), static_cast<std::int8_t>(packed & 0xFF)};
}

std::optional<Sip> decode_sip(const Frame& frame) noexcept {
  if (frame.type != kTypeSipStopped && frame.type != kTypeSipMoving) return std::nullopt;
  const std::span<const std::uint8_t> body = frame.body;
  if (body.size() < sip::kFixedBytes) return std::nullopt;
  const std::size_t announced = body[sip::kSonarCount];
  const std::size_t after_sonar = sip::kSonarFirst + announced * sip::kSonarEntryBytes;
  if (body.size() < after_sonar + sip::kGripTailBytes) return std::nullopt;

  Sip s;
  Reader r(body.subspan(1));
  s.moving = frame.type == kTypeSipMoving;
  s.x_raw = static_cast<std::uint16_t>(r.u16() & kPositionMask);
  s.y_raw = static_cast<std::uint16_t>(r.u16() & kPositionMask);
  s.theta_raw = r.i16();
  s.left_vel_mm_s = r.i16();
  s.right_vel_mm_s = r.i16();
  s.battery_dv = r.u8();
  s.stall_bumpers = r.u16();
  s.control_raw = r.i16();
  s.flags = r.u16();
  s.compass_2deg = r.u8();
  r.u8();  // sonar count, read above
  for (std::size_t i = 0; i < announced; ++i) {
    SonarReading reading;
    reading.disc = r.u8();
    reading.range_mm = r.u16();
    if (i < kMaxSonarPerSip) s.sonar[i] = reading;
  }
  s.sonar_count = static_cast<std::uint8_t>(std::min(announced, kMaxSonarPerSip));
  s.grip_state = r.u8();
  s.anport = r.u8();
  s.analog = r.u8();
  s.digin = r.u8();
  s.digout = r.u8();
  // Optional tail: each field only if all of its bytes are present.
  if (r.remaining() >= 2) {
    s.has_battery_x10 = true;
    s.battery_x10 = r.u16();
  }
  if (s.has_battery_x10 && r.remaining() >= 1) {
    s.has_charge_state = true;
    s.charge_state = static_cast<std::int8_t>(r.u8());
  }
  if (s.has_charge_state && r.remaining() >= 2) {
    s.has_rot_vel = true;
    s.rot_vel_ddeg_s = r.i16();
  }
  if (s.has_rot_vel && r.remaining() >= 2) {
    s.has_fault_flags = true;
    s.fault_flags = r.u16();
  }
  if (s.has_fault_flags && r.remaining() >= 2) {
    s.has_lat_vel = true;
    s.lat_vel_mm_s = r.i16();
  }
  if (s.has_lat_vel && r.remaining() >= 1) {
    s.has_temperature = true;
    s.temperature_c = static_cast<std::int8_t>(r.u8());
  }
  if (s.has_temperature && r.remaining() >= 1) {
    s.has_soc = true;
    s.soc_pct = r.u8();
  }
  return s;
}

Packet encode_sip(const Sip& s) noexcept {
  Writer w(s.moving ? kTypeSipMoving : kTypeSipStopped);
  w.u16(static_cast<std::uint16_t>(s.x_raw & kPositionMask));
  w.u16(static_cast<std::uint16_t>(s.y_raw & kPositionMask));
  w.i16(s.theta_raw);
  w.i16(s.left_vel_mm_s);
  w.i16(s.right_vel_mm_s);
  w.u8(s.battery_dv);
  w.u16(s.stall_bumpers);
  w.i16(s.control_raw);
  w.u16(s.flags);
  w.u8(s.compass_2deg);
  // Keep the frame within 200 bytes: fixed 20 + 5 grip/IO + 13 tail + 5 framing leaves room
  // for 52 readings; the array holds at most 32.
  const std::size_t count = std::min<std::size_t>(s.sonar_count, kMaxSonarPerSip);
  w.u8(static_cast<std::uint8_t>(count));
  for (std::size_t i = 0; i < count; ++i) {
    w.u8(s.sonar[i].disc);
    w.u16(s.sonar[i].range_mm);
  }
  w.u8(s.grip_state);
  w.u8(s.anport);
  w.u8(s.analog);
  w.u8(s.digin);
  w.u8(s.digout);
  if (s.has_battery_x10) {
    w.u16(s.battery_x10);
    if (s.has_charge_state) {
      w.u8(static_cast<std::uint8_t>(s.charge_state));
      if (s.has_rot_vel) {
        w.i16(s.rot_vel_ddeg_s);
        if (s.has_fault_flags) {
          w.u16(s.fault_flags);
          if (s.has_lat_vel) {
            w.i16(s.lat_vel_mm_s);
            if (s.has_temperature) {
              w.u8(static_cast<std::uint8_t>(s.temperature_c));
              if (s.has_soc) w.u8(s.soc_pct);
            }
          }
        }
      }
    }
  }
  return w.finish();
}

std::optional<SyncReply> decode_sync2_reply(const Frame& frame) noexcept {
  if (frame.type != kTypeSync2) return std::nullopt;
  SyncReply reply;
  Reader r(frame.payload);
  r.cstring(reply.name);
  r.cstring(reply.robot_class);
  r.cstring(reply.subclass);
  return reply;
}

Packet encode_sync2_reply(std::string_view name, std::string_view robot_class, std::string_view subclass) noexcept {
  constexpr std::size_t kMaxPeerString = 19;  // Player/ROS copy into 20-byte buffers
  Writer w(kTypeSync2);
  w.cstring(name.substr(0, std::min(name.size(), kMaxPeerString)));
  w.cstring(robot_class.substr(0, std::min(robot_class.size(), kMaxPeerString)));
  w.cstring(subclass.substr(0, std::min(subclass.size(), kMaxPeerString)));
  return w.finish();
}

std::optional<ConfigPacket> decode_config(const Frame& frame) noexcept {
  if (frame.type != kTypeConfig) return std::nullopt;
  ConfigPacket c;
  Reader r(frame.payload);
  r.cstring(c.robot_class);
  r.cstring(c.subclass);
  r.cstring(c.serial);
  c.four_motors = r.u8();
  c.rot_vel_top_deg_s = r.u16();
  c.trans_vel_top_mm_s = r.u16();
  c.rot_acc_top_deg_s2 = r.u16();
  c.trans_acc_top_mm_s2 = r.u16();
  c.pwm_max = r.u16();
  r.cstring(c.name);
  c.sip_cycle_ms = r.u8();
  c.host_baud_code = r.u8();
  c.aux1_baud_code = r.u8();
  c.has_gripper = r.u16();
  c.front_sonar = r.u16();
  c.rear_sonar = r.u8();
  c.low_battery_dv = r.u16();
  c.rev_count = r.u16();
  c.watchdog_ms = r.u16();
  c.normal_mpacs = r.u8();
  c.stall_val = r.u16();
  c.stall_count = r.u16();
  c.joy_vel_mm_s = r.u16();
  c.joy_rot_vel_deg_s = r.u16();
  c.rot_vel_max_deg_s = r.u16();
  c.trans_vel_max_mm_s = r.u16();
  c.rot_accel_deg_s2 = r.u16();
  c.rot_decel_deg_s2 = r.u16();
  c.rot_kp = r.u16();
  c.rot_kv = r.u16();
  c.rot_ki = r.u16();
  c.trans_accel_mm_s2 = r.u16();
  c.trans_decel_mm_s2 = r.u16();
  c.trans_kp = r.u16();
  c.trans_kv = r.u16();
  c.trans_ki = r.u16();
  c.front_bumps = r.u8();
  c.rear_bumps = r.u8();
  c.charger = r.u8();
  c.sonar_cycle_ms = r.u8();
  c.auto_baud = r.u8();
  c.has_gyro = r.u8();
  c.drift_factor = r.i16();
  c.aux2_baud_code = r.u8();
  c.aux3_baud_code = r.u8();
  c.ticks_mm = r.u16();
  c.shutdown_dv = r.u16();
  r.cstring(c.firmware_version);
  c.gyro_cw = r.u16();
  c.gyro_ccw = r.u16();
  c.kinematics_delay = r.u8();
  c.lat_vel_top = r.u16();
  c.lat_accel_top = r.u16();
  c.lat_vel_max = r.u16();
  c.lat_accel = r.u16();
  c.lat_decel = r.u16();
  c.charge_threshold = r.u16();
  c.pdb_port = r.u8();
  c.gyro_rate_limit = r.u16();
  c.high_temperature_shutdown_c = static_cast<std::int8_t>(r.u8());
  return c;
}

Packet encode_config(const ConfigPacket& c) noexcept {
  Writer w(kTypeConfig);
  w.cstring(c.robot_class);
  w.cstring(c.subclass);
  w.cstring(c.serial);
  w.u8(c.four_motors);
  w.u16(c.rot_vel_top_deg_s);
  w.u16(c.trans_vel_top_mm_s);
  w.u16(c.rot_acc_top_deg_s2);
  w.u16(c.trans_acc_top_mm_s2);
  w.u16(c.pwm_max);
  w.cstring(c.name);
  w.u8(c.sip_cycle_ms);
  w.u8(c.host_baud_code);
  w.u8(c.aux1_baud_code);
  w.u16(c.has_gripper);
  w.u16(c.front_sonar);
  w.u8(c.rear_sonar);
  w.u16(c.low_battery_dv);
  w.u16(c.rev_count);
  w.u16(c.watchdog_ms);
  w.u8(c.normal_mpacs);
  w.u16(c.stall_val);
  w.u16(c.stall_count);
  w.u16(c.joy_vel_mm_s);
  w.u16(c.joy_rot_vel_deg_s);
  w.u16(c.rot_vel_max_deg_s);
  w.u16(c.trans_vel_max_mm_s);
  w.u16(c.rot_accel_deg_s2);
  w.u16(c.rot_decel_deg_s2);
  w.u16(c.rot_kp);
  w.u16(c.rot_kv);
  w.u16(c.rot_ki);
  w.u16(c.trans_accel_mm_s2);
  w.u16(c.trans_decel_mm_s2);
  w.u16(c.trans_kp);
  w.u16(c.trans_kv);
  w.u16(c.trans_ki);
  w.u8(c.front_bumps);
  w.u8(c.rear_bumps);
  w.u8(c.charger);
  w.u8(c.sonar_cycle_ms);
  w.u8(c.auto_baud);
  w.u8(c.has_gyro);
  w.i16(c.drift_factor);
  w.u8(c.aux2_baud_code);
  w.u8(c.aux3_baud_code);
  w.u16(c.ticks_mm);
  w.u16(c.shutdown_dv);
  w.cstring(c.firmware_version);
  w.u16(c.gyro_cw);
  w.u16(c.gyro_ccw);
  w.u8(c.kinematics_delay);
  w.u16(c.lat_vel_top);
  w.u16(c.lat_accel_top);
  w.u16(c.lat_vel_max);
  w.u16(c.lat_accel);
  w.u16(c.lat_decel);
  w.u16(c.charge_threshold);
  w.u8(c.pdb_port);
  w.u16(c.gyro_rate_limit);
  w.u8(static_cast<std::uint8_t>(c.high_temperature_shutdown_c));
  return w.finish();
}

std::optional<EncoderPacket> decode_encoder(const Frame& frame) noexcept {
  constexpr std::size_t kEncoderPayloadBytes = 8;
  if (frame.type != kTypeEncoder || frame.payload.size() < kEncoderPayloadBytes) return std::nullopt;
  Reader r(frame.payload);
  EncoderPacket e;
  e.left_ticks = r.i32();
  e.right_ticks = r.i32();
  return e;
}

Packet encode_encoder(const EncoderPacket& e) noexcept {
  Writer w(kTypeEncoder);
  w.i32(e.left_ticks);
  w.i32(e.right_ticks);
  return w.finish();
}

std::string_view command_name(std::uint8_t command) noexcept {
  switch (static_cast<Command>(command)) {
    case Command::sync0: return "SYNC0/PULSE";
    case Command::sync1: return "SYNC1/OPEN";
    case Command::sync2: return "SYNC2/CLOSE";
    case Command::polling: return "POLLING";
    case Command::enable: return "ENABLE";
    case Command::seta: return "SETA";
    case Command::setv: return "SETV";
    case Command::seto: return "SETO";
    case Command::move: return "MOVE";
    case Command::rotate: return "ROTATE";
    case Command::setrv: return "SETRV";
    case Command::vel: return "VEL";
    case Command::head: return "HEAD";
    case Command::dhead: return "DHEAD";
    case Command::say: return "SAY";
    case Command::joyinfo: return "JOYINFO";
    case Command::config: return "CONFIG";
    case Command::encoder: return "ENCODER";
    case Command::setrvdir: return "SETRVDIR";
    case Command::rvel: return "RVEL";
    case Command::dchead: return "DCHEAD";
    case Command::setra: return "SETRA";
    case Command::sonar: return "SONAR";
    case Command::stop: return "STOP";
    case Command::digout: return "DIGOUT";
    case Command::vel2: return "VEL2";
    case Command::gripper: return "GRIPPER";
    case Command::adsel: return "ADSEL";
    case Command::ioreq: return "IOREQUEST";
    case Command::tty2: return "TTY2";
    case Command::getaux: return "GETAUX";
    case Command::bumpstall: return "BUMPSTALL";
    case Command::joydrive: return "JOYDRIVE";
    case Command::sonarcycle: return "SONARCYCLE";
    case Command::hostbaud: return "HOSTBAUD";
    case Command::estop: return "ESTOP";
    case Command::e_stall: return "E_STALL";
    case Command::batteryinfo: return "BATTERYINFO";
    case Command::battest: return "BATTEST";
    case Command::reset: return "RESET";
    case Command::maintenance: return "MAINTENANCE";
  }
  return "UNKNOWN";
}

std::string_view server_type_name(std::uint8_t type) noexcept {
  switch (type) {
    case kTypeSync0: return "SYNC0";
    case kTypeSync1: return "SYNC1";
    case kTypeSync2: return "SYNC2";
    case kTypeConfig: return "CONFIGpac";
    case kTypeSipStopped:
    case kTypeSipMoving: return "SIP";
    case kTypeEncoder: return "ENCODERpac";
    case kTypeResetA:
    case kTypeResetB: return "RESET";
    default: return "UNKNOWN";
  }
}

}  // namespace sen3bot::p2os
