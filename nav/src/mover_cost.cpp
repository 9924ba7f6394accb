#include "sen3bot/nav/mover_cost.hpp"

#include <algorithm>
#include <cmath>

namespace sen3bot::nav {

namespace {

// The Gaussian around one mover, prepared once for many cells.
struct MoverShape {
  double cos_h = 1.0;  // velocity direction
  double sin_h = 0.0;
  double plateau_m = 0.0;  // flat stretch ahead
  double inv_front_x = 0.0;  // 1 / (2 σ²)
  double inv_front_y = 0.0;
  double inv_back_x = 0.0;
  double inv_back_y = 0.0;
  double amplitude = 0.0;
  double cutoff = 0.0;
  double limit = -1.0;  // exponents above this give less than cutoff
  double reach_front_m = 0.0;
  double reach_back_m = 0.0;
  double reach_side_m = 0.0;
};

MoverShape make_shape(const DolCostConfig& config, double vx, double vy) noexcept {
  constexpr double kMinSigma2 = 1e-4;
  MoverShape shape;
  const double speed = std::hypot(vx, vy);
  const double heading = std::atan2(vy, vx);  // 0 at rest
  shape.cos_h = std::cos(heading);
  shape.sin_h = std::sin(heading);
  const double r = config.max_speed_m_s > 0.0 ? std::min(1.0, speed / config.max_speed_m_s) : 1.0;
  shape.plateau_m = std::max(0.0, config.front_horizon_s) * speed;
  const double front_x = std::max(kMinSigma2, (1.0 + r) * config.sigma2_front_x_m2);
  const double front_y = std::max(kMinSigma2, (1.0 - r / 2.0) * config.sigma2_front_y_m2);
  const double back_x = std::max(kMinSigma2, (1.0 - r) * config.sigma2_back_x_m2);
  const double back_y = std::max(kMinSigma2, (1.0 - r / 4.0) * config.sigma2_back_y_m2);
  shape.inv_front_x = 1.0 / (2.0 * front_x);
  shape.inv_front_y = 1.0 / (2.0 * front_y);
  shape.inv_back_x = 1.0 / (2.0 * back_x);
  shape.inv_back_y = 1.0 / (2.0 * back_y);
  shape.amplitude = std::min(config.amplitude, static_cast<double>(kMaxNonObstacleCost));
  shape.cutoff = config.cutoff;
  if (shape.amplitude > 0.0 && shape.amplitude >= config.cutoff) {
    shape.limit = config.cutoff > 0.0 ? std::log(shape.amplitude / config.cutoff) : 50.0;
    // exponent = along² / (2σ²) <= limit  <=>  |along| <= σ sqrt(2 limit)
    const double k = std::sqrt(2.0 * shape.limit);
    shape.reach_front_m = shape.plateau_m + k * std::sqrt(front_x);
    shape.reach_back_m = k * std::sqrt(back_x);
    shape.reach_side_m = k * std::sqrt(std::max(front_y, back_y));
  }
  return shape;
}

// The three pieces of the shape along the velocity: behind, the flat stretch, ahead of it.
enum Piece : int { kBack = 0, kPlateau = 1, kFront = 2 };

Piece piece_of(const MoverShape& shape, double along) noexcept {
  if (along <= 0.0) return kBack;
  return along <= shape.plateau_m ? kPlateau : kFront;
}

// The exponent with one piece's formula (each a quadratic in along and across).
double piece_exponent(const MoverShape& shape, Piece piece, double along, double across) noexcept {
  switch (piece) {
    case kBack:
      return along * along * shape.inv_back_x + across * across * shape.inv_back_y;
    case kPlateau:
      return across * across * shape.inv_front_y;
    case kFront:
      break;
  }
  const double ahead = along - shape.plateau_m;
  return ahead * ahead * shape.inv_front_x + across * across * shape.inv_front_y;
}

// The value at offset (dx, dy) from the mover's centre; 0 below the cutoff.
double shape_value(const MoverShape& shape, double dx, double dy) noexcept {
  const double along = dx * shape.cos_h + dy * shape.sin_h;
  const double across = -dx * shape.sin_h + dy * shape.cos_h;
  const double exponent = piece_exponent(shape, piece_of(shape, along), along, across);
  if (exponent > shape.limit) return 0.0;
  const double value = shape.amplitude * std::exp(-exponent);
  return value < shape.cutoff ? 0.0 : value;
}

// floor() or ceil() of a cell coordinate as an int, clamped to [-1, limit] first so that a
// point far off the grid cannot overflow the cast.
int clamped_cell(double v, int limit) noexcept {
  return static_cast<int>(std::clamp(std::isnan(v) ? -1.0 : v, -1.0, static_cast<double>(limit)));
}

// The dx with a * dx in [lo, hi], intersected into [dx_min, dx_max].
void restrict_interval(double a, double lo, double hi, double& dx_min, double& dx_max) noexcept {
  if (std::abs(a) < 1e-12) {
    if (lo > 0.0 || hi < 0.0) dx_max = dx_min - 1.0;  // empty
    return;
  }
  const double x0 = lo / a;
  const double x1 = hi / a;
  dx_min = std::max(dx_min, std::min(x0, x1));
  dx_max = std::min(dx_max, std::max(x0, x1));
}

}  // namespace

// Marks the cells whose centre lies within radius_m of (x, y), and the cell holding it, lethal.
void paint_core(double x_m, double y_m, double radius_m, Costmap2D& grid) noexcept {
  const GridGeometry& g = grid.geometry();
  double gx = 0.0;
  double gy = 0.0;
  g.world_to_grid(x_m, y_m, gx, gy);
  int col = 0;
  int row = 0;
  if (grid.world_to_cell(x_m, y_m, col, row)) grid.set(col, row, kLethalCost);
  const double reach = std::max(0.0, radius_m) / g.resolution_m();
  const int r0 = std::max(0, clamped_cell(std::floor(gy - 0.5 - reach), g.height()));
  const int r1 = std::min(g.height() - 1, clamped_cell(std::ceil(gy - 0.5 + reach), g.height()));
  const int c0 = std::max(0, clamped_cell(std::floor(gx - 0.5 - reach), g.width()));
  const int c1 = std::min(g.width() - 1, clamped_cell(std::ceil(gx - 0.5 + reach), g.width()));
  const double reach2 = reach * reach;
  for (int r = r0; r <= r1; ++r) {
    const double dy = r + 0.5 - gy;
    for (int c = c0; c <= c1; ++c) {
      const double dx = c + 0.5 - gx;
      if (dx * dx + dy * dy <= reach2) grid.set(c, r, kLethalCost);
    }
  }
}

double mover_cost(const DolCostConfig& config, double cx, double cy, double vx, double vy, double x_m,
                  double y_m) noexcept {
  return shape_value(make_shape(config, vx, vy), x_m - cx, y_m - cy);
}

void paint_mover(const DolCostConfig& config, double cx, double cy, double vx, double vy, Costmap2D& grid) noexcept {
  MoverShape shape = make_shape(config, vx, vy);
  if (shape.limit < 0.0) return;
  // Work in the grid's frame: distances and relative angles are the same as in the map frame.
  const GridGeometry& g = grid.geometry();
  const double res = g.resolution_m();
  const double yaw_c = std::cos(g.origin_yaw_rad());
  const double yaw_s = std::sin(g.origin_yaw_rad());
  const double cos_h = shape.cos_h * yaw_c + shape.sin_h * yaw_s;  // heading - yaw
  const double sin_h = shape.sin_h * yaw_c - shape.cos_h * yaw_s;
  shape.cos_h = cos_h;
  shape.sin_h = sin_h;
  double gx = 0.0;
  double gy = 0.0;
  g.world_to_grid(cx, cy, gx, gy);
  const double reach = std::max({shape.reach_front_m, shape.reach_back_m, shape.reach_side_m}) / res;
  const int r0 = std::max(0, clamped_cell(std::floor(gy - 0.5 - reach), g.height()));
  const int r1 = std::min(g.height() - 1, clamped_cell(std::ceil(gy - 0.5 + reach), g.height()));
  constexpr double kSlack = 1e-9;
  const auto cells = grid.cells();
  // Per piece, exp(-2 a res²) with a the exponent's x² coefficient along a row.
  const double res2 = res * res;
  const double step_ratio[3] = {
      std::exp(-2.0 * res2 * (shape.inv_back_x * cos_h * cos_h + shape.inv_back_y * sin_h * sin_h)),
      std::exp(-2.0 * res2 * (shape.inv_front_y * sin_h * sin_h)),
      std::exp(-2.0 * res2 * (shape.inv_front_x * cos_h * cos_h + shape.inv_front_y * sin_h * sin_h))};
  for (int r = r0; r <= r1; ++r) {
    const double dy = (r + 0.5 - gy) * res;
    // The cells of this row inside the box along ∈ [-back, front], across ∈ [-side, side].
    double dx_min = -std::numeric_limits<double>::infinity();
    double dx_max = std::numeric_limits<double>::infinity();
    restrict_interval(cos_h, -shape.reach_back_m - dy * sin_h - kSlack, shape.reach_front_m - dy * sin_h + kSlack,
                      dx_min, dx_max);
    restrict_interval(-sin_h, -shape.reach_side_m - dy * cos_h - kSlack, shape.reach_side_m - dy * cos_h + kSlack,
                      dx_min, dx_max);
    if (!(dx_min <= dx_max)) continue;
    const int c0 = std::max(0, clamped_cell(std::ceil(gx - 0.5 + dx_min / res), g.width()));
    const int c1 = std::min(g.width() - 1, clamped_cell(std::floor(gx - 0.5 + dx_max / res), g.width()));
    // Along a row each piece's exponent is a quadratic in the column, so exp(-exponent) follows
    // from cell to cell by two multiplications: g(k+1) = g(k) ratio(k), ratio(k+1) = ratio(k) m,
    // with m = exp(-2 a res²) for the quadratic's leading coefficient a. exp() is called only
    // where a row enters a piece.
    const std::size_t row = g.index(0, r);
    const double x0 = (c0 + 0.5 - gx) * res;
    const double along0 = x0 * cos_h + dy * sin_h;
    const double across0 = -x0 * sin_h + dy * cos_h;
    const double step_along = res * cos_h;
    const double step_across = -res * sin_h;
    const double floor_g = shape.cutoff / shape.amplitude;
    int piece = -1;
    double g_value = 0.0;
    double ratio = 0.0;
    for (int c = c0; c <= c1; ++c) {
      const double k = c - c0;
      const double along = along0 + k * step_along;
      const Piece here = piece_of(shape, along);
      if (here != piece) {
        piece = here;
        const double across = across0 + k * step_across;
        const double e = piece_exponent(shape, here, along, across);
        const double e_next = piece_exponent(shape, here, along + step_along, across + step_across);
        g_value = std::exp(-e);
        ratio = std::exp(e - e_next);
      } else {
        g_value *= ratio;
        ratio *= step_ratio[piece];
      }
      if (g_value < floor_g) continue;
      const auto cost = static_cast<std::uint8_t>(std::min(shape.amplitude, shape.amplitude * g_value));
      std::uint8_t& cell = cells[row + static_cast<std::size_t>(c)];
      if (cost > cell) cell = cost;
    }
  }
}

}  // namespace sen3bot::nav
