// The robot as a VDA 5050 vehicle, end to end in lockstep: the whole firmware on the simulated
// robot (config/sim.yaml with a fleet section instead of goals), its link a client of the
// site's in-process broker, and a master control in the test that writes its orders and
// instant actions as JSON text of its own and reads the robot's messages back.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdlib>
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "firmware.hpp"
#include "sen3bot/vda5050/codec.hpp"
#include "sen3bot/vda5050/extensions.hpp"
#include "sim_rig.hpp"

namespace sen3bot {
namespace {

constexpr const char* kPrefix = "uagv/v2/Sen3Bot/r1/";

std::span<const std::uint8_t> bytes(std::string_view text) {
  return {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()};
}

// The version the master writes in its headers.
std::string g_version = "2.1.0";

std::string header(int id) {
  return "\"headerId\":" + std::to_string(id) + ",\"timestamp\":\"2026-12-03T10:00:00.00Z\",\"version\":\"" + g_version +
         "\",\"manufacturer\":\"Sen3Bot\",\"serialNumber\":\"r1\"";
}

struct NodeSpec {
  const char* id;
  double x;
  double y;
  bool released = true;
};

// An order whose nodes are joined by edges e<i>, sequence ids counting from first_sequence.
std::string order_json(int header_id, const std::string& order_id, int update_id, const std::vector<NodeSpec>& nodes,
                       int first_sequence = 0) {
  std::string text = "{" + header(header_id) + ",\"orderId\":\"" + order_id + "\",\"orderUpdateId\":" + std::to_string(update_id) +
                     ",\"nodes\":[";
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    char node[256];
    std::snprintf(node, sizeof node,
                  "%s{\"nodeId\":\"%s\",\"sequenceId\":%d,\"released\":%s,\"nodePosition\":{\"x\":%.3f,\"y\":%.3f,"
                  "\"mapId\":\"lab\",\"allowedDeviationXY\":0.3},\"actions\":[]}",
                  i ? "," : "", nodes[i].id, first_sequence + static_cast<int>(2 * i), nodes[i].released ? "true" : "false",
                  nodes[i].x, nodes[i].y);
    text += node;
  }
  text += "],\"edges\":[";
  for (std::size_t i = 0; i + 1 < nodes.size(); ++i) {
    char edge[256];
    std::snprintf(edge, sizeof edge,
                  "%s{\"edgeId\":\"e%zu\",\"sequenceId\":%d,\"released\":%s,\"startNodeId\":\"%s\",\"endNodeId\":\"%s\","
                  "\"actions\":[]}",
                  i ? "," : "", i, first_sequence + static_cast<int>(2 * i + 1),
                  nodes[i + 1].released ? "true" : "false", nodes[i].id, nodes[i + 1].id);
    text += edge;
  }
  return text + "]}";
}

std::string instant_json(int header_id, const std::string& action_id, const std::string& type) {
  return "{" + header(header_id) + ",\"actions\":[{\"actionId\":\"" + action_id + "\",\"actionType\":\"" + type +
         "\",\"blockingType\":\"HARD\"}]}";
}

class FleetRig {
 public:
  // capture: a folder each message the robot sends is written to, as TOPIC.N.json.
  explicit FleetRig(vda5050::Version version = vda5050::Version::v2_1_0, std::string capture = {})
      : rig_(testing::load_sim_rig()), version_(version), capture_(std::move(capture)) {
    g_version = std::string(vda5050::to_string(version));
    firmware::FirmwareConfig& c = rig_.config;
    // People on: the simulated detector's boxes fused with the laser, as the robot sends them.
    rig_.world.detector.enabled = true;
    rig_.make_board();
    c.navigation.people_enabled = true;
    c.navigation.people_detector = "sim";
    c.tasks["detector"].arena_bytes = 4 * 1024;
    c.tasks["people"].arena_bytes = 64 * 1024;
    c.navigation.mission.goal_count = 0;
    c.tasks.erase("mission");
    c.tasks["fleet"] = firmware::TaskConfig{firmware::FleetTask::arena_bytes_needed() + 64 * 1024};
    c.has_fleet = true;
    c.fleet.broker = "sim";
    c.fleet.serial_number = "r1";
    c.fleet.map_id = "lab";
    c.fleet.state_period_s = 1.0;
    c.fleet.version = version;
    sink_ = std::fopen("/dev/null", "w");
    fw_ = std::make_unique<firmware::Firmware>(c, *rig_.board, sink_);
    hal::PubSubOptions master;
    master.client_id = "master";
    // The people the robot sends, and the formation commands the master sends as the centre.
    master.subscriptions = {{std::string(kPrefix) + "#", 1},
                            {"sen3bot/v1/people/Sen3Bot/r1", 0},
                            {"sen3bot/v1/formation/Sen3Bot/r1", 0}};
    master.inbound_slots = 4096;
    auto client = rig_.board->site_broker().connect(master);
    EXPECT_TRUE(client.ok());
    if (client.ok()) master_ = std::move(client.value());
  }
  ~FleetRig() {
    fw_->shutdown();
    std::fclose(sink_);
  }
  [[nodiscard]] Status init() { return fw_->init(); }
  firmware::Firmware& firmware() { return *fw_; }
  sim::SimBoard& board() { return *rig_.board; }

  void run_for(double seconds) {
    const hal::Nanos end = rig_.clock().now() + static_cast<hal::Nanos>(seconds * 1e9);
    while (rig_.clock().now() < end) {
      ASSERT_TRUE(fw_->scheduler().run_lockstep(rig_.clock(), hal::millis(10)));
      drain();
    }
  }
  // Runs until the predicate holds on the newest state (false after `limit` s).
  template <typename Predicate>
  bool run_until(Predicate done, double limit) {
    const hal::Nanos end = rig_.clock().now() + static_cast<hal::Nanos>(limit * 1e9);
    while (rig_.clock().now() < end) {
      if (!fw_->scheduler().run_lockstep(rig_.clock(), hal::millis(10))) return false;
      drain();
      if (have_state_ && done(state_)) return true;
    }
    return false;
  }
  void send(const std::string& topic, const std::string& json) {
    ASSERT_TRUE(master_->publish(std::string(kPrefix) + topic, bytes(json), 0, false).ok());
  }
  // A formation command as the centre encodes it.
  void send_formation(std::uint32_t header_id, double v, double w, double hold_s) {
    vda5050::FormationCommand m;
    m.header_id = header_id;
    m.timestamp = vda5050::iso8601(rig_.clock().now());
    (void)m.manufacturer.assign("Sen3Bot");
    (void)m.serial_number.assign("r1");
    m.v = v;
    m.omega = w;
    m.hold_s = hold_s;
    std::array<char, 512> out{};
    auto text = vda5050::encode_formation(m, out);
    ASSERT_TRUE(text.ok()) << text.error().c_str();
    ASSERT_TRUE(master_->publish(vda5050::formation_topic("Sen3Bot", "r1"), bytes(*text), 0, false).ok());
  }

  [[nodiscard]] const vda5050::State& state() const { return state_; }
  [[nodiscard]] std::size_t count(const std::string& topic) const {
    auto it = counts_.find(topic);
    return it == counts_.end() ? 0 : it->second;
  }
  [[nodiscard]] const std::vector<std::string>& connections() const { return connections_; }
  [[nodiscard]] const std::string& last(const std::string& topic) const { return last_.at(topic); }
  [[nodiscard]] nav::Pose2D truth() { return rig_.board->simulation().truth().pose; }
  [[nodiscard]] double true_speed() { return rig_.board->simulation().truth().speed_m_s; }
  [[nodiscard]] int bad_messages() const { return bad_; }

 private:
  void drain() {
    std::vector<char> topic(256);
    std::vector<std::uint8_t> payload(64 * 1024);
    for (;;) {
      auto message = master_->receive(topic, payload);
      ASSERT_TRUE(message.ok());
      if (!message.value()) return;
      const std::string name(topic.data(), message.value()->topic_size);
      const std::string text(reinterpret_cast<const char*>(payload.data()), message.value()->payload_size);
      // VDA 5050's topics by their last level, Sen3Bot's (sen3bot/v1/KIND/...) by their kind.
      constexpr std::string_view kOwn = "sen3bot/v1/";
      const std::string leaf = name.starts_with(kOwn) ? name.substr(kOwn.size(), name.find('/', kOwn.size()) - kOwn.size())
                                                      : name.substr(name.rfind('/') + 1);
      ++counts_[leaf];
      // The master hears its own orders too (it reads the robot's whole topic tree): what the
      // robot sent is captured, and the formation commands as the codec wrote them.
      if (!capture_.empty() && leaf != "order" && leaf != "instantActions") {
        const std::string file = capture_ + "/" + leaf + "." + std::to_string(counts_[leaf]) + ".json";
        std::FILE* f = std::fopen(file.c_str(), "w");
        ASSERT_NE(f, nullptr) << file;
        std::fwrite(text.data(), 1, text.size(), f);
        std::fclose(f);
      }
      last_[leaf] = text;
      if (leaf == "state") {
        const vda5050::Decoded decoded = vda5050::decode_state(text, version_, *scratch_state_, scratch_);
        if (decoded.ok()) {
          state_ = *scratch_state_;
          have_state_ = true;
        } else {
          ++bad_;
          ADD_FAILURE() << "a state the robot sent does not decode: " << decoded.error().description.view() << "\n" << text;
        }
      } else if (leaf == "connection") {
        vda5050::Connection connection;
        const vda5050::Decoded decoded = vda5050::decode_connection(text, version_, connection, scratch_);
        if (!decoded.ok()) ++bad_;
        connections_.emplace_back(vda5050::to_string(connection.state));
      }
    }
  }

  testing::SimRig rig_;
  vda5050::Version version_;
  std::string capture_;
  std::FILE* sink_ = nullptr;
  std::unique_ptr<firmware::Firmware> fw_;
  std::unique_ptr<hal::PubSub> master_;
  vda5050::DecodeScratch scratch_;
  std::unique_ptr<vda5050::State> scratch_state_ = std::make_unique<vda5050::State>();
  vda5050::State state_;
  bool have_state_ = false;
  std::map<std::string, std::size_t> counts_;
  std::map<std::string, std::string> last_;
  std::vector<std::string> connections_;
  int bad_ = 0;
};

const std::vector<NodeSpec> kRoute = {{"n0", 2.5, 2.0}, {"n1", 2.85, 3.5}, {"n2", 2.9, 4.25}};

bool done_with(const vda5050::State& s, std::string_view last) {
  return s.last_node_id == last && s.node_states.empty() && !s.driving;
}

TEST(Fleet, TheRobotComesOnlineWithItsFactsheetAndReportsStateVisualizationAndPeople) {
  FleetRig rig;
  ASSERT_TRUE(rig.init().ok());
  rig.run_for(3.0);
  ASSERT_FALSE(rig.connections().empty());
  EXPECT_EQ(rig.connections().front(), "ONLINE");
  EXPECT_EQ(rig.count("factsheet"), 1u);
  EXPECT_GE(rig.count("state"), 3u);  // at least once a second
  EXPECT_GE(rig.count("visualization"), 5u);
  EXPECT_GE(rig.count("people"), 10u);  // every 0.2 s
  EXPECT_NE(rig.last("people").find("\"schemaVersion\":\"1.1.0\""), std::string::npos);
  EXPECT_EQ(rig.bad_messages(), 0);
  const vda5050::State& s = rig.state();
  ASSERT_TRUE(s.agv_position.has_value());
  EXPECT_NEAR(s.agv_position->x, 2.5, 0.2);
  EXPECT_NEAR(s.agv_position->y, 2.0, 0.2);
  EXPECT_EQ(s.agv_position->map_id, "lab");
  EXPECT_TRUE(s.order_id.empty());
  EXPECT_FALSE(s.driving);
}

TEST(Fleet, AnOrderDrivesTheRobotThroughItsNodesAndTheStateFollows) {
  FleetRig rig;
  ASSERT_TRUE(rig.init().ok());
  rig.run_for(2.0);
  rig.send("order", order_json(1, "o1", 0, kRoute));
  ASSERT_TRUE(rig.run_until([](const vda5050::State& s) { return s.last_node_id == "n1"; }, 40.0));
  EXPECT_EQ(rig.state().order_id, "o1");
  ASSERT_TRUE(rig.run_until([](const vda5050::State& s) { return done_with(s, "n2"); }, 40.0));
  EXPECT_EQ(rig.state().last_node_sequence_id, 4u);
  EXPECT_TRUE(rig.state().edge_states.empty());
  const nav::Pose2D truth = rig.truth();
  // It finishes its approach to the last node after passing it within the deviation.
  EXPECT_LT(std::hypot(truth.x_m - 2.9, truth.y_m - 4.25), 0.2) << truth.x_m << ", " << truth.y_m;
  EXPECT_EQ(rig.firmware().fleet()->counters().orders_accepted, 1u);
  EXPECT_EQ(rig.bad_messages(), 0);
}

TEST(Fleet, CancelOrderStopsTheRobotAndAPauseHoldsIt) {
  FleetRig rig;
  ASSERT_TRUE(rig.init().ok());
  rig.run_for(2.0);
  rig.send("order", order_json(1, "o1", 0, kRoute));
  ASSERT_TRUE(rig.run_until([](const vda5050::State& s) { return s.driving; }, 10.0));
  rig.send("instantActions", instant_json(1, "pause-1", "startPause"));
  ASSERT_TRUE(rig.run_until([](const vda5050::State& s) { return s.paused && !s.driving; }, 5.0));
  const nav::Pose2D held = rig.truth();
  rig.run_for(3.0);
  EXPECT_LT(std::hypot(rig.truth().x_m - held.x_m, rig.truth().y_m - held.y_m), 0.05);
  rig.send("instantActions", instant_json(2, "pause-2", "stopPause"));
  ASSERT_TRUE(rig.run_until([](const vda5050::State& s) { return !s.paused && s.driving; }, 5.0));
  rig.send("instantActions", instant_json(3, "cancel-1", "cancelOrder"));
  ASSERT_TRUE(rig.run_until(
      [](const vda5050::State& s) {
        for (const vda5050::ActionState& a : s.action_states)
          if (a.action_id == "cancel-1") return a.status == vda5050::ActionStatus::finished;
        return false;
      },
      5.0));
  EXPECT_TRUE(rig.state().node_states.empty());
  EXPECT_EQ(rig.state().order_id, "o1");  // kept after a cancel
  EXPECT_LT(std::abs(rig.true_speed()), 0.03);
  // A second cancel has no order to cancel: FAILED and a noOrderToCancel warning.
  rig.send("instantActions", instant_json(4, "cancel-2", "cancelOrder"));
  ASSERT_TRUE(rig.run_until(
      [](const vda5050::State& s) {
        for (const vda5050::VehicleError& e : s.errors)
          if (e.error_type == "noOrderToCancel") return true;
        return false;
      },
      3.0));
}

TEST(Fleet, BadMessagesAreRejectedAndReportedWhileTheOrderGoesOn) {
  FleetRig rig;
  ASSERT_TRUE(rig.init().ok());
  rig.run_for(2.0);
  rig.send("order", order_json(1, "o1", 1, kRoute));
  ASSERT_TRUE(rig.run_until([](const vda5050::State& s) { return s.order_id == "o1"; }, 3.0));
  auto has_error = [](std::string_view type) {
    return [type](const vda5050::State& s) {
      for (const vda5050::VehicleError& e : s.errors)
        if (e.error_type == type) return true;
      return false;
    };
  };
  rig.send("order", "{\"headerId\": 2, this is not JSON");
  ASSERT_TRUE(rig.run_until(has_error("validationError"), 3.0));
  rig.send("order", order_json(3, "o1", 0, kRoute));  // an older update of the running order
  ASSERT_TRUE(rig.run_until(has_error("orderUpdateError"), 3.0));
  EXPECT_EQ(rig.state().order_update_id, 1u);
  rig.send("instantActions", instant_json(1, "x-1", "selfDestruct"));
  ASSERT_TRUE(rig.run_until(
      [](const vda5050::State& s) {
        for (const vda5050::ActionState& a : s.action_states)
          if (a.action_id == "x-1") return a.status == vda5050::ActionStatus::failed;
        return false;
      },
      3.0));
  ASSERT_TRUE(rig.run_until([](const vda5050::State& s) { return done_with(s, "n2"); }, 60.0));
  EXPECT_GE(rig.firmware().fleet()->counters().orders_rejected, 2u);
}

TEST(Fleet, ARobotCutOffFromTheBrokerKeepsDrivingItsOrderAndComesBackOnline) {
  FleetRig rig;
  ASSERT_TRUE(rig.init().ok());
  rig.run_for(2.0);
  rig.send("order", order_json(1, "o1", 0, kRoute));
  ASSERT_TRUE(rig.run_until([](const vda5050::State& s) { return s.driving; }, 10.0));
  rig.board().site_broker().set_reachable("r1", false);
  const std::size_t states_before = rig.count("state");
  const nav::Pose2D at_loss = rig.truth();
  rig.run_for(4.0);
  ASSERT_GE(rig.connections().size(), 2u);
  EXPECT_EQ(rig.connections().back(), "CONNECTIONBROKEN");
  EXPECT_EQ(rig.count("state"), states_before);  // nothing gets through
  EXPECT_GT(std::hypot(rig.truth().x_m - at_loss.x_m, rig.truth().y_m - at_loss.y_m), 0.5);  // still driving
  rig.board().site_broker().set_reachable("r1", true);
  ASSERT_TRUE(rig.run_until([](const vda5050::State& s) { return done_with(s, "n2"); }, 60.0));
  EXPECT_EQ(rig.connections().back(), "ONLINE");
  EXPECT_EQ(rig.firmware().fleet()->counters().sessions, 2u);
}

// Every message the robot sends in an eventful run (an order, a pause, a cancel, a refused
// message, an unknown action, a lost broker) validates against the shipped schemas of the
// site's version: VDA 5050's and the people schema; the formation commands sent to it too.
class FleetSchemas : public ::testing::TestWithParam<vda5050::Version> {};

TEST_P(FleetSchemas, EveryMessageTheRobotSendsValidates) {
  char folder[] = "/tmp/sen3bot-fleet-XXXXXX";
  ASSERT_NE(::mkdtemp(folder), nullptr);
  {
    FleetRig rig(GetParam(), folder);
    ASSERT_TRUE(rig.init().ok());
    rig.run_for(2.0);
    rig.send("order", order_json(1, "o1", 0, kRoute));
    ASSERT_TRUE(rig.run_until([](const vda5050::State& s) { return s.driving; }, 10.0));
    rig.send("instantActions", instant_json(1, "p1", "startPause"));
    rig.run_for(1.0);
    rig.send("instantActions", instant_json(2, "p2", "stopPause"));
    rig.send("instantActions", instant_json(3, "f1", "factsheetRequest"));
    rig.send("instantActions", instant_json(4, "x1", "selfDestruct"));
    rig.send("order", "[1, 2");
    rig.run_for(1.0);
    rig.board().site_broker().set_reachable("r1", false);
    rig.run_for(1.0);
    rig.board().site_broker().set_reachable("r1", true);
    rig.send("instantActions", instant_json(5, "c1", "cancelOrder"));
    rig.run_for(2.0);
    for (std::uint32_t i = 1; i <= 3; ++i) {
      rig.send_formation(i, 0.1, -0.1 * i, 0.3);
      rig.run_for(0.1);
    }
    rig.run_for(1.0);
    EXPECT_EQ(rig.firmware().fleet()->counters().formation_received, 3u);
    EXPECT_EQ(rig.firmware().fleet()->counters().formation_rejected, 0u);
    EXPECT_EQ(rig.count("formation"), 3u);
    EXPECT_EQ(rig.bad_messages(), 0);
  }
  const std::string version(vda5050::to_string(GetParam()));
  const std::string command = std::string("python3 ") + SEN3BOT_SOURCE_DIR + "/tests/vda5050/validate_messages.py " + folder + " " +
                              version + " " + SEN3BOT_SOURCE_DIR + "/docs/vda5050/schemas " + SEN3BOT_SOURCE_DIR + "/docs/fleet";
  EXPECT_EQ(std::system(command.c_str()), 0) << command;
  std::system((std::string("rm -rf ") + folder).c_str());
}

INSTANTIATE_TEST_SUITE_P(Versions, FleetSchemas, ::testing::Values(vda5050::Version::v2_1_0, vda5050::Version::v2_0_0),
                         [](const ::testing::TestParamInfo<vda5050::Version>& param) {
                           return param.param == vda5050::Version::v2_1_0 ? std::string("v2_1_0") : std::string("v2_0_0");
                         });

}  // namespace
}  // namespace sen3bot
