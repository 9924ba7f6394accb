// The robot on a real Mosquitto: the whole firmware on the simulated robot, paced to real time,
// its fleet link a real MQTT client. The broker is killed in the middle of an order and started
// again: the robot drives on, the broker tells the master CONNECTIONBROKEN, and once the broker
// is back the robot reconnects, says ONLINE and sends its state, and the order completes.
#include <gtest/gtest.h>

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "firmware.hpp"
#include "mosquitto_broker.hpp"
#include "sen3bot/vda5050/codec.hpp"
#include "sim_rig.hpp"

namespace sen3bot {
namespace {

using Clock = std::chrono::steady_clock;

std::string order_json() {
  const char* header =
      R"("headerId":1,"timestamp":"2026-12-03T10:00:00.00Z","version":"2.1.0","manufacturer":"Sen3Bot","serialNumber":"r1")";
  return std::string("{") + header +
         R"(,"orderId":"o1","orderUpdateId":0,"nodes":[)"
         R"({"nodeId":"n0","sequenceId":0,"released":true,"nodePosition":{"x":2.5,"y":2.0,"mapId":"lab","allowedDeviationXY":0.3},"actions":[]},)"
         R"({"nodeId":"n1","sequenceId":2,"released":true,"nodePosition":{"x":2.85,"y":3.5,"mapId":"lab","allowedDeviationXY":0.3},"actions":[]},)"
         R"({"nodeId":"n2","sequenceId":4,"released":true,"nodePosition":{"x":2.9,"y":4.25,"mapId":"lab","allowedDeviationXY":0.3},"actions":[]}],)"
         R"("edges":[{"edgeId":"e0","sequenceId":1,"released":true,"startNodeId":"n0","endNodeId":"n1","actions":[]},)"
         R"({"edgeId":"e1","sequenceId":3,"released":true,"startNodeId":"n1","endNodeId":"n2","actions":[]}]})";
}

class BrokerRig {
 public:
  BrokerRig() : broker_(testing::MosquittoBroker::plain()), rig_(testing::load_sim_rig()) {
    broker_.start();
    firmware::FirmwareConfig& c = rig_.config;
    c.navigation.mission.goal_count = 0;
    c.tasks.erase("mission");
    c.tasks["fleet"] = firmware::TaskConfig{firmware::FleetTask::arena_bytes_needed() + 64 * 1024};
    c.has_fleet = true;
    c.fleet.broker = broker_.url();
    c.fleet.serial_number = "r1";
    c.fleet.map_id = "lab";
    sink_ = std::fopen("/dev/null", "w");
    fw_ = std::make_unique<firmware::Firmware>(c, *rig_.board, sink_);
    hal::PubSubOptions master;
    master.url = broker_.url();
    master.client_id = "master";
    master.subscriptions = {{"uagv/v2/Sen3Bot/r1/state", 0}, {"uagv/v2/Sen3Bot/r1/connection", 1}};
    master.inbound_slots = 1024;
    master.reconnect_min_s = 0.1;
    master.reconnect_max_s = 0.5;
    auto client = hal::open_mqtt(master);
    EXPECT_TRUE(client.ok());
    if (client.ok()) master_ = std::move(client.value());
  }
  ~BrokerRig() {
    fw_->shutdown();
    std::fclose(sink_);
  }
  Status init() { return fw_->init(); }
  testing::MosquittoBroker& broker() { return broker_; }
  hal::PubSub& master() { return *master_; }
  firmware::Firmware& fw() { return *fw_; }

  // Runs simulated time at about the pace of real time, so the link's timers mean what they say.
  template <typename Predicate>
  bool run_until(Predicate done, double limit_s) {
    const auto start = Clock::now();
    while (std::chrono::duration<double>(Clock::now() - start).count() < limit_s) {
      const auto slice_start = Clock::now();
      if (!fw_->scheduler().run_lockstep(rig_.clock(), hal::millis(20))) return false;
      drain();
      if (done()) return true;
      std::this_thread::sleep_until(slice_start + std::chrono::milliseconds(20));
    }
    return done();
  }
  [[nodiscard]] const vda5050::State& state() const { return *state_; }
  [[nodiscard]] bool have_state() const { return have_state_; }
  [[nodiscard]] const std::vector<std::string>& connections() const { return connections_; }
  [[nodiscard]] nav::Pose2D truth() { return rig_.board->simulation().truth().pose; }
  [[nodiscard]] int states() const { return states_; }

 private:
  void drain() {
    for (;;) {
      auto m = master_->receive(topic_, payload_);
      if (!m.ok() || !m.value()) return;
      const std::string_view topic(topic_.data(), m.value()->topic_size);
      const std::string_view text(reinterpret_cast<const char*>(payload_.data()), m.value()->payload_size);
      if (topic.ends_with("/state")) {
        if (vda5050::decode_state(text, vda5050::Version::v2_1_0, *state_, scratch_).ok()) {
          have_state_ = true;
          ++states_;
        }
      } else {
        vda5050::Connection c;
        if (vda5050::decode_connection(text, vda5050::Version::v2_1_0, c, scratch_).ok())
          connections_.emplace_back(vda5050::to_string(c.state));
      }
    }
  }

  testing::MosquittoBroker broker_;
  testing::SimRig rig_;
  std::FILE* sink_ = nullptr;
  std::unique_ptr<firmware::Firmware> fw_;
  std::unique_ptr<hal::PubSub> master_;
  std::vector<char> topic_ = std::vector<char>(256);
  std::vector<std::uint8_t> payload_ = std::vector<std::uint8_t>(64 * 1024);
  vda5050::DecodeScratch scratch_;
  std::unique_ptr<vda5050::State> state_ = std::make_unique<vda5050::State>();
  bool have_state_ = false;
  int states_ = 0;
  std::vector<std::string> connections_;
};

TEST(FleetBroker, ABrokerKilledMidOrderLeavesTheRobotDrivingAndItComesBackWithItsState) {
  BrokerRig rig;
  ASSERT_TRUE(rig.init().ok());
  ASSERT_TRUE(rig.run_until([&] { return rig.have_state() && rig.state().agv_position && rig.state().agv_position->position_initialized; },
                            10.0)) << "states " << rig.states() << " connections " << rig.connections().size()
                                   << " master " << hal::to_string(rig.master().state()) << " robot link "
                                   << (rig.fw().fleet() && rig.fw().fleet()->link() ? hal::to_string(rig.fw().fleet()->link()->state()) : "none")
                                   << " published " << (rig.fw().fleet() ? rig.fw().fleet()->counters().states_published : 0)
                                   << " link published " << (rig.fw().fleet() && rig.fw().fleet()->link() ? rig.fw().fleet()->link()->stats().published : 0);
  ASSERT_FALSE(rig.connections().empty());
  EXPECT_EQ(rig.connections().back(), "ONLINE");
  const std::string order = order_json();
  ASSERT_TRUE(rig.master().publish("uagv/v2/Sen3Bot/r1/order", hal::as_bytes(order), 0, false).ok());
  ASSERT_TRUE(rig.run_until([&] { return rig.state().order_id == "o1" && rig.state().driving; }, 10.0));

  rig.broker().kill();
  const nav::Pose2D at_kill = rig.truth();
  const int states_before = rig.states();
  // Two seconds without a broker: the robot drives on (VDA 5050 6.2).
  ASSERT_TRUE(rig.run_until([] { return false; }, 2.0) == false);
  EXPECT_GT(std::hypot(rig.truth().x_m - at_kill.x_m, rig.truth().y_m - at_kill.y_m), 0.3);
  EXPECT_EQ(rig.states(), states_before);

  rig.broker().start();
  // The robot comes back: ONLINE again, states again, and the order completes.
  ASSERT_TRUE(rig.run_until([&] { return rig.states() > states_before; }, 15.0)) << "no state after the broker came back";
  ASSERT_TRUE(rig.run_until([&] { return rig.state().last_node_id == "n2" && rig.state().node_states.empty() && !rig.state().driving; },
                            30.0));
  EXPECT_EQ(rig.state().order_id, "o1");
  EXPECT_GE(std::count(rig.connections().begin(), rig.connections().end(), "ONLINE"), 2);
  EXPECT_LT(std::hypot(rig.truth().x_m - 2.9, rig.truth().y_m - 4.25), 0.2);
}

}  // namespace
}  // namespace sen3bot
