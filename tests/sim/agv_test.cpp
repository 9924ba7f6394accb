// The simulated plant AGV: it follows its order at its speed, honours pause, the centre's
// advisory (SLOW, STOP, CLEAR) and its own short-range scanner, and reports its state.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "sen3bot/sim/agv.hpp"

namespace sen3bot::sim {
namespace {

std::span<const std::uint8_t> bytes(std::string_view text) {
  return {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()};
}

std::string header(int id) {
  return "\"headerId\":" + std::to_string(id) +
         R"(,"timestamp":"2026-12-03T10:00:00.00Z","version":"2.1.0","manufacturer":"PlantAGV","serialNumber":"agv1")";
}

// A straight route along y = 0 from x = 0 to x = 20 m through x = 10 m.
std::string route_order() {
  return "{" + header(1) + R"(,"orderId":"a1","orderUpdateId":0,"nodes":[)"
         R"({"nodeId":"s","sequenceId":0,"released":true,"nodePosition":{"x":0,"y":0,"mapId":"hall"},"actions":[]},)"
         R"({"nodeId":"m","sequenceId":2,"released":true,"nodePosition":{"x":10,"y":0,"mapId":"hall"},"actions":[]},)"
         R"({"nodeId":"e","sequenceId":4,"released":true,"nodePosition":{"x":20,"y":0,"mapId":"hall"},"actions":[]}],"edges":[)"
         R"({"edgeId":"sm","sequenceId":1,"released":true,"startNodeId":"s","endNodeId":"m","actions":[]},)"
         R"({"edgeId":"me","sequenceId":3,"released":true,"startNodeId":"m","endNodeId":"e","actions":[]}]})";
}

std::string advisory(int id, const char* advice, double factor) {
  return R"({"schemaVersion":"1.0.0","headerId":)" + std::to_string(id) +
         R"(,"timestamp":"2026-12-03T10:00:00.00Z","agv":{"manufacturer":"PlantAGV","serialNumber":"agv1"},"advice":")" + advice +
         R"(","speedFactor":)" + std::to_string(factor) +
         R"(,"areaId":"x","areaType":"1.1","people":1,"dynamicPeople":1,"distanceToAreaM":5,"reason":"test"})";
}

struct Rig {
  hal::MemoryBroker broker;
  std::unique_ptr<hal::PubSub> master;
  std::unique_ptr<SimAgv> agv;
  hal::Nanos now = 0;
  Rig() {
    SimAgvConfig config;
    config.serial_number = "agv1";
    config.map_id = "hall";
    config.speed_m_s = 1.0;
    config.accel_m_s2 = 0.5;
    hal::PubSubOptions link;
    link.client_id = "agv1";
    link.subscriptions = SimAgv::subscriptions(config);
    agv = std::make_unique<SimAgv>(config, std::move(broker.connect(link).value()));
    hal::PubSubOptions m;
    m.client_id = "master";
    m.subscriptions = {{"uagv/v2/PlantAGV/agv1/state", 0}};
    m.inbound_slots = 1024;
    master = std::move(broker.connect(m).value());
  }
  void run(double seconds, std::span<const msg::Point2D> people = {}) {
    for (double t = 0; t < seconds; t += 0.05) {
      now += hal::millis(50);
      agv->step(now, 1'800'000'000'000'000'000 + now, 0.05, people);
    }
  }
};

TEST(SimAgv, FollowsItsOrderAtItsSpeedAndStopsOnTheLastNode) {
  Rig rig;
  rig.run(0.1);
  rig.broker.publish("uagv/v2/PlantAGV/agv1/order", bytes(route_order()), false);
  rig.run(5.0);
  EXPECT_NEAR(rig.agv->speed(), 1.0, 1e-6);
  rig.run(20.0);
  EXPECT_NEAR(rig.agv->x(), 20.0, 0.15);
  EXPECT_NEAR(rig.agv->speed(), 0.0, 0.05);
  EXPECT_EQ(rig.agv->vehicle().last_node_id(), "e");
  EXPECT_TRUE(rig.agv->vehicle().node_states().empty());
}

TEST(SimAgv, HonoursTheAdvisoryPauseAndItsOwnScanner) {
  Rig rig;
  rig.broker.publish("uagv/v2/PlantAGV/agv1/order", bytes(route_order()), false);
  rig.run(4.0);
  rig.broker.publish("sen3bot/v1/advisory/PlantAGV/agv1", bytes(advisory(1, "SLOW", 0.3)), true);
  rig.run(3.0);
  EXPECT_EQ(rig.agv->advice(), Advice::slow);
  EXPECT_NEAR(rig.agv->speed(), 0.3, 1e-6);
  rig.broker.publish("sen3bot/v1/advisory/PlantAGV/agv1", bytes(advisory(2, "STOP", 0.0)), true);
  rig.run(2.0);
  EXPECT_EQ(rig.agv->speed(), 0.0);
  const double held = rig.agv->x();
  rig.run(2.0);
  EXPECT_EQ(rig.agv->x(), held);
  rig.broker.publish("sen3bot/v1/advisory/PlantAGV/agv1", bytes(advisory(3, "CLEAR", 1.0)), true);
  rig.run(3.0);
  EXPECT_NEAR(rig.agv->speed(), 1.0, 1e-6);
  rig.broker.publish("uagv/v2/PlantAGV/agv1/instantActions",
                     bytes("{" + header(1) + R"(,"actions":[{"actionId":"p","actionType":"startPause","blockingType":"HARD"}]})"), false);
  rig.run(3.0);
  EXPECT_EQ(rig.agv->speed(), 0.0);
  EXPECT_TRUE(rig.agv->vehicle().paused());
  rig.broker.publish("uagv/v2/PlantAGV/agv1/instantActions",
                     bytes("{" + header(2) + R"(,"actions":[{"actionId":"q","actionType":"stopPause","blockingType":"HARD"}]})"), false);
  rig.run(3.0);
  EXPECT_GT(rig.agv->speed(), 0.5);
  // A person 1.5 m ahead: its own scanner stops it; one behind it does not.
  const msg::Point2D ahead{rig.agv->x() + 1.5, 0.0};
  rig.run(3.0, {&ahead, 1});
  EXPECT_EQ(rig.agv->speed(), 0.0);
  EXPECT_TRUE(rig.agv->stopped_by_own_sensor());
  const msg::Point2D behind{rig.agv->x() - 1.0, 0.0};
  rig.run(3.0, {&behind, 1});
  EXPECT_GT(rig.agv->speed(), 0.5);
}

TEST(SimAgv, ReportsItsStateWithTheRemainingRoute) {
  Rig rig;
  rig.broker.publish("uagv/v2/PlantAGV/agv1/order", bytes(route_order()), false);
  rig.run(3.0);
  std::vector<char> topic(256);
  std::vector<std::uint8_t> payload(64 * 1024);
  auto scratch = std::make_unique<vda5050::DecodeScratch>();
  auto state = std::make_unique<vda5050::State>();
  int states = 0;
  for (;;) {
    auto m = rig.master->receive(topic, payload);
    ASSERT_TRUE(m.ok());
    if (!m.value()) break;
    const std::string_view text(reinterpret_cast<const char*>(payload.data()), m.value()->payload_size);
    ASSERT_TRUE(vda5050::decode_state(text, vda5050::Version::v2_1_0, *state, *scratch).ok()) << text;
    ++states;
  }
  EXPECT_GE(states, 3);
  EXPECT_EQ(state->order_id, "a1");
  EXPECT_EQ(state->last_node_id, "s");
  ASSERT_EQ(state->node_states.size(), 2u);
  EXPECT_EQ(state->node_states[0].node_id, "m");
  ASSERT_TRUE(state->agv_position.has_value());
  EXPECT_GT(state->agv_position->x, 0.5);
  EXPECT_TRUE(state->driving);
}

}  // namespace
}  // namespace sen3bot::sim
