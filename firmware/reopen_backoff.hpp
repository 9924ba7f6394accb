#pragma once
// When to try opening a device again after it was absent or went away: the first retry after
// `first_ms`, each later one twice as long up to `max_ms`, back to `first_ms` once it opens.
// A missing device costs a few open() calls a minute, not one per cycle.
#include <algorithm>
#include <cstdint>

#include "sen3bot/hal/clock.hpp"

namespace sen3bot::firmware {

class ReopenBackoff {
 public:
  static constexpr std::int64_t kDefaultMaxMs = 5000;

  explicit ReopenBackoff(std::int64_t first_ms, std::int64_t max_ms = kDefaultMaxMs)
      : first_ms_(std::max<std::int64_t>(1, first_ms)), max_ms_(std::max(first_ms_, max_ms)), delay_ms_(first_ms_) {}

  [[nodiscard]] bool due(hal::Nanos now_ns) const noexcept { return now_ns >= next_ns_; }
  // An attempt failed at now_ns: the next one waits the current delay, which then doubles.
  void failed(hal::Nanos now_ns) noexcept {
    next_ns_ = now_ns + hal::millis(delay_ms_);
    delay_ms_ = std::min(delay_ms_ * 2, max_ms_);
  }
  void succeeded() noexcept {
    delay_ms_ = first_ms_;
    next_ns_ = 0;
  }
  [[nodiscard]] hal::Nanos next_attempt_ns() const noexcept { return next_ns_; }

 private:
  std::int64_t first_ms_;
  std::int64_t max_ms_;
  std::int64_t delay_ms_;
  hal::Nanos next_ns_ = 0;
};

}  // namespace sen3bot::firmware
