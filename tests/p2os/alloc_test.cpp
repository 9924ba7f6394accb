// Steady state allocates nothing: driver and emulator stepping, driving and faults, with the
// counting global allocator linked in. The task around the driver is covered with the whole
// task table in tests/firmware/zero_allocation_test.cpp.
#include <gtest/gtest.h>

#include <memory_resource>

#include "alloc_counter.hpp"
#include "lockstep_harness.hpp"

namespace sen3bot::p2os {
namespace {

using mem::testing::AllocationScope;

TEST(P2osAllocation, DriverAndEmulatorSteadyStateAllocateNothing) {
  test::Lockstep h;
  ASSERT_TRUE(h.connect());
  h.hold(0.3, 0.2);  // installs the planner (allocates once, outside the scope)
  h.run_for(hal::seconds(1));
  AllocationScope scope;
  h.run_for(hal::seconds(10));
  h.emulator.inject_noise(100);
  h.emulator.inject_bad_checksums(3);
  h.emulator.drop_sips(2);
  h.run_for(hal::seconds(2));
  h.emulator.set_silent(true);  // link loss and re-handshake are allocation-free too
  h.run_for(hal::seconds(2));
  h.emulator.set_silent(false);
  h.run_for(hal::seconds(3));
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(scope.malloc_calls(), 0u);
  EXPECT_EQ(h.driver.state().link, LinkState::connected);
  EXPECT_GT(h.driver.state().sip_count, 150u);
}

}  // namespace
}  // namespace sen3bot::p2os
