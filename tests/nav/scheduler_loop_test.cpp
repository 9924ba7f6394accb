// The navigation tasks composed as the firmware composes them: topics, arenas, and the
// firmware's own task table rows on the fixed-rate scheduler, run in lockstep on a simulated
// clock. A stand-in for the device tasks (on the table's "base" row) plays the Pioneer and the LMS200 in the
// ground-truth world.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <random>
#include <stdexcept>
#include <string_view>

#include "alloc_counter.hpp"
#include "firmware/task_table.hpp"
#include "sen3bot/mem/budget_arena.hpp"
#include "sen3bot/nav/nav_tasks.hpp"
#include "sen3bot/nav/waypoints.hpp"
#include "sen3bot/tasks/scheduler.hpp"
#include "sen3bot/world/world.hpp"

namespace sen3bot::nav {
namespace {

// The firmware's row of a named task. Evaluated at compile time, so a row renamed or removed
// from the table fails the build instead of the test silently using other numbers.
consteval tasks::TaskSpec firmware_row(std::string_view name) {
  for (const tasks::TaskSpec& row : firmware::kTaskTable)
    if (row.name == name) return row;
  throw std::invalid_argument("no such row in firmware::kTaskTable");
}

// Stands in for the base and laser drivers: publishes odometry every step and a scan every
// 100 ms (the rate the safety configuration below expects, whatever the base row's period),
// and moves the robot by the safety task's command (acceleration-limited).
class SimulatedRobot final : public tasks::Task {
 public:
  SimulatedRobot(world::World& truth, const SensorMount& mount, tasks::Topic<ScanMessage>& scan,
                 tasks::Topic<Odometry>& odom, tasks::Topic<BaseFlags>& base, const tasks::Topic<VelocityCommand>& command)
      : truth_(truth), mount_(mount), scan_(scan), odom_(odom), base_(base), command_(command) {
    msg_.count = 361;
    msg_.angle_min_rad = static_cast<float>(-M_PI / 2.0);
    msg_.increment_rad = static_cast<float>(M_PI / 360.0);
    msg_.range_max_m = 8.0f;
  }
  Status init(std::pmr::memory_resource&) override { return Status::success(); }
  void step(const tasks::StepContext& context) override {
    const hal::Nanos now = context.release_ns;
    const double dt = last_ns_ < 0 ? 0.0 : static_cast<double>(now - last_ns_) * 1e-9;
    last_ns_ = now;
    tasks::Sample<VelocityCommand> cmd;
    const bool have = command_.read(cmd);
    const double v_cmd = have ? cmd.value.v_m_s : 0.0;
    const double w_cmd = have ? cmd.value.w_rad_s : 0.0;
    v_ += std::clamp(v_cmd - v_, -0.6 * dt, 0.6 * dt);
    w_ += std::clamp(w_cmd - w_, -2.0 * dt, 2.0 * dt);
    const double th_mid = robot_.theta_rad + w_ * dt / 2.0;
    robot_.x_m += v_ * dt * std::cos(th_mid);
    robot_.y_m += v_ * dt * std::sin(th_mid);
    robot_.theta_rad = normalize_angle(robot_.theta_rad + w_ * dt);
    const double ds = v_ * dt * (1.0 + noise_(rng_));
    const double dth = w_ * dt * (1.0 + noise_(rng_));
    odom_pose_.x_m += ds * std::cos(odom_pose_.theta_rad + dth / 2.0);
    odom_pose_.y_m += ds * std::sin(odom_pose_.theta_rad + dth / 2.0);
    odom_pose_.theta_rad = normalize_angle(odom_pose_.theta_rad + dth);
    if (truth_.collides(robot_, Footprint::pioneer())) ++collisions_;
    truth_.set_time(static_cast<double>(now) * 1e-9);
    base_.publish({false, true}, now);
    odom_.publish({odom_pose_.x_m, odom_pose_.y_m, odom_pose_.theta_rad, v_, w_, now, true}, now);
    if (last_scan_ns_ < 0 || now - last_scan_ns_ >= kScanPeriod_ns) {
      last_scan_ns_ = now;
      truth_.noisy_scan(compose(robot_, mount_), msg_.angle_min_rad, msg_.increment_rad, msg_.count, msg_.range_max_m,
                        std::span<float>(msg_.ranges_m.data(), msg_.count));
      msg_.stamp_ns = now;
      scan_.publish(msg_, now);
    }
  }
  [[nodiscard]] const Pose2D& pose() const noexcept { return robot_; }
  [[nodiscard]] int collisions() const noexcept { return collisions_; }

 private:
  world::World& truth_;
  SensorMount mount_;
  tasks::Topic<ScanMessage>& scan_;
  tasks::Topic<Odometry>& odom_;
  tasks::Topic<BaseFlags>& base_;
  const tasks::Topic<VelocityCommand>& command_;
  ScanMessage msg_;
  Pose2D robot_{2.5, 2.0, M_PI / 2.0};
  Pose2D odom_pose_{2.5, 2.0, M_PI / 2.0};
  double v_ = 0.0;
  double w_ = 0.0;
  static constexpr hal::Nanos kScanPeriod_ns = hal::millis(100);
  hal::Nanos last_ns_ = -1;
  hal::Nanos last_scan_ns_ = -1;
  int collisions_ = 0;
  std::mt19937_64 rng_{7};
  std::normal_distribution<double> noise_{0.0, 0.01};
};

TEST(SchedulerLoop, TaskTableDrivesTheRobotToTheGoal) {
  auto map = load_map(SEN3BOT_SOURCE_DIR "/config/maps/lab.yaml");
  ASSERT_TRUE(map.ok());
  auto waypoints = load_waypoints(SEN3BOT_SOURCE_DIR "/config/maps/lab_waypoints.txt");
  ASSERT_TRUE(waypoints.ok());
  world::WorldConfig wc;
  wc.range_noise_sigma_m = 0.01;
  wc.seed = 42;
  world::World truth(*map, wc);
  const SensorMount mount{0.1, 0.0, 0.0};

  // The bus.
  tasks::Topic<ScanMessage> scan;
  tasks::Topic<Odometry> odom;
  tasks::Topic<BaseFlags> base;
  tasks::Topic<PoseEstimate> pose;
  tasks::Topic<NavGoal> goal;
  tasks::Topic<PathMessage> path;
  tasks::Topic<VelocityCommand> request;
  tasks::Topic<ControllerStatus> controller_status;
  tasks::Topic<VelocityCommand> command;
  tasks::Topic<SafetyOutput> safety_status;

  // Arenas: the measured sizes plus headroom (docs/navigation.md),
  // declared before the tasks so they outlive them.
  mem::BudgetArena safety_arena("safety", 1024);
  mem::BudgetArena localization_arena("localization", 1 << 20);
  mem::BudgetArena controller_arena("controller", 1 << 20);
  mem::BudgetArena planner_arena("planner", 2 << 20);
  LocalizationTaskConfig lc;
  lc.mcl.initial_pose = {2.5, 2.0, M_PI / 2.0};
  lc.mcl.initial_std_xy_m = 0.1;
  lc.mcl.initial_std_theta_rad = 0.1;
  lc.mcl.sigma_hit_m = 0.1;
  lc.mcl.alpha1 = lc.mcl.alpha2 = lc.mcl.alpha3 = lc.mcl.alpha4 = 0.05;
  lc.mcl.update_min_d_m = 0.1;
  lc.mcl.update_min_a_rad = 0.1;
  lc.mcl.laser_mount = mount;
  PlannerTaskConfig pc;
  pc.laser_mount = mount;
  ControllerTaskConfig cc;
  cc.laser_mount = mount;
  SafetyTaskConfig sc;
  sc.safety.scan_period_s = 0.1;
  sc.safety.laser_mount = mount;

  SimulatedRobot robot(truth, mount, scan, odom, base, command);
  tasks::Topic<msg::MovingObstacles> movers;
  SafetyTask safety(sc, {request, scan, odom, base, pose, movers, command, safety_status});
  LocalizationTask localization(lc, *map, {scan, odom, pose});
  ControllerTask controller(cc, *map, {pose, odom, scan, path, request, controller_status, movers});
  PlannerTask planner(pc, *map, *waypoints, {goal, pose, scan, path});

  ASSERT_TRUE(safety.init(safety_arena));
  ASSERT_TRUE(localization.init(localization_arena));
  ASSERT_TRUE(controller.init(controller_arena));
  ASSERT_TRUE(planner.init(planner_arena));

  // The firmware's rows for these tasks: period, budget, priority and thread as on the robot.
  hal::SimClock clock;
  tasks::Scheduler scheduler(clock);
  ASSERT_TRUE(scheduler.add(firmware_row("base"), robot));
  ASSERT_TRUE(scheduler.add(firmware_row("safety"), safety));
  ASSERT_TRUE(scheduler.add(firmware_row("localization"), localization));
  ASSERT_TRUE(scheduler.add(firmware_row("controller"), controller));
  ASSERT_TRUE(scheduler.add(firmware_row("planner"), planner));

  goal.publish({4.0, 7.0, 1, true}, 0);
  mem::testing::AllocationScope scope;
  bool reached = false;
  for (int second = 0; second < 40 && !reached; ++second) {
    ASSERT_TRUE(scheduler.run_lockstep(clock, 1'000'000'000));
    tasks::Sample<ControllerStatus> status;
    reached = controller_status.read(status) && status.value.status == DwaStatus::reached;
  }
  const auto allocations = scope.allocations();
  EXPECT_TRUE(reached);
  EXPECT_EQ(robot.collisions(), 0);
  EXPECT_EQ(allocations, 0u);
  EXPECT_LT(std::hypot(robot.pose().x_m - 4.0, robot.pose().y_m - 7.0), 0.25);
  // The simulated clock never moved inside a step, yet every task's cost was measured.
  for (std::size_t i = 0; i < scheduler.task_count(); ++i)
    EXPECT_GT(scheduler.stats(i).cpu_max_ns, 0) << scheduler.spec(i).name;
  scheduler.print_stats(stdout);
}

}  // namespace
}  // namespace sen3bot::nav
