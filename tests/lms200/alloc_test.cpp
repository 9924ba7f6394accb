// Steady state allocates nothing: the driver's and the emulator's step(), and the task's
// step() publishing on a Topic. Own executable: it counts global allocations.
#include <gtest/gtest.h>

#include <memory_resource>
#include <vector>

#include "alloc_counter.hpp"
#include "rig.hpp"
#include "sen3bot/lms200/task.hpp"

namespace sen3bot::lms200 {
namespace {

using mem::testing::AllocationScope;
using testing::Rig;

TEST(Lms200Allocation, DriverAndEmulatorStepsAllocateNothing) {
  Lms200Config c;
  c.baud = 500000;
  c.variant = {180, 50};
  Rig rig(EmulatorOptions{}, c);
  rig.device.start(rig.now);
  ASSERT_TRUE(rig.until_streaming());
  rig.run_for(hal::millis(100));
  AllocationScope scope;
  rig.run_for(hal::seconds(2));
  // Faults and errors take the same allocation-free paths.
  FaultPlan f;
  f.corrupt_crc_every = 2;
  f.false_header_every = 3;
  f.invalid_values_every = 1;
  rig.emulator.set_faults(f);
  rig.run_for(hal::seconds(1));
  rig.emulator.set_faults({});
  rig.run_for(hal::seconds(1));
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_GT(rig.device.counters().scans, 100u);
}

TEST(Lms200Allocation, TaskPublishesScansWithoutAllocating) {
  hal::MemoryPipe pipe(16384);
  WallWorld world = testing::test_world();
  SimulatedLine line;
  Lms200Emulator emulator(EmulatorOptions{}, pipe.b(), world, &line);
  tasks::Topic<LaserScan> topic;
  Lms200Config c;
  c.baud = 500000;
  c.variant = {180, 100};
  Lms200Task task(c, pipe.a(), &line, topic);
  // The arena is exactly the declared budget over the null resource: init fits in it.
  std::vector<std::byte> budget(Lms200Task::kArenaBytes);
  std::pmr::monotonic_buffer_resource arena(budget.data(), budget.size(), std::pmr::null_memory_resource());
  ASSERT_TRUE(task.init(arena).ok());
  hal::Nanos now = 0;
  std::uint64_t cycle = 0;
  auto run = [&](hal::Nanos duration) {
    for (const hal::Nanos end = now + duration; now < end; now += hal::millis(1)) {
      emulator.step(now);
      task.step({now, now, cycle++});
    }
  };
  run(hal::seconds(2));
  ASSERT_GT(topic.published(), 50u);
  AllocationScope scope;
  run(hal::seconds(2));
  EXPECT_EQ(scope.allocations(), 0u);
  tasks::Sample<LaserScan> sample;
  ASSERT_TRUE(topic.read(sample));
  EXPECT_EQ(sample.value.count, 181);
  EXPECT_EQ(sample.value.link_state, LinkState::streaming);
  EXPECT_GE(topic.published(), 2 * 75u + 50u);
}

TEST(Lms200Allocation, TaskRejectsBadConfigurationAndTinyArena) {
  hal::MemoryPipe pipe(1024);
  tasks::Topic<LaserScan> topic;
  Lms200Config bad;
  bad.variant = {180, 25};
  Lms200Task t1(bad, pipe.a(), nullptr, topic);
  std::vector<std::byte> budget(1 << 16);
  std::pmr::monotonic_buffer_resource big(budget.data(), budget.size(), std::pmr::null_memory_resource());
  EXPECT_EQ(t1.init(big).error().code(), Errc::config);
  Lms200Task t2(Lms200Config{}, pipe.a(), nullptr, topic);
  std::array<std::byte, 64> small;
  std::pmr::monotonic_buffer_resource tiny(small.data(), small.size(), std::pmr::null_memory_resource());
  EXPECT_EQ(t2.init(tiny).error().code(), Errc::capacity);
}

}  // namespace
}  // namespace sen3bot::lms200
