#pragma once
// The static map's obstacles as ellipses, for the supervisory planner's barrier (navigation.md
// §1): each obstacle enclosed in an ellipse of (near) minimal area, e(x) = (x - c)' A (x - c) - 1
// negative inside, zero on the boundary, positive outside.
//
// An obstacle is an 8-connected group of occupied cells. Its ellipse must hold every cell
// whole (the cells' corners), and it may not swallow free space the robot needs: when more
// than max_free_fraction of the map cells whose centres lie inside an ellipse are free, the
// group is split in two at the median of its cells along their longer principal axis, and each
// half gets its own ellipse, recursively, down to min_split_cells. A straight wall stays one
// thin ellipse (a rectangle fills 2/pi of its minimal ellipse, and the rest is mostly beside the
// wall); an L-shaped rack becomes two; the walls around a room, one ring that would enclose the
// whole room, become a chain of thin ellipses along them.
//
// The minimal-area ellipse of a point set is Khachiyan's algorithm (the minimum-volume
// enclosing ellipsoid, by coordinate ascent on the dual) with Todd and Yildirim's away steps,
// run on the convex hull of the cells' corners, then scaled so that the farthest corner lies
// exactly on the boundary. Everything
// runs in buffers sized at init(); fit() allocates nothing and is deterministic.
#include <cstdint>
#include <memory_resource>
#include <span>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/nav/geometry.hpp"
#include "sen3bot/nav/map.hpp"

namespace sen3bot::nav {

struct Ellipse {
  double cx_m = 0.0;
  double cy_m = 0.0;
  // The quadratic form: e(x) = a11 dx^2 + 2 a12 dx dy + a22 dy^2 - 1.
  double a11 = 1.0;
  double a12 = 0.0;
  double a22 = 1.0;
  double semi_major_m = 1.0;
  double semi_minor_m = 1.0;
  double angle_rad = 0.0;  // of the major axis, from the map's x axis
  std::uint32_t cells = 0;  // occupied cells it was fitted to

  // Negative inside, zero on the boundary, positive outside.
  [[nodiscard]] double value(double x_m, double y_m) const noexcept {
    const double dx = x_m - cx_m;
    const double dy = y_m - cy_m;
    return a11 * dx * dx + 2.0 * a12 * dx * dy + a22 * dy * dy - 1.0;
  }
  [[nodiscard]] Point2D gradient(double x_m, double y_m) const noexcept {
    const double dx = x_m - cx_m;
    const double dy = y_m - cy_m;
    return {2.0 * (a11 * dx + a12 * dy), 2.0 * (a12 * dx + a22 * dy)};
  }
  [[nodiscard]] double area_m2() const noexcept;
  // From centre, semi-axes and angle (the form follows).
  [[nodiscard]] static Ellipse from_axes(double cx_m, double cy_m, double semi_major_m, double semi_minor_m,
                                         double angle_rad) noexcept;
};

// The minimal-area ellipse enclosing points (at least 3 not on one line), scaled so every
// point is inside or on it. It stops when every point's distance in the current ellipse's
// metric is within the relative tolerance of the optimum's (then the area is within about
// that much of the minimum).
// work must hold points.size() doubles. Returns false for fewer than 3 points, points on one
// line, or no convergence within max_iterations.
bool enclosing_ellipse(std::span<const Point2D> points, std::span<double> work, double tolerance, int max_iterations,
                       Ellipse& out) noexcept;

struct MapEllipsesConfig {
  std::size_t max_map_cells = std::size_t{1} << 20;   // the largest map fit() accepts...
  int max_map_rows = 2048;                            // ...and its most rows
  std::size_t max_obstacle_cells = std::size_t{1} << 18;  // occupied cells in all
  std::size_t max_ellipses = 256;
  std::int8_t occupied_threshold = 65;   // a cell at least this is an obstacle (trinary maps: 100)
  double max_free_fraction = 0.5;        // of the cells inside an ellipse, before it is split
  std::size_t min_split_cells = 4;       // a smaller group is never split
  double tolerance = 1e-4;               // enclosing_ellipse()'s
  int max_iterations = 5000;
};

class MapEllipses {
 public:
  Status init(const MapEllipsesConfig& config, std::pmr::memory_resource& resource);
  // The bytes init() takes for config (to size an arena).
  [[nodiscard]] static std::size_t storage_bytes(const MapEllipsesConfig& config) noexcept;

  // Fits the map's obstacles. Errors: a map larger than max_map_cells, more ellipses than
  // max_ellipses, or a group whose ellipse does not converge; ellipses() is then empty.
  Status fit(const OccupancyMap& map) noexcept;
  [[nodiscard]] std::span<const Ellipse> ellipses() const noexcept { return ellipses_.first(count_); }
  [[nodiscard]] std::size_t splits() const noexcept { return splits_; }  // of the last fit()

 private:
  struct Range {
    std::uint32_t begin = 0;
    std::uint32_t end = 0;
  };
  Status fit_group(const OccupancyMap& map, std::uint32_t begin, std::uint32_t end) noexcept;
  bool fit_cells(const OccupancyMap& map, std::uint32_t begin, std::uint32_t end, Ellipse& out) noexcept;
  [[nodiscard]] double free_fraction(const OccupancyMap& map, const Ellipse& e) const noexcept;
  void split(const OccupancyMap& map, std::uint32_t begin, std::uint32_t end, std::uint32_t& middle) noexcept;

  MapEllipsesConfig config_;
  std::span<std::uint8_t> visited_;    // per map cell
  std::span<std::uint32_t> cells_;     // the occupied cells' indices, one group after another
  std::span<Point2D> points_;          // a group's outer corners (per row its first and last cell), then its hull
  std::span<double> work_;             // Khachiyan's weights
  std::span<Range> stack_;
  std::span<Ellipse> ellipses_;
  std::size_t count_ = 0;
  std::size_t splits_ = 0;
};

}  // namespace sen3bot::nav
