#include "sen3bot/nav/sgp.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>
#include <utility>

#include "sen3bot/nav/arena.hpp"

namespace sen3bot::nav {

const char* to_string(SgpStop stop) noexcept {
  switch (stop) {
    case SgpStop::nearest_to_goal: return "nearest_to_goal";
    case SgpStop::step_cap: return "step_cap";
    case SgpStop::stalled: return "stalled";
    case SgpStop::blocked: return "blocked";
    case SgpStop::start_inside: return "start_inside";
    case SgpStop::waypoint_cap: return "waypoint_cap";
    case SgpStop::left_bounds: return "left_bounds";
  }
  return "unknown";
}

// --- The safe curve --------------------------------------------------------------------------------

namespace {
using Powers = std::array<double, SafeCurve::kMaxDegree + 1>;
// v^0 .. v^kMaxDegree.
void powers(double v, Powers& out) noexcept {
  out[0] = 1.0;
  for (std::size_t k = 1; k < out.size(); ++k) out[k] = out[k - 1] * v;
}
}  // namespace

SafeCurve SafeCurve::line(Point2D a, Point2D b) noexcept {
  SafeCurve p;
  const double dx = b.x_m - a.x_m;
  const double dy = b.y_m - a.y_m;
  const double len = std::hypot(dx, dy);
  if (!(len > 0.0)) return p;
  const double nx = -dy / len;
  const double ny = dx / len;
  p.set_coefficient(1, 0, nx);
  p.set_coefficient(0, 1, ny);
  p.set_coefficient(0, 0, -(nx * a.x_m + ny * a.y_m));
  return p;
}

SafeCurve SafeCurve::circle(Point2D centre, double radius_m) noexcept {
  return ellipse(centre, radius_m, radius_m, 0.0);
}

SafeCurve SafeCurve::ellipse(Point2D centre, double semi_major_m, double semi_minor_m, double angle_rad) noexcept {
  SafeCurve p;
  if (!(semi_major_m > 0.0) || !(semi_minor_m > 0.0)) return p;
  const Ellipse e = Ellipse::from_axes(centre.x_m, centre.y_m, semi_major_m, semi_minor_m, angle_rad);
  // q = (x - c)'A(x - c) - 1, scaled by ab / (a + b): |grad p| averages 1 on V (a circle's p is
  // (|x - c|^2 - r^2) / 2r).
  const double k = semi_major_m * semi_minor_m / (semi_major_m + semi_minor_m);
  const double cx = centre.x_m;
  const double cy = centre.y_m;
  p.set_coefficient(2, 0, k * e.a11);
  p.set_coefficient(1, 1, k * 2.0 * e.a12);
  p.set_coefficient(0, 2, k * e.a22);
  p.set_coefficient(1, 0, k * (-2.0 * e.a11 * cx - 2.0 * e.a12 * cy));
  p.set_coefficient(0, 1, k * (-2.0 * e.a22 * cy - 2.0 * e.a12 * cx));
  p.set_coefficient(0, 0, k * (e.a11 * cx * cx + 2.0 * e.a12 * cx * cy + e.a22 * cy * cy - 1.0));
  return p;
}

double SafeCurve::value(double x_m, double y_m) const noexcept {
  Powers xp{};
  Powers yp{};
  powers(x_m, xp);
  powers(y_m, yp);
  double sum = 0.0;
  for (int d = 0; d <= kMaxDegree; ++d) {
    for (int j = 0; j <= d; ++j) {
      const int i = d - j;
      sum += c_[index(i, j)] * xp[static_cast<std::size_t>(i)] * yp[static_cast<std::size_t>(j)];
    }
  }
  return sum;
}

Point2D SafeCurve::gradient(double x_m, double y_m) const noexcept {
  Powers xp{};
  Powers yp{};
  powers(x_m, xp);
  powers(y_m, yp);
  Point2D g{0.0, 0.0};
  for (int d = 1; d <= kMaxDegree; ++d) {
    for (int j = 0; j <= d; ++j) {
      const int i = d - j;
      const double c = c_[index(i, j)];
      if (i > 0) g.x_m += c * i * xp[static_cast<std::size_t>(i - 1)] * yp[static_cast<std::size_t>(j)];
      if (j > 0) g.y_m += c * j * xp[static_cast<std::size_t>(i)] * yp[static_cast<std::size_t>(j - 1)];
    }
  }
  return g;
}

bool project_onto_curve(const SafeCurve& curve, Point2D from, Point2D& on) noexcept {
  // Newton's steps on p along grad p: for a point near V, the foot of its normal.
  Point2D x = from;
  for (int k = 0; k < 100; ++k) {
    const double p = curve.value(x.x_m, x.y_m);
    if (std::abs(p) < 1e-9) {
      on = x;
      return std::isfinite(x.x_m) && std::isfinite(x.y_m);
    }
    const Point2D g = curve.gradient(x.x_m, x.y_m);
    const double g2 = g.x_m * g.x_m + g.y_m * g.y_m;
    if (!(g2 > 1e-12)) return false;
    x.x_m -= p * g.x_m / g2;
    x.y_m -= p * g.y_m / g2;
  }
  return false;
}

CurveBounds intersect(const CurveBounds& a, const CurveBounds& b) noexcept {
  return {std::max(a.x0_m, b.x0_m), std::max(a.y0_m, b.y0_m), std::min(a.x1_m, b.x1_m), std::min(a.y1_m, b.y1_m)};
}

std::vector<std::array<Point2D, 2>> trace_curve(const SafeCurve& curve, const CurveBounds& box, double step_m) {
  std::vector<std::array<Point2D, 2>> segments;
  const int nx = static_cast<int>(std::ceil((box.x1_m - box.x0_m) / step_m));
  const int ny = static_cast<int>(std::ceil((box.y1_m - box.y0_m) / step_m));
  if (nx < 1 || ny < 1) return segments;
  const auto x_at = [&](int i) { return std::min(box.x0_m + i * step_m, box.x1_m); };
  const auto y_at = [&](int j) { return std::min(box.y0_m + j * step_m, box.y1_m); };
  std::vector<double> below(static_cast<std::size_t>(nx + 1));
  std::vector<double> above(below.size());
  for (int i = 0; i <= nx; ++i) below[static_cast<std::size_t>(i)] = curve.value(x_at(i), y_at(0));
  for (int j = 0; j < ny; ++j) {
    for (int i = 0; i <= nx; ++i) above[static_cast<std::size_t>(i)] = curve.value(x_at(i), y_at(j + 1));
    for (int i = 0; i < nx; ++i) {
      // The cell's corners counter-clockwise; a sign change on an edge puts V's crossing there.
      const double x0 = x_at(i), x1 = x_at(i + 1), y0 = y_at(j), y1 = y_at(j + 1);
      const double v[4] = {below[static_cast<std::size_t>(i)], below[static_cast<std::size_t>(i + 1)],
                           above[static_cast<std::size_t>(i + 1)], above[static_cast<std::size_t>(i)]};
      const Point2D c[4] = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
      Point2D cross[4];
      int n = 0;
      for (int e = 0; e < 4; ++e) {
        const double a = v[e], b = v[(e + 1) % 4];
        if ((a < 0) == (b < 0)) continue;
        const double t = a / (a - b);
        const Point2D& p = c[e];
        const Point2D& q = c[(e + 1) % 4];
        cross[n++] = {p.x_m + t * (q.x_m - p.x_m), p.y_m + t * (q.y_m - p.y_m)};
      }
      // Two crossings: one segment; four (a saddle): pair them in order round the cell.
      for (int k = 0; k + 1 < n; k += 2) segments.push_back({cross[k], cross[k + 1]});
    }
    std::swap(below, above);
  }
  return segments;
}

CurveBounds map_extent(const OccupancyMap& map) noexcept {
  const double w = map.width() * map.resolution_m();
  const double h = map.height() * map.resolution_m();
  const double c = std::cos(map.origin_yaw_rad());
  const double s = std::sin(map.origin_yaw_rad());
  CurveBounds b{map.origin_x_m(), map.origin_y_m(), map.origin_x_m(), map.origin_y_m()};
  for (const auto& [u, v] : {std::pair{w, 0.0}, std::pair{0.0, h}, std::pair{w, h}}) {
    const double x = map.origin_x_m() + c * u - s * v;
    const double y = map.origin_y_m() + s * u + c * v;
    b = {std::min(b.x0_m, x), std::min(b.y0_m, y), std::max(b.x1_m, x), std::max(b.y1_m, y)};
  }
  return b;
}

bool CurveBounds::reaches(const Ellipse& e) const noexcept {
  // The bounding box of dx'A dx <= 1 has half-widths sqrt((A^-1)_11) and sqrt((A^-1)_22).
  const double det = e.a11 * e.a22 - e.a12 * e.a12;
  if (!(det > 0.0)) return true;
  const double hx = std::sqrt(e.a22 / det);
  const double hy = std::sqrt(e.a11 / det);
  return e.cx_m + hx >= x0_m && e.cx_m - hx <= x1_m && e.cy_m + hy >= y0_m && e.cy_m - hy <= y1_m;
}

Status check_curve(const SafeCurve& curve, const CurveBounds& bounds, std::span<const Ellipse> ellipses) {
  // V somewhere inside the bounds: p takes both signs (or zero) on a grid over them.
  {
    constexpr int kGrid = 256;
    double lo = std::numeric_limits<double>::infinity();
    double hi = -lo;
    for (int r = 0; r <= kGrid; ++r)
      for (int c = 0; c <= kGrid; ++c) {
        const double x = bounds.x0_m + (bounds.x1_m - bounds.x0_m) * c / kGrid;
        const double y = bounds.y0_m + (bounds.y1_m - bounds.y0_m) * r / kGrid;
        const double p = curve.value(x, y);
        lo = std::min(lo, p);
        hi = std::max(hi, p);
      }
    if (!(lo <= 0.0 && hi >= 0.0)) {
      return Error::format(Errc::config, "the safe curve does not pass through its bounds [%g, %g] x [%g, %g] m",
                           bounds.x0_m, bounds.x1_m, bounds.y0_m, bounds.y1_m);
    }
  }
  // Each ellipse: p on its boundary and on rings inside it, in its own axes.
  constexpr int kAngles = 256;
  constexpr int kRings = 8;
  for (std::size_t i = 0; i < ellipses.size(); ++i) {
    const Ellipse& e = ellipses[i];
    if (!bounds.reaches(e)) continue;
    const double ca = std::cos(e.angle_rad);
    const double sa = std::sin(e.angle_rad);
    double lo = std::numeric_limits<double>::infinity();
    double hi = -lo;
    double least = lo;
    Point2D nearest{e.cx_m, e.cy_m};
    for (int ring = 0; ring <= kRings; ++ring) {
      const double f = static_cast<double>(ring) / kRings;
      const int angles = ring == 0 ? 1 : kAngles;
      for (int k = 0; k < angles; ++k) {
        const double t = 2.0 * std::numbers::pi * k / angles;
        const double u = f * e.semi_major_m * std::cos(t);
        const double v = f * e.semi_minor_m * std::sin(t);
        const double x = e.cx_m + ca * u - sa * v;
        const double y = e.cy_m + sa * u + ca * v;
        if (!bounds.contains(x, y)) continue;
        const double p = curve.value(x, y);
        lo = std::min(lo, p);
        hi = std::max(hi, p);
        if (std::abs(p) < least) {
          least = std::abs(p);
          nearest = {x, y};
        }
      }
    }
    if (lo <= 0.0 && hi >= 0.0) {
      Point2D at = nearest;
      (void)project_onto_curve(curve, nearest, at);
      return Error::format(Errc::config,
                           "the safe curve crosses obstacle ellipse %zu (centre (%.2f, %.2f) m, semi-axes %.2f x %.2f m, "
                           "%.0f deg) at (%.2f, %.2f) m",
                           i, e.cx_m, e.cy_m, e.semi_major_m, e.semi_minor_m, e.angle_rad * 180.0 / std::numbers::pi,
                           at.x_m, at.y_m);
    }
  }
  return Status::success();
}

// --- The planner -------------------------------------------------------------------------------------

Status SupervisoryPlanner::init(const SgpConfig& config, std::pmr::memory_resource& resource) {
  if (!(config.step_m > 0.0) || config.max_steps < 1 || !(config.waypoint_spacing_m > 0.0) || !(config.barrier_k >= 0.0) ||
      !(config.zeta > 0.0) || !(config.on_curve_m > 0.0) || config.max_waypoints < 2 || config.max_ellipses == 0) {
    return Error::format(Errc::config, "sgp: step_m, max_steps, waypoint_spacing_m, zeta, on_curve_m must be positive, "
                                       "barrier_k at least 0, max_waypoints at least 2");
  }
  config_ = config;
  return guarded("sgp", [&]() -> Status {
    ellipses_ = allocate_array<Ellipse>(resource, config.max_ellipses);
    best_ = allocate_array<Point2D>(resource, config.max_waypoints);
    other_ = allocate_array<Point2D>(resource, config.max_waypoints);
    return Status::success();
  });
}

Status SupervisoryPlanner::set_obstacles(std::span<const Ellipse> ellipses) noexcept {
  ellipse_count_ = 0;
  for (const Ellipse& e : ellipses) {
    if (!bounds_.reaches(e)) continue;
    if (ellipse_count_ == ellipses_.size()) {
      ellipse_count_ = 0;
      return Error::format(Errc::capacity, "sgp: more than %zu ellipses reach the curve's bounds", ellipses_.size());
    }
    ellipses_[ellipse_count_++] = e;
  }
  return Status::success();
}

Status SupervisoryPlanner::set_site(const SafeCurve& curve, const CurveBounds& bounds, std::span<const Ellipse> ellipses) {
  if (Status s = check_curve(curve, bounds, ellipses); !s) return s;
  set_curve(curve, bounds);
  return set_obstacles(ellipses);
}

bool SupervisoryPlanner::inside_any(double x_m, double y_m) const noexcept {
  for (std::size_t i = 0; i < ellipse_count_; ++i)
    if (ellipses_[i].value(x_m, y_m) <= 0.0) return true;
  return false;
}

double SupervisoryPlanner::barrier(double x_m, double y_m) const noexcept {
  Point2D unused;
  return barrier_with_gradient(x_m, y_m, unused);
}

Point2D SupervisoryPlanner::barrier_gradient(double x_m, double y_m) const noexcept {
  Point2D g;
  (void)barrier_with_gradient(x_m, y_m, g);
  return g;
}

double SupervisoryPlanner::barrier_with_gradient(double x_m, double y_m, Point2D& gradient) const noexcept {
  // One pass for both: grad b = b * sum grad f_i / f_i, f_i = e_i / (1 + e_i), and
  // grad f_i / f_i = grad e_i / (e_i (1 + e_i)).
  double b = 1.0;
  Point2D sum{0.0, 0.0};
  gradient = {0.0, 0.0};
  for (std::size_t i = 0; i < ellipse_count_; ++i) {
    const Ellipse& el = ellipses_[i];
    const double e = el.value(x_m, y_m);
    if (e <= 0.0) return 0.0;
    b *= e / (1.0 + e);
    const Point2D g = el.gradient(x_m, y_m);
    const double w = 1.0 / (e * (1.0 + e));
    sum.x_m += g.x_m * w;
    sum.y_m += g.y_m * w;
  }
  gradient = {b * sum.x_m, b * sum.y_m};
  return b;
}

Point2D SupervisoryPlanner::field(double x_m, double y_m, int sign) const noexcept {
  Point2D gb;
  const double b = barrier_with_gradient(x_m, y_m, gb);
  if (!(b > 0.0)) return {0.0, 0.0};
  const double p = curve_.value(x_m, y_m);
  const Point2D gp = curve_.gradient(x_m, y_m);
  const double zeta = sign >= 0 ? config_.zeta : -config_.zeta;
  const double b2 = b * b;
  // b^2 (phi + zeta psi): phi = -p grad p, psi = J grad p = (-dp/dy, dp/dx).
  double fx = b2 * (-p * gp.x_m - zeta * gp.y_m);
  double fy = b2 * (-p * gp.y_m + zeta * gp.x_m);
  // -k p^2 eta, eta = grad(p^2 / b) = (2 p b grad p - p^2 grad b) / b^2.
  const double p2 = p * p;
  const double k = config_.barrier_k * p2;
  fx -= k * (2.0 * p * gp.x_m / b - p2 * gb.x_m / b2);
  fy -= k * (2.0 * p * gp.y_m / b - p2 * gb.y_m / b2);
  return {fx, fy};
}

SgpResult SupervisoryPlanner::integrate(Point2D start, Point2D goal, int sign, std::span<Point2D> out,
                                         std::size_t& count) noexcept {
  SgpResult r;
  r.direction = sign;
  count = 0;
  out[count++] = start;
  r.min_barrier = barrier(start.x_m, start.y_m);
  r.goal_distance_m = std::hypot(goal.x_m - start.x_m, goal.y_m - start.y_m);
  if (!bounds_.contains(start.x_m, start.y_m)) {
    r.stop = SgpStop::left_bounds;
    return r;
  }
  if (inside_any(start.x_m, start.y_m)) {
    r.stop = SgpStop::start_inside;
    return r;
  }
  // Where V passes closest to the goal (the foot of the goal's normal on V); without one (the
  // goal where grad p vanishes), where on V the distance to the goal stops falling.
  Point2D target{};
  const bool has_target = project_onto_curve(curve_, goal, target);
  const double reach = config_.on_curve_m + config_.step_m;
  // The unit field: the streamline by arc length.
  bool stalled = false;
  const auto unit = [&](double x, double y) {
    const Point2D f = field(x, y, sign);
    const double n = std::hypot(f.x_m, f.y_m);
    if (!(n > config_.min_field)) {
      stalled = true;
      return Point2D{0.0, 0.0};
    }
    return Point2D{f.x_m / n, f.y_m / n};
  };
  const double h = config_.step_m;
  Point2D x = start;
  double since_waypoint = 0.0;
  double previous_goal = r.goal_distance_m;
  // A sink of the field (where the barrier and the pull onto V cancel) is not a zero the unit
  // field can see: the steps jitter about it. Over every kStallSteps steps the path must get
  // more than two steps away from where it was.
  constexpr int kStallSteps = 50;
  Point2D checkpoint = start;
  r.stop = SgpStop::step_cap;
  for (int step = 0; step < config_.max_steps; ++step) {
    if (step > 0 && step % kStallSteps == 0) {
      if (std::hypot(x.x_m - checkpoint.x_m, x.y_m - checkpoint.y_m) < 2.0 * h) {
        r.stop = SgpStop::stalled;
        break;
      }
      checkpoint = x;
    }
    const Point2D k1 = unit(x.x_m, x.y_m);
    const Point2D k2 = unit(x.x_m + 0.5 * h * k1.x_m, x.y_m + 0.5 * h * k1.y_m);
    const Point2D k3 = unit(x.x_m + 0.5 * h * k2.x_m, x.y_m + 0.5 * h * k2.y_m);
    const Point2D k4 = unit(x.x_m + h * k3.x_m, x.y_m + h * k3.y_m);
    if (stalled) {
      r.stop = SgpStop::stalled;
      break;
    }
    const Point2D next{x.x_m + h / 6.0 * (k1.x_m + 2.0 * k2.x_m + 2.0 * k3.x_m + k4.x_m),
                       x.y_m + h / 6.0 * (k1.y_m + 2.0 * k2.y_m + 2.0 * k3.y_m + k4.y_m)};
    if (!bounds_.contains(next.x_m, next.y_m)) {
      r.stop = SgpStop::left_bounds;
      break;
    }
    if (inside_any(next.x_m, next.y_m)) {
      r.stop = SgpStop::blocked;
      break;
    }
    const double moved = std::hypot(next.x_m - x.x_m, next.y_m - x.y_m);
    const double to_goal = std::hypot(goal.x_m - next.x_m, goal.y_m - next.y_m);
    // |p| / |grad p|: the distance to V to first order, whatever the polynomial's scale.
    const Point2D gp = curve_.gradient(next.x_m, next.y_m);
    const bool on_curve = std::abs(curve_.value(next.x_m, next.y_m)) < config_.on_curve_m * std::hypot(gp.x_m, gp.y_m);
    if (on_curve && has_target && std::hypot(target.x_m - next.x_m, target.y_m - next.y_m) < reach) {
      x = next;
      r.steps = step + 1;
      r.length_m += moved;
      since_waypoint += moved;
      r.min_barrier = std::min(r.min_barrier, barrier(x.x_m, x.y_m));
      r.on_curve = true;
      r.stop = SgpStop::nearest_to_goal;
      break;
    }
    if (on_curve && !has_target && r.on_curve && to_goal > previous_goal) {
      r.stop = SgpStop::nearest_to_goal;  // x was where the distance stopped falling
      break;
    }
    r.on_curve = r.on_curve || on_curve;
    x = next;
    r.steps = step + 1;
    r.length_m += moved;
    r.min_barrier = std::min(r.min_barrier, barrier(x.x_m, x.y_m));
    previous_goal = to_goal;
    since_waypoint += moved;
    if (since_waypoint >= config_.waypoint_spacing_m) {
      if (count >= out.size()) {
        r.stop = SgpStop::waypoint_cap;
        break;
      }
      out[count++] = x;
      since_waypoint = 0.0;
    }
  }
  // The path's end, unless it is the last waypoint already.
  if (since_waypoint > 0.0 && r.steps > 0) {
    if (count < out.size()) {
      out[count++] = x;
    } else {
      r.stop = SgpStop::waypoint_cap;
    }
  }
  r.goal_distance_m = std::hypot(goal.x_m - x.x_m, goal.y_m - x.y_m);
  return r;
}

SgpResult SupervisoryPlanner::plan(Point2D start, Point2D goal, int direction) noexcept {
  if (direction != 0) {
    const SgpResult only = integrate(start, goal, direction > 0 ? 1 : -1, best_, best_count_);
    return only;
  }
  std::size_t forward_count = 0;
  std::size_t backward_count = 0;
  const SgpResult forward = integrate(start, goal, 1, best_, forward_count);
  const SgpResult backward = integrate(start, goal, -1, other_, backward_count);
  const auto rank = [](const SgpResult& r) { return r.stop == SgpStop::nearest_to_goal ? 0 : 1; };
  bool take_backward = rank(backward) < rank(forward);
  if (rank(backward) == rank(forward)) {
    // Ends within two steps of each other are as near: then the shorter way.
    const double nearer = forward.goal_distance_m - backward.goal_distance_m;
    take_backward = std::abs(nearer) <= 2.0 * config_.step_m ? backward.length_m < forward.length_m : nearer > 0.0;
  }
  if (!take_backward) {
    best_count_ = forward_count;
    return forward;
  }
  std::swap(best_, other_);
  best_count_ = backward_count;
  return backward;
}

}  // namespace sen3bot::nav
