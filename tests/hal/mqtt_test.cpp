// The libmosquitto client against a real Mosquitto broker started by the test: delivery at
// QoS 1 without loss, the last will of a client that dies, the shipped TLS + ACL site
// configuration, refused credentials, and a broker killed and restarted mid-stream.
#include <gtest/gtest.h>
#include <signal.h>

#include <algorithm>
#include <chrono>
#include <string>
#include <thread>
#include <vector>

#include "child_process.hpp"
#include "mosquitto_broker.hpp"
#include "sen3bot/hal/pubsub.hpp"

namespace sen3bot::hal {
namespace {

using testing::MosquittoBroker;
using Clock = std::chrono::steady_clock;

std::span<const std::uint8_t> bytes(std::string_view text) {
  return {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()};
}

PubSubOptions options(const MosquittoBroker& broker, std::string id, std::vector<PubSubSubscription> subs = {}) {
  PubSubOptions o;
  o.url = broker.url();
  o.client_id = std::move(id);
  o.subscriptions = std::move(subs);
  o.reconnect_min_s = 0.05;
  o.reconnect_max_s = 0.4;
  o.keepalive_s = 5;
  return o;
}

template <typename Predicate>
bool wait_for(Predicate done, double seconds = 5.0) {
  const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(seconds));
  while (Clock::now() < deadline) {
    if (done()) return true;
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  return done();
}

struct Inbox {
  std::vector<std::string> topics;
  std::vector<std::string> payloads;
  std::vector<bool> retained;
  void poll(PubSub& client) {
    std::vector<char> topic(256);
    std::vector<std::uint8_t> payload(64 * 1024);
    for (;;) {
      auto message = client.receive(topic, payload);
      ASSERT_TRUE(message.ok());
      if (!message.value()) return;
      topics.emplace_back(topic.data(), message.value()->topic_size);
      payloads.emplace_back(reinterpret_cast<const char*>(payload.data()), message.value()->payload_size);
      retained.push_back(message.value()->retained);
    }
  }
};

// Reads and drops whatever `client` holds.
void drain(PubSub& client) {
  std::vector<char> topic(256);
  std::vector<std::uint8_t> payload(64 * 1024);
  for (;;) {
    auto m = client.receive(topic, payload);
    if (!m.ok() || !m.value()) break;
  }
}

// Clean sessions keep nothing for a subscription not yet made: publish probes on `probe_topic`
// until the reader has one, so the reader's subscription is known to be in place.
void await_subscription(PubSub& writer, PubSub& reader, std::string_view probe_topic) {
  std::vector<char> topic(256);
  std::vector<std::uint8_t> payload(64 * 1024);
  const bool seen = wait_for([&] {
    (void)writer.publish(probe_topic, bytes("probe"), 1, false);
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
    auto m = reader.receive(topic, payload);
    return m.ok() && m.value().has_value();
  }, 20.0);
  ASSERT_TRUE(seen) << "the reader's subscription never came into place";
  // Probes still on their way go too.
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  drain(reader);
}

// Publishes, retrying while the outbound queue is full.
void publish_all(PubSub& client, std::string_view topic, int count, int first = 0) {
  for (int i = first; i < first + count; ++i) {
    const std::string payload = std::to_string(i);
    for (;;) {
      const Status status = client.publish(topic, bytes(payload), 1, false);
      if (status.ok()) break;
      ASSERT_EQ(status.error().code(), Errc::capacity) << status.error().c_str();
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  }
}

TEST(Mqtt, TwoThousandQos1MessagesArriveInOrder) {
  MosquittoBroker broker = MosquittoBroker::plain();
  broker.start();
  auto sub_options = options(broker, "reader", {{"fleet/#", 1}});
  sub_options.inbound_slots = 4096;
  auto reader = open_mqtt(sub_options);
  auto writer = open_mqtt(options(broker, "writer"));
  ASSERT_TRUE(reader.ok()) << reader.error().c_str();
  ASSERT_TRUE(writer.ok()) << writer.error().c_str();
  ASSERT_TRUE(wait_for([&] { return (*reader)->state() == PubSubState::connected && (*writer)->state() == PubSubState::connected; }));
  await_subscription(**writer, **reader, "fleet/probe");
  publish_all(**writer, "fleet/r1/people", 2000);
  Inbox inbox;
  ASSERT_TRUE(wait_for([&] {
    inbox.poll(**reader);
    return inbox.payloads.size() >= 2000;
  }, 20.0)) << inbox.payloads.size();
  ASSERT_EQ(inbox.payloads.size(), 2000u);
  for (int i = 0; i < 2000; ++i) ASSERT_EQ(inbox.payloads[static_cast<std::size_t>(i)], std::to_string(i));
  EXPECT_TRUE(wait_for([&] { return (*writer)->stats().published >= 2000; })) << (*writer)->stats().published;
  EXPECT_EQ((*reader)->stats().receive_dropped, 0u);
}

TEST(Mqtt, AKilledClientsWillIsPublishedAndACleanCloseSendsNone) {
  MosquittoBroker broker = MosquittoBroker::plain();
  broker.start();
  auto watcher = open_mqtt(options(broker, "watcher", {{"uagv/v2/+/+/connection", 1}}));
  ASSERT_TRUE(watcher.ok());
  ASSERT_TRUE(wait_for([&] { return (*watcher)->state() == PubSubState::connected; }));

  // A clean close first: no will.
  auto polite_options = options(broker, "polite");
  polite_options.will = PubSubWill{"uagv/v2/S3B/polite/connection", "BROKEN polite", 1, true};
  auto polite = open_mqtt(polite_options);
  ASSERT_TRUE(polite.ok());
  ASSERT_TRUE(wait_for([&] { return (*polite)->state() == PubSubState::connected; }));
  (*polite)->close(1.0);

  // A process that dies with its connection open: killed once the broker has accepted it.
  const std::string dir = broker.dir();
  testing::ChildProcess doomed({SEN3BOT_MQTT_WILL_CLIENT, broker.url(), "doomed", "uagv/v2/S3B/doomed/connection", "BROKEN doomed"},
                               dir + "/doomed.out", dir + "/doomed.err");
  ASSERT_TRUE(doomed.started());
  ASSERT_TRUE(wait_for([&] { return doomed.out().find("connected") != std::string::npos; }, 30.0)) << doomed.err();
  doomed.signal(SIGKILL);
  EXPECT_EQ(doomed.wait(10.0), 128 + SIGKILL);
  Inbox inbox;
  ASSERT_TRUE(wait_for([&] {
    inbox.poll(**watcher);
    return !inbox.payloads.empty();
  }));
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  inbox.poll(**watcher);
  ASSERT_EQ(inbox.payloads.size(), 1u);
  EXPECT_EQ(inbox.payloads[0], "BROKEN doomed");

  // Retained: a centre that starts later still learns of it.
  auto late = open_mqtt(options(broker, "late", {{"uagv/v2/+/+/connection", 1}}));
  ASSERT_TRUE(late.ok());
  Inbox late_inbox;
  ASSERT_TRUE(wait_for([&] {
    late_inbox.poll(**late);
    return !late_inbox.payloads.empty();
  }));
  EXPECT_EQ(late_inbox.payloads[0], "BROKEN doomed");
  EXPECT_TRUE(late_inbox.retained[0]);
}

class MqttSite : public ::testing::Test {
 protected:
  MqttSite()
      : broker_(MosquittoBroker::site({{"ssc", "centre-secret"}, {"r1", "robot1-secret"}, {"r2", "robot2-secret"}})) {
    broker_.start();
  }
  PubSubOptions tls(std::string user, std::string password, std::vector<PubSubSubscription> subs = {}) {
    PubSubOptions o = options(broker_, user, std::move(subs));
    o.url = broker_.url("mqtts");
    o.ca_file = broker_.ca_file();
    o.username = std::move(user);
    o.password = std::move(password);
    return o;
  }
  MosquittoBroker broker_;
};

TEST_F(MqttSite, ARobotPublishesOnlyItsOwnTopicsAndOnlyTheCentreSendsOrders) {
  auto centre = open_mqtt(tls("ssc", "centre-secret", {{"uagv/#", 1}}));
  auto r1 = open_mqtt(tls("r1", "robot1-secret", {{"uagv/v2/+/r1/order", 1}}));
  auto r2 = open_mqtt(tls("r2", "robot2-secret", {{"uagv/v2/+/r2/order", 1}, {"uagv/v2/+/r1/state", 1}}));
  ASSERT_TRUE(centre.ok() && r1.ok() && r2.ok());
  ASSERT_TRUE(wait_for([&] {
    return (*centre)->state() == PubSubState::connected && (*r1)->state() == PubSubState::connected &&
           (*r2)->state() == PubSubState::connected;
  })) << broker_.log();
  // Each client's subscriptions are in place once a probe from a peer allowed to write has come
  // through; the centre sees the robots' probes too, so everyone starts empty.
  await_subscription(**r1, **centre, "uagv/v2/S3B/r1/visualization");
  await_subscription(**centre, **r1, "uagv/v2/probe/r1/order");
  await_subscription(**centre, **r2, "uagv/v2/probe/r2/order");
  std::this_thread::sleep_for(std::chrono::milliseconds(200));
  drain(**centre);

  ASSERT_TRUE((*r1)->publish("uagv/v2/S3B/r1/state", bytes("own state"), 1, false).ok());
  ASSERT_TRUE((*r1)->publish("uagv/v2/S3B/r2/state", bytes("forged state"), 1, false).ok());
  ASSERT_TRUE((*r1)->publish("uagv/v2/S3B/r2/order", bytes("forged order"), 1, false).ok());
  ASSERT_TRUE((*r1)->publish("uagv/v2/S3B/r1/order", bytes("self order"), 1, false).ok());
  ASSERT_TRUE((*centre)->publish("uagv/v2/S3B/r1/order", bytes("real order"), 1, false).ok());
  ASSERT_TRUE((*r1)->publish("uagv/v2/S3B/r1/connection", bytes("last"), 1, false).ok());

  Inbox at_centre, at_r1, at_r2;
  ASSERT_TRUE(wait_for([&] {
    at_centre.poll(**centre);
    return at_centre.payloads.size() >= 3;  // own state, the real order, the connection
  }));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  at_centre.poll(**centre);
  at_r1.poll(**r1);
  at_r2.poll(**r2);
  std::sort(at_centre.payloads.begin(), at_centre.payloads.end());  // from two clients: any order
  EXPECT_EQ(at_centre.payloads, (std::vector<std::string>{"last", "own state", "real order"}));
  EXPECT_EQ(at_r1.payloads, (std::vector<std::string>{"real order"}));
  // r2 asked for r1's state too, but a robot reads only its own orders: nothing, and no forgery.
  EXPECT_TRUE(at_r2.payloads.empty());
}

// Formation commands: only the centre writes them, and a robot reads only its own.
TEST_F(MqttSite, OnlyTheCentreSendsFormationCommandsAndARobotReadsOnlyItsOwn) {
  auto centre = open_mqtt(tls("ssc", "centre-secret"));
  auto r1 = open_mqtt(tls("r1", "robot1-secret", {{"sen3bot/v1/formation/+/r1", 1}}));
  auto r2 = open_mqtt(tls("r2", "robot2-secret", {{"sen3bot/v1/formation/+/r2", 1}, {"sen3bot/v1/formation/+/r1", 1}}));
  ASSERT_TRUE(centre.ok() && r1.ok() && r2.ok());
  ASSERT_TRUE(wait_for([&] {
    return (*centre)->state() == PubSubState::connected && (*r1)->state() == PubSubState::connected &&
           (*r2)->state() == PubSubState::connected;
  })) << broker_.log();
  await_subscription(**centre, **r1, "sen3bot/v1/formation/probe/r1");
  await_subscription(**centre, **r2, "sen3bot/v1/formation/probe/r2");

  ASSERT_TRUE((*r2)->publish("sen3bot/v1/formation/S3B/r1", bytes("forged by r2"), 1, false).ok());
  ASSERT_TRUE((*r1)->publish("sen3bot/v1/formation/S3B/r1", bytes("own"), 1, false).ok());
  ASSERT_TRUE((*centre)->publish("sen3bot/v1/formation/S3B/r1", bytes("for r1"), 1, false).ok());
  ASSERT_TRUE((*centre)->publish("sen3bot/v1/formation/S3B/r2", bytes("for r2"), 1, false).ok());

  Inbox at_r1, at_r2;
  ASSERT_TRUE(wait_for([&] {
    at_r1.poll(**r1);
    at_r2.poll(**r2);
    return !at_r1.payloads.empty() && !at_r2.payloads.empty();
  }));
  std::this_thread::sleep_for(std::chrono::milliseconds(300));
  at_r1.poll(**r1);
  at_r2.poll(**r2);
  EXPECT_EQ(at_r1.payloads, (std::vector<std::string>{"for r1"}));
  // r2 asked for r1's commands too: it gets only its own.
  EXPECT_EQ(at_r2.payloads, (std::vector<std::string>{"for r2"}));
}

TEST_F(MqttSite, WrongCredentialsAreRefusedAndPlainTextIsNotSpoken) {
  auto intruder = open_mqtt(tls("r1", "guess"));
  ASSERT_TRUE(intruder.ok());
  ASSERT_TRUE(wait_for([&] { return (*intruder)->stats().connections_refused > 0; })) << broker_.log();
  EXPECT_NE((*intruder)->state(), PubSubState::connected);
  EXPECT_EQ((*intruder)->session(), 0u);

  PubSubOptions plain = tls("r1", "robot1-secret");
  plain.url = broker_.url("mqtt");  // the TLS port, spoken to in plain text
  auto confused = open_mqtt(plain);
  ASSERT_TRUE(confused.ok());
  std::this_thread::sleep_for(std::chrono::milliseconds(500));
  EXPECT_EQ((*confused)->session(), 0u);

  PubSubOptions no_ca = tls("r1", "robot1-secret");
  no_ca.ca_file.clear();
  auto refused = open_mqtt(no_ca);
  ASSERT_FALSE(refused.ok());
  EXPECT_EQ(refused.error().code(), Errc::config);
  PubSubOptions http;
  http.url = "http://broker";
  auto bad_url = open_mqtt(http);
  ASSERT_FALSE(bad_url.ok());
  EXPECT_EQ(bad_url.error().code(), Errc::config);
  PubSubOptions hasty = tls("r1", "robot1-secret");
  hasty.keepalive_s = 2;  // libmosquitto would refuse every connect
  auto too_short = open_mqtt(hasty);
  ASSERT_FALSE(too_short.ok());
  EXPECT_EQ(too_short.error().code(), Errc::config);
}

TEST(Mqtt, ABrokerKilledAndRestartedMidStreamLosesNoSessionAndTheQueueCatchesUp) {
  MosquittoBroker broker = MosquittoBroker::plain();
  broker.start();
  auto reader_options = options(broker, "reader", {{"fleet/#", 1}});
  reader_options.inbound_slots = 1024;
  reader_options.reconnect_max_s = 0.2;
  // The writer comes back later than the reader, so the reader has subscribed again (clean
  // sessions, a broker without persistence) before the writer's held messages go out.
  auto writer_options = options(broker, "writer");
  writer_options.outbound_slots = 256;
  writer_options.reconnect_min_s = 1.0;
  writer_options.reconnect_max_s = 1.0;
  auto reader = open_mqtt(reader_options);
  auto writer = open_mqtt(writer_options);
  ASSERT_TRUE(reader.ok() && writer.ok());
  ASSERT_TRUE(wait_for([&] { return (*reader)->state() == PubSubState::connected && (*writer)->state() == PubSubState::connected; }));
  await_subscription(**writer, **reader, "fleet/probe");
  publish_all(**writer, "fleet/state", 100);
  Inbox inbox;
  ASSERT_TRUE(wait_for([&] {
    inbox.poll(**reader);
    return inbox.payloads.size() >= 100;
  }));

  broker.kill();
  ASSERT_TRUE(wait_for([&] { return (*writer)->state() == PubSubState::disconnected; }));
  // Published while the broker is away: held in the bounded queue.
  publish_all(**writer, "fleet/state", 100, 100);
  broker.start();
  ASSERT_TRUE(wait_for([&] { return (*reader)->session() == 2 && (*writer)->session() == 2; }, 10.0));
  ASSERT_TRUE(wait_for([&] {
    inbox.poll(**reader);
    return inbox.payloads.size() >= 200;
  }, 10.0)) << inbox.payloads.size();
  ASSERT_EQ(inbox.payloads.size(), 200u);
  for (int i = 0; i < 200; ++i) ASSERT_EQ(inbox.payloads[static_cast<std::size_t>(i)], std::to_string(i));
  EXPECT_EQ((*writer)->stats().publish_dropped, 0u);
  EXPECT_EQ((*writer)->stats().connection_losses, 1u);
}

}  // namespace
}  // namespace sen3bot::hal
