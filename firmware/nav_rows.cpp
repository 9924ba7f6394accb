// Navigation's rows (task_table.hpp): localization, the people's fusion, the local and global
// planners and the safety filter, each built from its configuration and its topics.
#include <algorithm>

#include "safe_curve.hpp"
#include "sen3bot/lms200/device.hpp"
#include "sen3bot/nav/nav_tasks.hpp"
#include "task_table.hpp"
#include "wiring.hpp"

namespace sen3bot::firmware {

namespace {

constexpr const char* kNeedsNavigation = "needs a navigation section";

// Whether the people row runs (fusing a detector's boxes, or relaying people known otherwise).
bool people_on(const Wiring& w) { return w.config.navigation.enabled && w.config.navigation.people_enabled; }
bool cage_movers(const Wiring& w) { return people_on(w) && w.config.navigation.cage_movers; }

}  // namespace

Status make_localization(Wiring& w) {
  if (!w.config.navigation.enabled) return w.absent(kNeedsNavigation);
  nav::LocalizationTaskConfig localization;
  localization.mcl = w.config.navigation.mcl;
  localization.mcl.laser_mount = w.shared.laser_mount;
  w.make<nav::LocalizationTask>(
      localization, w.shared.map,
      nav::LocalizationTopics{w.reads(&Topics::scan), w.reads(&Topics::odometry), w.writes(&Topics::pose)});
  return Status::success();
}

Status make_people(Wiring& w) {
  const NavigationSection& n = w.config.navigation;
  if (!people_on(w)) return w.absent("needs navigation.people");
  if (w.shared.external_people != nullptr) {
    w.takes("people known without sensing (a simulator's ground truth)");
    w.make<nav::PeopleRelayTask>(n.person_tracker, *w.shared.external_people, w.writes(&Topics::people));
    return Status::success();
  }
  nav::PeopleTaskConfig fusion;
  fusion.fusion = n.fusion;
  fusion.tracker = n.person_tracker;
  fusion.camera = nav::CameraCalibration{};
  fusion.laser_mount = w.shared.laser_mount;
  if (w.config.cobot.enabled) fusion.operator_safety_radius_m = w.config.cobot.operator_safety_radius_m;
  w.make<nav::PeopleTask>(
      fusion, w.shared.map,
      nav::PeopleTopics{.scan = w.reads(&Topics::scan),
                        .pose = w.reads(&Topics::pose),
                        .detections = w.reads(&Topics::detections),
                        .people = w.writes(&Topics::people),
                        .cobot = w.reads_if(w.config.cobot.enabled, &Topics::cobot_state),
                        // The rear discs are the only sensor behind the robot.
                        .sonar = w.reads_if(w.config.devices.has_base, &Topics::sonar)});
  return Status::success();
}

Status make_controller(Wiring& w) {
  const NavigationSection& n = w.config.navigation;
  if (!n.enabled) return w.absent(kNeedsNavigation);
  nav::ControllerTaskConfig controller;
  controller.laser_mount = w.shared.laser_mount;
  controller.dwa = n.dwa;
  controller.dynamic_obstacles = n.dynamic_obstacles;
  controller.local_costmap.width_m = n.local_costmap_size_m;
  controller.local_costmap.height_m = n.local_costmap_size_m;
  // The rolling window shares the static layer's cells: a map of any resolution works.
  controller.local_costmap.resolution_m = w.shared.map.resolution_m();
  controller.obstacle = n.local_obstacles;
  controller.use_people = people_on(w);
  controller.people_layer = n.cages;
  controller.crossings = n.crossings;
  controller.lanes = n.lanes;
  controller.make_way = n.make_way;
  controller.mover_keep_out_m = cage_movers(w) ? n.person_tracker.safety_radius_m : 0.0;
  nav::ControllerTask& task = w.make<nav::ControllerTask>(
      controller, w.shared.map,
      nav::ControllerTopics{.pose = w.reads(&Topics::pose),
                            .odometry = w.reads(&Topics::odometry),
                            .scan = w.reads(&Topics::scan),
                            .path = w.reads(&Topics::path),
                            .request = w.writes(&Topics::request),
                            .status = w.writes(&Topics::controller_status),
                            .movers = w.writes(&Topics::movers),
                            .people = w.reads_if(people_on(w), &Topics::people),
                            .formation = w.reads_if(w.config.has_fleet, &Topics::formation),
                            .sonar = w.reads_if(w.config.devices.has_base, &Topics::sonar)});
  // The live view's local costmap channel, every few cycles of this row.
  const double local_s = w.config.view.task.period_s[static_cast<std::size_t>(ViewChannel::local_costmap)];
  if (w.config.view.enabled && local_s > 0)
    task.publish_costmap(w.writes_if(true, &Topics::local_costmap),
                         static_cast<int>(std::lround(local_s * 1e6 / static_cast<double>(row("controller").period_us))));
  return Status::success();
}

Status make_planner(Wiring& w) {
  const NavigationSection& n = w.config.navigation;
  if (!n.enabled) return w.absent(kNeedsNavigation);
  nav::PlannerTaskConfig planner;
  planner.laser_mount = w.shared.laser_mount;
  if (!n.safe_curve_path.empty()) {
    Result<SiteCurve> curve = load_safe_curve(n.safe_curve_path);
    if (!curve)
      return Error::format(curve.error().code(), "%s: navigation.safe_curve: %s", w.file(), curve.error().c_str());
    planner.use_sgp = true;
    planner.sgp = n.sgp;
    planner.curve = curve->curve;
    planner.curve_bounds = curve->has_bounds ? curve->bounds : nav::map_extent(w.shared.map);
  }
  if (people_on(w)) {
    planner.use_people = true;
    planner.people_layer = n.cages;
    planner.use_osgp = n.osgp_enabled;
    planner.osgp = n.osgp;
  }
  w.make<nav::PlannerTask>(planner, w.shared.map, w.shared.waypoints,
                           nav::PlannerTopics{w.reads(&Topics::goal), w.reads(&Topics::pose), w.reads(&Topics::scan),
                                              w.writes(&Topics::path), w.reads_if(people_on(w), &Topics::people)});
  return Status::success();
}

Status make_safety(Wiring& w) {
  const NavigationSection& n = w.config.navigation;
  if (!n.enabled) return w.absent(kNeedsNavigation);
  const DevicesConfig& devices = w.config.devices;
  nav::SafetyTaskConfig safety;
  safety.safety = n.safety;
  safety.safety.laser_mount = w.shared.laser_mount;
  safety.safety.mover_cage_m = cage_movers(w) ? n.person_tracker.safety_radius_m : -1.0;
  if (devices.has_laser)
    safety.safety.scan_period_s = hal::to_seconds(lms200::scan_interval_ns(devices.laser.variant, devices.laser.baud));
  safety.safety.reaction_s = hal::to_seconds(kSenseToActBudgetNs);
  // The braking the stop zone counts on is the braking the base driver asks the robot for, or
  // the P3-DX's power-up deceleration when it asks for none.
  constexpr double kPowerUpDecelM_s2 = 0.3;
  safety.safety.decel_m_s2 =
      devices.has_base && devices.base.trans_decel_mm_s2 > 0 ? devices.base.trans_decel_mm_s2 / 1000.0 : kPowerUpDecelM_s2;
  safety.io_reset_at_start = devices.io_node.reset_at_start;
  w.make<nav::SafetyTask>(safety, nav::SafetyTopics{.request = w.reads(&Topics::request),
                                                    .scan = w.reads(&Topics::scan),
                                                    .odometry = w.reads(&Topics::odometry),
                                                    .base_flags = w.reads(&Topics::base_flags),
                                                    .pose = w.reads(&Topics::pose),
                                                    .movers = w.reads(&Topics::movers),
                                                    .command = w.writes(&Topics::command),
                                                    .status = w.writes(&Topics::safety_output),
                                                    .people = w.reads_if(people_on(w), &Topics::people),
                                                    .io = w.reads_if(devices.has_io_node, &Topics::safety_io),
                                                    .sonar = w.reads_if(devices.has_base, &Topics::sonar)});
  return Status::success();
}

}  // namespace sen3bot::firmware
