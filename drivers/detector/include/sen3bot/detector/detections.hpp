#pragma once
// What a person detector saw in one camera frame: the detectors' own type (the remote
// detector's gate and the on-board HOG detector fill it); the firmware's adapters turn it into
// the bus message (msg::PersonDetections).
#include <array>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "sen3bot/hal/clock.hpp"

namespace sen3bot::detector {

// A box around a person, in pixels of the camera image (u right, v down; u0 < u1, v0 < v1).
struct Box {
  float u0 = 0.0f;
  float v0 = 0.0f;
  float u1 = 0.0f;
  float v1 = 0.0f;
  float confidence = 0.0f;     // 0..1
  std::uint16_t class_id = 0;  // the detector's class (COCO: 0 is a person)
};
static_assert(std::is_trivially_copyable_v<Box>);

// One frame's boxes. capture_ns is when the frame was taken, on the firmware's clock.
struct Detections {
  static constexpr std::size_t kMax = 16;
  std::array<Box, kMax> boxes{};
  std::uint8_t count = 0;
  std::uint32_t source = 0;    // which detector
  std::uint32_t sequence = 0;  // the detector's own count of frames
  hal::Nanos capture_ns = 0;
};
static_assert(std::is_trivially_copyable_v<Detections>);

}  // namespace sen3bot::detector
