#pragma once
// Shared by the layer's detection and the layer: their grids move with the rolling window.
#include <span>

namespace sen3bot::nav {

// Moves a row-major grid's content by (-cols, -rows) in place; cells whose source lies outside
// take `entering`. Reads always run ahead of writes in the chosen direction, so no copy is needed.
template <typename T>
void shift_grid(std::span<T> grid, int width, int height, int cols, int rows, T entering) noexcept {
  if (cols == 0 && rows == 0) return;
  const long offset = static_cast<long>(rows) * width + cols;
  const auto move_cell = [&](int c, int r) {
    const int sc = c + cols;
    const int sr = r + rows;
    const std::size_t i = static_cast<std::size_t>(r) * static_cast<std::size_t>(width) + static_cast<std::size_t>(c);
    if (sc < 0 || sr < 0 || sc >= width || sr >= height) {
      grid[i] = entering;
    } else {
      grid[i] = grid[static_cast<std::size_t>(sr) * static_cast<std::size_t>(width) + static_cast<std::size_t>(sc)];
    }
  };
  if (offset > 0) {
    for (int r = 0; r < height; ++r)
      for (int c = 0; c < width; ++c) move_cell(c, r);
  } else {
    for (int r = height - 1; r >= 0; --r)
      for (int c = width - 1; c >= 0; --c) move_cell(c, r);
  }
}

}  // namespace sen3bot::nav
