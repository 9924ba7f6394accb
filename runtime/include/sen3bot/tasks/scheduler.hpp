#pragma once
// Fixed-rate task scheduler. Tasks are grouped onto threads; each thread releases its tasks on
// absolute deadlines (release_k = start + k * period) and runs the due ones in descending
// priority. A task that starts a period or more late counts a slip; the releases it missed
// are counted as skips and dropped (the task is re-phased onto its original grid, never run
// in a burst to catch up). Each step's cost is measured twice: on the scheduler's clock and
// as the CPU time of the running thread; the latter is the only one a lockstep run can show,
// because the simulated clock stands still during a step. The same code runs in real time (one OS thread per group,
// clock_nanosleep) and in lockstep on a SimClock (all groups on the calling thread).
#include <array>
#include <atomic>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string_view>
#include <thread>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/tasks/histogram.hpp"
#include "sen3bot/tasks/task.hpp"

namespace sen3bot::tasks {

struct TaskSpec {
  std::string_view name;
  std::int64_t period_us = 0;
  // Execution time above this counts an overrun, CPU time above it a CPU overrun.
  std::int64_t budget_us = 0;
  // 1..99 on the SCHED_FIFO scale, 0 for a task that needs no real-time priority. Within a
  // thread, due tasks run highest first; a thread runs at the highest priority of its tasks.
  int priority = 0;
  std::string_view thread;
};

// Live statistics of one task. Written only by the thread that runs the task; readable from
// any thread at any time (relaxed atomics: each field is individually consistent).
struct TaskCounters {
  std::atomic<std::uint64_t> runs{0};
  std::atomic<std::uint64_t> overruns{0};      // execution time (scheduler's clock) > budget
  std::atomic<std::uint64_t> cpu_overruns{0};  // CPU time of the step > budget
  std::atomic<std::uint64_t> slips{0};         // started >= one period after its release
  std::atomic<std::uint64_t> skips{0};         // releases dropped while the task was late
  // Execution time on the scheduler's clock: wall time in real time, the simulated cost (what
  // the step advanced the clock by) in lockstep.
  std::atomic<std::int64_t> exec_min_ns{0};
  std::atomic<std::int64_t> exec_max_ns{0};
  std::atomic<std::int64_t> exec_total_ns{0};
  // CPU time the running thread spent in the step (hal::thread_cpu_time_ns), in both modes.
  std::atomic<std::int64_t> cpu_min_ns{0};
  std::atomic<std::int64_t> cpu_max_ns{0};
  std::atomic<std::int64_t> cpu_total_ns{0};
  std::atomic<std::int64_t> last_start_ns{0};
  LatencyHistogram release_jitter;  // start - release
};

// A plain copy of the counters for printing and checks.
struct TaskStats {
  std::string_view name;
  std::string_view thread;
  std::int64_t period_us = 0;
  std::int64_t budget_us = 0;
  int priority = 0;
  std::uint64_t runs = 0;
  std::uint64_t overruns = 0;
  std::uint64_t cpu_overruns = 0;
  std::uint64_t slips = 0;
  std::uint64_t skips = 0;
  std::int64_t exec_min_ns = 0;
  std::int64_t exec_mean_ns = 0;
  std::int64_t exec_max_ns = 0;
  std::int64_t cpu_min_ns = 0;
  std::int64_t cpu_mean_ns = 0;
  std::int64_t cpu_max_ns = 0;
  std::int64_t jitter_p50_ns = 0;
  std::int64_t jitter_p99_ns = 0;
  std::int64_t jitter_max_ns = 0;
  std::int64_t last_start_ns = 0;
};

// What a real-time thread asks of the OS; each request is tried and its outcome kept.
struct ThreadOptions {
  std::string_view name;
  int cpu = -1;                       // -1: no affinity
  bool realtime = true;               // request SCHED_FIFO at the group's priority
  std::size_t prefault_stack_bytes = 64 * 1024;
};

class Scheduler {
 public:
  static constexpr std::size_t kMaxTasks = 32;
  static constexpr std::size_t kMaxThreads = 8;
  static constexpr std::size_t kMaxWarnings = 3 * kMaxThreads;

  explicit Scheduler(hal::Clock& clock) : clock_(clock) {}
  ~Scheduler();
  Scheduler(const Scheduler&) = delete;
  Scheduler& operator=(const Scheduler&) = delete;

  // Before start. Rejects bad specs (period <= 0, budget > period, duplicate names, too many).
  Status add(const TaskSpec& spec, Task& task);
  // Options for a named thread; a thread without options gets the defaults.
  Status configure_thread(const ThreadOptions& options);

  // Runs every group on the calling thread on a simulated clock for `duration_ns` of simulated
  // time. May be called again to continue (e.g. warm up, then measure).
  Status run_lockstep(hal::SimClock& clock, hal::Nanos duration_ns);

  // Starts one OS thread per group. Real-time requests that the OS refuses are recorded as
  // warnings (see warnings()) and the thread carries on at normal priority.
  Status start();
  void request_stop() noexcept { stop_.store(true, std::memory_order_release); }
  void join();
  [[nodiscard]] bool running() const noexcept { return running_; }

  [[nodiscard]] std::size_t task_count() const noexcept { return task_count_; }
  [[nodiscard]] TaskStats stats(std::size_t index) const;
  [[nodiscard]] const TaskCounters& counters(std::size_t index) const { return slots_[index].counters; }
  [[nodiscard]] const TaskSpec& spec(std::size_t index) const { return slots_[index].spec; }
  [[nodiscard]] const Task& task(std::size_t index) const { return *slots_[index].task; }
  // The table index of a task added to this scheduler, or task_count() if it was not added.
  [[nodiscard]] std::size_t index_of(const Task& task) const noexcept {
    for (std::size_t i = 0; i < task_count_; ++i)
      if (slots_[i].task == &task) return i;
    return task_count_;
  }
  [[nodiscard]] hal::Nanos start_time_ns() const noexcept { return start_ns_.load(std::memory_order_acquire); }

  [[nodiscard]] std::size_t warning_count() const noexcept { return warning_count_.load(std::memory_order_acquire); }
  [[nodiscard]] const Error& warning(std::size_t i) const { return warnings_[i]; }

  // A fixed-width table of every task's statistics.
  void print_stats(std::FILE* out) const;

 private:
  struct Slot {
    TaskSpec spec;
    Task* task = nullptr;
    std::size_t group = 0;
    hal::Nanos period_ns = 0;
    hal::Nanos budget_ns = 0;
    hal::Nanos next_release_ns = 0;
    TaskCounters counters;
  };
  struct Group {
    ThreadOptions options;
    int priority = 0;
    std::array<std::size_t, kMaxTasks> order{};  // slot indices, highest priority first
    std::size_t size = 0;
    std::thread thread;
  };

  Status prepare(hal::Nanos start_ns);
  [[nodiscard]] hal::Nanos next_release(const Group& group) const;
  void run_due(Group& group);
  void run_slot(Slot& slot);
  void thread_main(std::size_t group_index);
  void warn(const Error& error);
  std::size_t group_for(std::string_view thread_name);

  hal::Clock& clock_;
  std::array<Slot, kMaxTasks> slots_{};
  std::size_t task_count_ = 0;
  std::array<Group, kMaxThreads> groups_{};
  std::size_t group_count_ = 0;
  std::atomic<bool> stop_{false};
  std::atomic<hal::Nanos> start_ns_{0};
  bool running_ = false;
  bool prepared_ = false;
  std::array<Error, kMaxWarnings> warnings_{};
  std::atomic<std::size_t> warning_count_{0};
};

}  // namespace sen3bot::tasks
