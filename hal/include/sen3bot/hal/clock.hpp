#pragma once
// Monotonic time for the whole firmware. Everything periodic sleeps to absolute deadlines.
#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdint>

namespace sen3bot::hal {

// Nanoseconds on a monotonic time line whose origin is unspecified (CLOCK_MONOTONIC on
// POSIX, zero at construction for the simulated clock). Signed so differences are natural.
using Nanos = std::int64_t;

constexpr Nanos kNanosPerMicro = 1'000;
constexpr Nanos kNanosPerMilli = 1'000'000;
constexpr Nanos kNanosPerSecond = 1'000'000'000;

constexpr Nanos micros(std::int64_t us) { return us * kNanosPerMicro; }
constexpr Nanos millis(std::int64_t ms) { return ms * kNanosPerMilli; }
constexpr Nanos seconds(std::int64_t s) { return s * kNanosPerSecond; }
constexpr double to_seconds(Nanos ns) { return static_cast<double>(ns) * 1e-9; }
// A duration in seconds from a configuration, rounded to the nearest nanosecond.
inline Nanos from_seconds(double s) noexcept { return static_cast<Nanos>(std::llround(s * 1e9)); }

// CPU time consumed so far by the calling thread (CLOCK_THREAD_CPUTIME_ID on POSIX). Unlike a
// Clock it counts only time this thread spent running, so the difference around a call is the
// work that call did: in lockstep, where the simulated clock stands still during a step, it is
// the only measure of a step's cost, and in real time it leaves out preemption and sleeps.
[[nodiscard]] Nanos thread_cpu_time_ns() noexcept;

class Clock {
 public:
  virtual ~Clock() = default;
  [[nodiscard]] virtual Nanos now() const = 0;
  // Blocks until now() >= deadline_ns. Returns immediately for a deadline in the past.
  virtual void sleep_until(Nanos deadline_ns) = 0;
  // True for a clock that only moves when told to (lockstep simulation).
  [[nodiscard]] virtual bool simulated() const { return false; }
  // The wall clock (Unix ns) at this moment: what timestamps from other computers are in.
  [[nodiscard]] virtual std::int64_t unix_now_ns() const = 0;
};

// CLOCK_MONOTONIC, sleeping with clock_nanosleep(TIMER_ABSTIME) so that periodic loops
// never accumulate drift from the time spent computing the next deadline.
class PosixClock final : public Clock {
 public:
  [[nodiscard]] Nanos now() const override;
  [[nodiscard]] std::int64_t unix_now_ns() const override;  // CLOCK_REALTIME
  void sleep_until(Nanos deadline_ns) override;
};

// A clock that only moves when advanced. sleep_until() jumps forward to the deadline, so a
// single-threaded lockstep loop runs simulated time as fast as the CPU allows.
class SimClock final : public Clock {
 public:
  explicit SimClock(Nanos start_ns = 0) : now_ns_(start_ns) {}

  [[nodiscard]] Nanos now() const override { return now_ns_.load(std::memory_order_acquire); }
  // Simulated time counts from a fixed wall-clock instant, so runs are reproducible.
  static constexpr std::int64_t kEpochUnixNs = 1'767'225'600'000'000'000;  // 2026-01-01 00:00 UTC
  [[nodiscard]] std::int64_t unix_now_ns() const override { return kEpochUnixNs + now(); }
  void sleep_until(Nanos deadline_ns) override { advance_to(deadline_ns); }
  [[nodiscard]] bool simulated() const override { return true; }

  // Whatever lives on its own grid of simulated instants (a simulated world that steps every
  // few milliseconds) is told before time moves, so it can catch up to `to_ns` first. Called
  // on the advancing thread, also when time stays where it is.
  class Listener {
   public:
    virtual ~Listener() = default;
    virtual void before_advance(Nanos now_ns, Nanos to_ns) = 0;
  };
  void set_listener(Listener* listener) noexcept { listener_ = listener; }

  // Time never goes backwards: advancing to the past is a no-op.
  void advance_to(Nanos t_ns) {
    Nanos current = now_ns_.load(std::memory_order_relaxed);
    if (listener_ != nullptr && t_ns >= current) listener_->before_advance(current, t_ns);
    while (t_ns > current &&
           !now_ns_.compare_exchange_weak(current, t_ns, std::memory_order_acq_rel)) {
    }
  }
  void advance_by(Nanos dt_ns) { advance_to(now() + (dt_ns > 0 ? dt_ns : 0)); }

 private:
  std::atomic<Nanos> now_ns_;
  Listener* listener_ = nullptr;
};

}  // namespace sen3bot::hal
