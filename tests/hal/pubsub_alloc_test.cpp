// The in-process broker and its clients allocate when they connect and never afterwards:
// publishing, routing, retained messages, receiving, a cut-off and a reconnect.
#include <gtest/gtest.h>

#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/hal/pubsub.hpp"

namespace sen3bot::hal {
namespace {

using mem::testing::AllocationScope;

TEST(HalNoAllocation, MemoryBrokerSteadyState) {
  MemoryBroker broker;
  PubSubOptions master_options;
  master_options.client_id = "master";
  master_options.subscriptions = {{"uagv/v2/+/+/state", 0}, {"uagv/v2/+/+/connection", 1}};
  PubSubOptions robot_options;
  robot_options.client_id = "r1";
  robot_options.subscriptions = {{"uagv/v2/S3B/r1/order", 0}};
  robot_options.will = PubSubWill{"uagv/v2/S3B/r1/connection", "{\"connectionState\":\"CONNECTIONBROKEN\"}", 1, true};
  auto master = broker.connect(master_options);
  auto robot = broker.connect(robot_options);
  ASSERT_TRUE(master.ok() && robot.ok());
  std::vector<char> topic(256);
  std::vector<std::uint8_t> payload(64 * 1024);
  const std::uint8_t state[] = "{\"headerId\":1}";
  std::size_t received = 0;
  AllocationScope scope;
  for (int round = 0; round < 500; ++round) {
    Status a = (*robot)->publish("uagv/v2/S3B/r1/state", state, 0, false);
    Status b = (*robot)->publish("uagv/v2/S3B/r1/connection", state, 1, true);
    Status c = (*master)->publish("uagv/v2/S3B/r1/order", state, 0, false);
    EXPECT_TRUE(a.ok() && b.ok() && c.ok());
    if (round % 50 == 0) {
      broker.set_reachable("r1", false);
      broker.set_reachable("r1", true);
    }
    for (PubSub* client : {master->get(), robot->get()}) {
      for (;;) {
        auto message = client->receive(topic, payload);
        if (!message.ok() || !message.value()) break;
        ++received;
      }
    }
  }
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(scope.malloc_calls(), 0u);
  EXPECT_GT(received, 1500u);
}

}  // namespace
}  // namespace sen3bot::hal
