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
#include "sen3bot/nav/grid_geometry.hpp"

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

  [[nodiscard]] const GridGeometry& geometry() const noexcept { return geometry_; }
  [[nodiscard]] int width() const noexcept { return geometry_.width(); }
  [[nodiscard]] int height() const noexcept { return geometry_.height(); }
  [[nodiscard]] double resolution_m() const noexcept { return geometry_.resolution_m(); }
  [[nodiscard]] double origin_x_m() const noexcept { return geometry_.origin_x_m(); }
  [[nodiscard]] double origin_y_m() const noexcept { return geometry_.origin_y_m(); }
  [[nodiscard]] double origin_yaw_rad() const noexcept { return geometry_.origin_yaw_rad(); }
  [[nodiscard]] std::size_t cell_count() const noexcept { return cells_.size(); }
  [[nodiscard]] bool in_bounds(int col, int row) const noexcept { return geometry_.in_bounds(col, row); }

  [[nodiscard]] std::int8_t at(int col, int row) const noexcept { return cells_[geometry_.index(col, row)]; }
  void set(int col, int row, std::int8_t value) noexcept { cells_[geometry_.index(col, row)] = value; }
  [[nodiscard]] const std::vector<std::int8_t>& cells() const noexcept { return cells_; }

  // Map frame <-> grid (GridGeometry).
  void world_to_grid(double x_m, double y_m, double& gx, double& gy) const noexcept {
    geometry_.world_to_grid(x_m, y_m, gx, gy);
  }
  bool world_to_cell(double x_m, double y_m, int& col, int& row) const noexcept {
    return geometry_.world_to_cell(x_m, y_m, col, row);
  }
  void cell_to_world(int col, int row, double& x_m, double& y_m) const noexcept {
    geometry_.cell_to_world(col, row, x_m, y_m);
  }

 private:
  GridGeometry geometry_;
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

// Writes a map as map_saver does: `<stem>.pgm` beside `yaml_path` (P5, top row first; occupancy
// >= 65 black 0, 0..19 free 254, unknown and between 205) and the YAML naming it (trinary,
// thresholds 0.65 / 0.196, the grid's origin; a yawed grid keeps its yaw). `comment` (lines
// without '#', may be empty) heads both files. Errors: a map with no cells, a file that cannot
// be written (io). The folder must exist.
Status save_map(const OccupancyMap& map, const std::string& yaml_path, std::string_view comment = {});

}  // namespace sen3bot::nav
