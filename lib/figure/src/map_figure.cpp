#include "sen3bot/figure/map_figure.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>

namespace sen3bot::figure {

using namespace colours;

std::string format(const char* fmt, double v) {
  char buf[96];
  std::snprintf(buf, sizeof buf, fmt, v);
  return buf;
}

double figure_scale(const Grid& grid) noexcept {
  const double extent_m = std::max(grid.width, grid.height) * grid.resolution_m;
  return extent_m > 9.5 ? 760.0 / extent_m : 80.0;
}

void draw_grid(Canvas& canvas, const View& view, const Grid& grid) {
  const double res = grid.resolution_m;
  for (int row = 0; row < grid.height; ++row)
    for (int col = 0; col < grid.width; ++col) {
      const std::int8_t v = grid.at(col, row);
      if (v >= 0 && v < 50) continue;  // free: the paper
      const double x_m = grid.origin_x_m + col * res, y_m = grid.origin_y_m + row * res;
      const Px lo = view(x_m, y_m), hi = view(x_m + res, y_m + res);  // hi is up and right
      const int x0 = static_cast<int>(std::lround(lo.x)), x1 = static_cast<int>(std::lround(hi.x));
      const int y0 = static_cast<int>(std::lround(hi.y)), y1 = static_cast<int>(std::lround(lo.y));
      canvas.fill_rect(x0, y0, x1 - x0, y1 - y0, v < 0 ? kUnknown : kWall);
    }
}

bool has_unknown(const Grid& grid) noexcept {
  return std::any_of(grid.cells.begin(), grid.cells.end(), [](std::int8_t v) { return v < 0; });
}

double tick_step(double extent_m) noexcept {
  for (const double step : {0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0})
    if (extent_m / step <= 10.5) return step;
  return 100.0;
}

void draw_axes(Canvas& canvas, const View& view, const Grid& grid, int left, int top, int w, int h) {
  const double width_m = grid.width_m(), height_m = grid.height_m();
  const std::vector<Px> frame{{left - 1.0, top - 1.0},
                              {static_cast<double>(left + w), top - 1.0},
                              {static_cast<double>(left + w), static_cast<double>(top + h)},
                              {left - 1.0, static_cast<double>(top + h)}};
  canvas.outline_polygon(frame, kInk, 1);
  const double step = tick_step(std::max(width_m, height_m));
  const char* tick_format = step < 1 ? "%.1f" : "%.0f";
  for (double m = std::ceil(grid.origin_x_m / step) * step; m <= grid.origin_x_m + width_m + 1e-9; m += step) {
    const double x = view(m, 0).x;
    const double y = top + h;
    canvas.line({x, y}, {x, y + 5}, kInk);
    const std::string label = format(tick_format, m);
    canvas.text({x - Canvas::text_width(label, kSmallSize) / 2.0, y + 18}, label, kInk, kSmallSize);
  }
  for (double m = std::ceil(grid.origin_y_m / step) * step; m <= grid.origin_y_m + height_m + 1e-9; m += step) {
    const double y = view(0, m).y;
    const double x = left - 1.0;
    canvas.line({x - 5, y}, {x, y}, kInk);
    const std::string label = format(tick_format, m);
    canvas.text({x - 8 - Canvas::text_width(label, kSmallSize), y + 5}, label, kInk, kSmallSize);
  }
  canvas.text({left + w / 2.0 - 14, static_cast<double>(top + h + 36)}, "x (m)", kInk, kLineSize);
  canvas.text({kMargin, top - 8.0}, "y (m)", kInk, kLineSize);
}

double scale_bar_length_m(double px_per_m) noexcept {
  for (const double l : {0.5, 1.0, 2.0, 5.0, 10.0, 20.0, 50.0})
    if (l * px_per_m >= 60) return l;
  return 100.0;
}

void draw_scale_bar(Canvas& canvas, int x, int y, double px_per_m) {
  const double length_m = scale_bar_length_m(px_per_m);
  const int w = static_cast<int>(std::lround(length_m * px_per_m));
  canvas.fill_rect(x, y, w / 2, 6, kInk);
  canvas.fill_rect(x + w / 2, y, w - w / 2, 6, kPaper);
  // The white half's border, on the pixels just outside it.
  canvas.fill_rect(x + w / 2, y - 1, w - w / 2 + 1, 1, kInk);
  canvas.fill_rect(x + w / 2, y + 6, w - w / 2 + 1, 1, kInk);
  canvas.fill_rect(x + w, y, 1, 6, kInk);
  canvas.text({x - 3.0, y + 22.0}, "0", kInk, kSmallSize);
  canvas.text({x + w - 6.0, y + 22.0}, format(length_m < 1 ? "%.1f m" : "%.0f m", length_m), kInk, kSmallSize);
}

int legend_width(std::span<const LegendEntry> entries) {
  int w = 0;
  for (const LegendEntry& e : entries) w = std::max(w, kSwatch + 10 + Canvas::text_width(e.label, kLineSize));
  return w;
}

int legend_height(std::span<const LegendEntry> entries) { return static_cast<int>(entries.size()) * kRowPitch + 60; }

void draw_legend(Canvas& canvas, int x, int top, std::span<const LegendEntry> entries, double px_per_m) {
  double y = top + 10.0;
  for (const LegendEntry& e : entries) {
    e.swatch(canvas, {x + kSwatch / 2.0, y});
    canvas.text({static_cast<double>(x + kSwatch + 10), y + 5}, e.label, kInk, kLineSize);
    y += kRowPitch;
  }
  canvas.text({static_cast<double>(x), y + 8}, "scale", kInk, kLineSize);
  draw_scale_bar(canvas, x + 52, static_cast<int>(y) + 2, px_per_m);
}

void draw_arrow(Canvas& canvas, Px from, Px to, Rgb colour, int thickness) {
  canvas.line(from, to, colour, thickness);
  const double dx = to.x - from.x, dy = to.y - from.y, len = std::hypot(dx, dy);
  if (len < 1) return;
  const double ux = dx / len, uy = dy / len, head = std::min(9.0, len / 2);
  canvas.line(to, {to.x - head * (ux * 0.87 - uy * 0.5), to.y - head * (uy * 0.87 + ux * 0.5)}, colour, thickness);
  canvas.line(to, {to.x - head * (ux * 0.87 + uy * 0.5), to.y - head * (uy * 0.87 - ux * 0.5)}, colour, thickness);
}

void draw_cross(Canvas& canvas, Px c, double half, Rgb colour, int thickness) {
  canvas.line({c.x - half, c.y - half}, {c.x + half, c.y + half}, colour, thickness);
  canvas.line({c.x - half, c.y + half}, {c.x + half, c.y - half}, colour, thickness);
}

}  // namespace sen3bot::figure
