#include "fleet_people.hpp"

#include <cmath>

#include "sen3bot/vda5050/json.hpp"

namespace sen3bot::firmware {

std::string people_topic(std::string_view manufacturer, std::string_view serial_number) {
  return "sen3bot/v1/people/" + std::string(manufacturer) + "/" + std::string(serial_number);
}

Result<std::string_view> encode_people(const PeopleReport& report, std::span<char> out) noexcept {
  vda5050::json::Writer w(out);
  w.begin_object();
  w.member("schemaVersion", kPeopleSchemaVersion);
  w.member_uint32("headerId", report.header_id);
  w.member("timestamp", report.timestamp.view());
  w.member("manufacturer", report.manufacturer);
  w.member("serialNumber", report.serial_number);
  w.member("mapId", report.map_id);
  w.key("robot").begin_object();
  w.member_bool("positionInitialized", report.robot_valid);
  w.member_number("x", report.robot.x_m);
  w.member_number("y", report.robot.y_m);
  w.member_number("theta", std::remainder(report.robot.theta_rad, 2 * 3.14159265358979323846));
  w.end_object();
  w.key("people").begin_array();
  const std::size_t count = report.people == nullptr ? 0 : report.people->count;
  for (std::size_t i = 0; i < count && i < msg::People::kMax; ++i) {
    const msg::TrackedPerson& p = report.people->items[i];
    w.begin_object();
    w.member_uint32("id", p.id);
    w.member_number("x", p.x_m);
    w.member_number("y", p.y_m);
    w.member_number("vx", p.vx_m_s);
    w.member_number("vy", p.vy_m_s);
    w.member_number("width", p.width_m);
    w.member_number("cageRadius", p.cage_radius_m);
    w.member("state", p.state == msg::PersonState::dynamic_person ? "DYNAMIC" : "STATIC");
    const double age_s = report.now_ns > p.last_seen_ns ? static_cast<double>(report.now_ns - p.last_seen_ns) * 1e-9 : 0.0;
    w.member_number("ageS", age_s);
    w.member_uint32("laserPoints", p.points);
    w.end_object();
  }
  w.end_array();
  w.end_object();
  return w.finish();
}

}  // namespace sen3bot::firmware
