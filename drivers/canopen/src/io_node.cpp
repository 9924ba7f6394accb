#include "sen3bot/canopen/io_node.hpp"

namespace sen3bot::canopen {

namespace {
constexpr SdoAddress kHeartbeatTime{0x1017, 0};
constexpr SdoAddress kOutputsErrorMode{0x6206, 1};
constexpr SdoAddress kOutputsErrorValue{0x6207, 1};
constexpr SdoAddress kInputsEventTimer{0x1800, 5};

hal::Nanos seconds(double s) noexcept { return static_cast<hal::Nanos>(s * 1e9); }
}  // namespace

const char* to_string(IoNodeState state) noexcept {
  switch (state) {
    case IoNodeState::waiting_boot: return "waiting_boot";
    case IoNodeState::configuring: return "configuring";
    case IoNodeState::starting: return "starting";
    case IoNodeState::operational: return "operational";
    case IoNodeState::lost: return "lost";
    case IoNodeState::fault: return "fault";
  }
  return "unknown";
}

const char* to_string(IoNodeEvent event) noexcept {
  switch (event) {
    case IoNodeEvent::boot_up: return "boot_up";
    case IoNodeEvent::heartbeat_lost: return "heartbeat_lost";
    case IoNodeEvent::configured: return "configured";
    case IoNodeEvent::sdo_abort: return "sdo_abort";
    case IoNodeEvent::sdo_timeout: return "sdo_timeout";
    case IoNodeEvent::emergency: return "emergency";
    case IoNodeEvent::emergency_reset: return "emergency_reset";
    case IoNodeEvent::unexpected_frame: return "unexpected_frame";
  }
  return "unknown";
}

Status IoNodeMaster::check(const IoNodeConfig& c) {
  if (!valid_node(c.node))
    return Error::format(Errc::config, "CAN I/O node: node id %u is outside 1..127", static_cast<unsigned>(c.node));
  if (c.heartbeat_ms == 0 || !(c.heartbeat_timeout_s > c.heartbeat_ms / 1000.0))
    return Error::format(Errc::config,
                         "CAN I/O node %u: the heartbeat timeout (%g s) must be longer than its period (%u ms)",
                         static_cast<unsigned>(c.node), c.heartbeat_timeout_s, static_cast<unsigned>(c.heartbeat_ms));
  if (!(c.sdo_timeout_s > 0.0) || !(c.outputs_refresh_s > 0.0) || !(c.fault_retry_s > 0.0))
    return Error::format(Errc::config, "CAN I/O node %u: sdo_timeout_s, outputs_refresh_s and fault_retry_s must be "
                                       "positive",
                         static_cast<unsigned>(c.node));
  return {};
}

IoNodeMaster::IoNodeMaster(const IoNodeConfig& config) noexcept : config_(config) {
  writes_ = {Write{kHeartbeatTime, config.heartbeat_ms, 2}, Write{kInputsEventTimer, config.inputs_period_ms, 2},
             Write{kOutputsErrorMode, config.outputs_error_mode, 1},
             Write{kOutputsErrorValue, config.outputs_error_value, 1}};
}

void IoNodeMaster::enter(IoNodeState state, hal::Nanos now_ns) noexcept {
  state_ = state;
  state_since_ns_ = now_ns;
  if (state != IoNodeState::operational) inputs_seen_ = false;
}

void IoNodeMaster::begin_configuration(hal::Nanos now_ns) noexcept {
  write_index_ = 0;
  write_pending_ = true;
  write_attempts_ = 0;
  write_sent_ns_ = -1;
  start_pending_ = false;
  enter(IoNodeState::configuring, now_ns);
}

void IoNodeMaster::on_frame(const CanFrame& frame, hal::Nanos now_ns) noexcept {
  const Classified c = classify(frame);
  if (c.node != config_.node) return;
  switch (c.kind) {
    case Kind::heartbeat: {
      const Result<Heartbeat> hb = decode_heartbeat(frame);
      if (!hb) {
        note(IoNodeEvent::unexpected_frame);
        return;
      }
      last_heartbeat_ns_ = now_ns;
      heard_ = true;
      node_state_ = hb->state;
      if (hb->state == NmtState::boot_up) {
        // A reset node has lost its configuration (and its outputs): start again.
        note(IoNodeEvent::boot_up);
        outputs_ever_sent_ = false;
        begin_configuration(now_ns);
        return;
      }
      if (state_ == IoNodeState::waiting_boot || state_ == IoNodeState::lost) {
        // Already running (the master restarted, or the node came back): configure it anyway.
        begin_configuration(now_ns);
      } else if (state_ == IoNodeState::starting && hb->state == NmtState::operational) {
        outputs_ever_sent_ = false;
        enter(IoNodeState::operational, now_ns);
      } else if (state_ == IoNodeState::operational && hb->state != NmtState::operational) {
        // Stopped or sent back to pre-operational by someone else: its PDOs are off.
        start_pending_ = true;
        enter(IoNodeState::starting, now_ns);
      }
      return;
    }
    case Kind::sdo_response: {
      const Result<Sdo> sdo = decode_sdo(frame);
      if (!sdo || state_ != IoNodeState::configuring || write_sent_ns_ < 0 || write_index_ >= writes_.size()) {
        note(IoNodeEvent::unexpected_frame);
        return;
      }
      const Write& w = writes_[write_index_];
      if (sdo->type == SdoType::abort && sdo->at == w.at) {
        last_abort_ = sdo->value;
        last_abort_at_ = sdo->at;
        note(IoNodeEvent::sdo_abort);
        enter(IoNodeState::fault, now_ns);
        return;
      }
      if (sdo->type != SdoType::download_response || !(sdo->at == w.at)) {
        note(IoNodeEvent::unexpected_frame);
        return;
      }
      write_sent_ns_ = -1;
      write_attempts_ = 0;
      if (++write_index_ < writes_.size()) {
        write_pending_ = true;
      } else {
        note(IoNodeEvent::configured);
        start_pending_ = true;
        enter(IoNodeState::starting, now_ns);
      }
      return;
    }
    case Kind::tpdo:
      if (c.pdo != 1) return;
      if (frame.dlc < 1) {
        note(IoNodeEvent::unexpected_frame);
        return;
      }
      inputs_ = frame.data[0];
      inputs_ns_ = now_ns;
      inputs_seen_ = state_ == IoNodeState::operational;
      return;
    case Kind::emcy: {
      const Result<Emergency> e = decode_emergency(frame);
      if (!e) {
        note(IoNodeEvent::unexpected_frame);
        return;
      }
      last_emergency_ = *e;
      note(e->code == 0 ? IoNodeEvent::emergency_reset : IoNodeEvent::emergency);
      return;
    }
    default:
      return;  // the master's own frames (SDO requests, RPDOs) and other objects
  }
}

std::size_t IoNodeMaster::poll(hal::Nanos now_ns, std::span<CanFrame> out) noexcept {
  std::size_t n = 0;
  const auto push = [&](const Result<CanFrame>& f) {
    if (f && n < out.size()) out[n++] = *f;
  };
  if (heard_ && now_ns - last_heartbeat_ns_ > seconds(config_.heartbeat_timeout_s)) {
    heard_ = false;
    note(IoNodeEvent::heartbeat_lost);
    enter(IoNodeState::lost, now_ns);
  }
  switch (state_) {
    case IoNodeState::waiting_boot:
    case IoNodeState::lost:
      // Ask for a boot-up now and then: a node that was reset before the master listened, or
      // that came back, answers with one.
      if (reset_sent_ns_ < 0 || now_ns - reset_sent_ns_ >= seconds(config_.fault_retry_s)) {
        push(nmt(NmtCommand::reset_communication, config_.node));
        reset_sent_ns_ = now_ns;
      }
      break;
    case IoNodeState::configuring: {
      const Write& w = writes_[write_index_];
      if (!write_pending_ && write_sent_ns_ >= 0 && now_ns - write_sent_ns_ > seconds(config_.sdo_timeout_s)) {
        if (write_attempts_ > config_.sdo_retries) {
          note(IoNodeEvent::sdo_timeout);
          enter(IoNodeState::fault, now_ns);
          break;
        }
        write_pending_ = true;
      }
      if (write_pending_ && n < out.size()) {
        push(sdo_download_request(config_.node, w.at, w.value, w.size));
        write_pending_ = false;
        write_sent_ns_ = now_ns;
        ++write_attempts_;
      }
      break;
    }
    case IoNodeState::starting:
      if (!start_pending_ && now_ns - state_since_ns_ > seconds(config_.heartbeat_timeout_s)) {
        start_pending_ = true;  // the start was lost, or the node ignored it: again
        state_since_ns_ = now_ns;
      }
      if (start_pending_ && n < out.size()) {
        push(nmt(NmtCommand::start, config_.node));
        start_pending_ = false;
      }
      break;
    case IoNodeState::operational:
      if (!outputs_ever_sent_ || outputs_ != outputs_sent_ ||
          now_ns - outputs_sent_ns_ >= seconds(config_.outputs_refresh_s)) {
        const std::array<std::uint8_t, 1> data = {outputs_};
        if (n < out.size()) {
          push(pdo(config_.node, 1, false, data));
          outputs_sent_ = outputs_;
          outputs_sent_ns_ = now_ns;
          outputs_ever_sent_ = true;
        }
      }
      break;
    case IoNodeState::fault:
      if (now_ns - state_since_ns_ >= seconds(config_.fault_retry_s)) {
        push(nmt(NmtCommand::reset_communication, config_.node));
        reset_sent_ns_ = now_ns;
        heard_ = false;
        enter(IoNodeState::waiting_boot, now_ns);
      }
      break;
  }
  return n;
}

}  // namespace sen3bot::canopen
