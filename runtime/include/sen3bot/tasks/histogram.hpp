#pragma once
// A log-linear histogram of non-negative durations for percentile reporting (jitter p50/p99).
// Fixed storage, single writer, readers on other threads at any time. Each power of two is
// split into 32 sub-buckets, so a reported percentile is within ~3 % of the true value; the
// maximum is tracked exactly.
#include <array>
#include <atomic>
#include <bit>
#include <cstddef>
#include <cstdint>

namespace sen3bot::tasks {

class LatencyHistogram {
 public:
  static constexpr int kSubBucketBits = 5;
  static constexpr std::uint64_t kSubBuckets = 1u << kSubBucketBits;
  static constexpr int kMaxExponent = 44;  // 2^44 ns ~ 4.9 h: longer values saturate
  static constexpr std::size_t kBucketCount = (kMaxExponent - kSubBucketBits + 2) * kSubBuckets;

  // Single writer.
  void record(std::int64_t value_ns) noexcept {
    const std::uint64_t v = value_ns < 0 ? 0 : static_cast<std::uint64_t>(value_ns);
    auto& bucket = buckets_[index_of(v)];
    bucket.store(bucket.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
    count_.store(count_.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
    if (v > max_.load(std::memory_order_relaxed)) max_.store(v, std::memory_order_relaxed);
  }

  [[nodiscard]] std::uint64_t count() const noexcept { return count_.load(std::memory_order_relaxed); }
  [[nodiscard]] std::int64_t max_ns() const noexcept {
    return static_cast<std::int64_t>(max_.load(std::memory_order_relaxed));
  }

  // The value below which `fraction` (0..1) of the samples fall, as the midpoint of the
  // bucket that holds that rank (never above the exact maximum). 0 when empty.
  [[nodiscard]] std::int64_t percentile_ns(double fraction) const noexcept {
    const std::uint64_t total = count();
    if (total == 0) return 0;
    if (fraction < 0.0) fraction = 0.0;
    if (fraction > 1.0) fraction = 1.0;
    auto rank = static_cast<std::uint64_t>(fraction * static_cast<double>(total) + 0.5);
    if (rank < 1) rank = 1;
    std::uint64_t seen = 0;
    for (std::size_t i = 0; i < kBucketCount; ++i) {
      seen += buckets_[i].load(std::memory_order_relaxed);
      if (seen >= rank) {
        const std::uint64_t mid = midpoint_of(i);
        const std::uint64_t top = max_.load(std::memory_order_relaxed);
        return static_cast<std::int64_t>(mid < top ? mid : top);
      }
    }
    return max_ns();
  }

  void reset() noexcept {
    for (auto& b : buckets_) b.store(0, std::memory_order_relaxed);
    count_.store(0, std::memory_order_relaxed);
    max_.store(0, std::memory_order_relaxed);
  }

  static constexpr std::size_t index_of(std::uint64_t v) noexcept {
    if (v < kSubBuckets) return static_cast<std::size_t>(v);
    const int exponent = static_cast<int>(std::bit_width(v)) - 1;  // >= kSubBucketBits
    if (exponent > kMaxExponent) return kBucketCount - 1;
    const int shift = exponent - kSubBucketBits;
    const std::uint64_t sub = (v >> shift) & (kSubBuckets - 1);
    return static_cast<std::size_t>((exponent - kSubBucketBits + 1) * kSubBuckets + sub);
  }

  static constexpr std::uint64_t midpoint_of(std::size_t index) noexcept {
    if (index < kSubBuckets) return index;
    const std::size_t group = index / kSubBuckets;  // >= 1
    const std::uint64_t sub = index % kSubBuckets;
    const int shift = static_cast<int>(group) - 1;
    const std::uint64_t lower = (kSubBuckets + sub) << shift;
    return lower + ((std::uint64_t{1} << shift) >> 1);
  }

 private:
  std::array<std::atomic<std::uint32_t>, kBucketCount> buckets_{};
  std::atomic<std::uint64_t> count_{0};
  std::atomic<std::uint64_t> max_{0};
};

}  // namespace sen3bot::tasks
