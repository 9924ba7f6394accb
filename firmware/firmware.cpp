#include "firmware.hpp"

#include <algorithm>

#include "safe_curve.hpp"
#include "sen3bot/ssc/site_file.hpp"
#include "task_table.hpp"

namespace sen3bot::firmware {

Firmware::Firmware(const FirmwareConfig& config, hal::Board& board, std::FILE* out)
    : config_(config),
      board_(board),
      out_(out),
      scheduler_(board.clock()),
      health_(scheduler_, bus_, board.clock(), tasks::HealthConfig{config.health_stall_periods}),
      telemetry_(scheduler_, bus_, board.clock(), out,
                 tasks::TelemetryConfig{config.telemetry_status_period_ms, 512}) {}

Firmware::~Firmware() { shutdown(); }

tasks::Task* Firmware::task_named(std::string_view name) {
  if (name == "health") return &health_;
  if (name == "telemetry") return &telemetry_;
  if (name == "base") return base_task_.get();
  if (name == "laser") return laser_task_.get();
  if (name == "can_io") return can_io_task_.get();
  if (name == "camera") return camera_task_.get();
  if (name == "localization") return localization_task_.get();
  if (name == "planner") return planner_task_.get();
  if (name == "controller") return controller_task_.get();
  if (name == "safety") return safety_task_.get();
  if (name == "mission") return mission_task_.get();
  if (name == "fleet") return fleet_task_.get();
  if (name == "detector") return detector_task_.get();
  if (name == "people") return people_task_ ? static_cast<tasks::Task*>(people_task_.get()) : people_relay_task_.get();
  if (name == "cobot") return cobot_task_.get();
  if (name == "view") return view_task_.get();
#ifdef SEN3BOT_HAS_QR
  if (name == "qr") return qr_task_.get();
#endif
#ifdef SEN3BOT_HAS_RECOGNITION
  if (name == "recognition") return recognition_task_.get();
#endif
#ifdef SEN3BOT_HAS_HOG
  if (name == "vision") return vision_task_.get();
#endif
  return nullptr;
}

Status Firmware::create_navigation() {
  const char* file = config_.source_path.c_str();
  const NavigationSection& n = config_.navigation;
  Result<nav::OccupancyMap> map = nav::load_map(n.map_path);
  if (!map) return Error::format(map.error().code(), "%s: navigation.map: %s", file, map.error().c_str());
  map_ = std::move(*map);
  if (!n.waypoints_path.empty()) {
    Result<std::vector<msg::Point2D>> waypoints = nav::load_waypoints(n.waypoints_path);
    if (!waypoints)
      return Error::format(waypoints.error().code(), "%s: navigation.waypoints: %s", file, waypoints.error().c_str());
    waypoints_ = std::move(*waypoints);
  }
  const msg::SensorMount mount{config_.laser_mount.x_m, config_.laser_mount.y_m, config_.laser_mount.theta_rad};

  nav::LocalizationTaskConfig localization;
  localization.mcl = n.mcl;
  localization.mcl.laser_mount = mount;
  localization_task_ = std::make_unique<nav::LocalizationTask>(localization, map_, nav_scan_, nav_odometry_, nav_pose_);

  nav::PlannerTaskConfig planner;
  planner.laser_mount = mount;
  if (!n.safe_curve_path.empty()) {
    Result<SiteCurve> curve = load_safe_curve(n.safe_curve_path);
    if (!curve) return Error::format(curve.error().code(), "%s: navigation.safe_curve: %s", file, curve.error().c_str());
    planner.use_sgp = true;
    planner.sgp = n.sgp;
    planner.curve = curve->curve;
    planner.curve_bounds = curve->has_bounds ? curve->bounds : nav::map_extent(map_);
  }
  // People: the detector's channel and the fusion (or a relay of people known without sensing),
  // and the cages on both costmaps.
  const tasks::Topic<msg::People>* people = nullptr;
  if (n.people_enabled && external_people_ != nullptr) {
    people_relay_task_ = std::make_unique<nav::PeopleRelayTask>(n.person_tracker, *external_people_, nav_people_);
  } else if (n.people_enabled) {
    const nav::CameraCalibration camera;
    if (n.people_detector == "onboard") {
      // The boxes come from the camera's own frames (vision_task.hpp).
#ifdef SEN3BOT_HAS_HOG
      if (!config_.devices.has_camera && external_frames_ == nullptr)
        return Error::format(Errc::config, "%s: navigation.people.detector: onboard needs devices.camera", file);
      VisionTaskConfig vision;
      vision.hog = n.onboard_hog;
      vision.rate_hz = n.onboard_rate_hz;
      vision.calibration_width_px = static_cast<std::uint32_t>(camera.width_px);
      vision.calibration_height_px = static_cast<std::uint32_t>(camera.height_px);
      Result<const RowModule*> module = load_row_module("vision");
      if (!module)
        return Error::format(module.error().code(), "%s: navigation.people.detector: onboard: %s", file, module.error().c_str());
      vision_task_ = ModuleRow<VisionTask>(
          (*module)->vision(vision, frame_source(), nav_detections_));
#else
      return Error::format(Errc::config,
                           "%s: navigation.people.detector: onboard: this build has no on-board detector (it needs "
                           "OpenCV's objdetect module, libopencv-objdetect-dev)",
                           file);
#endif
    } else {
      DetectorTaskConfig detector;
      detector.address = n.people_detector;
      detector.gate.max_age_s = n.detection_max_age_s;
      detector.gate.width_px = static_cast<std::uint16_t>(camera.width_px);
      detector.gate.height_px = static_cast<std::uint16_t>(camera.height_px);
      detector_task_ = std::make_unique<DetectorTask>(detector, board_, nav_detections_);
    }
    nav::PeopleTaskConfig fusion;
    fusion.fusion = n.fusion;
    fusion.tracker = n.person_tracker;
    fusion.camera = camera;
    fusion.laser_mount = mount;
    if (config_.cobot.enabled) fusion.operator_safety_radius_m = config_.cobot.operator_safety_radius_m;
    people_task_ = std::make_unique<nav::PeopleTask>(fusion, map_, nav_scan_, nav_pose_, nav_detections_, nav_people_,
                                                     config_.cobot.enabled ? &nav_cobot_ : nullptr);
    // The rear discs are the only sensor behind the robot: weak evidence for people hidden there.
    if (config_.devices.has_base) people_task_->use_sonar(&nav_sonar_);
  }
  if (n.people_enabled) {
    people = &nav_people_;
    planner.use_people = true;
    planner.people_layer = n.cages;
    planner.use_osgp = n.osgp_enabled;
    planner.osgp = n.osgp;
  }
  planner_task_ =
      std::make_unique<nav::PlannerTask>(planner, map_, waypoints_, nav_goal_, nav_pose_, nav_scan_, nav_path_, people);

  nav::ControllerTaskConfig controller;
  controller.laser_mount = mount;
  controller.dwa = n.dwa;
  controller.dynamic_obstacles = n.dynamic_obstacles;
  controller.local_costmap.width_m = n.local_costmap_size_m;
  controller.local_costmap.height_m = n.local_costmap_size_m;
  // The rolling window shares the static layer's cells: a map of any resolution works.
  controller.local_costmap.resolution_m = map_.resolution_m();
  controller.obstacle = n.local_obstacles;
  controller.use_people = n.people_enabled;
  controller.people_layer = n.cages;
  controller.crossings = n.crossings;
  controller.lanes = n.lanes;
  controller.make_way = n.make_way;
  controller.mover_keep_out_m = n.people_enabled && n.cage_movers ? n.person_tracker.safety_radius_m : 0.0;
  controller_task_ = std::make_unique<nav::ControllerTask>(controller, map_, nav_pose_, nav_odometry_, nav_scan_, nav_path_,
                                                           nav_request_, nav_controller_, nav_movers_, people,
                                                           config_.has_fleet ? &nav_formation_ : nullptr);
  if (config_.devices.has_base) controller_task_->use_sonar(&nav_sonar_);

  nav::SafetyTaskConfig safety;
  safety.safety = n.safety;
  safety.safety.laser_mount = mount;
  safety.safety.mover_cage_m = n.people_enabled && n.cage_movers ? n.person_tracker.safety_radius_m : -1.0;
  if (config_.devices.has_laser)
    safety.safety.scan_period_s =
        hal::to_seconds(lms200::scan_interval_ns(config_.devices.laser.variant, config_.devices.laser.baud));
  safety.safety.reaction_s = hal::to_seconds(kSenseToActBudgetNs);
  // The braking the stop zone counts on is the braking the base driver asks the robot for, or
  // the P3-DX's power-up deceleration when it asks for none.
  constexpr double kPowerUpDecelM_s2 = 0.3;
  safety.safety.decel_m_s2 = config_.devices.has_base && config_.devices.base.trans_decel_mm_s2 > 0
                                 ? config_.devices.base.trans_decel_mm_s2 / 1000.0
                                 : kPowerUpDecelM_s2;
  safety.io_reset_at_start = config_.devices.io_node.reset_at_start;
  safety_task_ = std::make_unique<nav::SafetyTask>(safety, nav_request_, nav_scan_, nav_odometry_, nav_base_flags_,
                                                   nav_pose_, nav_movers_, nav_command_, nav_safety_, people,
                                                   config_.devices.has_io_node ? &nav_io_ : nullptr);
  if (config_.devices.has_base) safety_task_->use_sonar(&nav_sonar_);

  // With the collaborative mode the mission's or the fleet's goals are the cooperative ones:
  // the cobot row passes them on.
  tasks::Topic<msg::NavGoal>& goals = config_.cobot.enabled ? nav_coop_goal_ : nav_goal_;
  if (config_.has_fleet) {
    // The centre's formation commands are refused beyond what the DWA may ask of the robot
    // (and beyond what the base driver would clip it to).
    FleetConfig fleet = config_.fleet;
    fleet.formation_max_v_m_s = n.dwa.max_v_m_s;
    fleet.formation_max_w_rad_s = n.dwa.max_w_rad_s;
    if (config_.devices.has_base && config_.devices.base.max_v_m_s > 0 && config_.devices.base.max_omega_rad_s > 0) {
      fleet.formation_max_v_m_s = std::min(fleet.formation_max_v_m_s, config_.devices.base.max_v_m_s);
      fleet.formation_max_w_rad_s = std::min(fleet.formation_max_w_rad_s, config_.devices.base.max_omega_rad_s);
    }
    fleet_task_ = std::make_unique<FleetTask>(fleet, board_,
                                              FleetTopics{nav_pose_, nav_odometry_, nav_base_flags_, nav_controller_, nav_path_,
                                                          nav_safety_, nav_people_, goals, &nav_formation_});
  } else {
    mission_task_ = std::make_unique<MissionTask>(
        n.mission, MissionTopics{goals, nav_controller_, nav_path_, nav_pose_, nav_safety_});
  }
  if (config_.cobot.enabled) return create_cobot(mount, nav::CameraCalibration{});
  return Status::success();
}

Status Firmware::create_cobot(const msg::SensorMount& mount, const nav::CameraCalibration& camera) {
  const char* file = config_.source_path.c_str();
  const CobotSection& k = config_.cobot;
  Result<ssc::SiteFile> site = ssc::load_site(k.site_path);
  if (!site) return Error::format(site.error().code(), "%s: cobot.site: %s", file, site.error().c_str());
  CobotTaskConfig task = k.task;
  task.laser_mount = mount;
  task.camera = camera;
  task.area_count = 0;
  for (const ssc::Area& a : site->site.areas) {
    if (task.area_count == CobotTaskConfig::kMaxAreas)
      return Error::format(Errc::config, "%s: cobot.site: more than %zu areas", file, CobotTaskConfig::kMaxAreas);
    CobotArea& area = task.areas[task.area_count++];
    switch (a.type) {
      case ssc::AreaType::blind_intersection: area.type = cobot::AreaType::critical_1_1; break;
      case ssc::AreaType::transition: area.type = cobot::AreaType::critical_1_2; break;
      case ssc::AreaType::workstation: area.type = cobot::AreaType::sub_critical_2; break;
      case ssc::AreaType::not_monitored: area.type = cobot::AreaType::not_monitored_3; break;
    }
    if (a.outline.size() > CobotArea::kMaxVertices)
      return Error::format(Errc::config, "%s: cobot.site: an area of more than %zu corners", file, CobotArea::kMaxVertices);
    for (const ssc::Point& p : a.outline) area.outline[area.vertices++] = {p.x, p.y};
  }
  cobot_task_ = std::make_unique<CobotTask>(
      task, CobotTopics{nav_people_, nav_pose_, nav_odometry_, nav_scan_, nav_tags_, nav_coop_goal_, nav_path_,
                        nav_controller_, nav_goal_, nav_cobot_, nav_mode_, nav_worker_path_},
      &map_);
  if (external_frames_ != nullptr || config_.devices.has_camera) {
#ifdef SEN3BOT_HAS_QR
    QrTaskConfig qr;
    qr.rate_hz = k.qr_rate_hz;
    qr.reach_m = k.qr_reach_m;
    qr.band_height_m = task.band_height_m;
    qr.laser_height_m = task.laser_height_m;
    qr.tag_side_m = k.tag_side_m;
    qr.whole_frame = k.qr_whole_frame;
    qr.camera = camera;
    qr.laser_mount = mount;
    Result<const RowModule*> module = load_row_module("qr");
    if (!module) return Error::format(module.error().code(), "%s: cobot: the QR tag reader: %s", file, module.error().c_str());
    qr_task_ = ModuleRow<QrTask>(
        (*module)->qr(qr, frame_source(), QrTopics{nav_people_, nav_pose_, nav_tags_}));
#else
    return Error::format(Errc::config,
                         "%s: cobot: this build has no QR tag reader (it needs OpenCV's objdetect module, "
                         "libopencv-objdetect-dev)",
                         file);
#endif
  }
  if (k.recognition) {
#ifdef SEN3BOT_HAS_RECOGNITION
    RecognitionTaskConfig recognition;
    recognition.operations_path = k.operations_path;
    recognition.model_path = k.model_path;
    recognition.rate_hz = k.recognition_rate_hz;
    Result<const RowModule*> module = load_row_module("recognition");
    if (!module) return Error::format(module.error().code(), "%s: cobot.recognition: %s", file, module.error().c_str());
    recognition_task_ = ModuleRow<RecognitionTask>(
        (*module)->recognition(recognition, RecognitionTopics{nav_worker_path_, nav_operation_, nav_operation_reference_}));
#else
    return Error::format(Errc::config,
                         "%s: cobot.recognition: this build has no operation recognizer (it needs OpenCV's ml module, "
                         "libopencv-ml-dev)",
                         file);
#endif
  }
  return Status::success();
}

Status Firmware::create_tasks() {
  if (config_.devices.has_base)
    base_task_ = std::make_unique<BaseTask>(config_.devices.base, board_,
                                            BaseTopics{nav_command_, nav_odometry_, nav_base_flags_, &nav_sonar_});
  if (config_.devices.has_laser) laser_task_ = std::make_unique<LaserTask>(config_.devices.laser, board_, nav_scan_);
  if (config_.devices.has_io_node)
    can_io_task_ = std::make_unique<CanIoTask>(config_.devices.io_node, board_,
                                               CanIoTopics{nav_safety_, nav_command_, nav_mode_, nav_io_});
  if (config_.devices.has_camera) {
    Result<const RowModule*> module = load_row_module("camera");
    if (!module)
      return Error::format(module.error().code(), "%s: devices.camera: %s", config_.source_path.c_str(), module.error().c_str());
    camera_task_ = ModuleRow<CameraTask>((*module)->camera(config_.devices.camera, board_, bus_, &camera_device_));
  }
  if (config_.navigation.enabled) {
    if (Status s = create_navigation(); !s) return s;
  }
  if (config_.view.enabled) {
    const ViewTaskConfig& view = config_.view.task;
    const double local_s = view.period_s[static_cast<std::size_t>(ViewChannel::local_costmap)];
    if (controller_task_ && local_s > 0)
      controller_task_->publish_costmap(&nav_costmap_snapshot_,
                                        static_cast<int>(std::lround(local_s * 1e6 / static_cast<double>(row("controller").period_us))));
    view_task_ = std::make_unique<ViewTask>(view, view_sources(), external_view_);
  }
  for (const tasks::TaskSpec& row : kTaskTable)
    if (task_named(row.name) != nullptr) rows_.push_back(&row);
  return Status::success();
}

ViewSources Firmware::view_sources() {
  ViewSources s{.scheduler = scheduler_, .clock = board_.clock()};
  s.frames = frame_source();
  s.laser_mount = {config_.laser_mount.x_m, config_.laser_mount.y_m, config_.laser_mount.theta_rad};
  if (config_.devices.has_laser || config_.navigation.enabled) s.scan = &nav_scan_;
  if (!config_.navigation.enabled) return s;
  s.map = &map_;
  s.odometry = &nav_odometry_;
  s.pose = &nav_pose_;
  s.path = &nav_path_;
  s.request = &nav_request_;
  s.safety = &nav_safety_;
  s.controller = &nav_controller_;
  s.movers = &nav_movers_;
  if (people_task_ || people_relay_task_) s.people = &nav_people_;
  if (controller_task_) s.local_costmap = &nav_costmap_snapshot_;
  s.planner = planner_task_.get();
  s.mission = mission_task_.get();
  s.goal_count = config_.navigation.mission.goal_count;
  s.rollout_s = config_.navigation.dwa.sim_time_s;
  return s;
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

  if (Status s = create_tasks(); !s) return s;
  for (const auto& [name, task_config] : config_.tasks) {
    // The view's budget may stay in a configuration whose view is off (sen3bot-sim sim --view
    // turns it on).
    if (name == "view" && !config_.view.enabled) continue;
    if (task_named(name) == nullptr)
      return Error::format(Errc::config, "%s: tasks.%s: this task is not enabled by the configuration (%s)", file,
                           name.c_str(),
                           name == "base" || name == "laser" || name == "camera" ? "needs its device under devices"
                           : name == "can_io"                                   ? "needs devices.io_node"
                           : name == "detector" || name == "people"             ? "needs navigation.people"
                           : name == "vision" ? "needs navigation.people.detector: onboard"
                           : name == "fleet"  ? "needs a fleet section"
                           : name == "cobot" ? "needs a cobot section"
                           : name == "qr" ? "needs a cobot section and a camera"
                           : name == "recognition" ? "needs cobot.recognition"
                           : name == "mission" && config_.has_fleet ? "the fleet gives the goals: no mission"
                                                                                : "needs a navigation section");
  }
  for (const tasks::TaskSpec* row : rows_) {
    if (Status s = scheduler_.add(*row, *task_named(row->name)); !s) return s;
  }
  for (const auto& [name, thread] : config_.threads) {
    bool used = false;
    for (const tasks::TaskSpec* row : rows_) used = used || row->thread == name;
    if (!used) return Error::format(Errc::config, "%s: threads.%s: no task runs on this thread", file, name.c_str());
  }
  for (const tasks::TaskSpec* row_ptr : rows_) {
    const tasks::TaskSpec& row = *row_ptr;
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
  arenas_.reserve(rows_.size());
  for (const tasks::TaskSpec* row_ptr : rows_) {
    const tasks::TaskSpec& row = *row_ptr;
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
  for (const tasks::TaskSpec* row : rows_) task_named(row->name)->shutdown();
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
