#pragma once
// Occupancy maps in the ROS map_server format: a YAML file naming a PGM image plus its
// resolution, origin and thresholds. Loading happens once at start-up (it allocates); the
// costmaps copy the grid into their own fixed buffers at init().
//
// Occupancy per cell: -1 unknown, 0 free .. 100 occupied. Row 0 is the BOTTOM row of the
// image (the image is flipped on load), so cell (col, row) grows with map-frame x and y when
// the origin yaw is 0.
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "sen3bot/hal/result.hpp"

namespace sen3bot::nav {

enum class MapMode : std::uint8_t { trinary, scale, raw };

// The YAML keys, with the defaults used when a key is absent (map_saver's thresholds).
struct MapYaml {
  std::string image;             // required; relative paths are relative to the YAML's folder
  double resolution_m = 0.0;     // required, > 0
  double origin_x_m = 0.0;       // required: [x, y, yaw] of the lower-left pixel
  double origin_y_m = 0.0;
  double origin_yaw_rad = 0.0;
  double occupied_thresh = 0.65;
  double free_thresh = 0.25;
  bool negate = false;
  MapMode mode = MapMode::trinary;
};

// A greyscale image as read from a PGM (P2 ASCII or P5 binary), top row first.
struct PgmImage {
  int width = 0;
  int height = 0;
  int max_value = 255;
  std::vector<std::uint16_t> pixels;  // width * height, row-major, top row first
};

inline constexpr std::int8_t kUnknownOccupancy = -1;
inline constexpr std::int8_t kOccupiedOccupancy = 100;
// Images larger than this are refused (16 M cells: far beyond any site map we plan on).
inline constexpr std::size_t kMaxMapCells = std::size_t{1} << 24;

class OccupancyMap {
 public:
  OccupancyMap() = default;
  OccupancyMap(int width, int height, double resolution_m, double origin_x_m, double origin_y_m,
               double origin_yaw_rad = 0.0);

  [[nodiscard]] int width() const noexcept { return width_; }
  [[nodiscard]] int height() const noexcept { return height_; }
  [[nodiscard]] double resolution_m() const noexcept { return resolution_m_; }
  [[nodiscard]] double origin_x_m() const noexcept { return origin_x_m_; }
  [[nodiscard]] double origin_y_m() const noexcept { return origin_y_m_; }
  [[nodiscard]] double origin_yaw_rad() const noexcept { return origin_yaw_rad_; }
  [[nodiscard]] std::size_t cell_count() const noexcept { return cells_.size(); }

  [[nodiscard]] bool in_bounds(int col, int row) const noexcept {
    return col >= 0 && row >= 0 && col < width_ && row < height_;
  }
  [[nodiscard]] std::int8_t at(int col, int row) const noexcept {
    return cells_[static_cast<std::size_t>(row) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(col)];
  }
  void set(int col, int row, std::int8_t value) noexcept {
    cells_[static_cast<std::size_t>(row) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(col)] = value;
  }
  [[nodiscard]] const std::vector<std::int8_t>& cells() const noexcept { return cells_; }

  // Map frame <-> grid. world_to_grid gives continuous cell coordinates (cell (c, r) spans
  // [c, c+1) x [r, r+1)); world_to_cell floors them and reports whether the cell is inside.
  void world_to_grid(double x_m, double y_m, double& gx, double& gy) const noexcept;
  bool world_to_cell(double x_m, double y_m, int& col, int& row) const noexcept;
  // Centre of a cell in the map frame.
  void cell_to_world(int col, int row, double& x_m, double& y_m) const noexcept;

 private:
  int width_ = 0;
  int height_ = 0;
  double resolution_m_ = 0.05;
  double origin_x_m_ = 0.0;
  double origin_y_m_ = 0.0;
  double origin_yaw_rad_ = 0.0;
  double cos_yaw_ = 1.0;
  double sin_yaw_ = 0.0;
  std::vector<std::int8_t> cells_;
};

// Parsers over text already in memory; `source` names the file in error messages.
Result<MapYaml> parse_map_yaml(std::string_view text, std::string_view source);
Result<PgmImage> parse_pgm(std::string_view bytes, std::string_view source);

// Image + parameters -> occupancy (thresholds inclusive: p >= occupied_thresh is occupied,
// p <= free_thresh is free; p = (max - v) / max, or v / max with negate).
OccupancyMap occupancy_from_image(const PgmImage& image, const MapYaml& yaml);

// Reads the YAML, then the image it names. Errors name the file and the key or line.
Result<OccupancyMap> load_map(const std::string& yaml_path);

}  // namespace sen3bot::nav
