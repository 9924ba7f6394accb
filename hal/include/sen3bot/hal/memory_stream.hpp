#pragma once
// In-memory byte streams: a simulated device and its driver talk through two fixed-size
// byte rings, from two threads or single-threaded in lockstep.
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "sen3bot/hal/byte_stream.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/mem/cache_line.hpp"

namespace sen3bot::hal {

// Lock-free single-producer/single-consumer byte ring. The buffer is allocated once, in
// the constructor. write() from one thread, read() from one (possibly other) thread.
class SpscByteRing {
 public:
  explicit SpscByteRing(std::size_t capacity_bytes);  // at least 1 byte
  SpscByteRing(const SpscByteRing&) = delete;
  SpscByteRing& operator=(const SpscByteRing&) = delete;

  // Copies as much as fits and returns how much that was (may be less than offered).
  std::size_t write(std::span<const std::uint8_t> data) noexcept;  // producer only
  std::size_t read(std::span<std::uint8_t> out) noexcept;          // consumer only

  [[nodiscard]] std::size_t size() const noexcept;  // exact for either side, a snapshot for others
  [[nodiscard]] std::size_t free_space() const noexcept { return capacity_ - size(); }
  [[nodiscard]] std::size_t capacity() const noexcept { return capacity_; }
  // Empties the ring. Only while neither side is using it.
  void clear() noexcept;

 private:
  std::unique_ptr<std::uint8_t[]> buffer_;
  std::size_t capacity_;
  // Total bytes ever written / read. 64-bit so they never wrap in practice; the ring
  // position is counter % capacity, which works for any capacity, not only powers of two.
  // Separate cache lines: the producer's and consumer's counters must not false-share.
  alignas(mem::kCacheLineBytes) std::atomic<std::uint64_t> written_{0};
  alignas(mem::kCacheLineBytes) std::atomic<std::uint64_t> read_{0};
};

class MemoryPipe;

// One end of a MemoryPipe. Use each end from one thread at a time.
class MemoryPipeEnd final : public ByteStream {
 public:
  MemoryPipeEnd(const MemoryPipeEnd&) = delete;
  MemoryPipeEnd& operator=(const MemoryPipeEnd&) = delete;

  // 0 bytes = nothing now. After the peer disconnected: what it wrote before is still
  // returned, then Errc::disconnected. No allocation.
  Result<std::size_t> read(std::span<std::uint8_t> out) override;
  // Accepts as much as fits in the ring (0 when full). Errc::disconnected once either end
  // has disconnected (nobody would ever read it).
  Result<std::size_t> write(std::span<const std::uint8_t> data) override;
  [[nodiscard]] std::string_view name() const override { return name_; }

  // This end goes away, like an unplugged device: the other end drains, then reads
  // Errc::disconnected. This end's own read/write report disconnected at once.
  void disconnect() noexcept { closed_->store(true, std::memory_order_release); }
  [[nodiscard]] bool connected() const noexcept {
    return !closed_->load(std::memory_order_acquire) && !peer_closed_->load(std::memory_order_acquire);
  }
  [[nodiscard]] std::size_t readable_bytes() const noexcept { return rx_->size(); }
  [[nodiscard]] std::size_t writable_bytes() const noexcept { return tx_->free_space(); }

 private:
  friend class MemoryPipe;
  MemoryPipeEnd(SpscByteRing& rx, SpscByteRing& tx, std::atomic<bool>& closed, std::atomic<bool>& peer_closed,
                std::string name);

  SpscByteRing* rx_;
  SpscByteRing* tx_;
  std::atomic<bool>* closed_;
  std::atomic<bool>* peer_closed_;
  std::string name_;
};

// Two connected ByteStream ends; each direction has its own ring of capacity_bytes.
class MemoryPipe {
 public:
  explicit MemoryPipe(std::size_t capacity_bytes, std::string_view name_a = "memory:a",
                      std::string_view name_b = "memory:b");
  MemoryPipe(const MemoryPipe&) = delete;
  MemoryPipe& operator=(const MemoryPipe&) = delete;

  [[nodiscard]] MemoryPipeEnd& a() noexcept { return a_; }
  [[nodiscard]] MemoryPipeEnd& b() noexcept { return b_; }

  // Reconnects both ends with empty rings ("plug the device back in"). Only while no
  // thread is using either end.
  void reset() noexcept;

 private:
  SpscByteRing a_to_b_;
  SpscByteRing b_to_a_;
  std::atomic<bool> a_closed_{false};
  std::atomic<bool> b_closed_{false};
  MemoryPipeEnd a_;
  MemoryPipeEnd b_;
};

}  // namespace sen3bot::hal
