#pragma once
// The decode walker: reads a message's JSON into its type, keeping the JSON path and the
// innermost id so a rejection says where it happened.
#include <cmath>
#include <cstdarg>
#include <cstdio>

#include "sen3bot/vda5050/codec.hpp"
#include "wire_names.hpp"

namespace sen3bot::vda5050::wire {

using json::Type;
using json::Value;

// Walks a message, keeping the JSON path and the innermost id for the rejection.
class Decoder {
 public:
  Decoder(Version version, VehicleError& error, std::string_view topic) noexcept
      : version_(version), error_(error), topic_(topic) {}

  Version version() const noexcept { return version_; }

  class PathScope {
   public:
    PathScope(Decoder& d, std::size_t len) noexcept : d_(d), len_(len) {}
    PathScope(const PathScope&) = delete;
    PathScope& operator=(const PathScope&) = delete;
    ~PathScope() { d_.truncate(len_); }

   private:
    Decoder& d_;
    std::size_t len_;
  };
  [[nodiscard]] PathScope field(std::string_view key) noexcept {
    const std::size_t len = path_len_;
    append(path_len_ ? "." : "");
    append(key);
    return {*this, len};
  }
  [[nodiscard]] PathScope index(std::size_t i) noexcept {
    const std::size_t len = path_len_;
    char buf[24];
    const int n = std::snprintf(buf, sizeof buf, "[%zu]", i);
    append(std::string_view(buf, n > 0 ? static_cast<std::size_t>(n) : 0));
    return {*this, len};
  }

  // The node/edge/action whose fields are being read, for the rejection's references.
  class IdScope {
   public:
    IdScope(Decoder& d, std::string_view key) noexcept : d_(d), key_(d.id_key_), value_(d.id_value_) {
      d_.id_key_ = key;
      d_.id_value_ = Id();
    }
    IdScope(const IdScope&) = delete;
    IdScope& operator=(const IdScope&) = delete;
    ~IdScope() {
      d_.id_key_ = key_;
      d_.id_value_ = value_;
    }

   private:
    Decoder& d_;
    std::string_view key_;
    Id value_;
  };
  void set_id(const Id& id) noexcept { id_value_ = id; }
  void set_header_id(std::uint32_t id) noexcept {
    header_id_ = id;
    has_header_id_ = true;
  }
  void set_order_id(const Id& id) noexcept { order_id_ = id; }

  [[gnu::format(printf, 3, 4)]] bool fail(std::string_view error_type, const char* fmt, ...) noexcept {
    char reason[Text::kCapacity + 1];
    va_list args;
    va_start(args, fmt);
    std::vsnprintf(reason, sizeof reason, fmt, args);
    va_end(args);
    (void)error_.error_type.assign(error_type);
    error_.level = ErrorLevel::warning;
    char text[2 * Text::kCapacity + 4];  // path and reason; cut to the description's capacity
    if (path_len_) {
      std::snprintf(text, sizeof text, "%s: %s", path_, reason);
    } else {
      std::snprintf(text, sizeof text, "%s", reason);
    }
    (void)error_.description.assign(std::string_view(text).substr(0, Text::kCapacity));
    error_.references.clear();
    const auto ref = [&](std::string_view key, std::string_view value) {
      if (error_.references.full()) return;
      ErrorReference r;
      (void)r.key.assign(key);
      (void)r.value.assign(value.substr(0, Text::kCapacity));
      (void)error_.references.push_back(r);
    };
    if (path_len_) ref("field", std::string_view(path_, path_len_));
    if (!id_key_.empty() && !id_value_.empty()) ref(id_key_, id_value_.view());
    if (!order_id_.empty()) ref("orderId", order_id_.view());
    if (has_header_id_) {
      char id[16];
      std::snprintf(id, sizeof id, "%u", header_id_);
      ref("headerId", id);
    }
    ref("topic", topic_);
    return false;
  }

  bool require(Value obj, std::string_view key, Value& out) noexcept {
    out = obj.find(key);
    if (out.valid()) return true;
    auto at = field(key);
    return fail(kValidationError, "required field missing");
  }

  bool expect(Value v, Type t) noexcept {
    if (v.is(t)) return true;
    return fail(kValidationError, "%s expected, got %s", json::to_string(t).data(), json::to_string(v.type()).data());
  }

  template <typename S>
  bool string(Value v, S& out) noexcept {
    if (!expect(v, Type::string)) return false;
    if (Status st = v.string_to(out); !st) {
      return fail(kOrderError, "longer than the %zu bytes this vehicle holds", S::kCapacity);
    }
    return true;
  }
  template <typename S>
  bool string(Value obj, std::string_view key, S& out, bool required) noexcept {
    Value v = obj.find(key);
    if (!v.valid()) return required ? require(obj, key, v) : true;
    auto at = field(key);
    return string(v, out);
  }
  // A string we do not keep: only its type is checked.
  bool string_type(Value obj, std::string_view key) noexcept {
    Value v = obj.find(key);
    if (!v.valid()) return true;
    auto at = field(key);
    return expect(v, Type::string);
  }

  bool uint32(Value obj, std::string_view key, std::uint32_t& out, bool required) noexcept {
    Value v = obj.find(key);
    if (!v.valid()) return required ? require(obj, key, v) : true;
    auto at = field(key);
    if (!expect(v, Type::number)) return false;
    auto r = v.uint32();
    if (!r) return fail(kValidationError, "not a uint32: %s", r.error().c_str());
    out = *r;
    return true;
  }
  // An integer we do not keep, checked against a minimum.
  bool integer_type(Value obj, std::string_view key, double min) noexcept {
    Value v = obj.find(key);
    if (!v.valid()) return true;
    auto at = field(key);
    if (!expect(v, Type::number)) return false;
    const double d = *v.number();
    if (d != std::floor(d)) return fail(kValidationError, "an integer expected");
    if (d < min) return fail(kValidationError, "below the minimum %g", min);
    return true;
  }

  bool number(Value obj, std::string_view key, double& out, bool required, double min = -HUGE_VAL,
              double max = HUGE_VAL) noexcept {
    Value v = obj.find(key);
    if (!v.valid()) return required ? require(obj, key, v) : true;
    auto at = field(key);
    if (!expect(v, Type::number)) return false;
    const double d = *v.number();
    if (d < min || d > max) return fail(kValidationError, "%.17g outside [%.17g, %.17g]", d, min, max);
    out = d;
    return true;
  }
  bool number(Value obj, std::string_view key, std::optional<double>& out, double min = -HUGE_VAL,
              double max = HUGE_VAL) noexcept {
    if (!obj.find(key).valid()) return true;
    double d = 0;
    if (!number(obj, key, d, true, min, max)) return false;
    out = d;
    return true;
  }

  bool boolean(Value obj, std::string_view key, bool& out, bool required) noexcept {
    Value v = obj.find(key);
    if (!v.valid()) return required ? require(obj, key, v) : true;
    auto at = field(key);
    if (!expect(v, Type::boolean)) return false;
    out = *v.boolean();
    return true;
  }

  template <typename E, std::size_t N>
  bool enumeration(Value obj, std::string_view key, const std::string_view (&names)[N], E& out,
                   bool required = true) noexcept {
    Value v = obj.find(key);
    if (!v.valid()) return required ? require(obj, key, v) : true;
    auto at = field(key);
    if (!expect(v, Type::string)) return false;
    for (std::size_t i = 0; i < N; ++i) {
      if (v.string_equals(names[i])) {
        out = static_cast<E>(i);
        return true;
      }
    }
    const std::string_view t = v.json_text();
    return fail(kValidationError, "%.*s is not one of its values", static_cast<int>(t.size() < 48 ? t.size() : 48), t.data());
  }

  // An array member (required or not); its size checked against our capacity.
  bool array(Value obj, std::string_view key, Value& out, bool required, std::size_t capacity) noexcept {
    out = obj.find(key);
    if (!out.valid()) return required ? require(obj, key, out) : true;
    auto at = field(key);
    if (!expect(out, Type::array)) return false;
    const std::size_t n = out.size();
    if (n > capacity) return fail(kOrderError, "%zu elements, this vehicle holds at most %zu", n, capacity);
    return true;
  }
  bool object(Value obj, std::string_view key, Value& out, bool required) noexcept {
    out = obj.find(key);
    if (!out.valid()) return required ? require(obj, key, out) : true;
    auto at = field(key);
    return expect(out, Type::object);
  }

  bool header(Value root, Header& h) noexcept {
    if (!uint32(root, "headerId", h.header_id, true)) return false;
    set_header_id(h.header_id);
    if (!string(root, "timestamp", h.timestamp, true)) return false;
    if (h.timestamp.empty()) {  // an ISO 8601 time; the encoder would refuse to send it on
      auto at = field("timestamp");
      return fail(kValidationError, "empty, expected an ISO 8601 time");
    }
    if (!string(root, "version", h.version, true)) return false;
    if (!version_matches(h.version.view(), version_)) {
      auto at = field("version");
      return fail(kValidationError, "version %.*s, this site speaks %s", static_cast<int>(h.version.view().size()),
                  h.version.view().data(), to_string(version_).data());
    }
    return string(root, "manufacturer", h.manufacturer, true) && string(root, "serialNumber", h.serial_number, true);
  }

  // The optional agvPosition and velocity members of a state or a visualization.
  bool agv_position(Value root, std::optional<AgvPosition>& out) noexcept {
    Value obj;
    if (!object(root, "agvPosition", obj, false)) return false;
    if (!obj.valid()) return true;
    auto at = field("agvPosition");
    AgvPosition& p = out.emplace();
    return number(obj, "x", p.x, true) && number(obj, "y", p.y, true) && number(obj, "theta", p.theta, true) &&
           string(obj, "mapId", p.map_id, true) && string_type(obj, "mapDescription") &&
           boolean(obj, "positionInitialized", p.position_initialized, true) &&
           number(obj, "localizationScore", p.localization_score, 0.0, 1.0) && number(obj, "deviationRange", p.deviation_range);
  }
  bool velocity(Value root, std::optional<Velocity>& out) noexcept {
    Value obj;
    if (!object(root, "velocity", obj, false)) return false;
    if (!obj.valid()) return true;
    auto at = field("velocity");
    Velocity& v = out.emplace();
    return number(obj, "vx", v.vx, false) && number(obj, "vy", v.vy, false) && number(obj, "omega", v.omega, false);
  }

  bool parse(json::Document& doc, std::string_view text, Value& root) noexcept {
    if (Status st = doc.parse(text); !st) {
      if (st.error().code() == Errc::capacity)
        return fail(kOrderError, "message beyond this vehicle's capacity: %s", st.error().c_str());
      return fail(kValidationError, "malformed JSON: %s", st.error().c_str());
    }
    root = doc.root();
    return expect(root, Type::object);
  }

  bool action(Value v, Action& a) noexcept {
    IdScope id(*this, "actionId");
    if (!expect(v, Type::object)) return false;
    if (!string(v, "actionId", a.action_id, true)) return false;
    set_id(a.action_id);
    if (!string(v, "actionType", a.action_type, true)) return false;
    if (!string(v, "actionDescription", a.action_description, false)) return false;
    if (!enumeration(v, "blockingType", kBlockingNames, a.blocking_type)) return false;
    Value params;
    if (!array(v, "actionParameters", params, false, kMaxParameters)) return false;
    if (!params.valid()) return true;
    auto at = field("actionParameters");
    std::size_t i = 0;
    for (Value p : params.items()) {
      auto item = index(i++);
      if (!expect(p, Type::object)) return false;
      (void)a.parameters.emplace_back();
      ActionParameter& out = a.parameters.back();
      if (!string(p, "key", out.key, true)) return false;
      Value value;
      if (!require(p, "value", value)) return false;
      auto av = field("value");
      switch (value.type()) {
        case Type::string:
          out.value_type = ParameterType::string;
          if (!string(value, out.value)) return false;
          continue;
        case Type::number: out.value_type = ParameterType::number; break;
        case Type::boolean: out.value_type = ParameterType::boolean; break;
        case Type::array: out.value_type = ParameterType::array; break;
        case Type::object: out.value_type = ParameterType::object; break;
        case Type::null: return fail(kValidationError, "null is not an allowed parameter value");
      }
      if (!out.value.assign(value.json_text()))
        return fail(kOrderError, "longer than the %zu bytes this vehicle holds", Text::kCapacity);
    }
    return true;
  }

  bool actions(Value obj, std::string_view key, StaticVector<Action, kMaxActions>& out, bool required) noexcept {
    Value list;
    if (!array(obj, key, list, required, kMaxActions)) return false;
    if (!list.valid()) return true;
    auto at = field(key);
    std::size_t i = 0;
    for (Value v : list.items()) {
      auto item = index(i++);
      (void)out.emplace_back();
      if (!action(v, out.back())) return false;
    }
    return true;
  }

  bool node_position(Value v, NodePosition& p, bool order) noexcept {
    if (!expect(v, Type::object)) return false;
    if (!number(v, "x", p.x, true) || !number(v, "y", p.y, true)) return false;
    if (order) {
      if (!number(v, "theta", p.theta, -kThetaLimit, kThetaLimit)) return false;
      if (!number(v, "allowedDeviationXY", p.allowed_deviation_xy, false, 0)) return false;
      if (!number(v, "allowedDeviationTheta", p.allowed_deviation_theta, false, -kDeviationThetaLimit,
                  kDeviationThetaLimit))
        return false;
      if (!string_type(v, "mapDescription")) return false;
    } else if (!number(v, "theta", p.theta)) {
      return false;
    }
    return string(v, "mapId", p.map_id, true);
  }

  bool node(Value v, Node& n) noexcept {
    IdScope id(*this, "nodeId");
    if (!expect(v, Type::object)) return false;
    if (!string(v, "nodeId", n.node_id, true)) return false;
    set_id(n.node_id);
    if (!uint32(v, "sequenceId", n.sequence_id, true)) return false;
    if (!string_type(v, "nodeDescription")) return false;
    if (!boolean(v, "released", n.released, true)) return false;
    Value pos;
    if (!object(v, "nodePosition", pos, false)) return false;
    if (pos.valid()) {
      auto at = field("nodePosition");
      n.position.emplace();
      if (!node_position(pos, *n.position, true)) return false;
    }
    return actions(v, "actions", n.actions, true);
  }

  bool trajectory(Value t) noexcept {
    if (!expect(t, Type::object)) return false;
    std::uint32_t degree = 0;
    if (!uint32(t, "degree", degree, true)) return false;
    if (degree < 1) {
      auto at = field("degree");
      return fail(kValidationError, "below the minimum 1");
    }
    Value knots, points;
    if (!array(t, "knotVector", knots, true, SIZE_MAX) || !array(t, "controlPoints", points, true, SIZE_MAX)) return false;
    {
      auto at = field("knotVector");
      std::size_t i = 0;
      for (Value k : knots.items()) {
        auto item = index(i++);
        if (!expect(k, Type::number)) return false;
        const double d = *k.number();
        if (d < 0 || d > 1) return fail(kValidationError, "%.17g outside [0, 1]", d);
      }
    }
    auto at = field("controlPoints");
    std::size_t i = 0;
    for (Value p : points.items()) {
      auto item = index(i++);
      if (!expect(p, Type::object)) return false;
      double x = 0, y = 0, w = 0;
      if (!number(p, "x", x, true) || !number(p, "y", y, true) || !number(p, "weight", w, false, 0)) return false;
    }
    return true;
  }

  bool edge(Value v, Edge& e) noexcept {
    IdScope id(*this, "edgeId");
    if (!expect(v, Type::object)) return false;
    if (!string(v, "edgeId", e.edge_id, true)) return false;
    set_id(e.edge_id);
    if (!uint32(v, "sequenceId", e.sequence_id, true)) return false;
    if (!string_type(v, "edgeDescription")) return false;
    if (!boolean(v, "released", e.released, true)) return false;
    if (!string(v, "startNodeId", e.start_node_id, true) || !string(v, "endNodeId", e.end_node_id, true)) return false;
    if (!number(v, "maxSpeed", e.max_speed) || !number(v, "maxRotationSpeed", e.max_rotation_speed)) return false;
    if (!number(v, "orientation", e.orientation, -kThetaLimit, kThetaLimit)) return false;
    double ignored = 0;
    bool flag = false;
    if (!number(v, "maxHeight", ignored, false) || !number(v, "minHeight", ignored, false) ||
        !number(v, "length", ignored, false))
      return false;
    if (!string_type(v, "orientationType") || !string_type(v, "direction")) return false;
    if (!boolean(v, "rotationAllowed", flag, false)) return false;
    Value t;
    if (!object(v, "trajectory", t, false)) return false;
    if (t.valid()) {
      auto at = field("trajectory");
      if (!trajectory(t)) return false;
      e.has_trajectory = true;
    }
    if (version_ == Version::v2_1_0) {
      Value c;
      if (!object(v, "corridor", c, false)) return false;
      if (c.valid()) {
        auto at = field("corridor");
        int ref = 0;
        if (!number(c, "leftWidth", ignored, true, 0) || !number(c, "rightWidth", ignored, true, 0) ||
            !enumeration(c, "corridorRefPoint", kCorridorRefNames, ref, false))
          return false;
        e.has_corridor = true;
      }
    }
    return actions(v, "actions", e.actions, true);
  }

 private:
  void append(std::string_view s) noexcept {
    for (char c : s) {
      if (path_len_ + 1 >= sizeof path_) break;
      path_[path_len_++] = c;
    }
    path_[path_len_] = '\0';
  }
  void truncate(std::size_t len) noexcept {
    path_len_ = len;
    path_[len] = '\0';
  }

  Version version_;
  VehicleError& error_;
  std::string_view topic_;
  char path_[Text::kCapacity] = {};
  std::size_t path_len_ = 0;
  std::string_view id_key_;
  Id id_value_;
  Id order_id_;
  std::uint32_t header_id_ = 0;
  bool has_header_id_ = false;
};

}  // namespace sen3bot::vda5050::wire
