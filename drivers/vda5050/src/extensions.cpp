#include "sen3bot/vda5050/extensions.hpp"

#include <cmath>

#include "sen3bot/json/json.hpp"

namespace sen3bot::vda5050 {

namespace {

constexpr double kPi = 3.14159265358979323846;

// Field readers that say which field is wrong.
struct Reader {
  json::Value object;
  std::string_view what;

  Status missing(std::string_view key) const {
    return Error::format(Errc::protocol, "%.*s: '%.*s' missing or of the wrong type", static_cast<int>(what.size()), what.data(),
                         static_cast<int>(key.size()), key.data());
  }
  template <typename S>
  Status text(std::string_view key, S& out) const {
    const json::Value v = object.find(key);
    if (!v.is(json::Type::string)) return missing(key);
    if (Status s = v.string_to(out); !s)
      return Error::format(Errc::capacity, "%.*s: '%.*s' too long", static_cast<int>(what.size()), what.data(),
                           static_cast<int>(key.size()), key.data());
    return {};
  }
  Status number(std::string_view key, double& out) const {
    const json::Value v = object.find(key);
    if (!v.is(json::Type::number)) return missing(key);
    auto n = v.number();
    if (!n) return missing(key);
    out = *n;
    return {};
  }
  Status uint32(std::string_view key, std::uint32_t& out) const {
    const json::Value v = object.find(key);
    auto n = v.is(json::Type::number) ? v.uint32() : Result<std::uint32_t>(Error(Errc::protocol, ""));
    if (!n) return missing(key);
    out = *n;
    return {};
  }
  Status boolean(std::string_view key, bool& out) const {
    const json::Value v = object.find(key);
    if (!v.is(json::Type::boolean)) return missing(key);
    out = *v.boolean();
    return {};
  }
};

#define SEN3BOT_TRY(expr)       \
  do {                          \
    if (Status s_ = (expr); !s_) return s_; \
  } while (false)

Status check_schema_version(const Reader& r, std::string_view known) {
  Text version;
  SEN3BOT_TRY(r.text("schemaVersion", version));
  const std::string_view v = version.view();
  const std::size_t dot = known.find('.');
  if (v.size() <= dot || v.substr(0, dot + 1) != known.substr(0, dot + 1))
    return Error::format(Errc::not_supported, "%.*s: schemaVersion %.*s, this reader knows %.*s", static_cast<int>(r.what.size()),
                         r.what.data(), static_cast<int>(v.size()), v.data(), static_cast<int>(known.size()), known.data());
  return {};
}

}  // namespace

std::string_view to_string(AdviceKind advice) noexcept {
  switch (advice) {
    case AdviceKind::clear: return "CLEAR";
    case AdviceKind::slow: return "SLOW";
    case AdviceKind::stop: return "STOP";
  }
  return "CLEAR";
}

std::string people_topic(std::string_view manufacturer, std::string_view serial_number) {
  return "sen3bot/v1/people/" + std::string(manufacturer) + "/" + std::string(serial_number);
}

std::string advisory_topic(std::string_view manufacturer, std::string_view serial_number) {
  return "sen3bot/v1/advisory/" + std::string(manufacturer) + "/" + std::string(serial_number);
}

std::string formation_topic(std::string_view manufacturer, std::string_view serial_number) {
  return "sen3bot/v1/formation/" + std::string(manufacturer) + "/" + std::string(serial_number);
}

Result<std::string_view> encode_people(const PeopleMessage& m, std::span<char> out) noexcept {
  json::Writer w(out);
  w.begin_object();
  w.member("schemaVersion", kPeopleSchemaVersion);
  w.member_uint32("headerId", m.header_id);
  w.member("timestamp", m.timestamp.view());
  w.member("manufacturer", m.manufacturer.view());
  w.member("serialNumber", m.serial_number.view());
  w.member("mapId", m.map_id.view());
  w.key("robot").begin_object();
  w.member_bool("positionInitialized", m.robot_valid);
  w.member_number("x", m.robot_x);
  w.member_number("y", m.robot_y);
  w.member_number("theta", std::remainder(m.robot_theta, 2 * kPi));
  w.end_object();
  w.key("people").begin_array();
  for (const PersonReport& p : m.people) {
    w.begin_object();
    w.member_uint32("id", p.id);
    w.member_number("x", p.x);
    w.member_number("y", p.y);
    w.member_number("vx", p.vx);
    w.member_number("vy", p.vy);
    w.member_number("width", p.width);
    w.member_number("cageRadius", p.cage_radius);
    w.member("state", p.dynamic ? "DYNAMIC" : "STATIC");
    w.member_number("ageS", p.age_s);
    w.member_uint32("laserPoints", p.laser_points);
    w.member_bool("hidden", p.hidden);
    w.member_number("positionSigma", p.position_sigma);
    w.end_object();
  }
  w.end_array();
  w.end_object();
  return w.finish();
}

Status decode_people(std::string_view text, PeopleMessage& out, DecodeScratch& scratch) noexcept {
  json::Document& doc = scratch.document();
  SEN3BOT_TRY(doc.parse(text));
  const Reader r{doc.root(), "people"};
  if (!r.object.is(json::Type::object)) return Error(Errc::protocol, "people: not a JSON object");
  SEN3BOT_TRY(check_schema_version(r, kPeopleSchemaVersion));
  SEN3BOT_TRY(r.uint32("headerId", out.header_id));
  SEN3BOT_TRY(r.text("timestamp", out.timestamp));
  SEN3BOT_TRY(r.text("manufacturer", out.manufacturer));
  SEN3BOT_TRY(r.text("serialNumber", out.serial_number));
  SEN3BOT_TRY(r.text("mapId", out.map_id));
  const Reader robot{r.object.find("robot"), "people.robot"};
  if (!robot.object.is(json::Type::object)) return r.missing("robot");
  SEN3BOT_TRY(robot.boolean("positionInitialized", out.robot_valid));
  SEN3BOT_TRY(robot.number("x", out.robot_x));
  SEN3BOT_TRY(robot.number("y", out.robot_y));
  SEN3BOT_TRY(robot.number("theta", out.robot_theta));
  const json::Value list = r.object.find("people");
  if (!list.is(json::Type::array)) return r.missing("people");
  if (list.size() > kMaxReportedPeople)
    return Error::format(Errc::capacity, "people: %zu people, at most %zu", list.size(), kMaxReportedPeople);
  out.people.clear();
  for (json::Value item : list.items()) {
    const Reader p{item, "people.people[]"};
    if (!item.is(json::Type::object)) return Error(Errc::protocol, "people.people[]: not an object");
    PersonReport person;
    SEN3BOT_TRY(p.uint32("id", person.id));
    SEN3BOT_TRY(p.number("x", person.x));
    SEN3BOT_TRY(p.number("y", person.y));
    SEN3BOT_TRY(p.number("vx", person.vx));
    SEN3BOT_TRY(p.number("vy", person.vy));
    SEN3BOT_TRY(p.number("width", person.width));
    SEN3BOT_TRY(p.number("cageRadius", person.cage_radius));
    SEN3BOT_TRY(p.number("ageS", person.age_s));
    SEN3BOT_TRY(p.uint32("laserPoints", person.laser_points));
    Id state;
    SEN3BOT_TRY(p.text("state", state));
    if (state != "STATIC" && state != "DYNAMIC") return Error(Errc::protocol, "people.people[].state: STATIC or DYNAMIC");
    person.dynamic = state == "DYNAMIC";
    // Added in 1.1: optional, but of the right type when there.
    if (item.find("hidden").valid()) SEN3BOT_TRY(p.boolean("hidden", person.hidden));
    if (item.find("positionSigma").valid()) SEN3BOT_TRY(p.number("positionSigma", person.position_sigma));
    (void)out.people.push_back(person);
  }
  return {};
}

Result<std::string_view> encode_advisory(const AdvisoryMessage& m, std::span<char> out) noexcept {
  json::Writer w(out);
  w.begin_object();
  w.member("schemaVersion", kAdvisorySchemaVersion);
  w.member_uint32("headerId", m.header_id);
  w.member("timestamp", m.timestamp.view());
  w.key("agv").begin_object();
  w.member("manufacturer", m.agv_manufacturer.view());
  w.member("serialNumber", m.agv_serial_number.view());
  w.end_object();
  w.member("advice", to_string(m.advice));
  w.member_number("speedFactor", m.speed_factor);
  w.member("areaId", m.area_id.view());
  w.member("areaType", m.area_type.view());
  w.member_uint32("people", m.people);
  w.member_uint32("dynamicPeople", m.dynamic_people);
  w.member_number("distanceToAreaM", m.distance_to_area_m);
  w.member("reason", m.reason.view());
  w.end_object();
  return w.finish();
}

Status decode_advisory(std::string_view text, AdvisoryMessage& out, DecodeScratch& scratch) noexcept {
  json::Document& doc = scratch.document();
  SEN3BOT_TRY(doc.parse(text));
  const Reader r{doc.root(), "advisory"};
  if (!r.object.is(json::Type::object)) return Error(Errc::protocol, "advisory: not a JSON object");
  SEN3BOT_TRY(check_schema_version(r, kAdvisorySchemaVersion));
  SEN3BOT_TRY(r.uint32("headerId", out.header_id));
  SEN3BOT_TRY(r.text("timestamp", out.timestamp));
  const Reader agv{r.object.find("agv"), "advisory.agv"};
  if (!agv.object.is(json::Type::object)) return r.missing("agv");
  SEN3BOT_TRY(agv.text("manufacturer", out.agv_manufacturer));
  SEN3BOT_TRY(agv.text("serialNumber", out.agv_serial_number));
  Id advice;
  SEN3BOT_TRY(r.text("advice", advice));
  if (advice == "CLEAR") {
    out.advice = AdviceKind::clear;
  } else if (advice == "SLOW") {
    out.advice = AdviceKind::slow;
  } else if (advice == "STOP") {
    out.advice = AdviceKind::stop;
  } else {
    return Error(Errc::protocol, "advisory.advice: CLEAR, SLOW or STOP");
  }
  SEN3BOT_TRY(r.number("speedFactor", out.speed_factor));
  if (!(out.speed_factor >= 0 && out.speed_factor <= 1)) return Error(Errc::protocol, "advisory.speedFactor: in [0, 1]");
  SEN3BOT_TRY(r.text("areaId", out.area_id));
  SEN3BOT_TRY(r.text("areaType", out.area_type));
  SEN3BOT_TRY(r.uint32("people", out.people));
  SEN3BOT_TRY(r.uint32("dynamicPeople", out.dynamic_people));
  SEN3BOT_TRY(r.number("distanceToAreaM", out.distance_to_area_m));
  SEN3BOT_TRY(r.text("reason", out.reason));
  return {};
}

Result<std::string_view> encode_formation(const FormationCommand& m, std::span<char> out) noexcept {
  if (!std::isfinite(m.v)) return Error(Errc::invalid_argument, "formation.v: not a finite number");
  if (!std::isfinite(m.omega)) return Error(Errc::invalid_argument, "formation.omega: not a finite number");
  if (!(m.hold_s > 0 && m.hold_s <= kMaxFormationHoldS)) return Error(Errc::invalid_argument, "formation.holdS: in (0, 2]");
  json::Writer w(out);
  w.begin_object();
  w.member("schemaVersion", kFormationSchemaVersion);
  w.member_uint32("headerId", m.header_id);
  w.member("timestamp", m.timestamp.view());
  w.member("manufacturer", m.manufacturer.view());
  w.member("serialNumber", m.serial_number.view());
  w.member_number("v", m.v);
  w.member_number("omega", m.omega);
  w.member_number("holdS", m.hold_s);
  w.end_object();
  return w.finish();
}

Status decode_formation(std::string_view text, FormationCommand& out, DecodeScratch& scratch) noexcept {
  json::Document& doc = scratch.document();
  SEN3BOT_TRY(doc.parse(text));
  const Reader r{doc.root(), "formation"};
  if (!r.object.is(json::Type::object)) return Error(Errc::protocol, "formation: not a JSON object");
  SEN3BOT_TRY(check_schema_version(r, kFormationSchemaVersion));
  SEN3BOT_TRY(r.uint32("headerId", out.header_id));
  SEN3BOT_TRY(r.text("timestamp", out.timestamp));
  SEN3BOT_TRY(r.text("manufacturer", out.manufacturer));
  SEN3BOT_TRY(r.text("serialNumber", out.serial_number));
  SEN3BOT_TRY(r.number("v", out.v));
  SEN3BOT_TRY(r.number("omega", out.omega));
  SEN3BOT_TRY(r.number("holdS", out.hold_s));
  // The reader refuses numbers beyond a double's range; this is the robot's last word on it.
  if (!std::isfinite(out.v)) return Error(Errc::protocol, "formation.v: not a finite number");
  if (!std::isfinite(out.omega)) return Error(Errc::protocol, "formation.omega: not a finite number");
  if (!(out.hold_s > 0 && out.hold_s <= kMaxFormationHoldS)) return Error(Errc::protocol, "formation.holdS: in (0, 2]");
  return {};
}

}  // namespace sen3bot::vda5050
