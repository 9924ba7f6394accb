#include "sen3bot/nav/assignment.hpp"

#include <algorithm>
#include <limits>

#include "sen3bot/nav/arena.hpp"

namespace sen3bot::nav {

Status Hungarian::init(std::size_t max_n, std::pmr::memory_resource& resource) {
  max_n_ = max_n;
  return guarded("dynamic obstacles: assignment", [&]() -> Status {
    // Index 0 is the algorithm's virtual row and column; the real ones are 1..n.
    u_ = allocate_array<double>(resource, max_n + 1);
    v_ = allocate_array<double>(resource, max_n + 1);
    min_v_ = allocate_array<double>(resource, max_n + 1);
    match_ = allocate_array<int>(resource, max_n + 1);
    way_ = allocate_array<int>(resource, max_n + 1);
    used_ = allocate_array<std::uint8_t>(resource, max_n + 1);
    return Status::success();
  });
}

double Hungarian::solve(std::span<const double> cost, std::size_t rows, std::size_t cols,
                        std::span<int> row_to_col) noexcept {
  const std::size_t out = std::min(rows, row_to_col.size());
  std::fill(row_to_col.begin(), row_to_col.begin() + static_cast<std::ptrdiff_t>(out), kUnassigned);
  if (rows == 0 || cols == 0 || rows > max_n_ || cols > max_n_ || cost.size() < rows * cols || row_to_col.size() < rows) {
    return 0.0;
  }
  // The algorithm assigns every one of n "workers" to one of m >= n "jobs"; with more rows
  // than columns the columns are the workers (the matrix read transposed).
  const bool transposed = rows > cols;
  const std::size_t n = transposed ? cols : rows;
  const std::size_t m = transposed ? rows : cols;
  const auto a = [&](std::size_t worker, std::size_t job) {  // 1-based
    return transposed ? cost[(job - 1) * cols + (worker - 1)] : cost[(worker - 1) * cols + (job - 1)];
  };
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::fill(u_.begin(), u_.begin() + static_cast<std::ptrdiff_t>(n + 1), 0.0);
  std::fill(v_.begin(), v_.begin() + static_cast<std::ptrdiff_t>(m + 1), 0.0);
  std::fill(match_.begin(), match_.begin() + static_cast<std::ptrdiff_t>(m + 1), 0);  // job -> worker, 0: free
  for (std::size_t worker = 1; worker <= n; ++worker) {
    // Grow a tree of tight edges from the new worker (parked on virtual job 0) until it
    // reaches a free job: a shortest augmenting path under the reduced costs.
    match_[0] = static_cast<int>(worker);
    std::size_t job = 0;
    std::fill(min_v_.begin(), min_v_.begin() + static_cast<std::ptrdiff_t>(m + 1), kInf);
    std::fill(used_.begin(), used_.begin() + static_cast<std::ptrdiff_t>(m + 1), std::uint8_t{0});
    do {
      used_[job] = 1;
      const auto from = static_cast<std::size_t>(match_[job]);
      double delta = kInf;
      std::size_t next = 0;
      for (std::size_t j = 1; j <= m; ++j) {
        if (used_[j] != 0) continue;
        const double reduced = a(from, j) - u_[from] - v_[j];
        if (reduced < min_v_[j]) {
          min_v_[j] = reduced;
          way_[j] = static_cast<int>(job);
        }
        if (min_v_[j] < delta) {
          delta = min_v_[j];
          next = j;
        }
      }
      // Move the potentials so that the cheapest edge out of the tree becomes tight.
      for (std::size_t j = 0; j <= m; ++j) {
        if (used_[j] != 0) {
          u_[static_cast<std::size_t>(match_[j])] += delta;
          v_[j] -= delta;
        } else {
          min_v_[j] -= delta;
        }
      }
      job = next;
    } while (match_[job] != 0);
    // Flip the path back to the root.
    do {
      const auto previous = static_cast<std::size_t>(way_[job]);
      match_[job] = match_[previous];
      job = previous;
    } while (job != 0);
  }
  double total = 0.0;
  for (std::size_t j = 1; j <= m; ++j) {
    if (match_[j] == 0) continue;
    const auto worker = static_cast<std::size_t>(match_[j]);
    total += a(worker, j);
    if (transposed) {
      row_to_col[j - 1] = static_cast<int>(worker - 1);
    } else {
      row_to_col[worker - 1] = static_cast<int>(j - 1);
    }
  }
  return total;
}

}  // namespace sen3bot::nav
