#pragma once
// Supervisory global planner (SGP): the thesis' vector field (navigation.md §1, eq. 1.4) that
// makes a site's safe curve V = {x : p(x) = 0} attractive and invariant while a barrier keeps
// every trajectory out of the obstacles' ellipses,
//
//   xi' = b^2 phi + b^2 psi zeta - k p^2 eta,   eta = grad(p^2 / b),
//   phi = -p grad p (onto V),   psi = J grad p (along V, J the 90 degree rotation),
//
// integrated from the robot's position into waypoints for the global planner.
//
// Choices (the spec leaves them open):
// - p is kept close to a signed distance near V: a line's p is the distance along its unit
//   normal, a circle's (|x - c|^2 - r^2) / 2r, an ellipse's the same with its axes. Then
//   |grad p| is about 1 near V, and the on-curve tolerance is in metres.
// - b is the product over the ellipses of e_i / (1 + e_i), e_i(x) = (x - c)'A(x - c) - 1: zero
//   on each boundary, positive outside, below 1, so that with tens of ellipses it neither
//   overflows nor vanishes far from all of them (the plain product of e_i would reach 1e60 in a
//   room).
// - The path is the field's streamline: the field is normalised and integrated by arc length
//   (RK4, step_m), so the waypoints are evenly spaced whatever the field's magnitude; scaling a
//   field by a positive function does not change its streamlines.
// - Where to stop: the goal's foot on V (Newton's steps on p from the goal along grad p), where
//   the curve passes closest to the goal; the global planner finishes the approach. A path
//   ends when, on V (|p| / |grad p| < on_curve_m), it comes within on_curve_m + step_m of that point (or,
//   when there is none, where on V its distance to the goal stops falling).
// - zeta's sign: both are integrated; the one whose path ends nearer the goal wins, and of two
//   ends within two steps of each other, the shorter path.
// Deterministic: the same obstacles, curve, start and goal give bit-identical waypoints. All
// buffers are sized at init(); plan() allocates nothing.
#include <array>
#include <cstdint>
#include <memory_resource>
#include <span>
#include <vector>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/nav/geometry.hpp"
#include "sen3bot/nav/map_ellipses.hpp"

namespace sen3bot::nav {

// p(x, y) = sum of c_ij x^i y^j over i + j <= kMaxDegree.
class SafeCurve {
 public:
  static constexpr int kMaxDegree = 4;
  static constexpr std::size_t kTerms = (kMaxDegree + 1) * (kMaxDegree + 2) / 2;

  // The coefficient of x^i y^j (i + j <= kMaxDegree).
  [[nodiscard]] double coefficient(int i, int j) const noexcept { return c_[index(i, j)]; }
  void set_coefficient(int i, int j, double value) noexcept { c_[index(i, j)] = value; }
  [[nodiscard]] static constexpr bool valid_term(int i, int j) noexcept {
    return i >= 0 && j >= 0 && i + j <= kMaxDegree;
  }

  // Named shapes, scaled so that p is about the signed distance near V.
  [[nodiscard]] static SafeCurve line(Point2D a, Point2D b) noexcept;  // a != b
  [[nodiscard]] static SafeCurve circle(Point2D centre, double radius_m) noexcept;
  [[nodiscard]] static SafeCurve ellipse(Point2D centre, double semi_major_m, double semi_minor_m,
                                         double angle_rad) noexcept;

  [[nodiscard]] double value(double x_m, double y_m) const noexcept;
  [[nodiscard]] Point2D gradient(double x_m, double y_m) const noexcept;

 private:
  [[nodiscard]] static constexpr std::size_t index(int i, int j) noexcept {
    // Terms ordered by total degree, then by the power of y.
    const int d = i + j;
    return static_cast<std::size_t>(d * (d + 1) / 2 + j);
  }
  std::array<double, kTerms> c_{};
};

// The part of the site a safe curve serves, map frame. Only the obstacles whose ellipses reach
// into it matter to the curve, the curve is checked against them only inside it, and a path
// that would leave it stops (a line's V runs through a room's walls; its bounds end it short).
struct CurveBounds {
  double x0_m = -1e9;
  double y0_m = -1e9;
  double x1_m = 1e9;
  double y1_m = 1e9;
  [[nodiscard]] bool contains(double x_m, double y_m) const noexcept {
    return x_m >= x0_m && x_m <= x1_m && y_m >= y0_m && y_m <= y1_m;
  }
  // The ellipse's bounding box overlaps these bounds.
  [[nodiscard]] bool reaches(const Ellipse& e) const noexcept;
};

// Where V = {p = 0} passes within the bounds: an Error naming the first obstacle ellipse it
// crosses or touches and the place on V, or naming the bounds when V misses them. Sampled: each
// ellipse at 256 boundary points and 8 rings inside; the bounds on a 256 x 256 grid.
[[nodiscard]] Status check_curve(const SafeCurve& curve, const CurveBounds& bounds, std::span<const Ellipse> ellipses);

// The map's extent (the bounding box of its corners in the map frame): a curve's bounds when its
// file gives none.
[[nodiscard]] CurveBounds map_extent(const OccupancyMap& map) noexcept;

// The part of both boxes (empty, x1 < x0 or y1 < y0, when they do not meet).
[[nodiscard]] CurveBounds intersect(const CurveBounds& a, const CurveBounds& b) noexcept;

// V = {p = 0} inside the box as short segments (marching squares on a step_m grid): for figures
// and the live view, at start-up (it allocates).
[[nodiscard]] std::vector<std::array<Point2D, 2>> trace_curve(const SafeCurve& curve, const CurveBounds& box,
                                                              double step_m);

// The foot of `from` on V by Newton's steps along grad p; false when they do not converge.
[[nodiscard]] bool project_onto_curve(const SafeCurve& curve, Point2D from, Point2D& on) noexcept;

struct SgpConfig {
  double step_m = 0.02;             // arc length per RK4 step
  int max_steps = 20000;            // per direction
  double waypoint_spacing_m = 0.25;
  double barrier_k = 1.0;           // k of eq. 1.4
  double zeta = 1.0;                // |zeta|: how strongly the field runs along V
  double on_curve_m = 0.05;         // on V: |p| / |grad p| (the distance to first order) below this
  double min_field = 1e-9;          // a field weaker than this is a standstill (an equilibrium)
  std::size_t max_waypoints = 4096;
  std::size_t max_ellipses = 256;
};

enum class SgpStop : std::uint8_t {
  nearest_to_goal,  // on V, where it passes closest to the goal
  step_cap,         // max_steps without that
  stalled,          // at an equilibrium of eq. 1.4: the field vanished, or 50 steps went nowhere
  blocked,          // a step would have entered an ellipse (the barrier failed: a bug or a bad curve)
  start_inside,     // the start is inside an obstacle's ellipse
  waypoint_cap,     // more waypoints than max_waypoints
  left_bounds,      // the start, or the next step, is outside the curve's bounds
};
[[nodiscard]] const char* to_string(SgpStop stop) noexcept;

struct SgpResult {
  SgpStop stop = SgpStop::step_cap;
  int direction = 1;          // zeta's sign taken
  int steps = 0;              // of that direction
  double length_m = 0.0;
  double min_barrier = 0.0;   // the least b along the path
  double goal_distance_m = 0.0;  // from the last waypoint
  bool on_curve = false;      // the path reached V
};

class SupervisoryPlanner {
 public:
  Status init(const SgpConfig& config, std::pmr::memory_resource& resource);
  // The curve and its bounds first: set_obstacles() keeps the ellipses that reach the bounds.
  void set_curve(const SafeCurve& curve, const CurveBounds& bounds = {}) noexcept {
    curve_ = curve;
    bounds_ = bounds;
  }
  // Copies the ellipses that reach the bounds (at most max_ellipses of them).
  Status set_obstacles(std::span<const Ellipse> ellipses) noexcept;
  // A site: check_curve(), then set_curve() and set_obstacles(). Errors: the curve crosses an
  // ellipse or misses its bounds, or more than max_ellipses reach the bounds (then no ellipse is held).
  Status set_site(const SafeCurve& curve, const CurveBounds& bounds, std::span<const Ellipse> ellipses);
  [[nodiscard]] std::span<const Ellipse> obstacles() const noexcept { return ellipses_.first(ellipse_count_); }
  [[nodiscard]] const SafeCurve& curve() const noexcept { return curve_; }
  [[nodiscard]] const CurveBounds& bounds() const noexcept { return bounds_; }
  [[nodiscard]] const SgpConfig& config() const noexcept { return config_; }

  // b(x) and its gradient.
  [[nodiscard]] double barrier(double x_m, double y_m) const noexcept;
  [[nodiscard]] Point2D barrier_gradient(double x_m, double y_m) const noexcept;
  // xi' of eq. 1.4 with zeta = sign * config.zeta; zero inside an ellipse.
  [[nodiscard]] Point2D field(double x_m, double y_m, int sign) const noexcept;

  // Integrates from start in both directions along V and keeps the better path's waypoints
  // (the start first, then every waypoint_spacing_m, the path's end last). direction +1 or -1
  // takes that sign of zeta only (+1: counter-clockwise about grad p).
  SgpResult plan(Point2D start, Point2D goal, int direction = 0) noexcept;
  [[nodiscard]] std::span<const Point2D> waypoints() const noexcept { return best_.first(best_count_); }

 private:
  SgpResult integrate(Point2D start, Point2D goal, int sign, std::span<Point2D> out, std::size_t& count) noexcept;
  [[nodiscard]] bool inside_any(double x_m, double y_m) const noexcept;
  // b and grad b in one pass over the ellipses (both zero inside one).
  double barrier_with_gradient(double x_m, double y_m, Point2D& gradient) const noexcept;

  SgpConfig config_;
  SafeCurve curve_;
  CurveBounds bounds_;
  std::span<Ellipse> ellipses_;
  std::size_t ellipse_count_ = 0;
  std::span<Point2D> best_;
  std::span<Point2D> other_;
  std::size_t best_count_ = 0;
};

}  // namespace sen3bot::nav
