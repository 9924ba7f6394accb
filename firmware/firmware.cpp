#include "firmware.hpp"

#include "task_table.hpp"

namespace sen3bot::firmware {

Firmware::Firmware(const FirmwareConfig& config, hal::Clock& clock, std::FILE* out)
    : config_(config),
      clock_(clock),
      out_(out),
      scheduler_(clock),
      health_(scheduler_, bus_, clock, tasks::HealthConfig{config.health_stall_periods}),
      telemetry_(scheduler_, bus_, clock, out, tasks::TelemetryConfig{config.telemetry_status_period_ms, 512}) {}

Firmware::~Firmware() { shutdown(); }

tasks::Task* Firmware::task_named(std::string_view name) {
  if (name == "health") return &health_;
  if (name == "telemetry") return &telemetry_;
  return nullptr;
}

Status Firmware::init() {
  if (initialised_) return Error(Errc::invalid_argument, "firmware: init() called twice");
  const char* file = config_.source_path.c_str();

  // Every configured task must exist, so a misspelt name is not silently ignored.
  for (const auto& [name, task_config] : config_.tasks) {
    bool in_table = false;
    for (const tasks::TaskSpec& row : kTaskTable) in_table = in_table || row.name == name;
    if (!in_table)
      return Error::format(Errc::config, "%s: tasks.%s: no such task in the task table", file, name.c_str());
  }

  for (const tasks::TaskSpec& row : kTaskTable) {
    tasks::Task* task = task_named(row.name);
    if (task == nullptr)
      return Error::format(Errc::invalid_argument, "firmware: task table row '%.*s' has no task behind it",
                           static_cast<int>(row.name.size()), row.name.data());
    if (Status s = scheduler_.add(row, *task); !s) return s;
  }
  for (const auto& [name, thread] : config_.threads) {
    bool used = false;
    for (const tasks::TaskSpec& row : kTaskTable) used = used || row.thread == name;
    if (!used) return Error::format(Errc::config, "%s: threads.%s: no task runs on this thread", file, name.c_str());
  }
  for (const tasks::TaskSpec& row : kTaskTable) {
    tasks::ThreadOptions options;
    options.name = row.thread;
    options.prefault_stack_bytes = config_.prefault_stack_bytes;
    if (auto it = config_.threads.find(row.thread); it != config_.threads.end()) {
      options.cpu = it->second.cpu;
      options.realtime = it->second.realtime;
    }
    if (Status s = scheduler_.configure_thread(options); !s) return s;
  }

  // init() in table order, each inside its own budget.
  arenas_.reserve(kTaskTable.size());
  for (const tasks::TaskSpec& row : kTaskTable) {
    const auto it = config_.tasks.find(row.name);
    if (it == config_.tasks.end())
      return Error::format(Errc::config, "%s: tasks.%.*s.arena_bytes: missing (every task needs a memory budget)", file,
                           static_cast<int>(row.name.size()), row.name.data());
    auto& arena = arenas_.emplace_back(std::make_unique<mem::BudgetArena>(row.name, it->second.arena_bytes));
    tasks::Task* task = task_named(row.name);
    if (Status s = mem::try_init(*arena, [&] { return task->init(*arena); }); !s)
      return Error::format(s.error().code(), "task '%.*s' init failed: %s (budget from %s: tasks.%.*s.arena_bytes)",
                           static_cast<int>(row.name.size()), row.name.data(), s.error().c_str(), file,
                           static_cast<int>(row.name.size()), row.name.data());
  }
  initialised_ = true;
  return Status::success();
}

void Firmware::shutdown() {
  if (!initialised_) return;
  scheduler_.request_stop();
  scheduler_.join();
  for (const tasks::TaskSpec& row : kTaskTable) task_named(row.name)->shutdown();
  initialised_ = false;
}

void Firmware::print_memory(std::FILE* out) const {
  std::size_t total_budget = 0, total_used = 0;
  std::fprintf(out, "memory budgets (bytes):\n  %-14s %10s %10s\n", "task", "budget", "used");
  for (const auto& arena : arenas_) {
    std::fprintf(out, "  %-14.*s %10zu %10zu\n", static_cast<int>(arena->name().size()), arena->name().data(),
                 arena->capacity_bytes(), arena->used_bytes());
    total_budget += arena->capacity_bytes();
    total_used += arena->used_bytes();
  }
  std::fprintf(out, "  %-14s %10zu %10zu\n", "total", total_budget, total_used);
}

}  // namespace sen3bot::firmware
