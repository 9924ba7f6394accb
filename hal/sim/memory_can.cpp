#include <algorithm>

#include "sen3bot/hal/can.hpp"

namespace sen3bot::hal {

MemoryCanBus::MemoryCanBus(std::size_t max_nodes) : max_nodes_(max_nodes) { nodes_.reserve(max_nodes); }

Result<MemoryCanNode*> MemoryCanBus::attach(std::string_view name, MemoryCanNodeOptions options) {
  if (options.receive_queue_frames == 0) {
    return Error::format(Errc::invalid_argument, "memory CAN node '%.*s': receive queue of 0 frames",
                         static_cast<int>(name.size()), name.data());
  }
  std::lock_guard lock(mutex_);
  if (nodes_.size() >= max_nodes_) {
    return Error::format(Errc::capacity, "memory CAN bus: all %zu node slots in use, cannot attach '%.*s'", max_nodes_,
                         static_cast<int>(name.size()), name.data());
  }
  nodes_.push_back(std::unique_ptr<MemoryCanNode>(new MemoryCanNode(*this, std::string(name), options)));
  return nodes_.back().get();
}

void MemoryCanBus::set_link_up(bool up) { set_link_state(up ? CanLinkState::active : CanLinkState::bus_off); }

void MemoryCanBus::set_link_state(CanLinkState state) {
  std::lock_guard lock(mutex_);
  link_state_ = state;
  link_up_ = state != CanLinkState::bus_off;
}

CanLinkState MemoryCanBus::link_state() const {
  std::lock_guard lock(mutex_);
  return link_state_;
}

CanLinkState MemoryCanNode::link_state() const { return bus_.link_state(); }

bool MemoryCanBus::link_up() const {
  std::lock_guard lock(mutex_);
  return link_up_;
}

std::uint64_t MemoryCanBus::frames_sent() const {
  std::lock_guard lock(mutex_);
  return frames_sent_;
}

MemoryCanNode::MemoryCanNode(MemoryCanBus& bus, std::string name, MemoryCanNodeOptions options)
    : bus_(bus),
      name_(std::move(name)),
      options_(options),
      queue_(std::make_unique<CanFrame[]>(options.receive_queue_frames)) {}

bool MemoryCanNode::accepts(const CanFrame& frame) const noexcept {
  return std::any_of(filters_.begin(), filters_.begin() + static_cast<std::ptrdiff_t>(filter_count_),
                     [&](const CanFilter& filter) { return filter.matches(frame); });
}

void MemoryCanNode::deliver(const CanFrame& frame) noexcept {
  if (!accepts(frame)) return;
  if (queue_count_ == options_.receive_queue_frames) {
    ++overflow_count_;  // like a socket receive queue: the newest frame is the one lost
    return;
  }
  queue_[(queue_head_ + queue_count_) % options_.receive_queue_frames] = frame;
  ++queue_count_;
}

Status MemoryCanNode::send(const CanFrame& frame) {
  if (Status valid = frame.validate(); !valid) return valid;
  std::lock_guard lock(bus_.mutex_);
  if (!bus_.link_up_) return Error::format(Errc::disconnected, "%s: CAN bus is down (bus-off)", name_.c_str());
  for (const std::unique_ptr<MemoryCanNode>& node : bus_.nodes_) {
    if (node.get() != this || options_.receive_own) node->deliver(frame);
  }
  ++sent_count_;
  ++bus_.frames_sent_;
  return {};
}

Result<std::optional<CanFrame>> MemoryCanNode::receive() {
  std::lock_guard lock(bus_.mutex_);
  if (queue_count_ == 0) {
    if (!bus_.link_up_) return Error::format(Errc::disconnected, "%s: CAN bus is down", name_.c_str());
    return std::optional<CanFrame>();
  }
  const CanFrame frame = queue_[queue_head_];
  queue_head_ = (queue_head_ + 1) % options_.receive_queue_frames;
  --queue_count_;
  ++received_count_;
  return std::optional<CanFrame>(frame);
}

Status MemoryCanNode::set_filters(std::span<const CanFilter> filters) {
  if (filters.size() > kMaxCanFilters) {
    return Error::format(Errc::capacity, "%s: %zu filters, at most %zu", name_.c_str(), filters.size(), kMaxCanFilters);
  }
  std::lock_guard lock(bus_.mutex_);
  std::copy(filters.begin(), filters.end(), filters_.begin());
  filter_count_ = filters.size();
  return {};
}

std::size_t MemoryCanNode::queued_frames() const {
  std::lock_guard lock(bus_.mutex_);
  return queue_count_;
}

std::uint64_t MemoryCanNode::overflow_count() const {
  std::lock_guard lock(bus_.mutex_);
  return overflow_count_;
}

std::uint64_t MemoryCanNode::sent_count() const {
  std::lock_guard lock(bus_.mutex_);
  return sent_count_;
}

std::uint64_t MemoryCanNode::received_count() const {
  std::lock_guard lock(bus_.mutex_);
  return received_count_;
}

}  // namespace sen3bot::hal
