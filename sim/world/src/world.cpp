#include "sen3bot/world/world.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sen3bot/msg/point_math.hpp"

namespace sen3bot::world {
namespace {

struct Polygon {
  std::array<Point2D, Footprint::kMaxVertices> points{};
  std::size_t count = 0;
};

Polygon place(const Footprint& footprint, const Pose2D& pose) {
  Polygon p;
  const double c = std::cos(pose.theta_rad);
  const double s = std::sin(pose.theta_rad);
  for (std::size_t i = 0; i < footprint.vertex_count; ++i) {
    const Point2D v = footprint.vertices[i];
    p.points[i] = {pose.x_m + c * v.x_m - s * v.y_m, pose.y_m + s * v.x_m + c * v.y_m};
  }
  p.count = footprint.vertex_count;
  return p;
}

// Distance from q to the placed footprint (0 inside).
double polygon_distance(const Polygon& poly, Point2D q) {
  return msg::convex_polygon_distance({poly.points.data(), poly.count}, q);
}

// Separating-axis test between a convex polygon and an axis-aligned box.
bool overlaps_box(const Polygon& poly, double min_x, double min_y, double max_x, double max_y) {
  double pminx = std::numeric_limits<double>::infinity();
  double pmaxx = -pminx;
  double pminy = pminx;
  double pmaxy = -pminx;
  for (std::size_t i = 0; i < poly.count; ++i) {
    pminx = std::min(pminx, poly.points[i].x_m);
    pmaxx = std::max(pmaxx, poly.points[i].x_m);
    pminy = std::min(pminy, poly.points[i].y_m);
    pmaxy = std::max(pmaxy, poly.points[i].y_m);
  }
  if (pmaxx <= min_x || pminx >= max_x || pmaxy <= min_y || pminy >= max_y) return false;
  const Point2D corners[4] = {{min_x, min_y}, {max_x, min_y}, {max_x, max_y}, {min_x, max_y}};
  for (std::size_t i = 0; i < poly.count; ++i) {
    const Point2D a = poly.points[i];
    const Point2D b = poly.points[(i + 1) % poly.count];
    const double nx = b.y_m - a.y_m;
    const double ny = a.x_m - b.x_m;
    double lo_p = std::numeric_limits<double>::infinity();
    double hi_p = -lo_p;
    for (std::size_t k = 0; k < poly.count; ++k) {
      const double v = nx * poly.points[k].x_m + ny * poly.points[k].y_m;
      lo_p = std::min(lo_p, v);
      hi_p = std::max(hi_p, v);
    }
    double lo_b = std::numeric_limits<double>::infinity();
    double hi_b = -lo_b;
    for (const Point2D& c : corners) {
      const double v = nx * c.x_m + ny * c.y_m;
      lo_b = std::min(lo_b, v);
      hi_b = std::max(hi_b, v);
    }
    if (hi_p <= lo_b || hi_b <= lo_p) return false;
  }
  return true;
}

double box_point_distance(double min_x, double min_y, double max_x, double max_y, Point2D q) {
  const double dx = std::max({min_x - q.x_m, 0.0, q.x_m - max_x});
  const double dy = std::max({min_y - q.y_m, 0.0, q.y_m - max_y});
  return std::hypot(dx, dy);
}

// Distance along a ray from (ox, oy) in direction (dx, dy) (unit) to a circle, or +inf.
double ray_circle(double ox, double oy, double dx, double dy, Point2D c, double r) {
  const double fx = ox - c.x_m;
  const double fy = oy - c.y_m;
  const double b = fx * dx + fy * dy;
  const double cc = fx * fx + fy * fy - r * r;
  if (cc <= 0.0) return 0.0;  // the origin is inside
  const double disc = b * b - cc;
  if (disc < 0.0) return std::numeric_limits<double>::infinity();
  const double t = -b - std::sqrt(disc);
  return t >= 0.0 ? t : std::numeric_limits<double>::infinity();
}

// Slab test of a ray against an axis-aligned box, or +inf.
double ray_box(double ox, double oy, double dx, double dy, double min_x, double min_y, double max_x, double max_y) {
  double t0 = 0.0;
  double t1 = std::numeric_limits<double>::infinity();
  const double o[2] = {ox, oy};
  const double d[2] = {dx, dy};
  const double lo[2] = {min_x, min_y};
  const double hi[2] = {max_x, max_y};
  for (int k = 0; k < 2; ++k) {
    if (std::abs(d[k]) < 1e-15) {
      if (o[k] < lo[k] || o[k] > hi[k]) return std::numeric_limits<double>::infinity();
      continue;
    }
    double ta = (lo[k] - o[k]) / d[k];
    double tb = (hi[k] - o[k]) / d[k];
    if (ta > tb) std::swap(ta, tb);
    t0 = std::max(t0, ta);
    t1 = std::min(t1, tb);
    if (t0 > t1) return std::numeric_limits<double>::infinity();
  }
  return t0;
}

}  // namespace

World::World(const nav::OccupancyMap& map, WorldConfig config) : map_(map), config_(config), rng_(config.seed) {}

std::size_t World::add_mover(const MoverScript& script) {
  Mover m;
  m.script = script;
  if (m.script.path.empty()) m.script.path.push_back({0.0, 0.0});
  double total = 0.0;
  m.cumulative_m.push_back(0.0);
  const std::size_t n = m.script.path.size();
  const std::size_t edges = m.script.loop && n > 1 ? n : n - 1;
  for (std::size_t i = 0; i < edges; ++i) {
    const Point2D a = m.script.path[i];
    const Point2D b = m.script.path[(i + 1) % n];
    total += std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
    m.cumulative_m.push_back(total);
  }
  m.position = position_at(m, time_s_);
  m.visible = time_s_ >= m.script.appear_time_s && time_s_ < m.script.vanish_time_s;
  movers_.push_back(std::move(m));
  return movers_.size() - 1;
}

void World::extend_timeline(std::size_t index, Point2D at, double time_s) {
  MoverScript& script = movers_[index].script;
  if (!script.times_s.empty() && !(time_s > script.times_s.back())) return;
  script.timeline.push_back(at);
  script.times_s.push_back(time_s);
  movers_[index].position = position_at(movers_[index], time_s_);
}

Point2D World::position_at(const Mover& mover, double time_s) noexcept {
  const auto& timeline = mover.script.timeline;
  const auto& times = mover.script.times_s;
  if (!timeline.empty() && times.size() == timeline.size()) {
    if (time_s <= times.front()) return timeline.front();
    // A timeline grows as a run goes on (a teammate's every 50 ms): found by bisection.
    const auto after = std::lower_bound(times.begin(), times.end(), time_s);
    if (after == times.end()) return timeline.back();
    const auto i = static_cast<std::size_t>(after - times.begin());
    const double span = times[i] - times[i - 1];
    const double f = span > 0.0 ? (time_s - times[i - 1]) / span : 1.0;
    return {timeline[i - 1].x_m + f * (timeline[i].x_m - timeline[i - 1].x_m),
            timeline[i - 1].y_m + f * (timeline[i].y_m - timeline[i - 1].y_m)};
  }
  const auto& path = mover.script.path;
  const double total = mover.cumulative_m.back();
  if (path.size() < 2 || mover.script.speed_m_s <= 0.0 || total <= 0.0) return path.front();
  const double v = mover.script.speed_m_s;
  const double walked = std::max(0.0, time_s - mover.script.start_time_s) * v + std::max(0.0, mover.script.phase_m);
  const double accel = mover.script.accel_m_s2;
  double s = 0.0;
  if (!mover.script.loop && accel > 0.0) {
    // Each leg: speed up at a, walk, slow down at a (a triangle when the leg is too short to
    // reach full speed). The phase counts as time at full speed.
    double ramp_s = v / accel;
    double top = v;
    if (top * ramp_s > total) {
      ramp_s = std::sqrt(total / accel);
      top = accel * ramp_s;
    }
    const double ramp_m = 0.5 * top * ramp_s;
    const double leg_s = 2.0 * ramp_s + (total - 2.0 * ramp_m) / top;
    double tau = std::fmod(walked / v, 2.0 * leg_s);
    const bool back = tau > leg_s;
    if (back) tau -= leg_s;
    if (tau < ramp_s) {
      s = 0.5 * accel * tau * tau;
    } else if (tau > leg_s - ramp_s) {
      const double left = leg_s - tau;
      s = total - 0.5 * accel * left * left;
    } else {
      s = ramp_m + top * (tau - ramp_s);
    }
    s = std::clamp(s, 0.0, total);
    if (back) s = total - s;
  } else if (mover.script.loop) {
    s = std::fmod(walked, total);
  } else {
    s = std::fmod(walked, 2.0 * total);
    if (s > total) s = 2.0 * total - s;  // walking back
  }
  const auto it = std::upper_bound(mover.cumulative_m.begin(), mover.cumulative_m.end(), s);
  std::size_t edge = static_cast<std::size_t>(std::distance(mover.cumulative_m.begin(), it));
  edge = edge == 0 ? 0 : edge - 1;
  edge = std::min(edge, mover.cumulative_m.size() - 2);
  const Point2D a = path[edge];
  const Point2D b = path[(edge + 1) % path.size()];
  const double len = mover.cumulative_m[edge + 1] - mover.cumulative_m[edge];
  const double t = len > 0.0 ? (s - mover.cumulative_m[edge]) / len : 0.0;
  return {a.x_m + t * (b.x_m - a.x_m), a.y_m + t * (b.y_m - a.y_m)};
}

void World::set_time(double time_s) noexcept {
  const double dt = time_s - time_s_;
  time_s_ = time_s;
  for (Mover& m : movers_) {
    if (!m.script.driven) {
      const Point2D was = m.position;
      m.position = position_at(m, time_s);
      m.visible = time_s >= m.script.appear_time_s && time_s < m.script.vanish_time_s;
      if (dt > 0.0) m.velocity = (1.0 / dt) * (m.position - was);
    }
    if (m.script.legs && dt > 0.0) crowd::advance(m.gait, m.velocity, dt);
  }
}

void World::place_mover(std::size_t index, Point2D position, Point2D velocity, bool visible) noexcept {
  Mover& m = movers_[index];
  m.position = position;
  m.velocity = velocity;
  m.visible = visible;
}

std::array<Point2D, 2> World::mover_legs(std::size_t index) const noexcept {
  const Mover& m = movers_[index];
  return crowd::leg_centres(m.position, m.gait, msg::norm(m.velocity));
}

bool World::solid(int col, int row) const noexcept {
  return map_.in_bounds(col, row) && map_.at(col, row) >= config_.occupied_threshold;
}

double World::ray_to_map(double x_m, double y_m, double dx, double dy, double max_range_m) const noexcept {
  // Work in grid units: rotate the direction into the grid frame.
  double gx = 0.0;
  double gy = 0.0;
  map_.world_to_grid(x_m, y_m, gx, gy);
  const double yaw = map_.origin_yaw_rad();
  const double gdx = std::cos(yaw) * dx + std::sin(yaw) * dy;
  const double gdy = -std::sin(yaw) * dx + std::cos(yaw) * dy;
  const double res = map_.resolution_m();
  const double max_t = max_range_m / res;
  int col = static_cast<int>(std::floor(gx));
  int row = static_cast<int>(std::floor(gy));
  if (solid(col, row)) return 0.0;
  const int step_c = gdx > 0 ? 1 : -1;
  const int step_r = gdy > 0 ? 1 : -1;
  const double inf = std::numeric_limits<double>::infinity();
  const double delta_c = gdx != 0.0 ? std::abs(1.0 / gdx) : inf;
  const double delta_r = gdy != 0.0 ? std::abs(1.0 / gdy) : inf;
  double next_c = gdx != 0.0 ? ((gdx > 0 ? (col + 1 - gx) : (gx - col)) * delta_c) : inf;
  double next_r = gdy != 0.0 ? ((gdy > 0 ? (row + 1 - gy) : (gy - row)) * delta_r) : inf;
  for (;;) {
    double t = 0.0;
    if (next_c < next_r) {
      t = next_c;
      next_c += delta_c;
      col += step_c;
    } else {
      t = next_r;
      next_r += delta_r;
      row += step_r;
    }
    if (t >= max_t) return max_range_m;
    // Outside the map nothing is solid; stop once the ray has left it for good.
    if (!map_.in_bounds(col, row) &&
        ((col < 0 && step_c < 0) || (row < 0 && step_r < 0) || (col >= map_.width() && step_c > 0) ||
         (row >= map_.height() && step_r > 0))) {
      return max_range_m;
    }
    if (solid(col, row)) return t * res;
  }
}

double World::cast_ray(double x_m, double y_m, double angle_rad, double max_range_m) const noexcept {
  const double dx = std::cos(angle_rad);
  const double dy = std::sin(angle_rad);
  double best = ray_to_map(x_m, y_m, dx, dy, max_range_m);
  for (const Mover& m : movers_) {
    if (!m.visible) continue;
    const double half = m.script.size_m / 2.0;
    double t = 0.0;
    if (m.script.legs) {
      const std::array<Point2D, 2> legs = crowd::leg_centres(m.position, m.gait, msg::norm(m.velocity));
      t = std::min(ray_circle(x_m, y_m, dx, dy, legs[0], crowd::kLegRadiusM),
                   ray_circle(x_m, y_m, dx, dy, legs[1], crowd::kLegRadiusM));
    } else if (m.script.shape == MoverShape::circle) {
      t = ray_circle(x_m, y_m, dx, dy, m.position, half);
    } else {
      t = ray_box(x_m, y_m, dx, dy, m.position.x_m - half, m.position.y_m - half, m.position.x_m + half,
                  m.position.y_m + half);
    }
    best = std::min(best, t);
  }
  return std::min(best, max_range_m);
}

void World::scan(const Pose2D& sensor, double angle_min_rad, double increment_rad, std::size_t count,
                 double max_range_m, std::span<float> ranges_m) const noexcept {
  const std::size_t n = std::min(count, ranges_m.size());
  for (std::size_t i = 0; i < n; ++i) {
    const double angle = sensor.theta_rad + angle_min_rad + static_cast<double>(i) * increment_rad;
    ranges_m[i] = static_cast<float>(cast_ray(sensor.x_m, sensor.y_m, angle, max_range_m));
  }
}

void World::noisy_scan(const Pose2D& sensor, double angle_min_rad, double increment_rad, std::size_t count,
                       double max_range_m, std::span<float> ranges_m) noexcept {
  scan(sensor, angle_min_rad, increment_rad, count, max_range_m, ranges_m);
  if (config_.range_noise_sigma_m <= 0.0) return;
  std::normal_distribution<double> noise(0.0, config_.range_noise_sigma_m);
  const std::size_t n = std::min(count, ranges_m.size());
  for (std::size_t i = 0; i < n; ++i) {
    const double sample = noise(rng_);
    if (ranges_m[i] >= max_range_m) continue;  // no return stays no return
    ranges_m[i] = static_cast<float>(std::clamp(ranges_m[i] + sample, 0.0, max_range_m));
  }
}

bool World::collides(const Pose2D& pose, const Footprint& footprint) const noexcept {
  return touches_map(pose, footprint) || touching_mover(pose, footprint) >= 0;
}

bool World::touches_map(const Pose2D& pose, const Footprint& footprint) const noexcept {
  const double res = map_.resolution_m();
  const double reach = footprint.circumscribed_radius_m();
  const bool is_circle = footprint.vertex_count == 0;
  // Map cells, tested in the grid frame (cells are unit squares there).
  double gx = 0.0;
  double gy = 0.0;
  map_.world_to_grid(pose.x_m, pose.y_m, gx, gy);
  const Pose2D grid_pose{gx, gy, pose.theta_rad - map_.origin_yaw_rad()};
  Footprint grid_fp = footprint;
  for (std::size_t i = 0; i < grid_fp.vertex_count; ++i) {
    grid_fp.vertices[i].x_m /= res;
    grid_fp.vertices[i].y_m /= res;
  }
  const Polygon grid_poly = place(grid_fp, grid_pose);
  const double reach_cells = reach / res;
  const int c0 = static_cast<int>(std::floor(gx - reach_cells));
  const int c1 = static_cast<int>(std::floor(gx + reach_cells));
  const int r0 = static_cast<int>(std::floor(gy - reach_cells));
  const int r1 = static_cast<int>(std::floor(gy + reach_cells));
  for (int r = r0; r <= r1; ++r) {
    for (int c = c0; c <= c1; ++c) {
      if (!map_.in_bounds(c, r)) {
        // Leaving the map counts as a collision only if the body really overlaps outside.
        const bool hit = is_circle ? box_point_distance(c, r, c + 1, r + 1, {gx, gy}) < reach_cells
                                   : overlaps_box(grid_poly, c, r, c + 1, r + 1);
        if (hit) return true;
        continue;
      }
      if (!solid(c, r)) continue;
      const bool hit = is_circle ? box_point_distance(c, r, c + 1, r + 1, {gx, gy}) < reach_cells
                                 : overlaps_box(grid_poly, c, r, c + 1, r + 1);
      if (hit) return true;
    }
  }
  return false;
}

bool World::robot_closing(const Pose2D& pose, const Footprint& footprint, double v_m_s,
                          double min_speed_m_s) const noexcept {
  if (std::abs(v_m_s) <= min_speed_m_s) return false;
  const int mover = touching_mover(pose, footprint);
  if (mover < 0 || touches_map(pose, footprint)) return true;
  const Point2D at = movers_[static_cast<std::size_t>(mover)].position;
  const double dx = at.x_m - pose.x_m;
  const double dy = at.y_m - pose.y_m;
  const double d = std::hypot(dx, dy);
  if (!(d > 0.0)) return true;
  return v_m_s * (std::cos(pose.theta_rad) * dx + std::sin(pose.theta_rad) * dy) / d > min_speed_m_s;
}

int World::touching_mover(const Pose2D& pose, const Footprint& footprint) const noexcept {
  const double reach = footprint.circumscribed_radius_m();
  const bool is_circle = footprint.vertex_count == 0;
  const Polygon poly = place(footprint, pose);  // map frame
  for (std::size_t i = 0; i < movers_.size(); ++i) {
    const Mover& m = movers_[i];
    if (!m.visible) continue;
    const double half = m.script.size_m / 2.0;
    const Point2D p = m.position;
    bool hit = false;
    if (m.script.shape == MoverShape::circle) {
      const double d = is_circle ? std::hypot(p.x_m - pose.x_m, p.y_m - pose.y_m) - reach : polygon_distance(poly, p);
      hit = d < half;
    } else {
      hit = is_circle ? box_point_distance(p.x_m - half, p.y_m - half, p.x_m + half, p.y_m + half,
                                           {pose.x_m, pose.y_m}) < reach
                      : overlaps_box(poly, p.x_m - half, p.y_m - half, p.x_m + half, p.y_m + half);
    }
    if (hit) return static_cast<int>(i);
  }
  return -1;
}

double World::clearance_m(const Pose2D& pose, const Footprint& footprint, double limit_m) const noexcept {
  const bool is_circle = footprint.vertex_count == 0;
  const Polygon poly = place(footprint, pose);
  const auto distance_to = [&](Point2D q) {
    return is_circle ? std::max(0.0, std::hypot(q.x_m - pose.x_m, q.y_m - pose.y_m) - footprint.circle_radius_m)
                     : polygon_distance(poly, q);
  };
  double best = limit_m;
  const double res = map_.resolution_m();
  const double reach = footprint.circumscribed_radius_m() + limit_m;
  int cc = 0;
  int cr = 0;
  map_.world_to_cell(pose.x_m, pose.y_m, cc, cr);
  const int span = static_cast<int>(std::ceil(reach / res)) + 1;
  for (int r = cr - span; r <= cr + span; ++r) {
    for (int c = cc - span; c <= cc + span; ++c) {
      if (!solid(c, r)) continue;
      Point2D q;
      map_.cell_to_world(c, r, q.x_m, q.y_m);
      best = std::min(best, std::max(0.0, distance_to(q) - res / 2.0));
    }
  }
  for (const Mover& m : movers_) {
    if (!m.visible) continue;
    best = std::min(best, std::max(0.0, distance_to(m.position) - m.script.size_m / 2.0));
  }
  return best;
}

}  // namespace sen3bot::world
