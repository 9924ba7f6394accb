#pragma once
// Online SGP (navigation.md §5, the source's §2.2.1): the event that re-runs the supervisory
// planner from where the robot is. It fires when a tracked person is within trigger_distance_m
// of the robot while the robot is farther than deviation_m from the safe path and its approach to
// the goal (the local planner took it round the person), and it has been so for delay_s (the
// robot is passing the person by then). A deviation with nobody near (a box in the way) never
// fires; after firing it waits cooldown_s. Each cycle's outcome is counted by its reason. Pure: no I/O, no allocation.
#include <array>
#include <cstdint>
#include <span>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/msg/people.hpp"
#include "sen3bot/nav/geometry.hpp"

namespace sen3bot::nav {

struct OsgpConfig {
  double trigger_distance_m = 2.0;
  double deviation_m = 0.4;
  double delay_s = 1.0;
  double cooldown_s = 5.0;
  // A person seen near within this long counts (one being passed is soon out of the camera's
  // view, and their track expires, before the deviation shows).
  double person_timeout_s = 4.0;
};

enum class OsgpOutcome : std::uint8_t {
  on_path,            // within deviation_m of the safe path (or no safe path)
  deviated_no_person, // off the path with nobody near: an obstacle, not a person
  waiting,            // off the path with a person near, for less than delay_s
  triggered,          // re-run the SGP now
  cooling_down,       // off the path with a person near, within cooldown_s of the last trigger
};
inline constexpr std::size_t kOsgpOutcomes = 5;
[[nodiscard]] const char* to_string(OsgpOutcome outcome) noexcept;

// Distance from p to the polyline (infinity for an empty one).
[[nodiscard]] double distance_to_path(Point2D p, std::span<const Point2D> path) noexcept;

class OsgpTrigger {
 public:
  explicit OsgpTrigger(const OsgpConfig& config = {}) noexcept : config_(config) {}
  // The deviation is from the safe path continued to the goal (the global planner's approach
  // from the path's end).
  OsgpOutcome update(const Pose2D& robot, std::span<const Point2D> safe_path, Point2D goal, const msg::People& people,
                     hal::Nanos now_ns) noexcept;
  // A new goal (and its new safe path): the wait starts again, the cooldown is kept.
  void reset() noexcept { armed_ns_ = -1; }
  [[nodiscard]] std::uint64_t count(OsgpOutcome outcome) const noexcept {
    return counts_[static_cast<std::size_t>(outcome)];
  }

 private:
  OsgpConfig config_;
  hal::Nanos armed_ns_ = -1;         // when a person near and a deviation first held together
  hal::Nanos last_trigger_ns_ = -1;
  hal::Nanos last_near_ns_ = -1;     // when a person was last seen within trigger_distance_m
  std::array<std::uint64_t, kOsgpOutcomes> counts_{};
};

}  // namespace sen3bot::nav
