// The messages' encoders, the factsheet and the topics (codec.hpp).
#include <cmath>
#include <cstdio>

#include "sen3bot/vda5050/codec.hpp"
#include "wire_names.hpp"

namespace sen3bot::vda5050 {

using namespace wire;

namespace {

Status header(json::Writer& w, const Header& h, Version version) {
  if (h.timestamp.empty()) return Error(Errc::invalid_argument, "header.timestamp is empty");
  std::string_view v = h.version.view();
  if (v.empty()) {
    v = to_string(version);
  } else if (!version_matches(v, version)) {
    return Error::format(Errc::invalid_argument, "header.version %.*s is not %s", static_cast<int>(v.size()), v.data(),
                         to_string(version).data());
  }
  w.member_uint32("headerId", h.header_id)
      .member("timestamp", h.timestamp.view())
      .member("version", v)
      .member("manufacturer", h.manufacturer.view())
      .member("serialNumber", h.serial_number.view());
  return {};
}

template <typename F>
Result<std::string_view> write(std::span<char> out, F&& body) noexcept {
  json::Writer w(out);
  w.begin_object();
  if (Status st = body(w); !st) return st.error();
  w.end_object();
  return w.finish();
}

bool is_number_text(std::string_view t) noexcept { return !t.empty() && (t[0] == '-' || (t[0] >= '0' && t[0] <= '9')); }

Status write_action(json::Writer& w, const Action& a) {
  w.begin_object()
      .member("actionType", a.action_type.view())
      .member("actionId", a.action_id.view());
  if (!a.action_description.empty()) w.member("actionDescription", a.action_description.view());
  w.member("blockingType", to_string(a.blocking_type));
  if (!a.parameters.empty()) {
    w.key("actionParameters").begin_array();
    for (const ActionParameter& p : a.parameters) {
      w.begin_object().member("key", p.key.view()).key("value");
      const std::string_view t = p.value.view();
      bool shape = true;
      switch (p.value_type) {
        case ParameterType::string: w.string(t); break;
        case ParameterType::number: shape = is_number_text(t); break;
        case ParameterType::boolean: shape = t == "true" || t == "false"; break;
        case ParameterType::array: shape = t.starts_with('['); break;
        case ParameterType::object: shape = t.starts_with('{'); break;
      }
      if (!shape)
        return Error::format(Errc::invalid_argument, "action %.*s parameter %.*s: value is not of its type",
                             static_cast<int>(a.action_id.view().size()), a.action_id.view().data(),
                             static_cast<int>(p.key.view().size()), p.key.view().data());
      if (p.value_type != ParameterType::string) w.raw(t);
      w.end_object();
    }
    w.end_array();
  }
  w.end_object();
  return {};
}

Status write_actions(json::Writer& w, std::string_view key, const StaticVector<Action, kMaxActions>& actions) {
  w.key(key).begin_array();
  for (const Action& a : actions)
    if (Status st = write_action(w, a); !st) return st;
  w.end_array();
  return {};
}

void write_agv_position(json::Writer& w, const AgvPosition& p) {
  w.key("agvPosition").begin_object()
      .member_number("x", p.x)
      .member_number("y", p.y)
      .member_number("theta", p.theta)
      .member("mapId", p.map_id.view())
      .member_bool("positionInitialized", p.position_initialized);
  if (p.localization_score) w.member_number("localizationScore", *p.localization_score);
  if (p.deviation_range) w.member_number("deviationRange", *p.deviation_range);
  w.end_object();
}

void write_velocity(json::Writer& w, const Velocity& v) {
  w.key("velocity").begin_object().member_number("vx", v.vx).member_number("vy", v.vy).member_number("omega", v.omega).end_object();
}

}  // namespace

Result<std::string_view> encode_order(const Order& o, Version version, std::span<char> out) noexcept {
  return write(out, [&](json::Writer& w) -> Status {
    if (Status st = header(w, o.header, version); !st) return st;
    w.member("orderId", o.order_id.view()).member_uint32("orderUpdateId", o.order_update_id);
    if (!o.zone_set_id.empty()) w.member("zoneSetId", o.zone_set_id.view());
    w.key("nodes").begin_array();
    for (const Node& n : o.nodes) {
      w.begin_object()
          .member("nodeId", n.node_id.view())
          .member_uint32("sequenceId", n.sequence_id)
          .member_bool("released", n.released);
      if (n.position) {
        const NodePosition& p = *n.position;
        w.key("nodePosition").begin_object().member_number("x", p.x).member_number("y", p.y);
        if (p.theta) w.member_number("theta", *p.theta);
        if (p.allowed_deviation_xy != 0) w.member_number("allowedDeviationXY", p.allowed_deviation_xy);
        if (p.allowed_deviation_theta != 0) w.member_number("allowedDeviationTheta", p.allowed_deviation_theta);
        w.member("mapId", p.map_id.view()).end_object();
      }
      if (Status st = write_actions(w, "actions", n.actions); !st) return st;
      w.end_object();
    }
    w.end_array().key("edges").begin_array();
    for (const Edge& e : o.edges) {
      w.begin_object()
          .member("edgeId", e.edge_id.view())
          .member_uint32("sequenceId", e.sequence_id)
          .member_bool("released", e.released)
          .member("startNodeId", e.start_node_id.view())
          .member("endNodeId", e.end_node_id.view());
      if (e.max_speed) w.member_number("maxSpeed", *e.max_speed);
      if (e.max_rotation_speed) w.member_number("maxRotationSpeed", *e.max_rotation_speed);
      if (e.orientation) w.member_number("orientation", *e.orientation);
      if (Status st = write_actions(w, "actions", e.actions); !st) return st;
      w.end_object();
    }
    w.end_array();
    return {};
  });
}

Result<std::string_view> encode_instant_actions(const InstantActions& a, Version version, std::span<char> out) noexcept {
  return write(out, [&](json::Writer& w) -> Status {
    if (Status st = header(w, a.header, version); !st) return st;
    return write_actions(w, "actions", a.actions);
  });
}

Result<std::string_view> encode_connection(const Connection& c, Version version, std::span<char> out) noexcept {
  return write(out, [&](json::Writer& w) -> Status {
    if (Status st = header(w, c.header, version); !st) return st;
    w.member("connectionState", to_string(c.state));
    return {};
  });
}

Result<std::string_view> encode_visualization(const Visualization& v, Version version, std::span<char> out) noexcept {
  return write(out, [&](json::Writer& w) -> Status {
    if (Status st = header(w, v.header, version); !st) return st;
    if (v.agv_position) write_agv_position(w, *v.agv_position);
    if (v.velocity) write_velocity(w, *v.velocity);
    return {};
  });
}

Result<std::string_view> encode_state(const State& s, Version version, std::span<char> out) noexcept {
  return write(out, [&](json::Writer& w) -> Status {
    if (Status st = header(w, s.header, version); !st) return st;
    if (version == Version::v2_1_0 && !s.maps.empty()) {
      w.key("maps").begin_array();
      for (const MapState& m : s.maps) {
        w.begin_object().member("mapId", m.map_id.view()).member("mapVersion", m.map_version.view());
        if (!m.map_description.empty()) w.member("mapDescription", m.map_description.view());
        w.member("mapStatus", kMapStatusNames[static_cast<std::size_t>(m.status)]).end_object();
      }
      w.end_array();
    }
    w.member("orderId", s.order_id.view()).member_uint32("orderUpdateId", s.order_update_id);
    if (!s.zone_set_id.empty()) w.member("zoneSetId", s.zone_set_id.view());
    w.member("lastNodeId", s.last_node_id.view())
        .member_uint32("lastNodeSequenceId", s.last_node_sequence_id)
        .member_bool("driving", s.driving)
        .member_bool("paused", s.paused)
        .member_bool("newBaseRequest", s.new_base_request);
    if (s.distance_since_last_node) w.member_number("distanceSinceLastNode", *s.distance_since_last_node);
    w.member("operatingMode", to_string(s.operating_mode));
    w.key("nodeStates").begin_array();
    for (const NodeState& n : s.node_states) {
      w.begin_object()
          .member("nodeId", n.node_id.view())
          .member_uint32("sequenceId", n.sequence_id)
          .member_bool("released", n.released);
      if (n.position) {
        w.key("nodePosition").begin_object().member_number("x", n.position->x).member_number("y", n.position->y);
        if (n.position->theta) w.member_number("theta", *n.position->theta);
        w.member("mapId", n.position->map_id.view()).end_object();
      }
      w.end_object();
    }
    w.end_array().key("edgeStates").begin_array();
    for (const EdgeState& e : s.edge_states)
      w.begin_object()
          .member("edgeId", e.edge_id.view())
          .member_uint32("sequenceId", e.sequence_id)
          .member_bool("released", e.released)
          .end_object();
    w.end_array();
    if (s.agv_position) write_agv_position(w, *s.agv_position);
    if (s.velocity) write_velocity(w, *s.velocity);
    w.key("actionStates").begin_array();
    for (const ActionState& a : s.action_states) {
      w.begin_object().member("actionId", a.action_id.view());
      if (!a.action_type.empty()) w.member("actionType", a.action_type.view());
      w.member("actionStatus", to_string(a.status));
      if (!a.result_description.empty()) w.member("resultDescription", a.result_description.view());
      w.end_object();
    }
    w.end_array();
    w.key("batteryState").begin_object().member_number("batteryCharge", s.battery.battery_charge);
    if (s.battery.battery_voltage) w.member_number("batteryVoltage", *s.battery.battery_voltage);
    w.member_bool("charging", s.battery.charging).end_object();
    w.key("errors").begin_array();
    for (const VehicleError& e : s.errors) {
      w.begin_object().member("errorType", e.error_type.view());
      if (!e.references.empty()) {
        w.key("errorReferences").begin_array();
        for (const ErrorReference& r : e.references)
          w.begin_object().member("referenceKey", r.key.view()).member("referenceValue", r.value.view()).end_object();
        w.end_array();
      }
      if (!e.description.empty()) w.member("errorDescription", e.description.view());
      w.member("errorLevel", to_string(e.level)).end_object();
    }
    w.end_array();
    w.key("safetyState").begin_object()
        .member("eStop", to_string(s.e_stop))
        .member_bool("fieldViolation", s.field_violation)
        .end_object();
    return {};
  });
}

FactsheetInfo sen3bot_factsheet() noexcept {
  FactsheetInfo f;
  f.series_name = "Sen3Bot";
  f.series_description = "Human-aware sentry robot on a Pioneer 3-DX base";
  f.agv_kinematic = "DIFF";
  f.agv_class = "CARRIER";
  f.max_load_mass = 0;  // carries no load
  (void)f.localization_types.push_back("NATURAL");
  (void)f.navigation_types.push_back("AUTONOMOUS");
  // Pioneer 3-DX: 1.2 m/s top speed, 0.455 m long, 0.381 m wide; its ARCOS default
  // acceleration of 0.3 m/s^2; 0.5 m high with the laser and the camera mast.
  f.speed_min = 0.01;
  f.speed_max = 1.2;
  f.acceleration_max = 0.3;
  f.deceleration_max = 0.3;
  f.height_min = 0.237;
  f.height_max = 0.5;
  f.width = 0.381;
  f.length = 0.455;
  f.min_order_interval = 1.0;
  f.min_state_interval = 0.1;
  f.default_state_interval = 1.0;
  f.visualization_interval = 0.2;
  (void)f.optional_parameters.push_back({"order.nodes.nodePosition", false, "the vehicle plans its own path to it"});
  (void)f.optional_parameters.push_back({"order.edges.maxSpeed", false, ""});
  (void)f.optional_parameters.push_back({"order.edges.maxRotationSpeed", false, ""});
  (void)f.actions.push_back({"cancelOrder", "Cancels the current order.", true, false, false, ""});
  (void)f.actions.push_back({"startPause", "Pauses the current order.", true, false, false, ""});
  (void)f.actions.push_back({"stopPause", "Resumes the paused order.", true, false, false, ""});
  (void)f.actions.push_back({"factsheetRequest", "Publishes the factsheet.", true, false, false, ""});
  (void)f.actions.push_back({"stateRequest", "Publishes a state message.", true, false, false, ""});
  // Two driven wheels of 195 mm on a 0.33 m track, a rear caster.
  (void)f.wheels.push_back({"DRIVE", true, false, 0.0, 0.165, 0.195, 0.05});
  (void)f.wheels.push_back({"DRIVE", true, false, 0.0, -0.165, 0.195, 0.05});
  (void)f.wheels.push_back({"CASTER", false, false, -0.2, 0.0, 0.075, 0.03});
  (void)f.envelope.push_back({0.2275, 0.1905});
  (void)f.envelope.push_back({-0.2275, 0.1905});
  (void)f.envelope.push_back({-0.2275, -0.1905});
  (void)f.envelope.push_back({0.2275, -0.1905});
  f.firmware_version = "1.0.0";
  return f;
}

Result<std::string_view> encode_factsheet(const FactsheetInfo& f, Version version, std::span<char> out) noexcept {
  return write(out, [&](json::Writer& w) -> Status {
    if (Status st = header(w, f.header, version); !st) return st;
    w.key("typeSpecification").begin_object().member("seriesName", f.series_name);
    if (!f.series_description.empty()) w.member("seriesDescription", f.series_description);
    w.member("agvKinematic", f.agv_kinematic)
        .member("agvClass", f.agv_class)
        .member_number("maxLoadMass", f.max_load_mass)
        .key("localizationTypes")
        .begin_array();
    for (std::string_view t : f.localization_types) w.string(t);
    w.end_array().key("navigationTypes").begin_array();
    for (std::string_view t : f.navigation_types) w.string(t);
    w.end_array().end_object();

    w.key("physicalParameters").begin_object()
        .member_number("speedMin", f.speed_min)
        .member_number("speedMax", f.speed_max)
        .member_number("accelerationMax", f.acceleration_max)
        .member_number("decelerationMax", f.deceleration_max)
        .member_number("heightMin", f.height_min)
        .member_number("heightMax", f.height_max)
        .member_number("width", f.width)
        .member_number("length", f.length)
        .end_object();

    const auto u32 = [](std::size_t n) { return static_cast<std::uint32_t>(n); };
    w.key("protocolLimits").begin_object();
    w.key("maxStringLens").begin_object()
        .member_uint32("msgLen", u32(kMaxMessageBytes))
        .member_uint32("topicSerialLen", u32(kIdCapacity))
        .member_uint32("topicElemLen", u32(kIdCapacity))
        .member_uint32("idLen", u32(kIdCapacity))
        .member_bool("idNumericalOnly", false)
        .member_uint32("enumLen", u32(kIdCapacity))
        .member_uint32("loadIdLen", u32(kIdCapacity))
        .end_object();
    w.key("maxArrayLens").begin_object()
        .member_uint32("order.nodes", u32(kMaxNodes))
        .member_uint32("order.edges", u32(kMaxEdges))
        .member_uint32("node.actions", u32(kMaxActions))
        .member_uint32("edge.actions", u32(kMaxActions))
        .member_uint32("actions.actionsParameters", u32(kMaxParameters))
        .member_uint32("instantActions", u32(kMaxActions))
        .member_uint32("state.nodeStates", u32(kMaxNodes))
        .member_uint32("state.edgeStates", u32(kMaxEdges))
        .member_uint32("state.loads", 0)
        .member_uint32("state.actionStates", u32(kMaxActionStates))
        .member_uint32("state.errors", u32(kMaxErrors))
        .member_uint32("state.information", 0)
        .member_uint32("error.errorReferences", u32(kMaxErrorReferences))
        .end_object();
    w.key("timing").begin_object()
        .member_number("minOrderInterval", f.min_order_interval)
        .member_number("minStateInterval", f.min_state_interval)
        .member_number("defaultStateInterval", f.default_state_interval)
        .member_number("visualizationInterval", f.visualization_interval)
        .end_object();
    w.end_object();

    w.key("protocolFeatures").begin_object().key("optionalParameters").begin_array();
    for (const FactsheetParameter& p : f.optional_parameters) {
      w.begin_object().member("parameter", p.parameter).member("support", p.required ? "REQUIRED" : "SUPPORTED");
      if (!p.description.empty()) w.member("description", p.description);
      w.end_object();
    }
    w.end_array().key("agvActions").begin_array();
    for (const FactsheetAction& a : f.actions) {
      w.begin_object().member("actionType", a.action_type);
      if (!a.description.empty()) w.member("actionDescription", a.description);
      w.key("actionScopes").begin_array();
      if (a.instant) w.string("INSTANT");
      if (a.node) w.string("NODE");
      if (a.edge) w.string("EDGE");
      w.end_array();
      if (!a.result_description.empty()) w.member("resultDescription", a.result_description);
      w.end_object();
    }
    w.end_array().end_object();

    w.key("agvGeometry").begin_object().key("wheelDefinitions").begin_array();
    for (const FactsheetWheel& wh : f.wheels)
      w.begin_object()
          .member("type", wh.type)
          .member_bool("isActiveDriven", wh.active_driven)
          .member_bool("isActiveSteered", wh.active_steered)
          .key("position").begin_object().member_number("x", wh.x).member_number("y", wh.y).end_object()
          .member_number("diameter", wh.diameter)
          .member_number("width", wh.width)
          .end_object();
    w.end_array();
    if (!f.envelope.empty()) {
      w.key("envelopes2d").begin_array().begin_object().member("set", "base").key("polygonPoints").begin_array();
      for (const FactsheetPoint& p : f.envelope) w.begin_object().member_number("x", p.x).member_number("y", p.y).end_object();
      w.end_array().member("description", "the vehicle's outline").end_object().end_array();
    }
    w.end_object();
    // No load handling device: an empty specification (loadPositions absent) says so.
    w.key("loadSpecification").begin_object().end_object();
    if (version == Version::v2_1_0 && !f.firmware_version.empty()) {
      w.key("vehicleConfig").begin_object().key("versions").begin_array()
          .begin_object().member("key", "firmware").member("value", f.firmware_version).end_object()
          .end_array().end_object();
    }
    return {};
  });
}

Result<std::string_view> make_topic(std::span<char> out, std::string_view interface_name, Version version,
                                    std::string_view manufacturer, std::string_view serial_number,
                                    std::string_view topic) noexcept {
  (void)version;  // both versions are major 2
  const auto level_ok = [](std::string_view s) {
    if (s.empty()) return false;
    for (char c : s) {
      const auto u = static_cast<unsigned char>(c);
      if (c == '/' || c == '$' || c == '+' || c == '#' || u < 0x20 || u == 0x7F) return false;
    }
    return true;
  };
  const auto serial_ok = [](std::string_view s) {
    if (s.empty()) return false;
    for (char c : s) {
      const bool ok = (c >= 'A' && c <= 'Z') || (c >= 'a' && c <= 'z') || (c >= '0' && c <= '9') || c == '_' ||
                      c == '.' || c == ':' || c == '-';
      if (!ok) return false;
    }
    return true;
  };
  if (!level_ok(interface_name)) return Error(Errc::invalid_argument, "topic: interfaceName is empty or holds / $ + # or a control byte");
  if (!level_ok(manufacturer)) return Error(Errc::invalid_argument, "topic: manufacturer is empty or holds / $ + # or a control byte");
  if (!serial_ok(serial_number)) return Error(Errc::invalid_argument, "topic: serialNumber may hold only A-Z a-z 0-9 _ . : -");
  constexpr std::string_view kTopics[] = {"order", "instantActions", "state", "visualization", "connection", "factsheet"};
  bool known = false;
  for (std::string_view t : kTopics) known = known || t == topic;
  if (!known) return Error::format(Errc::invalid_argument, "topic: \"%.*s\" is not a VDA 5050 topic", static_cast<int>(topic.size() < 40 ? topic.size() : 40), topic.data());
  const std::string_view parts[] = {interface_name, "/v2/", manufacturer, "/", serial_number, "/", topic};
  std::size_t n = 0;
  for (std::string_view p : parts) n += p.size();
  if (n > out.size()) return Error::format(Errc::capacity, "topic: %zu bytes, the buffer holds %zu", n, out.size());
  std::size_t at = 0;
  for (std::string_view p : parts)
    for (char c : p) out[at++] = c;
  return std::string_view(out.data(), n);
}

}  // namespace sen3bot::vda5050
