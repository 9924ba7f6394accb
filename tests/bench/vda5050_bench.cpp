// VDA 5050 costs on the robot's side (Google Benchmark): decoding an order (10 nodes, and the
// 32-node capacity) and an instantActions message, encoding the state of a robot with an
// order in progress and the visualization, the order state machine taking an order and
// stepping, and one order message handled end to end the way the fleet task does it (decode,
// receive_order, update, fill_state, encode_state). Decoders and encoders report bytes/s of
// JSON text; the message-level benchmarks report items/s (messages per second).
//
// Orders, states and the decode scratch are large (an Order is about a megabyte); they are
// made once, outside the timed loops, as the fleet task makes them once in its arena.
#include <benchmark/benchmark.h>

#include <array>
#include <cstdio>
#include <memory>
#include <string>

#include "sen3bot/vda5050/codec.hpp"
#include "sen3bot/vda5050/vehicle.hpp"

namespace {

using namespace sen3bot;
using namespace sen3bot::vda5050;

constexpr Version kVersion = Version::v2_1_0;

std::string header_json(int header_id) {
  return "\"headerId\":" + std::to_string(header_id) +
         ",\"timestamp\":\"2026-12-03T10:00:00.00Z\",\"version\":\"2.1.0\",\"manufacturer\":\"Sen3Bot\","
         "\"serialNumber\":\"r1\"";
}

// An order as a master control writes one: every node with a position on the lab map, every
// edge with a speed limit and an orientation; a beep on the first node, a signal on the second
// edge, and a drop with its parameters on the last node. The first node is at (0, 0).
std::string order_json(int nodes, const std::string& order_id, int header_id = 1) {
  std::string text = "{" + header_json(header_id) + ",\"orderId\":\"" + order_id +
                     "\",\"orderUpdateId\":0,\"zoneSetId\":\"lab-zones\",\"nodes\":[";
  char buffer[640];
  for (int i = 0; i < nodes; ++i) {
    std::string actions;
    if (i == 0) {
      actions = R"({"actionType":"beep","actionId":"beep-0","blockingType":"NONE"})";
    } else if (i == nodes - 1) {
      actions =
          R"({"actionType":"drop","actionId":"drop-1","actionDescription":"leave the box at the station",)"
          R"("blockingType":"NONE","actionParameters":[{"key":"stationType","value":"floor"},)"
          R"({"key":"loadType","value":"box"},{"key":"weight","value":8.5}]})";
    }
    std::snprintf(buffer, sizeof buffer,
                  "%s{\"nodeId\":\"node-%02d\",\"sequenceId\":%d,\"released\":true,\"nodeDescription\":\"waypoint %d\","
                  "\"nodePosition\":{\"x\":%.3f,\"y\":%.3f,\"theta\":%.4f,\"allowedDeviationXY\":0.3,"
                  "\"allowedDeviationTheta\":0.5,\"mapId\":\"lab\"},\"actions\":[%s]}",
                  i ? "," : "", i, 2 * i, i, 0.75 * i, 0.25 * (i % 4), 0.1 * (i % 7), actions.c_str());
    text += buffer;
  }
  text += "],\"edges\":[";
  for (int i = 0; i + 1 < nodes; ++i) {
    const char* actions = i == 1 ? R"({"actionType":"signal","actionId":"signal-1","blockingType":"NONE",)"
                                   R"("actionParameters":[{"key":"pattern","value":"blink"}]})"
                                 : "";
    std::snprintf(buffer, sizeof buffer,
                  "%s{\"edgeId\":\"edge-%02d\",\"sequenceId\":%d,\"released\":true,\"startNodeId\":\"node-%02d\","
                  "\"endNodeId\":\"node-%02d\",\"maxSpeed\":0.8,\"orientation\":0.0,\"actions\":[%s]}",
                  i ? "," : "", i, 2 * i + 1, i, i + 1, actions);
    text += buffer;
  }
  return text + "]}";
}

// What an operator's panel sends: a pause, its end and a state request in one message.
std::string instant_actions_json() {
  return "{" + header_json(1) +
         R"(,"actions":[{"actionType":"startPause","actionId":"pause-1","blockingType":"HARD"},)"
         R"({"actionType":"stopPause","actionId":"pause-2","blockingType":"HARD"},)"
         R"({"actionType":"stateRequest","actionId":"state-1","blockingType":"NONE"}]})";
}

VehicleConfig vehicle_config() {
  VehicleConfig config;
  (void)config.manufacturer.assign("Sen3Bot");
  (void)config.serial_number.assign("r1");
  config.version = kVersion;
  for (const char* type : {"beep", "signal", "drop"}) {
    SupportedAction action;
    (void)action.action_type.assign(type);
    action.node = true;
    action.edge = true;
    (void)config.actions.push_back(action);
  }
  return config;
}

Pose at(double x, double y) {
  Pose pose;
  pose.x = x;
  pose.y = y;
  (void)pose.map_id.assign("lab");
  pose.localized = true;
  return pose;
}

Progress progress_at(double x, double y, double speed) {
  Progress progress;
  progress.pose = at(x, y);
  progress.speed = speed;
  return progress;
}

InstantActions cancel_order() {
  InstantActions message;
  Action cancel;
  (void)cancel.action_type.assign("cancelOrder");
  (void)cancel.action_id.assign("cancel-1");
  cancel.blocking_type = BlockingType::hard;
  (void)message.actions.push_back(cancel);
  return message;
}

// The decode side's long-lived objects, as in the fleet task's arena.
struct Buffers {
  Order order;
  InstantActions actions;
  State state;
  DecodeScratch scratch;
  std::array<char, 64 * 1024> out{};
};

std::unique_ptr<Buffers> make_buffers() { return std::make_unique<Buffers>(); }

// A state message of a robot with an order in progress: the 10-node order taken, a rejected
// message's warning, then the host's fields as the fleet task fills them.
void state_in_progress(Vehicle& vehicle, Buffers& b) {
  const std::string order = order_json(10, "order-1");
  if (!decode_order(order, kVersion, b.order, b.scratch).ok() || !vehicle.receive_order(b.order, at(0, 0))) return;
  VehicleError error;
  (void)error.error_type.assign(kValidationError);
  (void)error.description.assign("malformed JSON at byte 17: expected a value");
  ErrorReference reference;
  (void)reference.key.assign("topic");
  (void)reference.value.assign("order");
  (void)error.references.push_back(reference);
  vehicle.report_rejected_message(error);
  b.state = State{};
  vehicle.fill_state(b.state);
  b.state.header.header_id = 4711;
  (void)b.state.header.timestamp.assign("2026-12-03T10:00:01.25Z");
  AgvPosition position;
  position.position_initialized = true;
  position.x = 0.02;
  position.y = -0.01;
  position.theta = 0.015;
  position.localization_score = 1.0;
  position.deviation_range = 0.04;
  (void)position.map_id.assign("lab");
  b.state.agv_position = position;
  b.state.velocity = Velocity{0.35, 0.0, 0.05};
  b.state.driving = true;
  b.state.battery.battery_charge = 83.5;
  b.state.battery.battery_voltage = 12.42;
}

void decode_order_bench(benchmark::State& state, int nodes) {
  auto b = make_buffers();
  const std::string text = order_json(nodes, "order-1");
  for (auto _ : state) {
    const Decoded decoded = decode_order(text, kVersion, b->order, b->scratch);
    if (!decoded.ok()) {
      state.SkipWithError(decoded.error().description.view().data());
      break;
    }
    benchmark::DoNotOptimize(b->order.nodes.size());
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * text.size()));
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
  state.counters["json_bytes"] = static_cast<double>(text.size());
}

void BM_DecodeOrder10Nodes(benchmark::State& state) { decode_order_bench(state, 10); }
BENCHMARK(BM_DecodeOrder10Nodes);

void BM_DecodeOrder32Nodes(benchmark::State& state) { decode_order_bench(state, static_cast<int>(kMaxNodes)); }
BENCHMARK(BM_DecodeOrder32Nodes);

void BM_DecodeInstantActions(benchmark::State& state) {
  auto b = make_buffers();
  const std::string text = instant_actions_json();
  for (auto _ : state) {
    const Decoded decoded = decode_instant_actions(text, kVersion, b->actions, b->scratch);
    if (!decoded.ok()) {
      state.SkipWithError(decoded.error().description.view().data());
      break;
    }
    benchmark::DoNotOptimize(b->actions.actions.size());
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * text.size()));
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
  state.counters["json_bytes"] = static_cast<double>(text.size());
}
BENCHMARK(BM_DecodeInstantActions);

// The state of a robot 10 nodes into an order: 10 node states, 9 edge states, 3 action
// states, 1 error, position, velocity and battery.
void BM_EncodeStateInProgress(benchmark::State& state) {
  auto b = make_buffers();
  auto vehicle = std::make_unique<Vehicle>(vehicle_config());
  state_in_progress(*vehicle, *b);
  if (b->state.node_states.size() != 10 || b->state.action_states.size() != 3 || b->state.errors.size() != 1) {
    state.SkipWithError("the state is not the one meant");
    return;
  }
  std::size_t bytes = 0;
  for (auto _ : state) {
    auto text = encode_state(b->state, kVersion, b->out);
    if (!text) {
      state.SkipWithError(text.error().c_str());
      break;
    }
    bytes = text->size();
    benchmark::DoNotOptimize(text->data());
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * bytes));
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
  state.counters["json_bytes"] = static_cast<double>(bytes);
}
BENCHMARK(BM_EncodeStateInProgress);

void BM_EncodeVisualization(benchmark::State& state) {
  auto b = make_buffers();
  Visualization message;
  message.header.header_id = 815;
  (void)message.header.timestamp.assign("2026-12-03T10:00:01.25Z");
  (void)message.header.manufacturer.assign("Sen3Bot");
  (void)message.header.serial_number.assign("r1");
  AgvPosition position;
  position.position_initialized = true;
  position.x = 2.4871;
  position.y = 3.1052;
  position.theta = 1.5237;
  (void)position.map_id.assign("lab");
  message.agv_position = position;
  message.velocity = Velocity{0.35, 0.0, 0.05};
  std::size_t bytes = 0;
  for (auto _ : state) {
    auto text = encode_visualization(message, kVersion, b->out);
    if (!text) {
      state.SkipWithError(text.error().c_str());
      break;
    }
    bytes = text->size();
    benchmark::DoNotOptimize(text->data());
    benchmark::ClobberMemory();
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * bytes));
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
  state.counters["json_bytes"] = static_cast<double>(bytes);
}
BENCHMARK(BM_EncodeVisualization);

// The state machine alone on a decoded 10-node order: receive_order, one update() at the first
// node (traversed; its beep triggered), then a cancelOrder and the update() that finishes it
// at standstill, which frees the vehicle for the next iteration's order. An upper bound for
// taking one order: the cancellation is counted with it.
void BM_VehicleReceiveOrderAndUpdate(benchmark::State& state) {
  auto b = make_buffers();
  auto vehicle = std::make_unique<Vehicle>(vehicle_config());
  const std::string text = order_json(10, "order-1");
  if (!decode_order(text, kVersion, b->order, b->scratch).ok()) {
    state.SkipWithError("the order does not decode");
    return;
  }
  const InstantActions cancel = cancel_order();
  const Pose start = at(0, 0);
  const Progress standing = progress_at(0, 0, 0.0);
  std::array<Id, 2> ids;
  (void)ids[0].assign("order-a");
  (void)ids[1].assign("order-b");
  std::size_t i = 0;
  for (auto _ : state) {
    // Two order ids in turn: after the other's cancel each is a new order (Figure 8).
    b->order.order_id = ids[i++ & 1u];
    if (!vehicle->receive_order(b->order, start)) {
      state.SkipWithError("the order was refused");
      break;
    }
    vehicle->update(standing);
    vehicle->receive_instant_actions(cancel);
    vehicle->update(standing);
    benchmark::DoNotOptimize(vehicle->target().hold);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_VehicleReceiveOrderAndUpdate);

// One control cycle of the vehicle with an order in progress: update() with the pose moving
// along the first edge (no node reached), what the fleet task does every 100 ms.
void BM_VehicleUpdateDriving(benchmark::State& state) {
  auto b = make_buffers();
  auto vehicle = std::make_unique<Vehicle>(vehicle_config());
  const std::string text = order_json(10, "order-1");
  if (!decode_order(text, kVersion, b->order, b->scratch).ok() || !vehicle->receive_order(b->order, at(0, 0))) {
    state.SkipWithError("the order was refused");
    return;
  }
  vehicle->update(progress_at(0, 0, 0.0));  // node-00 traversed; driving to node-01
  const std::array<Progress, 4> steps = {progress_at(0.2, 0.05, 0.4), progress_at(0.3, 0.08, 0.4),
                                         progress_at(0.4, 0.12, 0.4), progress_at(0.3, 0.1, 0.4)};
  std::size_t i = 0;
  for (auto _ : state) {
    vehicle->update(steps[i++ & 3u]);
    benchmark::DoNotOptimize(vehicle->target().x);
  }
  if (vehicle->last_node_id() != "node-00") state.SkipWithError("a node was reached");
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_VehicleUpdateDriving);

// One order message handled as the fleet task handles it: decode_order, receive_order, the
// cycle's update(), then the state it publishes on the event (fill_state, the host's fields,
// encode_state). The cancelOrder that frees the vehicle for the next iteration (one more
// update()) is counted too.
void BM_RobotHandlesOrderMessage(benchmark::State& state) {
  auto b = make_buffers();
  auto vehicle = std::make_unique<Vehicle>(vehicle_config());
  // Orders of two ids taken in turn: each one new to the vehicle after the other's cancel.
  const std::array<std::string, 2> texts = {order_json(10, "order-a"), order_json(10, "order-b")};
  const InstantActions cancel = cancel_order();
  const Pose start = at(0, 0);
  const Progress standing = progress_at(0, 0, 0.0);
  std::size_t bytes_in = 0, bytes_out = 0, i = 0;
  for (auto _ : state) {
    const std::string& text = texts[i++ & 1u];
    const Decoded decoded = decode_order(text, kVersion, b->order, b->scratch);
    if (!decoded.ok() || !vehicle->receive_order(b->order, start)) {
      state.SkipWithError("the order was refused");
      break;
    }
    vehicle->update(standing);
    State& s = b->state;
    s = State{};
    vehicle->fill_state(s);
    s.header.header_id = static_cast<std::uint32_t>(i);
    (void)s.header.timestamp.assign("2026-12-03T10:00:01.25Z");
    AgvPosition position;
    position.position_initialized = true;
    position.localization_score = 1.0;
    position.deviation_range = 0.04;
    (void)position.map_id.assign("lab");
    s.agv_position = position;
    s.velocity = Velocity{0.0, 0.0, 0.0};
    s.battery.battery_charge = 83.5;
    s.battery.battery_voltage = 12.42;
    auto out = encode_state(s, kVersion, b->out);
    if (!out) {
      state.SkipWithError(out.error().c_str());
      break;
    }
    vehicle->state_published();
    bytes_in += text.size();
    bytes_out += out->size();
    vehicle->receive_instant_actions(cancel);
    vehicle->update(standing);
    benchmark::DoNotOptimize(out->data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
  state.SetBytesProcessed(static_cast<std::int64_t>(bytes_in + bytes_out));
}
BENCHMARK(BM_RobotHandlesOrderMessage);

// The state sent on the timer with an order in progress (no message came): fill_state, the
// host's fields and encode_state.
void BM_RobotPeriodicState(benchmark::State& state) {
  auto b = make_buffers();
  auto vehicle = std::make_unique<Vehicle>(vehicle_config());
  state_in_progress(*vehicle, *b);
  std::size_t bytes = 0;
  for (auto _ : state) {
    State& s = b->state;
    s = State{};
    vehicle->fill_state(s);
    s.header.header_id = 4711;
    (void)s.header.timestamp.assign("2026-12-03T10:00:01.25Z");
    s.velocity = Velocity{0.35, 0.0, 0.05};
    auto out = encode_state(s, kVersion, b->out);
    if (!out) {
      state.SkipWithError(out.error().c_str());
      break;
    }
    bytes += out->size();
    benchmark::DoNotOptimize(out->data());
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
  state.SetBytesProcessed(static_cast<std::int64_t>(bytes));
}
BENCHMARK(BM_RobotPeriodicState);

}  // namespace

BENCHMARK_MAIN();
