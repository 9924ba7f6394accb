#pragma once
// Watches the scheduler: a task that has not started for `stall_periods` of its periods is
// stalled; new overruns and slips are reported, and tasks whose device failed for good. The safety task will act on this report.
#include <cstdint>
#include <memory_resource>
#include <span>

#include "sen3bot/tasks/bus.hpp"
#include "sen3bot/tasks/scheduler.hpp"
#include "sen3bot/tasks/task.hpp"

namespace sen3bot::tasks {

struct HealthConfig {
  int stall_periods = 3;
};

class HealthTask final : public Task {
 public:
  HealthTask(const Scheduler& scheduler, Bus& bus, const hal::Clock& clock, HealthConfig config)
      : scheduler_(scheduler), bus_(bus), clock_(clock), config_(config) {}

  Status init(std::pmr::memory_resource& arena) override;
  void step(const StepContext& context) override;

 private:
  struct Previous {
    std::uint64_t overruns = 0;
    std::uint64_t slips = 0;
    bool stalled = false;
    bool failed = false;
    bool missing = false;
  };

  const Scheduler& scheduler_;
  Bus& bus_;
  const hal::Clock& clock_;
  HealthConfig config_;
  std::span<Previous> previous_;
  std::size_t self_index_ = 0;  // a running health task is never stalled itself
};

}  // namespace sen3bot::tasks
