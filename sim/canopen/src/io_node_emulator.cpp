#include "sen3bot/sim/canopen/io_node_emulator.hpp"

#include <array>

namespace sen3bot::canopen {

void IoNodeEmulator::power_up(hal::Nanos now_ns) noexcept {
  powered_ = true;
  state_ = NmtState::pre_operational;
  boot_pending_ = true;
  heartbeat_ms_ = config_.heartbeat_ms;
  next_heartbeat_ns_ = heartbeat_ms_ > 0 ? now_ns + heartbeat_ms_ * 1'000'000LL : -1;
  outputs_ = 0;
  error_mode_ = 0xFF;
  error_value_ = 0x00;
  inputs_ever_sent_ = false;
  tpdo_event_ms_ = 0;
  next_tpdo_ns_ = -1;
  sdo_answer_pending_ = false;
}

void IoNodeEmulator::raise_emergency(std::uint16_t code, std::uint8_t error_register) noexcept {
  emcy_ = {};
  emcy_.code = code;
  emcy_.error_register = error_register;
  emcy_pending_ = true;
}

void IoNodeEmulator::communication_error() noexcept {
  outputs_ = static_cast<std::uint8_t>((outputs_ & ~error_mode_) | (error_value_ & error_mode_));
}

Result<CanFrame> IoNodeEmulator::answer(const Sdo& request) noexcept {
  const std::uint8_t node = config_.node;
  const SdoAddress at = request.at;
  if (request.type == SdoType::upload_request) {
    if (at == SdoAddress{0x1000, 0}) return sdo_upload_response(node, at, config_.device_type, 4);
    if (at == SdoAddress{0x1017, 0}) return sdo_upload_response(node, at, heartbeat_ms_, 2);
    if (at == SdoAddress{0x1018, 1}) return sdo_upload_response(node, at, config_.vendor_id, 4);
    if (at == SdoAddress{0x1800, 5}) return sdo_upload_response(node, at, tpdo_event_ms_, 2);
    if (at == SdoAddress{0x6000, 1}) return sdo_upload_response(node, at, inputs_, 1);
    if (at == SdoAddress{0x6200, 1}) return sdo_upload_response(node, at, outputs_, 1);
    if (at == SdoAddress{0x6206, 1}) return sdo_upload_response(node, at, error_mode_, 1);
    if (at == SdoAddress{0x6207, 1}) return sdo_upload_response(node, at, error_value_, 1);
    const bool known_index = at.index == 0x1000 || at.index == 0x1017 || at.index == 0x1018 || at.index == 0x1800 ||
                             at.index == 0x6000 || at.index == 0x6200 || at.index == 0x6206 || at.index == 0x6207;
    return sdo_abort(node, at, known_index ? abort_code::kNoSubIndex : abort_code::kNoObject, true);
  }
  if (request.type != SdoType::download_request) return sdo_abort(node, at, abort_code::kBadCommand, true);
  if (refused_code_ != 0 && at.index == refused_index_) {
    const std::uint32_t code = refused_code_;
    refused_code_ = 0;
    return sdo_abort(node, at, code, true);
  }
  const auto sized = [&](std::uint8_t size) { return request.size == size; };
  if (at == SdoAddress{0x1017, 0}) {
    if (!sized(2)) return sdo_abort(node, at, abort_code::kLengthMismatch, true);
    heartbeat_ms_ = static_cast<std::uint16_t>(request.value);
    return sdo_download_response(node, at);
  }
  if (at == SdoAddress{0x1800, 5}) {
    if (!sized(2)) return sdo_abort(node, at, abort_code::kLengthMismatch, true);
    tpdo_event_ms_ = static_cast<std::uint16_t>(request.value);
    return sdo_download_response(node, at);
  }
  if (at == SdoAddress{0x6206, 1} || at == SdoAddress{0x6207, 1} || at == SdoAddress{0x6200, 1}) {
    if (!sized(1)) return sdo_abort(node, at, abort_code::kLengthMismatch, true);
    const auto v = static_cast<std::uint8_t>(request.value);
    if (at.index == 0x6206) error_mode_ = v;
    else if (at.index == 0x6207) error_value_ = v;
    else outputs_ = v;
    return sdo_download_response(node, at);
  }
  if (at.index == 0x1000 || at.index == 0x1018 || at.index == 0x6000)
    return sdo_abort(node, at, abort_code::kReadOnly, true);
  return sdo_abort(node, at, abort_code::kNoObject, true);
}

void IoNodeEmulator::on_frame(const CanFrame& frame, hal::Nanos now_ns) noexcept {
  if (!powered_ || silent_) return;
  const Classified c = classify(frame);
  if (c.kind == Kind::nmt) {
    const Result<Nmt> command = decode_nmt(frame);
    if (!command || (command->node != 0 && command->node != config_.node)) return;
    switch (command->command) {
      case NmtCommand::start: state_ = NmtState::operational; break;
      case NmtCommand::stop: state_ = NmtState::stopped; break;
      case NmtCommand::enter_pre_operational: state_ = NmtState::pre_operational; break;
      case NmtCommand::reset_node:
        power_up(now_ns);
        break;
      case NmtCommand::reset_communication: {
        // The communication objects return to their power-up values; the outputs stay.
        const std::uint8_t outputs = outputs_;
        const std::uint8_t mode = error_mode_;
        const std::uint8_t value = error_value_;
        power_up(now_ns);
        outputs_ = outputs;
        error_mode_ = mode;
        error_value_ = value;
        break;
      }
    }
    return;
  }
  if (c.node != config_.node) return;
  if (c.kind == Kind::sdo_request && state_ != NmtState::stopped) {
    const Result<Sdo> request = decode_sdo(frame);
    Result<CanFrame> reply =
        request ? answer(*request) : sdo_abort(config_.node, {}, abort_code::kBadCommand, true);
    if (reply) {
      sdo_answer_ = *reply;
      sdo_answer_pending_ = true;
    }
    return;
  }
  if (c.kind == Kind::rpdo && c.pdo == 1 && state_ == NmtState::operational && frame.dlc >= 1) outputs_ = frame.data[0];
}

std::size_t IoNodeEmulator::poll(hal::Nanos now_ns, std::span<CanFrame> out) noexcept {
  std::size_t n = 0;
  if (!powered_ || silent_) return 0;
  const auto push = [&](const Result<CanFrame>& f) {
    if (f && n < out.size()) out[n++] = *f;
  };
  if (boot_pending_ && n < out.size()) {
    push(heartbeat(config_.node, NmtState::boot_up));
    boot_pending_ = false;
  }
  if (sdo_answer_pending_ && n < out.size()) {
    push(sdo_answer_);
    sdo_answer_pending_ = false;
  }
  if (emcy_pending_ && n < out.size()) {
    push(emergency(config_.node, emcy_));
    emcy_pending_ = false;
  }
  if (malformed_pending_ && n + 2 <= out.size()) {
    CanFrame empty_heartbeat;
    empty_heartbeat.id = 0x700u + config_.node;
    CanFrame empty_tpdo;
    empty_tpdo.id = 0x180u + config_.node;
    out[n++] = empty_heartbeat;
    out[n++] = empty_tpdo;
    malformed_pending_ = false;
  }
  const bool timer_due = tpdo_event_ms_ > 0 && (next_tpdo_ns_ < 0 || now_ns >= next_tpdo_ns_);
  if (state_ == NmtState::operational && (!inputs_ever_sent_ || inputs_ != inputs_sent_ || timer_due) &&
      n < out.size()) {
    const std::array<std::uint8_t, 1> data = {inputs_};
    push(pdo(config_.node, 1, true, data));
    inputs_sent_ = inputs_;
    inputs_ever_sent_ = true;
    next_tpdo_ns_ = tpdo_event_ms_ > 0 ? now_ns + tpdo_event_ms_ * 1'000'000LL : -1;
  }
  if (heartbeat_ms_ > 0) {
    if (next_heartbeat_ns_ < 0) next_heartbeat_ns_ = now_ns;
    if (now_ns >= next_heartbeat_ns_ && n < out.size()) {
      push(heartbeat(config_.node, state_));
      next_heartbeat_ns_ = now_ns + heartbeat_ms_ * 1'000'000LL;
    }
  }
  if (state_ != NmtState::operational) inputs_ever_sent_ = false;
  return n;
}

}  // namespace sen3bot::canopen
