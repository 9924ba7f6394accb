#include "sen3bot/sim/report/sgp_layer.hpp"

#include <algorithm>
#include <cmath>

namespace sen3bot::sim::report {

std::vector<std::array<msg::Point2D, 2>> trace_curve(const nav::SafeCurve& curve, const nav::CurveBounds& box,
                                                     double step_m) {
  std::vector<std::array<msg::Point2D, 2>> segments;
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
      const msg::Point2D c[4] = {{x0, y0}, {x1, y0}, {x1, y1}, {x0, y1}};
      msg::Point2D cross[4];
      int n = 0;
      for (int e = 0; e < 4; ++e) {
        const double a = v[e], b = v[(e + 1) % 4];
        if ((a < 0) == (b < 0)) continue;
        const double t = a / (a - b);
        const msg::Point2D& p = c[e];
        const msg::Point2D& q = c[(e + 1) % 4];
        cross[n++] = {p.x_m + t * (q.x_m - p.x_m), p.y_m + t * (q.y_m - p.y_m)};
      }
      // Two crossings: one segment; four (a saddle): pair them in order round the cell.
      for (int k = 0; k + 1 < n; k += 2) segments.push_back({cross[k], cross[k + 1]});
    }
    std::swap(below, above);
  }
  return segments;
}

void add_sgp_layer(CaseFigure& figure, const nav::SupervisoryPlanner& sgp, int direction, double quiver_spacing_m) {
  const nav::OccupancyMap& map = *figure.map;
  const double w = map.width() * map.resolution_m(), h = map.height() * map.resolution_m();
  const nav::CurveBounds& bounds = sgp.bounds();
  const nav::CurveBounds box{std::max(bounds.x0_m, map.origin_x_m()), std::max(bounds.y0_m, map.origin_y_m()),
                             std::min(bounds.x1_m, map.origin_x_m() + w), std::min(bounds.y1_m, map.origin_y_m() + h)};
  for (const nav::Ellipse& e : sgp.obstacles())
    figure.ellipses.push_back({{e.cx_m, e.cy_m}, e.semi_major_m, e.semi_minor_m, e.angle_rad});
  figure.curve = trace_curve(sgp.curve(), box, 0.02);
  if (!(quiver_spacing_m > 0)) return;
  const double arrow_m = 0.4 * quiver_spacing_m;
  for (double y = box.y0_m + quiver_spacing_m / 2; y < box.y1_m; y += quiver_spacing_m)
    for (double x = box.x0_m + quiver_spacing_m / 2; x < box.x1_m; x += quiver_spacing_m) {
      const nav::Point2D f = sgp.field(x, y, direction);
      const double n = std::hypot(f.x_m, f.y_m);
      if (!(n > 0) || !std::isfinite(n)) continue;
      figure.field.push_back({{x - arrow_m / 2 * f.x_m / n, y - arrow_m / 2 * f.y_m / n},
                              {x + arrow_m / 2 * f.x_m / n, y + arrow_m / 2 * f.y_m / n}});
    }
}

}  // namespace sen3bot::sim::report
