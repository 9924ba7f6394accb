#pragma once
// The pieces of a map figure, from plain data: an occupancy grid drawn in metres, the frame
// with ticks and axis names, a legend of swatches and a scale bar, and the marks figures share.
#include <cstdint>
#include <functional>
#include <span>
#include <string>
#include <vector>

#include "sen3bot/figure/canvas.hpp"

namespace sen3bot::figure {

// The colours every map figure shares.
namespace colours {
inline constexpr Rgb kPaper{255, 255, 255};
inline constexpr Rgb kInk{40, 40, 40};
inline constexpr Rgb kWall{0, 0, 0};
inline constexpr Rgb kUnknown{175, 175, 175};
}  // namespace colours

inline constexpr double kTitleSize = 0.6;
inline constexpr double kLineSize = 0.45;
inline constexpr double kSmallSize = 0.38;
inline constexpr int kMargin = 12;
inline constexpr int kAxisLeft = 44;    // room for the y tick labels
inline constexpr int kAxisBottom = 44;  // tick labels and "x (m)"
inline constexpr int kLegendGap = 20;
inline constexpr int kSwatch = 28;
inline constexpr int kRowPitch = 22;

// An occupancy grid as the figure reads it: row-major cells from the lower-left corner, -1
// unknown, 0..100 the chance of an obstacle (50 and over drawn as a wall).
struct Grid {
  int width = 0;
  int height = 0;
  double resolution_m = 0.05;
  double origin_x_m = 0;  // the lower-left corner
  double origin_y_m = 0;
  std::span<const std::int8_t> cells;

  [[nodiscard]] std::int8_t at(int col, int row) const noexcept {
    return cells[static_cast<std::size_t>(row) * static_cast<std::size_t>(width) + static_cast<std::size_t>(col)];
  }
  [[nodiscard]] double width_m() const noexcept { return width * resolution_m; }
  [[nodiscard]] double height_m() const noexcept { return height * resolution_m; }
};

// printf of one number into a string.
[[nodiscard]] std::string format(const char* fmt, double v);

// Pixels per metre for a grid: 80, less for grids over 9.5 m (then 760 px across).
[[nodiscard]] double figure_scale(const Grid& grid) noexcept;
// Walls and unknown cells; free cells are left as the paper.
void draw_grid(Canvas& canvas, const View& view, const Grid& grid);
[[nodiscard]] bool has_unknown(const Grid& grid) noexcept;

// Tick spacing that gives at most about ten ticks over extent_m.
[[nodiscard]] double tick_step(double extent_m) noexcept;
// The frame around the plot at (left, top), w x h pixels, ticks in metres of the grid and the
// axis names.
void draw_axes(Canvas& canvas, const View& view, const Grid& grid, int left, int top, int w, int h);

// A scale bar's length: the first of 0.5, 1, 2, 5, ... m that is at least 60 px long.
[[nodiscard]] double scale_bar_length_m(double px_per_m) noexcept;
// The bar, its left end's top at (x, y), 6 px tall: the first half ink, the second half paper
// framed in ink; "0" and its length under it.
void draw_scale_bar(Canvas& canvas, int x, int y, double px_per_m);

struct LegendEntry {
  std::string label;
  std::function<void(Canvas&, Px)> swatch;  // drawn centred on the point, kSwatch wide
};
[[nodiscard]] int legend_width(std::span<const LegendEntry> entries);
[[nodiscard]] int legend_height(std::span<const LegendEntry> entries);  // the scale bar included
// The entries one a row from (x, top + 10), then the scale bar under them.
void draw_legend(Canvas& canvas, int x, int top, std::span<const LegendEntry> entries, double px_per_m);

void draw_arrow(Canvas& canvas, Px from, Px to, Rgb colour, int thickness);
void draw_cross(Canvas& canvas, Px c, double half, Rgb colour, int thickness);

}  // namespace sen3bot::figure
