#include <algorithm>
#include <cstring>

#include "sen3bot/hal/memory_stream.hpp"

namespace sen3bot::hal {

SpscByteRing::SpscByteRing(std::size_t capacity_bytes)
    : buffer_(std::make_unique<std::uint8_t[]>(capacity_bytes == 0 ? 1 : capacity_bytes)),
      capacity_(capacity_bytes == 0 ? 1 : capacity_bytes) {}

std::size_t SpscByteRing::write(std::span<const std::uint8_t> data) noexcept {
  const std::uint64_t head = written_.load(std::memory_order_relaxed);     // ours
  const std::uint64_t tail = read_.load(std::memory_order_acquire);        // consumer's
  const std::size_t used = static_cast<std::size_t>(head - tail);
  const std::size_t count = std::min(data.size(), capacity_ - used);
  if (count == 0) return 0;
  const std::size_t start = static_cast<std::size_t>(head % capacity_);
  const std::size_t first = std::min(count, capacity_ - start);  // up to the end of the buffer
  std::memcpy(buffer_.get() + start, data.data(), first);
  std::memcpy(buffer_.get(), data.data() + first, count - first);  // the wrapped part
  // Release: the bytes are visible before the consumer sees the new count.
  written_.store(head + count, std::memory_order_release);
  return count;
}

std::size_t SpscByteRing::read(std::span<std::uint8_t> out) noexcept {
  const std::uint64_t tail = read_.load(std::memory_order_relaxed);      // ours
  const std::uint64_t head = written_.load(std::memory_order_acquire);   // producer's
  const std::size_t available = static_cast<std::size_t>(head - tail);
  const std::size_t count = std::min(out.size(), available);
  if (count == 0) return 0;
  const std::size_t start = static_cast<std::size_t>(tail % capacity_);
  const std::size_t first = std::min(count, capacity_ - start);
  std::memcpy(out.data(), buffer_.get() + start, first);
  std::memcpy(out.data() + first, buffer_.get(), count - first);
  // Release: we are done with the bytes before the producer may overwrite them.
  read_.store(tail + count, std::memory_order_release);
  return count;
}

std::size_t SpscByteRing::size() const noexcept {
  const std::uint64_t tail = read_.load(std::memory_order_acquire);
  const std::uint64_t head = written_.load(std::memory_order_acquire);
  return head >= tail ? static_cast<std::size_t>(head - tail) : 0;
}

void SpscByteRing::clear() noexcept {
  written_.store(0, std::memory_order_relaxed);
  read_.store(0, std::memory_order_relaxed);
}

MemoryPipeEnd::MemoryPipeEnd(SpscByteRing& rx, SpscByteRing& tx, std::atomic<bool>& closed,
                             std::atomic<bool>& peer_closed, std::string name)
    : rx_(&rx), tx_(&tx), closed_(&closed), peer_closed_(&peer_closed), name_(std::move(name)) {}

Result<std::size_t> MemoryPipeEnd::read(std::span<std::uint8_t> out) {
  if (closed_->load(std::memory_order_acquire)) {
    return Error::format(Errc::disconnected, "%s: this end was disconnected", name_.c_str());
  }
  const std::size_t n = rx_->read(out);
  if (n > 0 || out.empty()) return n;
  if (peer_closed_->load(std::memory_order_acquire)) {
    // The peer may have written its last bytes between our read and its disconnect.
    const std::size_t last = rx_->read(out);
    if (last > 0) return last;
    return Error::format(Errc::disconnected, "%s: peer disconnected", name_.c_str());
  }
  return std::size_t{0};
}

Result<std::size_t> MemoryPipeEnd::write(std::span<const std::uint8_t> data) {
  if (closed_->load(std::memory_order_acquire)) {
    return Error::format(Errc::disconnected, "%s: this end was disconnected", name_.c_str());
  }
  if (peer_closed_->load(std::memory_order_acquire)) {
    return Error::format(Errc::disconnected, "%s: peer disconnected", name_.c_str());
  }
  return tx_->write(data);
}

MemoryPipe::MemoryPipe(std::size_t capacity_bytes, std::string_view name_a, std::string_view name_b)
    : a_to_b_(capacity_bytes),
      b_to_a_(capacity_bytes),
      a_(b_to_a_, a_to_b_, a_closed_, b_closed_, std::string(name_a)),
      b_(a_to_b_, b_to_a_, b_closed_, a_closed_, std::string(name_b)) {}

void MemoryPipe::reset() noexcept {
  a_to_b_.clear();
  b_to_a_.clear();
  a_closed_.store(false, std::memory_order_release);
  b_closed_.store(false, std::memory_order_release);
}

}  // namespace sen3bot::hal
