// The steady-state rule for the VDA 5050 code: the vehicle's order state machine, the
// decoders and the encoders allocate nothing. Many rounds of what the fleet task does with
// the messages a master control sends (orders, order updates, instant actions, refused and
// malformed messages) and with what it sends back (state, visualization, connection,
// factsheet), and the formation link (the centre's commands, the visualization read back),
// after one warm-up round, with no operator new and no malloc in between.
#include <gtest/gtest.h>

#include <array>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/vda5050/codec.hpp"
#include "sen3bot/vda5050/extensions.hpp"
#include "sen3bot/json/json.hpp"
#include "sen3bot/vda5050/vehicle.hpp"

namespace sen3bot::vda5050 {
namespace {

using mem::testing::AllocationScope;

constexpr Version kVersion = Version::v2_1_0;

std::string header_json(int header_id, std::string_view version = "2.1.0") {
  return "\"headerId\":" + std::to_string(header_id) + ",\"timestamp\":\"2026-12-03T10:00:00.00Z\",\"version\":\"" +
         std::string(version) + "\",\"manufacturer\":\"Sen3Bot\",\"serialNumber\":\"r1\"";
}

// An order of `count` nodes along x from `first_x`, sequence ids from first_sequence, the last
// `horizon` nodes (and the edges into them) not released; a beep on every node, a signal
// with a parameter on every edge, a HARD host-run pick on the node given.
std::string order_json(const std::string& order_id, int update_id, int count, int first_sequence, double first_x,
                       int horizon = 0, int pick_on = -1) {
  std::string text = "{" + header_json(1) + ",\"orderId\":\"" + order_id +
                     "\",\"orderUpdateId\":" + std::to_string(update_id) + ",\"nodes\":[";
  char buffer[512];
  for (int i = 0; i < count; ++i) {
    const int sequence = first_sequence + 2 * i;
    const bool released = i < count - horizon;
    std::string actions = "{\"actionType\":\"beep\",\"actionId\":\"beep-" + order_id + "-" + std::to_string(sequence) +
                          "\",\"blockingType\":\"NONE\"}";
    if (i == pick_on)
      actions += ",{\"actionType\":\"pick\",\"actionId\":\"pick-" + order_id + "-" + std::to_string(sequence) +
                 "\",\"blockingType\":\"HARD\",\"actionParameters\":[{\"key\":\"weight\",\"value\":8.5}]}";
    std::snprintf(buffer, sizeof buffer,
                  "%s{\"nodeId\":\"n%d\",\"sequenceId\":%d,\"released\":%s,\"nodePosition\":{\"x\":%.2f,\"y\":0,"
                  "\"theta\":0.0,\"allowedDeviationXY\":0.2,\"mapId\":\"lab\"},\"actions\":[%s]}",
                  i ? "," : "", sequence / 2, sequence, released ? "true" : "false", first_x + i, actions.c_str());
    text += buffer;
  }
  text += "],\"edges\":[";
  for (int i = 0; i + 1 < count; ++i) {
    const int sequence = first_sequence + 2 * i + 1;
    const bool released = i + 1 < count - horizon;
    std::snprintf(buffer, sizeof buffer,
                  "%s{\"edgeId\":\"e%d\",\"sequenceId\":%d,\"released\":%s,\"startNodeId\":\"n%d\",\"endNodeId\":\"n%d\","
                  "\"maxSpeed\":0.8,\"actions\":[{\"actionType\":\"signal\",\"actionId\":\"signal-%s-%d\","
                  "\"blockingType\":\"NONE\",\"actionParameters\":[{\"key\":\"pattern\",\"value\":\"blink\"}]}]}",
                  i ? "," : "", sequence, sequence, released ? "true" : "false", (sequence - 1) / 2, (sequence + 1) / 2,
                  order_id.c_str(), sequence);
    text += buffer;
  }
  return text + "]}";
}

std::string instant_json(int header_id, const std::string& action_id, const std::string& type) {
  return "{" + header_json(header_id) + ",\"actions\":[{\"actionId\":\"" + action_id + "\",\"actionType\":\"" + type +
         "\",\"blockingType\":\"HARD\"}]}";
}

VehicleConfig vehicle_config() {
  VehicleConfig config;
  (void)config.manufacturer.assign("Sen3Bot");
  (void)config.serial_number.assign("r1");
  config.version = kVersion;
  for (const char* type : {"beep", "signal", "pick"}) {
    SupportedAction action;
    (void)action.action_type.assign(type);
    action.node = true;
    action.edge = true;
    action.host_run = std::string_view(type) == "pick";
    (void)config.actions.push_back(action);
  }
  return config;
}

Progress progress_at(double x, double speed, std::uint32_t goal_sequence = 0, bool reached = false) {
  Progress progress;
  progress.pose.x = x;
  (void)progress.pose.map_id.assign("lab");
  progress.pose.localized = true;
  progress.speed = speed;
  progress.goal_sequence_id = goal_sequence;
  progress.goal_reached = reached;
  return progress;
}

// Everything long-lived, made before counting (an Order is about a megabyte).
struct Rig {
  Order order;
  InstantActions actions;
  State state;
  State state_read;
  Connection connection;
  DecodeScratch scratch;
  std::array<char, 64 * 1024> out{};
  std::array<char, 256> topic{};
  json::StaticDocument<256> small_doc;
};

// The messages of one round, as text made before counting. Every round starts at x = 0 with
// no order running (the previous round's last order was cancelled or finished).
struct Messages {
  std::vector<std::string> instant;
  std::string order_a = order_json("A", 0, 4, 0, 0.0, 1, 1);    // n0..n3, n3 horizon, pick on n1
  std::string update_a = order_json("A", 1, 3, 4, 2.0);         // from n2 (the decision point) to n4
  std::string order_b = order_json("B", 0, 3, 0, 0.0);          // while A runs: refused
  std::string far_order = order_json("C", 0, 2, 0, 50.0);       // first node out of reach: refused
  std::string stale_update = order_json("A", 0, 4, 0, 0.0, 1);  // lower orderUpdateId: refused
  std::string order_d = order_json("D", 0, 10, 0, 0.0);         // cancelled in its middle
  std::string malformed = "{\"headerId\":1,\"orderId\":";
  std::string wrong_version = "{" + header_json(2, "2.0.0") + ",\"orderId\":\"x\",\"orderUpdateId\":0,\"nodes\":[],\"edges\":[]}";
  std::string bad_type = "{" + header_json(3) + ",\"orderId\":7,\"orderUpdateId\":0,\"nodes\":[],\"edges\":[]}";
  std::string too_many = order_json("E", 0, static_cast<int>(kMaxNodes) + 1, 0, 0.0);
  std::string bad_instant = "{" + header_json(4) + ",\"actions\":[{\"actionType\":\"startPause\"}]}";
  Messages() {
    instant.push_back(instant_json(1, "pause", "startPause"));
    instant.push_back(instant_json(2, "resume", "stopPause"));
    instant.push_back(instant_json(3, "state", "stateRequest"));
    instant.push_back(instant_json(4, "factsheet", "factsheetRequest"));
    instant.push_back(instant_json(5, "cancel", "cancelOrder"));
    instant.push_back(instant_json(6, "cancel-none", "cancelOrder"));  // no order: fails
    instant.push_back(instant_json(7, "dance", "dance"));              // unsupported
  }
};

struct Tally {
  std::uint64_t decoded = 0, refused_by_codec = 0, accepted = 0, refused_by_vehicle = 0, encoded = 0,
                encode_failures = 0, states_encoded = 0, states_read = 0;
};

void decode_and_receive(Rig& rig, Vehicle& vehicle, std::string_view text, double x, Tally& tally) {
  const Decoded decoded = decode_order(text, kVersion, rig.order, rig.scratch);
  if (!decoded) {
    ++tally.refused_by_codec;
    vehicle.report_rejected_message(decoded.error());
    return;
  }
  ++tally.decoded;
  const std::size_t errors_before = vehicle.errors().size() + vehicle.dropped_errors();
  if (vehicle.receive_order(rig.order, progress_at(x, 0).pose)) {
    ++tally.accepted;
  } else if (vehicle.errors().size() + vehicle.dropped_errors() > errors_before) {
    ++tally.refused_by_vehicle;
  }
}

void instant(Rig& rig, Vehicle& vehicle, std::string_view text, Tally& tally) {
  const Decoded decoded = decode_instant_actions(text, kVersion, rig.actions, rig.scratch);
  if (!decoded) {
    ++tally.refused_by_codec;
    vehicle.report_rejected_message(decoded.error());
    return;
  }
  ++tally.decoded;
  vehicle.receive_instant_actions(rig.actions);
}

// The state message as the fleet task sends it, read back as master control reads it.
void publish_state(Rig& rig, Vehicle& vehicle, std::uint32_t header_id, double x, Tally& tally) {
  rig.state = State{};
  vehicle.fill_state(rig.state);
  rig.state.header.header_id = header_id;
  (void)rig.state.header.timestamp.assign("2026-12-03T10:00:01.25Z");
  AgvPosition position;
  position.position_initialized = true;
  position.x = x;
  position.localization_score = 1.0;
  position.deviation_range = 0.04;
  (void)position.map_id.assign("lab");
  rig.state.agv_position = position;
  rig.state.velocity = Velocity{0.3, 0.0, 0.01};
  rig.state.battery.battery_charge = 80.0;
  rig.state.battery.battery_voltage = 12.3;
  MapState map;
  (void)map.map_id.assign("lab");
  (void)map.map_version.assign("3");
  (void)rig.state.maps.push_back(map);
  auto text = encode_state(rig.state, kVersion, rig.out);
  if (!text) {
    ++tally.encode_failures;
    return;
  }
  ++tally.encoded;
  ++tally.states_encoded;
  vehicle.state_published();
  if (decode_state(*text, kVersion, rig.state_read, rig.scratch)) ++tally.states_read;
}

void other_messages(Rig& rig, Vehicle& vehicle, Tally& tally) {
  Visualization visualization;
  visualization.header.header_id = 9;
  (void)visualization.header.timestamp.assign("2026-12-03T10:00:01.25Z");
  visualization.velocity = Velocity{0.3, 0.0, 0.01};
  auto text = encode_visualization(visualization, kVersion, rig.out);
  text ? ++tally.encoded : ++tally.encode_failures;
  // The centre reads the robots' poses from these.
  if (text && decode_visualization(*text, kVersion, visualization, rig.scratch)) ++tally.decoded;

  // The centre's formation command, written, read, and one refused (a hold beyond 2 s).
  FormationCommand formation;
  formation.header_id = 4;
  (void)formation.timestamp.assign("2026-12-03T10:00:01.25Z");
  (void)formation.manufacturer.assign("Sen3Bot");
  (void)formation.serial_number.assign("r1");
  formation.v = 0.2;
  formation.omega = -0.1;
  formation.hold_s = 0.5;
  text = encode_formation(formation, rig.out);
  text ? ++tally.encoded : ++tally.encode_failures;
  if (text && decode_formation(*text, formation, rig.scratch)) ++tally.decoded;
  if (!decode_formation(R"({"schemaVersion":"1.0.0","headerId":5,"timestamp":"t","manufacturer":"Sen3Bot",)"
                        R"("serialNumber":"r1","v":0.2,"omega":0,"holdS":2.5})",
                        formation, rig.scratch))
    ++tally.refused_by_codec;

  rig.connection = Connection{};
  rig.connection.header.header_id = 3;
  (void)rig.connection.header.timestamp.assign("2026-12-03T10:00:01.25Z");
  rig.connection.state = ConnectionState::online;
  text = encode_connection(rig.connection, kVersion, rig.out);
  text ? ++tally.encoded : ++tally.encode_failures;
  if (text && decode_connection(*text, kVersion, rig.connection, rig.scratch)) ++tally.decoded;

  if (vehicle.factsheet_requested()) {
    FactsheetInfo factsheet = sen3bot_factsheet();
    factsheet.header.header_id = 1;
    (void)factsheet.header.timestamp.assign("2026-12-03T10:00:01.25Z");
    text = encode_factsheet(factsheet, kVersion, rig.out);
    text ? ++tally.encoded : ++tally.encode_failures;
    vehicle.factsheet_published();
  }
  // A buffer too small: Errc::capacity, not an allocation.
  text = encode_state(rig.state, kVersion, std::span<char>(rig.out.data(), 64));
  text ? ++tally.encoded : ++tally.encode_failures;
  auto topic = make_topic(rig.topic, "uagv", kVersion, "Sen3Bot", "r1", "state");
  topic ? ++tally.encoded : ++tally.encode_failures;
  if (json::validate(R"({"a":[1,2.5,true,null,"x\u00e9"]})")) ++tally.decoded;
  if (rig.small_doc.parse(R"({"k":[1,2,3],"s":"t\n"})") && rig.small_doc.root().find("k").size() == 3) ++tally.decoded;
}

// One round of what a master control exchanges with the robot.
void round(Rig& rig, Vehicle& vehicle, const Messages& m, Tally& tally, std::uint32_t& header_id) {
  auto state = [&](double x) { publish_state(rig, vehicle, header_id++, x, tally); };
  auto step_to = [&](double x, double speed) {
    const DriveTarget& target = vehicle.target();
    vehicle.update(progress_at(x, speed, target.sequence_id, speed == 0.0 && !target.hold && target.x == x));
    if (vehicle.state_changed()) state(x);
  };

  // Order A: n0 (start) .. n2 released, n3 horizon, a host-run HARD pick on n1.
  decode_and_receive(rig, vehicle, m.order_a, 0.0, tally);
  step_to(0.0, 0.0);  // n0 traversed
  decode_and_receive(rig, vehicle, m.order_b, 0.0, tally);       // another order while A runs
  decode_and_receive(rig, vehicle, m.malformed, 0.0, tally);     // not JSON
  decode_and_receive(rig, vehicle, m.wrong_version, 0.0, tally);  // 2.0 on a 2.1 site
  decode_and_receive(rig, vehicle, m.bad_type, 0.0, tally);      // orderId a number
  decode_and_receive(rig, vehicle, m.too_many, 0.0, tally);      // over kMaxNodes
  step_to(0.5, 0.4);
  step_to(1.0, 0.0);  // n1: the pick starts
  if (const Action* pick = vehicle.action_to_start(); pick != nullptr) {
    const Id id = pick->action_id;
    (void)vehicle.report_action(id.view(), ActionStatus::running);
    step_to(1.0, 0.0);
    instant(rig, vehicle, m.instant[0], tally);  // startPause
    step_to(1.0, 0.0);
    instant(rig, vehicle, m.instant[1], tally);  // stopPause
    (void)vehicle.report_action(id.view(), ActionStatus::finished, "picked");
  }
  step_to(1.0, 0.0);
  step_to(1.5, 0.4);
  step_to(2.0, 0.0);  // n2: the decision point
  decode_and_receive(rig, vehicle, m.update_a, 2.0, tally);      // n2 .. n4 released
  decode_and_receive(rig, vehicle, m.update_a, 2.0, tally);      // the same again: ignored
  decode_and_receive(rig, vehicle, m.stale_update, 2.0, tally);  // a lower orderUpdateId
  for (double x : {2.5, 3.0, 3.5, 4.0}) step_to(x, x == 3.0 || x == 4.0 ? 0.0 : 0.4);
  instant(rig, vehicle, m.instant[2], tally);  // stateRequest
  instant(rig, vehicle, m.instant[3], tally);  // factsheetRequest
  other_messages(rig, vehicle, tally);
  decode_and_receive(rig, vehicle, m.far_order, 4.0, tally);  // its first node is not here

  // Order D from x = 0 (the robot is put back), cancelled after two nodes.
  decode_and_receive(rig, vehicle, m.order_d, 0.0, tally);
  step_to(0.0, 0.0);
  step_to(1.0, 0.0);
  instant(rig, vehicle, m.instant[4], tally);  // cancelOrder
  step_to(1.0, 0.0);
  instant(rig, vehicle, m.instant[5], tally);  // cancelOrder with none: fails
  instant(rig, vehicle, m.instant[6], tally);  // an unsupported instant action
  instant(rig, vehicle, m.bad_instant, tally);  // no actionId, no blockingType
  step_to(1.0, 0.0);
  state(1.0);
  other_messages(rig, vehicle, tally);
}

TEST(Vda5050NoAllocation, VehicleDecodersAndEncodersInSteadyState) {
  auto rig = std::make_unique<Rig>();
  auto vehicle = std::make_unique<Vehicle>(vehicle_config());
  const Messages messages;
  Tally warm;
  std::uint32_t header_id = 0;
  round(*rig, *vehicle, messages, warm, header_id);
  // The warm-up round went the way it is meant to.
  EXPECT_EQ(warm.accepted, 3u);  // A, its update, D
  EXPECT_EQ(warm.refused_by_vehicle, 3u);  // B while A runs, A's stale update, C out of reach
  // malformed, 2.0, a type, 33 nodes, an instant action, and a formation command twice
  EXPECT_EQ(warm.refused_by_codec, 7u);
  EXPECT_EQ(warm.encode_failures, 2u);      // only the 64-byte buffer, twice
  EXPECT_GE(warm.states_encoded, 10u);
  EXPECT_EQ(warm.states_read, warm.states_encoded) << "every state encoded reads back";

  constexpr int kRounds = 300;
  Tally tally;
  AllocationScope scope;
  for (int i = 0; i < kRounds; ++i) round(*rig, *vehicle, messages, tally, header_id);
  const std::uint64_t allocations = scope.allocations();
  const std::uint64_t malloc_calls = scope.malloc_calls();

  EXPECT_EQ(allocations, 0u) << "operator new called in steady state";
  EXPECT_EQ(malloc_calls, 0u) << "malloc called in steady state";
  // Every round did the same as the warm-up.
  EXPECT_EQ(tally.accepted, kRounds * warm.accepted);
  EXPECT_EQ(tally.refused_by_vehicle, kRounds * warm.refused_by_vehicle);
  EXPECT_EQ(tally.refused_by_codec, kRounds * warm.refused_by_codec);
  EXPECT_EQ(tally.decoded, kRounds * warm.decoded);
  EXPECT_EQ(tally.encoded, kRounds * warm.encoded);
  EXPECT_EQ(tally.states_encoded, kRounds * warm.states_encoded);
  EXPECT_EQ(tally.states_read, kRounds * warm.states_read);
}

TEST(Vda5050NoAllocation, TheCounterSeesAllocations) {
  // Guards the guard: without the counting functions linked in, the test above passes vacuously.
  AllocationScope scope;
  auto order = std::make_unique<Order>();
  asm volatile("" : : "g"(order.get()) : "memory");
  EXPECT_EQ(scope.allocations(), 1u);
  if (mem::testing::counts_malloc()) {
    EXPECT_GE(scope.malloc_calls(), 1u);
  }
}

}  // namespace
}  // namespace sen3bot::vda5050
