#include "sen3bot/nav/mover_tracker.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sen3bot/geometry/point_math.hpp"
#include "sen3bot/nav/arena.hpp"

namespace sen3bot::nav {

namespace {

using geometry::Point2D;

double seconds_between(hal::Nanos from, hal::Nanos to) noexcept { return static_cast<double>(to - from) / 1e9; }

}  // namespace

Status MoverTracker::init(const DolTrackerConfig& config, std::pmr::memory_resource& resource) {
  if (config.max_tracks == 0 || config.confirm_hits < 1 || !(config.gate_m > 0.0) ||
      !(config.measurement_sigma_m > 0.0) || config.min_radius_m > config.max_radius_m) {
    return Error::format(Errc::config,
                         "dynamic obstacles: max_tracks >= 1, confirm_hits >= 1, gate_m > 0, measurement_sigma_m > 0 "
                         "and min_radius_m <= max_radius_m needed");
  }
  config_ = config;
  count_ = 0;
  next_id_ = 1;
  return guarded("dynamic obstacles: tracker", [&]() -> Status {
    const std::size_t n = std::max(config.max_tracks, config.max_blobs);
    if (Status s = hungarian_.init(n, resource); !s) return s;
    tracks_ = allocate_array<DolTrack>(resource, config.max_tracks);
    cost_ = allocate_array<double>(resource, config.max_tracks * std::max<std::size_t>(config.max_blobs, 1));
    assignment_ = allocate_array<int>(resource, config.max_tracks);
    blob_used_ = allocate_array<std::uint8_t>(resource, std::max<std::size_t>(config.max_blobs, 1));
    return Status::success();
  });
}

Point2D MoverTracker::predict_position(const DolTrack& track, hal::Nanos stamp_ns) noexcept {
  const double dt = std::max(0.0, seconds_between(track.stamp_ns, stamp_ns));
  return {track.kf.x[0] + track.kf.x[2] * dt, track.kf.x[1] + track.kf.x[3] * dt};
}

DolTrack MoverTracker::predicted(const DolTrack& track, hal::Nanos stamp_ns) const noexcept {
  DolTrack out = track;
  out.kf.predict(seconds_between(track.stamp_ns, stamp_ns), config_.accel_sigma_m_s2, ProcessNoise::piecewise_constant);
  if (stamp_ns > out.stamp_ns) out.stamp_ns = stamp_ns;
  return out;
}

void MoverTracker::follow_axis(DolTrack& track, Point2D z) const noexcept {
  const double forget = std::exp(-geometry::norm(z - track.seen) / std::max(config_.axis_memory_m, 1e-6));
  const Point2D r = z - track.birth;
  track.axis_weight = forget * track.axis_weight + 1.0;
  track.axis_sum = forget * track.axis_sum + r;
  track.axis_squares[0] = forget * track.axis_squares[0] + r.x_m * r.x_m;
  track.axis_squares[1] = forget * track.axis_squares[1] + r.x_m * r.y_m;
  track.axis_squares[2] = forget * track.axis_squares[2] + r.y_m * r.y_m;
}

bool MoverTracker::axis(const DolTrack& track, Axis& out) const noexcept {
  constexpr double kMinWeight = 3.0;   // a line needs a few centroids
  constexpr double kMinElongation = 16.0;  // variance ratio: 4 times as long as wide
  if (track.axis_weight < kMinWeight) return false;
  const Point2D mean{track.axis_sum.x_m / track.axis_weight, track.axis_sum.y_m / track.axis_weight};
  const double cxx = track.axis_squares[0] / track.axis_weight - mean.x_m * mean.x_m;
  const double cxy = track.axis_squares[1] / track.axis_weight - mean.x_m * mean.y_m;
  const double cyy = track.axis_squares[2] / track.axis_weight - mean.y_m * mean.y_m;
  const SymmetricEigen spread = symmetric_eigen(cxx, cxy, cyy);
  const double major = spread.larger;
  const double minor = std::max(0.0, spread.smaller);
  // A uniform spread over a segment of length L has variance L^2 / 12.
  if (!(12.0 * major >= config_.axis_min_travel_m * config_.axis_min_travel_m) || minor * kMinElongation > major) return false;
  out.centre = track.birth + mean;
  out.direction = {std::cos(spread.larger_angle_rad), std::sin(spread.larger_angle_rad)};
  return true;
}

bool MoverTracker::along_axis(const DolTrack& track, Axis& a) const noexcept {
  if (!axis(track, a)) return false;
  const Point2D v = track.kf.velocity();
  const double along = geometry::dot(v, a.direction);
  const double across = std::abs(geometry::cross(a.direction, v));
  return std::atan2(across, std::abs(along)) <= config_.axis_max_angle_rad;  // else turning: the filter's
}

Point2D MoverTracker::velocity(const DolTrack& track) const noexcept {
  const Point2D v = track.kf.velocity();
  Axis a;
  return along_axis(track, a) ? geometry::dot(v, a.direction) * a.direction : v;
}

void MoverTracker::hold_to_axis(DolTrack& track, Hold hold) const noexcept {
  Axis a;
  if (!along_axis(track, a)) return;
  const Point2D u = a.direction;
  double along = geometry::dot(track.kf.velocity(), u);
  if (hold == Hold::measured) {
    // Averaged over some 20 scans: the last, half-seen ones do not rule it.
    constexpr double kSpeedGain = 0.05;
    track.axis_speed_m_s = track.axis_speed_m_s > 0.0 ? track.axis_speed_m_s + kSpeedGain * (std::abs(along) - track.axis_speed_m_s)
                                                      : std::abs(along);
  } else if (hold == Hold::unseen) {
    // Out of sight: on the line, at the speed it kept while seen.
    const Point2D on_line = a.centre + geometry::dot(track.kf.position() - a.centre, u) * u;
    track.kf.x[0] = on_line.x_m;
    track.kf.x[1] = on_line.y_m;
    if (std::abs(along) < track.axis_speed_m_s) along = std::copysign(track.axis_speed_m_s, along);
  }
  track.kf.x[2] = along * u.x_m;
  track.kf.x[3] = along * u.y_m;
}

void MoverTracker::update(std::span<const Blob> blobs, hal::Nanos stamp_ns, const LaserView& view) noexcept {
  const std::size_t blob_count = std::min(blobs.size(), config_.max_blobs);
  last_update_ns_ = std::max(last_update_ns_, stamp_ns);
  for (std::size_t t = 0; t < count_; ++t) {
    DolTrack& track = tracks_[t];
    track.kf.predict(seconds_between(track.stamp_ns, stamp_ns), config_.accel_sigma_m_s2, ProcessNoise::piecewise_constant);
    track.stamp_ns = std::max(track.stamp_ns, stamp_ns);
  }
  std::fill(blob_used_.begin(), blob_used_.end(), std::uint8_t{0});
  std::fill(assignment_.begin(), assignment_.end(), Hungarian::kUnassigned);
  if (count_ > 0 && blob_count > 0) {
    // Out-of-gate pairs share one cost above the gate: they never win over an in-gate pair.
    const double far = 2.0 * config_.gate_m;
    for (std::size_t t = 0; t < count_; ++t) {
      for (std::size_t b = 0; b < blob_count; ++b) {
        const double d = std::hypot(blobs[b].x_m - tracks_[t].kf.x[0], blobs[b].y_m - tracks_[t].kf.x[1]);
        cost_[t * blob_count + b] = std::min(d, far);
      }
    }
    hungarian_.solve(cost_.first(count_ * blob_count), count_, blob_count, assignment_.first(count_));
    for (std::size_t t = 0; t < count_; ++t) {
      const int b = assignment_[t];
      if (b == Hungarian::kUnassigned) continue;
      if (cost_[t * blob_count + static_cast<std::size_t>(b)] > config_.gate_m) {
        assignment_[t] = Hungarian::kUnassigned;
        continue;
      }
      blob_used_[static_cast<std::size_t>(b)] = 1;
    }
  }
  // Corrections, then deaths (compacting in place, order kept).
  std::size_t kept = 0;
  for (std::size_t t = 0; t < count_; ++t) {
    DolTrack& track = tracks_[t];
    const int b = assignment_[t];
    if (b != Hungarian::kUnassigned) {
      const Blob& blob = blobs[static_cast<std::size_t>(b)];
      const Point2D z{blob.x_m, blob.y_m};
      const double dt = seconds_between(track.last_hit_ns, stamp_ns);
      const double s2 = config_.measurement_sigma_m * config_.measurement_sigma_m;
      if (track.hits == 1 && dt > 0.0) {
        // Two-point initialisation: the velocity from the two positions, with its covariance.
        const Point2D v{(z.x_m - track.kf.x[0]) / dt, (z.y_m - track.kf.x[1]) / dt};
        track.kf.reset(z, v, s2, 2.0 * s2 / (dt * dt));
        track.kf.P[0 * 4 + 2] = track.kf.P[2 * 4 + 0] = track.kf.P[1 * 4 + 3] = track.kf.P[3 * 4 + 1] = s2 / dt;
      } else if (!track.kf.correct(z, s2, 0.0, s2)) {
        const double v2 = config_.initial_velocity_sigma_m_s * config_.initial_velocity_sigma_m_s;
        track.kf.reset(z, {}, s2, v2);  // a broken state starts again at the fix
      }
      ++track.hits;
      track.last_hit_ns = stamp_ns;
      track.in_view = true;
      follow_axis(track, z);
      track.seen = z;
      hold_to_axis(track, Hold::measured);
      if (track.hits >= config_.confirm_hits) track.confirmed = true;
      constexpr double kRadiusGain = 0.3;  // blobs flicker with the scan; the size does not
      const double radius = std::clamp(blob.radius_m, config_.min_radius_m, config_.max_radius_m);
      track.radius_m += kRadiusGain * (radius - track.radius_m);
    } else {
      const double dx = track.kf.x[0] - view.x_m;
      const double dy = track.kf.x[1] - view.y_m;
      const double bearing = std::abs(normalize_angle(std::atan2(dy, dx) - view.heading_rad));
      track.in_view = bearing <= view.half_angle_rad && std::hypot(dx, dy) <= view.range_m;
      const double limit = track.in_view ? config_.max_coast_s : config_.max_coast_unseen_s;
      const bool lost = !track.confirmed || seconds_between(track.last_hit_ns, stamp_ns) > limit;
      if (lost) continue;
      // Coasting on along the axis, not off it with a sideways slide.
      hold_to_axis(track, track.in_view ? Hold::coasting : Hold::unseen);
    }
    if (kept != t) tracks_[kept] = track;
    ++kept;
  }
  count_ = kept;
  // Births from the blobs nobody took, while there is room.
  const double s2 = config_.measurement_sigma_m * config_.measurement_sigma_m;
  const double v2 = config_.initial_velocity_sigma_m_s * config_.initial_velocity_sigma_m_s;
  for (std::size_t b = 0; b < blob_count && count_ < tracks_.size(); ++b) {
    if (blob_used_[b] != 0) continue;
    DolTrack& track = tracks_[count_++];
    track = DolTrack{};
    track.id = next_id_++;
    track.hits = 1;
    track.confirmed = config_.confirm_hits <= 1;
    track.stamp_ns = stamp_ns;
    track.last_hit_ns = stamp_ns;
    track.birth = {blobs[b].x_m, blobs[b].y_m};
    track.seen = track.birth;
    track.kf.reset(track.birth, {}, s2, v2);
    track.radius_m = std::clamp(blobs[b].radius_m, config_.min_radius_m, config_.max_radius_m);
  }
}

void MoverTracker::classify(std::span<const std::uint8_t> image, const GridGeometry& geometry) noexcept {
  const auto vacated = [&](const DolTrack& track) {
    const double reach = config_.vacated_radius_m / geometry.resolution_m();
    const int k = static_cast<int>(std::ceil(reach));
    int col = 0;
    int row = 0;
    if (!geometry.world_to_cell(track.birth.x_m, track.birth.y_m, col, row)) return false;  // not in view: unknown
    for (int dr = -k; dr <= k; ++dr) {
      for (int dc = -k; dc <= k; ++dc) {
        if (dc * dc + dr * dr > reach * reach + 1e-9 || !geometry.in_bounds(col + dc, row + dr)) continue;
        if (image[geometry.index(col + dc, row + dr)] != 0) return false;
      }
    }
    return true;
  };
  for (std::size_t t = 0; t < count_; ++t) {
    DolTrack& track = tracks_[t];
    if (!track.confirmed || track.mover || track.last_hit_ns != last_update_ns_) continue;
    if (std::hypot(track.kf.x[2], track.kf.x[3]) < config_.moving_min_speed_m_s) continue;
    // Measured, not filtered: a filter's overshoot is no evidence of travel.
    const double travel = std::hypot(track.seen.x_m - track.birth.x_m, track.seen.y_m - track.birth.y_m);
    track.mover = travel >= config_.moving_far_travel_m || (travel >= config_.moving_min_travel_m && vacated(track));
  }
}

void MoverTracker::turn_back(std::size_t index) noexcept {
  if (index >= count_) return;
  tracks_[index].kf.x[2] = -tracks_[index].kf.x[2];
  tracks_[index].kf.x[3] = -tracks_[index].kf.x[3];
}

std::size_t MoverTracker::vouch(std::span<const Vouch> people) noexcept {
  if (!config_.camera_vouches || people.empty()) return 0;
  const double cos_max = std::cos(config_.vouch_max_angle_rad);
  std::size_t made = 0;
  for (std::size_t t = 0; t < count_; ++t) {
    DolTrack& track = tracks_[t];
    if (track.mover || track.hits < config_.vouch_min_hits || track.last_hit_ns != last_update_ns_ ||
        !track.kf.finite())
      continue;
    const double speed = geometry::norm(track.kf.velocity());
    if (speed < config_.moving_min_speed_m_s) continue;
    for (const Vouch& p : people) {
      const double person_speed = std::hypot(p.vx_m_s, p.vy_m_s);
      if (std::hypot(track.kf.x[0] - p.x_m, track.kf.x[1] - p.y_m) > config_.vouch_reach_m) continue;
      // Their way: the same direction, and a like speed (a box beside a walker has neither).
      if ((track.kf.x[2] * p.vx_m_s + track.kf.x[3] * p.vy_m_s) < cos_max * speed * person_speed) continue;
      if (speed > config_.vouch_speed_ratio * person_speed || person_speed > config_.vouch_speed_ratio * speed) continue;
      track.confirmed = true;
      track.mover = true;
      ++made;
      break;
    }
  }
  return made;
}

bool MoverTracker::moving(const DolTrack& track) const noexcept {
  return track.mover &&
         (!track.in_view || seconds_between(track.last_hit_ns, last_update_ns_) <= config_.publish_max_coast_s);
}

bool MoverTracker::candidate(const DolTrack& track) const noexcept {
  return track.confirmed && !track.mover && track.last_hit_ns == last_update_ns_ &&
         geometry::norm(track.kf.velocity()) >= config_.moving_min_speed_m_s;
}

}  // namespace sen3bot::nav
