#pragma once
// Assignment of tracks to measurements, shared by the mover tracker and the people tracker.
#include <cstddef>
#include <cstdint>
#include <memory_resource>
#include <span>

#include "sen3bot/hal/result.hpp"

namespace sen3bot::nav {

// Minimum-cost assignment of rows to columns (Kuhn-Munkres, O(n^3) with potentials), for
// rectangular matrices up to max_n x max_n. cost is row-major rows x cols.
class Hungarian {
 public:
  static constexpr int kUnassigned = -1;
  Status init(std::size_t max_n, std::pmr::memory_resource& resource);
  // row_to_col[r] = the column of row r, or kUnassigned (when rows > cols). Returns the total.
  double solve(std::span<const double> cost, std::size_t rows, std::size_t cols, std::span<int> row_to_col) noexcept;

 private:
  std::size_t max_n_ = 0;
  std::span<double> u_, v_, min_v_;
  std::span<int> match_, way_;
  std::span<std::uint8_t> used_;
};

}  // namespace sen3bot::nav
