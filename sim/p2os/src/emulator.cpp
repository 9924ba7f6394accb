#include "sen3bot/sim/p2os/emulator.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "sen3bot/p2os/sonar.hpp"

namespace sen3bot::p2os {

namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;
constexpr double kThetaUnitRad = 2.0 * std::numbers::pi / kThetaUnitsPerRev;
// VEL2 wheel units (Vel2Divisor of the P3-DX parameter files), mm/s.
constexpr double kVel2DivisorMm = 20.0;
// Integration step: big enough to be cheap, small enough that a square stays square.
constexpr hal::Nanos kMaxIntegrationStepNs = hal::millis(5);
// ARCOS reverts to its FLASH rate if no valid packet follows HOSTBAUD within this time.
constexpr int kBaudRevertMs = 500;
// MOVE counts as done within this distance of the goal.
constexpr double kMoveDoneMm = 0.5;
// HEAD/DHEAD count as done within this angle of the target; small enough that braking from
// the profile's speed there adds well under a tenth of a degree.
constexpr double kHeadDoneDeg = 0.05;
// Position modes brake at least this hard (mm/s², °/s²): a configured 0 would never stop.
constexpr double kMinDecel = 1.0;
// AMRISim sends this temperature for "no sensor".
constexpr std::int8_t kNoTemperature = -127;
// Below these the robot counts as stopped (SIP type 0x32).
constexpr double kMovingMmS = 0.5;
constexpr double kMovingDegS = 0.05;

// xorshift32: advances the state and returns it.
std::uint32_t xorshift32(std::uint32_t& state) noexcept {
  state ^= state << 13;
  state ^= state >> 17;
  state ^= state << 5;
  return state;
}

double approach(double value, double target, double rate_up, double rate_down, double dt_s) {
  // Speeding up (same sign, larger magnitude) uses the acceleration, anything else decelerates.
  const bool speeding_up = std::fabs(target) > std::fabs(value) && (value == 0 || (target > 0) == (value > 0));
  const double step = (speeding_up ? rate_up : rate_down) * dt_s;
  return value + std::clamp(target - value, -step, step);
}

// The fastest speed from which braking at `decel` in steps of `dt_s` stops within `distance`
// (all magnitudes). The continuous sqrt(2 a d) overshoots by about v dt / 2, because each
// step moves at the speed it has just set; this is the same sum taken over the steps.
double braking_speed(double distance, double decel, double dt_s) {
  const double a = std::max(decel, kMinDecel);
  const double half_step = a * dt_s / 2.0;
  return std::sqrt(half_step * half_step + 2.0 * a * distance) - half_step;
}

}  // namespace

P2osEmulator::P2osEmulator(const EmulatorConfig& config) : config_(config) {
  noise_state_ = config_.noise_seed != 0 ? config_.noise_seed : 1;
  sonar_noise_ = (noise_state_ * 2654435761u) | 1u;  // never 0: xorshift would stay there
  battery_dv_ = config_.battery_dv;
  reset_session();
}

void P2osEmulator::reset_session() noexcept {
  state_ = EmulatorState::sync_wait;
  expected_sync_ = 0;
  motors_enabled_ = false;
  v_mm_s_ = w_deg_s_ = 0;
  target_v_mm_s_ = target_w_deg_s_ = 0;
  heading_mode_ = false;
  move_mode_ = false;
  encoder_mode_ = 0;
  sonar_on_ = config_.sonar_enabled;
  max_v_mm_s_ = config_.trans_vel_max_mm_s;
  max_w_deg_s_ = config_.rot_vel_max_deg_s;
  accel_mm_s2_ = config_.trans_accel_mm_s2;
  decel_mm_s2_ = config_.trans_decel_mm_s2;
  rot_accel_deg_s2_ = config_.rot_accel_deg_s2;
  rot_decel_deg_s2_ = config_.rot_decel_deg_s2;
  watchdog_tripped_ = false;
  session_closed_ = false;
  // A new session counts from zero, as AMRISim does per connection; the world does not move.
  odom_x_mm_ = odom_y_mm_ = odom_theta_rad_ = 0;
  left_ticks_ = right_ticks_ = 0;
  host_baud_ = flash_baud();
  verifying_baud_ = false;
  parser_.reset();
  tx_head_ = tx_size_ = 0;
}

std::uint32_t P2osEmulator::flash_baud() const noexcept {
  return config_.host_baud_code < std::size(kHostBaudRates) ? kHostBaudRates[config_.host_baud_code] : 9600;
}

bool P2osEmulator::take_session_closed() noexcept {
  const bool closed = session_closed_;
  session_closed_ = false;
  return closed;
}

Pose2 P2osEmulator::odometry_pose() const noexcept {
  return {odom_x_mm_ * 1e-3, odom_y_mm_ * 1e-3, odom_theta_rad_};
}

double P2osEmulator::omega_rad_s() const noexcept { return w_deg_s_ / kDegPerRad; }

void P2osEmulator::set_estop(bool pressed) noexcept {
  estop_ = pressed;
  if (pressed) {
    // The STOP button cuts motor power; the client must ENABLE again after release.
    motors_enabled_ = false;
    stop_motion();
    v_mm_s_ = w_deg_s_ = 0;
  }
}

void P2osEmulator::stop_motion() noexcept {
  target_v_mm_s_ = target_w_deg_s_ = 0;
  heading_mode_ = false;
  move_mode_ = false;
}

std::size_t P2osEmulator::command_log_size() const noexcept {
  return static_cast<std::size_t>(std::min<std::uint64_t>(log_total_, kCommandLogDepth));
}

const ReceivedCommand& P2osEmulator::command_log(std::size_t i) const noexcept {
  const std::uint64_t first = log_total_ - command_log_size();
  return log_[(first + i) % kCommandLogDepth];
}

Status P2osEmulator::step(hal::ByteStream& stream, hal::Nanos now_ns) noexcept {
  if (!started_) {
    started_ = true;
    last_advance_ns_ = now_ns;
    last_packet_ns_ = now_ns;
    next_sip_ns_ = now_ns + hal::millis(config_.sip_cycle_ms);
  }
  Status status;
  for (int i = 0; i < 16; ++i) {
    Result<std::size_t> got = stream.read(read_buffer_);
    if (!got) {
      status = got.error();
      break;
    }
    if (*got == 0) break;
    if (!silent_) {
      parser_.feed(std::span<const std::uint8_t>(read_buffer_.data(), *got), now_ns,
                   [&](const Frame& frame) { on_packet(frame, now_ns); });
    }
    if (*got < read_buffer_.size()) break;
  }
  stats_.bad_checksums = parser_.stats().bad_checksums;
  if (verifying_baud_ && now_ns >= baud_verify_deadline_ns_) {
    verifying_baud_ = false;
    host_baud_ = flash_baud();
  }
  advance(now_ns);
  if (reset_pending_) {
    reset_pending_ = false;
    reset_session();
    send(make_packet(kTypeResetB, {}));
  }
  if (state_ == EmulatorState::open && now_ns >= next_sip_ns_) {
    const hal::Nanos cycle = hal::millis(config_.sip_cycle_ms);
    next_sip_ns_ += cycle;
    if (next_sip_ns_ <= now_ns) next_sip_ns_ = now_ns + cycle;  // fell behind: re-phase, no burst
    if (silent_) {
      // nothing
    } else if (drop_sips_ > 0) {
      drop_sips_ -= 1;
    } else {
      send_sip();
      if (encoder_mode_ > 0) {
        send_encoder();
        if (encoder_mode_ == 1) encoder_mode_ = 0;
      }
    }
  }
  if (!silent_ && status.ok()) status = flush(stream);
  return status;
}

void P2osEmulator::on_packet(const Frame& frame, hal::Nanos now_ns) noexcept {
  stats_.packets_received += 1;
  stats_.command_counts[frame.type] += 1;
  last_packet_ns_ = now_ns;
  verifying_baud_ = false;  // a valid packet at the current rate confirms it
  // With watchdog_resumes the old setpoints are still there and take effect again now.
  watchdog_tripped_ = false;
  const CommandArgument arg = decode_argument(frame.payload);
  ReceivedCommand& entry = log_[log_total_ % kCommandLogDepth];
  entry = ReceivedCommand{now_ns, frame.type, arg.kind, arg.value};
  log_total_ += 1;
  handle_command(frame, now_ns);
}

void P2osEmulator::handle_command(const Frame& frame, hal::Nanos now_ns) noexcept {
  const std::uint8_t cmd = frame.type;
  const CommandArgument arg = decode_argument(frame.payload);
  if (state_ != EmulatorState::open) {
    if (cmd > 2) return;  // nothing but the handshake before OPEN
    if (state_ == EmulatorState::synced && cmd == 1) {
      state_ = EmulatorState::open;
      motors_enabled_ = false;  // ARCOS comes up with the motors disabled
      stop_motion();
      stats_.sessions_opened += 1;
      next_sip_ns_ = now_ns + hal::millis(config_.sip_cycle_ms);
      return;
    }
    int n = cmd;
    if (n != expected_sync_ && !config_.follow_client_sync) {
      expected_sync_ = 0;
      state_ = EmulatorState::sync_wait;
      if (n != 0) return;
    }
    if (n < 2) {
      send(make_packet(static_cast<std::uint8_t>(n), {}));
      expected_sync_ = n + 1;
      state_ = EmulatorState::sync_wait;
    } else {
      send(encode_sync2_reply(config_.name, config_.robot_class, config_.subclass));
      expected_sync_ = 0;
      state_ = EmulatorState::synced;
    }
    return;
  }

  const double value = arg.value;
  switch (static_cast<Command>(cmd)) {
    case Command::sync0:  // PULSE
    case Command::sync1:  // OPEN again
      return;
    case Command::sync2:  // CLOSE
      stop_motion();
      v_mm_s_ = w_deg_s_ = 0;
      motors_enabled_ = false;
      encoder_mode_ = 0;
      state_ = EmulatorState::sync_wait;
      expected_sync_ = 0;
      session_closed_ = true;
      stats_.sessions_closed += 1;
      return;
    case Command::enable:
      motors_enabled_ = arg.value != 0 && !estop_;
      if (!motors_enabled_) {
        stop_motion();
        v_mm_s_ = w_deg_s_ = 0;
      }
      return;
    case Command::seta:
      if (arg.value > 0) accel_mm_s2_ = std::min<double>(value, config_.trans_acc_top_mm_s2);
      if (arg.value < 0) decel_mm_s2_ = std::min<double>(-value, config_.trans_acc_top_mm_s2);
      return;
    case Command::setv:
      max_v_mm_s_ = std::clamp<double>(value, 0, config_.trans_vel_top_mm_s);
      return;
    case Command::setrv:
      max_w_deg_s_ = std::clamp<double>(value, 0, config_.rot_vel_top_deg_s);
      return;
    case Command::setra:
      if (arg.value > 0) rot_accel_deg_s2_ = std::min<double>(value, config_.rot_acc_top_deg_s2);
      if (arg.value < 0) rot_decel_deg_s2_ = std::min<double>(-value, config_.rot_acc_top_deg_s2);
      return;
    case Command::seto:
      odom_x_mm_ = odom_y_mm_ = odom_theta_rad_ = 0;
      return;
    case Command::vel:
      target_v_mm_s_ = std::clamp(value, -max_v_mm_s_, max_v_mm_s_);
      move_mode_ = false;
      return;
    case Command::move:
      move_mode_ = true;
      move_remaining_mm_ = value;
      return;
    case Command::rvel:
    case Command::rotate:
      target_w_deg_s_ = std::clamp(value, -max_w_deg_s_, max_w_deg_s_);
      heading_mode_ = false;
      return;
    case Command::head:
      heading_mode_ = true;
      target_heading_rad_ = wrap_angle_rad(value / kDegPerRad);
      return;
    case Command::dhead:
      heading_mode_ = true;
      target_heading_rad_ = wrap_angle_rad(odom_theta_rad_ + value / kDegPerRad);
      return;
    case Command::dchead:
      // Relative to the current heading setpoint (or the heading, if none).
      target_heading_rad_ = wrap_angle_rad((heading_mode_ ? target_heading_rad_ : odom_theta_rad_) + value / kDegPerRad);
      heading_mode_ = true;
      return;
    case Command::vel2: {
      const Vel2Units units = decode_vel2(arg);
      const double left_mm_s = units.left * kVel2DivisorMm;
      const double right_mm_s = units.right * kVel2DivisorMm;
      target_v_mm_s_ = std::clamp((left_mm_s + right_mm_s) / 2.0, -max_v_mm_s_, max_v_mm_s_);
      target_w_deg_s_ = std::clamp((right_mm_s - left_mm_s) / 2.0 * config_.diff_conv_rad_per_mm * kDegPerRad,
                                   -max_w_deg_s_, max_w_deg_s_);
      heading_mode_ = false;
      move_mode_ = false;
      return;
    }
    case Command::stop:
      stop_motion();
      return;
    case Command::estop:
      stop_motion();
      v_mm_s_ = w_deg_s_ = 0;
      return;
    case Command::sonar:
      sonar_on_ = arg.value != 0;
      return;
    case Command::config:
      send_config();
      return;
    case Command::encoder:
      encoder_mode_ = std::max(0, arg.value);
      return;
    case Command::hostbaud:
      // On a pty or TCP the rate is meaningless; remember what was asked.
      if (arg.value >= 0 && arg.value < static_cast<int>(std::size(kHostBaudRates))) {
        requested_host_baud_ = kHostBaudRates[arg.value];
        host_baud_ = requested_host_baud_;
        verifying_baud_ = true;
        baud_verify_deadline_ns_ = now_ns + hal::millis(kBaudRevertMs);
      }
      return;
    case Command::reset:
      reset_session();
      return;
    default:
      // 57 is ESTOP on some firmware (AMRISim treats it so).
      if (cmd == 57) {
        stop_motion();
        v_mm_s_ = w_deg_s_ = 0;
      }
      return;  // accessories, BATTERYINFO, PTZ traffic: ignored quietly
  }
}

void P2osEmulator::advance(hal::Nanos now_ns) noexcept {
  hal::Nanos remaining_ns = now_ns - last_advance_ns_;
  last_advance_ns_ = now_ns;
  if (remaining_ns <= 0) return;
  if (state_ == EmulatorState::open && !watchdog_tripped_ &&
      now_ns - last_packet_ns_ > hal::millis(config_.watchdog_ms)) {
    watchdog_tripped_ = true;
    stats_.watchdog_stops += 1;
    // A client that went silent cannot stand behind its setpoints any more: drop them, so a
    // later PULSE (or a new client's SYNC0) does not drive the robot off again.
    if (!config_.watchdog_resumes) stop_motion();
  }
  while (remaining_ns > 0) {
    const hal::Nanos dt_ns = std::min(remaining_ns, kMaxIntegrationStepNs);
    remaining_ns -= dt_ns;
    const double dt_s = hal::to_seconds(dt_ns);
    const bool powered = state_ == EmulatorState::open && motors_enabled_ && !estop_;
    const bool pushed = !powered && (push_v_mm_s_ != 0.0 || push_w_deg_s_ != 0.0);
    if (!powered && !pushed) {
      v_mm_s_ = w_deg_s_ = 0;
      stalled_now_ = forced_stall_;
      continue;
    }
    if (pushed) {
      v_mm_s_ = push_v_mm_s_;
      w_deg_s_ = push_w_deg_s_;
    } else {
      double tv = watchdog_tripped_ ? 0.0 : target_v_mm_s_;
      double tw = watchdog_tripped_ ? 0.0 : target_w_deg_s_;
      if (heading_mode_ && !watchdog_tripped_) tw = heading_rate_deg_s(dt_s);
      if (move_mode_ && !watchdog_tripped_) {
        // Position mode: the fastest speed that can still brake to rest at the goal.
        const double reach = braking_speed(std::fabs(move_remaining_mm_), decel_mm_s2_, dt_s);
        tv = std::fabs(move_remaining_mm_) < kMoveDoneMm ? 0.0 : std::copysign(reach, move_remaining_mm_);
      }
      tv = std::clamp(tv, -max_v_mm_s_, max_v_mm_s_);
      v_mm_s_ = approach(v_mm_s_, tv, accel_mm_s2_, decel_mm_s2_, dt_s);
      w_deg_s_ = approach(w_deg_s_, tw, rot_accel_deg_s2_, rot_decel_deg_s2_, dt_s);
    }
    const double ds_mm = v_mm_s_ * dt_s;
    const double dth_rad = w_deg_s_ / kDegPerRad * dt_s;
    if (ds_mm == 0 && dth_rad == 0) {
      stalled_now_ = forced_stall_;
      continue;
    }
    const double mid = truth_.theta_rad + dth_rad / 2;
    const Pose2 to{truth_.x_m + ds_mm * 1e-3 * std::cos(mid), truth_.y_m + ds_mm * 1e-3 * std::sin(mid),
                   wrap_angle_rad(truth_.theta_rad + dth_rad)};
    if (forced_stall_ || world_->motion_blocked(truth_, to)) {
      stalled_now_ = true;
      v_mm_s_ = w_deg_s_ = 0;
      continue;
    }
    stalled_now_ = false;
    truth_ = to;
    if (move_mode_) move_remaining_mm_ -= ds_mm;
    const double odom_ds_mm = ds_mm * (1.0 + config_.odometry_scale_error);
    const double odom_dth_rad = dth_rad * (1.0 + config_.odometry_turn_error);
    const double odom_mid = odom_theta_rad_ + odom_dth_rad / 2;
    odom_x_mm_ += odom_ds_mm * std::cos(odom_mid);
    odom_y_mm_ += odom_ds_mm * std::sin(odom_mid);
    odom_theta_rad_ = wrap_angle_rad(odom_theta_rad_ + odom_dth_rad);
    const double wheel_offset_mm = dth_rad / config_.diff_conv_rad_per_mm;
    left_ticks_ += (ds_mm - wheel_offset_mm) * config_.ticks_mm;
    right_ticks_ += (ds_mm + wheel_offset_mm) * config_.ticks_mm;
  }
}

double P2osEmulator::heading_rate_deg_s(double dt_s) const noexcept {
  const double error_deg = wrap_angle_rad(target_heading_rad_ - odom_theta_rad_) * kDegPerRad;
  if (std::fabs(error_deg) < kHeadDoneDeg) return 0.0;
  // Like MOVE: the fastest rate that can still brake to rest at the target, so the heading
  // stops there instead of overshooting (a proportional servo asks for more braking than
  // RotDecel allows once the error is small).
  const double reach = braking_speed(std::fabs(error_deg), rot_decel_deg_s2_, dt_s);
  return std::copysign(std::min(reach, max_w_deg_s_), error_deg);
}

void P2osEmulator::send_sip() noexcept {
  Sip s;
  const bool moving = std::fabs(v_mm_s_) > kMovingMmS || std::fabs(w_deg_s_) > kMovingDegS;
  s.moving = moving;
  // 15-bit counters: plain two's-complement mm, masked (ARIA and Player both accept that).
  s.x_raw = static_cast<std::uint16_t>(static_cast<std::int64_t>(std::llround(odom_x_mm_)) & kPositionMask);
  s.y_raw = static_cast<std::uint16_t>(static_cast<std::int64_t>(std::llround(odom_y_mm_)) & kPositionMask);
  long theta_units = std::lround(odom_theta_rad_ / kThetaUnitRad);
  if (theta_units >= kThetaUnitsPerRev / 2) theta_units -= kThetaUnitsPerRev;
  if (theta_units < -kThetaUnitsPerRev / 2) theta_units += kThetaUnitsPerRev;
  s.theta_raw = static_cast<std::int16_t>(theta_units);
  const double w_rad_s = w_deg_s_ / kDegPerRad;
  const double wheel_offset_mm_s = w_rad_s / config_.diff_conv_rad_per_mm;
  s.left_vel_mm_s = static_cast<std::int16_t>(std::lround(v_mm_s_ - wheel_offset_mm_s));
  s.right_vel_mm_s = static_cast<std::int16_t>(std::lround(v_mm_s_ + wheel_offset_mm_s));
  s.battery_dv = static_cast<std::uint8_t>(std::min<std::uint16_t>(battery_dv_, 255));
  std::uint16_t stall_bumpers = static_cast<std::uint16_t>((rear_bumpers_ << 1) | (front_bumpers_ << 9));
  if (stalled_now_) stall_bumpers |= 0x0101u;  // both wheels, as AMRISim reports a stall
  s.stall_bumpers = stall_bumpers;
  s.control_raw = heading_mode_ ? static_cast<std::int16_t>(std::lround(target_heading_rad_ / kThetaUnitRad))
                                : s.theta_raw;
  std::uint16_t f = 0;
  if (motors_enabled_) f |= flags::kMotorsEnabled;
  if (sonar_on_) f |= flags::kSonarArrays;
  if (estop_) f |= flags::kEStop;
  s.flags = f;
  s.compass_2deg = 0;
  if (sonar_on_ && config_.sonar_count > 0) fire_sonar(s);
  s.digin = 0xFF;
  s.digout = 0xFF;
  s.has_battery_x10 = true;
  s.battery_x10 = battery_dv_;
  s.has_charge_state = true;
  s.charge_state = 0;
  s.has_rot_vel = true;
  s.rot_vel_ddeg_s = static_cast<std::int16_t>(std::lround(w_deg_s_ * 10.0));
  s.has_fault_flags = true;
  s.has_lat_vel = true;
  s.has_temperature = true;
  s.temperature_c = kNoTemperature;
  s.has_soc = true;
  send(encode_sip(s), true);
  stats_.sips_sent += 1;
}

void P2osEmulator::send_config() noexcept {
  ConfigPacket c;
  auto copy = [](auto& dst, const std::string& src) {
    const std::size_t n = std::min(src.size(), dst.size() - 1);
    std::copy_n(src.begin(), n, dst.begin());
    dst[n] = '\0';
  };
  copy(c.robot_class, config_.robot_class);
  copy(c.subclass, config_.subclass);
  copy(c.serial, config_.serial);
  copy(c.name, config_.name);
  copy(c.firmware_version, config_.firmware_version);
  c.rot_vel_top_deg_s = config_.rot_vel_top_deg_s;
  c.trans_vel_top_mm_s = config_.trans_vel_top_mm_s;
  c.rot_acc_top_deg_s2 = config_.rot_acc_top_deg_s2;
  c.trans_acc_top_mm_s2 = config_.trans_acc_top_mm_s2;
  c.pwm_max = 1000;
  c.sip_cycle_ms = static_cast<std::uint8_t>(std::clamp(config_.sip_cycle_ms, 1, 255));
  c.host_baud_code = config_.host_baud_code;
  c.front_sonar = 1;
  c.rear_sonar = 1;
  c.low_battery_dv = 115;
  c.rev_count = config_.rev_count;
  c.watchdog_ms = static_cast<std::uint16_t>(std::clamp(config_.watchdog_ms, 0, 65535));
  c.stall_val = 250;
  c.stall_count = 200;
  c.joy_vel_mm_s = 300;
  c.joy_rot_vel_deg_s = 60;
  c.rot_vel_max_deg_s = static_cast<std::uint16_t>(max_w_deg_s_);
  c.trans_vel_max_mm_s = static_cast<std::uint16_t>(max_v_mm_s_);
  c.rot_accel_deg_s2 = static_cast<std::uint16_t>(rot_accel_deg_s2_);
  c.rot_decel_deg_s2 = static_cast<std::uint16_t>(rot_decel_deg_s2_);
  c.rot_kp = 40;
  c.rot_kv = 20;
  c.trans_accel_mm_s2 = static_cast<std::uint16_t>(accel_mm_s2_);
  c.trans_decel_mm_s2 = static_cast<std::uint16_t>(decel_mm_s2_);
  c.trans_kp = 40;
  c.trans_kv = 30;
  c.front_bumps = 5;
  c.rear_bumps = 5;
  c.sonar_cycle_ms = 40;
  c.auto_baud = config_.auto_baud;
  c.ticks_mm = config_.ticks_mm;
  c.shutdown_dv = 110;
  c.high_temperature_shutdown_c = 70;
  send(encode_config(c));
}

void P2osEmulator::send_encoder() noexcept {
  EncoderPacket e;
  e.left_ticks = static_cast<std::int32_t>(static_cast<std::int64_t>(std::llround(left_ticks_)));
  e.right_ticks = static_cast<std::int32_t>(static_cast<std::int64_t>(std::llround(right_ticks_)));
  send(encode_encoder(e));
}

double P2osEmulator::sonar_echo_m(std::size_t disc) noexcept {
  const p2os::SonarMount& m = p2os::kP3dxSonar[disc];
  const double c = std::cos(truth_.theta_rad);
  const double sn = std::sin(truth_.theta_rad);
  const double x = truth_.x_m + (m.x_mm * c - m.y_mm * sn) * 1e-3;
  const double y = truth_.y_m + (m.x_mm * sn + m.y_mm * c) * 1e-3;
  const double heading = truth_.theta_rad + m.heading_deg / kDegPerRad;
  // The nearest echo within the cone; a lost echo (a surface at a glancing angle, cross-talk)
  // reads as nothing in range.
  constexpr int kRays = 5;
  const double half = p2os::kSonarBeamDeg / 2.0 / kDegPerRad;
  double nearest = config_.sonar_max_range_m;
  for (int r = 0; r < kRays; ++r) {
    const double a = heading - half + 2.0 * half * r / (kRays - 1);
    nearest = std::min(nearest, world_->sonar_range_m(Pose2{x, y, wrap_angle_rad(a)}, config_.sonar_max_range_m));
  }
  // Its own generator, so lost echoes leave the fault injection's byte stream as it was.
  if (config_.sonar_miss_rate > 0.0 && static_cast<double>(xorshift32(sonar_noise_)) / 4294967296.0 < config_.sonar_miss_rate)
    nearest = config_.sonar_max_range_m;
  return std::clamp(nearest, p2os::kSonarMinRangeM, config_.sonar_max_range_m);
}

void P2osEmulator::fire_sonar(Sip& s) noexcept {
  const auto count = static_cast<std::size_t>(std::min<int>(config_.sonar_count, static_cast<int>(p2os::kSonarDiscs)));
  const auto put = [&](std::size_t disc) {
    const double range_m = sonar_echo_m(disc);
    s.sonar[s.sonar_count++] = SonarReading{static_cast<std::uint8_t>(disc), static_cast<std::uint16_t>(std::lround(range_m * 1000.0))};
  };
  s.sonar_count = 0;
  if (config_.sonar_cycle_ms <= 0) {
    for (std::size_t disc = 0; disc < count; ++disc) put(disc);
    return;
  }
  // Each bank fires its next disc every cycle since the last SIP.
  sonar_credit_ms_ += config_.sip_cycle_ms;
  while (sonar_credit_ms_ >= config_.sonar_cycle_ms && static_cast<std::size_t>(s.sonar_count) + 2 <= kMaxSonarPerSip) {
    sonar_credit_ms_ -= config_.sonar_cycle_ms;
    for (std::size_t bank = 0; bank < count; bank += p2os::kSonarBank) {
      const std::size_t disc = bank + static_cast<std::size_t>(next_sonar_);
      if (disc < count) put(disc);
    }
    next_sonar_ = (next_sonar_ + 1) % static_cast<int>(p2os::kSonarBank);
  }
}

std::uint8_t P2osEmulator::next_noise_byte() noexcept {
  // Deterministic garbage for reproducible fault tests.
  return static_cast<std::uint8_t>(xorshift32(noise_state_));
}

void P2osEmulator::send(const Packet& packet, bool is_sip) noexcept {
  (void)is_sip;
  while (noise_bytes_ > 0) {
    const std::uint8_t b = next_noise_byte();
    send_raw(std::span<const std::uint8_t>(&b, 1));
    noise_bytes_ -= 1;
  }
  Packet out = packet;
  if (bad_checksum_packets_ > 0) {
    bad_checksum_packets_ -= 1;
    out.bytes[out.size - 1] ^= 0x5A;
  }
  std::size_t size = out.size;
  if (truncate_packets_ > 0) {
    truncate_packets_ -= 1;
    size /= 2;
  }
  send_raw(std::span<const std::uint8_t>(out.bytes.data(), size));
}

void P2osEmulator::send_raw(std::span<const std::uint8_t> bytes) noexcept {
  if (bytes.size() > tx_.size() - tx_size_) {
    stats_.bytes_dropped += bytes.size();
    return;
  }
  for (const std::uint8_t b : bytes) {
    tx_[(tx_head_ + tx_size_) % tx_.size()] = b;
    tx_size_ += 1;
  }
}

Status P2osEmulator::flush(hal::ByteStream& stream) noexcept {
  while (tx_size_ > 0) {
    const std::size_t contiguous = std::min(tx_size_, tx_.size() - tx_head_);
    Result<std::size_t> wrote = stream.write(std::span<const std::uint8_t>(tx_.data() + tx_head_, contiguous));
    if (!wrote) return wrote.error();
    if (*wrote == 0) break;
    tx_head_ = (tx_head_ + *wrote) % tx_.size();
    tx_size_ -= *wrote;
  }
  return Status::success();
}

}  // namespace sen3bot::p2os
