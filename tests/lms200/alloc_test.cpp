// Steady state allocates nothing: the driver's and the emulator's step(). Own executable: it
// counts global allocations. The task around the device is covered with the whole task table
// in tests/firmware/zero_allocation_test.cpp.
#include <gtest/gtest.h>

#include <memory_resource>
#include <vector>

#include "alloc_counter.hpp"
#include "rig.hpp"

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

}  // namespace
}  // namespace sen3bot::lms200
