#include "sen3bot/nav/crossings.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sen3bot::nav {

Status LaneMap::init(const LaneConfig& config, double origin_x_m, double origin_y_m, double width_m, double height_m,
                     std::pmr::memory_resource& resource) {
  if (!(config.cell_m > 0.0) || !(config.decay_s > 0.0) || !(config.band_weight > 0.0 && config.band_weight < 1.0) ||
      config.max_cells == 0 || !(width_m > 0.0) || !(height_m > 0.0))
    return Error::format(Errc::config, "lanes: cell_m, decay_s, band_weight (0-1), the budget and the extent must be positive");
  config_ = config;
  origin_x_m_ = origin_x_m;
  origin_y_m_ = origin_y_m;
  cell_m_ = config.cell_m;
  // A larger site gets coarser lanes, never more memory.
  while (std::ceil(width_m / cell_m_) * std::ceil(height_m / cell_m_) > static_cast<double>(config.max_cells))
    cell_m_ *= 1.25;
  columns_ = static_cast<int>(std::ceil(width_m / cell_m_));
  rows_ = static_cast<int>(std::ceil(height_m / cell_m_));
  const std::size_t cells = static_cast<std::size_t>(columns_) * static_cast<std::size_t>(rows_);
  auto* data = static_cast<float*>(resource.allocate(cells * sizeof(float), alignof(float)));
  walked_ = {data, cells};
  // The age at which the weight falls to band_weight.
  min_walked_s_ = config.decay_s * std::log(config.band_weight);
  clear();
  return Status::success();
}

void LaneMap::clear() noexcept { std::fill(walked_.begin(), walked_.end(), -std::numeric_limits<float>::infinity()); }

LaneMap::Cells LaneMap::cells_around(double x_m, double y_m, double r) const noexcept {
  const auto cell = [this](double v, double origin) { return static_cast<int>(std::floor((v - origin) / cell_m_)); };
  return {std::max(0, cell(x_m - r, origin_x_m_)), std::min(columns_ - 1, cell(x_m + r, origin_x_m_)),
          std::max(0, cell(y_m - r, origin_y_m_)), std::min(rows_ - 1, cell(y_m + r, origin_y_m_))};
}

void LaneMap::walk(double x_m, double y_m, double radius_m, double now_s) noexcept {
  if (walked_.empty()) return;
  const double r = radius_m + config_.half_width_m;
  const Cells c = cells_around(x_m, y_m, r);
  for (int row = c.row0; row <= c.row1; ++row) {
    for (int col = c.col0; col <= c.col1; ++col) {
      const double cx = origin_x_m_ + (col + 0.5) * cell_m_;
      const double cy = origin_y_m_ + (row + 0.5) * cell_m_;
      if (std::hypot(cx - x_m, cy - y_m) > r) continue;
      walked_[static_cast<std::size_t>(row) * static_cast<std::size_t>(columns_) + static_cast<std::size_t>(col)] =
          static_cast<float>(now_s);
    }
  }
}

double LaneMap::weight(double x_m, double y_m, double now_s) const noexcept {
  const int col = static_cast<int>(std::floor((x_m - origin_x_m_) / cell_m_));
  const int row = static_cast<int>(std::floor((y_m - origin_y_m_) / cell_m_));
  if (col < 0 || row < 0 || col >= columns_ || row >= rows_) return 0.0;
  const double at = walked_[static_cast<std::size_t>(row) * static_cast<std::size_t>(columns_) + static_cast<std::size_t>(col)];
  if (!std::isfinite(at)) return 0.0;
  return std::exp(-std::max(0.0, now_s - at) / config_.decay_s);
}

bool LaneMap::in_band(double x_m, double y_m, double radius_m, double now_s) const noexcept {
  if (walked_.empty()) return false;
  const double since = now_s + min_walked_s_;  // stamps at or after this are in a band
  const Cells c = cells_around(x_m, y_m, radius_m);
  // The centre's own cell, by the same rounding as the range: the gap to it is zero, not a
  // rounding of its edge (a centre on a cell boundary would otherwise miss its own cell).
  const int own_col = static_cast<int>(std::floor((x_m - origin_x_m_) / cell_m_));
  const int own_row = static_cast<int>(std::floor((y_m - origin_y_m_) / cell_m_));
  for (int row = c.row0; row <= c.row1; ++row) {
    for (int col = c.col0; col <= c.col1; ++col) {
      const double at =
          walked_[static_cast<std::size_t>(row) * static_cast<std::size_t>(columns_) + static_cast<std::size_t>(col)];
      if (!(at >= since)) continue;
      // The gap from the disc's centre to the cell along each axis.
      const double gx = col == own_col ? 0.0 : std::min(std::abs(origin_x_m_ + col * cell_m_ - x_m),
                                                         std::abs(origin_x_m_ + (col + 1) * cell_m_ - x_m));
      const double gy = row == own_row ? 0.0 : std::min(std::abs(origin_y_m_ + row * cell_m_ - y_m),
                                                         std::abs(origin_y_m_ + (row + 1) * cell_m_ - y_m));
      if (std::hypot(gx, gy) <= radius_m) return true;
    }
  }
  return false;
}

Status CrossingGate::init(const CrossingConfig& config, double body_radius_m, double max_v_m_s,
                          double acc_v_m_s2) noexcept {
  if (!(config.sample_m > 0.0) || !(config.time_step_s > 0.0) || !(config.horizon_s > 0.0) ||
      !(config.lookahead_m > 0.0) || !(config.decel_m_s2 > 0.0) || !(max_v_m_s > 0.0) || !(acc_v_m_s2 > 0.0))
    return Error::format(Errc::config, "crossings: sample_m, time_step_s, horizon_s, lookahead_m, decel and the drive limits must be positive");
  if (config.lookahead_m / config.sample_m + 1.0 > static_cast<double>(kMaxSamples))
    return Error::format(Errc::config, "crossings: lookahead_m / sample_m exceeds %zu samples", kMaxSamples);
  if (config.horizon_s / config.time_step_s + 1.0 > static_cast<double>(kMaxSteps))
    return Error::format(Errc::config, "crossings: horizon_s / time_step_s exceeds %zu steps", kMaxSteps - 1);
  config_ = config;
  body_m_ = body_radius_m;
  max_v_m_s_ = max_v_m_s;
  acc_v_m_s2_ = acc_v_m_s2;
  steps_ = static_cast<std::size_t>(std::floor(config.horizon_s / config.time_step_s + 1e-9)) + 1;
  max_samples_ = static_cast<std::size_t>(std::floor(config.lookahead_m / config.sample_m + 1e-9)) + 1;
  return Status::success();
}

void CrossingGate::sample_path(const CrossingInputs& in) noexcept {
  sample_count_ = 0;
  const std::size_t limit = max_samples_;
  Point2D prev{in.pose.x_m, in.pose.y_m};
  samples_[sample_count_++] = prev;
  tangent_[0] = {std::cos(in.pose.theta_rad), std::sin(in.pose.theta_rad)};
  double carried = 0.0;  // arc length since the last sample
  for (const msg::PathPoint& q : in.path) {
    const Point2D next{q.x_m, q.y_m};
    double len = std::hypot(next.x_m - prev.x_m, next.y_m - prev.y_m);
    const Point2D along = len > 0.0 ? Point2D{(next.x_m - prev.x_m) / len, (next.y_m - prev.y_m) / len} : Point2D{};
    while (len > 0.0 && carried + len >= config_.sample_m && sample_count_ < limit) {
      const double u = (config_.sample_m - carried) / len;
      prev = {prev.x_m + u * (next.x_m - prev.x_m), prev.y_m + u * (next.y_m - prev.y_m)};
      tangent_[sample_count_] = along;
      samples_[sample_count_++] = prev;
      len = std::hypot(next.x_m - prev.x_m, next.y_m - prev.y_m);
      carried = 0.0;
    }
    if (sample_count_ >= limit) return;
    carried += len;
    prev = next;
  }
}

bool CrossingGate::walks_along(const CrossingTrack& t, double ux, double uy, double reach_m) const noexcept {
  // Someone on the path now and walking along it (an operator the robot follows, or someone
  // coming the other way) leads or meets the robot, not crosses it. Where the path turns,
  // the straight prediction of a leader cuts across its later part; that is not a crossing.
  for (std::size_t k = 0; k < sample_count_; ++k) {
    const double dx = samples_[k].x_m - t.x_m;
    const double dy = samples_[k].y_m - t.y_m;
    if (dx * dx + dy * dy < reach_m * reach_m && std::abs(ux * tangent_[k].x_m + uy * tangent_[k].y_m) > config_.along_cos)
      return true;
  }
  return false;
}

void CrossingGate::mark(const CrossingInputs& in, Reach reach, std::span<std::uint64_t> taken,
                        std::span<std::uint32_t> by) const noexcept {
  std::fill(taken.begin(), taken.begin() + static_cast<std::ptrdiff_t>(sample_count_), 0);
  std::fill(by.begin(), by.begin() + static_cast<std::ptrdiff_t>(sample_count_), 0);
  for (const CrossingTrack& t : in.tracks) {
    const double speed = std::hypot(t.vx_m_s, t.vy_m_s);
    if (speed < config_.min_speed_m_s) continue;
    const double ux = t.vx_m_s / speed, uy = t.vy_m_s / speed;
    const double base = reach == Reach::body ? t.body_m + body_m_ : t.keep_out_m + body_m_ + config_.margin_m;
    const bool with_spread = reach == Reach::spread;
    if (walks_along(t, ux, uy, t.keep_out_m + body_m_ + config_.margin_m)) continue;
    for (std::size_t i = 0; i < steps_; ++i) {
      const double time = static_cast<double>(i) * config_.time_step_s;
      const double cx = t.x_m + t.vx_m_s * time;
      const double cy = t.y_m + t.vy_m_s * time;
      const double r = base + (with_spread ? config_.spread_m_s * time : 0.0);
      for (std::size_t k = 0; k < sample_count_; ++k) {
        const double dx = samples_[k].x_m - cx;
        const double dy = samples_[k].y_m - cy;
        if (dx * dx + dy * dy >= r * r) continue;
        // Walking along the path there (ahead of the robot, or towards it) is not crossing it:
        // following and meeting are the DWA's, the cages' and the safety filter's.
        if (std::abs(ux * tangent_[k].x_m + uy * tangent_[k].y_m) > config_.along_cos) continue;
        taken[k] |= std::uint64_t{1} << i;
        if (by[k] == 0) by[k] = t.id + 1;  // 0: none
      }
    }
  }
}

int CrossingGate::first_meeting(std::span<const std::uint64_t> taken, double v0, double share) const noexcept {
  // share: of the top speed and the acceleration the robot is counted on to reach
  const double top = max_v_m_s_ * share;
  const double acc = acc_v_m_s2_ * share;
  const double v = std::clamp(v0, 0.0, top);
  const double t_acc = (top - v) / acc;
  const double s_acc = v * t_acc + 0.5 * acc * t_acc * t_acc;
  const bool path_ends = sample_count_ < max_samples_;
  for (std::size_t i = 0; i < steps_; ++i) {
    const double t = static_cast<double>(i) * config_.time_step_s;
    const double s = t < t_acc ? v * t + 0.5 * acc * t * t : s_acc + top * (t - t_acc);
    auto k = static_cast<std::size_t>(std::floor(s / config_.sample_m + 0.5));
    if (k >= sample_count_) {
      if (!path_ends) return -1;  // past the look-ahead: out of this crossing
      k = sample_count_ - 1;      // the path ends here: the robot stands at its end
    }
    if ((taken[k] >> i) & 1u) return static_cast<int>(i);
  }
  return -1;
}

CrossingDecision CrossingGate::decide(const CrossingInputs& in) noexcept {
  CrossingDecision out;
  out.v_cap_m_s = std::numeric_limits<double>::infinity();
  sample_count_ = 0;
  if (!config_.enabled || in.path.empty() || in.tracks.empty()) return out;
  sample_path(in);
  mark(in, Reach::spread, taken_, taken_by_);
  if (std::all_of(taken_.begin(), taken_.begin() + static_cast<std::ptrdiff_t>(sample_count_),
                  [](std::uint64_t t) { return t == 0; }))
    return out;
  const double v0 = std::max(0.0, in.v_m_s);
  if (first_meeting(taken_, v0, config_.go_share) < 0) {
    out.action = Crossing::go;
    return out;
  }
  // Where to wait: outside every walker's keep-out along their predicted way (the spread is
  // the timing's uncertainty, which decides whether to go; it would push the wait point back
  // by metres).
  mark(in, Reach::keep_out, touched_, touched_by_);
  std::size_t block = 0;
  while (block < sample_count_ && touched_[block] == 0) ++block;
  if (block == sample_count_) {  // only the spread reaches the path: wait where it begins
    while (block < sample_count_ && taken_[block] == 0) ++block;
    out.track_id = taken_by_[block] - 1;
  } else {
    out.track_id = touched_by_[block] - 1;
  }
  out.conflict_at_m = static_cast<double>(block) * config_.sample_m;
  // Wait before the first taken sample, and before any band that holds it.
  auto k = static_cast<std::ptrdiff_t>(block) - static_cast<std::ptrdiff_t>(std::ceil(config_.stop_margin_m / config_.sample_m - 1e-9));
  if (in.lanes != nullptr) {
    while (k > 0 && in.lanes->in_band(samples_[static_cast<std::size_t>(k)].x_m, samples_[static_cast<std::size_t>(k)].y_m,
                                      body_m_, in.now_s))
      --k;
  }
  const double wait_at = std::max(0.0, static_cast<double>(k) * config_.sample_m);
  out.wait_at_m = wait_at;
  const double reach = v0 * config_.reaction_s + v0 * v0 / (2.0 * config_.decel_m_s2);
  if (k > 0 && wait_at >= reach) {
    out.action = Crossing::wait;
    out.v_cap_m_s = std::sqrt(2.0 * config_.decel_m_s2 * std::max(0.0, wait_at - v0 * config_.reaction_s));
    return out;
  }
  // Too late to stop before it, or standing in it. Where braking now would end, is it in a
  // walker's way (their body's sweep, no keep-out, no spread)? Then the gate steps aside: the
  // DWA's mover check and the safety filter's cage and approach checks decide (they brake for
  // a contact, or drive on out of the way). Else it stops there, short of their way.
  mark(in, Reach::body, bodies_, bodies_by_);
  const auto stop_k = std::min(sample_count_ - 1, static_cast<std::size_t>(std::ceil(reach / config_.sample_m - 1e-9)));
  bool in_their_way = false;
  for (std::size_t j = 0; j <= stop_k; ++j) in_their_way = in_their_way || bodies_[j] != 0;
  if (in_their_way) {
    out.action = Crossing::commit;
    return out;
  }
  out.action = Crossing::wait;
  out.v_cap_m_s = 0.0;
  return out;
}

namespace {
// The time to cover `distance` from speed v0 (towards it, >= 0) accelerating at acc up to top.
double travel_s(double distance, double v0, double top, double acc) noexcept {
  const double v = std::clamp(v0, 0.0, top);
  const double t_acc = (top - v) / acc;
  const double s_acc = v * t_acc + 0.5 * acc * t_acc * t_acc;
  if (distance >= s_acc) return t_acc + (distance - s_acc) / top;
  return (std::sqrt(v * v + 2.0 * acc * distance) - v) / acc;
}

struct Sweep {
  double along_m, offset_m, half_width_m, arrives_s;
};
// Where (x, y) lies against a walker's way: how far ahead of them along it, how far off it,
// the sweep's half width, and when the sweep reaches it (+inf: it does not within horizon_s).
Sweep sweep_of(const MakeWayConfig& config, const CrossingTrack& t, double x, double y, double body_radius_m) noexcept {
  const double speed = std::hypot(t.vx_m_s, t.vy_m_s);
  const double ux = t.vx_m_s / speed, uy = t.vy_m_s / speed;
  const double rx = x - t.x_m, ry = y - t.y_m;
  const double along = ux * rx + uy * ry;
  // Their heading is a prediction: the sweep widens with the time they take to get here.
  Sweep s{along, ux * ry - uy * rx,
          t.body_m + body_radius_m + config.margin_m + config.spread_m_s * std::max(0.0, along) / speed,
          std::numeric_limits<double>::infinity()};
  if (std::abs(s.offset_m) >= s.half_width_m || s.along_m + s.half_width_m < 0.0) return s;
  const double arrives = std::max(0.0, (s.along_m - s.half_width_m) / speed);
  if (arrives <= config.horizon_s) s.arrives_s = arrives;
  return s;
}
}  // namespace

MakeWayDecision make_way(const MakeWayConfig& config, const Pose2D& pose, double v_m_s, double body_radius_m,
                         std::span<const CrossingTrack> tracks) noexcept {
  MakeWayDecision out;
  if (!config.enabled) return out;
  const auto walking = [&](const CrossingTrack& t) { return std::hypot(t.vx_m_s, t.vy_m_s) >= config.min_walker_m_s; };
  // The walker whose sweep reaches the robot first.
  const CrossingTrack* first = nullptr;
  Sweep at{};
  for (const CrossingTrack& t : tracks) {
    if (!walking(t)) continue;
    const Sweep s = sweep_of(config, t, pose.x_m, pose.y_m, body_radius_m);
    if (std::isfinite(s.arrives_s) && (first == nullptr || s.arrives_s < at.arrives_s)) {
      first = &t;
      at = s;
    }
  }
  if (first == nullptr) return out;
  out.track_id = first->id;
  out.arrives_s = at.arrives_s;
  out.move = MakeWayMove::stay;
  // Moving s along its heading changes its offset from the walker's way by s * sin.
  const double speed = std::hypot(first->vx_m_s, first->vy_m_s);
  const double hx = std::cos(pose.theta_rad), hy = std::sin(pose.theta_rad);
  const double sin_cross = (first->vx_m_s * hy - first->vy_m_s * hx) / speed;
  if (std::abs(sin_cross) < config.min_cross_sin) return out;
  const double to_plus = (at.half_width_m - at.offset_m) / sin_cross;
  const double to_minus = (-at.half_width_m - at.offset_m) / sin_cross;
  const double forward = std::max(to_plus, to_minus);   // > 0
  const double backward = std::min(to_plus, to_minus);  // < 0
  // Free of every walker's sweep where it would end, a centimetre beyond the edge.
  const auto clear_at = [&](double s_m) {
    const double x = pose.x_m + s_m * hx, y = pose.y_m + s_m * hy;
    for (const CrossingTrack& t : tracks)
      if (walking(t) && std::isfinite(sweep_of(config, t, x, y, body_radius_m).arrives_s)) return false;
    return true;
  };
  // Moving along the walker's way as well brings the meeting sooner (or later): counted at
  // whichever end of the move is nearer them.
  const double cos_along = (first->vx_m_s * hx + first->vy_m_s * hy) / speed;
  const auto arrives = [&](double s_m) {
    return std::max(0.0, (std::min(at.along_m, at.along_m + s_m * cos_along) - at.half_width_m) / speed);
  };
  const double t_forward = travel_s(forward, v_m_s, config.forward_m_s, config.accel_m_s2);
  const double t_backward = travel_s(-backward, -v_m_s, config.reverse_m_s, config.accel_m_s2);
  if (t_forward + config.slack_s <= arrives(forward) && clear_at(forward + 0.01)) {
    out.move = MakeWayMove::forward;
    out.v_m_s = config.forward_m_s;
    out.exit_m = forward;
  } else if (t_backward + config.slack_s <= arrives(backward) && clear_at(backward - 0.01)) {
    out.move = MakeWayMove::backward;
    out.v_m_s = -config.reverse_m_s;
    out.exit_m = backward;
  }
  return out;
}

}  // namespace sen3bot::nav
