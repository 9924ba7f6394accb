#pragma once
// Sen3Bot's own messages beside VDA 5050, on the same broker and written the same way (a
// header, ISO 8601 timestamps, camelCase), each with a JSON schema in docs/fleet/ and a
// schemaVersion a reader checks (a reader accepts the major versions it knows; fields are only
// added within one):
//   people    sen3bot/v1/people/MANUFACTURER/SERIAL     a robot's tracked people, to the centre
//   advisory  sen3bot/v1/advisory/MANUFACTURER/SERIAL   the centre's advice about an AGV, to
//                                                       the plant's AGV coordination centre
//   formation sen3bot/v1/formation/MANUFACTURER/SERIAL  the centre's formation controller's
//                                                       velocity for one robot
// Fixed memory, like the codec: encoders write into the caller's buffer, decoders into fixed
// structs through a DecodeScratch.
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/vda5050/codec.hpp"
#include "sen3bot/vda5050/types.hpp"

namespace sen3bot::vda5050 {

inline constexpr std::string_view kPeopleSchemaVersion = "1.1.0";  // 1.1: hidden, positionSigma
inline constexpr std::string_view kAdvisorySchemaVersion = "1.0.0";
inline constexpr std::string_view kFormationSchemaVersion = "1.0.0";
inline constexpr std::size_t kMaxReportedPeople = 16;

struct PersonReport {
  std::uint32_t id = 0;  // the robot's own track id
  double x = 0, y = 0;   // m, map frame
  double vx = 0, vy = 0; // m/s
  double width = 0;      // m
  double cage_radius = 0;  // m
  bool dynamic = false;  // moved farther than the robot's threshold from where first seen
  double age_s = 0;      // since last seen
  std::uint32_t laser_points = 0;
  // Kept out of the sensors' view (a guess), and the position's sigma (m). Optional on reading:
  // a 1.0 report has neither (false, 0).
  bool hidden = false;
  double position_sigma = 0;
};

struct PeopleMessage {
  std::uint32_t header_id = 0;
  Id timestamp;
  Id manufacturer;
  Id serial_number;
  Id map_id;
  bool robot_valid = false;  // the robot is localized: the positions mean something
  double robot_x = 0, robot_y = 0, robot_theta = 0;
  StaticVector<PersonReport, kMaxReportedPeople> people;
};

enum class AdviceKind : std::uint8_t { clear, slow, stop };
std::string_view to_string(AdviceKind advice) noexcept;  // "CLEAR", "SLOW", "STOP"

// What the centre advises for one AGV because of people on its route.
struct AdvisoryMessage {
  std::uint32_t header_id = 0;
  Id timestamp;
  Id agv_manufacturer;
  Id agv_serial_number;
  AdviceKind advice = AdviceKind::clear;
  double speed_factor = 1.0;  // of the AGV's speed: 1 clear, 0 stop
  Id area_id;                 // the area of interest the advice is about (empty with CLEAR)
  Id area_type;               // "1.1", "1.2", "2"
  std::uint32_t people = 0;
  std::uint32_t dynamic_people = 0;
  double distance_to_area_m = 0;  // along the AGV's route
  Text reason;
};

// A velocity for one robot from the centre's formation controller.
inline constexpr double kMaxFormationHoldS = 2.0;
struct FormationCommand {
  std::uint32_t header_id = 0;
  Id timestamp;  // ISO 8601, as every other message
  Id manufacturer;
  Id serial_number;
  double v = 0;       // m/s, forward
  double omega = 0;   // rad/s
  double hold_s = 0;  // the robot drives this at most this long after it arrives (0 < hold_s <= 2)
};

Result<std::string_view> encode_people(const PeopleMessage& message, std::span<char> out) noexcept;
// Errc::protocol naming the field for a message that does not follow the schema, Errc::capacity
// for more people than kMaxReportedPeople, Errc::not_supported for another major version.
Status decode_people(std::string_view text, PeopleMessage& out, DecodeScratch& scratch) noexcept;

Result<std::string_view> encode_advisory(const AdvisoryMessage& message, std::span<char> out) noexcept;
Status decode_advisory(std::string_view text, AdvisoryMessage& out, DecodeScratch& scratch) noexcept;

// Errc::invalid_argument for a number that is not finite or a hold outside (0, 2].
Result<std::string_view> encode_formation(const FormationCommand& message, std::span<char> out) noexcept;
// Errc::protocol naming the field for a missing member, a wrong type or a hold outside (0, 2].
Status decode_formation(std::string_view text, FormationCommand& out, DecodeScratch& scratch) noexcept;

std::string people_topic(std::string_view manufacturer, std::string_view serial_number);
std::string advisory_topic(std::string_view manufacturer, std::string_view serial_number);
std::string formation_topic(std::string_view manufacturer, std::string_view serial_number);

}  // namespace sen3bot::vda5050
