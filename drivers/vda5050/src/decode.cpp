// The messages' decoders (codec.hpp), over the decode walker (decoder.hpp).
#include <cmath>
#include <cstdio>

#include "decoder.hpp"
#include "sen3bot/vda5050/codec.hpp"

namespace sen3bot::vda5050 {

using namespace wire;

namespace {

// Section 6.6.1: the graph of an order that decoded per the schema.
bool check_graph(Decoder& d, const Order& o) noexcept {
  if (o.nodes.empty()) {
    auto at = d.field("nodes");
    return d.fail(kValidationError, "an order needs at least one node");
  }
  if (o.edges.size() != o.nodes.size() - 1) {
    auto at = d.field("edges");
    return d.fail(kValidationError, "%zu edges for %zu nodes, there must be one fewer", o.edges.size(), o.nodes.size());
  }
  // Walk node 0, edge 0, node 1, ... : sequence ids rise, nothing released after the horizon.
  std::uint32_t last_seq = 0;
  bool horizon = false;
  for (std::size_t i = 0; i < o.nodes.size(); ++i) {
    const Node& n = o.nodes[i];
    {
      auto at = d.field("nodes");
      auto item = d.index(i);
      Decoder::IdScope id(d, "nodeId");
      d.set_id(n.node_id);
      if (i > 0 && n.sequence_id <= last_seq) {
        auto f = d.field("sequenceId");
        return d.fail(kValidationError, "sequenceId %u not above the previous edge's %u", n.sequence_id, last_seq);
      }
      if (n.released && horizon) {
        auto f = d.field("released");
        return d.fail(kValidationError, "a released node after an unreleased element");
      }
    }
    last_seq = n.sequence_id;
    horizon = horizon || !n.released;
    if (i == o.edges.size()) break;
    const Edge& e = o.edges[i];
    auto at = d.field("edges");
    auto item = d.index(i);
    Decoder::IdScope id(d, "edgeId");
    d.set_id(e.edge_id);
    if (e.sequence_id <= last_seq) {
      auto f = d.field("sequenceId");
      return d.fail(kValidationError, "sequenceId %u not above the previous node's %u", e.sequence_id, last_seq);
    }
    if (e.start_node_id != n.node_id) {
      auto f = d.field("startNodeId");
      return d.fail(kValidationError, "startNodeId is not the node before it (%.*s)", static_cast<int>(n.node_id.view().size()),
                    n.node_id.view().data());
    }
    const Node& next = o.nodes[i + 1];
    if (e.end_node_id != next.node_id) {
      auto f = d.field("endNodeId");
      return d.fail(kValidationError, "endNodeId is not the node after it (%.*s)", static_cast<int>(next.node_id.view().size()),
                    next.node_id.view().data());
    }
    if (e.released && (horizon || !next.released)) {
      auto f = d.field("released");
      return d.fail(kValidationError, "a released edge needs both its nodes released");
    }
    last_seq = e.sequence_id;
    horizon = horizon || !e.released;
  }
  return true;
}

// Action ids map actions to their states, so they must be unique within a message.
template <typename Visit>
bool check_unique_actions(Decoder& d, Visit&& each_list) noexcept {
  const Action* seen[kMaxActions * (kMaxNodes + kMaxEdges) + kMaxActions];
  std::size_t n = 0;
  bool ok = true;
  each_list([&](const StaticVector<Action, kMaxActions>& list, std::string_view where, std::size_t at) {
    for (std::size_t k = 0; k < list.size() && ok; ++k) {
      const Action& a = list[k];
      for (std::size_t j = 0; j < n; ++j) {
        if (seen[j]->action_id == a.action_id) {
          const auto report = [&] {
            auto fa = d.field("actions");
            auto fk = d.index(k);
            Decoder::IdScope id(d, "actionId");
            d.set_id(a.action_id);
            return d.fail(kValidationError, "actionId used twice in the message");
          };
          if (where.empty()) {
            ok = report();
          } else {
            auto f = d.field(where);
            auto fi = d.index(at);
            ok = report();
          }
          return;
        }
      }
      seen[n++] = &a;
    }
  });
  return ok;
}

void clear(Header& h) noexcept { h = Header{}; }

}  // namespace

std::string_view Decoded::reference(std::string_view key) const noexcept {
  for (const ErrorReference& r : error_.references)
    if (r.key == key) return r.value.view();
  return {};
}

Decoded decode_order(std::string_view text, Version version, Order& out, DecodeScratch& scratch) noexcept {
  VehicleError error;
  Decoder d(version, error, "order");
  clear(out.header);
  out.order_id = Id();
  out.order_update_id = 0;
  out.zone_set_id = Id();
  out.nodes.clear();
  out.edges.clear();
  Value root;
  const bool ok = [&] {
    if (!d.parse(scratch.document(), text, root)) return false;
    if (!d.header(root, out.header)) return false;
    if (!d.string(root, "orderId", out.order_id, true)) return false;
    d.set_order_id(out.order_id);
    if (!d.uint32(root, "orderUpdateId", out.order_update_id, true)) return false;
    if (!d.string(root, "zoneSetId", out.zone_set_id, false)) return false;
    Value nodes, edges;
    if (!d.array(root, "nodes", nodes, true, kMaxNodes) || !d.array(root, "edges", edges, true, kMaxEdges)) return false;
    {
      auto at = d.field("nodes");
      std::size_t i = 0;
      for (Value v : nodes.items()) {
        auto item = d.index(i++);
        (void)out.nodes.emplace_back();
        if (!d.node(v, out.nodes.back())) return false;
      }
    }
    {
      auto at = d.field("edges");
      std::size_t i = 0;
      for (Value v : edges.items()) {
        auto item = d.index(i++);
        (void)out.edges.emplace_back();
        if (!d.edge(v, out.edges.back())) return false;
      }
    }
    if (!check_graph(d, out)) return false;
    return check_unique_actions(d, [&](auto&& visit) {
      for (std::size_t i = 0; i < out.nodes.size(); ++i) visit(out.nodes[i].actions, "nodes", i);
      for (std::size_t i = 0; i < out.edges.size(); ++i) visit(out.edges[i].actions, "edges", i);
    });
  }();
  return ok ? Decoded() : Decoded(error);
}

Decoded decode_instant_actions(std::string_view text, Version version, InstantActions& out,
                               DecodeScratch& scratch) noexcept {
  VehicleError error;
  Decoder d(version, error, "instantActions");
  clear(out.header);
  out.actions.clear();
  Value root;
  const bool ok = [&] {
    if (!d.parse(scratch.document(), text, root)) return false;
    if (!d.header(root, out.header)) return false;
    // The 2.0.0 schema names the array "instantActions", its text "actions".
    std::string_view key = "actions";
    if (version == Version::v2_0_0 && !root.find(key).valid() && root.find("instantActions").valid())
      key = "instantActions";
    if (!d.actions(root, key, out.actions, true)) return false;
    return check_unique_actions(d, [&](auto&& visit) { visit(out.actions, "", 0); });
  }();
  return ok ? Decoded() : Decoded(error);
}

Decoded decode_connection(std::string_view text, Version version, Connection& out, DecodeScratch& scratch) noexcept {
  VehicleError error;
  Decoder d(version, error, "connection");
  clear(out.header);
  Value root;
  const bool ok = d.parse(scratch.document(), text, root) && d.header(root, out.header) &&
                  d.enumeration(root, "connectionState", kConnectionNames, out.state);
  return ok ? Decoded() : Decoded(error);
}

Decoded decode_visualization(std::string_view text, Version version, Visualization& out, DecodeScratch& scratch) noexcept {
  VehicleError error;
  Decoder d(version, error, "visualization");
  clear(out.header);
  out.agv_position.reset();
  out.velocity.reset();
  Value root;
  const bool ok = d.parse(scratch.document(), text, root) && d.header(root, out.header) &&
                  d.agv_position(root, out.agv_position) && d.velocity(root, out.velocity);
  return ok ? Decoded() : Decoded(error);
}

namespace {

// Calls each(v) on every element of `list` with the path at key[i]; false at the first false.
template <typename Each>
bool each_item(Decoder& d, std::string_view key, Value list, Each&& each) noexcept {
  auto at = d.field(key);
  std::size_t i = 0;
  for (Value v : list.items()) {
    auto item = d.index(i++);
    if (!each(v)) return false;
  }
  return true;
}

// A list member kept in `out` (which sets its capacity): each element an object, read by
// read(d, v, entry) into an entry of its own.
template <typename T, std::size_t N, typename Read>
bool decode_list(Decoder& d, Value obj, std::string_view key, bool required, StaticVector<T, N>& out,
                 Read&& read) noexcept {
  Value list;
  if (!d.array(obj, key, list, required, N)) return false;
  if (!list.valid()) return true;
  return each_item(d, key, list, [&](Value v) {
    if (!d.expect(v, Type::object)) return false;
    (void)out.emplace_back();
    return read(d, v, out.back());
  });
}

// What node and edge states share: the id (which a rejection names from here on, in the
// caller's id scope), the sequence id, the description (only checked) and whether released.
template <typename State>
bool graph_state(Decoder& d, Value v, std::string_view id_key, Id& id, std::string_view description_key,
                 State& state) noexcept {
  if (!d.string(v, id_key, id, true)) return false;
  d.set_id(id);
  return d.uint32(v, "sequenceId", state.sequence_id, true) && d.string_type(v, description_key) &&
         d.boolean(v, "released", state.released, true);
}

// An optional object member: read(obj) with the path at key, when it is there.
template <typename Read>
bool optional_object(Decoder& d, Value v, std::string_view key, Read&& read) noexcept {
  Value obj;
  if (!d.object(v, key, obj, false)) return false;
  if (!obj.valid()) return true;
  auto at = d.field(key);
  return read(obj);
}

bool node_state(Decoder& d, Value v, NodeState& n) noexcept {
  Decoder::IdScope id(d, "nodeId");
  if (!graph_state(d, v, "nodeId", n.node_id, "nodeDescription", n)) return false;
  return optional_object(d, v, "nodePosition", [&](Value pos) {
    n.position.emplace();
    return d.node_position(pos, *n.position, false);
  });
}

bool edge_state(Decoder& d, Value v, EdgeState& e) noexcept {
  Decoder::IdScope id(d, "edgeId");
  if (!graph_state(d, v, "edgeId", e.edge_id, "edgeDescription", e)) return false;
  return optional_object(d, v, "trajectory", [&](Value t) { return d.trajectory(t); });
}

bool action_state(Decoder& d, Value v, ActionState& a) noexcept {
  Decoder::IdScope id(d, "actionId");
  if (!d.string(v, "actionId", a.action_id, true)) return false;
  d.set_id(a.action_id);
  return d.string(v, "actionType", a.action_type, false) && d.string_type(v, "actionDescription") &&
         d.enumeration(v, "actionStatus", kActionStatusNames, a.status) &&
         d.string(v, "resultDescription", a.result_description, false);
}

bool error_reference(Decoder& d, Value r, ErrorReference& ref) noexcept {
  return d.string(r, "referenceKey", ref.key, true) && d.string(r, "referenceValue", ref.value, true);
}

bool vehicle_error(Decoder& d, Value v, VehicleError& e) noexcept {
  if (!d.string(v, "errorType", e.error_type, true) || !d.string(v, "errorDescription", e.description, false) ||
      !d.string_type(v, "errorHint") || !d.enumeration(v, "errorLevel", kErrorLevelNames, e.level))
    return false;
  return decode_list(d, v, "errorReferences", false, e.references, error_reference);
}

// Version 2.1.0's maps on the vehicle.
bool map_state(Decoder& d, Value v, MapState& m) noexcept {
  return d.string(v, "mapId", m.map_id, true) && d.string(v, "mapVersion", m.map_version, true) &&
         d.string(v, "mapDescription", m.map_description, false) &&
         d.enumeration(v, "mapStatus", kMapStatusNames, m.status);
}

// Loads are only checked against the schema: this vehicle carries none.
bool check_loads(Decoder& d, Value root) noexcept {
  Value list;
  if (!d.array(root, "loads", list, false, SIZE_MAX)) return false;
  if (!list.valid()) return true;
  return each_item(d, "loads", list, [&](Value v) {
    double w = 0;
    return d.expect(v, Type::object) && d.string_type(v, "loadId") && d.string_type(v, "loadType") &&
           d.string_type(v, "loadPosition") && d.number(v, "weight", w, false, 0);
  });
}

// Information is only checked against the schema: nothing of it is kept.
bool check_information(Decoder& d, Value root) noexcept {
  Value list;
  if (!d.array(root, "information", list, false, SIZE_MAX)) return false;
  if (!list.valid()) return true;
  return each_item(d, "information", list, [&](Value v) {
    Value t;
    int level = 0;
    if (!d.expect(v, Type::object) || !d.require(v, "infoType", t) || !d.string_type(v, "infoType") ||
        !d.string_type(v, "infoDescription") || !d.enumeration(v, "infoLevel", kInfoLevelNames, level))
      return false;
    Value refs;
    return d.array(v, "infoReferences", refs, false, SIZE_MAX);
  });
}

bool decode_battery(Decoder& d, Value root, State& s) noexcept {
  Value obj;
  if (!d.object(root, "batteryState", obj, true)) return false;
  auto at = d.field("batteryState");
  double ignored = 0;
  return d.number(obj, "batteryCharge", s.battery.battery_charge, true) &&
         d.number(obj, "batteryVoltage", s.battery.battery_voltage) &&
         d.number(obj, "batteryHealth", ignored, false, 0, 100) && d.boolean(obj, "charging", s.battery.charging, true) &&
         d.integer_type(obj, "reach", 0);
}

bool decode_safety(Decoder& d, Value root, State& s) noexcept {
  Value obj;
  if (!d.object(root, "safetyState", obj, true)) return false;
  auto at = d.field("safetyState");
  return d.enumeration(obj, "eStop", kEStopNames, s.e_stop) && d.boolean(obj, "fieldViolation", s.field_violation, true);
}

bool decode_state_body(Decoder& d, Value root, State& s) noexcept {
  if (!d.header(root, s.header)) return false;
  if (!d.string(root, "orderId", s.order_id, true)) return false;
  d.set_order_id(s.order_id);
  if (!d.uint32(root, "orderUpdateId", s.order_update_id, true)) return false;
  if (!d.string(root, "zoneSetId", s.zone_set_id, false)) return false;
  if (!d.string(root, "lastNodeId", s.last_node_id, true)) return false;
  if (!d.uint32(root, "lastNodeSequenceId", s.last_node_sequence_id, true)) return false;
  if (!d.boolean(root, "driving", s.driving, true) || !d.boolean(root, "paused", s.paused, false) ||
      !d.boolean(root, "newBaseRequest", s.new_base_request, false))
    return false;
  if (!d.number(root, "distanceSinceLastNode", s.distance_since_last_node)) return false;
  if (!d.enumeration(root, "operatingMode", kOperatingModeNames, s.operating_mode)) return false;
  return decode_list(d, root, "nodeStates", true, s.node_states, node_state) &&
         decode_list(d, root, "edgeStates", true, s.edge_states, edge_state) && d.agv_position(root, s.agv_position) &&
         d.velocity(root, s.velocity) && check_loads(d, root) &&
         decode_list(d, root, "actionStates", true, s.action_states, action_state) && decode_battery(d, root, s) &&
         decode_list(d, root, "errors", true, s.errors, vehicle_error) && check_information(d, root) &&
         decode_safety(d, root, s) &&
         (d.version() != Version::v2_1_0 || decode_list(d, root, "maps", false, s.maps, map_state));
}

}  // namespace

Decoded decode_state(std::string_view text, Version version, State& out, DecodeScratch& scratch) noexcept {
  VehicleError error;
  Decoder d(version, error, "state");
  clear(out.header);
  out.order_id = Id();
  out.order_update_id = 0;
  out.zone_set_id = Id();
  out.last_node_id = Id();
  out.last_node_sequence_id = 0;
  out.node_states.clear();
  out.edge_states.clear();
  out.agv_position.reset();
  out.velocity.reset();
  out.driving = out.paused = out.new_base_request = false;
  out.distance_since_last_node.reset();
  out.action_states.clear();
  out.battery = BatteryState{};
  out.operating_mode = OperatingMode::automatic;
  out.errors.clear();
  out.e_stop = EStop::none;
  out.field_violation = false;
  out.maps.clear();
  Value root;
  const bool ok = d.parse(scratch.document(), text, root) && decode_state_body(d, root, out);
  return ok ? Decoded() : Decoded(error);
}

}  // namespace sen3bot::vda5050
