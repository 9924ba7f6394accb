#pragma once
// Composition: the bus, the tasks of the task table with their arenas, and the scheduler that
// runs them, over a board (the robot computer's, or a simulated one: the firmware cannot tell).
// Everything is sized here, once, from the configuration.
#include <cstdio>
#include <memory>
#include <memory_resource>
#include <vector>

#include "config.hpp"
#include "sen3bot/hal/board.hpp"
#include "sen3bot/mem/budget_arena.hpp"
#include "sen3bot/tasks/bus.hpp"
#include "sen3bot/tasks/health.hpp"
#include "sen3bot/tasks/scheduler.hpp"
#include "sen3bot/tasks/telemetry.hpp"
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
#include "view_task.hpp"

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
  void use_camera_frames(camera::FramePool* frames) noexcept { external_frames_ = frames; }
  // A live view server that outlives this firmware (a simulator's, across its cases): with a
  // `view` section the view row publishes into it instead of starting its own. Before init().
  void use_view_server(view::Server* server) noexcept { external_view_ = server; }
  // People known without sensing (a simulator's ground truth): with navigation.people the
  // people row relays these instead of fusing a detector's boxes with the laser, and there is no
  // detector row. Before init(); the topic must outlive the firmware.
  void use_people_source(const tasks::Topic<msg::People>* people) noexcept { external_people_ = people; }
  // The view row; null without a `view` section.
  [[nodiscard]] ViewTask* view() { return view_task_.get(); }
  // The channels a configuration serves (for a server made before the firmware); reads the
  // map's size from its file.
  static Result<std::size_t> view_channels(const FirmwareConfig& config, bool external_frames,
                                           std::span<view::ChannelSpec, kViewChannels> out);

  [[nodiscard]] tasks::Scheduler& scheduler() { return scheduler_; }
  [[nodiscard]] tasks::Bus& bus() { return bus_; }
  [[nodiscard]] const mem::BudgetArena& arena(std::size_t task_index) const { return *arenas_[task_index]; }
  void print_memory(std::FILE* out) const;

  // The bus's messages, for the command line's reports, a simulator's referee and tests.
  [[nodiscard]] const tasks::Topic<msg::ScanMessage>& scan() const { return nav_scan_; }
  [[nodiscard]] const tasks::Topic<msg::Odometry>& odometry() const { return nav_odometry_; }
  [[nodiscard]] const tasks::Topic<msg::VelocityCommand>& request() const { return nav_request_; }
  [[nodiscard]] const tasks::Topic<msg::VelocityCommand>& command() const { return nav_command_; }
  [[nodiscard]] const tasks::Topic<msg::SafetyOutput>& safety_output() const { return nav_safety_; }
  // Null without the device.
  [[nodiscard]] const BaseTask* base() const { return base_task_.get(); }
  [[nodiscard]] const LaserTask* laser() const { return laser_task_.get(); }
  [[nodiscard]] const CanIoTask* can_io() const { return can_io_task_.get(); }
  [[nodiscard]] const nav::SafetyTask* safety() const { return safety_task_.get(); }
  // The safety I/O as the CAN I/O task reads it, and the collaborative mode's requests.
  [[nodiscard]] const tasks::Topic<msg::SafetyIo>& safety_io() const { return nav_io_; }
  [[nodiscard]] tasks::Topic<msg::OperatingMode>& operating_mode() { return nav_mode_; }
  // The newest decoded frames, for readers on any thread; null without a camera.
  [[nodiscard]] camera::FramePool* camera_frames() {
    if (external_frames_ != nullptr) return external_frames_;
    return camera_device_ != nullptr ? &camera_device_->frames() : nullptr;
  }
  // The camera row's camera (its status, whether it failed for good); null without one or
  // before init().
  [[nodiscard]] camera::Camera* camera() { return camera_device_; }
  // Null without a `navigation` section.
  [[nodiscard]] const MissionTask* mission() const { return mission_task_.get(); }
  // Null without a `fleet` section.
  [[nodiscard]] const FleetTask* fleet() const { return fleet_task_.get(); }
  // The local planner and its costmap, for a simulator's figures; read while the scheduler is
  // stopped or between lockstep slices. Null without a `navigation` section.
  [[nodiscard]] const nav::ControllerTask* controller() const { return controller_task_.get(); }
  [[nodiscard]] const tasks::Topic<msg::ControllerStatus>& controller_status() const { return nav_controller_; }
  [[nodiscard]] const tasks::Topic<msg::PoseEstimate>& pose_estimate() const { return nav_pose_; }
  [[nodiscard]] const tasks::Topic<msg::MovingObstacles>& movers() const { return nav_movers_; }
  [[nodiscard]] const tasks::Topic<msg::People>& people() const { return nav_people_; }
  // The centre's formation commands as the fleet task took them (never published without a
  // `fleet` section).
  [[nodiscard]] const tasks::Topic<msg::FormationCommand>& formation() const { return nav_formation_; }
  // Null without navigation.people.
  [[nodiscard]] const DetectorTask* detector() const { return detector_task_.get(); }
  [[nodiscard]] const nav::PeopleTask* people_task() const { return people_task_.get(); }
  [[nodiscard]] const nav::OccupancyMap& map() const { return map_; }
  // The collaborative mode; null without a `cobot` section.
  [[nodiscard]] const CobotTask* cobot() const { return cobot_task_.get(); }
  [[nodiscard]] const tasks::Topic<msg::CobotState>& cobot_state() const { return nav_cobot_; }
  [[nodiscard]] const tasks::Topic<msg::TagFrame>& tags() const { return nav_tags_; }
  [[nodiscard]] const tasks::Topic<msg::WorkerPath>& worker_path() const { return nav_worker_path_; }
  [[nodiscard]] const tasks::Topic<msg::OperationEstimate>& operation() const { return nav_operation_; }
  [[nodiscard]] const tasks::Topic<msg::NavGoal>& goal() const { return nav_goal_; }
  [[nodiscard]] const tasks::Topic<msg::PathMessage>& operation_reference() const { return nav_operation_reference_; }
  // For a test standing in for the QR row.
  [[nodiscard]] tasks::Topic<msg::TagFrame>& tags_topic() { return nav_tags_; }
  // The waypoints the global planner follows: the file's, or the supervisory planner's path
  // for the newest goal. The planner task, for its supervisory planner. Null or empty without
  // a `navigation` section; read while the scheduler is stopped.
  [[nodiscard]] std::span<const msg::Point2D> safe_path() const {
    return planner_task_ ? planner_task_->safe_path() : std::span<const msg::Point2D>(waypoints_);
  }
  [[nodiscard]] const nav::PlannerTask* planner() const { return planner_task_.get(); }

 private:
  tasks::Task* task_named(std::string_view name);
  Status create_tasks();
  Status create_navigation();
  Status create_cobot(const msg::SensorMount& mount, const nav::CameraCalibration& camera);
  ViewSources view_sources();
  // The frames of a given pool, else of the camera row (null slot without one).
  [[nodiscard]] FrameSource frame_source() const noexcept {
    return {external_frames_, camera_task_ ? &camera_device_ : nullptr};
  }

  const FirmwareConfig& config_;
  hal::Board& board_;
  std::FILE* out_;
  tasks::Bus bus_;
  tasks::Scheduler scheduler_;
  tasks::HealthTask health_;
  tasks::TelemetryTask telemetry_;
  // Navigation's bus (nav_tasks.hpp has the data flow).
  tasks::Topic<msg::ScanMessage> nav_scan_;
  tasks::Topic<msg::Odometry> nav_odometry_;
  tasks::Topic<msg::BaseFlags> nav_base_flags_;
  tasks::Topic<msg::Sonar> nav_sonar_;
  tasks::Topic<msg::PoseEstimate> nav_pose_;
  tasks::Topic<msg::NavGoal> nav_goal_;
  tasks::Topic<msg::PathMessage> nav_path_;
  tasks::Topic<msg::VelocityCommand> nav_request_;
  tasks::Topic<msg::VelocityCommand> nav_command_;
  tasks::Topic<msg::ControllerStatus> nav_controller_;
  tasks::Topic<msg::SafetyOutput> nav_safety_;
  tasks::Topic<msg::MovingObstacles> nav_movers_;
  tasks::Topic<msg::PersonDetections> nav_detections_;
  tasks::Topic<msg::People> nav_people_;
  tasks::Topic<msg::FormationCommand> nav_formation_;  // fleet -> controller
  tasks::Topic<msg::SafetyIo> nav_io_;
  tasks::Topic<msg::OperatingMode> nav_mode_;
  // The collaborative mode's: the mission's or fleet's goals pass through it.
  tasks::Topic<msg::NavGoal> nav_coop_goal_;
  tasks::Topic<msg::TagFrame> nav_tags_;
  tasks::Topic<msg::CobotState> nav_cobot_;
  tasks::Topic<msg::WorkerPath> nav_worker_path_;
  tasks::Topic<msg::OperationEstimate> nav_operation_;
  tasks::Topic<msg::PathMessage> nav_operation_reference_;
  tasks::Topic<msg::CostmapSnapshot> nav_costmap_snapshot_;  // controller -> view
  camera::FramePool* external_frames_ = nullptr;
  view::Server* external_view_ = nullptr;
  const tasks::Topic<msg::People>* external_people_ = nullptr;
  // Outlive the navigation tasks, which keep references.
  nav::OccupancyMap map_;
  std::vector<msg::Point2D> waypoints_;
  // One arena per running row, in table order; created once in init(). Declared before the
  // tasks so it outlives them: their destructors release what they built inside it.
  std::vector<std::unique_ptr<mem::BudgetArena>> arenas_;
  // Created by init() from the configuration; a row whose task is absent does not run.
  std::unique_ptr<BaseTask> base_task_;
  std::unique_ptr<LaserTask> laser_task_;
  std::unique_ptr<CanIoTask> can_io_task_;
  ModuleRow<CameraTask> camera_task_;  // the rows from modules: row_module.hpp
  camera::Camera* camera_device_ = nullptr;  // the camera row's, from its init()
  std::unique_ptr<nav::LocalizationTask> localization_task_;
  std::unique_ptr<nav::PlannerTask> planner_task_;
  std::unique_ptr<nav::ControllerTask> controller_task_;
  std::unique_ptr<nav::SafetyTask> safety_task_;
  std::unique_ptr<DetectorTask> detector_task_;
#ifdef SEN3BOT_HAS_HOG
  ModuleRow<VisionTask> vision_task_;
#endif
  std::unique_ptr<nav::PeopleTask> people_task_;
  std::unique_ptr<nav::PeopleRelayTask> people_relay_task_;  // instead, with use_people_source()
  std::unique_ptr<MissionTask> mission_task_;
  std::unique_ptr<FleetTask> fleet_task_;
  std::unique_ptr<CobotTask> cobot_task_;
  std::unique_ptr<ViewTask> view_task_;
#ifdef SEN3BOT_HAS_QR
  ModuleRow<QrTask> qr_task_;
#endif
#ifdef SEN3BOT_HAS_RECOGNITION
  ModuleRow<RecognitionTask> recognition_task_;
#endif
  std::vector<const tasks::TaskSpec*> rows_;  // the rows that run, in table order
  bool initialised_ = false;
};

}  // namespace sen3bot::firmware
