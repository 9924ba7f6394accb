#pragma once
// Plain value types shared by the centre's pieces: map-frame points and poses (metres,
// radians), the ids the host maps its robots, AGVs and areas to, and short fixed texts.
#include <array>
#include <cstdarg>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <string_view>

#include "sen3bot/geometry/geometry.hpp"
#include "sen3bot/geometry/point_math.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/mem/static_vector.hpp"

namespace sen3bot::ssc {

using mem::StaticVector;
using hal::Nanos;  // time is handed in by the caller; the centre never reads a clock

using Point = geometry::Point2D;
using Pose = geometry::Pose2D;

using geometry::distance;

// Small dense ids: the host keeps the mapping to VDA 5050 serial numbers and order ids.
using RobotId = std::uint16_t;
using AgvId = std::uint16_t;
using AreaId = std::uint16_t;
using TaskId = std::uint32_t;
inline constexpr std::uint16_t kNone = 0xFFFF;  // "no robot / AGV / area"

// Capacities of the whole centre; every container is sized by them at compile time.
inline constexpr std::size_t kMaxRobots = 64;    // robot ids are below this (the people map's 64-bit mask)
inline constexpr std::size_t kMaxAgvs = 128;
inline constexpr std::size_t kMaxAreas = 32;
inline constexpr std::size_t kMaxVertices = 16;      // per area outline
inline constexpr std::size_t kMaxSentryPoses = 4;    // per area
inline constexpr std::size_t kMaxRouteNodes = 32;    // an AGV's remaining route (as VDA 5050 orders)
inline constexpr std::size_t kMaxTracks = 128;       // global people tracks
inline constexpr std::size_t kMaxPeoplePerReport = 32;

// Text with a fixed capacity; longer text is truncated (names and log reasons only, where a
// cut tail is harmless).
template <std::size_t N>
class FixedText {
 public:
  FixedText() = default;
  FixedText(std::string_view text) noexcept { assign(text); }  // NOLINT(implicit)
  FixedText(const char* text) noexcept { assign(text); }       // NOLINT(implicit)
  void assign(std::string_view text) noexcept {
    size_ = text.size() < N ? text.size() : N;
    for (std::size_t i = 0; i < size_; ++i) data_[i] = text[i];
    data_[size_] = '\0';
  }
  [[gnu::format(printf, 2, 3)]] void format(const char* fmt, ...) noexcept {
    std::va_list args;
    va_start(args, fmt);
    const int n = std::vsnprintf(data_.data(), N + 1, fmt, args);
    va_end(args);
    size_ = n < 0 ? 0 : (static_cast<std::size_t>(n) < N ? static_cast<std::size_t>(n) : N);
  }
  [[nodiscard]] std::string_view view() const noexcept { return {data_.data(), size_}; }
  [[nodiscard]] const char* c_str() const noexcept { return data_.data(); }
  [[nodiscard]] bool empty() const noexcept { return size_ == 0; }
  friend bool operator==(const FixedText& a, std::string_view b) noexcept { return a.view() == b; }

 private:
  std::array<char, N + 1> data_{};
  std::size_t size_ = 0;
};

using Name = FixedText<31>;
using Reason = FixedText<159>;

}  // namespace sen3bot::ssc
