// Topic rules, the bounded queue, and the in-process broker's MQTT semantics.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "sen3bot/hal/pubsub.hpp"

namespace sen3bot::hal {
namespace {

std::span<const std::uint8_t> bytes(std::string_view text) {
  return {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()};
}

struct Received {
  std::string topic;
  std::string payload;
  bool retained = false;
  int qos = 0;
};

std::vector<Received> drain(PubSub& client) {
  std::vector<Received> out;
  std::vector<char> topic(256);
  std::vector<std::uint8_t> payload(64 * 1024);
  for (;;) {
    auto message = client.receive(topic, payload);
    EXPECT_TRUE(message.ok());
    if (!message.ok() || !message.value()) return out;
    const PubSubMessage& m = *message.value();
    out.push_back({std::string(topic.data(), m.topic_size),
                   std::string(reinterpret_cast<const char*>(payload.data()), m.payload_size), m.retained, m.qos});
  }
}

PubSubOptions client(std::string id, std::vector<PubSubSubscription> subscriptions = {}) {
  PubSubOptions options;
  options.url = "sim";
  options.client_id = std::move(id);
  options.subscriptions = std::move(subscriptions);
  return options;
}

TEST(TopicRules, FiltersMatchAsMqttSays) {
  struct Case {
    const char* filter;
    const char* topic;
    bool match;
  };
  const Case cases[] = {
      {"uagv/v2/ACME/0001/order", "uagv/v2/ACME/0001/order", true},
      {"uagv/v2/ACME/0001/order", "uagv/v2/ACME/0001/orders", false},
      {"uagv/v2/+/+/state", "uagv/v2/ACME/0001/state", true},
      {"uagv/v2/+/+/state", "uagv/v2/ACME/state", false},
      {"uagv/v2/+/+/state", "uagv/v2/ACME/0001/x/state", false},
      {"uagv/#", "uagv/v2/ACME/0001/state", true},
      {"uagv/#", "uagv", true},  // '#' takes in the parent level
      {"#", "anything/at/all", true},
      {"+", "one", true},
      {"+", "one/two", false},
      {"+/+", "/x", true},  // an empty level is a level
      {"#", "$SYS/broker/uptime", false},
      {"+/broker/uptime", "$SYS/broker/uptime", false},
      {"$SYS/#", "$SYS/broker/uptime", true},
      {"a/b", "a/b/", false},
      {"a/b/", "a/b/", true},
  };
  for (const Case& c : cases) EXPECT_EQ(topic_matches(c.filter, c.topic), c.match) << c.filter << " vs " << c.topic;
}

TEST(TopicRules, PublishTopicsAndFiltersAreChecked) {
  EXPECT_TRUE(valid_publish_topic("uagv/v2/ACME/0001/state", 256));
  EXPECT_FALSE(valid_publish_topic("", 256));
  EXPECT_FALSE(valid_publish_topic("uagv/+/state", 256));
  EXPECT_FALSE(valid_publish_topic("uagv/#", 256));
  EXPECT_FALSE(valid_publish_topic(std::string_view("a\0b", 3), 256));
  EXPECT_FALSE(valid_publish_topic(std::string(257, 'a'), 256));
  EXPECT_TRUE(valid_topic_filter("uagv/v2/+/+/order"));
  EXPECT_TRUE(valid_topic_filter("#"));
  EXPECT_FALSE(valid_topic_filter("uagv/#/order"));
  EXPECT_FALSE(valid_topic_filter("uagv/v2+/order"));
  EXPECT_FALSE(valid_topic_filter("uagv/ab#"));
  EXPECT_FALSE(valid_topic_filter(""));
}

TEST(MessageQueue, KeepsOrderRefusesWhenFullAndNeverTruncates) {
  MessageQueue queue(2, 8, 4);
  EXPECT_TRUE(queue.push("a", bytes("1"), 0, false));
  EXPECT_TRUE(queue.push("bb", bytes("22"), 1, true));
  EXPECT_FALSE(queue.push("c", bytes("3"), 0, false));       // full
  char topic[8];
  std::uint8_t payload[4];
  auto first = queue.pop(topic, payload);
  ASSERT_TRUE(first.ok() && first.value());
  EXPECT_EQ(std::string_view(topic, first.value()->topic_size), "a");
  EXPECT_TRUE(queue.push("toolongtopic", bytes("1"), 0, false) == false);
  EXPECT_FALSE(queue.push("c", bytes("55555"), 0, false));  // payload over the slot
  char small_topic[1];
  auto refused = queue.pop(small_topic, payload);           // "bb" stays queued
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code(), Errc::capacity);
  auto second = queue.pop(topic, payload);
  ASSERT_TRUE(second.ok() && second.value());
  EXPECT_EQ(second.value()->qos, 1);
  EXPECT_TRUE(second.value()->retained);
  EXPECT_EQ(std::string_view(reinterpret_cast<char*>(payload), second.value()->payload_size), "22");
  auto none = queue.pop(topic, payload);
  ASSERT_TRUE(none.ok());
  EXPECT_FALSE(none.value());
}

TEST(MemoryBroker, RoutesByFilterAndDeliversAtTheLowerQos) {
  MemoryBroker broker;
  auto master = broker.connect(client("master", {{"uagv/v2/+/+/state", 1}}));
  auto robot = broker.connect(client("robot", {{"uagv/v2/S3B/r1/order", 0}}));
  ASSERT_TRUE(master.ok() && robot.ok());
  EXPECT_EQ((*master)->state(), PubSubState::connected);
  EXPECT_EQ((*master)->session(), 1u);
  ASSERT_TRUE((*robot)->publish("uagv/v2/S3B/r1/state", bytes("{\"a\":1}"), 0, false).ok());
  ASSERT_TRUE((*master)->publish("uagv/v2/S3B/r1/order", bytes("{}"), 1, false).ok());
  ASSERT_TRUE((*master)->publish("uagv/v2/S3B/r2/order", bytes("{}"), 1, false).ok());
  const auto at_master = drain(**master);
  ASSERT_EQ(at_master.size(), 1u);
  EXPECT_EQ(at_master[0].topic, "uagv/v2/S3B/r1/state");
  EXPECT_EQ(at_master[0].payload, "{\"a\":1}");
  EXPECT_EQ(at_master[0].qos, 0);
  const auto at_robot = drain(**robot);
  ASSERT_EQ(at_robot.size(), 1u);
  EXPECT_EQ(at_robot[0].topic, "uagv/v2/S3B/r1/order");
  EXPECT_EQ(at_robot[0].qos, 0);
}

TEST(MemoryBroker, RetainedMessagesReachLateSubscribersAndAnEmptyOneClearsThem) {
  MemoryBroker broker;
  auto robot = broker.connect(client("robot"));
  ASSERT_TRUE(robot.ok());
  ASSERT_TRUE((*robot)->publish("uagv/v2/S3B/r1/connection", bytes("ONLINE"), 1, true).ok());
  ASSERT_TRUE((*robot)->publish("uagv/v2/S3B/r1/connection", bytes("ONLINE2"), 1, true).ok());
  auto late = broker.connect(client("late", {{"uagv/v2/+/+/connection", 1}}));
  ASSERT_TRUE(late.ok());
  auto got = drain(**late);
  ASSERT_EQ(got.size(), 1u);
  EXPECT_EQ(got[0].payload, "ONLINE2");
  EXPECT_TRUE(got[0].retained);
  ASSERT_TRUE((*robot)->publish("uagv/v2/S3B/r1/connection", bytes(""), 1, true).ok());
  auto later = broker.connect(client("later", {{"uagv/#", 1}}));
  ASSERT_TRUE(later.ok());
  EXPECT_TRUE(drain(**later).empty());
}

TEST(MemoryBroker, AWillIsPublishedWhenAClientIsCutOffOrDisappearsButNotOnClose) {
  MemoryBroker broker;
  auto master = broker.connect(client("master", {{"uagv/v2/+/+/connection", 1}}));
  ASSERT_TRUE(master.ok());
  auto with_will = [](std::string id) {
    PubSubOptions options = client(id);
    options.will = PubSubWill{"uagv/v2/S3B/" + id + "/connection", "BROKEN " + id, 1, true};
    return options;
  };
  auto r1 = broker.connect(with_will("r1"));
  auto r2 = broker.connect(with_will("r2"));
  auto r3 = broker.connect(with_will("r3"));
  ASSERT_TRUE(r1.ok() && r2.ok() && r3.ok());

  broker.set_reachable("r1", false);  // a lost network
  EXPECT_EQ((*r1)->state(), PubSubState::disconnected);
  (*r2)->close();                      // a clean goodbye
  EXPECT_EQ((*r2)->state(), PubSubState::closed);
  r3.value().reset();                  // a crashed process
  const auto got = drain(**master);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].payload, "BROKEN r1");
  EXPECT_EQ(got[1].payload, "BROKEN r3");
}

TEST(MemoryBroker, ACutOffClientKeepsItsPublishesQueuedAndSendsThemOnReconnect) {
  MemoryBroker broker;
  auto master = broker.connect(client("master", {{"uagv/v2/+/+/state", 0}}));
  PubSubOptions options = client("r1", {{"uagv/v2/S3B/r1/order", 0}});
  options.outbound_slots = 2;
  auto robot = broker.connect(options);
  ASSERT_TRUE(master.ok() && robot.ok());
  broker.set_reachable("r1", false);
  ASSERT_TRUE((*robot)->publish("uagv/v2/S3B/r1/state", bytes("1"), 0, false).ok());
  ASSERT_TRUE((*robot)->publish("uagv/v2/S3B/r1/state", bytes("2"), 0, false).ok());
  const Status third = (*robot)->publish("uagv/v2/S3B/r1/state", bytes("3"), 0, false);
  ASSERT_FALSE(third.ok());
  EXPECT_EQ(third.error().code(), Errc::capacity);
  ASSERT_TRUE((*master)->publish("uagv/v2/S3B/r1/order", bytes("lost"), 0, false).ok());  // not for a cut-off client
  EXPECT_TRUE(drain(**master).empty());

  broker.set_reachable("r1", true);
  EXPECT_EQ((*robot)->state(), PubSubState::connected);
  EXPECT_EQ((*robot)->session(), 2u);
  const auto got = drain(**master);
  ASSERT_EQ(got.size(), 2u);
  EXPECT_EQ(got[0].payload, "1");
  EXPECT_EQ(got[1].payload, "2");
  EXPECT_TRUE(drain(**robot).empty());
  const PubSubStats stats = (*robot)->stats();
  EXPECT_EQ(stats.publish_dropped, 1u);
  EXPECT_EQ(stats.connection_losses, 1u);
  EXPECT_EQ(stats.connects, 2u);
}

TEST(MemoryBroker, AFullInboxDropsAndCountsAndOversizedMessagesAreRefused) {
  MemoryBroker broker;
  PubSubOptions options = client("slow", {{"t/#", 1}});
  options.inbound_slots = 3;
  options.max_payload = 8;
  auto slow = broker.connect(options);
  auto fast = broker.connect(client("fast"));
  ASSERT_TRUE(slow.ok() && fast.ok());
  for (int i = 0; i < 5; ++i) ASSERT_TRUE((*fast)->publish("t/x", bytes("m"), 1, false).ok());
  ASSERT_TRUE((*fast)->publish("t/big", bytes("0123456789"), 1, false).ok());
  EXPECT_EQ(drain(**slow).size(), 3u);
  const PubSubStats stats = (*slow)->stats();
  EXPECT_EQ(stats.received, 3u);
  EXPECT_EQ(stats.receive_dropped, 2u);
  EXPECT_EQ(stats.receive_oversized, 1u);
  EXPECT_EQ(broker.deliveries_dropped(), 3u);
  EXPECT_FALSE((*slow)->publish("t/#", bytes("x"), 0, false).ok());
  EXPECT_FALSE((*slow)->publish("t/x", bytes("0123456789"), 0, false).ok());
  EXPECT_FALSE((*slow)->publish("t/x", bytes("x"), 2, false).ok());
  EXPECT_EQ((*slow)->stats().publish_refused, 3u);
}

TEST(MemoryBroker, ClientIdsAreUniqueAndBounded) {
  MemoryBroker::Limits limits;
  limits.max_clients = 2;
  MemoryBroker broker(limits);
  auto a = broker.connect(client("a"));
  ASSERT_TRUE(a.ok());
  auto again = broker.connect(client("a"));
  ASSERT_FALSE(again.ok());
  EXPECT_EQ(again.error().code(), Errc::invalid_argument);
  auto b = broker.connect(client("b"));
  ASSERT_TRUE(b.ok());
  auto c = broker.connect(client("c"));
  ASSERT_FALSE(c.ok());
  EXPECT_EQ(c.error().code(), Errc::capacity);
  (*a)->close();
  EXPECT_TRUE(broker.connect(client("c")).ok());
  auto bad = broker.connect(client("d", {{"a/#/b", 0}}));
  EXPECT_FALSE(bad.ok());
}

}  // namespace
}  // namespace sen3bot::hal
