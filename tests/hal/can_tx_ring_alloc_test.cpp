// The transmit ring allocates at construction only: queuing, flushing, dropping on a full
// ring and the error values it returns allocate nothing. So does following the link state.
#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "sen3bot/hal/can.hpp"
#include "sen3bot/hal/candump.hpp"

namespace sen3bot::hal {
namespace {

using mem::testing::AllocationScope;

// Takes `room` frames, then refuses with would_block.
struct Controller {
  std::size_t room = 0;
  std::size_t written = 0;
  Status operator()(const CanFrame&) {
    if (room == 0) return Error(Errc::would_block, "full");
    --room;
    ++written;
    return {};
  }
};

TEST(HalNoAllocation, CanTxRing) {
  CanTxRing ring(16, "can0");
  Controller controller;
  CanFrame frame;
  frame.id = 0x201;
  frame.dlc = 1;
  std::size_t refused = 0;
  AllocationScope scope;
  for (int round = 0; round < 500; ++round) {
    controller.room = static_cast<std::size_t>(round % 3);
    for (int i = 0; i < 8; ++i) {
      Status sent = ring.send(frame, controller);
      refused += sent.ok() ? 0 : 1;
    }
    Status flushed = ring.flush(controller);
    refused += flushed.ok() ? 0 : 1;
  }
  (void)ring.discard();
  EXPECT_EQ(scope.allocations(), 0U);
  EXPECT_GT(controller.written, 0U);
  EXPECT_GT(refused, 0U);
  EXPECT_GT(ring.dropped(), 0U);
}

TEST(HalNoAllocation, CanLinkStateFromErrorFrames) {
  CanFrame error;
  error.extended = true;
  error.dlc = 8;
  CanLinkState state = CanLinkState::active;
  AllocationScope scope;
  for (int round = 0; round < 500; ++round) {
    error.id = round % 2 == 0 ? can_error::kBusOff : can_error::kRestarted;
    state = next_link_state(state, error);
  }
  EXPECT_EQ(scope.allocations(), 0U);
  EXPECT_EQ(state, CanLinkState::active);
}

}  // namespace
}  // namespace sen3bot::hal
