// Lockstep closed loop: the navigation tasks drive a simulated Pioneer (unicycle with
// acceleration limits) in the ground-truth world of lab.yaml, seeing an ideal laser with
// seeded noise and odometry with seeded drift. Deterministic: simulated time, fixed seeds.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/mem/budget_arena.hpp"
#include "sen3bot/nav/nav_tasks.hpp"
#include "sen3bot/nav/waypoints.hpp"
#include "sen3bot/world/world.hpp"

namespace sen3bot::nav {
namespace {

constexpr hal::Nanos kTickNs = 50'000'000;  // 20 Hz base tick

struct Outcome {
  bool reached = false;
  int collisions = 0;
  double time_s = 0.0;
  double rms_error_m = 0.0;
  double max_error_m = 0.0;
  bool safety_stopped_for_obstacle = false;
  int forward_in_stop_zone = 0;  // ticks commanding forward with something inside the stop zone
  std::uint64_t step_allocations = 0;
  std::uint32_t recoveries = 0;
  std::uint32_t plans = 0;
  std::size_t arena_bytes[4] = {};
};

// blind_forward replaces the controller by a constant forward request (a planner that does
// not see the person): only the safety task stands between the robot and the person.
// box_before_planning / box_during_motion are the thesis' cases 2 and 3: a 0.4 m box on the
// waypoint route, seen before the first plan, or appearing while the robot drives.
enum class Scenario { plain, person_crossing, blind_forward, box_before_planning, box_during_motion };

Outcome run(Scenario scenario) {
  auto map_result = load_map(SEN3BOT_SOURCE_DIR "/config/maps/lab.yaml");
  EXPECT_TRUE(map_result.ok());
  const OccupancyMap map = std::move(*map_result);
  auto waypoints = load_waypoints(SEN3BOT_SOURCE_DIR "/config/maps/lab_waypoints.txt");
  EXPECT_TRUE(waypoints.ok());
  world::WorldConfig wc;
  wc.range_noise_sigma_m = 0.01;
  wc.seed = 42;
  world::World truth(map, wc);
  const Footprint footprint = Footprint::pioneer();
  const SensorMount mount{0.1, 0.0, 0.0};

  tasks::Topic<ScanMessage> scan_topic;
  tasks::Topic<Odometry> odom_topic;
  tasks::Topic<PoseEstimate> pose_topic;
  tasks::Topic<NavGoal> goal_topic;
  tasks::Topic<PathMessage> path_topic;
  tasks::Topic<VelocityCommand> request_topic;
  tasks::Topic<ControllerStatus> controller_topic;
  tasks::Topic<BaseFlags> base_topic;
  tasks::Topic<VelocityCommand> command_topic;
  tasks::Topic<SafetyOutput> safety_topic;

  // Arenas before tasks: they must outlive them.
  mem::BudgetArena arenas[4] = {{"localization", 2 << 20}, {"planner", 2 << 20}, {"controller", 1 << 20}, {"safety", 1024}};
  LocalizationTaskConfig lc;
  lc.mcl.initial_pose = {2.5, 2.0, M_PI / 2.0};
  lc.mcl.initial_std_xy_m = 0.1;
  lc.mcl.initial_std_theta_rad = 0.1;
  lc.mcl.sigma_hit_m = 0.1;
  lc.mcl.alpha1 = lc.mcl.alpha2 = lc.mcl.alpha3 = lc.mcl.alpha4 = 0.05;
  lc.mcl.update_min_d_m = 0.1;
  lc.mcl.update_min_a_rad = 0.1;
  lc.mcl.update_max_interval_s = 1.0;
  // Random-particle injection stays off (the default): with it, case 3 here ends in a
  // standstill next to the box (docs/navigation.md, not done yet). Recovery has tests of its own.
  lc.mcl.laser_mount = mount;
  PlannerTaskConfig pc;
  pc.laser_mount = mount;
  ControllerTaskConfig cc;
  cc.laser_mount = mount;
  cc.dwa.footprint_check_min_cost = 1;
  SafetyTaskConfig sc;
  sc.safety.scan_period_s = 0.1;
  sc.safety.laser_mount = mount;

  LocalizationTask localization(lc, map, {scan_topic, odom_topic, pose_topic});
  PlannerTask planner(pc, map, *waypoints, {goal_topic, pose_topic, scan_topic, path_topic});
  tasks::Topic<msg::MovingObstacles> movers_topic;
  ControllerTask controller(cc, map,
                            {pose_topic, odom_topic, scan_topic, path_topic, request_topic, controller_topic, movers_topic});
  SafetyTask safety(sc, {request_topic, scan_topic, odom_topic, base_topic, pose_topic, movers_topic, command_topic,
                         safety_topic});
  tasks::Task* all[4] = {&localization, &planner, &controller, &safety};
  for (int i = 0; i < 4; ++i) {
    const Status s = all[i]->init(arenas[i]);
    EXPECT_TRUE(s.ok()) << s.error().c_str();
  }
  Outcome outcome;
  for (int i = 0; i < 4; ++i) outcome.arena_bytes[i] = arenas[i].used_bytes();

  Pose2D robot{2.5, 2.0, M_PI / 2.0};
  Pose2D odom = robot;
  double v = 0.0;
  double w = 0.0;
  std::mt19937_64 rng(7);
  std::normal_distribution<double> noise(0.0, 0.01);
  ScanMessage scan;
  scan.count = 361;
  scan.angle_min_rad = static_cast<float>(-M_PI / 2.0);
  scan.increment_rad = static_cast<float>(M_PI / 360.0);
  scan.range_max_m = 8.0f;
  if (scenario == Scenario::box_before_planning || scenario == Scenario::box_during_motion) {
    world::MoverScript box;
    // Case 2: on the route below the door, there from the start. Case 3: on the route above
    // the door, appearing when the robot is about 2 m short of it.
    const bool during = scenario == Scenario::box_during_motion;
    box.path = {during ? world::Point2D{3.35, 5.86} : world::Point2D{2.8, 3.3}};
    box.size_m = 0.4;
    box.shape = world::MoverShape::square;
    box.appear_time_s = during ? 4.0 : 0.0;
    truth.add_mover(box);
  }
  base_topic.publish({false, true}, 0);
  goal_topic.publish({4.0, 7.0, 1, true}, 0);
  double sum_err2 = 0.0;
  int err_samples = 0;
  bool person_added = false;
  const int max_ticks = scenario == Scenario::blind_forward ? 20 * 10 : 20 * 120;
  for (int tick = 0; tick < max_ticks; ++tick) {
    const hal::Nanos now = tick * kTickNs;
    truth.set_time(static_cast<double>(now) * 1e-9);
    // Sensors.
    odom_topic.publish({odom.x_m, odom.y_m, odom.theta_rad, v, w, now, true}, now);
    if (tick % 2 == 0) {
      const Pose2D sensor = compose(robot, mount);
      truth.noisy_scan(sensor, scan.angle_min_rad, scan.increment_rad, scan.count, scan.range_max_m,
                       std::span<float>(scan.ranges_m.data(), scan.count));
      scan.stamp_ns = now;
      scan_topic.publish(scan, now);
    }
    // Tasks, in the task table's priority order: safety last so it sees this tick's request.
    {
      mem::testing::AllocationScope scope;
      const tasks::StepContext ctx{now, now, static_cast<std::uint64_t>(tick)};
      localization.step(ctx);
      // The first plan waits for the first scan (tick 2), so a box already there is in it.
      if (tick % 10 == 2) planner.step(ctx);
      if (scenario == Scenario::blind_forward) {
        request_topic.publish({0.4, 0.0, now}, now);
      } else if (tick % 2 == 0) {
        controller.step(ctx);
      }
      safety.step(ctx);
      outcome.step_allocations += scope.allocations();
    }
    tasks::Sample<PoseEstimate> est;
    if (pose_topic.read(est) && est.value.updates > 3) {
      const double e = std::hypot(est.value.pose.x_m - robot.x_m, est.value.pose.y_m - robot.y_m);
      sum_err2 += e * e;
      ++err_samples;
      outcome.max_error_m = std::max(outcome.max_error_m, e);
    }
    tasks::Sample<SafetyOutput> safe;
    if (safety_topic.read(safe)) {
      if ((safe.value.reasons & kSafetyObstacle) != 0) outcome.safety_stopped_for_obstacle = true;
      // Whoever decided it, nothing moves forward into the stop zone.
      if (safe.value.nearest_ahead_m <= safe.value.stop_distance_m && safe.value.command.v_m_s > 0.0) {
        ++outcome.forward_in_stop_zone;
      }
    }
    tasks::Sample<ControllerStatus> status;
    if (std::getenv("LOOP_TRACE") != nullptr && tick % 20 == 0 && controller_topic.read(status)) {
      tasks::Sample<PathMessage> p;
      (void)path_topic.read(p);
      std::printf("t=%.1f robot %.2f %.2f %.2f ctrl %s plan %s exp %u wp %u len %.2f\n", static_cast<double>(now) * 1e-9,
                  robot.x_m, robot.y_m, robot.theta_rad, to_string(status.value.status), to_string(p.value.status),
                  p.value.expansions, p.value.waypoints_passed, p.value.length_m);
    }
    if (controller_topic.read(status) && status.value.status == DwaStatus::reached) {
      outcome.reached = true;
      outcome.time_s = static_cast<double>(now) * 1e-9;
      outcome.recoveries = status.value.recoveries.total();
      break;
    }
    // A person steps out from behind cover just ahead of the robot, a little to its right:
    // inside the braking corridor, but not blocking every arc to the left, so the local
    // planner may still ask to move and the safety filter has to stop it. The person stands
    // there for two seconds, then walks off to the right.
    if ((scenario == Scenario::person_crossing || scenario == Scenario::blind_forward) && !person_added &&
        robot.y_m > 3.0) {
      world::MoverScript person;
      const double ahead = 0.2275 + 0.3 + 0.2;  // 0.3 m from the front edge to the person's edge
      const double right = scenario == Scenario::blind_forward ? 0.0 : 0.3;
      const double c = std::cos(robot.theta_rad);
      const double s = std::sin(robot.theta_rad);
      const double px = robot.x_m + ahead * c + right * s;
      const double py = robot.y_m + ahead * s - right * c;
      person.path = {{px, py}, {px + 3.0 * s, py - 3.0 * c}};
      person.speed_m_s = 0.6;
      person.size_m = 0.4;
      person.person = true;
      person.appear_time_s = static_cast<double>(now) * 1e-9;
      person.start_time_s = person.appear_time_s + 2.0;
      person.vanish_time_s = person.appear_time_s + 6.0;
      truth.add_mover(person);
      person_added = true;
    }
    // The base: the safety task's command, with the Pioneer's acceleration limits.
    tasks::Sample<VelocityCommand> cmd;
    double v_cmd = 0.0;
    double w_cmd = 0.0;
    if (command_topic.read(cmd)) {
      v_cmd = cmd.value.v_m_s;
      w_cmd = cmd.value.w_rad_s;
    }
    const double dt = static_cast<double>(kTickNs) * 1e-9;
    v += std::clamp(v_cmd - v, -0.6 * dt, 0.6 * dt);
    w += std::clamp(w_cmd - w, -2.0 * dt, 2.0 * dt);
    const double th_mid = robot.theta_rad + w * dt / 2.0;
    robot.x_m += v * dt * std::cos(th_mid);
    robot.y_m += v * dt * std::sin(th_mid);
    robot.theta_rad = normalize_angle(robot.theta_rad + w * dt);
    const double ds = v * dt * (1.0 + noise(rng));
    const double dth = w * dt * (1.0 + noise(rng));
    odom.x_m += ds * std::cos(odom.theta_rad + dth / 2.0);
    odom.y_m += ds * std::sin(odom.theta_rad + dth / 2.0);
    odom.theta_rad = normalize_angle(odom.theta_rad + dth);
    if (truth.collides(robot, footprint)) {
      if (outcome.collisions == 0 && std::getenv("LOOP_TRACE") != nullptr) std::printf("first collision t=%.2f at %.3f %.3f %.3f v %.2f\n", static_cast<double>(now) * 1e-9, robot.x_m, robot.y_m, robot.theta_rad, v);
      ++outcome.collisions;
    }
  }
  outcome.rms_error_m = err_samples > 0 ? std::sqrt(sum_err2 / err_samples) : 1e9;
  outcome.plans = planner.plans();
  std::printf("reached %d in %.1f s, collisions %d, localization RMS %.3f m (max %.3f), recoveries %u, plans %u, "
              "safety obstacle stop %d, arenas %zu/%zu/%zu/%zu B\n",
              outcome.reached, outcome.time_s, outcome.collisions, outcome.rms_error_m, outcome.max_error_m,
              outcome.recoveries, outcome.plans, outcome.safety_stopped_for_obstacle, outcome.arena_bytes[0],
              outcome.arena_bytes[1], outcome.arena_bytes[2], outcome.arena_bytes[3]);
  return outcome;
}

TEST(ClosedLoop, ThesisQueryReachesTheGoalWithoutCollision) {
  const Outcome o = run(Scenario::plain);
  EXPECT_TRUE(o.reached);
  EXPECT_EQ(o.collisions, 0);
  EXPECT_LT(o.rms_error_m, 0.1);
  EXPECT_EQ(o.step_allocations, 0u);
}

TEST(ClosedLoop, StopsForAPersonSteppingOutAndThenReachesTheGoal) {
  // The local planner usually stops first (it sees the same scan); either way nothing may
  // command forward motion while the person is inside the stop zone.
  const Outcome o = run(Scenario::person_crossing);
  EXPECT_EQ(o.forward_in_stop_zone, 0);
  EXPECT_EQ(o.collisions, 0);
  EXPECT_TRUE(o.reached);
  EXPECT_EQ(o.step_allocations, 0u);
}

TEST(ClosedLoop, SafetyAloneStopsABlindForwardRequestForAPerson) {
  const Outcome o = run(Scenario::blind_forward);
  EXPECT_TRUE(o.safety_stopped_for_obstacle);
  EXPECT_EQ(o.forward_in_stop_zone, 0);
  EXPECT_EQ(o.collisions, 0);
}

}  // namespace
}  // namespace sen3bot::nav

namespace sen3bot::nav {
namespace {

TEST(ClosedLoop, ThesisCase2BoxSeenBeforePlanning) {
  const Outcome o = run(Scenario::box_before_planning);
  EXPECT_TRUE(o.reached);
  EXPECT_EQ(o.collisions, 0);
  EXPECT_EQ(o.step_allocations, 0u);
}

}  // namespace
}  // namespace sen3bot::nav

namespace sen3bot::nav {
namespace {

TEST(ClosedLoop, ThesisCase3BoxAppearsDuringMotion) {
  const Outcome o = run(Scenario::box_during_motion);
  EXPECT_TRUE(o.reached);
  EXPECT_EQ(o.collisions, 0);
  EXPECT_EQ(o.step_allocations, 0u);
}

}  // namespace
}  // namespace sen3bot::nav
