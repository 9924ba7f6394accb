#include "sen3bot/p2os/driver.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace sen3bot::p2os {

namespace {

// How long a robot that was still open gets to process our CLOSE before SYNC0 again.
constexpr hal::Nanos kDislodgeSettleNs = hal::millis(300);
// ARIA switches its own rate 10 ms after sending HOSTBAUD.
constexpr hal::Nanos kBaudSwitchSettleNs = hal::millis(10);
constexpr int kMaxReadsPerStep = 16;

std::int32_t to_mm_s(double v_m_s, double max_m_s) noexcept {
  const double v = std::clamp(std::isfinite(v_m_s) ? v_m_s : 0.0, -max_m_s, max_m_s);
  return static_cast<std::int32_t>(std::lround(v * 1000.0));
}

std::int32_t to_deg_s(double omega_rad_s, double max_rad_s) noexcept {
  const double w = std::clamp(std::isfinite(omega_rad_s) ? omega_rad_s : 0.0, -max_rad_s, max_rad_s);
  return static_cast<std::int32_t>(std::lround(w * 180.0 / std::numbers::pi));
}

}  // namespace

const char* to_string(LinkState state) noexcept {
  switch (state) {
    case LinkState::disconnected: return "disconnected";
    case LinkState::syncing: return "syncing";
    case LinkState::connected: return "connected";
    case LinkState::closing: return "closing";
    case LinkState::closed: return "closed";
  }
  return "unknown";
}

P2osDriver::P2osDriver(const P2osConfig& config)
    : config_(config), baud_(config.baud), open_baud_(config.baud), odometry_(config.conversion) {}

void P2osDriver::attach(hal::ByteStream& stream, hal::Nanos now_ns, BaudControl* baud_control,
                        std::uint32_t current_baud) noexcept {
  if (phase_ == Phase::closed) return;
  stream_ = &stream;
  stream_error_.reset();
  baud_control_ = baud_control;
  baud_ = current_baud != 0 ? current_baud : config_.baud;
  open_baud_ = baud_;
  // Probing continues from the rate we are at, in the usual order.
  probe_index_ = 0;
  for (std::size_t i = 0; i < kProbeBauds.size(); ++i)
    if (kProbeBauds[i] == baud_) probe_index_ = i;
  have_in_flight_ = false;
  in_flight_offset_ = 0;
  sync_started_ns_ = now_ns;
  misses_ = 0;
  enter_sync(now_ns);
}

void P2osDriver::detach() noexcept {
  stream_ = nullptr;
  baud_control_ = nullptr;
  have_in_flight_ = false;
  queue_.clear();
  if (phase_ != Phase::closed) {
    phase_ = Phase::idle;
    state_.link = LinkState::disconnected;
  }
}

void P2osDriver::fail_stream(const Error& error) noexcept {
  if (phase_ == Phase::running) state_.link_losses += 1;
  stream_error_ = error;
  stream_ = nullptr;
  baud_control_ = nullptr;
  have_in_flight_ = false;
  queue_.clear();
  vel_dirty_ = rvel_dirty_ = false;
  // A close in progress cannot finish without a link; it ends here.
  if (phase_ == Phase::closing || phase_ == Phase::closed) {
    phase_ = Phase::closed;
    state_.link = LinkState::closed;
  } else {
    phase_ = Phase::idle;
    state_.link = LinkState::disconnected;
  }
}

void P2osDriver::set_setpoint(const BaseSetpoint& setpoint, hal::Nanos now_ns) noexcept {
  setpoint_ = setpoint;
  setpoint_stamp_ns_ = now_ns;
  have_setpoint_ = true;
}

void P2osDriver::request_close(hal::Nanos now_ns) noexcept {
  if (phase_ == Phase::closing || phase_ == Phase::closed) return;
  if (stream_ != nullptr && (phase_ == Phase::running || phase_ == Phase::opening)) {
    queue_.clear();
    vel_dirty_ = rvel_dirty_ = false;
    queue(encode_command_int(Command::vel, 0));
    queue(encode_command_int(Command::rvel, 0));
    queue(encode_command_int(Command::enable, 0));
    queue(encode_command(kClose));
    phase_ = Phase::closing;
    phase_deadline_ns_ = now_ns + hal::millis(config_.sync_timeout_ms);
    state_.link = LinkState::closing;
    return;
  }
  phase_ = Phase::closed;
  state_.link = LinkState::closed;
}

void P2osDriver::step(hal::Nanos now_ns) noexcept {
  if (stream_ == nullptr) return;
  bool any = false;
  for (int i = 0; i < kMaxReadsPerStep; ++i) {
    Result<std::size_t> got = stream_->read(read_buffer_);
    if (!got) {
      fail_stream(got.error());
      return;
    }
    if (*got == 0) break;
    any = true;
    parser_.feed(std::span<const std::uint8_t>(read_buffer_.data(), *got), now_ns,
                 [&](const Frame& frame) { on_frame(frame, now_ns); });
    if (*got < read_buffer_.size()) break;
  }
  if (!any) parser_.feed({}, now_ns, [](const Frame&) {});  // expire a stale partial frame
  state_.bad_checksums = parser_.stats().bad_checksums;
  run_timers(now_ns);
  if (stream_ != nullptr) flush_tx(now_ns);
}

void P2osDriver::enter_sync(hal::Nanos now_ns) noexcept {
  if (phase_ == Phase::running || phase_ == Phase::idle || phase_ == Phase::closed) sync_started_ns_ = now_ns;
  queue_.clear();
  vel_dirty_ = rvel_dirty_ = false;
  sent_enable_ = false;
  sent_vel_mm_s_ = 0;
  sent_rvel_deg_s_ = 0;
  baud_switch_ = BaudSwitch::none;
  parser_.reset();
  state_.link = LinkState::syncing;
  send_sync(0, now_ns);
}

void P2osDriver::send_sync(int n, hal::Nanos now_ns) noexcept {
  queue(encode_command(static_cast<Command>(n)));
  phase_ = n == 0 ? Phase::sync0 : (n == 1 ? Phase::sync1 : Phase::sync2);
  phase_deadline_ns_ = now_ns + hal::millis(config_.sync_timeout_ms);
}

void P2osDriver::handshake_miss(hal::Nanos now_ns) noexcept {
  misses_ += 1;
  if (config_.probe_bauds && baud_control_ != nullptr && config_.sync_misses_per_baud > 0 &&
      misses_ % config_.sync_misses_per_baud == 0) {
    probe_index_ = (probe_index_ + 1) % kProbeBauds.size();
    if (baud_control_->set_baud(kProbeBauds[probe_index_])) baud_ = kProbeBauds[probe_index_];
  }
  enter_sync(now_ns);
}

void P2osDriver::link_lost(hal::Nanos now_ns) noexcept {
  state_.link_losses += 1;
  enter_sync(now_ns);
}

void P2osDriver::on_frame(const Frame& frame, hal::Nanos now_ns) noexcept {
  last_rx_frame_ns_ = now_ns;
  if (baud_switch_ == BaudSwitch::verify) baud_switch_ = BaudSwitch::done;
  const bool is_sip = frame.type == kTypeSipStopped || frame.type == kTypeSipMoving;
  const bool is_reset = frame.type == kTypeResetA || frame.type == kTypeResetB;
  switch (phase_) {
    case Phase::sync0:
    case Phase::sync1:
    case Phase::sync2: {
      const int expected = phase_ == Phase::sync0 ? 0 : (phase_ == Phase::sync1 ? 1 : 2);
      if (frame.type == expected) {
        if (expected < 2) {
          send_sync(expected + 1, now_ns);
          return;
        }
        if (auto reply = decode_sync2_reply(frame)) identity_ = *reply;
        odometry_.rebase();
        queue(encode_command(kOpen));
        // ARCOS resumes its last setpoint once traffic returns: stop it before anything else.
        queue(encode_command_int(Command::vel, 0));
        queue(encode_command_int(Command::rvel, 0));
        if (config_.request_config) queue(encode_command(Command::config));
        if (config_.bumpstall >= 0) queue(encode_command_int(Command::bumpstall, config_.bumpstall));
        // SETA with a negative argument sets the braking deceleration.
        if (config_.trans_decel_mm_s2 > 0) queue(encode_command_int(Command::seta, -config_.trans_decel_mm_s2));
        if (config_.request_encoders) queue(encode_command_int(Command::encoder, 2));
        phase_ = Phase::opening;
        phase_deadline_ns_ = now_ns + hal::millis(config_.sync_timeout_ms);
      } else if (is_sip) {
        // Still open from an earlier client: it answers with SIPs, not echoes.
        queue_.clear();
        queue(encode_command(kClose));
        phase_ = Phase::dislodge;
        phase_deadline_ns_ = now_ns + kDislodgeSettleNs;
      } else {
        enter_sync(now_ns);
      }
      return;
    }
    case Phase::opening:
      if (is_sip) {
        phase_ = Phase::running;
        state_.link = LinkState::connected;
        connect_duration_ns_ = now_ns - sync_started_ns_;
        if (ever_connected_) state_.reconnects += 1;
        ever_connected_ = true;
        misses_ = 0;
        last_velocity_sent_ns_ = now_ns;
        on_sip(frame, now_ns);
      } else if (frame.type == kTypeConfig) {
        config_packet_ = decode_config(frame);
      }
      return;
    case Phase::running:
    case Phase::closing:
      if (is_sip) {
        on_sip(frame, now_ns);
      } else if (frame.type == kTypeConfig) {
        config_packet_ = decode_config(frame);
      } else if (frame.type == kTypeEncoder) {
        if (auto enc = decode_encoder(frame)) {
          state_.left_encoder_ticks = enc->left_ticks;
          state_.right_encoder_ticks = enc->right_ticks;
          state_.encoders_valid = true;
        }
      } else if (is_reset && phase_ == Phase::running) {
        link_lost(now_ns);
      }
      return;
    case Phase::idle:
    case Phase::dislodge:
    case Phase::closed:
      return;
  }
}

void P2osDriver::on_sip(const Frame& frame, hal::Nanos now_ns) noexcept {
  const std::optional<Sip> decoded = decode_sip(frame);
  if (!decoded) return;
  const Sip& s = *decoded;
  last_sip_ = s;
  last_sip_ns_ = now_ns;
  odometry_.update(s);
  const ConversionFactors& k = config_.conversion;
  state_.x_m = odometry_.pose().x_m;
  state_.y_m = odometry_.pose().y_m;
  state_.theta_rad = odometry_.pose().theta_rad;
  state_.distance_m = odometry_.distance_m();
  state_.left_wheel_m_s = s.left_vel_mm_s * k.vel_conv_mm_s_per_unit * 1e-3;
  state_.right_wheel_m_s = s.right_vel_mm_s * k.vel_conv_mm_s_per_unit * 1e-3;
  state_.v_m_s = (state_.left_wheel_m_s + state_.right_wheel_m_s) / 2.0;
  if (s.has_rot_vel) {
    state_.omega_rad_s = s.rot_vel_ddeg_s / 10.0 * std::numbers::pi / 180.0;
  } else {
    state_.omega_rad_s =
        (s.right_vel_mm_s - s.left_vel_mm_s) * k.vel_conv_mm_s_per_unit / 2.0 * k.diff_conv_rad_per_mm;
  }
  state_.battery_v = s.has_battery_x10 ? s.battery_x10 / 10.0 : s.battery_dv / 10.0;
  state_.stall_bumpers_raw = s.stall_bumpers;
  state_.left_stall = (s.stall_bumpers & 0x0001u) != 0;
  state_.right_stall = (s.stall_bumpers & 0x0100u) != 0;
  state_.rear_bumpers = static_cast<std::uint8_t>((s.stall_bumpers >> 1) & 0x7Fu);
  state_.front_bumpers = static_cast<std::uint8_t>((s.stall_bumpers >> 9) & 0x7Fu);
  state_.flags_raw = s.flags;
  state_.motors_enabled = (s.flags & flags::kMotorsEnabled) != 0;
  state_.estop = (s.flags & flags::kEStop) != 0;
  state_.moving = s.moving;
  state_.sip_stamp_ns = now_ns;
  state_.sip_count += 1;
  new_sip_ = true;
}

void P2osDriver::run_timers(hal::Nanos now_ns) noexcept {
  switch (phase_) {
    case Phase::sync0:
    case Phase::sync1:
    case Phase::sync2:
    case Phase::opening:
      if (now_ns >= phase_deadline_ns_) handshake_miss(now_ns);
      return;
    case Phase::dislodge:
      if (now_ns >= phase_deadline_ns_) {
        parser_.reset();
        send_sync(0, now_ns);
      }
      return;
    case Phase::running: {
      const bool switching = baud_switch_ == BaudSwitch::settle || baud_switch_ == BaudSwitch::verify;
      if (!switching && now_ns - last_sip_ns_ > hal::millis(config_.link_timeout_ms)) {
        link_lost(now_ns);
        return;
      }
      run_baud_switch(now_ns);
      update_setpoints(now_ns);
      if (queue_.empty() && !have_in_flight_ && !vel_dirty_ && !rvel_dirty_ &&
          now_ns - last_tx_ns_ >= hal::millis(config_.pulse_interval_ms)) {
        queue(encode_command(kPulse));
      }
      return;
    }
    case Phase::closing:
      if ((queue_.empty() && !have_in_flight_) || now_ns >= phase_deadline_ns_) {
        phase_ = Phase::closed;
        state_.link = LinkState::closed;
      }
      return;
    case Phase::idle:
    case Phase::closed:
      return;
  }
}

void P2osDriver::run_baud_switch(hal::Nanos now_ns) noexcept {
  switch (baud_switch_) {
    case BaudSwitch::none: {
      if (!config_packet_ || baud_control_ == nullptr || config_.switch_to_baud <= baud_) return;
      constexpr std::uint8_t kAutoBaudSwitchable = 2;
      if (config_packet_->auto_baud != kAutoBaudSwitchable) return;
      for (std::size_t code = 0; code < std::size(kHostBaudRates); ++code) {
        if (kHostBaudRates[code] == config_.switch_to_baud) {
          queue(encode_command_int(Command::hostbaud, static_cast<std::int32_t>(code)));
          baud_switch_ = BaudSwitch::hostbaud_queued;
          return;
        }
      }
      baud_switch_ = BaudSwitch::done;  // not a rate HOSTBAUD can select
      return;
    }
    case BaudSwitch::hostbaud_queued:
      if (queue_.empty() && !have_in_flight_) {
        baud_switch_ = BaudSwitch::settle;
        baud_switch_deadline_ns_ = now_ns + kBaudSwitchSettleNs;
      }
      return;
    case BaudSwitch::settle:
      if (now_ns >= baud_switch_deadline_ns_) {
        baud_before_switch_ = baud_;
        if (!baud_control_->set_baud(config_.switch_to_baud)) {
          baud_switch_ = BaudSwitch::done;
          return;
        }
        baud_ = config_.switch_to_baud;
        parser_.reset();
        queue(encode_command(kPulse));
        baud_switch_ = BaudSwitch::verify;
        baud_switch_deadline_ns_ = now_ns + hal::millis(config_.baud_switch_timeout_ms);
      }
      return;
    case BaudSwitch::verify:
      if (now_ns >= baud_switch_deadline_ns_) {
        // Silence at the new rate: go back (the robot reverts too after 500 ms).
        if (baud_control_->set_baud(baud_before_switch_)) baud_ = baud_before_switch_;
        parser_.reset();
        last_sip_ns_ = now_ns;
        baud_switch_ = BaudSwitch::done;
      }
      return;
    case BaudSwitch::done:
      return;
  }
}

void P2osDriver::update_setpoints(hal::Nanos now_ns) noexcept {
  const bool timed_out = have_setpoint_ && now_ns - setpoint_stamp_ns_ > hal::millis(config_.command_timeout_ms);
  if (timed_out && !state_.command_timed_out) state_.command_timeouts += 1;
  state_.command_timed_out = timed_out;
  const bool want_enable = have_setpoint_ && setpoint_.enable_motors;
  const bool drive = want_enable && !timed_out;
  const std::int32_t vel = drive ? to_mm_s(setpoint_.v_m_s, config_.max_v_m_s) : 0;
  const std::int32_t rvel = drive ? to_deg_s(setpoint_.omega_rad_s, config_.max_omega_rad_s) : 0;
  if (want_enable != sent_enable_) {
    if (!want_enable) {
      // Stop before disabling, so a later ENABLE cannot resume an old speed.
      queue(encode_command_int(Command::vel, 0));
      queue(encode_command_int(Command::rvel, 0));
      sent_vel_mm_s_ = sent_rvel_deg_s_ = 0;
      vel_dirty_ = rvel_dirty_ = false;
    }
    queue(encode_command_int(Command::enable, want_enable ? 1 : 0));
    sent_enable_ = want_enable;
  }
  const bool active = vel != 0 || rvel != 0;
  const bool refresh = active && now_ns - last_velocity_sent_ns_ >= hal::millis(config_.setpoint_refresh_ms);
  if (vel != sent_vel_mm_s_ || refresh) {
    sent_vel_mm_s_ = vel;
    vel_dirty_ = true;
  }
  if (rvel != sent_rvel_deg_s_ || refresh) {
    sent_rvel_deg_s_ = rvel;
    rvel_dirty_ = true;
  }
  if (refresh) last_velocity_sent_ns_ = now_ns;
}

void P2osDriver::queue(const Packet& packet) noexcept {
  if (!queue_.push(packet)) commands_dropped_ += 1;
}

void P2osDriver::flush_tx(hal::Nanos now_ns) noexcept {
  for (;;) {
    if (have_in_flight_) {
      const std::span<const std::uint8_t> rest = in_flight_.view().subspan(in_flight_offset_);
      Result<std::size_t> wrote = stream_->write(rest);
      if (!wrote) {
        fail_stream(wrote.error());
        return;
      }
      in_flight_offset_ += *wrote;
      if (in_flight_offset_ < in_flight_.size) return;  // the link is full; resume next step
      have_in_flight_ = false;
      last_tx_ns_ = now_ns;
      packets_sent_ += 1;
    }
    if (packets_sent_ > 0 && now_ns - last_packet_start_ns_ < hal::millis(config_.command_spacing_ms)) return;
    if (!queue_.empty()) {
      in_flight_ = queue_.front();
      queue_.drop_front();
    } else if (vel_dirty_ && phase_ == Phase::running) {
      in_flight_ = encode_command_int(Command::vel, sent_vel_mm_s_);
      vel_dirty_ = false;
      last_velocity_sent_ns_ = now_ns;
    } else if (rvel_dirty_ && phase_ == Phase::running) {
      in_flight_ = encode_command_int(Command::rvel, sent_rvel_deg_s_);
      rvel_dirty_ = false;
      last_velocity_sent_ns_ = now_ns;
    } else {
      return;
    }
    have_in_flight_ = true;
    in_flight_offset_ = 0;
    last_packet_start_ns_ = now_ns;
  }
}

}  // namespace sen3bot::p2os
