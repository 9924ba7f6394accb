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
#include "sen3bot/lms200/scan.hpp"
#include "sen3bot/lms200/task.hpp"
#include "sen3bot/p2os/task.hpp"
#include "sen3bot/p2os/types.hpp"
#include "sen3bot/sim/simulation.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/msg/messages.hpp"
#include "sen3bot/nav/nav_tasks.hpp"
#include "sen3bot/nav/waypoints.hpp"
#include "bridge.hpp"
#include "mission.hpp"

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

  // The devices' messages, for the command line's reports and for tests.
  [[nodiscard]] tasks::Topic<p2os::BaseSetpoint>& base_setpoint() { return base_setpoint_; }
  [[nodiscard]] const tasks::Topic<p2os::BaseState>& base_state() const { return base_state_; }
  [[nodiscard]] const tasks::Topic<lms200::LaserScan>& laser_scan() const { return laser_scan_; }
  [[nodiscard]] const tasks::Topic<sim::GroundTruth>& ground_truth() const { return ground_truth_; }
  // Null without a `sim` section.
  [[nodiscard]] sim::Simulation* simulation() { return simulation_.get(); }
  // Null without a `navigation` section.
  [[nodiscard]] const MissionTask* mission() const { return mission_task_.get(); }
  [[nodiscard]] const tasks::Topic<nav::PoseEstimate>& pose_estimate() const { return nav_pose_; }
  [[nodiscard]] const nav::OccupancyMap& map() const { return map_; }
  [[nodiscard]] std::span<const nav::Point2D> waypoints() const { return waypoints_; }

 private:
  tasks::Task* task_named(std::string_view name);
  Status create_tasks();
  Status create_navigation();

  const FirmwareConfig& config_;
  hal::Clock& clock_;
  std::FILE* out_;
  tasks::Bus bus_;
  tasks::Scheduler scheduler_;
  tasks::HealthTask health_;
  tasks::TelemetryTask telemetry_;
  tasks::Topic<p2os::BaseSetpoint> base_setpoint_;
  tasks::Topic<p2os::BaseState> base_state_;
  tasks::Topic<lms200::LaserScan> laser_scan_;
  tasks::Topic<sim::GroundTruth> ground_truth_;
  // Navigation's bus (nav_tasks.hpp has the data flow).
  tasks::Topic<nav::ScanMessage> nav_scan_;
  tasks::Topic<nav::Odometry> nav_odometry_;
  tasks::Topic<nav::BaseFlags> nav_base_flags_;
  tasks::Topic<nav::PoseEstimate> nav_pose_;
  tasks::Topic<nav::NavGoal> nav_goal_;
  tasks::Topic<nav::PathMessage> nav_path_;
  tasks::Topic<nav::VelocityCommand> nav_request_;
  tasks::Topic<nav::VelocityCommand> nav_command_;
  tasks::Topic<nav::ControllerStatus> nav_controller_;
  tasks::Topic<nav::SafetyOutput> nav_safety_;
  // Outlive the navigation tasks, which keep references.
  nav::OccupancyMap map_;
  std::vector<nav::Point2D> waypoints_;
  // One arena per running row, in table order; created once in init(). Declared before the
  // tasks so it outlives them: their destructors release what they built inside it.
  std::vector<std::unique_ptr<mem::BudgetArena>> arenas_;
  // Created by init() from the configuration; a row whose task is absent does not run.
  std::unique_ptr<sim::Simulation> simulation_;
  std::unique_ptr<sim::SimulationTask> sim_task_;
  std::unique_ptr<p2os::P2osTask> base_task_;
  std::unique_ptr<lms200::Lms200Task> laser_task_;
  std::unique_ptr<BridgeTask> bridge_task_;
  std::unique_ptr<nav::LocalizationTask> localization_task_;
  std::unique_ptr<nav::PlannerTask> planner_task_;
  std::unique_ptr<nav::ControllerTask> controller_task_;
  std::unique_ptr<nav::SafetyTask> safety_task_;
  std::unique_ptr<MissionTask> mission_task_;
  std::vector<const tasks::TaskSpec*> rows_;  // the rows that run, in table order
  bool initialised_ = false;
};

}  // namespace sen3bot::firmware
