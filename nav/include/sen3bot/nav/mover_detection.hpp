#pragma once
// The dynamic obstacle layer's detection (dynamic_obstacles.hpp): which local costmap cells
// changed lately, and their blobs. Fixed memory from init().
#include <cstdint>
#include <memory_resource>
#include <span>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/nav/costmap.hpp"

namespace sen3bot::nav {

struct DolDetectorConfig {
  // Anchors' defaults (ros2_costmap_to_dynamic_obstacles).
  double alpha_fast = 0.85;
  double alpha_slow = 0.3;
  double beta = 0.85;
  double c1 = 120.0;  // P_f above this...
  double c2 = 80.0;   // ...and P_f - P_s above this: dynamic
  // Cells within this distance of an occupied cell of the static map are never dynamic, so
  // localization drift along a wall is not motion (0: off). Occupied: kOccupiedOccupancy, what
  // the static layer marks lethal by default. Distances between cell centres.
  double static_mask_radius_m = 0.15;
  int min_blob_cells = 1;
  int max_blob_cells = 400;   // larger blobs are not movers (a wall the map lacks)
  // Dynamic cells up to this many cells apart (in rows and in columns) join one blob; 1 is
  // plain 8-connectivity. A box sliding along one of its faces shows only that face's leading
  // end and the face across the motion as new, two pieces a cell or two apart, which 8-connected
  // become two tracks: 2 joins them (people walking side by side 10 cm apart become one).
  int blob_link_cells = 2;
};

// The two running averages over a grid of width x height cells, in float.
class BackgroundSubtractor {
 public:
  Status init(int width, int height, const DolDetectorConfig& config, std::pmr::memory_resource& resource);
  // The grid moved by (cols, rows) cells: content moves by (-cols, -rows); cells that enter
  // take the value of the next image.
  void shift(int cols, int rows) noexcept;
  // One step of both averages with image (width * height values 0..255), then the dynamic
  // test; dynamic[i] = 1 or 0. mask (optional, same size): cells with mask != 0 never dynamic.
  // Neighbours outside the grid count as the cell itself. Spans shorter than the grid: no-op.
  void apply(std::span<const std::uint8_t> image, std::span<std::uint8_t> dynamic,
             std::span<const std::uint8_t> mask = {}) noexcept;
  void reset() noexcept;  // every cell takes the next image's value
  [[nodiscard]] float fast(std::size_t i) const noexcept { return fast_[i]; }
  [[nodiscard]] float slow(std::size_t i) const noexcept { return slow_[i]; }
  [[nodiscard]] int width() const noexcept { return width_; }
  [[nodiscard]] int height() const noexcept { return height_; }

 private:
  DolDetectorConfig config_;
  int width_ = 0;
  int height_ = 0;
  std::span<float> fast_;
  std::span<float> slow_;
  std::span<float> scratch_;        // the previous step's values while updating
  std::span<std::uint8_t> fresh_;   // 1: take the next image's value
  bool any_fresh_ = false;
};

struct Blob {
  double x_m = 0.0;  // centroid, world frame
  double y_m = 0.0;
  int cells = 0;
  double min_x_m = 0.0;  // axis-aligned extent of its cells' centres, world frame
  double max_x_m = 0.0;
  double min_y_m = 0.0;
  double max_y_m = 0.0;
  double radius_m = 0.0;  // half the extent's diagonal plus half a cell: the cells' footprint
};

// Connected components of a 0/1 grid (8-connected, or cells up to link_cells apart in both
// directions); blobs outside [min_cells, max_cells] are dropped.
class BlobFinder {
 public:
  Status init(int width, int height, std::size_t max_blobs, std::pmr::memory_resource& resource);
  // Returns the blobs found (at most max_blobs; the largest are not preferred: first found).
  std::span<const Blob> find(std::span<const std::uint8_t> dynamic, const GridGeometry& geometry, int min_cells,
                             int max_cells, int link_cells = 1) noexcept;

 private:
  int width_ = 0;
  int height_ = 0;
  std::span<std::int32_t> labels_;
  std::span<std::uint32_t> stack_;
  std::span<Blob> blobs_;
  std::size_t count_ = 0;
};

}  // namespace sen3bot::nav
