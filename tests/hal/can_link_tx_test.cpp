// The SocketCAN backend's pure parts, without a kernel: the link state from error frames
// (next_link_state) and the transmit ring (CanTxRing) over a fake controller.
#include <gtest/gtest.h>

#include <cstdint>
#include <limits>
#include <string>
#include <vector>

#include "hal_test_util.hpp"
#include "sen3bot/hal/can.hpp"
#include "sen3bot/hal/candump.hpp"

namespace sen3bot::hal {
namespace {

constexpr CanLinkState kAllStates[] = {CanLinkState::active, CanLinkState::warning, CanLinkState::passive,
                                       CanLinkState::bus_off};

// An error frame as the kernel's, and parse_candump_line's: id = classes, extended, dlc 8.
CanFrame error_frame(std::uint32_t classes, std::uint8_t controller = 0) {
  CanFrame frame;
  frame.id = classes;
  frame.extended = true;
  frame.dlc = 8;
  frame.data[1] = controller;
  return frame;
}

TEST(HalCanLinkState, BusOffFromEveryState) {
  for (const CanLinkState from : kAllStates) {
    EXPECT_EQ(next_link_state(from, error_frame(can_error::kBusOff)), CanLinkState::bus_off) << to_string(from);
  }
}

TEST(HalCanLinkState, RestartedIsErrorActive) {
  for (const CanLinkState from : kAllStates) {
    EXPECT_EQ(next_link_state(from, error_frame(can_error::kRestarted)), CanLinkState::active) << to_string(from);
  }
}

TEST(HalCanLinkState, ControllerStateBits) {
  struct Case {
    std::uint8_t bits;
    CanLinkState expected;
  };
  const Case cases[] = {
      {can_error::kRxWarning, CanLinkState::warning},
      {can_error::kTxWarning, CanLinkState::warning},
      {can_error::kRxWarning | can_error::kTxWarning, CanLinkState::warning},
      {can_error::kRxPassive, CanLinkState::passive},
      {can_error::kTxPassive, CanLinkState::passive},
      {can_error::kTxPassive | can_error::kRxWarning, CanLinkState::passive},  // the worse wins
      {can_error::kActive, CanLinkState::active},
  };
  for (const CanLinkState from : kAllStates) {
    for (const Case& c : cases) {
      EXPECT_EQ(next_link_state(from, error_frame(can_error::kController, c.bits)), c.expected)
          << to_string(from) << " data[1]=0x" << std::hex << unsigned{c.bits};
    }
  }
}

TEST(HalCanLinkState, CombinedClasses) {
  // Bus-off wins over a restart or a controller report in the same frame.
  EXPECT_EQ(next_link_state(CanLinkState::active, error_frame(can_error::kBusOff | can_error::kRestarted)),
            CanLinkState::bus_off);
  EXPECT_EQ(next_link_state(CanLinkState::warning,
                            error_frame(can_error::kBusOff | can_error::kController, can_error::kActive)),
            CanLinkState::bus_off);
  // Restarted with the controller's state: the controller's state decides.
  EXPECT_EQ(next_link_state(CanLinkState::bus_off,
                            error_frame(can_error::kRestarted | can_error::kController, can_error::kRxWarning)),
            CanLinkState::warning);
  // Classes that say nothing about the state ride along without changing the answer.
  EXPECT_EQ(next_link_state(CanLinkState::active, error_frame(can_error::kController | can_error::kBusError |
                                                                  can_error::kProtocol,
                                                              can_error::kTxPassive)),
            CanLinkState::passive);
  EXPECT_EQ(next_link_state(CanLinkState::passive, error_frame(can_error::kTxTimeout | can_error::kRestarted)),
            CanLinkState::active);
}

TEST(HalCanLinkState, OtherClassesLeaveTheStateAlone) {
  const std::uint32_t neutral[] = {0,
                                   can_error::kTxTimeout,
                                   can_error::kLostArbitration,
                                   can_error::kProtocol,
                                   can_error::kTransceiver,
                                   can_error::kNoAck,
                                   can_error::kBusError,
                                   can_error::kTxTimeout | can_error::kNoAck | can_error::kBusError};
  for (const CanLinkState from : kAllStates) {
    for (const std::uint32_t classes : neutral) {
      EXPECT_EQ(next_link_state(from, error_frame(classes, can_error::kTxPassive)), from)
          << to_string(from) << " classes 0x" << std::hex << classes;  // data[1] counts only with kController
    }
    // A controller report of overflows only, or with no state byte, changes nothing.
    EXPECT_EQ(next_link_state(from, error_frame(can_error::kController, can_error::kRxOverflow)), from);
    EXPECT_EQ(next_link_state(from, error_frame(can_error::kController, can_error::kTxOverflow)), from);
    CanFrame short_frame = error_frame(can_error::kController, can_error::kTxPassive);
    short_frame.dlc = 1;
    EXPECT_EQ(next_link_state(from, short_frame), from);
  }
}

TEST(HalCanLinkState, FromCandumpLines) {
  struct Case {
    const char* line;
    CanLinkState from;
    CanLinkState expected;
  };
  const Case cases[] = {
      {"(1700000000.000000) can0 20000040#0000000000000000", CanLinkState::passive, CanLinkState::bus_off},
      {"(1700000000.000000) can0 20000100#0000000000000000", CanLinkState::bus_off, CanLinkState::active},
      {"(1700000000.000000) can0 20000004#0008000000000000", CanLinkState::active, CanLinkState::warning},
      {"(1700000000.000000) can0 20000004#0020000000000000", CanLinkState::warning, CanLinkState::passive},
      {"(1700000000.000000) can0 20000004#0040000000000000", CanLinkState::passive, CanLinkState::active},
      {"(1700000000.000000) can0 20000020#0000000000000000", CanLinkState::warning, CanLinkState::warning},
  };
  for (const Case& c : cases) {
    Result<CandumpLine> line = parse_candump_line(c.line);
    ASSERT_TRUE(line.ok()) << c.line << ": " << line.error().c_str();
    ASSERT_TRUE(line->error_frame) << c.line;
    EXPECT_EQ(next_link_state(c.from, line->frame), c.expected) << c.line;
  }
}

// A controller with room for `room` more frames; then it answers would_block, or `failure`.
struct FakeController {
  std::size_t room = std::numeric_limits<std::size_t>::max();
  Errc failure = Errc::would_block;
  std::vector<std::uint32_t> written;

  Status operator()(const CanFrame& frame) {
    if (room == 0) return Error::format(failure, "fake: refused 0x%X", static_cast<unsigned>(frame.id));
    --room;
    written.push_back(frame.id);
    return {};
  }
};

CanFrame data_frame(std::uint32_t id) {
  CanFrame frame;
  frame.id = id;
  frame.dlc = 1;
  frame.data[0] = static_cast<std::uint8_t>(id);
  return frame;
}

TEST(HalCanTxRing, WritesDirectlyWhileTheControllerHasRoom) {
  CanTxRing ring(4, "can0");
  FakeController controller;
  for (std::uint32_t id = 1; id <= 10; ++id) ASSERT_TRUE(ring.send(data_frame(id), controller).ok());
  EXPECT_EQ(controller.written, std::vector<std::uint32_t>({1, 2, 3, 4, 5, 6, 7, 8, 9, 10}));
  EXPECT_EQ(ring.size(), 0U);
  EXPECT_EQ(ring.dropped(), 0U);
  EXPECT_EQ(ring.capacity(), 4U);
  EXPECT_TRUE(ring.flush(controller).ok());
}

TEST(HalCanTxRing, RefusedFramesWaitAndKeepTheirOrder) {
  CanTxRing ring(8, "can0");
  FakeController controller;
  controller.room = 0;
  for (std::uint32_t id = 1; id <= 3; ++id) EXPECT_TRUE(ring.send(data_frame(id), controller).ok());
  EXPECT_EQ(ring.size(), 3U);
  EXPECT_EQ(ring.front().id, 1U);
  EXPECT_TRUE(controller.written.empty());
  // Room for two: send() flushes 1 and 2 first; 4 goes behind 3, not before it.
  controller.room = 2;
  EXPECT_TRUE(ring.send(data_frame(4), controller).ok());
  EXPECT_EQ(controller.written, std::vector<std::uint32_t>({1, 2}));
  EXPECT_EQ(ring.size(), 2U);
  EXPECT_EQ(ring.front().id, 3U);
  controller.room = 100;
  EXPECT_TRUE(ring.flush(controller).ok());
  EXPECT_EQ(controller.written, std::vector<std::uint32_t>({1, 2, 3, 4}));
  EXPECT_TRUE(ring.empty());
  // Emptied, the next frame goes straight to the controller.
  EXPECT_TRUE(ring.send(data_frame(5), controller).ok());
  EXPECT_EQ(controller.written.back(), 5U);
  EXPECT_EQ(ring.dropped(), 0U);
}

TEST(HalCanTxRing, AFullRingDropsTheNewFrameAndCountsIt) {
  CanTxRing ring(4, "can0");
  FakeController controller;
  controller.room = 0;
  for (std::uint32_t id = 1; id <= 4; ++id) ASSERT_TRUE(ring.send(data_frame(id), controller).ok());
  for (std::uint32_t id = 5; id <= 6; ++id) {
    Status refused = ring.send(data_frame(id), controller);
    ASSERT_FALSE(refused.ok());
    EXPECT_EQ(refused.error().code(), Errc::would_block);
    EXPECT_TRUE(testing::contains(refused.error().message(), "can0")) << refused.error().c_str();
    EXPECT_TRUE(testing::contains(refused.error().message(), "dropped")) << refused.error().c_str();
  }
  EXPECT_EQ(ring.dropped(), 2U);
  EXPECT_EQ(ring.size(), 4U);
  controller.room = 100;
  EXPECT_TRUE(ring.flush(controller).ok());
  EXPECT_EQ(controller.written, std::vector<std::uint32_t>({1, 2, 3, 4}));  // the oldest kept
}

TEST(HalCanTxRing, PartialFlushSaysHowManyWait) {
  CanTxRing ring(8, "vcan0");
  FakeController controller;
  controller.room = 0;
  for (std::uint32_t id = 1; id <= 5; ++id) ASSERT_TRUE(ring.send(data_frame(id), controller).ok());
  controller.room = 2;
  Status partial = ring.flush(controller);
  ASSERT_FALSE(partial.ok());
  EXPECT_EQ(partial.error().code(), Errc::would_block);
  EXPECT_EQ(partial.error().message(), "vcan0: transmit queue full, 3 frames waiting");
  EXPECT_EQ(controller.written, std::vector<std::uint32_t>({1, 2}));
  EXPECT_EQ(ring.size(), 3U);
  EXPECT_EQ(ring.front().id, 3U);
}

TEST(HalCanTxRing, WrapsAroundInOrder) {
  CanTxRing ring(3, "can0");
  FakeController controller;
  std::vector<std::uint32_t> expected;
  std::uint32_t id = 0;
  for (int round = 0; round < 20; ++round) {
    controller.room = 0;
    for (int i = 0; i < 2; ++i) {
      ASSERT_TRUE(ring.send(data_frame(++id), controller).ok());
      expected.push_back(id);
    }
    controller.room = round % 2 == 0 ? 1 : 3;  // the ring fills to 3, the head moves round
    (void)ring.flush(controller);
  }
  controller.room = 100;
  ASSERT_TRUE(ring.flush(controller).ok());
  EXPECT_EQ(controller.written, expected);
  EXPECT_EQ(ring.dropped(), 0U);
}

TEST(HalCanTxRing, WithoutAQueueARefusedFrameIsDropped) {
  CanTxRing ring(0, "can0");
  FakeController controller;
  controller.room = 0;
  Status refused = ring.send(data_frame(0x42), controller);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code(), Errc::would_block);
  EXPECT_EQ(refused.error().message(), "can0: kernel transmit queue full, frame 0x42 dropped (no queue)");
  EXPECT_EQ(ring.dropped(), 1U);
  EXPECT_EQ(ring.size(), 0U);
  EXPECT_TRUE(ring.flush(controller).ok());
  controller.room = 1;
  EXPECT_TRUE(ring.send(data_frame(0x43), controller).ok());
  EXPECT_EQ(controller.written, std::vector<std::uint32_t>({0x43}));
}

TEST(HalCanTxRing, OtherErrorsArePassedOnAndNothingIsLost) {
  CanTxRing ring(4, "can0");
  FakeController controller;
  controller.room = 0;
  controller.failure = Errc::disconnected;
  // Straight to the controller, refused for good: the caller has the error, nothing queued.
  Status down = ring.send(data_frame(1), controller);
  ASSERT_FALSE(down.ok());
  EXPECT_EQ(down.error().code(), Errc::disconnected);
  EXPECT_EQ(ring.size(), 0U);
  EXPECT_EQ(ring.dropped(), 0U);
  // Frames already waiting stay, and a new one is not taken while the flush fails.
  controller.failure = Errc::would_block;
  ASSERT_TRUE(ring.send(data_frame(2), controller).ok());
  controller.failure = Errc::io;
  Status io = ring.send(data_frame(3), controller);
  ASSERT_FALSE(io.ok());
  EXPECT_EQ(io.error().code(), Errc::io);
  EXPECT_EQ(ring.size(), 1U);
  EXPECT_EQ(ring.front().id, 2U);
  controller.room = 10;
  EXPECT_TRUE(ring.flush(controller).ok());
  EXPECT_EQ(controller.written, std::vector<std::uint32_t>({2}));
}

TEST(HalCanTxRing, DiscardCountsTheDroppedFrames) {
  CanTxRing ring(4, "can0");
  FakeController controller;
  controller.room = 0;
  for (std::uint32_t id = 1; id <= 3; ++id) ASSERT_TRUE(ring.send(data_frame(id), controller).ok());
  EXPECT_EQ(ring.discard(), 3U);
  EXPECT_EQ(ring.dropped(), 3U);
  EXPECT_TRUE(ring.empty());
  EXPECT_EQ(ring.discard(), 0U);
  EXPECT_TRUE(ring.push(data_frame(9)));
  EXPECT_EQ(ring.front().id, 9U);
}

TEST(HalCanTxRing, ALongNameIsCutInTheMessages) {
  const std::string long_name(40, 'x');
  CanTxRing ring(0, long_name);
  FakeController controller;
  controller.room = 0;
  Status refused = ring.send(data_frame(1), controller);
  ASSERT_FALSE(refused.ok());
  EXPECT_TRUE(testing::contains(refused.error().message(), std::string(31, 'x') + ": kernel")) << refused.error().c_str();
}

TEST(HalSocketCanOptions, Defaults) {
  const SocketCanOptions options;
  EXPECT_FALSE(options.receive_own);
  EXPECT_EQ(options.tx_queue_frames, 16U);
}

}  // namespace
}  // namespace sen3bot::hal
