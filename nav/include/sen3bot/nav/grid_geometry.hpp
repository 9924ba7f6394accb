#pragma once
// Where a row-major grid of square cells lies in the map frame: the lower-left corner of cell
// (0, 0) (origin), the cell size, the cell count, and an optional rotation of the grid about
// its origin (a map's yaw; costmaps are axis-aligned). Cell (c, r) spans [c, c+1) x [r, r+1)
// in grid coordinates; col grows with x and row with y when the yaw is 0.
#include <algorithm>
#include <cmath>
#include <cstdlib>
#include <cstddef>

namespace sen3bot::nav {

class GridGeometry {
 public:
  GridGeometry() = default;
  GridGeometry(int width, int height, double resolution_m, double origin_x_m, double origin_y_m,
               double origin_yaw_rad = 0.0) noexcept
      : width_(width),
        height_(height),
        resolution_m_(resolution_m),
        origin_x_m_(origin_x_m),
        origin_y_m_(origin_y_m),
        origin_yaw_rad_(origin_yaw_rad),
        cos_yaw_(std::cos(origin_yaw_rad)),
        sin_yaw_(std::sin(origin_yaw_rad)) {}

  [[nodiscard]] int width() const noexcept { return width_; }
  [[nodiscard]] int height() const noexcept { return height_; }
  [[nodiscard]] double resolution_m() const noexcept { return resolution_m_; }
  [[nodiscard]] double origin_x_m() const noexcept { return origin_x_m_; }
  [[nodiscard]] double origin_y_m() const noexcept { return origin_y_m_; }
  [[nodiscard]] double origin_yaw_rad() const noexcept { return origin_yaw_rad_; }
  [[nodiscard]] std::size_t cell_count() const noexcept {
    return static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_);
  }
  // A rolling window moves its origin; size, resolution and yaw stay.
  void set_origin(double x_m, double y_m) noexcept {
    origin_x_m_ = x_m;
    origin_y_m_ = y_m;
  }

  [[nodiscard]] bool in_bounds(int col, int row) const noexcept {
    return col >= 0 && row >= 0 && col < width_ && row < height_;
  }
  [[nodiscard]] std::size_t index(int col, int row) const noexcept {
    return static_cast<std::size_t>(row) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(col);
  }

  // Continuous grid coordinates of a map-frame point.
  void world_to_grid(double x_m, double y_m, double& gx, double& gy) const noexcept {
    const double dx = x_m - origin_x_m_;
    const double dy = y_m - origin_y_m_;
    gx = (cos_yaw_ * dx + sin_yaw_ * dy) / resolution_m_;
    gy = (-sin_yaw_ * dx + cos_yaw_ * dy) / resolution_m_;
  }
  // The cell holding a point; false when it lies outside the grid. col and row are set
  // either way, so a caller can search around a point just off the grid.
  bool world_to_cell(double x_m, double y_m, int& col, int& row) const noexcept {
    double gx = 0.0;
    double gy = 0.0;
    world_to_grid(x_m, y_m, gx, gy);
    // Clamped before the cast so far-away points (or NaN) cannot overflow int; a million
    // cells off the grid is far beyond any search around the point.
    constexpr double kFar = 1 << 20;
    gx = std::clamp(std::isnan(gx) ? -kFar : gx, -kFar, width_ + kFar);
    gy = std::clamp(std::isnan(gy) ? -kFar : gy, -kFar, height_ + kFar);
    col = static_cast<int>(std::floor(gx));
    row = static_cast<int>(std::floor(gy));
    return in_bounds(col, row);
  }
  // The map-frame point of continuous grid coordinates (the inverse of world_to_grid).
  void grid_to_world(double gx, double gy, double& x_m, double& y_m) const noexcept {
    const double lx = gx * resolution_m_;
    const double ly = gy * resolution_m_;
    x_m = origin_x_m_ + cos_yaw_ * lx - sin_yaw_ * ly;
    y_m = origin_y_m_ + sin_yaw_ * lx + cos_yaw_ * ly;
  }
  // The centre of a cell in the map frame.
  void cell_to_world(int col, int row, double& x_m, double& y_m) const noexcept {
    grid_to_world(col + 0.5, row + 0.5, x_m, y_m);
  }

 private:
  int width_ = 0;
  int height_ = 0;
  double resolution_m_ = 0.05;
  double origin_x_m_ = 0.0;
  double origin_y_m_ = 0.0;
  double origin_yaw_rad_ = 0.0;
  double cos_yaw_ = 1.0;
  double sin_yaw_ = 0.0;
};

// The cells of the Bresenham line from (c0, r0) towards (c1, r1), the end cell excluded, in order:
// visit(col, row, step) with step counting from 0; the walk stops when visit returns false.
template <typename Visit>
void walk_line(int c0, int r0, int c1, int r1, Visit&& visit) noexcept(noexcept(visit(0, 0, 0))) {
  const int dc = std::abs(c1 - c0);
  const int dr = -std::abs(r1 - r0);
  const int sc = c0 < c1 ? 1 : -1;
  const int sr = r0 < r1 ? 1 : -1;
  int err = dc + dr;
  int c = c0;
  int r = r0;
  for (int step = 0; c != c1 || r != r1; ++step) {
    if (!visit(c, r, step)) return;
    const int e2 = 2 * err;
    if (e2 >= dr) {
      err += dr;
      c += sc;
    }
    if (e2 <= dc) {
      err += dc;
      r += sr;
    }
  }
}

}  // namespace sen3bot::nav
