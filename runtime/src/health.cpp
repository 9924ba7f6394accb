#include "sen3bot/tasks/health.hpp"

#include <cinttypes>

namespace sen3bot::tasks {

Status HealthTask::init(std::pmr::memory_resource& arena) {
  if (config_.stall_periods < 1) return Error(Errc::config, "health: stall_periods must be at least 1");
  const std::size_t n = scheduler_.task_count();
  if (n > 64) return Error(Errc::capacity, "health: the stalled-task mask holds 64 tasks");
  std::pmr::polymorphic_allocator<Previous> alloc(&arena);
  Previous* storage = alloc.allocate(n);
  for (std::size_t i = 0; i < n; ++i) alloc.construct(storage + i);
  previous_ = std::span<Previous>(storage, n);
  self_index_ = scheduler_.index_of(*this);
  return Status::success();
}

void HealthTask::step(const StepContext& context) {
  const hal::Nanos now = clock_.now();
  HealthReport report;
  report.task_count = static_cast<std::uint32_t>(previous_.size());
  for (std::size_t i = 0; i < previous_.size(); ++i) {
    const TaskSpec& spec = scheduler_.spec(i);
    const TaskCounters& c = scheduler_.counters(i);
    const std::uint64_t runs = c.runs.load(std::memory_order_acquire);
    const hal::Nanos last = runs ? c.last_start_ns.load(std::memory_order_relaxed) : scheduler_.start_time_ns();
    const bool stalled = i != self_index_ && now - last > config_.stall_periods * hal::micros(spec.period_us);
    if (stalled) {
      ++report.stalled_count;
      report.stalled_mask |= std::uint64_t{1} << i;
    }
    if (stalled != previous_[i].stalled) {
      bus_.events.post(now, stalled ? Severity::error : Severity::info, "health", "task %.*s %s",
                       static_cast<int>(spec.name.size()), spec.name.data(), stalled ? "stalled" : "running again");
      previous_[i].stalled = stalled;
    }
    const bool failed = scheduler_.task(i).failed();
    if (failed) {
      ++report.failed_count;
      report.failed_mask |= std::uint64_t{1} << i;
    }
    if (failed != previous_[i].failed) {
      bus_.events.post(now, failed ? Severity::error : Severity::info, "health", "task %.*s %s",
                       static_cast<int>(spec.name.size()), spec.name.data(),
                       failed ? "failed: running without its device" : "has its device again");
      previous_[i].failed = failed;
    }
    const bool missing = scheduler_.task(i).device_missing();
    if (missing) {
      ++report.missing_count;
      report.missing_mask |= std::uint64_t{1} << i;
    }
    if (missing != previous_[i].missing) {
      bus_.events.post(now, missing ? Severity::error : Severity::info, "health", "task %.*s %s",
                       static_cast<int>(spec.name.size()), spec.name.data(),
                       missing ? "has no device: retrying" : "has its device");
      previous_[i].missing = missing;
    }
    const std::uint64_t overruns = c.overruns.load(std::memory_order_relaxed);
    const std::uint64_t slips = c.slips.load(std::memory_order_relaxed);
    report.overruns_total += overruns;
    report.slips_total += slips;
    report.skips_total += c.skips.load(std::memory_order_relaxed);
    const std::uint64_t new_overruns = overruns - previous_[i].overruns;
    const std::uint64_t new_slips = slips - previous_[i].slips;
    if (new_overruns + new_slips > 0 && context.cycle > 0) {
      bus_.events.post(now, Severity::warning, "health", "task %.*s: %" PRIu64 " overruns, %" PRIu64 " slips",
                       static_cast<int>(spec.name.size()), spec.name.data(), new_overruns, new_slips);
    }
    report.overruns_since_last += new_overruns;
    report.slips_since_last += new_slips;
    previous_[i].overruns = overruns;
    previous_[i].slips = slips;
  }
  report.ok = report.stalled_count == 0 && report.failed_count == 0 && report.missing_count == 0 &&
              report.slips_since_last == 0;
  bus_.health.publish(report, now);
}

}  // namespace sen3bot::tasks
