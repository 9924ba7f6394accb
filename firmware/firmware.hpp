#pragma once
// Composition: the bus, the tasks of the task table with their arenas, and the scheduler that
// runs them, over a board (the robot computer's, or a simulated one: the firmware cannot tell).
// Everything is sized here, once, from the configuration.
#include <array>
#include <cstdio>
#include <memory>
#include <memory_resource>
#include <vector>

#include "config.hpp"
#include "sen3bot/hal/board.hpp"
#include "sen3bot/mem/budget_arena.hpp"
#include "sen3bot/tasks/bus.hpp"
#include "sen3bot/tasks/scheduler.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/msg/messages.hpp"
#include "sen3bot/nav/nav_tasks.hpp"
#include "sen3bot/nav/waypoints.hpp"
#include "base_task.hpp"
#include "can_io_task.hpp"
#include "cobot_task.hpp"
#include "detector_task.hpp"
#include "fleet_task.hpp"
#include "laser_task.hpp"
#include "mission.hpp"
#include "row_module.hpp"
#include "task_table.hpp"
#include "topics.hpp"
#include "view_task.hpp"
#include "wiring.hpp"

namespace sen3bot::firmware {

class Firmware {
 public:
  Firmware(const FirmwareConfig& config, hal::Board& board, std::FILE* out);
  ~Firmware();

  // Adds every row of the task table to the scheduler and runs each task's init() inside its
  // arena. Fails with the first problem: a row without a configured budget, a task whose
  // init() asks for more than its budget, a bad specification.
  Status init();
  void shutdown();
  // Frames from elsewhere than the camera row (a simulated camera): the QR and vision rows
  // read these. Before init(); the pool must outlive the firmware.
  void use_camera_frames(camera::FramePool* frames) noexcept { shared_.external_frames = frames; }
  // A live view server that outlives this firmware (a simulator's, across its cases): with a
  // `view` section the view row publishes into it instead of starting its own. Before init().
  void use_view_server(view::Server* server) noexcept { shared_.external_view = server; }
  // People known without sensing (a simulator's ground truth): with navigation.people the
  // people row relays these instead of fusing a detector's boxes with the laser, and there is no
  // detector row. Before init(); the topic must outlive the firmware.
  void use_people_source(const tasks::Topic<msg::People>* people) noexcept { shared_.external_people = people; }
  // The view row; null without a `view` section.
  [[nodiscard]] ViewTask* view() { return task_as<ViewTask>("view"); }
  // The channels a configuration serves (for a server made before the firmware); reads the
  // map's size from its file.
  static Result<std::size_t> view_channels(const FirmwareConfig& config, bool external_frames,
                                           std::span<view::ChannelSpec, kViewChannels> out);

  [[nodiscard]] tasks::Scheduler& scheduler() { return scheduler_; }
  [[nodiscard]] tasks::Bus& bus() { return bus_; }
  [[nodiscard]] const mem::BudgetArena& arena(std::size_t task_index) const { return *arenas_[task_index]; }
  void print_memory(std::FILE* out) const;

  // The bus's messages, for the command line's reports, a simulator's referee and tests.
  [[nodiscard]] const tasks::Topic<msg::ScanMessage>& scan() const { return topics_.scan; }
  [[nodiscard]] const tasks::Topic<msg::Odometry>& odometry() const { return topics_.odometry; }
  [[nodiscard]] const tasks::Topic<msg::VelocityCommand>& request() const { return topics_.request; }
  [[nodiscard]] const tasks::Topic<msg::VelocityCommand>& command() const { return topics_.command; }
  [[nodiscard]] const tasks::Topic<msg::SafetyOutput>& safety_output() const { return topics_.safety_output; }
  // Null without the device.
  [[nodiscard]] const BaseTask* base() const { return task_as<BaseTask>("base"); }
  [[nodiscard]] const LaserTask* laser() const { return task_as<LaserTask>("laser"); }
  [[nodiscard]] const CanIoTask* can_io() const { return task_as<CanIoTask>("can_io"); }
  [[nodiscard]] const nav::SafetyTask* safety() const { return task_as<nav::SafetyTask>("safety"); }
  // The safety I/O as the CAN I/O task reads it, and the collaborative mode's requests.
  [[nodiscard]] const tasks::Topic<msg::SafetyIo>& safety_io() const { return topics_.safety_io; }
  [[nodiscard]] tasks::Topic<msg::OperatingMode>& operating_mode() { return topics_.operating_mode; }
  // The newest decoded frames, for readers on any thread; null without a camera.
  [[nodiscard]] camera::FramePool* camera_frames() {
    if (shared_.external_frames != nullptr) return shared_.external_frames;
    return shared_.camera != nullptr ? &shared_.camera->frames() : nullptr;
  }
  // The camera row's camera (its status, whether it failed for good); null without one or
  // before init().
  [[nodiscard]] camera::Camera* camera() { return shared_.camera; }
  // Null without a `navigation` section.
  [[nodiscard]] const MissionTask* mission() const { return task_as<MissionTask>("mission"); }
  // Null without a `fleet` section.
  [[nodiscard]] const FleetTask* fleet() const { return task_as<FleetTask>("fleet"); }
  // The local planner and its costmap, for a simulator's figures; read while the scheduler is
  // stopped or between lockstep slices. Null without a `navigation` section.
  [[nodiscard]] const nav::ControllerTask* controller() const { return task_as<nav::ControllerTask>("controller"); }
  [[nodiscard]] const tasks::Topic<msg::ControllerStatus>& controller_status() const { return topics_.controller_status; }
  [[nodiscard]] const tasks::Topic<msg::PoseEstimate>& pose_estimate() const { return topics_.pose; }
  [[nodiscard]] const tasks::Topic<msg::MovingObstacles>& movers() const { return topics_.movers; }
  [[nodiscard]] const tasks::Topic<msg::People>& people() const { return topics_.people; }
  // The centre's formation commands as the fleet task took them (never published without a
  // `fleet` section).
  [[nodiscard]] const tasks::Topic<msg::FormationCommand>& formation() const { return topics_.formation; }
  // Null without navigation.people.
  [[nodiscard]] const DetectorTask* detector() const { return task_as<DetectorTask>("detector"); }
  // Null without navigation.people, or when the people are relayed (use_people_source()).
  [[nodiscard]] const nav::PeopleTask* people_task() const {
    return dynamic_cast<const nav::PeopleTask*>(task("people"));
  }
  [[nodiscard]] const nav::OccupancyMap& map() const { return shared_.map; }
  // The collaborative mode; null without a `cobot` section.
  [[nodiscard]] const CobotTask* cobot() const { return task_as<CobotTask>("cobot"); }
  [[nodiscard]] const MappingTask* mapping() const { return task_as<MappingTask>("mapping"); }
  [[nodiscard]] const tasks::Topic<msg::CobotState>& cobot_state() const { return topics_.cobot_state; }
  [[nodiscard]] const tasks::Topic<msg::TagFrame>& tags() const { return topics_.tags; }
  [[nodiscard]] const tasks::Topic<msg::WorkerPath>& worker_path() const { return topics_.worker_path; }
  [[nodiscard]] const tasks::Topic<msg::OperationEstimate>& operation() const { return topics_.operation; }
  [[nodiscard]] const tasks::Topic<msg::NavGoal>& goal() const { return topics_.goal; }
  [[nodiscard]] const tasks::Topic<msg::PathMessage>& operation_reference() const { return topics_.operation_reference; }
  // For a test standing in for the QR row.
  [[nodiscard]] tasks::Topic<msg::TagFrame>& tags_topic() { return topics_.tags; }
  // The waypoints the global planner follows: the file's, or the supervisory planner's path
  // for the newest goal. The planner task, for its supervisory planner. Null or empty without
  // a `navigation` section; read while the scheduler is stopped.
  [[nodiscard]] std::span<const msg::Point2D> safe_path() const {
    const nav::PlannerTask* planner = task_as<nav::PlannerTask>("planner");
    return planner != nullptr ? planner->safe_path() : std::span<const msg::Point2D>(shared_.waypoints);
  }
  [[nodiscard]] const nav::PlannerTask* planner() const { return task_as<nav::PlannerTask>("planner"); }

 // The bus, as the factories wired it, and each row's wiring (after init(); the rows that
  // run and the rows this configuration leaves out, with why).
  [[nodiscard]] const Topics& topics() const { return topics_; }
  [[nodiscard]] std::span<const RowWiring> wiring() const { return wiring_; }
  // Makes the configured rows' tasks without starting anything: what `sen3bot graph` prints.
  Status wire();

 private:
  [[nodiscard]] const tasks::Task* task(std::string_view name) const;
  template <class T>
  [[nodiscard]] const T* task_as(std::string_view name) const {
    return static_cast<const T*>(task(name));
  }
  template <class T>
  [[nodiscard]] T* task_as(std::string_view name) {
    return const_cast<T*>(static_cast<const T*>(task(name)));
  }

  const FirmwareConfig& config_;
  hal::Board& board_;
  std::FILE* out_;
  tasks::Bus bus_;
  tasks::Scheduler scheduler_;
  Topics topics_;
  // Outlives the tasks, which keep references (the map, the waypoints, the camera's pool).
  Shared shared_;
  // One arena per running row, in table order; created once in init(). Declared before the
  // tasks so it outlives them: their destructors release what they built inside it.
  std::vector<std::unique_ptr<mem::BudgetArena>> arenas_;
  // Each row's task (null: the configuration runs none), made by the row's factory.
  std::array<std::unique_ptr<tasks::Task>, kRows.size()> tasks_{};
  std::array<RowWiring, kRows.size()> wiring_{};
  bool wired_ = false;
  std::vector<std::size_t> running_;  // the rows that run, in table order
  bool initialised_ = false;
};

}  // namespace sen3bot::firmware
