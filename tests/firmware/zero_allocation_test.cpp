// The steady-state rule, proved on the real task table running the simulated mission: after
// init() and a warm-up, the tasks run at least 10 000 times in all, the slowest of them at
// least 100 times, and the process allocates nothing. A task added to the table is covered
// automatically, and the test fails if it does not run (the supervisory planner, computing a
// goal's waypoints, among them); the camera's row is the one the
// simulated robot cannot run yet (it has no camera).
#include <gtest/gtest.h>

#include <cstdio>

#include "alloc_counter.hpp"
#include "config.hpp"
#include "firmware.hpp"
#include "sim_rig.hpp"
#include "task_table.hpp"

namespace sen3bot::firmware {
namespace {

constexpr std::uint64_t kSteadyStateTicks = 10'000;  // task runs in all
constexpr std::uint64_t kSlowestTaskRuns = 100;

TEST(ZeroAllocation, EveryTaskOfTheTableRunsTenThousandTicksWithoutAllocating) {
  testing::SimRig rig = testing::load_sim_rig();
  ASSERT_NE(rig.board, nullptr);
  FirmwareConfig* config = &rig.config;
  config->telemetry_status_period_ms = 1'000;  // exercise the status path often
  // The moving-obstacle layer and the DWA's time-aware check too (config/sim.yaml leaves them
  // off): the worker walking across is detected, tracked and painted meanwhile.
  config->navigation.dynamic_obstacles.enabled = true;
  config->navigation.dwa.mover_prediction = true;
  // The supervisory planner computes each goal's waypoints (config/sim.yaml gives a file).
  config->navigation.waypoints_path.clear();
  config->navigation.safe_curve_path = SEN3BOT_SOURCE_DIR "/config/maps/lab_curve.yaml";
  // People: the simulated detector's frames through the gate, the fusion and the cages.
  rig.world.detector.enabled = true;
  // The safety I/O's faults in the window: an e-stop, a silent node and a node that reboots,
  // each followed by a reset.
  using What = sim::SimIoEvent::What;
  rig.world.io_node.events = {
      {15.0, What::inputs, 0x00}, {16.0, What::inputs, 0x01}, {17.0, What::inputs, 0x03}, {17.2, What::inputs, 0x01},
      {25.0, What::silent, 0},    {26.0, What::talking, 0},   {28.0, What::inputs, 0x03}, {28.2, What::inputs, 0x01},
      {35.0, What::reboot, 0},    {37.0, What::inputs, 0x03}, {37.2, What::inputs, 0x01}};
  rig.make_board();
  config->navigation.people_enabled = true;
  config->navigation.people_detector = "sim";
  config->tasks["detector"].arena_bytes = 4 * 1024;
  config->tasks["people"].arena_bytes = 64 * 1024;
  hal::SimClock& clock = rig.clock();

  std::FILE* sink = std::fopen("/dev/null", "w");
  ASSERT_NE(sink, nullptr);
  Firmware fw(*config, *rig.board, sink);
  ASSERT_TRUE(fw.init());
  tasks::Scheduler& scheduler = fw.scheduler();
  // Every row but the camera's and the on-board detector's (the simulated robot has no camera
  // yet, and OpenCV's search, on its own thread, allocates; docs/people.md) and the fleet's,
  // which takes the mission's place when the robot has one (counted in the test below).
  ASSERT_EQ(scheduler.task_count(), kTaskTable.size() - 3);

  // Warm-up: first-use work (stdio buffers, lazily sized state) happens here.
  ASSERT_TRUE(scheduler.run_lockstep(clock, hal::seconds(5)));
  ASSERT_NE(fw.planner(), nullptr);
  const std::uint32_t sgp_runs_before = fw.planner()->sgp_runs();
  std::vector<std::uint64_t> runs_before;
  for (std::size_t i = 0; i < scheduler.task_count(); ++i) runs_before.push_back(scheduler.stats(i).runs);

  // Long enough for the slowest task of the table to run kSlowestTaskRuns times; the mission
  // drives through the whole window (its goals take longer).
  std::int64_t longest_period_us = 0;
  for (const auto& row : kTaskTable) longest_period_us = std::max(longest_period_us, row.period_us);
  const hal::Nanos window = hal::micros(longest_period_us) * static_cast<hal::Nanos>(kSlowestTaskRuns);

  mem::testing::AllocationScope scope;
  const Status ran = scheduler.run_lockstep(clock, window);
  const std::uint64_t allocations = scope.allocations();
  const std::uint64_t malloc_calls = scope.malloc_calls();
  ASSERT_TRUE(ran);

  EXPECT_EQ(allocations, 0u) << "operator new called in steady state";
  EXPECT_EQ(malloc_calls, 0u) << "malloc called in steady state";
  std::uint64_t total_runs = 0;
  for (std::size_t i = 0; i < scheduler.task_count(); ++i) {
    const tasks::TaskStats s = scheduler.stats(i);
    EXPECT_GE(s.runs - runs_before[i], kSlowestTaskRuns) << s.name;
    total_runs += s.runs - runs_before[i];
  }
  EXPECT_GE(total_runs, kSteadyStateTicks);
  // The window covered real driving, not an idle robot.
  const MissionTask* mission = fw.mission();
  ASSERT_NE(mission, nullptr);
  EXPECT_GE(mission->report().goals_reached, 1u);
  // A goal came inside the window, and the supervisory planner ran for it.
  EXPECT_GT(fw.planner()->sgp_runs(), sgp_runs_before);
  EXPECT_TRUE(fw.planner()->sgp_result().on_curve);
  // The worker was seen, placed and caged meanwhile.
  ASSERT_NE(fw.people_task(), nullptr);
  EXPECT_GT(fw.people_task()->frames_fused(), 0u);
  EXPECT_GT(fw.people_task()->fusion().count(nav::BoxVerdict::located), 0u);
  // The e-stop chain held the robot three times, and the node was set up again after its reboot.
  ASSERT_NE(fw.safety(), nullptr);
  EXPECT_EQ(fw.safety()->latch()->trips(), 3u);
  EXPECT_FALSE(fw.safety()->latch()->held());
  EXPECT_EQ(fw.can_io()->master().count(canopen::IoNodeEvent::boot_up), 2u);
  EXPECT_EQ(fw.can_io()->master().count(canopen::IoNodeEvent::heartbeat_lost), 1u);
  fw.shutdown();
  std::fclose(sink);
}

TEST(ZeroAllocation, TheCounterSeesAllocations) {
  // Guards the guard: if the replacement functions were not linked in, the test above would
  // pass vacuously.
  mem::testing::AllocationScope scope;
  auto* p = new int(7);
  std::vector<int> v(100);
  void* raw = std::malloc(64);
  asm volatile("" : : "g"(p), "g"(v.data()), "g"(raw) : "memory");  // keep all three
  const std::uint64_t allocations = scope.allocations();
  const std::uint64_t malloc_calls = scope.malloc_calls();
  delete p;
  std::free(raw);
  EXPECT_EQ(allocations, 2u);
  if (mem::testing::counts_malloc()) {
    EXPECT_EQ(malloc_calls, 3u);
  }
}

}  // namespace
}  // namespace sen3bot::firmware
