#pragma once
// Decoded frames in a fixed pool of buffers allocated once, handed from the (non-real-time)
// decoder thread to real-time readers through a lock-free latest-value slot. Readers never
// block and never allocate: they pin the newest slot with a reference count, the writer
// only ever fills a slot that is neither the newest nor pinned.
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <type_traits>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/result.hpp"

namespace sen3bot::camera {

enum class PixelFormat : std::uint8_t { bgr8, gray8 };
constexpr std::size_t bytes_per_pixel(PixelFormat f) { return f == PixelFormat::bgr8 ? 3 : 1; }

// What a reader gets: fixed-size and trivially copyable so it can cross into real-time code.
struct FrameRef {
  const std::uint8_t* data = nullptr;  // rows of stride_bytes; valid while the handle lives
  std::uint32_t width_px = 0;
  std::uint32_t height_px = 0;
  std::uint32_t stride_bytes = 0;
  PixelFormat format = PixelFormat::bgr8;
  std::uint64_t sequence = 0;          // 1, 2, ... in decode order; 0 = no frame
  std::uint32_t rtp_timestamp = 0;     // 90 kHz media clock
  hal::Nanos last_packet_ns = 0;       // CLOCK_MONOTONIC arrival of the frame's last RTP packet
  hal::Nanos decoded_ns = 0;           // when the frame became readable
};
static_assert(std::is_trivially_copyable_v<FrameRef>);

class FramePool;

// A pinned frame. Move-only; releases the pin when destroyed.
class FrameHandle {
 public:
  FrameHandle() = default;
  FrameHandle(FrameHandle&& other) noexcept : pool_(other.pool_), slot_(other.slot_), ref_(other.ref_) { other.pool_ = nullptr; }
  FrameHandle& operator=(FrameHandle&& other) noexcept;
  FrameHandle(const FrameHandle&) = delete;
  FrameHandle& operator=(const FrameHandle&) = delete;
  ~FrameHandle() { release(); }

  [[nodiscard]] const FrameRef& ref() const { return ref_; }
  [[nodiscard]] explicit operator bool() const { return pool_ != nullptr; }
  void release();

 private:
  friend class FramePool;
  FrameHandle(FramePool* pool, std::uint32_t slot, const FrameRef& ref) : pool_(pool), slot_(slot), ref_(ref) {}
  FramePool* pool_ = nullptr;
  std::uint32_t slot_ = 0;
  FrameRef ref_;
};

class FramePool {
 public:
  // At least 3 slots: the newest, one a reader holds, one being written. Each reader that
  // may hold a frame across a publish needs one more.
  static constexpr std::size_t kMinSlots = 3;

  static Result<std::unique_ptr<FramePool>> create(std::size_t slots, std::uint32_t width_px, std::uint32_t height_px,
                                                  PixelFormat format);

  // --- writer side (one thread) ---------------------------------------------------------
  // A slot to fill, or -1 when every slot is the newest or pinned (the frame is then dropped).
  int begin_write();
  [[nodiscard]] std::span<std::uint8_t> slot_pixels(int slot);
  void publish(int slot, std::uint32_t width_px, std::uint32_t height_px, std::uint32_t rtp_timestamp,
               hal::Nanos last_packet_ns, hal::Nanos decoded_ns);

  // --- reader side (any thread, real-time safe) -------------------------------------------
  // The newest frame, pinned; empty when none was published yet. Lock-free, no allocation.
  FrameHandle acquire_latest();
  // Sequence number of the newest frame (0 = none): lets a task skip acquire when unchanged.
  [[nodiscard]] std::uint64_t latest_sequence() const { return latest_sequence_.load(std::memory_order_acquire); }

  [[nodiscard]] std::uint32_t width_px() const { return width_px_; }
  [[nodiscard]] std::uint32_t height_px() const { return height_px_; }
  [[nodiscard]] PixelFormat format() const { return format_; }
  [[nodiscard]] std::size_t slot_count() const { return slot_count_; }
  [[nodiscard]] std::size_t bytes() const { return slot_count_ * slot_bytes_; }

 private:
  friend class FrameHandle;
  struct Slot {
    std::atomic<std::uint32_t> pins{0};
    FrameRef ref;
  };
  FramePool(std::size_t slots, std::uint32_t width_px, std::uint32_t height_px, PixelFormat format);
  void unpin(std::uint32_t slot) { slots_[slot].pins.fetch_sub(1, std::memory_order_seq_cst); }

  std::size_t slot_count_;
  std::uint32_t width_px_;
  std::uint32_t height_px_;
  PixelFormat format_;
  std::size_t slot_bytes_;
  std::unique_ptr<std::uint8_t[]> pixels_;
  std::unique_ptr<Slot[]> slots_;
  std::atomic<int> latest_{-1};
  std::atomic<std::uint64_t> latest_sequence_{0};
  std::uint64_t next_sequence_ = 1;
};

// For a real-time task: hands out a frame only when a newer one than last time exists.
// Holds no pin between calls unless the caller keeps the handle. No blocking, no allocation.
class FrameReader {
 public:
  explicit FrameReader(FramePool& pool) : pool_(&pool) {}

  // The newest frame if it is newer than the last one returned; empty otherwise.
  FrameHandle newer() {
    if (pool_->latest_sequence() <= last_sequence_) return {};
    FrameHandle frame = pool_->acquire_latest();
    if (!frame || frame.ref().sequence <= last_sequence_) return {};
    if (last_sequence_ != 0) skipped_ += frame.ref().sequence - last_sequence_ - 1;
    last_sequence_ = frame.ref().sequence;
    return frame;
  }
  [[nodiscard]] std::uint64_t last_sequence() const { return last_sequence_; }
  // Frames published but never seen by this reader (it ran slower than the camera).
  [[nodiscard]] std::uint64_t skipped() const { return skipped_; }

 private:
  FramePool* pool_;
  std::uint64_t last_sequence_ = 0;
  std::uint64_t skipped_ = 0;
};

}  // namespace sen3bot::camera
