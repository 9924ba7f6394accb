#pragma once
// The collaborative side (Sen3CoBot): QR tags read from the camera, the robot's collaborative
// mode and the operation a worker is recognised to be doing.
#include <array>
#include <cstddef>
#include <cstdint>
#include <type_traits>

#include "sen3bot/hal/clock.hpp"

namespace sen3bot::msg {

// Which tag of an operator's leg band: front (shown first) or back.
enum class TagSide : std::uint8_t { front, back };

// One tag read in one camera frame. u/v/size are in the frame's pixels (the tag's centre and
// its mean side length), for telling which person wears it.
struct TagSighting {
  std::uint32_t operator_id = 0;
  TagSide side = TagSide::front;
  float u_px = 0.0f;
  float v_px = 0.0f;
  float size_px = 0.0f;
};
static_assert(std::is_trivially_copyable_v<TagSighting>);

// The tags read in one frame (a frame may show none).
struct TagFrame {
  static constexpr std::size_t kMax = 4;
  std::array<TagSighting, kMax> tags{};
  std::uint8_t count = 0;
  std::uint64_t frame_sequence = 0;  // the camera's frame number
  hal::Nanos capture_ns = 0;         // when the frame was taken, firmware clock
  std::uint64_t frames_searched = 0;  // the reader's totals, this frame included
  std::uint64_t tags_read = 0;
};
static_assert(std::is_trivially_copyable_v<TagFrame>);

enum class CobotMode : std::uint8_t {
  cooperative,    // the robot's own (or the fleet's) task
  wait4col,       // standing in a sub-critical area, waiting for an operator's request
  collaborative,  // following its operator
};
[[nodiscard]] constexpr const char* to_string(CobotMode mode) noexcept {
  switch (mode) {
    case CobotMode::cooperative: return "cooperative";
    case CobotMode::wait4col: return "wait4col";
    case CobotMode::collaborative: return "collaborative";
  }
  return "unknown";
}

// What the collaborative mode publishes each cycle.
struct CobotState {
  CobotMode mode = CobotMode::cooperative;
  std::uint32_t operator_id = 0;     // the operator in collaborative mode (0: none)
  std::uint32_t operator_track = 0;  // their people track (0: not seen); gets the smaller cage
  std::uint32_t toggles = 0;         // completed requests so far
  std::uint32_t rejections = 0;      // refused attempts so far, all reasons
  hal::Nanos stamp_ns = 0;
};
static_assert(std::is_trivially_copyable_v<CobotState>);

// A worker's path (map frame, no timing), as the collaborative mode records it.
struct WorkerPath {
  static constexpr std::size_t kMax = 1024;
  std::array<float, 2 * kMax> xy{};  // x0, y0, x1, y1, ...
  std::uint16_t count = 0;
  std::uint32_t track = 0;    // the people track recorded
  std::uint32_t version = 0;  // changes whenever points are added or the path restarts
};
static_assert(std::is_trivially_copyable_v<WorkerPath>);

// The operation recognised from a worker's path: one probability per configured operation.
struct OperationEstimate {
  static constexpr std::size_t kMaxOperations = 16;
  std::array<float, kMaxOperations> probability{};
  std::uint8_t operations = 0;
  std::int8_t best = -1;  // -1: nothing recognised yet
  std::uint16_t points = 0;     // path points classified
  std::uint32_t path_version = 0;
  hal::Nanos stamp_ns = 0;
};
static_assert(std::is_trivially_copyable_v<OperationEstimate>);

}  // namespace sen3bot::msg
