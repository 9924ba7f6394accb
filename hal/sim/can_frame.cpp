// CanFrame checks shared by every CanBus backend (no OS dependency).
#include <algorithm>

#include "sen3bot/hal/can.hpp"

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
