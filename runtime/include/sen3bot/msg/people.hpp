#pragma once
// People: what a person detector saw in one camera frame, and the people the fusion of those
// boxes with the laser keeps on the map.
#include <array>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "sen3bot/hal/clock.hpp"

namespace sen3bot::msg {

// A detector's box around a person, in pixels of the camera image (u right, v down; u0 < u1,
// v0 < v1).
struct PersonBox {
  float u0 = 0.0f;
  float v0 = 0.0f;
  float u1 = 0.0f;
  float v1 = 0.0f;
  float confidence = 0.0f;  // 0..1
  std::uint16_t class_id = 0;  // the detector's class (COCO: 0 is a person)
};
static_assert(std::is_trivially_copyable_v<PersonBox>);

// One frame's boxes. capture_ns is when the frame was taken, on the firmware's clock.
struct PersonDetections {
  static constexpr std::size_t kMax = 16;
  std::array<PersonBox, kMax> boxes{};
  std::uint8_t count = 0;
  std::uint32_t source = 0;    // which detector
  std::uint32_t sequence = 0;  // the detector's own count of frames
  hal::Nanos capture_ns = 0;
};
static_assert(std::is_trivially_copyable_v<PersonDetections>);

enum class PersonState : std::uint8_t {
  static_person,   // still within the threshold of where it was first seen
  dynamic_person,  // has moved farther than that
};

// A tracked person on the map, with the radius of its virtual cage.
struct TrackedPerson {
  std::uint32_t id = 0;
  double x_m = 0.0;
  double y_m = 0.0;
  double vx_m_s = 0.0;
  double vy_m_s = 0.0;
  double width_m = 0.0;        // the box's horizontal extent at the person's range
  double cage_radius_m = 0.0;  // half the width plus the safety radius (and, hidden, the growth)
  PersonState state = PersonState::static_person;
  hal::Nanos last_seen_ns = 0;
  std::uint16_t points = 0;    // laser returns in the last fix
  // Not seen for the tracker's expire_s but kept: their place is out of the sensors' view (behind
  // the robot, behind a rack) and has not been seen empty. The position is a guess.
  bool hidden = false;
  double position_sigma_m = 0.0;  // the position's standard deviation along its longest axis
};
static_assert(std::is_trivially_copyable_v<TrackedPerson>);

struct People {
  static constexpr std::size_t kMax = 16;
  std::array<TrackedPerson, kMax> items{};
  std::uint8_t count = 0;
  hal::Nanos stamp_ns = 0;
};
static_assert(std::is_trivially_copyable_v<People>);

}  // namespace sen3bot::msg
