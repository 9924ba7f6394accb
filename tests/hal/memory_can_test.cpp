#include <gtest/gtest.h>

#include <thread>
#include <vector>

#include "hal_test_util.hpp"
#include "sen3bot/hal/can.hpp"

namespace sen3bot::hal {
namespace {

CanFrame frame(std::uint32_t id, std::initializer_list<std::uint8_t> payload = {}, bool extended = false) {
  const std::vector<std::uint8_t> bytes(payload);
  Result<CanFrame> made = CanFrame::make(id, bytes, extended);
  EXPECT_TRUE(made.ok()) << (made.ok() ? "" : made.error().c_str());
  return made.ok() ? *made : CanFrame{};
}

MemoryCanNode* attach(MemoryCanBus& bus, std::string_view name, MemoryCanNodeOptions options = {}) {
  Result<MemoryCanNode*> node = bus.attach(name, options);
  EXPECT_TRUE(node.ok()) << (node.ok() ? "" : node.error().c_str());
  return node.ok() ? *node : nullptr;
}

std::vector<std::uint32_t> drain_ids(CanBus& node) {
  std::vector<std::uint32_t> ids;
  for (;;) {
    Result<std::optional<CanFrame>> received = node.receive();
    if (!received.ok() || !*received) break;
    ids.push_back((*received)->id);
  }
  return ids;
}

TEST(HalCanFrame, Validation) {
  EXPECT_TRUE(frame(0x7FF).validate().ok());
  EXPECT_TRUE(frame(0x1FFFFFFF, {}, true).validate().ok());

  CanFrame too_long = frame(0x100);
  too_long.dlc = 9;
  Status dlc = too_long.validate();
  ASSERT_FALSE(dlc.ok());
  EXPECT_EQ(dlc.error().code(), Errc::invalid_argument);
  EXPECT_TRUE(testing::contains(dlc.error().message(), "dlc 9"));

  CanFrame wide_standard;
  wide_standard.id = 0x800;
  Status standard = wide_standard.validate();
  ASSERT_FALSE(standard.ok());
  EXPECT_TRUE(testing::contains(standard.error().message(), "11 bits"));

  CanFrame wide_extended;
  wide_extended.id = 0x20000000;
  wide_extended.extended = true;
  Status extended = wide_extended.validate();
  ASSERT_FALSE(extended.ok());
  EXPECT_TRUE(testing::contains(extended.error().message(), "29 bits"));

  const std::uint8_t nine[9] = {};
  Result<CanFrame> made = CanFrame::make(0x10, nine);
  ASSERT_FALSE(made.ok());
  EXPECT_EQ(made.error().code(), Errc::invalid_argument);
  EXPECT_FALSE(CanFrame::make(0x800, {}).ok());
  EXPECT_TRUE(CanFrame::make(0x800, {}, true).ok());

  const CanFrame f = frame(0x123, {1, 2, 3});
  EXPECT_EQ(f.dlc, 3);
  EXPECT_EQ(f.payload().size(), 3U);
  EXPECT_EQ(f.payload()[2], 3);
}

TEST(HalCanFilter, LinuxSemantics) {
  const CanFilter range{0x100, 0x700};  // 0x100..0x1FF
  EXPECT_TRUE(range.matches(frame(0x100)));
  EXPECT_TRUE(range.matches(frame(0x1FF)));
  EXPECT_FALSE(range.matches(frame(0x200)));
  // Without a format the id bits alone decide, as with a can_filter whose mask lacks
  // CAN_EFF_FLAG: an extended frame with the same low bits passes too.
  EXPECT_TRUE(range.matches(frame(0x100, {}, true)));
  const CanFilter standard_only{0x100, 0x700, CanFilter::Format::standard};
  EXPECT_FALSE(standard_only.matches(frame(0x100, {}, true)));
  const CanFilter extended_only{0x18FF0000, 0x1FFF0000, CanFilter::Format::extended};
  EXPECT_TRUE(extended_only.matches(frame(0x18FF1234, {}, true)));
  EXPECT_FALSE(extended_only.matches(frame(0x123)));
  EXPECT_TRUE(CanFilter{}.matches(frame(0x7FF)));
}

TEST(HalMemoryCan, SendReachesEveryOtherNode) {
  MemoryCanBus bus;
  MemoryCanNode* a = attach(bus, "a");
  MemoryCanNode* b = attach(bus, "b");
  MemoryCanNode* c = attach(bus, "c");
  ASSERT_TRUE(a && b && c);
  const CanFrame sent = frame(0x321, {0xDE, 0xAD, 0xBE, 0xEF});
  ASSERT_TRUE(a->send(sent).ok());
  for (MemoryCanNode* node : {b, c}) {
    Result<std::optional<CanFrame>> received = node->receive();
    ASSERT_TRUE(received.ok());
    ASSERT_TRUE(received->has_value());
    EXPECT_EQ(**received, sent);
  }
  Result<std::optional<CanFrame>> own = a->receive();
  ASSERT_TRUE(own.ok());
  EXPECT_FALSE(own->has_value());  // no local loopback by default (like CAN_RAW_RECV_OWN_MSGS off)
  EXPECT_EQ(a->sent_count(), 1U);
  EXPECT_EQ(b->received_count(), 1U);
  EXPECT_EQ(bus.frames_sent(), 1U);
  EXPECT_EQ(a->name(), "a");
  EXPECT_EQ(a->poll_fd(), -1);
}

TEST(HalMemoryCan, ReceiveOwnLoopsBack) {
  MemoryCanBus bus;
  MemoryCanNodeOptions options;
  options.receive_own = true;
  MemoryCanNode* a = attach(bus, "a", options);
  MemoryCanNode* b = attach(bus, "b");
  ASSERT_TRUE(a && b);
  ASSERT_TRUE(a->send(frame(0x10)).ok());
  EXPECT_EQ(drain_ids(*a), std::vector<std::uint32_t>({0x10}));
  EXPECT_EQ(drain_ids(*b), std::vector<std::uint32_t>({0x10}));
}

TEST(HalMemoryCan, AcceptanceFilters) {
  MemoryCanBus bus;
  MemoryCanNode* sender = attach(bus, "sender");
  MemoryCanNode* node = attach(bus, "node");
  ASSERT_TRUE(sender && node);
  const CanFilter filters[] = {
      {0x100, 0x7F0, CanFilter::Format::standard},  // 0x100..0x10F
      {0x200, 0x7FF, CanFilter::Format::standard},  // exactly 0x200
  };
  ASSERT_TRUE(node->set_filters(filters).ok());
  for (const std::uint32_t id : {0x0FFU, 0x100U, 0x10FU, 0x110U, 0x200U, 0x201U}) {
    ASSERT_TRUE(sender->send(frame(id)).ok());
  }
  ASSERT_TRUE(sender->send(frame(0x100, {}, true)).ok());  // extended: filtered out by format
  EXPECT_EQ(drain_ids(*node), std::vector<std::uint32_t>({0x100, 0x10F, 0x200}));

  ASSERT_TRUE(node->set_filters({}).ok());  // as in SocketCAN: no filter, no frames
  ASSERT_TRUE(sender->send(frame(0x100)).ok());
  EXPECT_TRUE(drain_ids(*node).empty());

  ASSERT_TRUE(node->accept_all().ok());
  ASSERT_TRUE(sender->send(frame(0x555)).ok());
  EXPECT_EQ(drain_ids(*node), std::vector<std::uint32_t>({0x555}));

  std::vector<CanFilter> too_many(kMaxCanFilters + 1);
  Status rejected = node->set_filters(too_many);
  ASSERT_FALSE(rejected.ok());
  EXPECT_EQ(rejected.error().code(), Errc::capacity);
}

TEST(HalMemoryCan, FullQueueDropsAndCountsOverflow) {
  MemoryCanBus bus;
  MemoryCanNodeOptions small;
  small.receive_queue_frames = 4;
  MemoryCanNode* sender = attach(bus, "sender");
  MemoryCanNode* slow = attach(bus, "slow", small);
  MemoryCanNode* fast = attach(bus, "fast");
  ASSERT_TRUE(sender && slow && fast);
  for (std::uint32_t id = 1; id <= 10; ++id) ASSERT_TRUE(sender->send(frame(id)).ok());
  EXPECT_EQ(slow->queued_frames(), 4U);
  EXPECT_EQ(slow->overflow_count(), 6U);
  EXPECT_EQ(drain_ids(*slow), std::vector<std::uint32_t>({1, 2, 3, 4}));  // oldest kept, in order
  EXPECT_EQ(drain_ids(*fast).size(), 10U);  // one slow node does not hurt the others
  EXPECT_EQ(fast->overflow_count(), 0U);

  // The queue wraps around correctly after partial drains.
  for (std::uint32_t round = 0; round < 10; ++round) {
    ASSERT_TRUE(sender->send(frame(100 + round * 2)).ok());
    ASSERT_TRUE(sender->send(frame(101 + round * 2)).ok());
    EXPECT_EQ(drain_ids(*slow), std::vector<std::uint32_t>({100 + round * 2, 101 + round * 2}));
  }
}

TEST(HalMemoryCan, InvalidFramesAreNotSent) {
  MemoryCanBus bus;
  MemoryCanNode* a = attach(bus, "a");
  MemoryCanNode* b = attach(bus, "b");
  ASSERT_TRUE(a && b);
  CanFrame bad;
  bad.id = 0x800;
  Status sent = a->send(bad);
  ASSERT_FALSE(sent.ok());
  EXPECT_EQ(sent.error().code(), Errc::invalid_argument);
  bad.id = 0x1;
  bad.dlc = 12;
  EXPECT_FALSE(a->send(bad).ok());
  EXPECT_EQ(b->queued_frames(), 0U);
  EXPECT_EQ(bus.frames_sent(), 0U);
}

TEST(HalMemoryCan, RemoteRequestsKeepTheirFlagAndLength) {
  MemoryCanBus bus;
  MemoryCanNode* a = attach(bus, "a");
  MemoryCanNode* b = attach(bus, "b");
  ASSERT_TRUE(a && b);
  CanFrame request;
  request.id = 0x1ABCDE;
  request.extended = true;
  request.rtr = true;
  request.dlc = 8;
  ASSERT_TRUE(a->send(request).ok());
  Result<std::optional<CanFrame>> received = b->receive();
  ASSERT_TRUE(received.ok() && received->has_value());
  EXPECT_TRUE((*received)->rtr);
  EXPECT_TRUE((*received)->extended);
  EXPECT_EQ((*received)->dlc, 8);
}

TEST(HalMemoryCan, BusLimitsAreReported) {
  MemoryCanBus bus(2);
  ASSERT_TRUE(attach(bus, "one"));
  ASSERT_TRUE(attach(bus, "two"));
  Result<MemoryCanNode*> third = bus.attach("three");
  ASSERT_FALSE(third.ok());
  EXPECT_EQ(third.error().code(), Errc::capacity);
  EXPECT_TRUE(testing::contains(third.error().message(), "three"));

  MemoryCanBus other;
  MemoryCanNodeOptions no_queue;
  no_queue.receive_queue_frames = 0;
  Result<MemoryCanNode*> bad = other.attach("x", no_queue);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code(), Errc::invalid_argument);
}

TEST(HalMemoryCan, LinkDownIsDisconnectedAfterDraining) {
  MemoryCanBus bus;
  MemoryCanNode* a = attach(bus, "a");
  MemoryCanNode* b = attach(bus, "b");
  ASSERT_TRUE(a && b);
  ASSERT_TRUE(a->send(frame(0x1)).ok());
  bus.set_link_up(false);
  EXPECT_FALSE(bus.link_up());
  Status sent = a->send(frame(0x2));
  ASSERT_FALSE(sent.ok());
  EXPECT_EQ(sent.error().code(), Errc::disconnected);
  EXPECT_TRUE(testing::contains(sent.error().message(), "a"));
  Result<std::optional<CanFrame>> queued = b->receive();
  ASSERT_TRUE(queued.ok() && queued->has_value());  // already received before the cut
  Result<std::optional<CanFrame>> after = b->receive();
  ASSERT_FALSE(after.ok());
  EXPECT_EQ(after.error().code(), Errc::disconnected);
  bus.set_link_up(true);
  ASSERT_TRUE(a->send(frame(0x3)).ok());
  EXPECT_EQ(drain_ids(*b), std::vector<std::uint32_t>({0x3}));
}

TEST(HalMemoryCan, LinkStateFollowsTheBus) {
  MemoryCanBus bus;
  MemoryCanNode* a = attach(bus, "a");
  MemoryCanNode* b = attach(bus, "b");
  ASSERT_TRUE(a && b);
  EXPECT_EQ(a->link_state(), CanLinkState::active);
  EXPECT_EQ(bus.link_state(), CanLinkState::active);

  // Warning and passive: many errors, but the controller is still on the bus.
  for (const CanLinkState degraded : {CanLinkState::warning, CanLinkState::passive}) {
    bus.set_link_state(degraded);
    EXPECT_EQ(a->link_state(), degraded);
    EXPECT_EQ(b->link_state(), degraded);
    EXPECT_TRUE(bus.link_up());
    ASSERT_TRUE(a->send(frame(0x10)).ok()) << to_string(degraded);
    EXPECT_EQ(drain_ids(*b), std::vector<std::uint32_t>({0x10}));
  }

  // Bus-off: nothing is sent, and the error says so.
  bus.set_link_state(CanLinkState::bus_off);
  EXPECT_EQ(a->link_state(), CanLinkState::bus_off);
  EXPECT_FALSE(bus.link_up());
  Status refused = a->send(frame(0x11));
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code(), Errc::disconnected);
  EXPECT_TRUE(testing::contains(refused.error().message(), "bus-off")) << refused.error().c_str();
  Result<std::optional<CanFrame>> nothing = b->receive();
  ASSERT_FALSE(nothing.ok());
  EXPECT_EQ(nothing.error().code(), Errc::disconnected);

  // Back to error active: the bus works again.
  bus.set_link_state(CanLinkState::active);
  EXPECT_EQ(a->link_state(), CanLinkState::active);
  EXPECT_TRUE(bus.link_up());
  ASSERT_TRUE(a->send(frame(0x12)).ok());
  EXPECT_EQ(drain_ids(*b), std::vector<std::uint32_t>({0x12}));

  // set_link_up maps onto the same states.
  bus.set_link_up(false);
  EXPECT_EQ(a->link_state(), CanLinkState::bus_off);
  bus.set_link_up(true);
  EXPECT_EQ(a->link_state(), CanLinkState::active);
}

TEST(HalMemoryCan, NoKernelTimestampsAndNoTransmitQueue) {
  MemoryCanBus bus;
  MemoryCanNode* a = attach(bus, "a");
  MemoryCanNode* b = attach(bus, "b");
  ASSERT_TRUE(a && b);
  ASSERT_TRUE(a->send(frame(0x20)).ok());
  Result<std::optional<CanFrame>> received = b->receive();
  ASSERT_TRUE(received.ok() && received->has_value());
  EXPECT_EQ(b->last_receive_unix_ns(), -1);
  EXPECT_TRUE(a->flush().ok());
  EXPECT_EQ(a->tx_queued(), 0U);
  EXPECT_EQ(a->tx_dropped(), 0U);
  EXPECT_EQ(a->error_frames(), 0U);
}

TEST(HalMemoryCan, NodesOnSeparateThreads) {
  constexpr std::uint32_t kFrames = 20'000;
  MemoryCanBus bus;
  MemoryCanNodeOptions roomy;
  roomy.receive_queue_frames = 256;
  MemoryCanNode* producer = attach(bus, "producer");
  MemoryCanNode* consumer = attach(bus, "consumer", roomy);
  ASSERT_TRUE(producer && consumer);
  std::thread sender([&] {
    for (std::uint32_t i = 0; i < kFrames; ++i) {
      // Back off while the consumer's queue is full so nothing is dropped.
      while (consumer->queued_frames() >= roomy.receive_queue_frames) std::this_thread::yield();
      CanFrame f;
      f.id = i & CanFrame::kMaxExtendedId;
      f.extended = true;
      f.dlc = 4;
      f.data = {static_cast<std::uint8_t>(i), static_cast<std::uint8_t>(i >> 8), 0, 0, 0, 0, 0, 0};
      (void)producer->send(f);
    }
  });
  std::uint32_t expected = 0;
  bool in_order = true;
  while (expected < kFrames) {
    Result<std::optional<CanFrame>> received = consumer->receive();
    ASSERT_TRUE(received.ok());
    if (!*received) {
      std::this_thread::yield();
      continue;
    }
    if ((*received)->id != expected) in_order = false;
    ++expected;
  }
  sender.join();
  EXPECT_TRUE(in_order);
  EXPECT_EQ(consumer->overflow_count(), 0U);
}

}  // namespace
}  // namespace sen3bot::hal
