#include "firmware.hpp"

#include "sen3bot/tasks/health.hpp"
#include "sen3bot/tasks/telemetry.hpp"
#include "task_table.hpp"

namespace sen3bot::firmware {

Firmware::Firmware(const FirmwareConfig& config, hal::Board& board, std::FILE* out)
    : config_(config), board_(board), out_(out), scheduler_(board.clock()) {
  shared_.laser_mount = {config.laser_mount.x_m, config.laser_mount.y_m, config.laser_mount.theta_rad};
}

Firmware::~Firmware() { shutdown(); }

const tasks::Task* Firmware::task(std::string_view name) const {
  for (std::size_t i = 0; i < kRows.size(); ++i)
    if (kRows[i].spec.name == name) return tasks_[i].get();
  return nullptr;
}

Status make_health(Wiring& w) {
  w.make<tasks::HealthTask>(w.scheduler, w.bus, w.board.clock(), tasks::HealthConfig{w.config.health_stall_periods});
  return Status::success();
}

Status make_telemetry(Wiring& w) {
  w.sends("telemetry: one status line every " + std::to_string(w.config.telemetry_status_period_ms) +
          " ms and the event log, on standard output");
  w.make<tasks::TelemetryTask>(w.scheduler, w.bus, w.out,
                               tasks::TelemetryConfig{w.config.telemetry_status_period_ms, 512});
  return Status::success();
}

Status Firmware::wire() {
  if (wired_) return Status::success();
  const char* file = config_.source_path.c_str();
  const NavigationSection& n = config_.navigation;
  if (n.enabled) {
    Result<nav::OccupancyMap> map = nav::load_map(n.map_path);
    if (!map) return Error::format(map.error().code(), "%s: navigation.map: %s", file, map.error().c_str());
    shared_.map = std::move(*map);
    if (!n.waypoints_path.empty()) {
      Result<std::vector<msg::Point2D>> waypoints = nav::load_waypoints(n.waypoints_path);
      if (!waypoints)
        return Error::format(waypoints.error().code(), "%s: navigation.waypoints: %s", file, waypoints.error().c_str());
      shared_.waypoints = std::move(*waypoints);
    }
  }
  Wiring w(config_, board_, bus_, scheduler_, out_, topics_, shared_, tasks_, wiring_);
  for (std::size_t i = 0; i < kRows.size(); ++i) {
    wiring_[i].name = kRows[i].spec.name;
    w.begin_row(i);
    if (Status s = kRows[i].make(w); !s) return s;
  }
  wired_ = true;
  return Status::success();
}

Result<std::size_t> Firmware::view_channels(const FirmwareConfig& config, bool external_frames,
                                            std::span<view::ChannelSpec, kViewChannels> out) {
  ViewTask::Shape shape;
  shape.navigation = config.navigation.enabled;
  shape.scan = config.devices.has_laser || config.navigation.enabled;
  shape.camera = config.devices.has_camera || external_frames;
  if (shape.navigation) {
    Result<nav::OccupancyMap> map = nav::load_map(config.navigation.map_path);
    if (!map) return map.error();
    shape.map_cells = map->cell_count();
  }
  return ViewTask::channel_specs(config.view.task, shape, out);
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

  if (Status s = wire(); !s) return s;
  for (std::size_t i = 0; i < kRows.size(); ++i)
    if (tasks_[i] != nullptr) running_.push_back(i);
  for (const auto& [name, task_config] : config_.tasks) {
    // The view's budget may stay in a configuration whose view is off (sen3bot-sim sim --view
    // turns it on).
    if (name == "view" && !config_.view.enabled) continue;
    for (std::size_t i = 0; i < kRows.size(); ++i)
      if (kRows[i].spec.name == name && tasks_[i] == nullptr)
        return Error::format(Errc::config, "%s: tasks.%s: this task is not enabled by the configuration (%s)", file,
                             name.c_str(), wiring_[i].absent.c_str());
  }
  for (const std::size_t i : running_) {
    if (Status s = scheduler_.add(kRows[i].spec, *tasks_[i]); !s) return s;
  }
  for (const auto& [name, thread] : config_.threads) {
    bool used = false;
    for (const std::size_t i : running_) used = used || kRows[i].spec.thread == name;
    if (!used) return Error::format(Errc::config, "%s: threads.%s: no task runs on this thread", file, name.c_str());
  }
  for (const std::size_t i : running_) {
    const tasks::TaskSpec& row = kRows[i].spec;
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
  arenas_.reserve(running_.size());
  for (const std::size_t i : running_) {
    const tasks::TaskSpec& row = kRows[i].spec;
    const auto it = config_.tasks.find(row.name);
    if (it == config_.tasks.end())
      return Error::format(Errc::config, "%s: tasks.%.*s.arena_bytes: missing (every task needs a memory budget)", file,
                           static_cast<int>(row.name.size()), row.name.data());
    auto& arena = arenas_.emplace_back(std::make_unique<mem::BudgetArena>(row.name, it->second.arena_bytes));
    tasks::Task* task = tasks_[i].get();
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
  for (const std::size_t i : running_) tasks_[i]->shutdown();
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
