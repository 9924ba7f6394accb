#include "sen3bot/tasks/scheduler.hpp"

#include <algorithm>
#include <cinttypes>
#include <mutex>

#include "sen3bot/hal/rt_setup.hpp"

namespace sen3bot::tasks {

namespace {
// A real-time thread wakes at least this often so that a stop request is seen promptly even
// when its next release is far away (a 1 Hz background task).
constexpr hal::Nanos kStopPollInterval_ns = hal::millis(50);
// Real-time threads are created, pinned, raised and their stacks prefaulted before the first
// release, so start-up is not counted as release jitter.
constexpr hal::Nanos kStartupPhase_ns = hal::millis(20);

std::mutex& warnings_mutex() {
  static std::mutex m;
  return m;
}
}  // namespace

Scheduler::~Scheduler() {
  request_stop();
  join();
}

std::size_t Scheduler::group_for(std::string_view thread_name) {
  for (std::size_t g = 0; g < group_count_; ++g)
    if (groups_[g].options.name == thread_name) return g;
  if (group_count_ == kMaxThreads) return kMaxThreads;
  groups_[group_count_].options.name = thread_name;
  return group_count_++;
}

Status Scheduler::add(const TaskSpec& spec, Task& task) {
  if (running_ || prepared_) return Error(Errc::invalid_argument, "scheduler: tasks must be added before it starts");
  const int name_len = static_cast<int>(spec.name.size());
  if (spec.name.empty() || spec.thread.empty())
    return Error(Errc::invalid_argument, "scheduler: a task needs a name and a thread");
  if (task_count_ == kMaxTasks)
    return Error::format(Errc::capacity, "scheduler: task '%.*s': the table holds at most %zu tasks", name_len,
                         spec.name.data(), kMaxTasks);
  if (spec.period_us <= 0)
    return Error::format(Errc::invalid_argument, "scheduler: task '%.*s': period must be positive, got %" PRId64 " us",
                         name_len, spec.name.data(), spec.period_us);
  if (spec.budget_us <= 0 || spec.budget_us > spec.period_us)
    return Error::format(Errc::invalid_argument,
                         "scheduler: task '%.*s': budget %" PRId64 " us must be in (0, period %" PRId64 " us]",
                         name_len, spec.name.data(), spec.budget_us, spec.period_us);
  if (spec.priority < 0 || spec.priority > 99)
    return Error::format(Errc::invalid_argument, "scheduler: task '%.*s': priority %d is outside 0..99", name_len,
                         spec.name.data(), spec.priority);
  for (std::size_t i = 0; i < task_count_; ++i)
    if (slots_[i].spec.name == spec.name)
      return Error::format(Errc::invalid_argument, "scheduler: duplicate task name '%.*s'", name_len, spec.name.data());
  const std::size_t g = group_for(spec.thread);
  if (g == kMaxThreads)
    return Error::format(Errc::capacity, "scheduler: task '%.*s': at most %zu threads", name_len, spec.name.data(),
                         kMaxThreads);

  Slot& slot = slots_[task_count_];
  slot.spec = spec;
  slot.task = &task;
  slot.group = g;
  slot.period_ns = hal::micros(spec.period_us);
  slot.budget_ns = hal::micros(spec.budget_us);

  // Keep the group's run order sorted by descending priority; ties keep table order.
  Group& group = groups_[g];
  std::size_t pos = group.size;
  while (pos > 0 && slots_[group.order[pos - 1]].spec.priority < spec.priority) {
    group.order[pos] = group.order[pos - 1];
    --pos;
  }
  group.order[pos] = task_count_;
  ++group.size;
  group.priority = std::max(group.priority, spec.priority);
  ++task_count_;
  return Status::success();
}

Status Scheduler::configure_thread(const ThreadOptions& options) {
  if (running_) return Error(Errc::invalid_argument, "scheduler: threads must be configured before it starts");
  const std::size_t g = group_for(options.name);
  if (g == kMaxThreads)
    return Error::format(Errc::capacity, "scheduler: at most %zu threads", kMaxThreads);
  groups_[g].options = options;
  return Status::success();
}

Status Scheduler::prepare(hal::Nanos start_ns) {
  if (prepared_) return Error(Errc::invalid_argument, "scheduler: already started once");
  if (task_count_ == 0) return Error(Errc::invalid_argument, "scheduler: no tasks");
  for (std::size_t i = 0; i < task_count_; ++i) slots_[i].next_release_ns = start_ns;
  start_ns_.store(start_ns, std::memory_order_release);
  stop_.store(false, std::memory_order_release);
  prepared_ = true;
  return Status::success();
}

hal::Nanos Scheduler::next_release(const Group& group) const {
  hal::Nanos earliest = INT64_MAX;
  for (std::size_t k = 0; k < group.size; ++k)
    earliest = std::min(earliest, slots_[group.order[k]].next_release_ns);
  return earliest;
}

void Scheduler::run_due(Group& group) {
  for (std::size_t k = 0; k < group.size; ++k) {
    Slot& slot = slots_[group.order[k]];
    // Re-read the clock per task: a task released while a higher one ran still runs now.
    if (slot.next_release_ns <= clock_.now()) run_slot(slot);
  }
}

void Scheduler::run_slot(Slot& slot) {
  TaskCounters& c = slot.counters;
  const hal::Nanos release = slot.next_release_ns;
  const hal::Nanos start = clock_.now();
  const hal::Nanos lateness = start - release;
  const std::uint64_t runs = c.runs.load(std::memory_order_relaxed);

  // Read inside the clock readings, so in real time a step's CPU time never exceeds its exec.
  const hal::Nanos cpu_start = hal::thread_cpu_time_ns();

  slot.task->step(StepContext{release, start, runs});

  const hal::Nanos cpu = hal::thread_cpu_time_ns() - cpu_start;
  const hal::Nanos end = clock_.now();
  const hal::Nanos exec = end - start;

  c.release_jitter.record(lateness);
  if (lateness >= slot.period_ns) c.slips.store(c.slips.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
  // One writer per counter (this thread): plain load-then-store is enough.
  auto record = [&](hal::Nanos t, std::atomic<std::uint64_t>& over, std::atomic<std::int64_t>& min,
                    std::atomic<std::int64_t>& max, std::atomic<std::int64_t>& total) {
    if (t > slot.budget_ns) over.store(over.load(std::memory_order_relaxed) + 1, std::memory_order_relaxed);
    if (runs == 0 || t < min.load(std::memory_order_relaxed)) min.store(t, std::memory_order_relaxed);
    if (t > max.load(std::memory_order_relaxed)) max.store(t, std::memory_order_relaxed);
    total.store(total.load(std::memory_order_relaxed) + t, std::memory_order_relaxed);
  };
  record(exec, c.overruns, c.exec_min_ns, c.exec_max_ns, c.exec_total_ns);
  record(cpu, c.cpu_overruns, c.cpu_min_ns, c.cpu_max_ns, c.cpu_total_ns);
  c.last_start_ns.store(start, std::memory_order_relaxed);
  c.runs.store(runs + 1, std::memory_order_release);

  // Next release on the original grid. Releases that already passed are dropped and counted,
  // so a late task runs once, not in a burst.
  hal::Nanos next = release + slot.period_ns;
  if (end >= next) {
    const hal::Nanos missed = (end - next) / slot.period_ns + 1;
    c.skips.store(c.skips.load(std::memory_order_relaxed) + static_cast<std::uint64_t>(missed),
                  std::memory_order_relaxed);
    next += missed * slot.period_ns;
  }
  slot.next_release_ns = next;
}

Status Scheduler::run_lockstep(hal::SimClock& clock, hal::Nanos duration_ns) {
  if (&clock != &clock_) return Error(Errc::invalid_argument, "scheduler: lockstep needs the scheduler's own clock");
  // The first call releases every task now; later calls continue where the last one ended.
  if (!prepared_) {
    if (Status s = prepare(clock.now()); !s) return s;
  }
  stop_.store(false, std::memory_order_release);
  running_ = true;
  const hal::Nanos end = duration_ns > INT64_MAX - clock.now() ? INT64_MAX : clock.now() + duration_ns;
  while (!stop_.load(std::memory_order_acquire)) {
    // The group with the earliest release runs next; ties go to the higher-priority group,
    // then to table order, so a simulation is deterministic.
    std::size_t best = 0;
    hal::Nanos best_release = INT64_MAX;
    for (std::size_t g = 0; g < group_count_; ++g) {
      const hal::Nanos r = next_release(groups_[g]);
      if (r < best_release || (r == best_release && groups_[g].priority > groups_[best].priority)) {
        best = g;
        best_release = r;
      }
    }
    if (best_release >= end) break;
    clock.advance_to(best_release);
    run_due(groups_[best]);
  }
  clock.advance_to(end);
  running_ = false;
  return Status::success();
}

void Scheduler::warn(const Error& error) {
  std::lock_guard lock(warnings_mutex());
  const std::size_t n = warning_count_.load(std::memory_order_relaxed);
  if (n == kMaxWarnings) return;
  warnings_[n] = error;
  warning_count_.store(n + 1, std::memory_order_release);
}

void Scheduler::thread_main(std::size_t group_index) {
  Group& group = groups_[group_index];
  const ThreadOptions& options = group.options;
  if (options.cpu >= 0) {
    if (Status s = hal::set_current_thread_affinity(options.cpu); !s) warn(s.error());
  }
  if (options.realtime && group.priority > 0) {
    if (Status s = hal::set_current_thread_fifo(group.priority); !s) warn(s.error());
  }
  if (options.prefault_stack_bytes > 0) {
    if (Status s = hal::prefault_stack(options.prefault_stack_bytes); !s) warn(s.error());
  }

  while (!stop_.load(std::memory_order_acquire)) {
    const hal::Nanos release = next_release(group);
    const hal::Nanos wake = std::min(release, clock_.now() + kStopPollInterval_ns);
    clock_.sleep_until(wake);
    if (wake == release) run_due(group);
  }
}

Status Scheduler::start() {
  if (clock_.simulated()) return Error(Errc::invalid_argument, "scheduler: real-time start needs a real clock");
  if (Status s = prepare(clock_.now() + kStartupPhase_ns); !s) return s;
  running_ = true;
  for (std::size_t g = 0; g < group_count_; ++g) groups_[g].thread = std::thread([this, g] { thread_main(g); });
  return Status::success();
}

void Scheduler::join() {
  for (std::size_t g = 0; g < group_count_; ++g)
    if (groups_[g].thread.joinable()) groups_[g].thread.join();
  running_ = false;
}

TaskStats Scheduler::stats(std::size_t index) const {
  const Slot& slot = slots_[index];
  const TaskCounters& c = slot.counters;
  TaskStats s;
  s.name = slot.spec.name;
  s.thread = slot.spec.thread;
  s.period_us = slot.spec.period_us;
  s.budget_us = slot.spec.budget_us;
  s.priority = slot.spec.priority;
  s.runs = c.runs.load(std::memory_order_acquire);
  s.overruns = c.overruns.load(std::memory_order_relaxed);
  s.cpu_overruns = c.cpu_overruns.load(std::memory_order_relaxed);
  s.slips = c.slips.load(std::memory_order_relaxed);
  s.skips = c.skips.load(std::memory_order_relaxed);
  s.exec_min_ns = c.exec_min_ns.load(std::memory_order_relaxed);
  s.exec_max_ns = c.exec_max_ns.load(std::memory_order_relaxed);
  s.exec_mean_ns = s.runs ? c.exec_total_ns.load(std::memory_order_relaxed) / static_cast<std::int64_t>(s.runs) : 0;
  s.cpu_min_ns = c.cpu_min_ns.load(std::memory_order_relaxed);
  s.cpu_max_ns = c.cpu_max_ns.load(std::memory_order_relaxed);
  s.cpu_mean_ns = s.runs ? c.cpu_total_ns.load(std::memory_order_relaxed) / static_cast<std::int64_t>(s.runs) : 0;
  s.jitter_p50_ns = c.release_jitter.percentile_ns(0.50);
  s.jitter_p99_ns = c.release_jitter.percentile_ns(0.99);
  s.jitter_max_ns = c.release_jitter.max_ns();
  s.last_start_ns = c.last_start_ns.load(std::memory_order_relaxed);
  return s;
}

void Scheduler::print_stats(std::FILE* out) const {
  // Three durations in microseconds as one column, e.g. "12.0/15.3/40.1".
  const auto triple = [](char (&buf)[48], std::int64_t a_ns, std::int64_t b_ns, std::int64_t c_ns) {
    std::snprintf(buf, sizeof buf, "%.1f/%.1f/%.1f", static_cast<double>(a_ns) / 1e3, static_cast<double>(b_ns) / 1e3,
                  static_cast<double>(c_ns) / 1e3);
  };
  std::fprintf(out, "%-14s %-11s %9s %8s %3s %9s %8s %8s %6s %6s %24s %24s %24s\n", "task", "thread", "period_us",
               "budget_us", "pri", "runs", "overruns", "cpu_over", "slips", "skips", "exec min/mean/max us",
               "cpu min/mean/max us", "jitter p50/p99/max us");
  for (std::size_t i = 0; i < task_count_; ++i) {
    const TaskStats s = stats(i);
    char exec[48];
    char cpu[48];
    char jitter[48];
    triple(exec, s.exec_min_ns, s.exec_mean_ns, s.exec_max_ns);
    triple(cpu, s.cpu_min_ns, s.cpu_mean_ns, s.cpu_max_ns);
    triple(jitter, s.jitter_p50_ns, s.jitter_p99_ns, s.jitter_max_ns);
    std::fprintf(out,
                 "%-14.*s %-11.*s %9" PRId64 " %8" PRId64 " %3d %9" PRIu64 " %8" PRIu64 " %8" PRIu64 " %6" PRIu64
                 " %6" PRIu64 " %24s %24s %24s\n",
                 static_cast<int>(s.name.size()), s.name.data(), static_cast<int>(s.thread.size()), s.thread.data(),
                 s.period_us, s.budget_us, s.priority, s.runs, s.overruns, s.cpu_overruns, s.slips, s.skips, exec, cpu,
                 jitter);
  }
}

}  // namespace sen3bot::tasks
