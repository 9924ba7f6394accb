// Steady state allocates nothing: the driver's and the emulator's step(), in every streaming mode. Own executable: it
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
  f.device_fault = true;
  rig.emulator.set_faults(f);
  rig.run_for(hal::seconds(1));
  rig.emulator.set_faults({});
  rig.run_for(hal::seconds(1));
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_GT(rig.device.counters().scans, 100u);
}

TEST(Lms200Allocation, EmulatorStreamingMeansAndSubrangesAllocatesNothing) {
  EmulatorOptions o;
  o.initial_baud = 500000;
  o.variant = {100, 25};
  o.availability = kAvailabilityRealTimeIndices;
  WallWorld world = testing::test_world();
  hal::MemoryPipe pipe{16384};
  SimulatedLine line(500000);
  Lms200Emulator emulator(o, pipe.b(), world, &line);
  const Request mean = *request_mean_values(10);
  const Request subrange = *request_subrange(50, 350, o.variant);
  const Request partial = request_mode(OperatingMode::partial_scans);
  std::array<std::uint8_t, 4096> sink{};
  hal::Nanos now = 0;
  AllocationScope scope;
  for (const Request* r : {&mean, &subrange, &partial}) {
    ASSERT_EQ(*pipe.a().write(r->span()), r->size);
    for (const hal::Nanos end = now + hal::seconds(1); now < end; now += hal::micros(200)) {
      emulator.step(now);
      while (*pipe.a().read(sink) > 0) {
      }
    }
  }
  EXPECT_EQ(scope.allocations(), 0u);
  // A second each at 100/0.25 (18.75 complete scans a second): one mean of 10 scans, 18
  // sub-ranges, 74 partial scans.
  EXPECT_GT(emulator.counters().scans_sent, 80u);
}

}  // namespace
}  // namespace sen3bot::lms200
