#include "sen3bot/camera/frame_pool.hpp"

namespace sen3bot::camera {

FrameHandle& FrameHandle::operator=(FrameHandle&& other) noexcept {
  if (this != &other) {
    release();
    pool_ = other.pool_;
    slot_ = other.slot_;
    ref_ = other.ref_;
    other.pool_ = nullptr;
  }
  return *this;
}

void FrameHandle::release() {
  if (pool_ != nullptr) {
    pool_->unpin(slot_);
    pool_ = nullptr;
  }
}

Result<std::unique_ptr<FramePool>> FramePool::create(std::size_t slots, std::uint32_t width_px, std::uint32_t height_px,
                                                     PixelFormat format) {
  if (slots < kMinSlots || slots > 64) return Error(Errc::invalid_argument, "frame pool needs 3..64 slots");
  if (width_px == 0 || height_px == 0 || width_px > 8192 || height_px > 8192) {
    return Error(Errc::invalid_argument, "frame pool size must be 1..8192 px per side");
  }
  return std::unique_ptr<FramePool>(new FramePool(slots, width_px, height_px, format));
}

FramePool::FramePool(std::size_t slots, std::uint32_t width_px, std::uint32_t height_px, PixelFormat format)
    : slot_count_(slots),
      width_px_(width_px),
      height_px_(height_px),
      format_(format),
      slot_bytes_(std::size_t{width_px} * height_px * bytes_per_pixel(format)),
      pixels_(new std::uint8_t[slots * slot_bytes_]()),
      slots_(new Slot[slots]) {}

int FramePool::begin_write() {
  const int latest = latest_.load(std::memory_order_seq_cst);
  for (std::size_t i = 0; i < slot_count_; ++i) {
    if (static_cast<int>(i) != latest && slots_[i].pins.load(std::memory_order_seq_cst) == 0) return static_cast<int>(i);
  }
  return -1;
}

std::span<std::uint8_t> FramePool::slot_pixels(int slot) {
  return {pixels_.get() + static_cast<std::size_t>(slot) * slot_bytes_, slot_bytes_};
}

void FramePool::publish(int slot, std::uint32_t width_px, std::uint32_t height_px, std::uint32_t rtp_timestamp,
                        hal::Nanos last_packet_ns, hal::Nanos decoded_ns) {
  FrameRef& ref = slots_[slot].ref;
  ref.data = slot_pixels(slot).data();
  ref.width_px = width_px;
  ref.height_px = height_px;
  ref.stride_bytes = static_cast<std::uint32_t>(width_px * bytes_per_pixel(format_));
  ref.format = format_;
  ref.sequence = next_sequence_++;
  ref.rtp_timestamp = rtp_timestamp;
  ref.last_packet_ns = last_packet_ns;
  ref.decoded_ns = decoded_ns;
  latest_.store(slot, std::memory_order_seq_cst);
  latest_sequence_.store(ref.sequence, std::memory_order_release);
}

FrameHandle FramePool::acquire_latest() {
  // Pin, then confirm the slot is still the newest. The writer never fills the newest slot
  // nor a pinned one, so a confirmed pin is stable (both sides use seq_cst so the writer's
  // pin check and our re-read cannot both miss each other).
  for (int attempt = 0; attempt < 8; ++attempt) {
    const int slot = latest_.load(std::memory_order_seq_cst);
    if (slot < 0) return {};
    slots_[slot].pins.fetch_add(1, std::memory_order_seq_cst);
    if (latest_.load(std::memory_order_seq_cst) == slot) {
      return FrameHandle(this, static_cast<std::uint32_t>(slot), slots_[slot].ref);
    }
    slots_[slot].pins.fetch_sub(1, std::memory_order_seq_cst);
  }
  return {};  // the writer kept publishing; try again next cycle rather than spin
}

}  // namespace sen3bot::camera
