#include <cerrno>
#include <ctime>

#include "sen3bot/hal/clock.hpp"

namespace sen3bot::hal {

namespace {
timespec to_timespec(Nanos t_ns) {
  timespec ts{};
  ts.tv_sec = static_cast<time_t>(t_ns / kNanosPerSecond);
  ts.tv_nsec = static_cast<long>(t_ns % kNanosPerSecond);
  return ts;
}
}  // namespace

Nanos PosixClock::now() const {
  timespec ts{};
  clock_gettime(CLOCK_MONOTONIC, &ts);
  return static_cast<Nanos>(ts.tv_sec) * kNanosPerSecond + ts.tv_nsec;
}

std::int64_t PosixClock::unix_now_ns() const {
  timespec ts{};
  clock_gettime(CLOCK_REALTIME, &ts);
  return static_cast<std::int64_t>(ts.tv_sec) * kNanosPerSecond + ts.tv_nsec;
}

Nanos thread_cpu_time_ns() noexcept {
  timespec ts{};
  clock_gettime(CLOCK_THREAD_CPUTIME_ID, &ts);
  return static_cast<Nanos>(ts.tv_sec) * kNanosPerSecond + ts.tv_nsec;
}

void PosixClock::sleep_until(Nanos deadline_ns) {
  const timespec deadline = to_timespec(deadline_ns);
  // Absolute deadline: a signal interrupting the sleep just resumes towards the same instant.
  while (clock_nanosleep(CLOCK_MONOTONIC, TIMER_ABSTIME, &deadline, nullptr) == EINTR) {
  }
}

}  // namespace sen3bot::hal
