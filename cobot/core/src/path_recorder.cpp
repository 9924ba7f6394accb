#include "sen3bot/cobot/path_recorder.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sen3bot/nav/arena.hpp"

namespace sen3bot::cobot {

Status PathRecorder::init(const PathConfig& config, std::pmr::memory_resource& resource) {
  if (config.capacity < 3 || config.capacity > msg::WorkerPath::kMax || !(config.min_spacing_m > 0.0) ||
      !(config.depth_band_m > 0.0) || !(config.bearing_margin_rad >= 0.0)) {
    return Error::format(Errc::config, "cobot path: 3 <= capacity <= %zu, min_spacing_m > 0, depth_band_m > 0, "
                                       "bearing_margin_rad >= 0",
                         msg::WorkerPath::kMax);
  }
  config_ = config;
  reset(0);
  return nav::guarded("cobot path", [&]() -> Status {
    points_ = nav::allocate_array<msg::Point2D>(resource, config.capacity);
    return Status::success();
  });
}

void PathRecorder::reset(std::uint32_t track) noexcept {
  size_ = 0;
  spacing_m_ = config_.min_spacing_m;
  track_ = track;
  ++version_;
}

bool PathRecorder::nearest_return(const msg::ScanView& scan, const msg::Pose2D& laser_pose, msg::Point2D person_at,
                                  double person_width_m, msg::Point2D& out) const noexcept {
  const double c = std::cos(laser_pose.theta_rad);
  const double s = std::sin(laser_pose.theta_rad);
  const double dx = person_at.x_m - laser_pose.x_m;
  const double dy = person_at.y_m - laser_pose.y_m;
  const double person_range = std::hypot(dx, dy);
  if (!(person_range > 0.0)) return false;
  // The person's bearing in the laser frame and the half angle the body covers from there.
  const double person_bearing = std::atan2(-s * dx + c * dy, c * dx + s * dy);
  const double half_angle =
      std::atan(0.5 * std::max(person_width_m, 0.0) / person_range) + config_.bearing_margin_rad;

  double nearest = std::numeric_limits<double>::infinity();
  double nearest_bearing = 0.0;
  for (std::size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const double r = scan.ranges_m[i];
    // NaN (unreadable) fails both comparisons; at or beyond range_max is no return.
    if (!(r > scan.range_min_m) || !(r < scan.range_max_m)) continue;
    if (std::abs(r - person_range) > config_.depth_band_m || !(r < nearest)) continue;
    const double a = scan.angle_min_rad + static_cast<double>(i) * scan.increment_rad;
    if (std::abs(msg::normalize_angle(a - person_bearing)) > half_angle) continue;
    nearest = r;
    nearest_bearing = a;
  }
  if (!std::isfinite(nearest)) return false;
  const double lx = nearest * std::cos(nearest_bearing);
  const double ly = nearest * std::sin(nearest_bearing);
  out = {laser_pose.x_m + c * lx - s * ly, laser_pose.y_m + s * lx + c * ly};
  return true;
}

bool PathRecorder::add_scan(const msg::ScanView& scan, const msg::Pose2D& laser_pose, msg::Point2D person_at,
                            double person_width_m) noexcept {
  msg::Point2D sample;
  if (points_.empty() || !nearest_return(scan, laser_pose, person_at, person_width_m, sample)) return false;
  if (size_ > 0) {
    const msg::Point2D last = points_[size_ - 1];
    if (!(std::hypot(sample.x_m - last.x_m, sample.y_m - last.y_m) > spacing_m_)) return false;
  }
  if (size_ == points_.size()) {
    halve();
    const msg::Point2D last = points_[size_ - 1];
    if (!(std::hypot(sample.x_m - last.x_m, sample.y_m - last.y_m) > spacing_m_)) {
      ++version_;  // halving changed the path
      return false;
    }
  }
  points_[size_++] = sample;
  ++version_;
  return true;
}

void PathRecorder::halve() noexcept {
  // Keep the even points, and the newest so the path still ends where the worker is.
  const std::size_t newest = size_ - 1;
  std::size_t kept = 0;
  for (std::size_t i = 0; i < size_; i += 2) points_[kept++] = points_[i];
  if (newest % 2 != 0) points_[kept++] = points_[newest];
  size_ = kept;
  spacing_m_ *= 2.0;
}

void PathRecorder::fill(msg::WorkerPath& out) const noexcept {
  const std::size_t n = std::min(size_, msg::WorkerPath::kMax);
  for (std::size_t i = 0; i < n; ++i) {
    out.xy[2 * i] = static_cast<float>(points_[i].x_m);
    out.xy[2 * i + 1] = static_cast<float>(points_[i].y_m);
  }
  out.count = static_cast<std::uint16_t>(n);
  out.track = track_;
  out.version = version_;
}

}  // namespace sen3bot::cobot
