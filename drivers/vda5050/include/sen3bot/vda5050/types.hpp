#pragma once
// VDA 5050 (2.0.0 and 2.1.0) messages as fixed-capacity values: what the codec decodes an
// order or instant actions into, and what the vehicle's state machine reports. Every
// container has a compile-time bound, so a robot holding an order owns no heap memory; a
// message that does not fit is rejected by the codec with the field that overflowed.
#include <array>
#include <cstddef>
#include <cstdint>
#include <optional>
#include <string_view>

#include "sen3bot/mem/static_vector.hpp"

namespace sen3bot::vda5050 {

using mem::StaticVector;

// A string field with a fixed capacity. The protocol sets no length limit; ours are in
// kIdCapacity and kTextCapacity, and a longer value is a validation error, never truncated.
template <std::size_t N>
class FixedString {
 public:
  static constexpr std::size_t kCapacity = N;
  FixedString() = default;
  // False when text does not fit (the string is then left empty).
  [[nodiscard]] bool assign(std::string_view text) noexcept {
    if (text.size() > N) {
      size_ = 0;
      return false;
    }
    for (std::size_t i = 0; i < text.size(); ++i) data_[i] = text[i];
    size_ = static_cast<std::uint16_t>(text.size());
    return true;
  }
  [[nodiscard]] std::string_view view() const noexcept { return {data_.data(), size_}; }
  [[nodiscard]] bool empty() const noexcept { return size_ == 0; }
  friend bool operator==(const FixedString& a, const FixedString& b) noexcept { return a.view() == b.view(); }
  friend bool operator==(const FixedString& a, std::string_view b) noexcept { return a.view() == b; }

 private:
  std::array<char, N> data_{};
  std::uint16_t size_ = 0;
};

inline constexpr std::size_t kIdCapacity = 64;     // ids, types, keys, map ids, enum text
inline constexpr std::size_t kTextCapacity = 128;  // descriptions and parameter values
inline constexpr std::size_t kMaxNodes = 32;       // per order message (and held per order)
inline constexpr std::size_t kMaxEdges = kMaxNodes - 1;
inline constexpr std::size_t kMaxActions = 8;      // per node, per edge, per instantActions
inline constexpr std::size_t kMaxParameters = 8;   // per action
inline constexpr std::size_t kMaxActionStates = 64;
inline constexpr std::size_t kMaxErrors = 8;
inline constexpr std::size_t kMaxErrorReferences = 4;

using Id = FixedString<kIdCapacity>;
using Text = FixedString<kTextCapacity>;

// The protocol versions a site may speak. Topics carry "v2" for both.
enum class Version : std::uint8_t { v2_0_0, v2_1_0 };
std::string_view to_string(Version version) noexcept;               // "2.0.0", "2.1.0"
std::optional<Version> parse_version(std::string_view text) noexcept;  // exact "2.0.0" / "2.1.0"

// ISO 8601 UTC with hundredths, as VDA 5050 writes timestamps: "2026-12-03T15:04:13.25Z".
Id iso8601(std::int64_t unix_ns) noexcept;
// Such a timestamp as Unix nanoseconds: any fraction, "Z" or a "+hh:mm" / "-hh:mm" offset;
// false for anything else.
[[nodiscard]] bool parse_iso8601(std::string_view text, std::int64_t& unix_ns) noexcept;

// The header every message starts with (section 6.4).
struct Header {
  std::uint32_t header_id = 0;
  Id timestamp;  // ISO 8601 UTC, as received
  Id version;    // "major.minor.patch", as received
  Id manufacturer;
  Id serial_number;
};

enum class BlockingType : std::uint8_t { none, soft, hard };
enum class ActionStatus : std::uint8_t { waiting, initializing, running, paused, finished, failed };
enum class ErrorLevel : std::uint8_t { warning, fatal };
std::string_view to_string(BlockingType value) noexcept;  // "NONE", "SOFT", "HARD"
std::string_view to_string(ActionStatus value) noexcept;  // "WAITING" ... "FAILED"
std::string_view to_string(ErrorLevel value) noexcept;    // "WARNING", "FATAL"

// The JSON type of an action parameter's value: tells the string "8.5" from the number 8.5.
enum class ParameterType : std::uint8_t { string, number, boolean, array, object };

struct ActionParameter {
  Id key;
  Text value;  // the value's JSON text as received (a string's content without quotes)
  ParameterType value_type = ParameterType::string;
};

struct Action {
  Id action_type;
  Id action_id;
  Text action_description;
  BlockingType blocking_type = BlockingType::none;
  StaticVector<ActionParameter, kMaxParameters> parameters;
};

struct NodePosition {
  double x = 0;
  double y = 0;
  std::optional<double> theta;
  double allowed_deviation_xy = 0;     // 0: the vehicle's own tolerance
  double allowed_deviation_theta = 0;  // 0: the vehicle's own tolerance
  Id map_id;
};

struct Node {
  Id node_id;
  std::uint32_t sequence_id = 0;
  bool released = false;
  std::optional<NodePosition> position;
  StaticVector<Action, kMaxActions> actions;
};

struct Edge {
  Id edge_id;
  std::uint32_t sequence_id = 0;
  bool released = false;
  Id start_node_id;
  Id end_node_id;
  std::optional<double> max_speed;          // m/s
  std::optional<double> max_rotation_speed; // rad/s
  std::optional<double> orientation;        // rad
  bool has_trajectory = false;              // present in the message (we plan our own paths)
  bool has_corridor = false;                // 2.1.0 only
  StaticVector<Action, kMaxActions> actions;
};

struct Order {
  Header header;
  Id order_id;
  std::uint32_t order_update_id = 0;
  Id zone_set_id;
  StaticVector<Node, kMaxNodes> nodes;
  StaticVector<Edge, kMaxEdges> edges;
};

struct InstantActions {
  Header header;
  StaticVector<Action, kMaxActions> actions;
};

struct ErrorReference {
  Id key;    // "orderId", "orderUpdateId", "actionId", "nodeId", "edgeId", "headerId", "topic"
  Text value;
};

struct VehicleError {
  Id error_type;  // "validationError", "orderError", "orderUpdateError", "noOrderToCancel", ...
  Text description;
  ErrorLevel level = ErrorLevel::warning;
  StaticVector<ErrorReference, kMaxErrorReferences> references;
};

struct ActionState {
  Id action_id;
  Id action_type;
  ActionStatus status = ActionStatus::waiting;
  Text result_description;
};

struct NodeState {
  Id node_id;
  std::uint32_t sequence_id = 0;
  bool released = false;
  std::optional<NodePosition> position;
};

struct EdgeState {
  Id edge_id;
  std::uint32_t sequence_id = 0;
  bool released = false;
};


enum class ConnectionState : std::uint8_t { online, offline, connection_broken };
std::string_view to_string(ConnectionState value) noexcept;  // "ONLINE", "OFFLINE", "CONNECTIONBROKEN"

struct Connection {
  Header header;
  ConnectionState state = ConnectionState::online;
};

enum class EStop : std::uint8_t { autoack, manual, remote, none };
enum class OperatingMode : std::uint8_t { automatic, semiautomatic, manual, service, teachin };
std::string_view to_string(EStop value) noexcept;          // "AUTOACK", "MANUAL", "REMOTE", "NONE"
std::string_view to_string(OperatingMode value) noexcept;  // "AUTOMATIC", ...

struct AgvPosition {
  bool position_initialized = false;
  std::optional<double> localization_score;  // [0, 1]
  std::optional<double> deviation_range;     // m
  double x = 0;
  double y = 0;
  double theta = 0;  // [-pi, pi]
  Id map_id;
};

struct Velocity {
  double vx = 0;
  double vy = 0;
  double omega = 0;
};

struct BatteryState {
  double battery_charge = 0;  // %
  std::optional<double> battery_voltage;
  bool charging = false;
};

// A map the vehicle holds (state.maps, 2.1.0 only).
inline constexpr std::size_t kMaxMaps = 4;
enum class MapStatus : std::uint8_t { enabled, disabled };
struct MapState {
  Id map_id;
  Id map_version;
  Text map_description;
  MapStatus status = MapStatus::enabled;
};

// The state message (section 6.10.6): what a vehicle reports, and what a reader of another
// vehicle's state (an AGV's, at the fleet's centre) keeps of it.
struct State {
  Header header;
  Id order_id;
  std::uint32_t order_update_id = 0;
  Id zone_set_id;
  Id last_node_id;
  std::uint32_t last_node_sequence_id = 0;
  StaticVector<NodeState, kMaxNodes> node_states;
  StaticVector<EdgeState, kMaxEdges> edge_states;
  std::optional<AgvPosition> agv_position;
  std::optional<Velocity> velocity;
  bool driving = false;
  bool paused = false;
  bool new_base_request = false;
  std::optional<double> distance_since_last_node;
  StaticVector<ActionState, kMaxActionStates> action_states;
  BatteryState battery;
  OperatingMode operating_mode = OperatingMode::automatic;
  StaticVector<VehicleError, kMaxErrors> errors;
  EStop e_stop = EStop::none;
  bool field_violation = false;
  StaticVector<MapState, kMaxMaps> maps;  // 2.1.0 only; not written in 2.0.0
};

// The visualization message (section 6.13): the position and velocity at a higher rate.
struct Visualization {
  Header header;
  std::optional<AgvPosition> agv_position;
  std::optional<Velocity> velocity;
};

}  // namespace sen3bot::vda5050
