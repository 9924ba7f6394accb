#include "sen3bot/slam/scan_matcher.hpp"

#include <algorithm>
#include <cmath>

#include "sen3bot/nav/arena.hpp"

namespace sen3bot::slam {
namespace {

constexpr int kMaxWindowCells = 64;

double max_range(std::span<const PointF> points) noexcept {
  double m = 0.0;
  for (const PointF& p : points) m = std::max(m, std::hypot(static_cast<double>(p.x), static_cast<double>(p.y)));
  return m;
}

// Bilinear probability at continuous grid coordinates, with its gradient there.
double surface(const ProbabilityView& g, double gx, double gy, double& du, double& dv) noexcept {
  const double u = gx - 0.5;
  const double v = gy - 0.5;
  const double fu = std::floor(u);
  const double fv = std::floor(v);
  const int c = static_cast<int>(fu);
  const int r = static_cast<int>(fv);
  const double a = u - fu;
  const double b = v - fv;
  const double p00 = g.probability(c, r);
  const double p10 = g.probability(c + 1, r);
  const double p01 = g.probability(c, r + 1);
  const double p11 = g.probability(c + 1, r + 1);
  du = (1.0 - b) * (p10 - p00) + b * (p11 - p01);
  dv = (1.0 - a) * (p01 - p00) + a * (p11 - p10);
  return (1.0 - a) * (1.0 - b) * p00 + a * (1.0 - b) * p10 + (1.0 - a) * b * p01 + a * b * p11;
}

struct Refinement {
  const ProbabilityView& grid;
  std::span<const PointF> points;
  nav::Pose2D anchor;
  double wt;
  double wr;

  double cost(const nav::Pose2D& p) const noexcept {
    double sum = 0.0;
    const double c = std::cos(p.theta_rad);
    const double s = std::sin(p.theta_rad);
    for (const PointF& q : points) {
      double du = 0.0;
      double dv = 0.0;
      const double m = surface(grid, grid.grid_x(p.x_m + c * q.x - s * q.y), grid.grid_y(p.y_m + s * q.x + c * q.y), du, dv);
      sum += (1.0 - m) * (1.0 - m);
    }
    const double dx = p.x_m - anchor.x_m;
    const double dy = p.y_m - anchor.y_m;
    const double da = nav::normalize_angle(p.theta_rad - anchor.theta_rad);
    return sum / static_cast<double>(points.size()) + wt * (dx * dx + dy * dy) + wr * da * da;
  }
};

}  // namespace

double angular_step(double resolution_m, double range_m) noexcept {
  const double r = std::max(range_m, 4.0 * resolution_m);
  return std::acos(1.0 - resolution_m * resolution_m / (2.0 * r * r));
}

double match_score(const ProbabilityView& grid, const nav::Pose2D& pose, std::span<const PointF> points) noexcept {
  if (points.empty()) return 0.0;
  const double c = std::cos(pose.theta_rad);
  const double s = std::sin(pose.theta_rad);
  double sum = 0.0;
  for (const PointF& q : points) {
    const double gx = grid.grid_x(pose.x_m + c * q.x - s * q.y);
    const double gy = grid.grid_y(pose.y_m + s * q.x + c * q.y);
    sum += grid.probability(static_cast<int>(std::floor(gx)), static_cast<int>(std::floor(gy)));
  }
  return sum / static_cast<double>(points.size());
}

Match refine_match(const ProbabilityView& grid, const nav::Pose2D& start, std::span<const PointF> points,
                   double translation_weight, double rotation_weight, int iterations) noexcept {
  if (points.empty()) return {start, 0.0};
  const Refinement f{grid, points, start, translation_weight, rotation_weight};
  nav::Pose2D p = start;
  double cost = f.cost(p);
  const double inv_n = 1.0 / static_cast<double>(points.size());
  const double inv_res = 1.0 / grid.resolution_m;
  for (int it = 0; it < iterations; ++it) {
    double h[3][3] = {};
    double g[3] = {};
    const double c = std::cos(p.theta_rad);
    const double s = std::sin(p.theta_rad);
    for (const PointF& q : points) {
      const double wx = p.x_m + c * q.x - s * q.y;
      const double wy = p.y_m + s * q.x + c * q.y;
      double du = 0.0;
      double dv = 0.0;
      const double m = surface(grid, grid.grid_x(wx), grid.grid_y(wy), du, dv);
      const double r = 1.0 - m;
      // d r / d (x, y, theta)
      const double j[3] = {-du * inv_res, -dv * inv_res, -(du * (-s * q.x - c * q.y) + dv * (c * q.x - s * q.y)) * inv_res};
      for (int a = 0; a < 3; ++a) {
        g[a] += j[a] * r * inv_n;
        for (int b = 0; b < 3; ++b) h[a][b] += j[a] * j[b] * inv_n;
      }
    }
    g[0] += translation_weight * (p.x_m - start.x_m);
    g[1] += translation_weight * (p.y_m - start.y_m);
    g[2] += rotation_weight * nav::normalize_angle(p.theta_rad - start.theta_rad);
    h[0][0] += translation_weight;
    h[1][1] += translation_weight;
    h[2][2] += rotation_weight;
    // 3x3 solve by Cramer's rule: h is symmetric positive definite (the priors make it so).
    const double det = h[0][0] * (h[1][1] * h[2][2] - h[1][2] * h[2][1]) - h[0][1] * (h[1][0] * h[2][2] - h[1][2] * h[2][0]) +
                       h[0][2] * (h[1][0] * h[2][1] - h[1][1] * h[2][0]);
    if (!(std::abs(det) > 1e-18)) break;
    const auto solve = [&](int col) {
      double m[3][3];
      for (int a = 0; a < 3; ++a)
        for (int b = 0; b < 3; ++b) m[a][b] = b == col ? -g[a] : h[a][b];
      return (m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) +
              m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])) /
             det;
    };
    const double step[3] = {solve(0), solve(1), solve(2)};
    double scale = 1.0;
    bool moved = false;
    for (int tries = 0; tries < 4; ++tries, scale *= 0.5) {
      const nav::Pose2D trial{p.x_m + scale * step[0], p.y_m + scale * step[1],
                              nav::normalize_angle(p.theta_rad + scale * step[2])};
      const double trial_cost = f.cost(trial);
      if (trial_cost < cost) {
        p = trial;
        cost = trial_cost;
        moved = true;
        break;
      }
    }
    if (!moved || std::hypot(step[0], step[1]) * scale < 1e-5 * grid.resolution_m) break;
  }
  return {p, match_score(grid, p, points)};
}

Status ScanMatcher::init(std::pmr::memory_resource& arena, std::size_t max_points, const LocalMatchConfig& config) {
  if (!(config.linear_window_m >= 0.0) || !(config.angular_window_rad >= 0.0) || config.refine_iterations < 0)
    return Error(Errc::invalid_argument, "scan matcher: windows and iterations must not be negative");
  config_ = config;
  return nav::guarded("scan matcher", [&]() -> Status {
    cols_ = nav::allocate_array<int>(arena, max_points);
    rows_ = nav::allocate_array<int>(arena, max_points);
    sums_ = nav::allocate_array<float>(arena, static_cast<std::size_t>((2 * kMaxWindowCells + 1) * (2 * kMaxWindowCells + 1)));
    return {};
  });
}

Match ScanMatcher::match(const ProbabilityView& grid, const nav::Pose2D& prior, std::span<const PointF> points) noexcept {
  points = points.first(std::min(points.size(), cols_.size()));
  if (points.empty()) return {prior, 0.0};
  const double res = grid.resolution_m;
  const int half = std::min(kMaxWindowCells, static_cast<int>(std::ceil(config_.linear_window_m / res)));
  const int side = 2 * half + 1;
  const double step = angular_step(res, max_range(points));
  const int angles = static_cast<int>(std::ceil(config_.angular_window_rad / step));
  const auto& table = probability_table();
  const double inv_n = 1.0 / static_cast<double>(points.size());
  Match best{prior, -1.0};
  double best_penalised = -1.0;
  for (int k = -angles; k <= angles; ++k) {
    const double da = k * step;
    const double th = prior.theta_rad + da;
    const double c = std::cos(th);
    const double s = std::sin(th);
    for (std::size_t i = 0; i < points.size(); ++i) {
      const PointF& q = points[i];
      cols_[i] = static_cast<int>(std::floor(grid.grid_x(prior.x_m + c * q.x - s * q.y)));
      rows_[i] = static_cast<int>(std::floor(grid.grid_y(prior.y_m + s * q.x + c * q.y)));
    }
    std::fill(sums_.begin(), sums_.begin() + side * side, 0.0F);
    for (std::size_t i = 0; i < points.size(); ++i) {
      for (int dy = -half; dy <= half; ++dy) {
        float* out = &sums_[static_cast<std::size_t>((dy + half) * side)];
        const int row = rows_[i] + dy;
        if (row < 0 || row >= grid.height) {
          for (int dx = 0; dx < side; ++dx) out[dx] += table[0];
          continue;
        }
        const std::uint8_t* line = grid.cells + static_cast<std::size_t>(row) * static_cast<std::size_t>(grid.width);
        for (int dx = -half; dx <= half; ++dx) {
          const int col = cols_[i] + dx;
          out[dx + half] += table[(col >= 0 && col < grid.width) ? line[col] : 0];
        }
      }
    }
    for (int dy = -half; dy <= half; ++dy)
      for (int dx = -half; dx <= half; ++dx) {
        const double score = sums_[static_cast<std::size_t>((dy + half) * side + dx + half)] * inv_n;
        const double d2 = (dx * res) * (dx * res) + (dy * res) * (dy * res);
        const double penalised =
            score * std::exp(-(config_.search_translation_weight * d2 + config_.search_rotation_weight * da * da));
        if (penalised > best_penalised) {
          best_penalised = penalised;
          best = {{prior.x_m + dx * res, prior.y_m + dy * res, nav::normalize_angle(th)}, score};
        }
      }
  }
  if (config_.refine_iterations == 0) return best;
  return refine_match(grid, best.pose, points, config_.refine_translation_weight, config_.refine_rotation_weight,
                      config_.refine_iterations);
}

}  // namespace sen3bot::slam
