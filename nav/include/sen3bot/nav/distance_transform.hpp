#pragma once
// Exact squared Euclidean distance transform of a grid (Felzenszwalb and Huttenlocher, 2012):
// a pass over the columns, then one over the rows, each the lower envelope of parabolas.
// The costmap's inflation and localization's likelihood field both start from it. The line
// scratch is taken once at init(); transform() allocates nothing.
#include <cstddef>
#include <memory_resource>
#include <span>

#include "sen3bot/hal/result.hpp"

namespace sen3bot::nav {

class DistanceTransform {
 public:
  // Sizes the scratch for grids up to max_line cells wide and high.
  Status init(std::size_t max_line, std::pmr::memory_resource& resource);
  static std::size_t storage_bytes(std::size_t max_line) noexcept;

  // grid is row-major, width x height. On entry 0 marks a site and +infinity anything else;
  // on return each cell holds the squared distance, in cells, to the nearest site (+infinity
  // when there is none). Grids larger than init() allowed are left unchanged (returns false).
  bool transform(std::span<float> grid, int width, int height) noexcept;

 private:
  void transform_line(std::size_t n) noexcept;  // f_[0, n) -> d_[0, n)

  std::size_t max_line_ = 0;
  std::span<float> f_;
  std::span<float> d_;
  std::span<float> z_;  // max_line + 1: the envelope's boundaries
  std::span<int> v_;    // the envelope's parabola sites
};

}  // namespace sen3bot::nav
