#pragma once
// Real-time code must not print: it posts short events into this bounded multi-producer,
// single-consumer queue and a background task writes them out. Posting never blocks and never
// allocates; when the queue is full the event is dropped and counted.
#include <array>
#include <atomic>
#include <cstdarg>
#include <cstddef>
#include <cstdint>
#include <cstdio>

#include "sen3bot/hal/clock.hpp"

namespace sen3bot::tasks {

enum class Severity : std::uint8_t { info, warning, error };

struct Event {
  static constexpr std::size_t kTextCapacity = 112;
  hal::Nanos stamp_ns = 0;
  Severity severity = Severity::info;
  char source[15] = {};
  char text[kTextCapacity] = {};
};

template <std::size_t Capacity>
class EventLog {
  static_assert(Capacity >= 2 && (Capacity & (Capacity - 1)) == 0, "capacity must be a power of two");

 public:
  EventLog() {
    for (std::size_t i = 0; i < Capacity; ++i) cells_[i].sequence.store(i, std::memory_order_relaxed);
  }

  // Any thread. Bounded queue after D. Vyukov: each cell's sequence says whose turn it is.
  [[gnu::format(printf, 5, 6)]] bool post(hal::Nanos stamp_ns, Severity severity, const char* source,
                                          const char* fmt, ...) noexcept {
    std::size_t pos = head_.load(std::memory_order_relaxed);
    Cell* cell;
    for (;;) {
      cell = &cells_[pos & (Capacity - 1)];
      const std::size_t seq = cell->sequence.load(std::memory_order_acquire);
      const auto diff = static_cast<std::ptrdiff_t>(seq) - static_cast<std::ptrdiff_t>(pos);
      if (diff == 0) {
        if (head_.compare_exchange_weak(pos, pos + 1, std::memory_order_relaxed)) break;
      } else if (diff < 0) {
        dropped_.fetch_add(1, std::memory_order_relaxed);
        return false;
      } else {
        pos = head_.load(std::memory_order_relaxed);
      }
    }
    Event& e = cell->event;
    e.stamp_ns = stamp_ns;
    e.severity = severity;
    std::snprintf(e.source, sizeof e.source, "%s", source);
    std::va_list args;
    va_start(args, fmt);
    std::vsnprintf(e.text, sizeof e.text, fmt, args);
    va_end(args);
    cell->sequence.store(pos + 1, std::memory_order_release);
    return true;
  }

  // Single consumer.
  bool pop(Event& out) noexcept {
    Cell& cell = cells_[tail_ & (Capacity - 1)];
    const std::size_t seq = cell.sequence.load(std::memory_order_acquire);
    if (seq != tail_ + 1) return false;
    out = cell.event;
    cell.sequence.store(tail_ + Capacity, std::memory_order_release);
    ++tail_;
    return true;
  }

  [[nodiscard]] std::uint64_t dropped() const noexcept { return dropped_.load(std::memory_order_relaxed); }

 private:
  struct Cell {
    std::atomic<std::size_t> sequence{0};
    Event event;
  };
  std::array<Cell, Capacity> cells_{};
  alignas(64) std::atomic<std::size_t> head_{0};
  alignas(64) std::size_t tail_ = 0;
  std::atomic<std::uint64_t> dropped_{0};
};

}  // namespace sen3bot::tasks
