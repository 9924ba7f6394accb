#pragma once
// Composition: the bus, the tasks of the task table with their arenas, and the scheduler that
// runs them. Everything is sized here, once, from the configuration.
#include <cstdio>
#include <memory>
#include <memory_resource>
#include <vector>

#include "config.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/mem/budget_arena.hpp"
#include "sen3bot/tasks/bus.hpp"
#include "sen3bot/tasks/health.hpp"
#include "sen3bot/tasks/scheduler.hpp"
#include "sen3bot/tasks/telemetry.hpp"

namespace sen3bot::firmware {

class Firmware {
 public:
  Firmware(const FirmwareConfig& config, hal::Clock& clock, std::FILE* out);
  ~Firmware();

  // Adds every row of the task table to the scheduler and runs each task's init() inside its
  // arena. Fails with the first problem: a row without a configured budget, a task whose
  // init() asks for more than its budget, a bad specification.
  Status init();
  void shutdown();

  [[nodiscard]] tasks::Scheduler& scheduler() { return scheduler_; }
  [[nodiscard]] tasks::Bus& bus() { return bus_; }
  [[nodiscard]] const mem::BudgetArena& arena(std::size_t task_index) const { return *arenas_[task_index]; }
  void print_memory(std::FILE* out) const;

 private:
  tasks::Task* task_named(std::string_view name);

  const FirmwareConfig& config_;
  hal::Clock& clock_;
  std::FILE* out_;
  tasks::Bus bus_;
  tasks::Scheduler scheduler_;
  tasks::HealthTask health_;
  tasks::TelemetryTask telemetry_;
  // One arena per task-table row, in table order; created once in init().
  std::vector<std::unique_ptr<mem::BudgetArena>> arenas_;
  bool initialised_ = false;
};

}  // namespace sen3bot::firmware
