#pragma once
// The robot's people for the fleet's centre: Sen3Bot's own message beside VDA 5050, on
// "sen3bot/v1/people/MANUFACTURER/SERIAL", schema docs/fleet/people.schema.json (version 1).
#include <cstdint>
#include <span>
#include <string>
#include <string_view>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/msg/messages.hpp"
#include "sen3bot/vda5050/types.hpp"

namespace sen3bot::firmware {

inline constexpr std::string_view kPeopleSchemaVersion = "1.0.0";

struct PeopleReport {
  std::uint32_t header_id = 0;
  vda5050::Id timestamp;
  std::string_view manufacturer;
  std::string_view serial_number;
  std::string_view map_id;
  bool robot_valid = false;
  msg::Pose2D robot;
  const msg::People* people = nullptr;
  hal::Nanos now_ns = 0;  // for each person's age since last seen
};

std::string people_topic(std::string_view manufacturer, std::string_view serial_number);

// The JSON, or Errc::capacity when out is too small. Allocates nothing.
Result<std::string_view> encode_people(const PeopleReport& report, std::span<char> out) noexcept;

}  // namespace sen3bot::firmware
