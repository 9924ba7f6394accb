#include "sen3bot/nav/local_planner.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include "sen3bot/nav/arena.hpp"

namespace sen3bot::nav {
namespace {
constexpr double kPerimeterStepM = 0.025;  // half a 0.05 m cell: no cell is skipped along an edge
constexpr std::size_t kMaxPerimeterPoints = 512;
constexpr std::uint16_t kUnreached = 0xFFFF;
constexpr double kUnreachedPenaltyM = 10.0;  // a rollout ending where the target cannot be reached
// How far around a tracked mover's centre its own laser marks may lie (the track lags the box
// and its radius comes from what the laser saw of it): two cells.
constexpr double kMoverCellSlackM = 0.1;

}  // namespace

Status DwaPlanner::init(const DwaConfig& config, std::pmr::memory_resource& resource) {
  if (config.v_samples < 1 || config.w_samples < 1 || !(config.control_period_s > 0.0) || !(config.sim_step_s > 0.0) ||
      config.sim_time_s < config.sim_step_s || config.max_path_points == 0) {
    return Error::format(Errc::config, "dwa: samples, control_period_s, sim_step_s, sim_time_s and max_path_points must be positive");
  }
  config_ = config;
  return guarded("dwa", [&]() -> Status {
    path_ = allocate_array<PathPoint>(resource, config.max_path_points);
    path_blocked_ = allocate_array<std::uint8_t>(resource, config.max_path_points);
    goal_distance_ = allocate_array<std::uint16_t>(resource, config.max_costmap_cells);
    path_distance_ = allocate_array<std::uint16_t>(resource, config.max_costmap_cells);
    queue_ = allocate_array<std::uint32_t>(resource, config.max_costmap_cells);
    // The checked outline is padded (each corner pushed out per axis, exact for the
    // rectangular Pioneer), so an edge grazing a lethal cell's corner is not missed. The bare
    // outline is kept for escaping when the robot already stands within the padding.
    const auto outline = [&](double padding) {
      std::span<Point2D> out = allocate_array<Point2D>(resource, kMaxPerimeterPoints);
      std::size_t n = 0;
      Footprint fp = config.footprint;
      fp.circle_radius_m += padding;
      for (std::size_t i = 0; i < fp.vertex_count; ++i) {
        fp.vertices[i].x_m += std::copysign(padding, fp.vertices[i].x_m);
        fp.vertices[i].y_m += std::copysign(padding, fp.vertices[i].y_m);
      }
      if (fp.vertex_count == 0) {
        const double circumference = 2.0 * std::numbers::pi * fp.circle_radius_m;
        const auto steps = std::clamp<std::size_t>(static_cast<std::size_t>(circumference / kPerimeterStepM) + 1, 8, kMaxPerimeterPoints);
        for (std::size_t i = 0; i < steps; ++i) {
          const double ang = 2.0 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(steps);
          out[n++] = {fp.circle_radius_m * std::cos(ang), fp.circle_radius_m * std::sin(ang)};
        }
      } else {
        for (std::size_t i = 0; i < fp.vertex_count; ++i) {
          const Point2D va = fp.vertices[i];
          const Point2D vb = fp.vertices[(i + 1) % fp.vertex_count];
          const double len = std::hypot(vb.x_m - va.x_m, vb.y_m - va.y_m);
          const auto steps = std::max<std::size_t>(1, static_cast<std::size_t>(std::ceil(len / kPerimeterStepM)));
          for (std::size_t k = 0; k < steps && n < kMaxPerimeterPoints; ++k) {
            const double t = static_cast<double>(k) / static_cast<double>(steps);
            out[n++] = {va.x_m + t * (vb.x_m - va.x_m), va.y_m + t * (vb.y_m - va.y_m)};
          }
        }
      }
      return out.first(n);
    };
    padded_ = outline(config.footprint_padding_m);
    bare_ = outline(0.0);
    body_min_x_ = body_min_y_ = std::numeric_limits<double>::infinity();
    body_max_x_ = body_max_y_ = -std::numeric_limits<double>::infinity();
    for (const Point2D& p : padded_) {
      body_min_x_ = std::min(body_min_x_, p.x_m);
      body_max_x_ = std::max(body_max_x_, p.x_m);
      body_min_y_ = std::min(body_min_y_, p.y_m);
      body_max_y_ = std::max(body_max_y_, p.y_m);
    }
    check_ = padded_;
    inscribed_m_ = config.footprint.inscribed_radius_m();
    return Status::success();
  });
}

void DwaPlanner::set_path(std::span<const PathPoint> path) noexcept {
  path_count_ = std::min(path.size(), path_.size());
  std::copy_n(path.begin(), path_count_, path_.begin());
  window_begin_ = 0;
  window_end_ = 0;
  target_index_ = 0;
  recovery_state_ = DwaStatus::tracking;
  recovery_ticks_ = 0;
  recovery_cycles_ = 0;
  yield_ticks_ = 0;
  held_by_movers_ = false;
}

void DwaPlanner::clear_path() noexcept { path_count_ = 0; }

bool DwaPlanner::footprint_collides(const Pose2D& pose, const Costmap2D& costmap) const noexcept {
  return outline_hits(pose, costmap, padded_);
}

bool DwaPlanner::outline_hits(const Pose2D& pose, const Costmap2D& costmap, std::span<const Point2D> outline,
                              bool movers_move_on) const noexcept {
  const double c = std::cos(pose.theta_rad);
  const double s = std::sin(pose.theta_rad);
  for (const Point2D& p : outline) {
    int col = 0;
    int row = 0;
    const double x = pose.x_m + c * p.x_m - s * p.y_m;
    const double y = pose.y_m + s * p.x_m + c * p.y_m;
    if (!costmap.world_to_cell(x, y, col, row)) return true;
    const std::uint8_t cost = costmap.at(col, row);
    if (cost == kNoInformationCost) return true;
    if (cost == kLethalCost && !(movers_move_on && near_mover(x, y, kMoverCellSlackM))) return true;
  }
  return false;
}

bool DwaPlanner::near_mover(double x_m, double y_m, double reach_m) const noexcept {
  const double min_speed2 = config_.mover_min_speed_m_s * config_.mover_min_speed_m_s;
  for (const msg::MovingObstacle& m : movers_) {
    if (m.vx_m_s * m.vx_m_s + m.vy_m_s * m.vy_m_s < min_speed2) continue;
    const double r = m.radius_m + reach_m;
    const double dx = x_m - m.x_m;
    const double dy = y_m - m.y_m;
    if (dx * dx + dy * dy <= r * r) return true;
  }
  return false;
}

DwaPlanner::Rollout DwaPlanner::roll_out(const Pose2D& pose, double v, double w, const Costmap2D& costmap) const noexcept {
  Rollout r;
  Pose2D p = pose;
  const int steps = static_cast<int>(std::lround(config_.sim_time_s / config_.sim_step_s));
  const double dt = config_.sim_step_s;
  for (int k = 0; k < steps; ++k) {
    advance_arc(p, v, w, dt);
    int col = 0;
    int row = 0;
    if (!costmap.world_to_cell(p.x_m, p.y_m, col, row)) return r;
    const std::uint8_t cost = costmap.at(col, row);
    // Where a tracked mover stands now, the costmap holds its present, not where it will be:
    // the time-aware check decides about it, so that the robot may pass behind it.
    if (cost >= kInscribedCost) {  // the centre inside the inscribed radius: certain collision
      if (!near_mover(p.x_m, p.y_m, inscribed_m_ + kMoverCellSlackM)) return r;
    } else {
      if (cost >= config_.footprint_check_min_cost && outline_hits(p, costmap, check_, true)) return r;
      r.max_cost = std::max(r.max_cost, cost);
    }
  }
  r.admissible = true;
  r.end = p;
  // Slow rollouts are short; keep checking along the same arc until min_clear_distance_m,
  // so the planner does not pick an arc the safety filter would stop.
  if (v > 0.0) {
    Pose2D q = p;
    double travelled = v * config_.sim_time_s;
    const double step = std::max(0.02, v * dt);
    const double w_per_m = w / v;
    while (travelled < config_.min_clear_distance_m) {
      q.x_m += step * std::cos(q.theta_rad + 0.5 * w_per_m * step);
      q.y_m += step * std::sin(q.theta_rad + 0.5 * w_per_m * step);
      q.theta_rad += w_per_m * step;
      travelled += step;
      if (outline_hits(q, costmap, check_, true)) {
        r.admissible = false;
        return r;
      }
    }
  }
  return r;
}

namespace {
// The hull of {t in [0, horizon] : a t^2 + b t + c <= 0}; false when that set is empty.
bool hull_at_or_below_zero(double a, double b, double c, double horizon, double& lo, double& hi) noexcept {
  constexpr double kFlat = 1e-12;
  if (std::abs(a) < kFlat) {
    if (std::abs(b) < kFlat) {
      lo = 0.0;
      hi = horizon;
      return c <= 0.0;
    }
    const double root = -c / b;
    lo = b > 0.0 ? 0.0 : std::max(0.0, root);
    hi = b > 0.0 ? std::min(horizon, root) : horizon;
    return lo <= hi;
  }
  const double disc = b * b - 4.0 * a * c;
  if (disc < 0.0) {  // never zero: always above (a > 0) or always below (a < 0)
    lo = 0.0;
    hi = horizon;
    return a < 0.0;
  }
  const double q = std::sqrt(disc);
  const double r1 = std::min((-b - q) / (2.0 * a), (-b + q) / (2.0 * a));
  const double r2 = std::max((-b - q) / (2.0 * a), (-b + q) / (2.0 * a));
  if (a > 0.0) {  // below between the roots
    lo = std::max(0.0, r1);
    hi = std::min(horizon, r2);
    return lo <= hi;
  }
  // Below outside the roots: [0, r1] and [r2, horizon].
  const bool early = r1 >= 0.0;
  const bool late = r2 <= horizon;
  if (!early && !late) return false;
  lo = early ? 0.0 : std::max(0.0, r2);
  hi = late ? horizon : std::min(horizon, r1);
  return lo <= hi;
}
}  // namespace

double DwaPlanner::time_to_contact(const Pose2D& pose, double v, double w, std::span<const msg::MovingObstacle> movers,
                                   MoverMotion motion, MoverReach reach_of) const noexcept {
  // Movers are taken a fixed-size batch at a time (the message holds at most 16; the broad
  // phase below needs a window per mover and way); the earliest contact of any batch counts.
  constexpr std::size_t kBatch = msg::MovingObstacles::kMax;
  double earliest = std::numeric_limits<double>::infinity();
  for (std::size_t first = 0; first < movers.size(); first += kBatch) {
    const auto batch = movers.subspan(first, std::min(kBatch, movers.size() - first));
    earliest = std::min(earliest, contact_in_batch(pose, v, w, batch, motion, reach_of, earliest));
  }
  return earliest;
}

double DwaPlanner::contact_in_batch(const Pose2D& pose, double v, double w, std::span<const msg::MovingObstacle> movers,
                                    MoverMotion motion, MoverReach reach_of, double before_s) const noexcept {
  const bool brake = motion == MoverMotion::brake;
  const double dt = config_.sim_step_s;
  // Where braking ends, or standing, the robot stays: a mover that goes back and forth may
  // turn and come back along its way meanwhile, and over a longer time.
  const bool stays = brake || std::abs(v) < config_.min_progress_v_m_s;
  const double horizon_s = stays ? std::max(config_.mover_horizon_s, config_.mover_stay_horizon_s) : config_.mover_horizon_s;
  int steps = static_cast<int>(std::lround(horizon_s / dt));
  if (std::isfinite(before_s)) steps = std::min(steps, static_cast<int>(std::lround(before_s / dt)) - 1);
  const double cx = 0.5 * (body_min_x_ + body_max_x_);
  const double cy = 0.5 * (body_min_y_ + body_max_y_);
  const double hx = 0.5 * (body_max_x_ - body_min_x_);
  const double hy = 0.5 * (body_max_y_ - body_min_y_);
  const double margin = reach_of == MoverReach::touching ? 0.0 : config_.mover_margin_m;
  const double min_speed2 = config_.mover_min_speed_m_s * config_.mover_min_speed_m_s;
  const int ways = stays && config_.mover_may_return ? 2 : 1;

  // Broad phase: contact at t needs the mover's centre within reach + the body box's farthest
  // corner of where the robot is then, which is within the distance it can have driven of
  // where it is now. Each mover and way keeps the steps where that can hold; most walkers in
  // a crowd have none, and the step loop below skips them.
  struct Window {
    const msg::MovingObstacle* mover;
    double sign;
    int first;
    int last;
  };
  std::array<Window, 2 * msg::MovingObstacles::kMax> near{};
  std::size_t near_count = 0;
  int first_step = steps + 1;
  int last_step = 0;
  if (config_.mover_broad_phase) {
    const double corner = std::hypot(std::abs(cx) + hx, std::abs(cy) + hy);
    const double speed = std::abs(v);
    // The fastest it drives on this motion, and (braking) how far it can go at all.
    const double top = motion == MoverMotion::speed_up ? std::max(speed, config_.max_v_m_s) : speed;
    const double braked = speed * (config_.control_period_s + config_.mover_brake_delay_s + 2.0 * dt) +
                          speed * speed / (2.0 * config_.mover_brake_decel_m_s2);
    const double slack = 1e-6;
    for (const msg::MovingObstacle& m : movers) {
      if (m.vx_m_s * m.vx_m_s + m.vy_m_s * m.vy_m_s < min_speed2) continue;
      const double reach = m.radius_m + margin + corner + slack;
      for (int way = 0; way < ways; ++way) {
        const double sign = way == 0 ? 1.0 : -1.0;
        const double dx = m.x_m - pose.x_m;
        const double dy = m.y_m - pose.y_m;
        const double ux = sign * m.vx_m_s;
        const double uy = sign * m.vy_m_s;
        // |d + u t| <= reach + top t, and when braking also <= reach + braked.
        double lo = 0.0;
        double hi = 0.0;
        if (!hull_at_or_below_zero(ux * ux + uy * uy - top * top, 2.0 * (dx * ux + dy * uy - reach * top),
                                   dx * dx + dy * dy - reach * reach, horizon_s, lo, hi)) {
          continue;
        }
        if (brake) {
          const double stop = reach + braked;
          double blo = 0.0;
          double bhi = 0.0;
          if (!hull_at_or_below_zero(ux * ux + uy * uy, 2.0 * (dx * ux + dy * uy), dx * dx + dy * dy - stop * stop,
                                     horizon_s, blo, bhi)) {
            continue;
          }
          lo = std::max(lo, blo);
          hi = std::min(hi, bhi);
          if (lo > hi) continue;
        }
        // One step of slack each side for the rounding of the times.
        const int k0 = std::max(1, static_cast<int>(std::floor(lo / dt)) - 1);
        const int k1 = std::min(steps, static_cast<int>(std::ceil(hi / dt)) + 1);
        if (k0 > k1) continue;
        near[near_count++] = {&m, sign, k0, k1};
        first_step = std::min(first_step, k0);
        last_step = std::max(last_step, k1);
      }
    }
  } else {
    for (const msg::MovingObstacle& m : movers) {
      if (m.vx_m_s * m.vx_m_s + m.vy_m_s * m.vy_m_s < min_speed2) continue;
      for (int way = 0; way < ways; ++way) near[near_count++] = {&m, way == 0 ? 1.0 : -1.0, 1, steps};
    }
    first_step = 1;
    last_step = steps;
  }
  if (near_count == 0) return std::numeric_limits<double>::infinity();

  // The heading's cosine and sine are carried by rotation, not recomputed: this loop runs for
  // every rollout and every mover, and libm's sin and cos were most of its time.
  double px = pose.x_m;
  double py = pose.y_m;
  double c = std::cos(pose.theta_rad);
  double s = std::sin(pose.theta_rad);
  double step_turn = std::numeric_limits<double>::quiet_NaN();
  double step_c = 1.0;
  double step_s = 0.0;
  double speed = v;
  double turn = w;
  for (int k = 1; k <= last_step; ++k) {
    const double t = k * dt;
    if (brake && t > config_.control_period_s + config_.mover_brake_delay_s + 1e-9 && speed != 0.0) {
      // Same arc, slower: w keeps its ratio to v.
      const double slower = std::max(0.0, std::abs(speed) - config_.mover_brake_decel_m_s2 * dt);
      turn = v != 0.0 ? w * slower / std::abs(v) : turn;
      speed = std::copysign(slower, speed);
    } else if (motion == MoverMotion::speed_up && v > 0.0 && t > config_.control_period_s + 1e-9) {
      // The next periods may go on speeding up along the same arc, as their windows allow
      // (from a standstill the window itself holds only a crawl).
      const double faster = std::min(config_.max_v_m_s, speed + config_.acc_v_m_s2 * dt);
      turn = w * faster / v;
      speed = faster;
    }
    if (std::abs(turn) < 1e-6) {
      px += speed * dt * c;
      py += speed * dt * s;
    } else {
      if (turn != step_turn) {
        step_turn = turn;
        step_c = std::cos(turn * dt);
        step_s = std::sin(turn * dt);
      }
      const double c1 = c * step_c - s * step_s;
      const double s1 = s * step_c + c * step_s;
      px += speed / turn * (s1 - s);
      py -= speed / turn * (c1 - c);
      c = c1;
      s = s1;
    }
    if (k < first_step) continue;
    for (std::size_t i = 0; i < near_count; ++i) {
      const Window& n = near[i];
      if (k < n.first || k > n.last) continue;
      const msg::MovingObstacle& m = *n.mover;
      const double reach = m.radius_m + margin;
      const double dx = m.x_m + n.sign * m.vx_m_s * t - px;
      const double dy = m.y_m + n.sign * m.vy_m_s * t - py;
      // The mover's centre in the body frame, then its distance to the padded body's box.
      const double bx = c * dx + s * dy - cx;
      const double by = -s * dx + c * dy - cy;
      const double ex = std::max(0.0, std::abs(bx) - hx);
      const double ey = std::max(0.0, std::abs(by) - hy);
      if (ex * ex + ey * ey < reach * reach) return t;
    }
  }
  return std::numeric_limits<double>::infinity();
}

bool DwaPlanner::meets_mover(const Pose2D& pose, double v, double w) const noexcept {
  return !movers_.empty() && std::isfinite(time_to_contact(pose, v, w, movers_));
}

bool DwaPlanner::braking_is_clear(const Pose2D& pose, double v, double w, const Costmap2D& costmap) const noexcept {
  // The base decelerates at acc_v_m_s2 along the arc it is on; w falls in proportion.
  const double dt = config_.sim_step_s;
  Pose2D p = pose;
  double speed = v;
  while (speed > 0.0) {
    const double turn = w * speed / v;
    p.x_m += speed * dt * std::cos(p.theta_rad + 0.5 * turn * dt);
    p.y_m += speed * dt * std::sin(p.theta_rad + 0.5 * turn * dt);
    p.theta_rad += turn * dt;
    if (outline_hits(p, costmap, check_)) return false;
    speed -= config_.acc_v_m_s2 * dt;
  }
  return true;
}

void DwaPlanner::update_window(const Pose2D& pose) noexcept {
  // The nearest path point, searched forward from the last one (the robot does not go back
  // along its plan) within a bounded look-ahead, so a looping path cannot make it jump.
  double best = std::numeric_limits<double>::infinity();
  std::size_t nearest = window_begin_;
  double walked = 0.0;
  for (std::size_t i = window_begin_; i < path_count_; ++i) {
    if (i > window_begin_) {
      walked += std::hypot(path_[i].x_m - path_[i - 1].x_m, path_[i].y_m - path_[i - 1].y_m);
      if (walked > 2.0 * config_.prune_distance_m + 1.0) break;
    }
    const double d = std::hypot(path_[i].x_m - pose.x_m, path_[i].y_m - pose.y_m);
    if (d < best) {
      best = d;
      nearest = i;
    }
  }
  window_begin_ = nearest;
  double along = 0.0;
  std::size_t end = nearest;
  while (end + 1 < path_count_) {
    const double step = std::hypot(path_[end + 1].x_m - path_[end].x_m, path_[end + 1].y_m - path_[end].y_m);
    if (along + step > config_.prune_distance_m) break;
    along += step;
    ++end;
  }
  window_end_ = end;
}

void DwaPlanner::wavefront(const Costmap2D& costmap, std::span<std::uint16_t> distance, bool from_path) noexcept {
  // 4-connected breadth-first distances in cells through cells below the inscribed cost
  // (DWB's map-grid critics): an obstacle between a rollout's end and the target counts.
  const std::size_t n = costmap.size();
  std::fill_n(distance.begin(), n, kUnreached);
  std::size_t head = 0;
  std::size_t tail = 0;
  const auto seed = [&](double x_m, double y_m) {
    int col = 0;
    int row = 0;
    if (!costmap.world_to_cell(x_m, y_m, col, row) || costmap.at(col, row) >= kInscribedCost) return;
    const std::size_t i = costmap.index(col, row);
    if (distance[i] == 0) return;
    distance[i] = 0;
    queue_[tail++] = static_cast<std::uint32_t>(i);
  };
  if (from_path) {
    for (std::size_t i = window_begin_; i <= target_index_; ++i) seed(path_[i].x_m, path_[i].y_m);
  } else {
    seed(path_[target_index_].x_m, path_[target_index_].y_m);
  }
  const int w = costmap.width();
  const auto cells = costmap.cells();
  while (head < tail) {
    const std::uint32_t cur = queue_[head++];
    const auto next_d = static_cast<std::uint16_t>(distance[cur] + 1);
    const int c = static_cast<int>(cur % static_cast<std::uint32_t>(w));
    const std::size_t neighbours[4] = {c + 1 < w ? cur + 1 : cur, c > 0 ? cur - 1 : cur,
                                       cur + static_cast<std::size_t>(w) < n ? cur + static_cast<std::size_t>(w) : cur,
                                       cur >= static_cast<std::size_t>(w) ? cur - static_cast<std::size_t>(w) : cur};
    for (const std::size_t k : neighbours) {
      if (distance[k] != kUnreached || cells[k] >= kInscribedCost) continue;
      distance[k] = next_d;
      queue_[tail++] = static_cast<std::uint32_t>(k);
    }
  }
}

double DwaPlanner::grid_distance_m(std::span<const std::uint16_t> distance, const Costmap2D& costmap, double x_m,
                                    double y_m) const noexcept {
  int col = 0;
  int row = 0;
  if (!costmap.world_to_cell(x_m, y_m, col, row)) return kUnreachedPenaltyM;
  const std::uint16_t d = distance[costmap.index(col, row)];
  return d == kUnreached ? kUnreachedPenaltyM : d * costmap.resolution_m();
}

double DwaPlanner::distance_to_window(double x_m, double y_m) const noexcept {
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = window_begin_; i <= window_end_; ++i) {
    if (path_blocked_[i - window_begin_] != 0) continue;
    best = std::min(best, std::hypot(path_[i].x_m - x_m, path_[i].y_m - y_m));
  }
  return std::isfinite(best) ? best : 0.0;
}

void DwaPlanner::skip_blocked_part(const Costmap2D& costmap) noexcept {
  // Path points inside an obstacle the global plan did not know about cannot be tracked:
  // they do not count for the path distance, and the target moves past them (up to
  // blocked_lookahead_m farther along the path) so the rollouts are drawn around it.
  const auto blocked = [&](std::size_t i) {
    int col = 0;
    int row = 0;
    return costmap.world_to_cell(path_[i].x_m, path_[i].y_m, col, row) && costmap.at(col, row) >= kInscribedCost;
  };
  bool any = false;
  const std::size_t span = std::min(window_end_ - window_begin_ + 1, path_blocked_.size());
  for (std::size_t k = 0; k < span; ++k) {
    path_blocked_[k] = blocked(window_begin_ + k) ? 1 : 0;
    any = any || path_blocked_[k] != 0;
  }
  window_end_ = window_begin_ + span - 1;
  target_index_ = window_end_;
  window_blocked_ = any;
  if (!any) return;
  std::size_t i = window_end_;
  if (path_blocked_[span - 1] != 0) {  // the window ends inside the obstacle: look beyond it
    double extra = 0.0;
    while (i + 1 < path_count_ && extra < config_.blocked_lookahead_m) {
      extra += std::hypot(path_[i + 1].x_m - path_[i].x_m, path_[i + 1].y_m - path_[i].y_m);
      ++i;
      if (!blocked(i)) break;
    }
  }
  target_index_ = i;
}

double DwaPlanner::score_rollout(const Rollout& r, double v, const PathPoint& target, const Costmap2D& costmap) const noexcept {
  const double bearing = std::atan2(target.y_m - r.end.y_m, target.x_m - r.end.x_m);
  const double heading = 1.0 - std::abs(normalize_angle(bearing - r.end.theta_rad)) / std::numbers::pi;
  const double clearance = 1.0 - r.max_cost / static_cast<double>(kInscribedCost);
  const double velocity = v / config_.max_v_m_s;
  // While the window is blocked the LP is going around: only the target pulls.
  const double path_distance =
      window_blocked_ ? 0.0 : grid_distance_m(path_distance_, costmap, r.end.x_m, r.end.y_m) / config_.prune_distance_m;
  const double goal_distance = grid_distance_m(goal_distance_, costmap, r.end.x_m, r.end.y_m) / config_.prune_distance_m;
  return config_.heading_weight * heading + config_.clearance_weight * clearance + config_.velocity_weight * velocity -
         config_.path_weight * path_distance - config_.goal_weight * goal_distance;
}

void DwaPlanner::offer_refused(const Pose2D& pose, double v, double w, double score, double ttc, double ttc_braking,
                               MoverFallback& f) const noexcept {
  // Met whatever it does: the way (on, speeding up or braking) whose contact comes latest.
  // Speeding up is how a robot standing in a mover's way gets out of it; then, among equals,
  // the fastest, so that the robot does go through. Otherwise the slowest, so that if the
  // contact comes the robot is (nearly) standing.
  const double ttc_faster = v > 0.0 ? time_to_contact(pose, v, w, movers_, MoverMotion::speed_up) : ttc;
  const double latest = std::max({ttc, ttc_braking, ttc_faster});
  const double preference = ttc_faster >= std::max(ttc, ttc_braking) && ttc_faster > ttc ? v : -v;
  // First what would really touch (a graze of the margin is not a hit), then the margin.
  const auto touch = [&](MoverMotion motion) { return time_to_contact(pose, v, w, movers_, motion, MoverReach::touching); };
  const double hit_hold = touch(MoverMotion::hold);
  const double hit_brake = std::isfinite(hit_hold) && v != 0.0 ? touch(MoverMotion::brake) : hit_hold;
  const double hit_faster = v > 0.0 ? touch(MoverMotion::speed_up) : hit_hold;
  const double hit = std::max({hit_hold, hit_brake, hit_faster});
  // Some way of going on touches nothing: if holding or braking is that way, the usual score
  // picks; if only speeding up is, the fastest does.
  const int free_class = std::isinf(hit_hold) || std::isinf(hit_brake) ? 2 : std::isinf(hit_faster) ? 1 : 0;
  if (free_class > 0) {
    const double key = free_class == 2 ? score : v;
    if (free_class > f.free_class || (free_class == f.free_class && key > f.free_key)) {
      f.free_class = free_class;
      f.free_key = key;
      f.free_v = v;
      f.free_w = w;
    }
  }
  const bool later = hit > f.escape_hit || (hit == f.escape_hit && latest > f.escape_ttc);
  const bool as_late = hit == f.escape_hit && latest == f.escape_ttc;
  if (later || (as_late && preference > f.escape_preference) ||
      (as_late && preference == f.escape_preference && score > f.escape_score)) {
    f.escape_hit = hit;
    f.escape_ttc = latest;
    f.escape_score = score;
    f.escape_preference = preference;
    f.escape_v = v;
    f.escape_w = w;
  }
}

DwaCommand DwaPlanner::compute(const Pose2D& pose, double v_m_s, double w_rad_s, const Costmap2D& costmap,
                               std::span<const msg::MovingObstacle> movers) noexcept {
  DwaCommand out;
  if (path_count_ == 0) return out;
  const PathPoint goal = path_[path_count_ - 1];
  out.distance_to_goal_m = std::hypot(goal.x_m - pose.x_m, goal.y_m - pose.y_m);
  if (out.distance_to_goal_m <= config_.goal_tolerance_m) {
    out.status = DwaStatus::reached;
    return out;
  }
  if (recovery_state_ == DwaStatus::failed) {
    out.status = DwaStatus::failed;
    return out;
  }
  update_window(pose);
  skip_blocked_part(costmap);
  // Already within the padding of something (the robot squeezed past it, or it came closer):
  // the padded outline would reject every move, even away from it, so this cycle checks the
  // bare footprint. The clearance term still prefers moving away.
  escaping_ = outline_hits(pose, costmap, padded_);
  check_ = escaping_ ? bare_ : padded_;

  const double dt = config_.control_period_s;
  const double v_cap = std::min(config_.max_v_m_s, config_.max_v_m_s * std::max(0.1, out.distance_to_goal_m / config_.slow_down_radius_m));
  double v_lo = std::max(0.0, v_m_s - config_.acc_v_m_s2 * dt);
  double v_hi = std::min(v_cap, v_m_s + config_.acc_v_m_s2 * dt);
  if (v_hi < v_lo) v_lo = v_hi = std::max(0.0, std::min(v_cap, v_lo));  // over the cap: brake
  const double w_lo = std::max(-config_.max_w_rad_s, w_rad_s - config_.acc_w_rad_s2 * dt);
  const double w_hi = std::min(config_.max_w_rad_s, w_rad_s + config_.acc_w_rad_s2 * dt);
  const PathPoint target = path_[target_index_];
  if (costmap.size() > goal_distance_.size()) {
    out.status = DwaStatus::failed;  // a costmap larger than init() sized for: a configuration error
    return out;
  }
  wavefront(costmap, goal_distance_, false);
  if (!window_blocked_) wavefront(costmap, path_distance_, true);

  if (!config_.mover_prediction) movers = {};
  movers_ = movers;
  double best_score = -std::numeric_limits<double>::infinity();
  MoverFallback fallback;
  bool movers_cost_progress = false;  // a moving rollout was refused or penalised for a mover
  for (int i = 0; i < config_.v_samples; ++i) {
    const double v = config_.v_samples == 1 ? v_hi : v_lo + (v_hi - v_lo) * i / (config_.v_samples - 1);
    for (int j = 0; j < config_.w_samples; ++j) {
      const double w = config_.w_samples == 1 ? 0.0 : w_lo + (w_hi - w_lo) * j / (config_.w_samples - 1);
      ++out.evaluated;
      const Rollout r = roll_out(pose, v, w, costmap);
      if (!r.admissible) continue;
      ++out.admissible;
      double score = score_rollout(r, v, target, costmap);
      if (!movers.empty()) {
        const double ttc = time_to_contact(pose, v, w, movers);
        const bool moving = v >= config_.min_progress_v_m_s;
        const double ttc_braking =
            std::isfinite(ttc) && v != 0.0 ? time_to_contact(pose, v, w, movers, MoverMotion::brake) : ttc;
        if (std::isfinite(ttc_braking)) {  // even braking meets it: unavoidable on this arc
          ++out.mover_rejected;
          movers_cost_progress = movers_cost_progress || moving;
          offer_refused(pose, v, w, score, ttc, ttc_braking, fallback);
          continue;
        }
        if (std::isfinite(ttc)) {
          score -= config_.mover_weight * (1.0 - ttc / config_.mover_horizon_s);
          movers_cost_progress = movers_cost_progress || moving;
        }
      }
      if (score > best_score) {  // strict: the first best sample wins ties
        best_score = score;
        out.v_m_s = v;
        out.w_rad_s = w;
      }
    }
  }
  // Standing still, or turning on the spot while already facing the target, is not progress:
  // then recover instead of spinning in front of an obstacle.
  const double target_bearing =
      std::abs(normalize_angle(std::atan2(target.y_m - pose.y_m, target.x_m - pose.x_m) - pose.theta_rad));
  const bool refused_all = out.admissible > 0 && out.admissible == out.mover_rejected;
  if (refused_all) {  // every way meets a mover soon: the one that meets it latest
    out.v_m_s = fallback.free_class > 0 ? fallback.free_v : fallback.escape_v;
    out.w_rad_s = fallback.free_class > 0 ? fallback.free_w : fallback.escape_w;
  }
  // Turning on the spot among movers swings the body's corners out: not into a mover's way
  // when standing still keeps out of it.
  if (out.v_m_s < config_.min_progress_v_m_s && out.w_rad_s != 0.0 && w_lo <= 0.0 && w_hi >= 0.0 &&
      meets_mover(pose, out.v_m_s, out.w_rad_s) && !meets_mover(pose, 0.0, 0.0)) {
    out.w_rad_s = 0.0;
  }
  const bool progress = out.v_m_s >= config_.min_progress_v_m_s ||
                        (out.w_rad_s != 0.0 && target_bearing > config_.align_angle_rad);
  if (out.admissible > 0 && progress && !refused_all) {
    out.status = DwaStatus::tracking;
    recovery_state_ = DwaStatus::tracking;
    recovery_cycles_ = 0;
    yield_ticks_ = 0;
    return out;
  }
  // Among movers, nothing admissible at this speed (the window holds only fast arcs) while
  // the robot can still stop clear of everything: brake as hard as the window allows and
  // choose again from lower speed, rather than give up. (Among still obstacles the recoveries
  // keep their old timing.)
  if (out.admissible == 0 && !movers.empty() && v_m_s >= config_.min_progress_v_m_s &&
      braking_is_clear(pose, v_m_s, w_rad_s, costmap)) {
    out.v_m_s = v_lo;
    out.w_rad_s = std::clamp(0.0, w_lo, w_hi);
    out.status = DwaStatus::braking;
    recovery_state_ = DwaStatus::tracking;
    return out;
  }
  // Held back by movers, not by the map: let them pass (a while) instead of recovering.
  if (out.admissible > 0 && movers_cost_progress &&
      yield_ticks_ < static_cast<int>(std::lround(config_.max_yield_s / dt))) {
    ++yield_ticks_;
    out.status = DwaStatus::yielding;
    recovery_state_ = DwaStatus::tracking;
    return out;
  }
  out.v_m_s = 0.0;
  out.w_rad_s = 0.0;
  return recover(pose, costmap, out);
}

DwaCommand DwaPlanner::recover(const Pose2D& pose, const Costmap2D& costmap, DwaCommand out) noexcept {
  const double dt = config_.control_period_s;
  const auto ticks_for = [&](double seconds) { return std::max(1, static_cast<int>(std::lround(seconds / dt))); };
  const auto enter = [&](DwaStatus state) {
    recovery_state_ = state;
    recovery_ticks_ = 0;
    if (state == DwaStatus::waiting) ++recoveries_.waits;
    if (state == DwaStatus::rotating) ++recoveries_.rotations;
    if (state == DwaStatus::backing_off) ++recoveries_.backoffs;
  };
  // The turn or the back-off would swing into a mover's way: stand instead, this period.
  const auto stand_for_movers = [&] {
    held_by_movers_ = true;
    out.status = DwaStatus::waiting;
    out.v_m_s = 0.0;
    out.w_rad_s = 0.0;
    return out;
  };
  if (recovery_state_ == DwaStatus::tracking) enter(DwaStatus::waiting);
  for (int guard = 0; guard < 4; ++guard) {
    ++recovery_ticks_;
    switch (recovery_state_) {
      case DwaStatus::waiting:
        if (recovery_ticks_ <= ticks_for(config_.wait_s)) {
          out.status = DwaStatus::waiting;
          out.v_m_s = 0.0;
          out.w_rad_s = 0.0;
          return out;
        }
        enter(DwaStatus::rotating);
        continue;
      case DwaStatus::rotating: {
        const PathPoint target = path_[target_index_];
        const double bearing = normalize_angle(std::atan2(target.y_m - pose.y_m, target.x_m - pose.x_m) - pose.theta_rad);
        const double w = bearing >= 0.0 ? config_.rotate_w_rad_s : -config_.rotate_w_rad_s;
        const Pose2D ahead{pose.x_m, pose.y_m, pose.theta_rad + w * dt * 3.0};
        if (recovery_ticks_ <= ticks_for(config_.rotate_s) && meets_mover(pose, 0.0, w)) return stand_for_movers();
        if (recovery_ticks_ <= ticks_for(config_.rotate_s) && !outline_hits(ahead, costmap, check_)) {
          out.status = DwaStatus::rotating;
          out.v_m_s = 0.0;
          out.w_rad_s = w;
          return out;
        }
        enter(DwaStatus::backing_off);
        continue;
      }
      case DwaStatus::backing_off: {
        const double back = config_.backoff_v_m_s * dt * 3.0;
        const Pose2D behind{pose.x_m + back * std::cos(pose.theta_rad), pose.y_m + back * std::sin(pose.theta_rad), pose.theta_rad};
        if (recovery_ticks_ <= ticks_for(config_.backoff_s) && meets_mover(pose, config_.backoff_v_m_s, 0.0))
          return stand_for_movers();
        if (recovery_ticks_ <= ticks_for(config_.backoff_s) && !outline_hits(behind, costmap, check_)) {
          out.status = DwaStatus::backing_off;
          out.v_m_s = config_.backoff_v_m_s;
          out.w_rad_s = 0.0;
          return out;
        }
        // A cycle that movers held back is not a failure of the way: it does not count.
        if (!std::exchange(held_by_movers_, false) && ++recovery_cycles_ >= config_.max_recovery_cycles) {
          recovery_state_ = DwaStatus::failed;
          out.status = DwaStatus::failed;
          out.v_m_s = 0.0;
          out.w_rad_s = 0.0;
          return out;
        }
        // Back to sampling: the next compute() tries the window again before waiting.
        recovery_state_ = DwaStatus::tracking;
        out.status = DwaStatus::waiting;
        out.v_m_s = 0.0;
        out.w_rad_s = 0.0;
        return out;
      }
      default:
        enter(DwaStatus::waiting);
        continue;
    }
  }
  out.v_m_s = 0.0;
  out.w_rad_s = 0.0;
  return out;
}

}  // namespace sen3bot::nav
