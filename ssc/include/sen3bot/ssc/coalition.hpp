#pragma once
// Coalition formation, thesis Table 2.1: how many robots monitor an area an AGV's route
// crosses. The first area crossed decides. A coalition starts with the initial size for the
// area type; once people are known in the area their behaviour sets the final size:
//
//   area                      initial   static people   dynamic people
//   1.1 blind intersection       2            2               2
//   1.2 transition               2            1               2
//   2   workstation              1            1               2
//   3   not monitored            0            0               0
//
// With nobody detected the thesis gives no final size; the initial size is kept while the
// AGV approaches (for 1.1 it says two robots "at all times, until the AGV leaves the area"),
// and the coalition is released once the AGV has passed.
#include <cstdint>

#include "sen3bot/ssc/people_map.hpp"
#include "sen3bot/ssc/site.hpp"

namespace sen3bot::ssc {

enum class PeopleState : std::uint8_t { none, static_people, dynamic_people };  // ordered: worse is larger
std::string_view to_string(PeopleState state) noexcept;  // "none", "static", "dynamic"
[[nodiscard]] PeopleState people_state(const AreaPeople& people) noexcept;

[[nodiscard]] std::uint8_t initial_size(AreaType type) noexcept;
[[nodiscard]] std::uint8_t final_size(AreaType type, PeopleState people) noexcept;

// The priority of a monitoring task: 0 for a 1.1 area (thesis: "p = 0 for monitoring a 1.1
// area"); 1 for 1.2 and 2, the medium level the thesis gives work that another monitoring
// request may take over (scenario 3 frees a 1.2 robot at p = 2 and reuses it nearby).
[[nodiscard]] std::uint8_t monitoring_priority(AreaType type) noexcept;

inline constexpr std::size_t kMaxCoalitionSize = 4;

// One coalition: the robots that monitor one area for every AGV whose route crosses it first.
// Two AGVs heading for the same area share it rather than doubling the robots.
struct Coalition {
  AreaId area = kNone;
  AreaType type = AreaType::not_monitored;
  Nanos started = 0;
  StaticVector<AgvId, kMaxAgvs> agvs;                     // the AGVs it serves
  StaticVector<RobotId, kMaxCoalitionSize> members;
  // The worst people state seen during the coalition's life. Latched, so an area whose people
  // left keeps its final size instead of growing back to the initial one until the AGV passed.
  PeopleState people = PeopleState::none;
  std::uint8_t shortfall = 0;  // robots missing at the last staffing attempt (logged on change)

  // The size it should have now.
  [[nodiscard]] std::uint8_t wanted() const noexcept {
    return people == PeopleState::none ? initial_size(type) : final_size(type, people);
  }
  // Latches the state seen now; true when it got worse.
  bool observe(PeopleState now) noexcept {
    if (now <= people) return false;
    people = now;
    return true;
  }
};

}  // namespace sen3bot::ssc
