#pragma once
// SpscRing<T, N>: a lock-free, wait-free queue for exactly one producer thread and one
// consumer thread (e.g. a driver thread handing scans to a real-time task). Never allocates,
// never blocks, never throws.
//
// Memory ordering: the producer constructs the element, then publishes it with a release store
// of tail_; the consumer's acquire load of tail_ therefore sees the finished element. The same
// pairing on head_ tells the producer that a slot has been destroyed and may be reused.
// Indices count up forever (they wrap at 2^64, never in practice) and are masked into the
// storage, so all N slots are usable and "full" is simply tail - head == N.
#include <atomic>
#include <cstddef>
#include <memory>
#include <optional>
#include <type_traits>
#include <utility>

#include "sen3bot/mem/cache_line.hpp"

namespace sen3bot::mem {

template <typename T, std::size_t N>
class SpscRing {
  static_assert(N >= 2 && (N & (N - 1)) == 0, "SpscRing capacity must be a power of two");
  static_assert(std::is_nothrow_move_constructible_v<T> && std::is_nothrow_destructible_v<T>,
                "elements cross threads by move; a throwing move would lose an element");
  static_assert(std::atomic<std::size_t>::is_always_lock_free, "needs lock-free indices");

 public:
  using value_type = T;

  SpscRing() noexcept {}  // NOLINT: the union member is deliberately left unconstructed
  SpscRing(const SpscRing&) = delete;
  SpscRing& operator=(const SpscRing&) = delete;
  // Only when neither thread uses the queue any more.
  ~SpscRing() {
    while (try_pop()) {
    }
  }

  [[nodiscard]] static constexpr std::size_t capacity() noexcept { return N; }

  // --- producer thread only ---------------------------------------------------------------------
  [[nodiscard]] bool try_push(const T& value) noexcept(std::is_nothrow_copy_constructible_v<T>) {
    return try_emplace(value);
  }
  [[nodiscard]] bool try_push(T&& value) noexcept { return try_emplace(std::move(value)); }
  // False (and nothing constructed) when the queue is full.
  template <typename... Args>
  [[nodiscard]] bool try_emplace(Args&&... args) noexcept(std::is_nothrow_constructible_v<T, Args...>) {
    const std::size_t tail = producer_.tail.load(std::memory_order_relaxed);
    if (tail - producer_.head_seen == N) {
      // Looks full from the last known head: refresh it (one cross-core read, not one per push).
      producer_.head_seen = consumer_.head.load(std::memory_order_acquire);
      if (tail - producer_.head_seen == N) return false;
    }
    std::construct_at(items_ + (tail & kMask), std::forward<Args>(args)...);
    producer_.tail.store(tail + 1, std::memory_order_release);
    return true;
  }

  // --- consumer thread only ---------------------------------------------------------------------
  // The oldest element, moved out, or nullopt when empty.
  [[nodiscard]] std::optional<T> try_pop() noexcept {
    std::optional<T> out;
    const std::size_t head = consumer_.head.load(std::memory_order_relaxed);
    if (!refresh_if_empty(head)) return out;
    T& slot = items_[head & kMask];
    out.emplace(std::move(slot));
    std::destroy_at(&slot);
    consumer_.head.store(head + 1, std::memory_order_release);
    return out;
  }
  // Moves the oldest element into out; false when empty (out untouched).
  [[nodiscard]] bool try_pop(T& out) noexcept(std::is_nothrow_move_assignable_v<T>) {
    const std::size_t head = consumer_.head.load(std::memory_order_relaxed);
    if (!refresh_if_empty(head)) return false;
    T& slot = items_[head & kMask];
    out = std::move(slot);
    std::destroy_at(&slot);
    consumer_.head.store(head + 1, std::memory_order_release);
    return true;
  }

  // --- either thread: a snapshot that may be stale by the time it is used ------------------------
  [[nodiscard]] std::size_t size_approx() const noexcept {
    const std::size_t head = consumer_.head.load(std::memory_order_acquire);
    const std::size_t tail = producer_.tail.load(std::memory_order_acquire);
    return tail - head <= N ? tail - head : 0;  // the two loads are not one snapshot
  }
  [[nodiscard]] bool empty_approx() const noexcept { return size_approx() == 0; }

 private:
  static constexpr std::size_t kMask = N - 1;

  // True when there is an element at head; refreshes the consumer's view of tail only when the
  // cached one says empty.
  bool refresh_if_empty(std::size_t head) noexcept {
    if (head != consumer_.tail_seen) return true;
    consumer_.tail_seen = producer_.tail.load(std::memory_order_acquire);
    return head != consumer_.tail_seen;
  }

  // Each side's index and its cached copy of the other side's index share one cache line that
  // only that side writes.
  struct alignas(kCacheLineBytes) ProducerSide {
    std::atomic<std::size_t> tail{0};  // next slot to fill
    std::size_t head_seen = 0;         // last head the producer read
  };
  struct alignas(kCacheLineBytes) ConsumerSide {
    std::atomic<std::size_t> head{0};  // next slot to empty
    std::size_t tail_seen = 0;         // last tail the consumer read
  };

  ProducerSide producer_;
  ConsumerSide consumer_;
  union {
    alignas(kCacheLineBytes) T items_[N];  // the slots start on their own line
  };
};

}  // namespace sen3bot::mem
