#include <gtest/gtest.h>

#include <ctime>
#include <functional>
#include <thread>

#include "sen3bot/tasks/scheduler.hpp"

namespace sen3bot::tasks {
namespace {

using hal::micros;
using hal::millis;
using hal::seconds;

// A task whose step runs a test-supplied function; on the simulated clock a step "takes" as
// long as the function advances the clock.
class ScriptedTask final : public Task {
 public:
  explicit ScriptedTask(std::function<void(const StepContext&)> body = {}) : body_(std::move(body)) {}
  Status init(std::pmr::memory_resource&) override { return Status::success(); }
  void step(const StepContext& context) override {
    ++steps;
    last = context;
    if (body_) body_(context);
  }
  std::uint64_t steps = 0;
  StepContext last{};

 private:
  std::function<void(const StepContext&)> body_;
};

TEST(Scheduler, LockstepRunsEveryTaskExactlyAtItsRate) {
  hal::SimClock clock;
  Scheduler scheduler(clock);
  ScriptedTask fast, medium, slow;
  ASSERT_TRUE(scheduler.add({"fast", 1'000, 200, 80, "control"}, fast));
  ASSERT_TRUE(scheduler.add({"medium", 10'000, 2'000, 70, "control"}, medium));
  ASSERT_TRUE(scheduler.add({"slow", 1'000'000, 10'000, 0, "background"}, slow));
  ASSERT_TRUE(scheduler.run_lockstep(clock, seconds(60)));

  EXPECT_EQ(fast.steps, 60'000u);
  EXPECT_EQ(medium.steps, 6'000u);
  EXPECT_EQ(slow.steps, 60u);
  for (std::size_t i = 0; i < scheduler.task_count(); ++i) {
    const TaskStats s = scheduler.stats(i);
    EXPECT_EQ(s.overruns, 0u) << s.name;
    EXPECT_EQ(s.slips, 0u) << s.name;
    EXPECT_EQ(s.skips, 0u) << s.name;
    EXPECT_EQ(s.jitter_max_ns, 0) << s.name;
  }
  EXPECT_EQ(clock.now(), seconds(60));
  // The last release of the fast task is at 59.999 s.
  EXPECT_EQ(fast.last.release_ns, seconds(60) - micros(1'000));
}

TEST(Scheduler, ASimulatedMinuteRunsInWellUnderASecond) {
  hal::SimClock clock;
  Scheduler scheduler(clock);
  ScriptedTask a, b;
  ASSERT_TRUE(scheduler.add({"a", 1'000, 100, 80, "control"}, a));
  ASSERT_TRUE(scheduler.add({"b", 20'000, 100, 50, "io"}, b));
  const auto wall_start = std::chrono::steady_clock::now();
  ASSERT_TRUE(scheduler.run_lockstep(clock, seconds(60)));
  const auto wall = std::chrono::steady_clock::now() - wall_start;
  EXPECT_EQ(a.steps, 60'000u);
  EXPECT_EQ(b.steps, 3'000u);
  // Generous bound (a sanitizer build under qemu is slow); the benchmark reports the real rate.
  EXPECT_LT(std::chrono::duration<double>(wall).count(), 5.0);
}

TEST(Scheduler, OverrunIsCountedWhenAStepExceedsItsBudget) {
  hal::SimClock clock;
  Scheduler scheduler(clock);
  ScriptedTask task([&](const StepContext& c) {
    // Every third run takes 700 us against a 500 us budget; the others take 300 us.
    clock.advance_by(c.cycle % 3 == 0 ? micros(700) : micros(300));
  });
  ASSERT_TRUE(scheduler.add({"worker", 10'000, 500, 50, "control"}, task));
  ASSERT_TRUE(scheduler.run_lockstep(clock, seconds(1)));
  const TaskStats s = scheduler.stats(0);
  EXPECT_EQ(s.runs, 100u);
  EXPECT_EQ(s.overruns, 34u);  // cycles 0, 3, ..., 99
  EXPECT_EQ(s.slips, 0u);
  EXPECT_EQ(s.skips, 0u);
  EXPECT_EQ(s.exec_min_ns, micros(300));
  EXPECT_EQ(s.exec_max_ns, micros(700));
  EXPECT_EQ(s.exec_mean_ns, (34 * micros(700) + 66 * micros(300)) / 100);
}

// Keeps the CPU busy for `ns` of process CPU time. It reads std::clock rather than the HAL's
// thread clock so the measurement under test is checked against an independent one.
void burn_cpu(hal::Nanos ns) {
  const std::clock_t start = std::clock();
  const auto ticks = static_cast<std::clock_t>(static_cast<double>(ns) * 1e-9 * CLOCKS_PER_SEC);
  volatile std::uint64_t sink = 0;
  while (std::clock() - start < ticks) sink = sink + 1;
}

TEST(Scheduler, LockstepMeasuresTheCpuTimeOfEachStep) {
  hal::SimClock clock;
  Scheduler scheduler(clock);
  ScriptedTask burner([](const StepContext&) { burn_cpu(millis(2)); });
  ScriptedTask idle;
  ASSERT_TRUE(scheduler.add({"burner", 10'000, 5'000, 50, "control"}, burner));
  ASSERT_TRUE(scheduler.add({"idle", 10'000, 5'000, 40, "control"}, idle));
  ASSERT_TRUE(scheduler.run_lockstep(clock, millis(200)));

  const TaskStats b = scheduler.stats(0);
  EXPECT_EQ(b.runs, 20u);
  // The simulated clock stood still: only the CPU time shows the work. Bounds are loose (other
  // threads of a sanitizer runtime share the process clock) but far from zero.
  EXPECT_EQ(b.exec_max_ns, 0);
  EXPECT_GE(b.cpu_min_ns, millis(1));
  EXPECT_GE(b.cpu_mean_ns, micros(1'500));
  EXPECT_LE(b.cpu_mean_ns, millis(10));
  EXPECT_LE(b.cpu_min_ns, b.cpu_mean_ns);
  EXPECT_LE(b.cpu_mean_ns, b.cpu_max_ns);
  EXPECT_EQ(b.cpu_overruns, 0u);

  const TaskStats i = scheduler.stats(1);
  EXPECT_EQ(i.runs, 20u);
  EXPECT_LT(i.cpu_mean_ns, micros(200));
  EXPECT_EQ(i.cpu_overruns, 0u);
}

TEST(Scheduler, LockstepCountsCpuOverrunsThatTheSimulatedClockCannotShow) {
  hal::SimClock clock;
  Scheduler scheduler(clock);
  // Every other run burns 3 ms of CPU against a 1 ms budget; the others do nothing.
  ScriptedTask task([](const StepContext& c) {
    if (c.cycle % 2 == 0) burn_cpu(millis(3));
  });
  ASSERT_TRUE(scheduler.add({"worker", 10'000, 1'000, 50, "control"}, task));
  ASSERT_TRUE(scheduler.run_lockstep(clock, millis(100)));
  const TaskStats s = scheduler.stats(0);
  EXPECT_EQ(s.runs, 10u);
  EXPECT_EQ(s.cpu_overruns, 5u);  // cycles 0, 2, 4, 6, 8
  EXPECT_EQ(s.overruns, 0u);      // on the simulated clock every step took no time
  EXPECT_EQ(s.slips, 0u);
  EXPECT_EQ(s.skips, 0u);
  EXPECT_GT(s.cpu_max_ns, millis(1));
}

TEST(Scheduler, ALongStepSkipsTheMissedReleasesAndRephasesWithoutBursting) {
  hal::SimClock clock;
  Scheduler scheduler(clock);
  std::vector<hal::Nanos> starts;
  starts.reserve(200);
  ScriptedTask task([&](const StepContext& c) {
    starts.push_back(c.start_ns);
    if (c.cycle == 5) clock.advance_by(millis(25));  // released at 50 ms, ends at 75 ms
  });
  ASSERT_TRUE(scheduler.add({"worker", 10'000, 5'000, 50, "control"}, task));
  ASSERT_TRUE(scheduler.run_lockstep(clock, seconds(1)));
  const TaskStats s = scheduler.stats(0);
  EXPECT_EQ(s.skips, 2u);  // the releases at 60 and 70 ms
  EXPECT_EQ(s.runs, 98u);
  EXPECT_EQ(s.overruns, 1u);
  EXPECT_EQ(s.slips, 0u);  // it started on time; it just ran long
  // After the long run the next start is on the original 10 ms grid, not immediately.
  ASSERT_GT(starts.size(), 7u);
  EXPECT_EQ(starts[5], millis(50));
  EXPECT_EQ(starts[6], millis(80));
  EXPECT_EQ(starts[7], millis(90));
}

TEST(Scheduler, ATaskDelayedByAHigherPriorityOneSlipsAndIsRephased) {
  hal::SimClock clock;
  Scheduler scheduler(clock);
  ScriptedTask blocker([&](const StepContext& c) {
    if (c.cycle == 1) clock.advance_by(millis(35));  // the run released at 100 ms
  });
  ScriptedTask victim;
  ASSERT_TRUE(scheduler.add({"victim", 10'000, 1'000, 10, "control"}, victim));
  ASSERT_TRUE(scheduler.add({"blocker", 100'000, 50'000, 50, "control"}, blocker));
  ASSERT_TRUE(scheduler.run_lockstep(clock, seconds(1)));
  const TaskStats v = scheduler.stats(0);
  // Released at 100 ms, started at 135 ms: one slip; 110, 120, 130 were missed.
  EXPECT_EQ(v.slips, 1u);
  EXPECT_EQ(v.skips, 3u);
  EXPECT_EQ(v.runs, 97u);
  EXPECT_EQ(v.jitter_max_ns, millis(35));
  EXPECT_EQ(v.jitter_p50_ns, 0);
  const TaskStats b = scheduler.stats(1);
  EXPECT_EQ(b.runs, 10u);
  EXPECT_EQ(b.overruns, 0u);  // 35 ms is inside its 50 ms budget
}

TEST(Scheduler, HigherPriorityRunsFirstWhenReleasedTogether) {
  hal::SimClock clock;
  Scheduler scheduler(clock);
  std::vector<int> order;
  order.reserve(16);
  ScriptedTask low([&](const StepContext&) { order.push_back(1); });
  ScriptedTask high([&](const StepContext&) { order.push_back(2); });
  ASSERT_TRUE(scheduler.add({"low", 10'000, 100, 10, "control"}, low));
  ASSERT_TRUE(scheduler.add({"high", 10'000, 100, 90, "control"}, high));
  ASSERT_TRUE(scheduler.run_lockstep(clock, millis(20)));
  EXPECT_EQ(order, (std::vector<int>{2, 1, 2, 1}));
}

TEST(Scheduler, RejectsBadSpecifications) {
  hal::SimClock clock;
  Scheduler scheduler(clock);
  ScriptedTask t;
  EXPECT_EQ(scheduler.add({"zero", 0, 1, 1, "control"}, t).error().code(), Errc::invalid_argument);
  EXPECT_EQ(scheduler.add({"over", 1'000, 2'000, 1, "control"}, t).error().code(), Errc::invalid_argument);
  EXPECT_EQ(scheduler.add({"prio", 1'000, 100, 120, "control"}, t).error().code(), Errc::invalid_argument);
  EXPECT_EQ(scheduler.add({"", 1'000, 100, 1, "control"}, t).error().code(), Errc::invalid_argument);
  ASSERT_TRUE(scheduler.add({"ok", 1'000, 100, 1, "control"}, t));
  const Status dup = scheduler.add({"ok", 1'000, 100, 1, "control"}, t);
  ASSERT_FALSE(dup);
  EXPECT_NE(dup.error().message().find("duplicate task name 'ok'"), std::string_view::npos);
  const Status budget = scheduler.add({"big", 1'000, 5'000, 1, "control"}, t);
  EXPECT_NE(budget.error().message().find("budget 5000 us"), std::string_view::npos);
}

TEST(Scheduler, RefusesARealTimeStartOnASimulatedClock) {
  hal::SimClock clock;
  Scheduler scheduler(clock);
  ScriptedTask t;
  ASSERT_TRUE(scheduler.add({"t", 1'000, 100, 1, "control"}, t));
  EXPECT_FALSE(scheduler.start());
}

TEST(Scheduler, StatisticsAreReadableWhileRunning) {
  hal::SimClock clock;
  Scheduler scheduler(clock);
  std::uint64_t seen_runs = 0;
  ScriptedTask worker;
  ScriptedTask observer([&](const StepContext&) { seen_runs = scheduler.stats(0).runs; });
  ASSERT_TRUE(scheduler.add({"worker", 1'000, 100, 80, "control"}, worker));
  ASSERT_TRUE(scheduler.add({"observer", 100'000, 1'000, 10, "background"}, observer));
  ASSERT_TRUE(scheduler.run_lockstep(clock, seconds(1)));
  // The observer's last run (at 900 ms) saw the worker's 901 runs (0..900 ms inclusive).
  EXPECT_EQ(seen_runs, 901u);
}

TEST(Scheduler, RealTimeThreadsKeepTheirRateAndNeverBurst) {
  hal::PosixClock clock;
  Scheduler scheduler(clock);
  ScriptedTask fast, slow;
  ASSERT_TRUE(scheduler.add({"fast", 2'000, 1'000, 10, "control"}, fast));
  ASSERT_TRUE(scheduler.add({"slow", 50'000, 10'000, 0, "background"}, slow));
  ASSERT_TRUE(scheduler.configure_thread({"control", -1, true, 16 * 1024}));
  ASSERT_TRUE(scheduler.start());
  std::uint64_t observed = 0;
  for (int i = 0; i < 5; ++i) {  // readable from another thread while running
    std::this_thread::sleep_for(std::chrono::milliseconds(60));
    observed = std::max(observed, scheduler.stats(0).runs);
  }
  const hal::Nanos started = scheduler.start_time_ns();
  scheduler.request_stop();
  scheduler.join();
  const hal::Nanos elapsed = clock.now() - started;
  const TaskStats f = scheduler.stats(0);
  EXPECT_GT(observed, 0u);
  // Releases are on a fixed grid: never more runs than releases that fell in the interval,
  // however late the machine was (the counts of a loaded machine show up as skips instead).
  EXPECT_LE(f.runs, static_cast<std::uint64_t>(elapsed / micros(2'000)) + 1);
  EXPECT_GE(f.runs, 1u);
  // Every release up to the stop is either run or counted as skipped, never both.
  EXPECT_LE(f.runs + f.skips, static_cast<std::uint64_t>(elapsed / micros(2'000)) + 2);
  EXPECT_GE(scheduler.stats(1).runs, 1u);
  // CPU time is read inside the wall-clock interval of each step, so it cannot exceed it.
  EXPECT_LE(f.cpu_max_ns, f.exec_max_ns + micros(50));
}

}  // namespace
}  // namespace sen3bot::tasks
