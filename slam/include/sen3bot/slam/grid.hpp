#pragma once
// The grids a submap is made of. A submap being built keeps log-odds per cell (what each scan's
// hits and misses add up to) and, beside them, the probability the matchers read, one byte per
// cell: 0 unknown, 1..255 from kMinProbability to kMaxProbability. A finished submap keeps only
// the bytes, cropped to the cells its scans touched.
//
// Frames: a submap's grid is axis-aligned in the submap's own frame, whose origin is the pose
// the submap was started at (heading 0 there). Cell (c, r) spans [c, c+1) x [r, r+1) in grid
// coordinates; the grid's lower-left corner sits at (origin_x_m, origin_y_m) of that frame.
#include <array>
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <memory_resource>
#include <span>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/nav/geometry.hpp"

namespace sen3bot::slam {

inline constexpr double kMinProbability = 0.1;
inline constexpr double kMaxProbability = 0.9;

// A point of a scan, in metres, in whatever frame its owner says.
struct PointF {
  float x = 0.0F;
  float y = 0.0F;
};

// The probability each byte stands for (0, unknown, reads as the minimum: a scan that falls
// on unexplored cells must not score).
const std::array<float, 256>& probability_table() noexcept;
std::uint8_t probability_byte(double p) noexcept;

// Read-only probability bytes with their place in the submap frame.
struct ProbabilityView {
  const std::uint8_t* cells = nullptr;
  int width = 0;
  int height = 0;
  double resolution_m = 0.05;
  double origin_x_m = 0.0;
  double origin_y_m = 0.0;

  [[nodiscard]] bool in_bounds(int col, int row) const noexcept {
    return col >= 0 && row >= 0 && col < width && row < height;
  }
  [[nodiscard]] std::uint8_t byte(int col, int row) const noexcept {
    return in_bounds(col, row) ? cells[static_cast<std::size_t>(row) * static_cast<std::size_t>(width) +
                                       static_cast<std::size_t>(col)]
                               : std::uint8_t{0};
  }
  [[nodiscard]] float probability(int col, int row) const noexcept { return probability_table()[byte(col, row)]; }
  // Continuous grid coordinates of a point of the submap frame.
  [[nodiscard]] double grid_x(double x_m) const noexcept { return (x_m - origin_x_m) / resolution_m; }
  [[nodiscard]] double grid_y(double y_m) const noexcept { return (y_m - origin_y_m) / resolution_m; }
};

// The probability a hit and a miss move a cell towards. A wall cell saturates after a couple of
// hits: with Cartographer's gentler 0.55 / 0.49 a wall's cells keep counting up for many scans,
// the cells seen from nearer and more often score higher, and along a corridor that slope pulls
// every new scan back towards where the walls were seen from (a straight 30 m drive came out
// 5.7 % short with 0.55 / 0.49, 0.06 % long with these; tests/slam/corridor_test.cpp).
struct InsertionConfig {
  double hit_probability = 0.7;
  double miss_probability = 0.4;
};

// The grid a submap is built in: a square of side cells that it never outgrows (points past it
// are dropped), over memory taken once from an arena.
class BuildGrid {
 public:
  // side * side cells: 2 bytes of log-odds, 1 of probability, 2 of update mark each.
  Status init(std::pmr::memory_resource& arena, int side, double resolution_m, const InsertionConfig& config);
  [[nodiscard]] static std::size_t bytes_for(int side) noexcept;

  // Empties the grid and centres it on the submap frame's origin.
  void reset() noexcept;
  // One scan: the sensor at `sensor` and its returns `hits`, both in the submap frame. Each cell
  // is updated once per scan: hits first, then the misses on the rays that end in them.
  void insert(const PointF& sensor, std::span<const PointF> hits) noexcept;

  [[nodiscard]] ProbabilityView view() const noexcept;
  // The smallest rectangle holding every known cell (empty when none is known).
  struct Bounds {
    int min_col = 0, min_row = 0, max_col = -1, max_row = -1;
    [[nodiscard]] bool empty() const noexcept { return max_col < min_col; }
  };
  [[nodiscard]] Bounds known_bounds() const noexcept { return bounds_; }
  [[nodiscard]] int side() const noexcept { return side_; }
  [[nodiscard]] double resolution_m() const noexcept { return resolution_m_; }

 private:
  void update(std::size_t index, std::int16_t delta) noexcept;
  void ray(int c0, int r0, int c1, int r1) noexcept;

  int side_ = 0;
  double resolution_m_ = 0.05;
  std::int16_t hit_delta_ = 0;
  std::int16_t miss_delta_ = 0;
  std::span<std::int16_t> log_odds_;   // kUnknownLogOdds when never seen
  std::span<std::uint8_t> bytes_;
  std::span<std::uint16_t> marks_;     // the scan that last updated the cell
  std::uint16_t mark_ = 0;
  Bounds bounds_;
};

// A finished submap's probabilities, cropped, in an arena.
Result<ProbabilityView> freeze(const BuildGrid& grid, std::pmr::memory_resource& arena);

}  // namespace sen3bot::slam
