#pragma once
// The message bus is a fixed set of topics, each carrying one fixed-size, trivially copyable
// struct. A Topic keeps the latest sample: one writer publishes, any number of readers on any
// thread read without locks (a sequence lock over atomic words, so it is race-free by the
// C++ memory model, not only in practice). Readers detect stale data from the stamp.
#include <array>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <type_traits>

#include "sen3bot/hal/clock.hpp"

namespace sen3bot::tasks {

template <typename T>
struct Sample {
  T value{};
  hal::Nanos stamp_ns = 0;   // when the writer published it
  std::uint64_t sequence = 0;  // 0: never published; then 1, 2, ... per publish
};

template <typename T>
class Topic {
  static_assert(std::is_trivially_copyable_v<T>,
                "bus messages cross thread boundaries by copy: no pointers to heap, no std::vector");

 public:
  Topic() = default;
  // The name the data-flow graph shows (firmware/topics.hpp names each).
  explicit constexpr Topic(const char* name) noexcept : name_(name) {}
  [[nodiscard]] const char* name() const noexcept { return name_; }

  // Single writer.
  void publish(const T& value, hal::Nanos stamp_ns) noexcept {
    const std::uint64_t seq = seq_.load(std::memory_order_relaxed);
    seq_.store(seq + 1, std::memory_order_relaxed);  // odd: write in progress
    std::atomic_thread_fence(std::memory_order_release);
    std::array<std::uint64_t, kWords> words{};
    std::memcpy(words.data(), &value, sizeof(T));
    words[kValueWords] = static_cast<std::uint64_t>(stamp_ns);
    words[kValueWords + 1] = seq / 2 + 1;
    for (std::size_t i = 0; i < kWords; ++i) words_[i].store(words[i], std::memory_order_relaxed);
    seq_.store(seq + 2, std::memory_order_release);
  }

  // Copies the latest sample. Returns false if nothing was published yet or a writer kept
  // the data busy for every attempt (the writer is periodic, so a retry soon succeeds).
  bool read(Sample<T>& out) const noexcept {
    for (int attempt = 0; attempt < kMaxAttempts; ++attempt) {
      const std::uint64_t before = seq_.load(std::memory_order_acquire);
      if (before == 0) return false;
      if (before & 1u) continue;
      std::array<std::uint64_t, kWords> words;
      for (std::size_t i = 0; i < kWords; ++i) words[i] = words_[i].load(std::memory_order_relaxed);
      std::atomic_thread_fence(std::memory_order_acquire);
      if (seq_.load(std::memory_order_relaxed) != before) continue;
      // T is trivially copyable (asserted above); the cast silences -Wclass-memaccess for
      // types whose default constructor is not trivial.
      std::memcpy(static_cast<void*>(&out.value), words.data(), sizeof(T));
      out.stamp_ns = static_cast<hal::Nanos>(words[kValueWords]);
      out.sequence = words[kValueWords + 1];
      return true;
    }
    return false;
  }

  [[nodiscard]] std::uint64_t published() const noexcept { return seq_.load(std::memory_order_acquire) / 2; }

 private:
  // Layout over the words: the value, then the stamp, then the publish count.
  static constexpr std::size_t kValueWords = (sizeof(T) + 7) / 8;
  static constexpr std::size_t kWords = kValueWords + 2;
  static constexpr int kMaxAttempts = 64;

  const char* name_ = "";
  std::atomic<std::uint64_t> seq_{0};
  std::array<std::atomic<std::uint64_t>, kWords> words_{};
};

}  // namespace sen3bot::tasks
