#include "sen3bot/ssc/coalition.hpp"

namespace sen3bot::ssc {

std::string_view to_string(PeopleState state) noexcept {
  switch (state) {
    case PeopleState::none: return "none";
    case PeopleState::static_people: return "static";
    case PeopleState::dynamic_people: return "dynamic";
  }
  return "?";
}

PeopleState people_state(const AreaPeople& people) noexcept {
  if (people.any_dynamic()) return PeopleState::dynamic_people;
  if (people.any()) return PeopleState::static_people;
  return PeopleState::none;
}

std::uint8_t initial_size(AreaType type) noexcept {
  switch (type) {
    case AreaType::blind_intersection: return 2;
    case AreaType::transition: return 2;
    case AreaType::workstation: return 1;
    case AreaType::not_monitored: return 0;
  }
  return 0;
}

std::uint8_t final_size(AreaType type, PeopleState people) noexcept {
  if (people == PeopleState::none) return initial_size(type);
  const bool dynamic = people == PeopleState::dynamic_people;
  switch (type) {
    case AreaType::blind_intersection: return 2;
    case AreaType::transition: return dynamic ? 2 : 1;
    case AreaType::workstation: return dynamic ? 2 : 1;
    case AreaType::not_monitored: return 0;
  }
  return 0;
}

std::uint8_t monitoring_priority(AreaType type) noexcept { return type == AreaType::blind_intersection ? 0 : 1; }

}  // namespace sen3bot::ssc
