#include "sen3bot/nav/people.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "sen3bot/nav/arena.hpp"

namespace sen3bot::nav {

const char* to_string(BoxVerdict verdict) noexcept {
  switch (verdict) {
    case BoxVerdict::located: return "located";
    case BoxVerdict::other_class: return "other_class";
    case BoxVerdict::low_confidence: return "low_confidence";
    case BoxVerdict::out_of_window: return "out_of_window";
    case BoxVerdict::no_returns: return "no_returns";
  }
  return "unknown";
}

// --- Projection ---------------------------------------------------------------------------------

Status CameraProjection::set(const CameraCalibration& c) noexcept {
  const std::array<double, 9>& p = c.phi;
  // Phi^-1 by the adjugate: the calibration's Phi is a rotation only up to its rounding.
  const double det = p[0] * (p[4] * p[8] - p[5] * p[7]) - p[1] * (p[3] * p[8] - p[5] * p[6]) +
                     p[2] * (p[3] * p[7] - p[4] * p[6]);
  if (!(std::abs(det) > 1e-9) || !(c.k[0] > 0.0) || !(c.k[4] > 0.0) || c.width_px <= 0 || c.height_px <= 0) {
    return Error::format(Errc::config, "camera calibration: Phi must be invertible, K's focal lengths positive and the "
                                       "image not empty");
  }
  const std::array<double, 9> inv = {
      (p[4] * p[8] - p[5] * p[7]) / det, (p[2] * p[7] - p[1] * p[8]) / det, (p[1] * p[5] - p[2] * p[4]) / det,
      (p[5] * p[6] - p[3] * p[8]) / det, (p[0] * p[8] - p[2] * p[6]) / det, (p[2] * p[3] - p[0] * p[5]) / det,
      (p[3] * p[7] - p[4] * p[6]) / det, (p[1] * p[6] - p[0] * p[7]) / det, (p[0] * p[4] - p[1] * p[3]) / det};
  for (int r = 0; r < 3; ++r) {
    for (int col = 0; col < 3; ++col) {
      double sum = 0.0;
      for (int j = 0; j < 3; ++j) sum += c.k[static_cast<std::size_t>(3 * r + j)] * inv[static_cast<std::size_t>(3 * j + col)];
      m_[static_cast<std::size_t>(3 * r + col)] = sum;
    }
    double sum = 0.0;
    for (int j = 0; j < 3; ++j) sum += c.k[static_cast<std::size_t>(3 * r + j)] * c.delta[static_cast<std::size_t>(j)];
    t_[static_cast<std::size_t>(r)] = sum;
  }
  fx_ = c.k[0];
  width_ = c.width_px;
  height_ = c.height_px;
  return Status::success();
}

bool CameraProjection::project_point(double forward_m, double left_m, double up_m, double& u_px,
                                     double& v_px) const noexcept {
  // L = (-left, -up, forward) in the camera's axes at the laser (y down).
  const double lx = -left_m;
  const double ly = -up_m;
  const double lz = forward_m;
  // K's last row is (0, 0, 1): c_z is the point's depth in the camera frame.
  const double cz = m_[6] * lx + m_[7] * ly + m_[8] * lz - t_[2];
  if (!(cz > 0.05)) return false;
  u_px = (m_[0] * lx + m_[1] * ly + m_[2] * lz - t_[0]) / cz;
  v_px = (m_[3] * lx + m_[4] * ly + m_[5] * lz - t_[1]) / cz;
  return true;
}

bool CameraProjection::project(double forward_m, double left_m, double& u_px, double& v_px) const noexcept {
  return project_point(forward_m, left_m, 0.0, u_px, v_px) && u_px >= 0.0 && v_px >= 0.0 && u_px < width_ &&
         v_px < height_;
}

// --- Fusion ---------------------------------------------------------------------------------------

Status PeopleFusion::init(const FusionConfig& config, const CameraCalibration& calibration, const OccupancyMap* map,
                          std::size_t max_beams, std::pmr::memory_resource& resource) {
  if (!(config.match_window_s >= 0.0) || !(config.depth_band_m > 0.0) || config.min_points < 1 || max_beams == 0 ||
      !(config.max_body_radius_m >= 0.0) || !(config.background_m >= 0.0 && config.background_m <= 1.0) ||
      !(config.segment_jump_m >= 0.0)) {
    return Error::format(Errc::config, "people fusion: match_window_s >= 0, depth_band_m > 0, min_points >= 1, "
                                       "max_body_radius_m >= 0, segment_jump_m >= 0, 0 <= background_m <= 1 and "
                                       "room for a scan");
  }
  if (Status s = projection_.set(calibration); !s) return s;
  config_ = config;
  map_ = map;
  background_cells_ =
      map != nullptr ? std::max(1, static_cast<int>(std::ceil(config.background_m / map->resolution_m() - 1e-9))) : 1;
  return guarded("people fusion", [&]() -> Status {
    u_ = allocate_array<float>(resource, max_beams);
    v_ = allocate_array<float>(resource, max_beams);
    x_ = allocate_array<double>(resource, max_beams);
    y_ = allocate_array<double>(resource, max_beams);
    return Status::success();
  });
}

bool PeopleFusion::background(double x_m, double y_m) const noexcept {
  if (map_ == nullptr) return false;
  int col = 0;
  int row = 0;
  if (!map_->world_to_cell(x_m, y_m, col, row)) return false;
  const int reach = background_cells_;
  for (int dr = -reach; dr <= reach; ++dr)
    for (int dc = -reach; dc <= reach; ++dc) {
      if (dr * dr + dc * dc > reach * reach) continue;
      const int c = col + dc;
      const int r = row + dr;
      if (c >= 0 && r >= 0 && c < map_->width() && r < map_->height() && map_->at(c, r) >= config_.occupied_threshold)
        return true;
    }
  return false;
}

std::size_t PeopleFusion::fuse(const msg::ScanView& scan, const Pose2D& laser_pose, const msg::PersonDetections& frame,
                               std::span<PersonFix> out) noexcept {
  const std::size_t beams = std::min(scan.ranges_m.size(), u_.size());
  // Every usable return's pixel, once per scan (NaN: none).
  for (std::size_t i = 0; i < beams; ++i) {
    u_[i] = v_[i] = std::numeric_limits<float>::quiet_NaN();
    const float r = scan.ranges_m[i];
    if (!(r > scan.range_min_m) || !(r < scan.range_max_m)) continue;
    const double a = scan.angle_min_rad + static_cast<double>(i) * scan.increment_rad;
    double u = 0.0;
    double v = 0.0;
    if (projection_.project(r * std::cos(a), r * std::sin(a), u, v)) {
      u_[i] = static_cast<float>(u);
      v_[i] = static_cast<float>(v);
    }
  }
  locate(scan, laser_pose, beams);
  const bool in_window =
      std::abs(static_cast<double>(frame.capture_ns - scan.stamp_ns)) <= config_.match_window_s * 1e9;
  std::size_t written = 0;
  const std::size_t boxes = std::min<std::size_t>(frame.count, msg::PersonDetections::kMax);
  for (std::size_t b = 0; b < boxes; ++b) {
    const msg::PersonBox& box = frame.boxes[b];
    BoxVerdict verdict = BoxVerdict::located;
    if (box.class_id != config_.person_class) verdict = BoxVerdict::other_class;
    else if (!(box.confidence >= config_.min_confidence)) verdict = BoxVerdict::low_confidence;
    else if (!in_window) verdict = BoxVerdict::out_of_window;
    PersonFix fix;
    if (verdict == BoxVerdict::located) {
      const auto in_box = [&](std::size_t i) {
        return u_[i] >= box.u0 && u_[i] <= box.u1 && v_[i] >= box.v0 && v_[i] <= box.v1;
      };
      if (!place(scan, laser_pose, beams, in_box, fix)) {
        verdict = BoxVerdict::no_returns;
      } else {
        fix.width_m = (box.u1 - box.u0) * fix.range_m / projection_.focal_x_px();
        fix.box = static_cast<std::uint8_t>(b);
      }
    }
    ++counts_[static_cast<std::size_t>(verdict)];
    if (verdict == BoxVerdict::located && written < out.size()) out[written++] = fix;
  }
  return written;
}

void PeopleFusion::locate(const msg::ScanView& scan, const Pose2D& laser_pose, std::size_t beams) noexcept {
  const double c = std::cos(laser_pose.theta_rad);
  const double s = std::sin(laser_pose.theta_rad);
  for (std::size_t i = 0; i < beams; ++i) {
    x_[i] = y_[i] = std::numeric_limits<double>::quiet_NaN();
    const double r = scan.ranges_m[i];
    if (!(r > scan.range_min_m) || !(r < scan.range_max_m)) continue;
    const double a = scan.angle_min_rad + static_cast<double>(i) * scan.increment_rad;
    const double x = laser_pose.x_m + c * r * std::cos(a) - s * r * std::sin(a);
    const double y = laser_pose.y_m + s * r * std::cos(a) + c * r * std::sin(a);
    if (background(x, y)) continue;
    x_[i] = x;
    y_[i] = y;
  }
}

template <typename Region>
bool PeopleFusion::place(const msg::ScanView& scan, const Pose2D& laser_pose, std::size_t beams, const Region& region,
                         PersonFix& fix) const noexcept {
  // The nearest located return in the region, then those within the depth band behind it,
  // and the unbroken run of returns around the nearest (the body where a box taken at another
  // moment than the scan, or drawn tight, cuts it).
  double nearest = std::numeric_limits<double>::infinity();
  std::size_t at = beams;
  for (std::size_t i = 0; i < beams; ++i)
    if (scan.ranges_m[i] < nearest && !std::isnan(x_[i]) && region(i)) {
      nearest = scan.ranges_m[i];
      at = i;
    }
  if (!std::isfinite(nearest)) return false;
  const double far = nearest + config_.depth_band_m;
  // A run stops where a body would end (a person against an unmapped cart or wall is not
  // taken for the whole of it).
  const double reach = 2.0 * config_.max_body_radius_m;
  const auto joins = [&](std::size_t i, std::size_t j) {
    return !std::isnan(x_[j]) && scan.ranges_m[j] <= far &&
           std::abs(scan.ranges_m[j] - scan.ranges_m[i]) <= config_.segment_jump_m &&
           std::hypot(x_[j] - x_[at], y_[j] - y_[at]) <= reach;
  };
  std::size_t run_lo = at;
  std::size_t run_hi = at;
  while (run_lo > 0 && joins(run_lo, run_lo - 1)) --run_lo;
  while (run_hi + 1 < beams && joins(run_hi, run_hi + 1)) ++run_hi;
  // Cut short: the scan ends there, or the next return is nearer by more than a step (it hides
  // the rest of the body).
  const auto hidden_past = [&](std::size_t edge, std::size_t next) {
    return scan.ranges_m[next] < scan.ranges_m[edge] - config_.segment_jump_m;
  };
  const bool partial = run_lo == 0 || run_hi + 1 >= beams || hidden_past(run_lo, run_lo - 1) ||
                       hidden_past(run_hi, run_hi + 1);
  double sx = 0.0;
  double sy = 0.0;
  std::size_t lo = beams;
  std::size_t hi = 0;
  std::size_t n = 0;
  for (std::size_t i = 0; i < beams; ++i) {
    const bool in_run = i >= run_lo && i <= run_hi;
    if (!in_run && (!(scan.ranges_m[i] <= far) || std::isnan(x_[i]) || !region(i))) continue;
    sx += x_[i];
    sy += y_[i];
    lo = std::min(lo, i);
    hi = std::max(hi, i);
    ++n;
  }
  if (n < config_.min_points) return false;
  // The returns lie on the body's near side. For a round body of radius w (the returns' half
  // width, each edge beam counting half a step) their mean is w (1 - pi/4) behind the nearest
  // point, so the centre is pi/4 w behind the mean, along the ray.
  const double mx = sx / static_cast<double>(n);
  const double my = sy / static_cast<double>(n);
  const double mean_range = std::hypot(mx - laser_pose.x_m, my - laser_pose.y_m);
  const double half_angle = std::min(0.5 * static_cast<double>(hi - lo + 1) * std::abs(scan.increment_rad), 1.0);
  const double w = std::min(mean_range * std::sin(half_angle), config_.max_body_radius_m);
  const double back = mean_range > 1e-6 ? std::numbers::pi / 4.0 * w / mean_range : 0.0;
  fix.x_m = mx + (mx - laser_pose.x_m) * back;
  fix.y_m = my + (my - laser_pose.y_m) * back;
  fix.range_m = mean_range * (1.0 + back);
  fix.ray_x = mean_range > 1e-6 ? (mx - laser_pose.x_m) / mean_range : 0.0;
  fix.ray_y = mean_range > 1e-6 ? (my - laser_pose.y_m) / mean_range : 0.0;
  fix.partial = partial;
  fix.points = static_cast<std::uint16_t>(std::min<std::size_t>(n, 0xffff));
  return true;
}

std::size_t PeopleFusion::follow(const msg::ScanView& scan, const Pose2D& laser_pose, std::span<const Point2D> predicted,
                                 double gate_m, std::span<PersonFix> out) noexcept {
  const std::size_t beams = std::min(scan.ranges_m.size(), x_.size());
  locate(scan, laser_pose, beams);
  std::size_t found = 0;
  for (std::size_t t = 0; t < std::min(predicted.size(), out.size()); ++t) {
    const Point2D p = predicted[t];
    const auto near = [&](std::size_t i) { return std::hypot(x_[i] - p.x_m, y_[i] - p.y_m) <= gate_m; };
    out[t] = PersonFix{};
    if (place(scan, laser_pose, beams, near, out[t])) ++found;
    else out[t].points = 0;
  }
  return found;
}

// --- Tracking ------------------------------------------------------------------------------------

namespace {
std::array<double, 16> start_covariance(const PersonTrackerConfig& c) noexcept {
  CvFilter f;
  f.reset({}, {}, c.fix_sigma_m * c.fix_sigma_m, c.start_speed_sigma_m_s * c.start_speed_sigma_m_s);
  return f.P;
}
}  // namespace

Status PersonTracker::init(const PersonTrackerConfig& config, std::pmr::memory_resource& resource) {
  if (config.max_tracks == 0 || config.max_tracks > msg::People::kMax || !(config.gate_m > 0.0) ||
      !(config.expire_s > 0.0) || !(config.dynamic_after_m >= 0.0) || !(config.safety_radius_m >= 0.0) ||
      !(config.min_width_m >= 0.0) || !(config.fix_sigma_m > 0.0) || !(config.partial_sigma_m > 0.0) ||
      !(config.accel_sigma_m_s2 > 0.0) || !(config.start_speed_sigma_m_s > 0.0) || !(config.max_speed_m_s > 0.0) ||
      config.confirm_hits < 1 || !(config.laser_follow_s >= 0.0) || !(config.follow_gate_m > 0.0) ||
      !(config.coast_s >= 0.0)) {
    return Error::format(Errc::config, "person tracker: 1 <= max_tracks <= %zu, gate_m, expire_s, max_speed_m_s, "
                                       "follow_gate_m, fix_sigma_m, partial_sigma_m, accel_sigma_m_s2, "
                                       "start_speed_sigma_m_s > 0, confirm_hits >= 1, "
                                       "laser_follow_s, coast_s, dynamic_after_m, safety_radius_m, min_width_m >= 0",
                         msg::People::kMax);
  }
  if (!(config.hidden_max_s > 0.0) || !(config.hidden_max_sigma_m > 0.0) || !(config.hidden_cage_growth_m >= 0.0) ||
      !(config.hidden_wander_m2_s >= 0.0) || !(config.sonar_half_angle_rad > 0.0) ||
      !(config.sonar_half_angle_rad < std::numbers::pi / 2.0) || !(config.sonar_max_age_s > 0.0) ||
      !(config.sonar_window_m >= 0.0)) {
    return Error(Errc::config, "person tracker: hidden_max_s, hidden_max_sigma_m, sonar_max_age_s > 0, "
                               "hidden_cage_growth_m, hidden_wander_m2_s, sonar_window_m >= 0, "
                               "0 < sonar_half_angle_rad < pi/2");
  }
  config_ = config;
  const std::size_t n = std::max(config.max_tracks, msg::PersonDetections::kMax);
  if (Status s = hungarian_.init(n, resource); !s) return s;
  return guarded("person tracker", [&]() -> Status {
    tracks_ = allocate_array<Track>(resource, config.max_tracks);
    cost_ = allocate_array<double>(resource, n * n);
    assignment_ = allocate_array<int>(resource, n);
    fix_used_ = allocate_array<std::uint8_t>(resource, n);
    return Status::success();
  });
}

void PersonTracker::update(std::span<const PersonFix> fixes, hal::Nanos stamp_ns) noexcept {
  const std::size_t fix_count = std::min(fixes.size(), fix_used_.size());
  std::fill(fix_used_.begin(), fix_used_.end(), std::uint8_t{0});
  std::fill(assignment_.begin(), assignment_.end(), Hungarian::kUnassigned);
  // Predicted positions, matched to the fixes; an out-of-gate pair never wins over an in-gate one.
  const auto predicted = [&](const Track& t) { return predict(t, stamp_ns); };
  if (count_ > 0 && fix_count > 0) {
    const double far = 2.0 * config_.gate_m;
    for (std::size_t t = 0; t < count_; ++t) {
      const Point2D p = predicted(tracks_[t]);
      for (std::size_t f = 0; f < fix_count; ++f)
        cost_[t * fix_count + f] = std::min(std::hypot(fixes[f].x_m - p.x_m, fixes[f].y_m - p.y_m), far);
    }
    hungarian_.solve(cost_.first(count_ * fix_count), count_, fix_count, assignment_.first(count_));
  }
  for (std::size_t t = 0; t < count_; ++t) {
    const int f = assignment_[t];
    if (f == Hungarian::kUnassigned || cost_[t * fix_count + static_cast<std::size_t>(f)] > config_.gate_m) continue;
    const PersonFix& fix = fixes[static_cast<std::size_t>(f)];
    fix_used_[static_cast<std::size_t>(f)] = 1;
    Track& track = tracks_[t];
    // A frame older than the laser's last fix (the camera's latency) confirms, but does not
    // move the track back.
    if (stamp_ns > track.last_seen_ns) correct(track, fix, stamp_ns);
    track.width_m = fix.width_m;
    track.camera_seen_ns = std::max(track.camera_seen_ns, stamp_ns);
    ++track.hits;
  }
  // Stale tracks end here only when nothing may keep them (unconfirmed, or keeping hidden people
  // off); a confirmed one is for expire() to judge against what the sensors see.
  std::size_t kept = 0;
  for (std::size_t t = 0; t < count_; ++t) {
    const Track& track = tracks_[t];
    if (static_cast<double>(stamp_ns - track.last_seen_ns) > config_.expire_s * 1e9 &&
        (track.hits < config_.confirm_hits || !config_.keep_hidden))
      continue;
    if (kept != t) tracks_[kept] = track;
    ++kept;
  }
  count_ = kept;
  for (std::size_t f = 0; f < fix_count; ++f) {
    if (fix_used_[f] != 0) continue;
    // Two boxes on one body (a detector's double or stray box): a second person cannot stand
    // this close to a tracked one.
    bool same_body = false;
    for (std::size_t t = 0; t < count_ && !same_body; ++t) {
      const Point2D p = predicted(tracks_[t]);
      same_body = std::hypot(fixes[f].x_m - p.x_m, fixes[f].y_m - p.y_m) < config_.min_separation_m;
    }
    if (same_body) {
      ++duplicates_;
      continue;
    }
    std::size_t slot = count_;
    if (slot == tracks_.size()) {
      // Full: a person seen takes the place of the one hidden longest (a guess).
      for (std::size_t t = 0; t < count_; ++t)
        if (tracks_[t].hidden && (slot == count_ || tracks_[t].last_seen_ns < tracks_[slot].last_seen_ns)) slot = t;
      if (slot == count_) break;
      ++forgotten_;
    } else {
      ++count_;
    }
    Track& track = tracks_[slot];
    track = Track{};
    track.id = next_id_++;
    track.at = track.first_seen = {fixes[f].x_m, fixes[f].y_m};
    track.covariance = start_covariance(config_);
    track.width_m = fixes[f].width_m;
    track.points = fixes[f].points;
    track.last_seen_ns = track.camera_seen_ns = stamp_ns;
    track.hits = 1;
  }
}

bool PersonTracker::walking(const Track& track) const noexcept {
  return track.state == msg::PersonState::dynamic_person ||
         std::hypot(track.velocity.x_m, track.velocity.y_m) >= config_.walking_speed_m_s;
}

Point2D PersonTracker::predict(const Track& track, hal::Nanos stamp_ns) const noexcept {
  if (!walking(track)) return track.at;
  const double dt = std::clamp(static_cast<double>(stamp_ns - track.last_seen_ns) * 1e-9, 0.0, config_.coast_s);
  return {track.at.x_m + track.velocity.x_m * dt, track.at.y_m + track.velocity.y_m * dt};
}


void PersonTracker::correct(Track& track, const PersonFix& fix, hal::Nanos stamp_ns) noexcept {
  // Kalman: predict the state to the fix, then weigh the fix by its error, anisotropic when the
  // body is cut (the velocity is kept for a standing person too: it shows them setting off).
  const double dt = std::max(0.0, static_cast<double>(stamp_ns - track.last_seen_ns) * 1e-9);
  CvFilter f{{track.at.x_m, track.at.y_m, track.velocity.x_m, track.velocity.y_m}, track.covariance};
  f.predict(dt, config_.accel_sigma_m_s2, ProcessNoise::continuous);
  // The fix's covariance: fix_sigma along the ray, and across it unless partial.
  const double along2 = config_.fix_sigma_m * config_.fix_sigma_m;
  const double across = fix.partial ? std::max(config_.partial_sigma_m, config_.fix_sigma_m) : config_.fix_sigma_m;
  const double across2 = across * across;
  const double ray_norm = std::hypot(fix.ray_x, fix.ray_y);
  const double ux = ray_norm > 1e-9 ? fix.ray_x / ray_norm : 1.0;
  const double uy = ray_norm > 1e-9 ? fix.ray_y / ray_norm : 0.0;
  const double r00 = along2 * ux * ux + across2 * uy * uy;
  const double r01 = (along2 - across2) * ux * uy;
  const double r11 = along2 * uy * uy + across2 * ux * ux;
  if (f.correct({fix.x_m, fix.y_m}, r00, r01, r11)) {
    track.at = f.position();
    track.velocity = f.velocity();
    track.covariance = f.P;
  } else {
    track.covariance = start_covariance(config_);
    track.at = {fix.x_m, fix.y_m};
    track.velocity = {};
  }
  const double speed = std::hypot(track.velocity.x_m, track.velocity.y_m);
  if (speed > config_.max_speed_m_s) {
    track.velocity.x_m *= config_.max_speed_m_s / speed;
    track.velocity.y_m *= config_.max_speed_m_s / speed;
  }
  track.points = fix.points;
  track.last_seen_ns = stamp_ns;
  track.hidden = false;
  // Dynamic once its centre has moved farther than the threshold from where it was first seen.
  if (std::hypot(track.at.x_m - track.first_seen.x_m, track.at.y_m - track.first_seen.y_m) > config_.dynamic_after_m)
    track.state = msg::PersonState::dynamic_person;
}

std::size_t PersonTracker::followable(hal::Nanos stamp_ns, std::span<Point2D> out,
                                      std::span<std::uint8_t> which) const noexcept {
  std::size_t n = 0;
  for (std::size_t t = 0; t < count_ && n < std::min(out.size(), which.size()); ++t) {
    const Track& track = tracks_[t];
    if (track.hits < config_.confirm_hits || stamp_ns <= track.last_seen_ns ||
        static_cast<double>(stamp_ns - track.camera_seen_ns) > config_.laser_follow_s * 1e9)
      continue;
    out[n] = predict(track, stamp_ns);
    which[n++] = static_cast<std::uint8_t>(t);
  }
  return n;
}

void PersonTracker::follow(std::size_t index, const PersonFix& fix, hal::Nanos stamp_ns) noexcept {
  if (index >= count_ || stamp_ns <= tracks_[index].last_seen_ns) return;
  correct(tracks_[index], fix, stamp_ns);
}

double PersonTracker::position_sigma(const Track& track, hal::Nanos stamp_ns) const noexcept {
  // A walker coasting on their velocity: the Kalman prediction's growth. Then held (or standing
  // all along): a person out of sight may have wandered anywhere near, by hidden_wander_m2_s.
  const double age_s = std::max(0.0, static_cast<double>(stamp_ns - track.last_seen_ns) * 1e-9);
  const double coasted_s = walking(track) ? std::min(age_s, config_.coast_s) : 0.0;
  CvFilter f;
  f.P = track.covariance;
  f.predict(coasted_s, config_.accel_sigma_m_s2, ProcessNoise::continuous);
  const std::array<double, 16>& p = f.P;
  const double wander = config_.hidden_wander_m2_s * (age_s - coasted_s);
  const double a = p[0] + wander;
  const double c = p[5] + wander;
  const double b = p[1];
  // The larger eigenvalue of the position block: the ellipse's long axis.
  return std::sqrt(std::max(0.0, 0.5 * (a + c) + std::sqrt(0.25 * (a - c) * (a - c) + b * b)));
}

namespace {
// Whether the scan looked past a body of radius body_m at `at` by margin_m: every beam across
// the body reads farther than the body's centre plus the margin (a reading at range_max saw
// nothing that near). Partly or wholly outside the scan's field, an unreadable beam, a nearer
// return on one of those bearings (a rack, another person) or a place beyond the laser's reach:
// not seen.
bool sees_past(const msg::ScanView& scan, const Pose2D& laser, Point2D at, double body_m, double margin_m) noexcept {
  const double dx = at.x_m - laser.x_m;
  const double dy = at.y_m - laser.y_m;
  const double distance = std::hypot(dx, dy);
  if (!(distance > body_m) || scan.ranges_m.empty() || !(scan.increment_rad > 0.0f)) return false;
  const double bearing = normalize_angle(std::atan2(dy, dx) - laser.theta_rad);
  const double half = std::asin(body_m / distance);
  const double lo = (bearing - half - scan.angle_min_rad) / scan.increment_rad;
  const double hi = (bearing + half - scan.angle_min_rad) / scan.increment_rad;
  const double last_beam = static_cast<double>(scan.ranges_m.size() - 1);
  if (lo < 0.0 || hi > last_beam) return false;
  // The beams across the body, or the nearest one where the body is narrower than a beam's step.
  std::size_t first = static_cast<std::size_t>(std::ceil(lo));
  std::size_t last = static_cast<std::size_t>(std::floor(hi));
  if (first > last) first = last = static_cast<std::size_t>(std::lround(0.5 * (lo + hi)));
  for (std::size_t i = first; i <= last; ++i) {
    const double r = scan.ranges_m[i];
    if (!(r > scan.range_min_m)) return false;  // unreadable (NaN) or too near to tell
    const double reach = std::min(r, static_cast<double>(scan.range_max_m));
    if (!(reach > distance + margin_m)) return false;
  }
  return true;
}
}  // namespace

bool PersonTracker::keep_hidden(Track& track, hal::Nanos now_ns, const SensorCoverage& coverage) noexcept {
  if (!track.hidden) {
    track.hidden = true;
    track.hidden_since_ns = now_ns;
  }
  const Point2D at = predict(track, now_ns);
  const double sigma = position_sigma(track, now_ns);
  const double body = std::max(track.width_m, config_.min_width_m) / 2.0;
  // Seen empty means seen past the body and its uncertainty along the line of sight; only
  // readings taken after the last fix count (an older one saw the place before they came).
  const double margin = body + sigma;
  bool empty = coverage.scan != nullptr && coverage.scan->stamp_ns > track.last_seen_ns &&
               sees_past(*coverage.scan, coverage.laser_pose, at, body, margin);
  bool echo = false;
  if (coverage.sonar != nullptr) {
    const msg::Sonar& sonar = *coverage.sonar;
    for (std::size_t d = 0; d < std::min<std::size_t>(sonar.count, msg::Sonar::kMax); ++d) {
      const hal::Nanos stamp = sonar.stamp_ns[d];
      const double range = sonar.range_m[d];
      if (stamp < 0 || stamp <= track.last_seen_ns ||
          static_cast<double>(now_ns - stamp) > config_.sonar_max_age_s * 1e9 || !(range >= 0.0))
        continue;
      const Pose2D disc = apply_motion(coverage.robot_pose, sonar.mount[d]);
      const double distance = std::hypot(at.x_m - disc.x_m, at.y_m - disc.y_m);
      if (!(distance > body)) continue;
      const double off =
          std::abs(normalize_angle(std::atan2(at.y_m - disc.y_m, at.x_m - disc.x_m) - disc.theta_rad));
      const bool returned = range < sonar.max_range_m;
      // The cone's axis region holds the place and it heard nothing until past it.
      if (off <= config_.sonar_half_angle_rad && std::min(range, sonar.max_range_m) > distance + margin) empty = true;
      // An echo from about the body's near side, with any of the body in the cone: weak
      // evidence that they are still there (an echo says nothing of where across the cone).
      if (returned && off <= config_.sonar_half_angle_rad + std::asin(body / distance) &&
          std::abs(range - (distance - body)) <= config_.sonar_window_m)
        echo = true;
    }
  }
  // An echo from the place outweighs a look past it: sonar misses what glances off it, and a
  // wrongly kept guess only costs room, a wrongly dropped person a cage.
  if (echo) {
    track.hidden_since_ns = now_ns;
  } else if (empty) {
    ++seen_empty_;
    return false;
  }
  if (sigma > config_.hidden_max_sigma_m ||
      static_cast<double>(now_ns - track.hidden_since_ns) > config_.hidden_max_s * 1e9) {
    ++forgotten_;
    return false;
  }
  return true;
}

void PersonTracker::expire(hal::Nanos now_ns, const SensorCoverage& coverage) noexcept {
  const bool sensed = coverage.scan != nullptr || coverage.sonar != nullptr;
  std::size_t kept = 0;
  for (std::size_t t = 0; t < count_; ++t) {
    Track& track = tracks_[t];
    bool keep = static_cast<double>(now_ns - track.last_seen_ns) <= config_.expire_s * 1e9;
    if (!keep && config_.keep_hidden && sensed && track.hits >= config_.confirm_hits) {
      keep = keep_hidden(track, now_ns, coverage);
    } else if (!keep && track.hidden) {
      ++forgotten_;  // nothing to tell hidden from gone any more
    }
    if (!keep) continue;
    if (kept != t) tracks_[kept] = track;
    ++kept;
  }
  count_ = kept;
}

double cage_radius(const PersonTrackerConfig& config, double width_m, double safety_radius_m, bool hidden,
                   double position_sigma_m) noexcept {
  const double growth = hidden ? std::clamp(position_sigma_m, 0.0, config.hidden_cage_growth_m) : 0.0;
  return std::max(width_m, config.min_width_m) / 2.0 + safety_radius_m + growth;
}

void PersonTracker::publish(hal::Nanos now_ns, msg::People& out) const noexcept {
  out.count = 0;
  out.stamp_ns = now_ns;
  for (std::size_t t = 0; t < count_ && out.count < msg::People::kMax; ++t) {
    const Track& track = tracks_[t];
    if (track.hits < config_.confirm_hits) continue;
    msg::TrackedPerson& p = out.items[out.count++];
    p.id = track.id;
    const Point2D at = predict(track, now_ns);
    p.x_m = at.x_m;
    p.y_m = at.y_m;
    // A standing person's cage stays where they stand (their velocity is the fixes' noise); a
    // hidden walker's is held after coast_s, and so has no velocity.
    const bool held = track.hidden && static_cast<double>(now_ns - track.last_seen_ns) > config_.coast_s * 1e9;
    const bool moving = walking(track) && !held;
    p.vx_m_s = moving ? track.velocity.x_m : 0.0;
    p.vy_m_s = moving ? track.velocity.y_m : 0.0;
    p.width_m = track.width_m;
    p.position_sigma_m = position_sigma(track, now_ns);
    p.hidden = track.hidden;
    p.cage_radius_m = cage_radius(config_, track.width_m, config_.safety_radius_m, track.hidden, p.position_sigma_m);
    p.state = track.state;
    p.last_seen_ns = track.last_seen_ns;
    p.points = track.points;
  }
}

// --- The cages ----------------------------------------------------------------------------------

Status PeopleLayer::init(const Costmap2D& master, std::pmr::memory_resource& resource) {
  (void)master;
  (void)resource;
  if (!(config_.expire_s > 0.0) || !(config_.max_radius_m > 0.0) || !(config_.robot_clearance_m >= 0.0))
    return Error::format(Errc::config,
                         "people layer: expire_s and max_radius_m must be positive, robot_clearance_m at least 0");
  return Status::success();
}

void PeopleLayer::update(Costmap2D& master, const CostmapInputs& inputs) noexcept {
  cages_ = 0;
  const GridGeometry& grid = master.geometry();
  const double res = grid.resolution_m();
  const std::size_t count = std::min<std::size_t>(people_.count, msg::People::kMax);
  for (std::size_t i = 0; i < count; ++i) {
    const msg::TrackedPerson& p = people_.items[i];
    // A hidden person is kept by the tracker past expire_s; their list must still be current.
    const double age_s = static_cast<double>(inputs.now_ns - (p.hidden ? people_.stamp_ns : p.last_seen_ns)) * 1e-9;
    if (age_s > config_.expire_s) continue;
    const double dt = config_.predict ? std::max(0.0, static_cast<double>(inputs.now_ns - people_.stamp_ns) * 1e-9) : 0.0;
    const double x = p.x_m + p.vx_m_s * dt;
    const double y = p.y_m + p.vy_m_s * dt;
    const double to_robot = std::hypot(x - inputs.robot_pose.x_m, y - inputs.robot_pose.y_m);
    const double r = std::min({p.cage_radius_m, config_.max_radius_m, to_robot - config_.robot_clearance_m});
    if (!(r > 0.0) || !std::isfinite(x) || !std::isfinite(y)) continue;
    // The disc's cells: centres within r of the centre, in the grid's own (possibly rotated) frame.
    double gx = 0.0;
    double gy = 0.0;
    grid.world_to_grid(x, y, gx, gy);
    const double rc = r / res;
    if (gx + rc < 0.0 || gy + rc < 0.0 || gx - rc > master.width() || gy - rc > master.height()) continue;
    const int c0 = static_cast<int>(std::floor(gx - rc));
    const int c1 = static_cast<int>(std::ceil(gx + rc));
    const int r0 = static_cast<int>(std::floor(gy - rc));
    const int r1 = static_cast<int>(std::ceil(gy + rc));
    bool painted = false;
    for (int row = std::max(r0, 0); row <= std::min(r1, master.height() - 1); ++row)
      for (int col = std::max(c0, 0); col <= std::min(c1, master.width() - 1); ++col) {
        const double dx = col + 0.5 - gx;
        const double dy = row + 0.5 - gy;
        if (dx * dx + dy * dy > rc * rc) continue;
        master.set(col, row, kLethalCost);
        painted = true;
      }
    cages_ += painted ? 1 : 0;
  }
}

}  // namespace sen3bot::nav
