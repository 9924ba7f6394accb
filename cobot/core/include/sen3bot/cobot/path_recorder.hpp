#pragma once
// The worker's path as the operation recogniser reads it (fleet.md, "Operation recognition
// from 2D paths"): per scan, the nearest laser return on the worker's body, on the map,
// without timing.
//
// The body's returns: those whose bearing from the laser lies within the person's angular
// half extent, atan((width / 2) / range), plus bearing_margin_rad, of the bearing to the
// person's position, and whose range is within depth_band_m of the person's range. Of those,
// the nearest to the laser is the sample. A sample farther than the spacing (min_spacing_m at
// first) from the last point is appended, so a worker standing still adds nothing. When the
// path is full it is halved, every other point dropped but the first and the newest kept, and
// the spacing doubled: the whole path stays, coarser. The memory is taken in init().
#include <cstddef>
#include <cstdint>
#include <memory_resource>
#include <span>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/msg/cobot.hpp"
#include "sen3bot/msg/geometry.hpp"
#include "sen3bot/msg/laser.hpp"

namespace sen3bot::cobot {

struct PathConfig {
  std::size_t capacity = msg::WorkerPath::kMax;  // points, at most WorkerPath::kMax
  double min_spacing_m = 0.05;
  double depth_band_m = 0.4;         // returns this far from the person's range, either way
  double bearing_margin_rad = 0.05;  // added to the person's angular half extent
};

class PathRecorder {
 public:
  // Errors: a capacity under 3 or over WorkerPath::kMax, a spacing or band not positive.
  Status init(const PathConfig& config, std::pmr::memory_resource& resource);
  // Restarts the path for a person track.
  void reset(std::uint32_t track) noexcept;
  // One scan (laser frame) with the laser's pose on the map and the person's position (map)
  // and width; true when a point was appended.
  bool add_scan(const msg::ScanView& scan, const msg::Pose2D& laser_pose, msg::Point2D person_at,
                double person_width_m) noexcept;
  // The person's nearest body return in this scan (map), without recording it; false: none.
  bool nearest_return(const msg::ScanView& scan, const msg::Pose2D& laser_pose, msg::Point2D person_at,
                      double person_width_m, msg::Point2D& out) const noexcept;
  void fill(msg::WorkerPath& out) const noexcept;

  [[nodiscard]] std::size_t size() const noexcept { return size_; }
  [[nodiscard]] msg::Point2D point(std::size_t i) const noexcept { return points_[i]; }
  [[nodiscard]] double spacing_m() const noexcept { return spacing_m_; }
  [[nodiscard]] std::uint32_t track() const noexcept { return track_; }
  [[nodiscard]] std::uint32_t version() const noexcept { return version_; }

 private:
  void halve() noexcept;

  PathConfig config_;
  std::span<msg::Point2D> points_;
  std::size_t size_ = 0;
  double spacing_m_ = 0.0;
  std::uint32_t track_ = 0;
  std::uint32_t version_ = 0;
};

}  // namespace sen3bot::cobot
