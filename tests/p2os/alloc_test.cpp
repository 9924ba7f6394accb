// Steady state allocates nothing: driver and emulator stepping, driving, faults and the task
// wrapper publishing state, with the counting global allocator linked in.
#include <gtest/gtest.h>

#include <memory_resource>

#include "alloc_counter.hpp"
#include "lockstep_harness.hpp"
#include "sen3bot/p2os/task.hpp"

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

class BorrowedStream final : public hal::ByteStream {
 public:
  explicit BorrowedStream(hal::ByteStream& inner) : inner_(inner) {}
  Result<std::size_t> read(std::span<std::uint8_t> out) override { return inner_.read(out); }
  Result<std::size_t> write(std::span<const std::uint8_t> data) override { return inner_.write(data); }
  [[nodiscard]] std::string_view name() const override { return inner_.name(); }

 private:
  hal::ByteStream& inner_;
};

TEST(P2osAllocation, TaskStepAllocatesNothing) {
  hal::MemoryPipe pipe(16384);
  P2osEmulator emu(test::fast_emulator_config());
  hal::SimClock clock(hal::seconds(1));
  tasks::Topic<BaseSetpoint> setpoints;
  tasks::Topic<BaseState> states;
  P2osTask task(P2osConfig{}, clock, setpoints, states, [&](const P2osConfig&) -> Result<OpenedLink> {
    OpenedLink link;
    link.stream = std::make_unique<BorrowedStream>(pipe.a());
    return link;
  });
  std::array<std::byte, 64 * 1024> buffer;
  std::pmr::monotonic_buffer_resource arena(buffer.data(), buffer.size(), std::pmr::null_memory_resource());
  ASSERT_TRUE(task.init(arena));
  std::uint64_t cycle = 0;
  auto run = [&](hal::Nanos d) {
    const hal::Nanos end = clock.now() + d;
    while (clock.now() < end) {
      (void)emu.step(pipe.b(), clock.now());
      if (cycle % 10 == 0) setpoints.publish(BaseSetpoint{0.2, -0.1, true}, clock.now());
      task.step(tasks::StepContext{clock.now(), clock.now(), cycle++});
      clock.advance_by(hal::millis(5));
    }
  };
  run(hal::seconds(2));
  AllocationScope scope;
  run(hal::seconds(10));
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(scope.malloc_calls(), 0u);
  tasks::Sample<BaseState> s;
  ASSERT_TRUE(states.read(s));
  EXPECT_EQ(s.value.link, LinkState::connected);
}

}  // namespace
}  // namespace sen3bot::p2os
