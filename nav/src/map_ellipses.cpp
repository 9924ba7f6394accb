#include "sen3bot/nav/map_ellipses.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "sen3bot/nav/arena.hpp"

namespace sen3bot::nav {
namespace {

constexpr std::size_t kStackDepth = 64;  // a median split halves a group: 2^64 cells never come

// The inverse of a symmetric 3 x 3 matrix (row-major), false when singular.
bool invert3(const double m[9], double out[9]) noexcept {
  const double c00 = m[4] * m[8] - m[5] * m[7];
  const double c01 = m[5] * m[6] - m[3] * m[8];
  const double c02 = m[3] * m[7] - m[4] * m[6];
  const double det = m[0] * c00 + m[1] * c01 + m[2] * c02;
  if (!(std::abs(det) > 1e-300)) return false;
  const double inv = 1.0 / det;
  out[0] = c00 * inv;
  out[1] = (m[2] * m[7] - m[1] * m[8]) * inv;
  out[2] = (m[1] * m[5] - m[2] * m[4]) * inv;
  out[3] = c01 * inv;
  out[4] = (m[0] * m[8] - m[2] * m[6]) * inv;
  out[5] = (m[2] * m[3] - m[0] * m[5]) * inv;
  out[6] = c02 * inv;
  out[7] = (m[1] * m[6] - m[0] * m[7]) * inv;
  out[8] = (m[0] * m[4] - m[1] * m[3]) * inv;
  return true;
}

double cross(const Point2D& o, const Point2D& a, const Point2D& b) noexcept {
  return (a.x_m - o.x_m) * (b.y_m - o.y_m) - (a.y_m - o.y_m) * (b.x_m - o.x_m);
}

// Andrew's monotone chain: the convex hull of in (sorted here) into out (room for in.size() + 1),
// counter-clockwise, no collinear points. Returns the hull's size.
std::size_t convex_hull(std::span<Point2D> in, std::span<Point2D> out) noexcept {
  std::sort(in.begin(), in.end(), [](const Point2D& a, const Point2D& b) {
    return a.x_m < b.x_m || (a.x_m == b.x_m && a.y_m < b.y_m);
  });
  const std::size_t n = in.size();
  if (n < 3) {
    std::copy(in.begin(), in.end(), out.begin());
    return n;
  }
  std::size_t k = 0;
  for (std::size_t i = 0; i < n; ++i) {
    while (k >= 2 && cross(out[k - 2], out[k - 1], in[i]) <= 0.0) --k;
    out[k++] = in[i];
  }
  const std::size_t lower = k + 1;
  for (std::size_t i = n - 1; i-- > 0;) {
    while (k >= lower && cross(out[k - 2], out[k - 1], in[i]) <= 0.0) --k;
    out[k++] = in[i];
  }
  return k - 1;  // the last point repeats the first
}

}  // namespace

double Ellipse::area_m2() const noexcept { return std::numbers::pi * semi_major_m * semi_minor_m; }

Ellipse Ellipse::from_axes(double cx_m, double cy_m, double semi_major_m, double semi_minor_m, double angle_rad) noexcept {
  Ellipse e;
  e.cx_m = cx_m;
  e.cy_m = cy_m;
  e.semi_major_m = semi_major_m;
  e.semi_minor_m = semi_minor_m;
  e.angle_rad = angle_rad;
  const double c = std::cos(angle_rad);
  const double s = std::sin(angle_rad);
  const double ia = 1.0 / (semi_major_m * semi_major_m);
  const double ib = 1.0 / (semi_minor_m * semi_minor_m);
  e.a11 = c * c * ia + s * s * ib;
  e.a22 = s * s * ia + c * c * ib;
  e.a12 = c * s * (ia - ib);
  return e;
}

bool enclosing_ellipse(std::span<const Point2D> points, std::span<double> work, double tolerance, int max_iterations,
                       Ellipse& out) noexcept {
  const std::size_t n = points.size();
  if (n < 3 || work.size() < n) return false;
  // Centred on the points' mean, for conditioning far from the map's origin.
  double mx = 0.0;
  double my = 0.0;
  for (const Point2D& p : points) {
    mx += p.x_m;
    my += p.y_m;
  }
  mx /= static_cast<double>(n);
  my /= static_cast<double>(n);
  std::span<double> u = work.first(n);
  std::fill(u.begin(), u.end(), 1.0 / static_cast<double>(n));
  bool converged = false;
  for (int iteration = 0; iteration < max_iterations; ++iteration) {
    // X = sum u_i q_i q_i', q_i = (x, y, 1), then the point farthest in X's metric.
    double x[9] = {};
    for (std::size_t i = 0; i < n; ++i) {
      const double px = points[i].x_m - mx;
      const double py = points[i].y_m - my;
      x[0] += u[i] * px * px;
      x[1] += u[i] * px * py;
      x[2] += u[i] * px;
      x[4] += u[i] * py * py;
      x[5] += u[i] * py;
      x[8] += u[i];
    }
    x[3] = x[1];
    x[6] = x[2];
    x[7] = x[5];
    double xi[9];
    if (!invert3(x, xi)) return false;  // all points on one line
    // Todd and Yildirim's version: a step towards the farthest point, or away from the
    // nearest one still weighed, whichever is further from optimal; it converges far faster
    // than Khachiyan's alone when many points are on the boundary (a disc).
    double farthest = -1.0;
    double nearest = std::numeric_limits<double>::infinity();
    std::size_t j_far = 0;
    std::size_t j_near = 0;
    for (std::size_t i = 0; i < n; ++i) {
      const double q[3] = {points[i].x_m - mx, points[i].y_m - my, 1.0};
      double m = 0.0;
      for (int r = 0; r < 3; ++r) m += q[r] * (xi[3 * r] * q[0] + xi[3 * r + 1] * q[1] + xi[3 * r + 2] * q[2]);
      if (m > farthest) {
        farthest = m;
        j_far = i;
      }
      if (u[i] > 0.0 && m < nearest) {
        nearest = m;
        j_near = i;
      }
    }
    constexpr double kD = 3.0;  // dimension + 1
    const double gap_far = farthest / kD - 1.0;
    const double gap_near = 1.0 - nearest / kD;
    if (std::max(gap_far, gap_near) < tolerance) {
      converged = true;
      break;
    }
    if (gap_far >= gap_near) {
      const double step = (farthest - kD) / (kD * (farthest - 1.0));
      for (double& w : u) w *= 1.0 - step;
      u[j_far] += step;
    } else {
      const double limit = u[j_near] / (1.0 - u[j_near]);
      const double step = std::min((kD - nearest) / (kD * (nearest - 1.0)), limit);
      for (double& w : u) w *= 1.0 + step;
      u[j_near] = step == limit ? 0.0 : u[j_near] - step;
    }
  }
  if (!converged) return false;
  // Centre and shape from the weights: A = (sum u p p' - c c')^-1 / 2.
  double cx = 0.0;
  double cy = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    cx += u[i] * (points[i].x_m - mx);
    cy += u[i] * (points[i].y_m - my);
  }
  double sxx = 0.0;
  double sxy = 0.0;
  double syy = 0.0;
  for (std::size_t i = 0; i < n; ++i) {
    const double dx = points[i].x_m - mx - cx;
    const double dy = points[i].y_m - my - cy;
    sxx += u[i] * dx * dx;
    sxy += u[i] * dx * dy;
    syy += u[i] * dy * dy;
  }
  const double det = sxx * syy - sxy * sxy;
  if (!(det > 0.0)) return false;
  double a11 = syy / det / 2.0;
  double a12 = -sxy / det / 2.0;
  double a22 = sxx / det / 2.0;
  // Exactly enclosing: the farthest point on the boundary.
  double worst = 0.0;
  for (const Point2D& p : points) {
    const double dx = p.x_m - mx - cx;
    const double dy = p.y_m - my - cy;
    worst = std::max(worst, a11 * dx * dx + 2.0 * a12 * dx * dy + a22 * dy * dy);
  }
  if (!(worst > 0.0)) return false;
  a11 /= worst;
  a12 /= worst;
  a22 /= worst;
  const SymmetricEigen form = symmetric_eigen(a11, a12, a22);
  const double small = form.smaller;  // along the major axis
  const double large = form.larger;
  if (!(small > 0.0)) return false;
  out.cx_m = mx + cx;
  out.cy_m = my + cy;
  out.a11 = a11;
  out.a12 = a12;
  out.a22 = a22;
  out.semi_major_m = 1.0 / std::sqrt(small);
  out.semi_minor_m = 1.0 / std::sqrt(large);
  // The larger eigenvalue's direction is the minor axis.
  double angle = form.larger_angle_rad + 0.5 * std::numbers::pi;
  if (angle > 0.5 * std::numbers::pi) angle -= std::numbers::pi;
  out.angle_rad = angle;
  return true;
}

std::size_t MapEllipses::storage_bytes(const MapEllipsesConfig& config) noexcept {
  const std::size_t rows = static_cast<std::size_t>(std::max(config.max_map_rows, 1));
  const auto padded = [](std::size_t bytes) { return bytes + 64; };  // alignment slack per array
  return padded(config.max_map_cells) + padded(config.max_obstacle_cells * sizeof(std::uint32_t)) +
         padded((16 * rows + 2) * sizeof(Point2D)) + padded(8 * rows * sizeof(double)) + padded(kStackDepth * sizeof(Range)) +
         padded(config.max_ellipses * sizeof(Ellipse));
}

Status MapEllipses::init(const MapEllipsesConfig& config, std::pmr::memory_resource& resource) {
  if (config.max_map_cells == 0 || config.max_map_rows < 1 || config.max_obstacle_cells == 0 || config.max_ellipses == 0 ||
      !(config.tolerance > 0.0) || config.max_iterations < 1 || !(config.max_free_fraction >= 0.0 && config.max_free_fraction <= 1.0)) {
    return Error::format(Errc::config, "map ellipses: sizes, tolerance and iterations must be positive, max_free_fraction in [0, 1]");
  }
  config_ = config;
  return guarded("map ellipses", [&]() -> Status {
    const std::size_t rows = static_cast<std::size_t>(config.max_map_rows);
    visited_ = allocate_array<std::uint8_t>(resource, config.max_map_cells);
    cells_ = allocate_array<std::uint32_t>(resource, config.max_obstacle_cells);
    points_ = allocate_array<Point2D>(resource, 16 * rows + 2);
    work_ = allocate_array<double>(resource, 8 * rows);
    stack_ = allocate_array<Range>(resource, kStackDepth);
    ellipses_ = allocate_array<Ellipse>(resource, config.max_ellipses);
    return Status::success();
  });
}

Status MapEllipses::fit(const OccupancyMap& map) noexcept {
  count_ = 0;
  splits_ = 0;
  const std::size_t n = map.cell_count();
  if (n > visited_.size() || map.height() > config_.max_map_rows) {
    return Error::format(Errc::capacity, "map ellipses: the map (%d x %d cells) is larger than configured (%zu cells, %d rows)",
                         map.width(), map.height(), visited_.size(), config_.max_map_rows);
  }
  const int w = map.width();
  const int h = map.height();
  const std::span<const std::int8_t> grid(map.cells());
  const auto occupied = [&](std::size_t i) { return grid[i] >= config_.occupied_threshold; };
  std::fill_n(visited_.begin(), n, std::uint8_t{0});
  std::size_t total = 0;
  for (std::size_t start = 0; start < n; ++start) {
    if (visited_[start] != 0 || !occupied(start)) continue;
    // One 8-connected group, gathered breadth-first into cells_[begin, total).
    const std::size_t begin = total;
    if (total >= cells_.size()) {
      count_ = 0;
      return Error::format(Errc::capacity, "map ellipses: more than %zu occupied cells", cells_.size());
    }
    visited_[start] = 1;
    cells_[total++] = static_cast<std::uint32_t>(start);
    for (std::size_t head = begin; head < total; ++head) {
      const int col = static_cast<int>(cells_[head] % static_cast<std::uint32_t>(w));
      const int row = static_cast<int>(cells_[head] / static_cast<std::uint32_t>(w));
      for (int dr = -1; dr <= 1; ++dr) {
        for (int dc = -1; dc <= 1; ++dc) {
          const int c = col + dc;
          const int r = row + dr;
          if ((dr == 0 && dc == 0) || c < 0 || r < 0 || c >= w || r >= h) continue;
          const std::size_t k = static_cast<std::size_t>(r) * static_cast<std::size_t>(w) + static_cast<std::size_t>(c);
          if (visited_[k] != 0 || !occupied(k)) continue;
          if (total >= cells_.size()) {
            count_ = 0;
            return Error::format(Errc::capacity, "map ellipses: more than %zu occupied cells", cells_.size());
          }
          visited_[k] = 1;
          cells_[total++] = static_cast<std::uint32_t>(k);
        }
      }
    }
    if (Status s = fit_group(map, static_cast<std::uint32_t>(begin), static_cast<std::uint32_t>(total)); !s) {
      count_ = 0;
      return s;
    }
  }
  return Status::success();
}

Status MapEllipses::fit_group(const OccupancyMap& map, std::uint32_t begin, std::uint32_t end) noexcept {
  std::size_t depth = 0;
  stack_[depth++] = {begin, end};
  while (depth > 0) {
    const Range range = stack_[--depth];
    Ellipse e;
    if (!fit_cells(map, range.begin, range.end, e)) {
      return Error::format(Errc::invalid_argument, "map ellipses: the ellipse of %u cells did not converge",
                           range.end - range.begin);
    }
    const std::uint32_t size = range.end - range.begin;
    if (size >= config_.min_split_cells && depth + 2 <= stack_.size() && free_fraction(map, e) > config_.max_free_fraction) {
      std::uint32_t middle = range.begin;
      split(map, range.begin, range.end, middle);
      ++splits_;
      // The first half on top: the ellipses come out in the order of the cells.
      stack_[depth++] = {middle, range.end};
      stack_[depth++] = {range.begin, middle};
      continue;
    }
    if (count_ >= ellipses_.size()) {
      return Error::format(Errc::capacity, "map ellipses: more than %zu ellipses", ellipses_.size());
    }
    ellipses_[count_++] = e;
  }
  return Status::success();
}

bool MapEllipses::fit_cells(const OccupancyMap& map, std::uint32_t begin, std::uint32_t end, Ellipse& out) noexcept {
  // Row-major indices sort by row, then column: per row its first and last cell hold every
  // corner the hull can use.
  const std::span<std::uint32_t> group = cells_.subspan(begin, end - begin);
  std::sort(group.begin(), group.end());
  const GridGeometry& g = map.geometry();
  const auto w = static_cast<std::uint32_t>(map.width());
  const std::size_t half = points_.size() / 2;
  std::size_t n = 0;
  const auto add_corners = [&](std::uint32_t cell) {
    const double col = static_cast<double>(cell % w);
    const double row = static_cast<double>(cell / w);
    for (const double dc : {0.0, 1.0}) {
      for (const double dr : {0.0, 1.0}) {
        Point2D p;
        g.grid_to_world(col + dc, row + dr, p.x_m, p.y_m);
        points_[n++] = p;
      }
    }
  };
  for (std::size_t i = 0; i < group.size();) {
    const std::uint32_t row = group[i] / w;
    std::size_t last = i;
    while (last + 1 < group.size() && group[last + 1] / w == row) ++last;
    if (n + 8 > half) return false;
    add_corners(group[i]);
    if (last != i) add_corners(group[last]);
    i = last + 1;
  }
  const std::size_t hull = convex_hull(points_.first(n), points_.subspan(half));
  if (!enclosing_ellipse(points_.subspan(half, hull), work_, config_.tolerance, config_.max_iterations, out)) return false;
  out.cells = end - begin;
  return true;
}

double MapEllipses::free_fraction(const OccupancyMap& map, const Ellipse& e) const noexcept {
  // The map cells whose centres lie inside: how many of them are free (known and below the
  // occupied threshold; unknown space is not a corridor).
  const GridGeometry& g = map.geometry();
  const double r = e.semi_major_m;
  double gx0 = 0.0;
  double gy0 = 0.0;
  // The bounding box in grid coordinates (a rotated map turns it; take the corners' extent).
  double lo_x = std::numeric_limits<double>::infinity();
  double lo_y = lo_x;
  double hi_x = -lo_x;
  double hi_y = -lo_x;
  for (const double sx : {-1.0, 1.0}) {
    for (const double sy : {-1.0, 1.0}) {
      g.world_to_grid(e.cx_m + sx * r, e.cy_m + sy * r, gx0, gy0);
      lo_x = std::min(lo_x, gx0);
      lo_y = std::min(lo_y, gy0);
      hi_x = std::max(hi_x, gx0);
      hi_y = std::max(hi_y, gy0);
    }
  }
  const int c0 = std::max(0, static_cast<int>(std::floor(lo_x)));
  const int r0 = std::max(0, static_cast<int>(std::floor(lo_y)));
  const int c1 = std::min(map.width() - 1, static_cast<int>(std::ceil(hi_x)));
  const int r1 = std::min(map.height() - 1, static_cast<int>(std::ceil(hi_y)));
  std::size_t inside = 0;
  std::size_t free = 0;
  for (int row = r0; row <= r1; ++row) {
    for (int col = c0; col <= c1; ++col) {
      double x = 0.0;
      double y = 0.0;
      g.cell_to_world(col, row, x, y);
      if (e.value(x, y) > 0.0) continue;
      ++inside;
      const std::int8_t v = map.at(col, row);
      if (v >= 0 && v < config_.occupied_threshold) ++free;
    }
  }
  return inside == 0 ? 0.0 : static_cast<double>(free) / static_cast<double>(inside);
}

void MapEllipses::split(const OccupancyMap& map, std::uint32_t begin, std::uint32_t end, std::uint32_t& middle) noexcept {
  // The cells' principal axis (their centres' scatter), then the median along it.
  const auto w = static_cast<std::uint32_t>(map.width());
  double mx = 0.0;
  double my = 0.0;
  for (std::uint32_t i = begin; i < end; ++i) {
    mx += static_cast<double>(cells_[i] % w);
    my += static_cast<double>(cells_[i] / w);
  }
  const double count = static_cast<double>(end - begin);
  mx /= count;
  my /= count;
  double sxx = 0.0;
  double sxy = 0.0;
  double syy = 0.0;
  for (std::uint32_t i = begin; i < end; ++i) {
    const double dx = static_cast<double>(cells_[i] % w) - mx;
    const double dy = static_cast<double>(cells_[i] / w) - my;
    sxx += dx * dx;
    sxy += dx * dy;
    syy += dy * dy;
  }
  const double angle = symmetric_eigen(sxx, sxy, syy).larger_angle_rad;  // the larger spread
  const double ux = std::cos(angle);
  const double uy = std::sin(angle);
  const auto key = [&](std::uint32_t cell) {
    return ux * static_cast<double>(cell % w) + uy * static_cast<double>(cell / w);
  };
  middle = begin + (end - begin) / 2;
  // Ties broken by the index: the same map always splits the same way.
  std::nth_element(cells_.begin() + begin, cells_.begin() + middle, cells_.begin() + end, [&](std::uint32_t a, std::uint32_t b) {
    const double ka = key(a);
    const double kb = key(b);
    return ka < kb || (ka == kb && a < b);
  });
}

}  // namespace sen3bot::nav
