#pragma once
// A laser scan filtered and projected once, for every reader of it (safety filter,
// localization, costmap). Per beam: its range, whether it is a usable return (finite, at
// least range_min, below range_max), whether it saw nothing up to range_max ("no return":
// free space, nothing to mark), and for usable returns the end point in the robot frame.
// Unreadable beams (NaN) are neither: they must not clear anything.
//
// Fixed capacity (ScanMessage::kMaxBeams), filled in place: assign() allocates nothing.
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <span>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/nav/geometry.hpp"
#include "sen3bot/nav/scan.hpp"

namespace sen3bot::nav {

class ProjectedScan {
 public:
  static constexpr std::size_t kMaxBeams = ScanMessage::kMaxBeams;

  // Beams past kMaxBeams are dropped.
  void assign(const ScanView& scan, const SensorMount& mount) noexcept {
    size_ = std::min(scan.ranges_m.size(), kMaxBeams);
    valid_count_ = 0;
    stamp_ns_ = scan.stamp_ns;
    range_max_m_ = scan.range_max_m;
    mount_ = mount;
    const double mc = std::cos(mount.theta_rad);
    const double ms = std::sin(mount.theta_rad);
    for (std::size_t i = 0; i < size_; ++i) {
      const float r = scan.ranges_m[i];
      range_m_[i] = r;
      const bool finite = std::isfinite(r);
      const bool valid = finite && r >= scan.range_min_m && r < scan.range_max_m;
      no_return_[i] = finite && r >= scan.range_max_m && r >= scan.range_min_m;
      valid_[i] = valid;
      if (!valid && !no_return_[i]) continue;
      const double a = scan.angle_min_rad + static_cast<double>(i) * scan.increment_rad;
      const double ca = std::cos(a);
      const double sa = std::sin(a);
      direction_[i] = {mc * ca - ms * sa, ms * ca + mc * sa};
      if (!valid) continue;
      const double sx = static_cast<double>(r) * ca;
      const double sy = static_cast<double>(r) * sa;
      end_[i] = {mount.x_m + mc * sx - ms * sy, mount.y_m + ms * sx + mc * sy};
      points_[valid_count_++] = end_[i];
    }
  }

  [[nodiscard]] std::size_t size() const noexcept { return size_; }
  [[nodiscard]] bool valid(std::size_t i) const noexcept { return valid_[i]; }
  [[nodiscard]] bool no_return(std::size_t i) const noexcept { return no_return_[i]; }
  [[nodiscard]] float range_m(std::size_t i) const noexcept { return range_m_[i]; }
  // Robot frame; only for valid(i).
  [[nodiscard]] const Point2D& end(std::size_t i) const noexcept { return end_[i]; }
  // Unit vector along the beam, robot frame; for valid(i) or no_return(i).
  [[nodiscard]] const Point2D& direction(std::size_t i) const noexcept { return direction_[i]; }
  // The valid beams' end points, in beam order.
  [[nodiscard]] std::span<const Point2D> points() const noexcept { return {points_.data(), valid_count_}; }

  [[nodiscard]] hal::Nanos stamp_ns() const noexcept { return stamp_ns_; }
  [[nodiscard]] float range_max_m() const noexcept { return range_max_m_; }
  [[nodiscard]] const SensorMount& mount() const noexcept { return mount_; }

 private:
  std::size_t size_ = 0;
  std::size_t valid_count_ = 0;
  hal::Nanos stamp_ns_ = 0;
  float range_max_m_ = 0.0f;
  SensorMount mount_;
  std::array<float, kMaxBeams> range_m_{};
  std::array<bool, kMaxBeams> valid_{};
  std::array<bool, kMaxBeams> no_return_{};
  std::array<Point2D, kMaxBeams> end_{};
  std::array<Point2D, kMaxBeams> direction_{};
  std::array<Point2D, kMaxBeams> points_{};
};

}  // namespace sen3bot::nav
