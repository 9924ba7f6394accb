#include "sen3bot/nav/safety.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <span>

#include "sen3bot/msg/point_math.hpp"

namespace sen3bot::nav {

SafetyFilter::SafetyFilter(const SafetyConfig& config) noexcept : config_(config) {
  const Footprint& fp = config.footprint;
  if (fp.vertex_count == 0) {
    front_m_ = fp.circle_radius_m;
    rear_m_ = -fp.circle_radius_m;
    half_width_m_ = fp.circle_radius_m;
  } else {
    for (std::size_t i = 0; i < fp.vertex_count; ++i) {
      front_m_ = std::max(front_m_, fp.vertices[i].x_m);
      rear_m_ = std::min(rear_m_, fp.vertices[i].x_m);
      half_width_m_ = std::max(half_width_m_, std::abs(fp.vertices[i].y_m));
    }
  }
  turn_radius_m_ = fp.circumscribed_radius_m() + config.lateral_margin_m;
}

namespace {
// A published mover or person (map frame, stamped) predicted to now, position and velocity in
// the robot's body frame.
struct BodyMover {
  double x_m, y_m, vx_m_s, vy_m_s;
};
template <typename Tracked>
BodyMover in_body(const SafetyInputs& in, const Tracked& m, hal::Nanos stamp_ns) noexcept {
  const double c = std::cos(in.pose.theta_rad);
  const double s = std::sin(in.pose.theta_rad);
  const double age_s = std::max(0.0, static_cast<double>(in.now_ns - stamp_ns) * 1e-9);
  const double dx = m.x_m + m.vx_m_s * age_s - in.pose.x_m;
  const double dy = m.y_m + m.vy_m_s * age_s - in.pose.y_m;
  return {c * dx + s * dy, -s * dx + c * dy, c * m.vx_m_s + s * m.vy_m_s, -s * m.vx_m_s + c * m.vy_m_s};
}
BodyMover in_body(const SafetyInputs& in, const msg::MovingObstacle& m) noexcept {
  return in_body(in, m, in.movers->stamp_ns);
}
// Distance from q (body frame) to the footprint, 0 inside it.
double footprint_distance(const Footprint& fp, double qx, double qy) noexcept {
  if (fp.vertex_count == 0) return std::max(0.0, std::hypot(qx, qy) - fp.circle_radius_m);
  const std::span<const Point2D> outline(fp.vertices.data(), fp.vertex_count);
  const Point2D q{qx, qy};
  return msg::inside_polygon(outline, q) ? 0.0 : msg::polygon_edge_distance(outline, q);
}

// The gap between the body, at pose (x, y, heading) in the body frame of now, and a mover's
// disc at (mx, my).
double gap_at(const Footprint& fp, double x, double y, double heading, double mx, double my, double radius) noexcept {
  const double c = std::cos(heading);
  const double s = std::sin(heading);
  const double dx = mx - x;
  const double dy = my - y;
  return footprint_distance(fp, c * dx + s * dy, -s * dx + c * dy) - radius;
}
}  // namespace

SafetyFilter::Gaps SafetyFilter::gaps(const SafetyInputs& in, double v, double w, double x, double y, double vx,
                                      double vy, double radius, double horizon_s, bool then_stop) const noexcept {
  const double v0 = in.measured_v_m_s;
  const double brake_s = std::abs(v0) / config_.decel_m_s2;
  // then_stop: the command reaches the wheels after reaction_s and the robot then brakes along
  // its arc (tau: the time the command has been held, at full speed, by then).
  const double stop_s = std::abs(v) / config_.decel_m_s2;
  if (then_stop) horizon_s = config_.reaction_s + stop_s;
  Gaps g{std::numeric_limits<double>::infinity(), std::numeric_limits<double>::infinity()};
  for (double t = 0.0; t <= horizon_s + 1e-9; t += kApproachStepS) {
    const double mx = x + vx * t;
    const double my = y + vy * t;
    double tau = t;
    if (then_stop && t > config_.reaction_s) {
      const double after = std::min(t - config_.reaction_s, stop_s);
      tau = config_.reaction_s + after - (stop_s > 0.0 ? 0.5 * after * after / stop_s : 0.0);
    }
    const double heading = w * tau;
    const bool straight = std::abs(w) < 1e-9;
    const double px = straight ? v * tau : v / w * std::sin(heading);
    const double py = straight ? 0.0 : v / w * (1.0 - std::cos(heading));
    g.moving_m = std::min(g.moving_m, gap_at(config_.footprint, px, py, heading, mx, my, radius));
    const double tb = std::min(t, brake_s);
    const double travelled = v0 * tb - std::copysign(0.5 * config_.decel_m_s2 * tb * tb, v0);
    g.braking_m = std::min(g.braking_m, gap_at(config_.footprint, travelled, 0.0, 0.0, mx, my, radius));
  }
  return g;
}

bool SafetyFilter::approach_refused(const SafetyInputs& in, double v, double w) const noexcept {
  if (in.movers == nullptr || !(config_.approach_horizon_s > 0.0) || (v == 0.0 && w == 0.0)) return false;
  const std::size_t tracks = in.movers->count + (config_.approach_candidates ? in.movers->candidate_count : 0u);
  for (std::size_t i = 0; i < std::min<std::size_t>(tracks, msg::MovingObstacles::kMax); ++i) {
    const msg::MovingObstacle& m = in.movers->items[i];
    if (std::hypot(m.vx_m_s, m.vy_m_s) < config_.approach_min_speed_m_s) continue;
    const BodyMover b = in_body(in, m);
    const Gaps g = gaps(in, v, w, b.x_m, b.y_m, b.vx_m_s, b.vy_m_s, m.radius_m, config_.approach_horizon_s);
    if (g.moving_m < config_.approach_margin_m && g.moving_m < g.braking_m - kApproachSlackM) return true;
  }
  return false;
}

bool SafetyFilter::cage_refused(const SafetyInputs& in, double v, double w) const noexcept {
  if (config_.cage_margin_m < 0.0 || (v == 0.0 && w == 0.0)) return false;
  // The robot must still be able to stop outside the cage of the person held where they are
  // now; and holding the command must not take the body into a walker's cage on their way.
  const auto closes = [&](double x, double y, double vx, double vy, double radius) {
    const Gaps held = gaps(in, v, w, x, y, 0.0, 0.0, radius, 0.0, true);
    if (held.moving_m < 0.0 && held.moving_m < held.braking_m - kCageSlackM) return true;
    if (std::hypot(vx, vy) < config_.approach_min_speed_m_s) return false;
    const Gaps walking = gaps(in, v, w, x, y, vx, vy, radius, config_.cage_horizon_s);
    return walking.moving_m < 0.0 && walking.moving_m < walking.braking_m - kCageSlackM;
  };
  const std::size_t people = in.people != nullptr ? std::min<std::size_t>(in.people->count, msg::People::kMax) : 0;
  for (std::size_t i = 0; i < people; ++i) {
    const msg::TrackedPerson& p = in.people->items[i];
    const BodyMover b = in_body(in, p, in.people->stamp_ns);
    // The cage as a disc about the person's centre: a gap below zero is inside it.
    if (closes(b.x_m, b.y_m, b.vx_m_s, b.vy_m_s, p.cage_radius_m + config_.cage_margin_m)) return true;
  }
  if (in.movers == nullptr || config_.mover_cage_m < 0.0) return false;
  for (std::size_t i = 0; i < std::min<std::size_t>(in.movers->count, msg::MovingObstacles::kMax); ++i) {
    const msg::MovingObstacle& m = in.movers->items[i];
    if (std::hypot(m.vx_m_s, m.vy_m_s) < config_.approach_min_speed_m_s) continue;
    const BodyMover b = in_body(in, m);
    const double radius = m.radius_m + config_.mover_cage_m + config_.cage_margin_m;
    if (closes(b.x_m, b.y_m, b.vx_m_s, b.vy_m_s, radius)) return true;
  }
  return false;
}

double SafetyFilter::separation_speed(double gap_m, double approach_m_s, double latency_s, double decel_m_s2) noexcept {
  const double b = latency_s + approach_m_s / decel_m_s2;
  const double c = approach_m_s * latency_s - gap_m;
  if (c >= 0.0) return 0.0;
  return decel_m_s2 * (std::sqrt(b * b - 2.0 * c / decel_m_s2) - b);
}

double SafetyFilter::separation_cap(const SafetyInputs& in, double v, double scan_age_s, SafetyOutput& out) const noexcept {
  double cap = std::numeric_limits<double>::infinity();
  if (config_.separation_spread_m_s < 0.0 || config_.cage_margin_m < 0.0 || v == 0.0) return cap;
  const double latency_s = config_.reaction_s + scan_age_s;
  const auto consider = [&](const BodyMover& b, double cage_radius_m) {
    const double range = std::hypot(b.x_m, b.y_m);
    if (!(range > 1e-6)) return;
    const double toward = v * b.x_m / range;  // the robot's speed towards them
    if (!(toward > 0.0)) return;
    const double gap = footprint_distance(config_.footprint, b.x_m, b.y_m) - cage_radius_m - config_.cage_margin_m;
    // The spread is a walker's: the prediction's error was measured on walkers, and a standing
    // person's possible step is what the cage's safety radius is for.
    const bool walking = std::hypot(b.vx_m_s, b.vy_m_s) >= config_.approach_min_speed_m_s;
    const double approach = std::max(0.0, -(b.vx_m_s * b.x_m + b.vy_m_s * b.y_m) / range) +
                            (walking ? config_.separation_spread_m_s : 0.0);
    const double limit = separation_speed(gap, approach, latency_s, config_.decel_m_s2) * std::abs(v) / toward;
    if (limit < cap) {
      cap = limit;
      out.separation_cap_m_s = limit;
      out.separation_gap_m = gap;
      out.separation_approach_m_s = approach;
    }
  };
  const std::size_t people = in.people != nullptr ? std::min<std::size_t>(in.people->count, msg::People::kMax) : 0;
  for (std::size_t i = 0; i < people; ++i) {
    const msg::TrackedPerson& p = in.people->items[i];
    consider(in_body(in, p, in.people->stamp_ns), p.cage_radius_m);
  }
  if (in.movers == nullptr || config_.mover_cage_m < 0.0) return cap;
  const std::size_t tracks = in.movers->count + (config_.approach_candidates ? in.movers->candidate_count : 0u);
  for (std::size_t i = 0; i < std::min<std::size_t>(tracks, msg::MovingObstacles::kMax); ++i) {
    const msg::MovingObstacle& m = in.movers->items[i];
    if (std::hypot(m.vx_m_s, m.vy_m_s) < config_.approach_min_speed_m_s) continue;
    consider(in_body(in, m), m.radius_m + config_.mover_cage_m);
  }
  return cap;
}

double SafetyFilter::closing_speed(const SafetyInputs& in) const noexcept {
  if (in.movers == nullptr) return 0.0;
  double nearest = std::numeric_limits<double>::infinity();
  double closing = 0.0;
  for (std::size_t i = 0; i < in.movers->count; ++i) {
    const msg::MovingObstacle& m = in.movers->items[i];
    const BodyMover b = in_body(in, m);
    if (b.x_m <= 0.0 || std::abs(b.y_m) > half_width_m_ + config_.lateral_margin_m + m.radius_m) continue;
    if (b.x_m < nearest) {
      nearest = b.x_m;
      closing = std::max(0.0, -b.vx_m_s);
    }
  }
  return closing;
}

SafetyFilter::Crossers SafetyFilter::crossing_movers(const SafetyInputs& in, double half_width_m,
                                                     double scan_age_s) const noexcept {
  Crossers out;
  if (in.movers == nullptr) return out;
  for (std::size_t i = 0; i < in.movers->count && out.count < out.items.size(); ++i) {
    const msg::MovingObstacle& m = in.movers->items[i];
    const BodyMover b = in_body(in, m);
    // Only a mover going across and not towards the robot; it is out of the way once its near
    // side has passed the corridor's far edge.
    if (std::abs(b.vy_m_s) < config_.min_crossing_speed_m_s || b.vx_m_s < -config_.min_crossing_speed_m_s) continue;
    Crosser k;
    // Its points are where it was when the scan was taken.
    k.x_m = b.x_m - b.vx_m_s * scan_age_s;
    k.y_m = b.y_m - b.vy_m_s * scan_age_s;
    k.radius_m = m.radius_m + config_.mover_point_slack_m;
    const double edge = std::copysign(half_width_m + k.radius_m + config_.crossing_margin_m, b.vy_m_s);
    k.leaves_s = std::max(0.0, (edge - b.y_m) / b.vy_m_s);
    out.items[out.count++] = k;
  }
  return out;
}

bool SafetyFilter::Crossers::gone_before(const Point2D& q, double arrival_s) const noexcept {
  for (std::size_t i = 0; i < count; ++i) {
    const Crosser& k = items[i];
    const double dx = q.x_m - k.x_m;
    const double dy = q.y_m - k.y_m;
    if (dx * dx + dy * dy <= k.radius_m * k.radius_m) return k.leaves_s < arrival_s;
  }
  return false;
}

namespace {
// Whether disc d has a reading no older than max_age_s.
bool sonar_fresh(const SafetyInputs& in, double max_age_s, std::size_t d) noexcept {
  const hal::Nanos stamp = in.sonar->stamp_ns[d];
  return stamp >= 0 && static_cast<double>(in.now_ns - stamp) <= max_age_s * 1e9;
}
// A sonar echo in the body frame, if the disc's reading is fresh and saw something.
bool sonar_echo(const SafetyInputs& in, double max_age_s, std::size_t d, Point2D& at) noexcept {
  const msg::Sonar& s = *in.sonar;
  if (!sonar_fresh(in, max_age_s, d)) return false;
  if (!(s.range_m[d] < s.max_range_m)) return false;
  const Pose2D& m = s.mount[d];
  at = {m.x_m + s.range_m[d] * std::cos(m.theta_rad), m.y_m + s.range_m[d] * std::sin(m.theta_rad)};
  return true;
}
}  // namespace

bool SafetyFilter::sonar_blocks_reverse(const SafetyInputs& in, double v) const noexcept {
  if (in.sonar == nullptr || !(v < 0.0)) return false;
  const double speed = std::max(-v, -in.measured_v_m_s);
  const double reach = config_.sonar_stop_m + speed * config_.reaction_s + speed * speed / (2.0 * config_.decel_m_s2);
  const double half_width = half_width_m_ + config_.lateral_margin_m;
  for (std::size_t d = 0; d < std::min<std::size_t>(in.sonar->count, msg::Sonar::kMax); ++d) {
    if (std::cos(in.sonar->mount[d].theta_rad) >= 0.0) continue;  // faces forwards or sideways
    Point2D q;
    if (!sonar_echo(in, config_.sonar_max_age_s, d, q)) continue;
    if (q.x_m <= rear_m_ + 1e-9 && q.x_m >= rear_m_ - reach && std::abs(q.y_m) <= half_width) return true;
  }
  return false;
}

bool SafetyFilter::sonar_watches_behind(const SafetyInputs& in) const noexcept {
  if (in.sonar == nullptr) return false;
  std::size_t behind = 0;
  for (std::size_t d = 0; d < std::min<std::size_t>(in.sonar->count, msg::Sonar::kMax); ++d) {
    if (std::cos(in.sonar->mount[d].theta_rad) >= 0.0) continue;
    if (!sonar_fresh(in, config_.sonar_max_age_s, d)) return false;
    ++behind;
  }
  return behind > 0;
}

bool SafetyFilter::sonar_in_turn_circle(const SafetyInputs& in) const noexcept {
  if (in.sonar == nullptr) return false;
  for (std::size_t d = 0; d < std::min<std::size_t>(in.sonar->count, msg::Sonar::kMax); ++d) {
    Point2D q;
    if (sonar_echo(in, config_.sonar_max_age_s, d, q) && std::hypot(q.x_m, q.y_m) < turn_radius_m_) return true;
  }
  return false;
}

std::uint32_t SafetyLatch::update(const msg::SafetyIo* io) noexcept {
  std::uint32_t causes = kSafetyNone;
  bool latching = true;
  if (io == nullptr || !io->healthy) {
    causes |= kSafetyIoLost;
    latching = reset_at_start_ || ever_healthy_ || (io != nullptr && io->ever_healthy);
  } else {
    ever_healthy_ = true;
    if (io->estop) causes |= kSafetyEstopChain;
    if (io->bumper) causes |= kSafetyBumper;
  }
  if (causes != kSafetyNone) {
    if (latching && !held_) ++trips_;
    held_ = held_ || latching;
    counted_since_clear_ = false;
    return causes;
  }
  if (!held_) return kSafetyNone;
  // A reset counts only when pressed after the cause went away: the counter as first seen
  // with no cause is the baseline.
  if (!counted_since_clear_) {
    counted_since_clear_ = true;
    resets_seen_ = io->resets;
    return kSafetyResetNeeded;
  }
  if (io->resets != resets_seen_) {
    held_ = false;
    return kSafetyNone;
  }
  return kSafetyResetNeeded;
}

SafetyOutput SafetyFilter::filter(const SafetyInputs& in) const noexcept {
  SafetyOutput out;
  out.command = in.requested;
  out.nearest_ahead_m = std::numeric_limits<double>::infinity();
  // A stamp ahead of now (clocks a little apart) counts as a fresh scan, never a negative age.
  if (in.scan != nullptr) out.scan_age_s = std::max(0.0, static_cast<double>(in.now_ns - in.scan->stamp_ns()) * 1e-9);
  const double stale_scan_ns = config_.stale_scan_periods * config_.scan_period_s * 1e9;
  if (in.scan == nullptr || static_cast<double>(in.now_ns - in.scan->stamp_ns()) > stale_scan_ns) out.reasons |= kSafetyScanStale;
  if (in.odom_stamp_ns < 0 || static_cast<double>(in.now_ns - in.odom_stamp_ns) > config_.odom_timeout_s * 1e9) {
    out.reasons |= kSafetyOdomStale;
  }
  if (in.estop) out.reasons |= kSafetyEstop;
  out.reasons |= in.io_stops;
  if (!in.motors_enabled) out.reasons |= kSafetyMotorsOff;
  if (in.localization_lost) out.reasons |= kSafetyLocalizationLost;
  if (out.reasons != kSafetyNone || !std::isfinite(in.requested.v_m_s) || !std::isfinite(in.requested.w_rad_s)) {
    out.command.v_m_s = 0.0;
    out.command.w_rad_s = 0.0;
    return out;
  }

  double v = in.requested.v_m_s;
  double w = in.requested.w_rad_s;
  const double speed = std::max({0.0, in.measured_v_m_s, v});
  out.closing_speed_m_s = v > 0.0 ? closing_speed(in) : 0.0;
  const double stop = config_.stop_distance_m + speed * (config_.reaction_s + out.scan_age_s) +
                      speed * speed / (2.0 * config_.decel_m_s2) +
                      out.closing_speed_m_s * (config_.reaction_s + out.scan_age_s + speed / config_.decel_m_s2);
  out.stop_distance_m = stop;

  const std::span<const Point2D> points = in.scan->points();
  bool inside_turn_circle = false;
  for (const Point2D& q : points) {
    if (std::hypot(q.x_m, q.y_m) < turn_radius_m_) inside_turn_circle = true;
  }

  // Sweep the front half of the body (widened by the lateral margin) forward along the
  // commanded arc in kSweepStepM steps, up to the end of the slow zone: the first arc length
  // at which a point would be inside it is the free travel ahead.
  if (v > 0.0) {
    const double curvature = w / v;
    const double reach = stop + config_.slow_distance_m;
    const double half_width = half_width_m_ + config_.lateral_margin_m;
    const Crossers crossers = crossing_movers(in, half_width, out.scan_age_s);
    for (double travelled = 0.0; travelled <= reach + 1e-9 && !std::isfinite(out.nearest_ahead_m);
         travelled += kSweepStepM) {
      const double heading = curvature * travelled;
      const bool straight = std::abs(curvature) < 1e-9;
      const double px = straight ? travelled : std::sin(heading) / curvature;
      const double py = straight ? 0.0 : (1.0 - std::cos(heading)) / curvature;
      const double c = std::cos(heading);
      const double s = std::sin(heading);
      for (const Point2D& q : points) {
        const double dx = q.x_m - px;
        const double dy = q.y_m - py;
        const double bx = c * dx + s * dy;  // the point in the body frame at this step
        const double by = -s * dx + c * dy;
        if (bx >= 0.0 && bx <= front_m_ && std::abs(by) <= half_width) {
          // Beyond the fixed stop distance, a point of a mover that will have crossed out of the
          // way before the robot gets there neither stops nor slows it.
          if (travelled > config_.stop_distance_m && crossers.gone_before(q, travelled / std::max(speed, 1e-3))) continue;
          out.nearest_ahead_m = travelled;
          break;
        }
      }
    }
    if (out.nearest_ahead_m <= stop) {
      v = 0.0;
      out.reasons |= kSafetyObstacle;
    } else if (out.nearest_ahead_m < stop + config_.slow_distance_m) {
      const double scale = (out.nearest_ahead_m - stop) / config_.slow_distance_m;
      v *= scale;
      w *= scale;  // keep the arc that was checked
      out.reasons |= kSafetySlowed;
    }
  } else if (v < 0.0) {
    const double reverse_cap =
        sonar_watches_behind(in) ? std::max(config_.max_reverse_m_s, config_.sonar_reverse_m_s) : config_.max_reverse_m_s;
    if (v < -reverse_cap) {
      v = -reverse_cap;
      out.reasons |= kSafetyReverseCapped;
    }
    if (sonar_blocks_reverse(in, v)) {
      v = 0.0;
      w = 0.0;
      out.reasons |= kSafetySonar;
    }
  }
  if (const double cap = separation_cap(in, v, out.scan_age_s, out); std::abs(v) > cap) {
    const double scale = cap / std::abs(v);
    v *= scale;
    // Keep the arc; with nothing left towards them, turning on the spot (which closes no
    // distance; the turn circle check below still applies) is what lets it face away.
    if (v != 0.0) w *= scale;
    out.reasons |= kSafetySeparation;
  }
  if (w != 0.0 && std::abs(v) < 1e-9 && sonar_in_turn_circle(in)) inside_turn_circle = true;
  if (w != 0.0 && inside_turn_circle && std::abs(v) < 1e-9) {
    w = 0.0;
    out.reasons |= kSafetyObstacle;
  }
  if (approach_refused(in, v, w)) {
    v = 0.0;
    w = 0.0;
    out.reasons |= kSafetyMoverApproach;
  }
  if (cage_refused(in, v, w)) {
    v = 0.0;
    w = 0.0;
    out.reasons |= kSafetyCage;
  }
  out.command.v_m_s = v;
  out.command.w_rad_s = w;
  return out;
}

}  // namespace sen3bot::nav
