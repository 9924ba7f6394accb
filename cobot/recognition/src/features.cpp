// The classifier's input from a path (operations.hpp). Each point is splatted bilinearly on the
// four cells whose centres surround it, so a path that sways across a cell boundary changes the
// features smoothly instead of flipping a cell on and off.
#include <algorithm>
#include <array>
#include <cmath>

#include "sen3bot/cobot/operations.hpp"

namespace sen3bot::cobot {

std::size_t feature_count(const GridSpec& grid, FeatureEncoding encoding) noexcept {
  return encoding == FeatureEncoding::occupancy ? grid.cells() : kFeatureChannels * grid.cells();
}

void path_features(std::span<const float> xy, const GridSpec& grid, std::span<float> out,
                   FeatureEncoding encoding) noexcept {
  const std::size_t cells = grid.cells();
  const std::size_t wanted = feature_count(grid, encoding);
  std::fill(out.begin(), out.end(), 0.0f);
  if (cells == 0 || cells > kMaxGridCells || out.size() < wanted || !(grid.cell_m > 0.0)) return;
  const bool with_order = encoding == FeatureEncoding::occupancy_order;
  std::span<float> occupancy = out.first(cells);
  std::span<float> order = with_order ? out.subspan(cells, cells) : std::span<float>();
  std::array<float, kMaxGridCells> weight_sum{};  // per cell: the weights the order averages over

  const std::size_t points = xy.size() / 2;
  const double last = points > 1 ? static_cast<double>(points - 1) : 1.0;
  const double max_u = grid.cols - 1, max_v = grid.rows - 1;
  for (std::size_t i = 0; i < points; ++i) {
    const double x = xy[2 * i], y = xy[2 * i + 1];
    if (!std::isfinite(x) || !std::isfinite(y)) continue;
    // Continuous coordinates with cell centres on integers, clamped to the border centres.
    const double u = std::clamp((x - grid.origin_x_m) / grid.cell_m - 0.5, 0.0, max_u);
    const double v = std::clamp((y - grid.origin_y_m) / grid.cell_m - 0.5, 0.0, max_v);
    const int c0 = std::min(static_cast<int>(u), grid.cols - 1);
    const int r0 = std::min(static_cast<int>(v), grid.rows - 1);
    const double fu = u - c0, fv = v - r0;
    const float fraction = static_cast<float>(static_cast<double>(i) / last);
    for (int dr = 0; dr <= 1; ++dr) {
      for (int dc = 0; dc <= 1; ++dc) {
        const int c = c0 + dc, r = r0 + dr;
        if (c >= grid.cols || r >= grid.rows) continue;
        const float w = static_cast<float>((dc ? fu : 1.0 - fu) * (dr ? fv : 1.0 - fv));
        if (w <= 0.0f) continue;
        const std::size_t k = static_cast<std::size_t>(r) * static_cast<std::size_t>(grid.cols) + static_cast<std::size_t>(c);
        occupancy[k] = std::max(occupancy[k], w);
        if (with_order) {
          weight_sum[k] += w;
          order[k] += w * fraction;
        }
      }
    }
  }
  if (with_order)
    for (std::size_t k = 0; k < cells; ++k)
      if (weight_sum[k] > 0.0f) order[k] /= weight_sum[k];
}

}  // namespace sen3bot::cobot
