#include "sen3bot/view/channel_board.hpp"

#include <new>

namespace sen3bot::view {

Result<std::unique_ptr<ChannelBoard>> ChannelBoard::create(std::span<const ChannelSpec> channels, std::size_t headroom,
                                                           std::pmr::memory_resource& memory) {
  if (channels.empty() || channels.size() > kMaxChannels)
    return Error::format(Errc::invalid_argument, "view: %zu channels (1 to %zu)", channels.size(), kMaxChannels);
  std::unique_ptr<ChannelBoard> board(new ChannelBoard());
  board->count_ = channels.size();
  board->headroom_ = headroom;
  // Buffers start at multiples of 16 so every headroom begins aligned, as the frame writers like.
  std::size_t total = 0;
  for (std::size_t i = 0; i < channels.size(); ++i) {
    if (channels[i].capacity_bytes == 0 || channels[i].topic.empty())
      return Error::format(Errc::invalid_argument, "view: channel %zu has no topic or no capacity", i);
    board->specs_[i] = channels[i];
    const std::size_t capacity = (channels[i].capacity_bytes + kMaxRecords * headroom + 15) / 16 * 16;
    board->slots_[i].capacity = capacity;
    total += 3 * capacity;
  }
  try {
    board->block_ = static_cast<char*>(memory.allocate(total, 16));
  } catch (const std::bad_alloc&) {
    return Error::format(Errc::capacity, "view: cannot take %zu bytes for the channel buffers", total);
  }
  board->memory_ = &memory;
  board->bytes_ = total;
  char* at = board->block_;
  for (std::size_t i = 0; i < board->count_; ++i)
    for (Publication& p : board->slots_[i].buffers) {
      p.data = at;
      at += board->slots_[i].capacity;
    }
  return board;
}

ChannelBoard::~ChannelBoard() {
  if (block_ != nullptr) memory_->deallocate(block_, bytes_, 16);
}

std::span<char> ChannelBoard::space(std::size_t channel) noexcept {
  Slot& s = slots_[channel];
  const Publication& back = s.buffers[s.back];
  const std::size_t start = s.used + headroom_;
  if (back.record_count >= kMaxRecords || start >= s.capacity) return {};
  return {back.data + start, s.capacity - start};
}

void ChannelBoard::commit(std::size_t channel, std::size_t size, hal::Nanos stamp_ns) noexcept {
  Slot& s = slots_[channel];
  Publication& back = s.buffers[s.back];
  const std::size_t start = s.used + headroom_;
  if (back.record_count >= kMaxRecords || start + size > s.capacity) return;  // space() was empty
  back.records[back.record_count++] = {start, size, stamp_ns};
  // The next headroom begins 16-aligned.
  s.used = (start + size + 15) / 16 * 16;
  if (s.used > s.capacity) s.used = s.capacity;
}

void ChannelBoard::publish(std::size_t channel) noexcept {
  Slot& s = slots_[channel];
  Publication& back = s.buffers[s.back];
  if (back.record_count == 0) return;
  back.seq = s.next_seq++;
  s.back = s.middle.exchange(static_cast<std::uint8_t>(s.back | kFresh), std::memory_order_acq_rel) & 3u;
  s.published.store(back.seq, std::memory_order_release);
  s.buffers[s.back].record_count = 0;
  s.used = 0;
}

void ChannelBoard::discard(std::size_t channel) noexcept {
  Slot& s = slots_[channel];
  s.buffers[s.back].record_count = 0;
  s.used = 0;
}

const Publication& ChannelBoard::take(std::size_t channel) noexcept {
  Slot& s = slots_[channel];
  if (s.middle.load(std::memory_order_acquire) & kFresh)
    s.front = s.middle.exchange(s.front, std::memory_order_acq_rel) & 3u;
  return s.buffers[s.front];
}

}  // namespace sen3bot::view
