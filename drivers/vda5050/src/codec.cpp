#include "sen3bot/vda5050/codec.hpp"

#include <cmath>
#include <cstdarg>
#include <cstdio>

namespace sen3bot::vda5050 {
namespace {

using json::Type;
using json::Value;

// Ranges the schemas set.
constexpr double kThetaLimit = 3.14159265359;             // node/edge theta, orientation
constexpr double kDeviationThetaLimit = 3.141592654;      // allowedDeviationTheta

constexpr std::string_view kBlockingNames[] = {"NONE", "SOFT", "HARD"};
constexpr std::string_view kActionStatusNames[] = {"WAITING", "INITIALIZING", "RUNNING", "PAUSED", "FINISHED", "FAILED"};
constexpr std::string_view kErrorLevelNames[] = {"WARNING", "FATAL"};
constexpr std::string_view kConnectionNames[] = {"ONLINE", "OFFLINE", "CONNECTIONBROKEN"};
constexpr std::string_view kEStopNames[] = {"AUTOACK", "MANUAL", "REMOTE", "NONE"};
constexpr std::string_view kOperatingModeNames[] = {"AUTOMATIC", "SEMIAUTOMATIC", "MANUAL", "SERVICE", "TEACHIN"};
constexpr std::string_view kMapStatusNames[] = {"ENABLED", "DISABLED"};
constexpr std::string_view kCorridorRefNames[] = {"KINEMATICCENTER", "CONTOUR"};
constexpr std::string_view kInfoLevelNames[] = {"INFO", "DEBUG"};

// "2.<minor>.<patch>" with the site's minor.
bool version_matches(std::string_view text, Version version) noexcept {
  std::size_t i = 0;
  unsigned parts[3] = {0, 0, 0};
  for (int p = 0; p < 3; ++p) {
    const std::size_t start = i;
    while (i < text.size() && text[i] >= '0' && text[i] <= '9' && i - start < 6) parts[p] = parts[p] * 10 + static_cast<unsigned>(text[i++] - '0');
    if (i == start) return false;
    if (p < 2) {
      if (i == text.size() || text[i] != '.') return false;
      ++i;
    }
  }
  if (i != text.size()) return false;
  return parts[0] == 2 && parts[1] == (version == Version::v2_0_0 ? 0u : 1u);
}

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

  Value list;
  if (!d.array(root, "nodeStates", list, true, kMaxNodes)) return false;
  {
    auto at = d.field("nodeStates");
    std::size_t i = 0;
    for (Value v : list.items()) {
      auto item = d.index(i++);
      Decoder::IdScope id(d, "nodeId");
      if (!d.expect(v, Type::object)) return false;
      (void)s.node_states.emplace_back();
      NodeState& n = s.node_states.back();
      if (!d.string(v, "nodeId", n.node_id, true)) return false;
      d.set_id(n.node_id);
      if (!d.uint32(v, "sequenceId", n.sequence_id, true) || !d.string_type(v, "nodeDescription") ||
          !d.boolean(v, "released", n.released, true))
        return false;
      Value pos;
      if (!d.object(v, "nodePosition", pos, false)) return false;
      if (pos.valid()) {
        auto ap = d.field("nodePosition");
        n.position.emplace();
        if (!d.node_position(pos, *n.position, false)) return false;
      }
    }
  }
  if (!d.array(root, "edgeStates", list, true, kMaxEdges)) return false;
  {
    auto at = d.field("edgeStates");
    std::size_t i = 0;
    for (Value v : list.items()) {
      auto item = d.index(i++);
      Decoder::IdScope id(d, "edgeId");
      if (!d.expect(v, Type::object)) return false;
      (void)s.edge_states.emplace_back();
      EdgeState& e = s.edge_states.back();
      if (!d.string(v, "edgeId", e.edge_id, true)) return false;
      d.set_id(e.edge_id);
      if (!d.uint32(v, "sequenceId", e.sequence_id, true) || !d.string_type(v, "edgeDescription") ||
          !d.boolean(v, "released", e.released, true))
        return false;
      Value t;
      if (!d.object(v, "trajectory", t, false)) return false;
      if (t.valid()) {
        auto af = d.field("trajectory");
        if (!d.trajectory(t)) return false;
      }
    }
  }
  if (!d.agv_position(root, s.agv_position) || !d.velocity(root, s.velocity)) return false;
  Value obj;
  if (!d.array(root, "loads", list, false, SIZE_MAX)) return false;
  if (list.valid()) {
    auto at = d.field("loads");
    std::size_t i = 0;
    for (Value v : list.items()) {
      auto item = d.index(i++);
      double w = 0;
      if (!d.expect(v, Type::object) || !d.string_type(v, "loadId") || !d.string_type(v, "loadType") ||
          !d.string_type(v, "loadPosition") || !d.number(v, "weight", w, false, 0))
        return false;
    }
  }
  if (!d.array(root, "actionStates", list, true, kMaxActionStates)) return false;
  {
    auto at = d.field("actionStates");
    std::size_t i = 0;
    for (Value v : list.items()) {
      auto item = d.index(i++);
      Decoder::IdScope id(d, "actionId");
      if (!d.expect(v, Type::object)) return false;
      (void)s.action_states.emplace_back();
      ActionState& a = s.action_states.back();
      if (!d.string(v, "actionId", a.action_id, true)) return false;
      d.set_id(a.action_id);
      if (!d.string(v, "actionType", a.action_type, false) || !d.string_type(v, "actionDescription") ||
          !d.enumeration(v, "actionStatus", kActionStatusNames, a.status) ||
          !d.string(v, "resultDescription", a.result_description, false))
        return false;
    }
  }
  if (!d.object(root, "batteryState", obj, true)) return false;
  {
    auto at = d.field("batteryState");
    double ignored = 0;
    if (!d.number(obj, "batteryCharge", s.battery.battery_charge, true) ||
        !d.number(obj, "batteryVoltage", s.battery.battery_voltage) ||
        !d.number(obj, "batteryHealth", ignored, false, 0, 100) || !d.boolean(obj, "charging", s.battery.charging, true) ||
        !d.integer_type(obj, "reach", 0))
      return false;
  }
  if (!d.array(root, "errors", list, true, kMaxErrors)) return false;
  {
    auto at = d.field("errors");
    std::size_t i = 0;
    for (Value v : list.items()) {
      auto item = d.index(i++);
      if (!d.expect(v, Type::object)) return false;
      (void)s.errors.emplace_back();
      VehicleError& e = s.errors.back();
      if (!d.string(v, "errorType", e.error_type, true) || !d.string(v, "errorDescription", e.description, false) ||
          !d.string_type(v, "errorHint") || !d.enumeration(v, "errorLevel", kErrorLevelNames, e.level))
        return false;
      Value refs;
      if (!d.array(v, "errorReferences", refs, false, kMaxErrorReferences)) return false;
      if (!refs.valid()) continue;
      auto ar = d.field("errorReferences");
      std::size_t k = 0;
      for (Value r : refs.items()) {
        auto ak = d.index(k++);
        if (!d.expect(r, Type::object)) return false;
        (void)e.references.emplace_back();
        ErrorReference& ref = e.references.back();
        if (!d.string(r, "referenceKey", ref.key, true) || !d.string(r, "referenceValue", ref.value, true)) return false;
      }
    }
  }
  if (!d.array(root, "information", list, false, SIZE_MAX)) return false;
  if (list.valid()) {
    auto at = d.field("information");
    std::size_t i = 0;
    for (Value v : list.items()) {
      auto item = d.index(i++);
      Value t;
      int level = 0;
      if (!d.expect(v, Type::object) || !d.require(v, "infoType", t) || !d.string_type(v, "infoType") ||
          !d.string_type(v, "infoDescription") || !d.enumeration(v, "infoLevel", kInfoLevelNames, level))
        return false;
      Value refs;
      if (!d.array(v, "infoReferences", refs, false, SIZE_MAX)) return false;
    }
  }
  if (!d.object(root, "safetyState", obj, true)) return false;
  {
    auto at = d.field("safetyState");
    if (!d.enumeration(obj, "eStop", kEStopNames, s.e_stop) || !d.boolean(obj, "fieldViolation", s.field_violation, true))
      return false;
  }
  if (d.version() == Version::v2_1_0) {
    if (!d.array(root, "maps", list, false, kMaxMaps)) return false;
    if (list.valid()) {
      auto at = d.field("maps");
      std::size_t i = 0;
      for (Value v : list.items()) {
        auto item = d.index(i++);
        if (!d.expect(v, Type::object)) return false;
        (void)s.maps.emplace_back();
        MapState& m = s.maps.back();
        if (!d.string(v, "mapId", m.map_id, true) || !d.string(v, "mapVersion", m.map_version, true) ||
            !d.string(v, "mapDescription", m.map_description, false) ||
            !d.enumeration(v, "mapStatus", kMapStatusNames, m.status))
          return false;
      }
    }
  }
  return true;
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

// ---- encoders ----

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
