#include "sen3bot/nav/mover_detection.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>

#include "grid_shift.hpp"
#include "sen3bot/nav/arena.hpp"

namespace sen3bot::nav {

namespace {

// The 8-neighbour sum of cell (c, r), neighbours off the grid counted as the cell itself.
float border_neighbour_sum(std::span<const float> prev, int width, int height, int c, int r) noexcept {
  const float own = prev[static_cast<std::size_t>(r) * static_cast<std::size_t>(width) + static_cast<std::size_t>(c)];
  float sum = 0.0f;
  for (int dr = -1; dr <= 1; ++dr) {
    for (int dc = -1; dc <= 1; ++dc) {
      if (dc == 0 && dr == 0) continue;
      const int nc = c + dc;
      const int nr = r + dr;
      const bool inside = nc >= 0 && nr >= 0 && nc < width && nr < height;
      sum += inside ? prev[static_cast<std::size_t>(nr) * static_cast<std::size_t>(width) + static_cast<std::size_t>(nc)]
                    : own;
    }
  }
  return sum;
}

// One step of a running average: out = β[(1-α)prev + α C] + (1-β)/8 Σ neighbours(prev).
void blend(std::span<const float> prev, std::span<const std::uint8_t> image, float alpha, float beta, int width,
           int height, std::span<float> out) noexcept {
  const float keep = beta * (1.0f - alpha);
  const float take = beta * alpha;
  const float spread = (1.0f - beta) / 8.0f;
  const auto w = static_cast<std::size_t>(width);
  const auto cell = [&](std::size_t i, float neighbours) {
    out[i] = keep * prev[i] + take * static_cast<float>(image[i]) + spread * neighbours;
  };
  for (int r = 0; r < height; ++r) {
    const bool border_row = r == 0 || r == height - 1;
    const std::size_t row = static_cast<std::size_t>(r) * w;
    if (border_row || width < 3) {
      for (int c = 0; c < width; ++c) cell(row + static_cast<std::size_t>(c), border_neighbour_sum(prev, width, height, c, r));
      continue;
    }
    cell(row, border_neighbour_sum(prev, width, height, 0, r));
    // Interior: plain pointer arithmetic the compiler can vectorise.
    const float* up = prev.data() + row - w;
    const float* mid = prev.data() + row;
    const float* down = prev.data() + row + w;
    for (std::size_t c = 1; c + 1 < w; ++c) {
      const float n = up[c - 1] + up[c] + up[c + 1] + mid[c - 1] + mid[c + 1] + down[c - 1] + down[c] + down[c + 1];
      out[row + c] = keep * mid[c] + take * static_cast<float>(image[row + c]) + spread * n;
    }
    cell(row + w - 1, border_neighbour_sum(prev, width, height, width - 1, r));
  }
}

}  // namespace

Status BackgroundSubtractor::init(int width, int height, const DolDetectorConfig& config,
                                  std::pmr::memory_resource& resource) {
  if (width <= 0 || height <= 0) return Error::format(Errc::config, "dynamic obstacles: bad grid %d x %d", width, height);
  config_ = config;
  width_ = width;
  height_ = height;
  return guarded("dynamic obstacles: detector", [&]() -> Status {
    const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    fast_ = allocate_array<float>(resource, n);
    slow_ = allocate_array<float>(resource, n);
    scratch_ = allocate_array<float>(resource, n);
    fresh_ = allocate_array<std::uint8_t>(resource, n);
    reset();
    return Status::success();
  });
}

void BackgroundSubtractor::reset() noexcept {
  std::fill(fresh_.begin(), fresh_.end(), std::uint8_t{1});
  any_fresh_ = true;
}

void BackgroundSubtractor::shift(int cols, int rows) noexcept {
  if (cols == 0 && rows == 0) return;
  if (std::abs(cols) >= width_ || std::abs(rows) >= height_) {
    reset();  // nothing of the old window remains
    return;
  }
  shift_grid(fast_, width_, height_, cols, rows, 0.0f);
  shift_grid(slow_, width_, height_, cols, rows, 0.0f);
  shift_grid(fresh_, width_, height_, cols, rows, std::uint8_t{1});
  any_fresh_ = true;
}

void BackgroundSubtractor::apply(std::span<const std::uint8_t> image, std::span<std::uint8_t> dynamic,
                                 std::span<const std::uint8_t> mask) noexcept {
  const std::size_t n = fast_.size();
  if (n == 0 || image.size() < n || dynamic.size() < n) return;
  const bool masked = mask.size() >= n;
  const auto beta = static_cast<float>(config_.beta);
  // The neighbours must be the previous step's values: blend from a copy.
  std::memcpy(scratch_.data(), fast_.data(), n * sizeof(float));
  blend(scratch_, image, static_cast<float>(config_.alpha_fast), beta, width_, height_, fast_);
  std::memcpy(scratch_.data(), slow_.data(), n * sizeof(float));
  blend(scratch_, image, static_cast<float>(config_.alpha_slow), beta, width_, height_, slow_);
  if (any_fresh_) {
    // New cells start at what they show now, so a wall entering the window is not motion.
    for (std::size_t i = 0; i < n; ++i) {
      if (fresh_[i] == 0) continue;
      fast_[i] = slow_[i] = static_cast<float>(image[i]);
      fresh_[i] = 0;
    }
    any_fresh_ = false;
  }
  const auto c1 = static_cast<float>(config_.c1);
  const auto c2 = static_cast<float>(config_.c2);
  for (std::size_t i = 0; i < n; ++i) {
    const bool moving = fast_[i] > c1 && fast_[i] - slow_[i] > c2;
    dynamic[i] = moving && !(masked && mask[i] != 0) ? 1 : 0;
  }
}

// --- BlobFinder ---------------------------------------------------------------------------

Status BlobFinder::init(int width, int height, std::size_t max_blobs, std::pmr::memory_resource& resource) {
  if (width <= 0 || height <= 0) return Error::format(Errc::config, "dynamic obstacles: bad grid %d x %d", width, height);
  width_ = width;
  height_ = height;
  return guarded("dynamic obstacles: blob finder", [&]() -> Status {
    const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    labels_ = allocate_array<std::int32_t>(resource, n);
    stack_ = allocate_array<std::uint32_t>(resource, n);
    blobs_ = allocate_array<Blob>(resource, max_blobs);
    return Status::success();
  });
}

std::span<const Blob> BlobFinder::find(std::span<const std::uint8_t> dynamic, const GridGeometry& geometry,
                                       int min_cells, int max_cells, int link_cells) noexcept {
  count_ = 0;
  const std::size_t n = labels_.size();
  if (dynamic.size() < n || geometry.width() != width_ || geometry.height() != height_) return {};
  std::fill(labels_.begin(), labels_.end(), 0);
  const auto w = static_cast<std::uint32_t>(width_);
  const int link = std::max(1, link_cells);
  std::int32_t label = 0;
  for (std::size_t seed = 0; seed < n && count_ < blobs_.size(); ++seed) {
    if (dynamic[seed] == 0 || labels_[seed] != 0) continue;
    ++label;
    // Depth-first flood fill; every cell is pushed once (labelled when pushed).
    std::size_t top = 0;
    stack_[top++] = static_cast<std::uint32_t>(seed);
    labels_[seed] = label;
    Blob blob;
    blob.min_x_m = blob.min_y_m = std::numeric_limits<double>::infinity();
    blob.max_x_m = blob.max_y_m = -std::numeric_limits<double>::infinity();
    double sum_x = 0.0;
    double sum_y = 0.0;
    while (top > 0) {
      const std::uint32_t i = stack_[--top];
      const int c = static_cast<int>(i % w);
      const int r = static_cast<int>(i / w);
      double x = 0.0;
      double y = 0.0;
      geometry.cell_to_world(c, r, x, y);
      sum_x += x;
      sum_y += y;
      blob.min_x_m = std::min(blob.min_x_m, x);
      blob.max_x_m = std::max(blob.max_x_m, x);
      blob.min_y_m = std::min(blob.min_y_m, y);
      blob.max_y_m = std::max(blob.max_y_m, y);
      ++blob.cells;
      for (int dr = -link; dr <= link; ++dr) {
        for (int dc = -link; dc <= link; ++dc) {
          const int nc = c + dc;
          const int nr = r + dr;
          if (!geometry.in_bounds(nc, nr)) continue;
          const std::size_t j = geometry.index(nc, nr);
          if (dynamic[j] == 0 || labels_[j] != 0) continue;
          labels_[j] = label;
          stack_[top++] = static_cast<std::uint32_t>(j);
        }
      }
    }
    if (blob.cells < min_cells || blob.cells > max_cells) continue;
    blob.x_m = sum_x / blob.cells;
    blob.y_m = sum_y / blob.cells;
    blob.radius_m = 0.5 * std::hypot(blob.max_x_m - blob.min_x_m, blob.max_y_m - blob.min_y_m) +
                    0.5 * geometry.resolution_m();
    blobs_[count_++] = blob;
  }
  return {blobs_.data(), count_};
}

}  // namespace sen3bot::nav
