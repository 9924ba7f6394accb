#include "sen3bot/crowd/orca.hpp"

#include <algorithm>
#include <array>
#include <cmath>

namespace sen3bot::crowd {
namespace {

using Planes = std::array<OrcaHalfPlane, kMaxOrcaNeighbors>;

// How far v breaks the half-plane (negative inside).
double violation(const OrcaHalfPlane& h, Point2D v) noexcept { return -dot(v - h.point, h.normal); }

// What the 2D program optimises: the velocity nearest `target`, or, when `along` is a unit
// vector, the one furthest along it (on a line square to `along`, where every point is as far,
// the one nearest `target`).
struct Objective {
  Point2D target;
  Point2D along;
};

// The best point on plane i's line that keeps the planes before it and the speed circle; false
// when that part of the line is empty.
bool best_on_line(std::span<const OrcaHalfPlane> planes, std::size_t i, double max_speed, const Objective& goal,
                  Point2D& result) noexcept {
  const Point2D q = planes[i].point;
  const Point2D d = perpendicular(planes[i].normal);  // the line is q + t d
  const double qd = dot(q, d);
  const double disc = qd * qd + max_speed * max_speed - norm_squared(q);
  if (disc < 0.0) return false;  // the line misses the speed circle
  const double s = std::sqrt(disc);
  double lo = -qd - s;
  double hi = -qd + s;
  for (std::size_t j = 0; j < i; ++j) {
    // (q + t d - point_j) . n_j >= 0  <=>  t (d . n_j) >= (point_j - q) . n_j
    const double denom = dot(d, planes[j].normal);
    const double numer = dot(planes[j].point - q, planes[j].normal);
    if (std::abs(denom) < 1e-12) {
      if (numer > 0.0) return false;  // parallel and the whole line is outside
      continue;
    }
    if (denom > 0.0) {
      lo = std::max(lo, numer / denom);
    } else {
      hi = std::min(hi, numer / denom);
    }
    if (lo > hi) return false;
  }
  const double slope = dot(goal.along, d);
  const double t = std::abs(slope) > 1e-12 ? (slope > 0.0 ? hi : lo) : std::clamp(dot(goal.target - q, d), lo, hi);
  result = q + t * d;
  return true;
}

// Incremental 2D program: starts from the optimum inside the speed circle alone and, for each
// plane the answer breaks, moves it onto that plane's line. Returns planes.size() on success,
// else the index of the first plane that cannot be met (result then meets the ones before it).
std::size_t solve_2d(std::span<const OrcaHalfPlane> planes, double max_speed, const Objective& goal,
                     Point2D& result) noexcept {
  if (norm_squared(goal.along) > 0.0) {
    result = max_speed * goal.along;
  } else if (norm_squared(goal.target) > max_speed * max_speed) {
    result = max_speed * unit_or(goal.target, {});
  } else {
    result = goal.target;
  }
  for (std::size_t i = 0; i < planes.size(); ++i) {
    if (violation(planes[i], result) <= 0.0) continue;
    const Point2D kept = result;
    if (!best_on_line(planes, i, max_speed, goal, result)) {
      result = kept;
      return i;
    }
  }
  return planes.size();
}

// 3D program in (v, d): minimise d with every plane relaxed by d, starting where the 2D program
// failed (planes before `first` are met, d = 0). A plane broken by more than the current d holds
// the new optimum on its relaxed boundary, (v - point_i) . n_i = -d; there, plane j relaxed by the
// same d reads v . (n_j - n_i) >= point_j . n_j - point_i . n_i, and minimising d is going as far
// along n_i as the circle and those planes allow: a 2D program with a direction objective.
// Ties go to the point nearest the preferred velocity.
void solve_3d(std::span<const OrcaHalfPlane> planes, std::size_t first, double max_speed, Point2D preferred,
              Point2D& result) noexcept {
  double worst = 0.0;
  for (std::size_t i = first; i < planes.size(); ++i) {
    if (violation(planes[i], result) <= worst) continue;
    const OrcaHalfPlane& pi = planes[i];
    Planes projected;
    std::size_t count = 0;
    for (std::size_t j = 0; j < i; ++j) {
      const Point2D m = planes[j].normal - pi.normal;
      const double m2 = norm_squared(m);
      // Same direction: on plane i's boundary plane j is broken less than i, so it never binds.
      if (m2 < 1e-18) continue;
      const double c = dot(planes[j].point, planes[j].normal) - dot(pi.point, pi.normal);
      projected[count++] = {(c / m2) * m, (1.0 / std::sqrt(m2)) * m, {}};
    }
    const Point2D kept = result;
    // Only rounding can make this fail (the previous answer is feasible for it); keep that one.
    if (solve_2d({projected.data(), count}, max_speed, {preferred, pi.normal}, result) < count) result = kept;
    worst = violation(pi, result);
  }
}

// The nearest candidates within range, sorted; equal distances stay in the order offered.
class Nearest {
 public:
  Nearest(std::size_t limit, double range_m) noexcept
      : limit_(std::min(limit, kMaxOrcaNeighbors)), range2_(range_m * range_m) {}

  void offer(double dist2, std::size_t index) noexcept {
    if (limit_ == 0 || dist2 >= range2_) return;
    if (count_ == limit_ && dist2 >= entries_[count_ - 1].dist2) return;
    std::size_t k = count_ < limit_ ? count_++ : count_ - 1;
    for (; k > 0 && entries_[k - 1].dist2 > dist2; --k) entries_[k] = entries_[k - 1];
    entries_[k] = {dist2, index};
  }
  [[nodiscard]] std::size_t size() const noexcept { return count_; }
  [[nodiscard]] std::size_t index(std::size_t k) const noexcept { return entries_[k].index; }

 private:
  struct Entry {
    double dist2;
    std::size_t index;
  };
  std::array<Entry, kMaxOrcaNeighbors> entries_{};
  std::size_t count_ = 0;
  std::size_t limit_;
  double range2_;
};

// The velocity for `self` among the chosen neighbours (at most kMaxOrcaNeighbors), every radius
// padded.
Point2D solve_among(const OrcaAgent& self, std::span<const OrcaNeighbor> chosen, const OrcaParams& params,
                    double dt) noexcept {
  OrcaAgent padded = self;
  padded.radius_m += params.radius_padding_m;
  Planes planes;
  for (std::size_t k = 0; k < chosen.size(); ++k) {
    OrcaNeighbor b = chosen[k];
    b.radius_m += params.radius_padding_m;
    planes[k] = orca_half_plane(padded, b, params.time_horizon_s, dt);
  }
  return solve_velocity({planes.data(), chosen.size()}, self.preferred_velocity, self.max_speed_m_s);
}

}  // namespace

OrcaHalfPlane orca_half_plane(const OrcaAgent& self, const OrcaNeighbor& other, double time_horizon_s,
                              double dt) noexcept {
  const Point2D p = other.position - self.position;
  const Point2D v = self.velocity - other.velocity;
  const double r = self.radius_m + other.radius_m;
  const double p2 = norm_squared(p);
  Point2D n;
  Point2D u;
  if (p2 > r * r) {
    const double tau = time_horizon_s;
    const Point2D w = v - (1.0 / tau) * p;  // from the centre of the cut-off disc
    const double wp = dot(w, p);
    // The cut-off arc is nearest when w points at the origin's side within the angle between the
    // centre-to-tangent-point radii: cos(angle to -p) > r / |p|.
    if (wp < 0.0 && wp * wp > r * r * norm_squared(w)) {
      const double wl = norm(w);
      n = (1.0 / wl) * w;
      u = (r / tau - wl) * n;
    } else {
      // A leg: the tangent from the origin, p turned by asin(r/|p|) to the left or right.
      const double leg = std::sqrt(p2 - r * r);
      Point2D d;
      if (cross(p, w) > 0.0) {
        d = (1.0 / p2) * Point2D{p.x_m * leg - p.y_m * r, p.x_m * r + p.y_m * leg};
        n = perpendicular(d);  // the cone lies clockwise of its left leg
      } else {
        d = (1.0 / p2) * Point2D{p.x_m * leg + p.y_m * r, -p.x_m * r + p.y_m * leg};
        n = -perpendicular(d);
      }
      u = dot(v, d) * d - v;
    }
  } else {
    // Overlapping: leave D(p/dt, r/dt), i.e. be apart after one step. With w = 0 push away from B.
    const Point2D w = v - (1.0 / dt) * p;
    n = unit_or(w, unit_or(-p, Point2D{1.0, 0.0}));
    u = (r / dt - norm(w)) * n;
  }
  return {self.velocity + other.responsibility * u, n, u};
}

Point2D solve_velocity(std::span<const OrcaHalfPlane> planes, Point2D preferred, double max_speed_m_s) noexcept {
  planes = planes.first(std::min(planes.size(), kMaxOrcaNeighbors));
  Point2D result;
  const std::size_t failed = solve_2d(planes, max_speed_m_s, {preferred, {}}, result);
  if (failed < planes.size()) solve_3d(planes, failed, max_speed_m_s, preferred, result);
  return result;
}

Point2D new_velocity(const OrcaAgent& self, std::span<const OrcaNeighbor> neighbors, const OrcaParams& params,
                     double dt) noexcept {
  Nearest near(params.max_neighbors, params.neighbor_distance_m);
  for (std::size_t j = 0; j < neighbors.size(); ++j) {
    near.offer(norm_squared(neighbors[j].position - self.position), j);
  }
  std::array<OrcaNeighbor, kMaxOrcaNeighbors> chosen;
  for (std::size_t k = 0; k < near.size(); ++k) chosen[k] = neighbors[near.index(k)];
  return solve_among(self, {chosen.data(), near.size()}, params, dt);
}

bool orca_step(std::span<OrcaAgent> agents, std::span<const OrcaDisc> others, const OrcaParams& params,
               double dt) noexcept {
  if (agents.size() > kMaxOrcaAgents) return false;
  std::array<Point2D, kMaxOrcaAgents> next;
  for (std::size_t i = 0; i < agents.size(); ++i) {
    const OrcaAgent& a = agents[i];
    if (!a.active) continue;
    Nearest near(params.max_neighbors, params.neighbor_distance_m);
    for (std::size_t j = 0; j < agents.size(); ++j) {
      if (j != i && agents[j].active) near.offer(norm_squared(agents[j].position - a.position), j);
    }
    for (std::size_t k = 0; k < others.size(); ++k) {
      near.offer(norm_squared(others[k].position - a.position), agents.size() + k);
    }
    std::array<OrcaNeighbor, kMaxOrcaNeighbors> chosen;
    for (std::size_t k = 0; k < near.size(); ++k) {
      const std::size_t j = near.index(k);
      if (j < agents.size()) {
        chosen[k] = {agents[j].position, agents[j].velocity, agents[j].radius_m, 0.5};
      } else {
        const OrcaDisc& o = others[j - agents.size()];
        chosen[k] = {o.position, o.velocity, o.radius_m, 1.0};
      }
    }
    next[i] = solve_among(a, {chosen.data(), near.size()}, params, dt);
  }
  for (std::size_t i = 0; i < agents.size(); ++i) {
    if (!agents[i].active) continue;
    agents[i].velocity = next[i];
    agents[i].position += dt * next[i];
  }
  return true;
}

}  // namespace sen3bot::crowd
