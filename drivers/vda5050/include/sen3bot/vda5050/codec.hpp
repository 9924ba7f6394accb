#pragma once
// VDA 5050 messages to and from JSON, for a site speaking 2.0.0 or 2.1.0.
//
// Decoders check what the version's schema requires (required fields, types, enums, ranges,
// uint32 fields) and the order graph rules of section 6.6.1, and say why a message is refused
// the way the vehicle reports it (section 6.6.4): "validationError" for malformed JSON and
// schema or rule violations, "orderError" for what we cannot hold (a capacity from types.hpp),
// with references naming the field and the node, edge or action. Members the schemas do not
// name are ignored: no schema sets additionalProperties, so they are allowed.
//
// Encoders write into the caller's buffer exactly what the version's schema has, and fail
// with Errc::capacity rather than truncate. Nothing allocates; Order and State are large
// (Order is about a megabyte), so keep them and the DecodeScratch static or long-lived.
//
// What differs between the two versions, and what the codec does about it:
//
//   where                    2.0.0                       2.1.0                    here
//   header.version           "2.0.x"                     "2.1.x"                  must match the site's major.minor
//   order edge.corridor      not defined                 optional object          2.1: checked, Edge::has_corridor;
//                                                                                 2.0: an unknown member, ignored
//   state.maps               not defined                 optional array           2.1: read and written (State::maps);
//                                                                                 2.0: neither
//   instantActions array     "instantActions" in the     "actions"                2.0: either name is read;
//                            2.0.0 schema, "actions"                              always written as "actions"
//                            in the text
//   factsheet vehicleConfig  not defined                 optional object          2.1 only
//   factsheet agvActions[]   not defined                 optional array; the      not written (every action
//     .blockingTypes                                     schema puts its enum     here takes any blocking type)
//                                                        on the array itself, so
//                                                        no array validates
//   map actions (downloadMap, enableMap, deleteMap)      defined in 2.1           not offered by this vehicle
//   actionStatus 'PAUSED'    in text and schema          in the text, missing     read in both; written as the
//                                                        from state.schema        text says (the 2.1 schema rejects it)
//
// Topics carry "v2" for both (section 6.3).
#include <array>
#include <cstddef>
#include <span>
#include <string_view>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/json/json.hpp"
#include "sen3bot/vda5050/types.hpp"

namespace sen3bot::vda5050 {

inline constexpr std::string_view kValidationError = "validationError";
inline constexpr std::string_view kOrderError = "orderError";

// The outcome of a decode: accepted, or a rejection as the vehicle reports it (errorType,
// description, references: "field" with the JSON path, then the node/edge/action id, the
// orderId and the headerId when known). After a rejection the output is partly written.
class [[nodiscard]] Decoded {
 public:
  Decoded() = default;
  explicit Decoded(const VehicleError& error) noexcept : ok_(false), error_(error) {}
  [[nodiscard]] bool ok() const noexcept { return ok_; }
  explicit operator bool() const noexcept { return ok_; }
  [[nodiscard]] const VehicleError& error() const noexcept { return error_; }
  // The reference with this key, or empty.
  [[nodiscard]] std::string_view reference(std::string_view key) const noexcept;

 private:
  bool ok_ = true;
  VehicleError error_;
};

inline constexpr std::size_t kMaxMessageBytes = 256 * 1024;
// Enough for an order at every capacity in types.hpp, with room for members we ignore.
inline constexpr std::size_t kDecodeTokens = 32768;

// The token array a decode parses into (512 KiB): one per decoding thread.
class DecodeScratch {
 public:
  DecodeScratch() noexcept = default;
  json::Document& document() noexcept { return doc_; }

 private:
  json::StaticDocument<kDecodeTokens> doc_{json::Limits{32, kMaxMessageBytes}};
};

Decoded decode_order(std::string_view text, Version version, Order& out, DecodeScratch& scratch) noexcept;
Decoded decode_instant_actions(std::string_view text, Version version, InstantActions& out,
                               DecodeScratch& scratch) noexcept;
Decoded decode_state(std::string_view text, Version version, State& out, DecodeScratch& scratch) noexcept;
Decoded decode_connection(std::string_view text, Version version, Connection& out, DecodeScratch& scratch) noexcept;
// The schema makes every member optional; the header is required here as in every other
// message (a reader needs the vehicle's name and the version).
Decoded decode_visualization(std::string_view text, Version version, Visualization& out,
                             DecodeScratch& scratch) noexcept;

// The factsheet (section 6.15): what the vehicle tells master control about itself. The
// text fields are views of constants the caller keeps alive.
struct FactsheetAction {
  std::string_view action_type;
  std::string_view description;
  bool instant = true;  // scopes
  bool node = false;
  bool edge = false;
  std::string_view result_description;
};

struct FactsheetParameter {
  std::string_view parameter;  // e.g. "order.edges.maxSpeed"
  bool required = false;       // "REQUIRED" rather than "SUPPORTED"
  std::string_view description;
};

struct FactsheetWheel {
  std::string_view type;  // "DRIVE", "CASTER", "FIXED", "MECANUM"
  bool active_driven = false;
  bool active_steered = false;
  double x = 0, y = 0;  // m, vehicle frame
  double diameter = 0;  // m
  double width = 0;     // m
};

struct FactsheetPoint {
  double x = 0, y = 0;
};

struct FactsheetInfo {
  Header header;  // timestamp, manufacturer, serialNumber (headerId and version are set by the encoder)
  // typeSpecification
  std::string_view series_name;
  std::string_view series_description;
  std::string_view agv_kinematic = "DIFF";  // "DIFF", "OMNI", "THREEWHEEL"
  std::string_view agv_class = "CARRIER";   // "FORKLIFT", "CONVEYOR", "TUGGER", "CARRIER"
  double max_load_mass = 0;                 // kg
  StaticVector<std::string_view, 6> localization_types;  // "NATURAL", "REFLECTOR", ...
  StaticVector<std::string_view, 3> navigation_types;    // "AUTONOMOUS", ...
  // physicalParameters (m, m/s, m/s^2)
  double speed_min = 0, speed_max = 0, acceleration_max = 0, deceleration_max = 0;
  double height_min = 0, height_max = 0, width = 0, length = 0;
  // protocolLimits.timing (s)
  double min_order_interval = 0, min_state_interval = 0, default_state_interval = 0, visualization_interval = 0;
  // protocolFeatures
  StaticVector<FactsheetParameter, 8> optional_parameters;
  StaticVector<FactsheetAction, 8> actions;
  // agvGeometry: wheels and the 2D envelope "base" (a polygon in the vehicle frame)
  StaticVector<FactsheetWheel, 4> wheels;
  StaticVector<FactsheetPoint, 8> envelope;
  // vehicleConfig.versions (2.1.0): e.g. {"firmware", "1.4.2"}
  std::string_view firmware_version;
};

// Sen3Bot on a Pioneer 3-DX: 0.455 m x 0.381 m, 1.2 m/s, the instant actions it performs.
FactsheetInfo sen3bot_factsheet() noexcept;

// Encoders: the message's JSON in out, or Errc::capacity (out too small) /
// Errc::invalid_argument (a value the schema does not allow, e.g. NaN, an empty timestamp, a
// header version of another major.minor). An empty header.version is written as the version.
Result<std::string_view> encode_order(const Order& order, Version version, std::span<char> out) noexcept;
Result<std::string_view> encode_instant_actions(const InstantActions& actions, Version version,
                                                std::span<char> out) noexcept;
Result<std::string_view> encode_state(const State& state, Version version, std::span<char> out) noexcept;
Result<std::string_view> encode_connection(const Connection& connection, Version version,
                                           std::span<char> out) noexcept;
Result<std::string_view> encode_visualization(const Visualization& visualization, Version version,
                                              std::span<char> out) noexcept;
Result<std::string_view> encode_factsheet(const FactsheetInfo& factsheet, Version version,
                                          std::span<char> out) noexcept;

// "interfaceName/majorVersion/manufacturer/serialNumber/topic" (section 6.3), e.g.
// "uagv/v2/ACME/0001/state". The serial number may hold only A-Z a-z 0-9 _ . : -; no level
// may be empty or hold '/', '$', '+', '#' or control bytes; topic is one of the six.
Result<std::string_view> make_topic(std::span<char> out, std::string_view interface_name, Version version,
                                    std::string_view manufacturer, std::string_view serial_number,
                                    std::string_view topic) noexcept;

}  // namespace sen3bot::vda5050
