// CanFrame checks, the link state from error frames and the transmit ring: shared by every
// CanBus backend, with no OS dependency.
#include <algorithm>

#include "sen3bot/hal/can.hpp"
#include "sen3bot/hal/candump.hpp"

namespace sen3bot::hal {

const char* to_string(CanLinkState state) noexcept {
  switch (state) {
    case CanLinkState::active: return "error-active";
    case CanLinkState::warning: return "error-warning";
    case CanLinkState::passive: return "error-passive";
    case CanLinkState::bus_off: return "bus-off";
  }
  return "unknown";
}

CanLinkState next_link_state(CanLinkState current, const CanFrame& error_frame) noexcept {
  const std::uint32_t classes = error_frame.id;
  if ((classes & can_error::kBusOff) != 0) return CanLinkState::bus_off;
  CanLinkState next = current;
  if ((classes & can_error::kRestarted) != 0) next = CanLinkState::active;
  if ((classes & can_error::kController) != 0 && error_frame.dlc >= 2) {
    const std::uint8_t state = error_frame.data[1];
    if ((state & (can_error::kRxPassive | can_error::kTxPassive)) != 0) {
      next = CanLinkState::passive;
    } else if ((state & (can_error::kRxWarning | can_error::kTxWarning)) != 0) {
      next = CanLinkState::warning;
    } else if ((state & can_error::kActive) != 0) {
      next = CanLinkState::active;
    }
  }
  return next;
}

CanTxRing::CanTxRing(std::size_t capacity, std::string_view name)
    : frames_(capacity > 0 ? std::make_unique<CanFrame[]>(capacity) : nullptr), capacity_(capacity) {
  const std::size_t n = std::min(name.size(), name_.size() - 1);
  std::copy_n(name.begin(), n, name_.begin());
}

bool CanTxRing::push(const CanFrame& frame) noexcept {
  if (count_ == capacity_) {
    ++dropped_;
    return false;
  }
  frames_[(head_ + count_) % capacity_] = frame;
  ++count_;
  return true;
}

void CanTxRing::pop() noexcept {
  head_ = (head_ + 1) % capacity_;
  --count_;
}

std::size_t CanTxRing::discard() noexcept {
  const std::size_t n = count_;
  dropped_ += n;
  head_ = 0;
  count_ = 0;
  return n;
}

Status CanTxRing::flush(WriteFn write, void* context) {
  while (count_ > 0) {
    Status written = write(context, front());
    if (!written) {
      if (written.error().code() != Errc::would_block) return written;
      return Error::format(Errc::would_block, "%s: transmit queue full, %zu frames waiting", name_.data(), count_);
    }
    pop();
  }
  return {};
}

Status CanTxRing::send(const CanFrame& frame, WriteFn write, void* context) {
  if (Status flushed = flush(write, context); !flushed && flushed.error().code() != Errc::would_block) {
    return flushed;
  }
  if (count_ == 0) {
    Status written = write(context, frame);
    if (written || written.error().code() != Errc::would_block) return written;
  }
  // Behind the waiting frames, or the controller has no room: keep it for the next flush.
  if (push(frame)) return {};
  if (capacity_ == 0) {
    return Error::format(Errc::would_block, "%s: kernel transmit queue full, frame 0x%X dropped (no queue)",
                         name_.data(), static_cast<unsigned>(frame.id));
  }
  return Error::format(Errc::would_block, "%s: transmit queue full (%zu frames waiting), frame 0x%X dropped",
                       name_.data(), capacity_, static_cast<unsigned>(frame.id));
}

Status CanFrame::validate() const {
  if (dlc > kMaxDataBytes) {
    return Error::format(Errc::invalid_argument, "CAN frame 0x%X: dlc %u exceeds %zu", static_cast<unsigned>(id),
                         static_cast<unsigned>(dlc), kMaxDataBytes);
  }
  const std::uint32_t max_id = extended ? kMaxExtendedId : kMaxStandardId;
  if (id > max_id) {
    return Error::format(Errc::invalid_argument, "CAN id 0x%X does not fit in %d bits (%s frame)",
                         static_cast<unsigned>(id), extended ? 29 : 11, extended ? "extended" : "standard");
  }
  return {};
}

Result<CanFrame> CanFrame::make(std::uint32_t id, std::span<const std::uint8_t> payload, bool extended) {
  CanFrame frame;
  frame.id = id;
  frame.extended = extended;
  if (payload.size() > kMaxDataBytes) {
    return Error::format(Errc::invalid_argument, "CAN frame 0x%X: %zu data bytes exceed %zu", static_cast<unsigned>(id),
                         payload.size(), kMaxDataBytes);
  }
  frame.dlc = static_cast<std::uint8_t>(payload.size());
  std::copy(payload.begin(), payload.end(), frame.data.begin());
  if (Status valid = frame.validate(); !valid) return valid.error();
  return frame;
}

}  // namespace sen3bot::hal
