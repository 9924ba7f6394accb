// The device tasks, where composition makes a driver a task: links come from the board, the
// bus carries the vocabulary's messages, a failed link is reopened through the board.
#include <gtest/gtest.h>

#include <array>
#include <functional>
#include <memory_resource>
#include <vector>

#include "base_task.hpp"
#include "laser_task.hpp"
#include "lockstep_harness.hpp"
#include "pipe_board.hpp"
#include "sen3bot/sim/lms200/emulator.hpp"
#include "sen3bot/sim/p2os/emulator.hpp"
#include "sen3bot/sim/p2os/emulator_runner.hpp"

namespace sen3bot::firmware {
namespace {

p2os::EmulatorConfig brisk_robot() { return p2os::test::fast_emulator_config(); }

struct BaseRig {
  hal::MemoryPipe pipe{16384};
  p2os::P2osEmulator emulator{brisk_robot()};
  testing::PipeBoard board{hal::seconds(1)};
  tasks::Topic<msg::VelocityCommand> command;
  tasks::Topic<msg::Odometry> odometry;
  tasks::Topic<msg::BaseFlags> flags;
  std::array<std::byte, 64 * 1024> buffer{};
  std::pmr::monotonic_buffer_resource arena{buffer.data(), buffer.size(), std::pmr::null_memory_resource()};
  BaseTask task{p2os::P2osConfig{}, board, BaseTopics{command, odometry, flags}};
  std::uint64_t cycle = 0;

  BaseRig() { board.attach("base", pipe.a()); }
  void run(hal::Nanos duration, double v_m_s) {
    hal::SimClock& clock = board.sim_clock();
    const hal::Nanos end = clock.now() + duration;
    while (clock.now() < end) {
      (void)emulator.step(pipe.b(), clock.now());
      if (cycle % 25 == 0) command.publish(msg::VelocityCommand{v_m_s, 0.0}, clock.now());
      task.step(tasks::StepContext{clock.now(), clock.now(), cycle++});
      clock.advance_by(hal::millis(2));
    }
  }
};

TEST(BaseTask, PublishesOdometryEverySipAndFollowsTheCommand) {
  BaseRig rig;
  ASSERT_TRUE(rig.task.init(rig.arena));
  EXPECT_EQ(rig.board.opens("base"), 1);
  rig.run(hal::seconds(3), 0.25);
  tasks::Sample<msg::Odometry> odom;
  ASSERT_TRUE(rig.odometry.read(odom));
  EXPECT_TRUE(odom.value.valid);
  const std::uint64_t sips = rig.task.driver()->state().sip_count;
  EXPECT_GE(sips, 25u);
  EXPECT_GE(rig.odometry.published(), sips);
  EXPECT_NEAR(odom.value.v_m_s, 0.25, 0.002);
  EXPECT_GT(odom.value.x_m, 0.3);
  EXPECT_NEAR(rig.emulator.velocity_m_s(), 0.25, 1e-9);
  tasks::Sample<msg::BaseFlags> flags;
  ASSERT_TRUE(rig.flags.read(flags));
  EXPECT_TRUE(flags.value.motors_enabled);
  EXPECT_FALSE(flags.value.estop);
}

TEST(BaseTask, ReopensThroughTheBoardAfterTheLinkFails) {
  BaseRig rig;
  ASSERT_TRUE(rig.task.init(rig.arena));
  rig.run(hal::seconds(2), 0.2);
  rig.pipe.b().disconnect();
  rig.run(hal::millis(100), 0.2);
  tasks::Sample<msg::Odometry> odom;
  ASSERT_TRUE(rig.odometry.read(odom));
  EXPECT_FALSE(odom.value.valid);  // the link went: the odometry says so at once
  rig.pipe.reset();
  rig.emulator.reset_session();
  rig.run(hal::seconds(2), 0.2);
  EXPECT_EQ(rig.board.opens("base"), 2);
  ASSERT_TRUE(rig.odometry.read(odom));
  EXPECT_TRUE(odom.value.valid);
  EXPECT_EQ(rig.task.driver()->state().link, p2os::LinkState::connected);
  rig.task.shutdown();
  (void)rig.emulator.step(rig.pipe.b(), rig.board.clock().now());
  EXPECT_EQ(rig.emulator.state(), p2os::EmulatorState::sync_wait);  // CLOSE went out
}

TEST(BaseTask, ConnectsToATcpSimulatorAndReconnectsAfterADrop) {
  auto runner = p2os::TcpEmulatorRunner::start(brisk_robot(), 0);
  ASSERT_TRUE(runner) << runner.error().c_str();
  p2os::TcpEmulatorRunner& emu = **runner;
  p2os::P2osConfig config;
  config.port = "tcp://127.0.0.1:" + std::to_string(emu.port());
  config.reopen_delay_ms = 100;
  hal::PosixBoard board;
  tasks::Topic<msg::VelocityCommand> command;
  tasks::Topic<msg::Odometry> odometry;
  tasks::Topic<msg::BaseFlags> flags;
  std::array<std::byte, 64 * 1024> buffer;
  std::pmr::monotonic_buffer_resource arena(buffer.data(), buffer.size(), std::pmr::null_memory_resource());
  BaseTask task(config, board, BaseTopics{command, odometry, flags});
  ASSERT_TRUE(task.init(arena));
  hal::Clock& clock = board.clock();
  std::uint64_t cycle = 0;
  auto run_until = [&](const std::function<bool(const msg::Odometry&)>& done, hal::Nanos max_ns) {
    const hal::Nanos end = clock.now() + max_ns;
    while (clock.now() < end) {
      const hal::Nanos now = clock.now();
      command.publish(msg::VelocityCommand{0.4, 0.0}, now);
      task.step(tasks::StepContext{now, now, cycle++});
      tasks::Sample<msg::Odometry> s;
      if (odometry.read(s) && done(s.value)) return true;
      clock.sleep_until(now + hal::millis(2));
    }
    return false;
  };
  ASSERT_TRUE(run_until([](const msg::Odometry& o) { return o.valid && o.v_m_s > 0.39; }, hal::seconds(5)));
  emu.drop_client();
  ASSERT_TRUE(run_until([](const msg::Odometry& o) { return !o.valid; }, hal::seconds(2)));
  ASSERT_TRUE(run_until([](const msg::Odometry& o) { return o.valid && o.v_m_s > 0.39; }, hal::seconds(5)));
  EXPECT_GE(emu.clients_served(), 2u);
  task.shutdown();
}

TEST(LaserTask, PublishesNavigationScansFromTheBoardsLink) {
  hal::MemoryPipe pipe(16384);
  lms200::WallWorld world = lms200::WallWorld::room_with_box(8.0, 6.0, 6.0, 3.0, 1.0);
  lms200::SimulatedLine line;
  lms200::Lms200Emulator emulator(lms200::EmulatorOptions{}, pipe.b(), world, &line);
  testing::PipeBoard board;
  board.attach("laser", pipe.a(), &line);
  tasks::Topic<msg::ScanMessage> topic;
  lms200::Lms200Config c;
  c.port = "sim";
  c.baud = 500000;
  c.variant = {180, 100};
  // The arena is exactly the declared budget over the null resource: init fits in it.
  std::vector<std::byte> budget(LaserTask::kArenaBytes);
  std::pmr::monotonic_buffer_resource arena(budget.data(), budget.size(), std::pmr::null_memory_resource());
  LaserTask task(c, board, topic);  // after the arena: it gives its memory back first
  ASSERT_TRUE(task.init(arena));
  EXPECT_EQ(board.opens("laser"), 1);
  for (hal::Nanos now = 0; now < hal::seconds(2); now += hal::millis(1)) {
    emulator.step(now);
    task.step({now, now, static_cast<std::uint64_t>(now / hal::millis(1))});
  }
  EXPECT_EQ(line.baud(), 500000u);  // the device switched the line through the board's control
  ASSERT_GT(topic.published(), 50u);
  tasks::Sample<msg::ScanMessage> scan;
  ASSERT_TRUE(topic.read(scan));
  EXPECT_EQ(scan.value.count, 181);
  EXPECT_GT(scan.value.range_max_m, 7.0f);
  int in_room = 0;
  for (std::size_t i = 0; i < scan.value.count; ++i)
    if (scan.value.ranges_m[i] > 0.5f && scan.value.ranges_m[i] < 6.0f) ++in_room;
  EXPECT_GT(in_room, 150);  // walls of an 8 m x 6 m room seen from inside
}

TEST(LaserTask, RejectsAVariantTheScannerDoesNotHave) {
  testing::PipeBoard board;
  tasks::Topic<msg::ScanMessage> topic;
  std::vector<std::byte> budget(1 << 16);
  std::pmr::monotonic_buffer_resource arena(budget.data(), budget.size(), std::pmr::null_memory_resource());
  lms200::Lms200Config bad;
  bad.variant = {180, 25};
  EXPECT_EQ(LaserTask(bad, board, topic).init(arena).error().code(), Errc::config);
}

// Steps a task every 5 ms of simulated time, calling `each` (the far end's emulator) first.
void step_for(tasks::Task& task, hal::SimClock& clock, std::uint64_t& cycle, hal::Nanos duration,
              const std::function<void()>& each) {
  const hal::Nanos end = clock.now() + duration;
  while (clock.now() < end) {
    if (each) each();
    task.step(tasks::StepContext{clock.now(), clock.now(), cycle++});
    clock.advance_by(hal::millis(5));
  }
}

// Opens at 0, 0.5, 1.5, 3.5 and 7.5 s: restart/reopen delay 500 ms doubling to the 5 s cap.
constexpr int kAttemptsInTenSeconds = 5;

TEST(LaserTask, StartsWithoutItsDeviceReportsItAndRetriesWithBackoff) {
  testing::PipeBoard board;
  tasks::Topic<msg::ScanMessage> topic;
  std::vector<std::byte> budget(1 << 16);
  std::pmr::monotonic_buffer_resource arena(budget.data(), budget.size(), std::pmr::null_memory_resource());
  lms200::Lms200Config config;
  config.restart_delay_ms = 500;
  LaserTask task(config, board, topic);
  ASSERT_TRUE(task.init(arena));  // the base task starts without its device too
  EXPECT_TRUE(task.device_missing());
  ASSERT_TRUE(task.last_open_error().has_value());
  EXPECT_EQ(task.last_open_error()->code(), Errc::not_found);
  hal::SimClock& clock = board.sim_clock();
  std::uint64_t cycle = 0;
  auto run = [&](hal::Nanos duration, const std::function<void()>& each = {}) {
    step_for(task, clock, cycle, duration, each);
  };
  run(hal::seconds(10));
  EXPECT_EQ(board.attempts("laser"), kAttemptsInTenSeconds);
  EXPECT_TRUE(task.device_missing());
  EXPECT_EQ(task.device(), nullptr);

  // Plugged in: the next attempt (at 12.5 s) finds it and scans flow.
  hal::MemoryPipe pipe(16384);
  lms200::WallWorld world = lms200::WallWorld::room_with_box(8.0, 6.0, 6.0, 3.0, 1.0);
  lms200::SimulatedLine line;
  lms200::Lms200Emulator emulator(lms200::EmulatorOptions{}, pipe.b(), world, &line);
  board.attach("laser", pipe.a(), &line);
  run(hal::seconds(8), [&] { emulator.step(clock.now()); });
  EXPECT_EQ(board.opens("laser"), 1);
  EXPECT_FALSE(task.device_missing());
  EXPECT_FALSE(task.last_open_error().has_value());
  tasks::Sample<msg::ScanMessage> scan;
  EXPECT_TRUE(topic.read(scan));
}

TEST(BaseTask, StartsWithoutItsDeviceReportsItAndRetriesWithBackoff) {
  testing::PipeBoard board;
  tasks::Topic<msg::VelocityCommand> command;
  tasks::Topic<msg::Odometry> odometry;
  tasks::Topic<msg::BaseFlags> flags;
  p2os::P2osConfig config;
  config.reopen_delay_ms = 500;
  std::array<std::byte, 64 * 1024> buffer{};
  std::pmr::monotonic_buffer_resource arena{buffer.data(), buffer.size(), std::pmr::null_memory_resource()};
  BaseTask task(config, board, BaseTopics{command, odometry, flags});
  ASSERT_TRUE(task.init(arena));
  EXPECT_TRUE(task.device_missing());
  hal::SimClock& clock = board.sim_clock();
  std::uint64_t cycle = 0;
  auto run = [&](hal::Nanos duration, const std::function<void()>& each = {}) {
    step_for(task, clock, cycle, duration, each);
  };
  run(hal::seconds(10));
  EXPECT_EQ(board.attempts("base"), kAttemptsInTenSeconds);
  EXPECT_TRUE(task.device_missing());

  hal::MemoryPipe pipe{16384};
  p2os::P2osEmulator emulator{brisk_robot()};
  board.attach("base", pipe.a());
  run(hal::seconds(8), [&] { (void)emulator.step(pipe.b(), clock.now()); });
  EXPECT_EQ(board.opens("base"), 1);
  EXPECT_FALSE(task.device_missing());
  EXPECT_EQ(task.driver()->state().link, p2os::LinkState::connected);
}

}  // namespace
}  // namespace sen3bot::firmware
