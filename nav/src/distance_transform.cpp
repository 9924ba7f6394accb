#include "sen3bot/nav/distance_transform.hpp"

#include <algorithm>
#include <limits>

#include "sen3bot/nav/arena.hpp"

namespace sen3bot::nav {

Status DistanceTransform::init(std::size_t max_line, std::pmr::memory_resource& resource) {
  return guarded("distance transform", [&]() -> Status {
    f_ = allocate_array<float>(resource, max_line);
    d_ = allocate_array<float>(resource, max_line);
    z_ = allocate_array<float>(resource, max_line + 1);
    v_ = allocate_array<int>(resource, max_line);
    max_line_ = max_line;
    return Status::success();
  });
}

std::size_t DistanceTransform::storage_bytes(std::size_t max_line) noexcept {
  // Plus alignment slack per array.
  return max_line * 3 * sizeof(float) + sizeof(float) + max_line * sizeof(int) + 4 * alignof(std::max_align_t);
}

void DistanceTransform::transform_line(std::size_t n) noexcept {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  // Cells at infinity are not parabola sites: they cannot be nearest.
  std::size_t first = 0;
  while (first < n && f_[first] == kInf) ++first;
  if (first == n) {
    std::fill(d_.begin(), d_.begin() + static_cast<std::ptrdiff_t>(n), kInf);
    return;
  }
  std::size_t k = 0;
  v_[0] = static_cast<int>(first);
  z_[0] = -kInf;
  z_[1] = kInf;
  for (std::size_t q = first + 1; q < n; ++q) {
    if (f_[q] == kInf) continue;
    const float fq = f_[q] + static_cast<float>(q * q);
    float s = 0.0f;
    for (;;) {
      const auto p = static_cast<std::size_t>(v_[k]);
      s = (fq - (f_[p] + static_cast<float>(p * p))) / (2.0f * static_cast<float>(q) - 2.0f * static_cast<float>(p));
      if (s > z_[k] || k == 0) break;
      --k;
    }
    ++k;
    v_[k] = static_cast<int>(q);
    z_[k] = s;
    z_[k + 1] = kInf;
  }
  k = 0;
  for (std::size_t q = 0; q < n; ++q) {
    while (z_[k + 1] < static_cast<float>(q)) ++k;
    const float diff = static_cast<float>(q) - static_cast<float>(v_[k]);
    d_[q] = diff * diff + f_[static_cast<std::size_t>(v_[k])];
  }
}

bool DistanceTransform::transform(std::span<float> grid, int width, int height) noexcept {
  if (width <= 0 || height <= 0) return true;
  const auto w = static_cast<std::size_t>(width);
  const auto h = static_cast<std::size_t>(height);
  if (w > max_line_ || h > max_line_ || grid.size() < w * h) return false;
  for (std::size_t c = 0; c < w; ++c) {
    for (std::size_t r = 0; r < h; ++r) f_[r] = grid[r * w + c];
    transform_line(h);
    for (std::size_t r = 0; r < h; ++r) grid[r * w + c] = d_[r];
  }
  for (std::size_t r = 0; r < h; ++r) {
    float* row = grid.data() + r * w;
    std::copy(row, row + w, f_.begin());
    transform_line(w);
    std::copy(d_.begin(), d_.begin() + static_cast<std::ptrdiff_t>(w), row);
  }
  return true;
}

}  // namespace sen3bot::nav
