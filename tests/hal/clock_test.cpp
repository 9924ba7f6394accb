// The thread CPU-time reading: it advances while the thread computes and stands still while the
// thread sleeps, which is what makes it usable as a step's cost when the wall clock is simulated.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdint>
#include <thread>

#include "sen3bot/hal/clock.hpp"

namespace sen3bot::hal {
namespace {

TEST(ThreadCpuTime, AdvancesWhileSpinningAndNotWhileSleeping) {
  const Nanos spin_start = thread_cpu_time_ns();
  const auto wall_start = std::chrono::steady_clock::now();
  // Spin on the wall clock so the expectation does not come from the clock under test.
  volatile std::uint64_t sink = 0;
  while (std::chrono::steady_clock::now() - wall_start < std::chrono::milliseconds(20)) sink = sink + 1;
  const Nanos spun = thread_cpu_time_ns() - spin_start;
  // A loaded machine may preempt the spin, so only a fraction of the 20 ms is certain.
  EXPECT_GT(spun, millis(1));
  EXPECT_LE(spun, millis(20) + millis(1));

  const Nanos sleep_start = thread_cpu_time_ns();
  std::this_thread::sleep_for(std::chrono::milliseconds(50));
  EXPECT_LT(thread_cpu_time_ns() - sleep_start, millis(5));
}

TEST(ThreadCpuTime, CountsOnlyTheCallingThread) {
  const Nanos before = thread_cpu_time_ns();
  std::thread busy([] {
    const Nanos start = thread_cpu_time_ns();
    volatile std::uint64_t sink = 0;
    while (thread_cpu_time_ns() - start < millis(30)) sink = sink + 1;
  });
  busy.join();
  // This thread only waited for the other one.
  EXPECT_LT(thread_cpu_time_ns() - before, millis(10));
}

}  // namespace
}  // namespace sen3bot::hal
