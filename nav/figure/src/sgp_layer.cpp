#include "sen3bot/nav_figure/sgp_layer.hpp"

#include <algorithm>
#include <cmath>

namespace sen3bot::figure {

void add_sgp_layer(CaseFigure& figure, const nav::SupervisoryPlanner& sgp, int direction, double quiver_spacing_m) {
  const nav::CurveBounds box = nav::intersect(sgp.bounds(), nav::map_extent(*figure.map));
  for (const nav::Ellipse& e : sgp.obstacles())
    figure.ellipses.push_back({{e.cx_m, e.cy_m}, e.semi_major_m, e.semi_minor_m, e.angle_rad});
  figure.curve = nav::trace_curve(sgp.curve(), box, 0.02);
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

}  // namespace sen3bot::figure
