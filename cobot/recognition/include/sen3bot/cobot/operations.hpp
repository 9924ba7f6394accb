#pragma once
// A worker's operation is a sequence of workstation visits (thesis §3.1.1). This header holds
// what the robot and the simulator share about them: the operations file (the workstations, the
// operations and their station order, the coarse grid the path is rasterised on, and the route
// the robot drives to assist each operation), and the feature extraction that turns a recorded
// path (map points, no timing) into the classifier's input. docs/cobot/recognition.md.
//
// Features: the path drawn on a coarse grid over the map, two channels per cell.
//   occupancy  the path drawn on the map image, downsampled: the largest bilinear weight any
//              path point gives the cell (0..1). This alone is the thesis' input.
//   order      where in the path the cell was walked: the weight-averaged path fraction
//              (0 at the first point, 1 at the newest) of the points that touch it; 0 when
//              none do. A path and its reverse draw the same occupancy but opposite order.
// The fraction is of the points given, so a partial path looks like a whole short one: the
// classifier is trained on prefixes for that.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/msg/cobot.hpp"
#include "sen3bot/msg/geometry.hpp"

namespace sen3bot::cobot {

inline constexpr std::size_t kMaxWorkstations = 32;
inline constexpr std::size_t kMaxOperations = msg::OperationEstimate::kMaxOperations;
inline constexpr std::size_t kMaxVisits = 16;     // stations in one operation
inline constexpr std::size_t kMaxGridCells = 1024;  // per channel; bounds the feature vector
inline constexpr std::size_t kFeatureChannels = 2;
inline constexpr std::size_t kMaxFeatures = kFeatureChannels * kMaxGridCells;
// The recorder's capacity: a path longer than this cannot come from the robot.
inline constexpr std::size_t kMaxPathPoints = msg::WorkerPath::kMax;

// The coarse grid over the map. Cell (c, r) covers [x0 + c*cell, x0 + (c+1)*cell) x [y0 + ...).
struct GridSpec {
  double origin_x_m = 0.0;
  double origin_y_m = 0.0;
  double cell_m = 0.5;
  int cols = 0;
  int rows = 0;
  [[nodiscard]] std::size_t cells() const noexcept {
    return static_cast<std::size_t>(cols) * static_cast<std::size_t>(rows);
  }
  friend bool operator==(const GridSpec&, const GridSpec&) = default;
};

struct Workstation {
  std::string name;
  msg::Point2D position;  // where a worker stands to work at it
  double radius_m = 0.4;  // a worker within this of position is at the station
};

struct Operation {
  std::string name;
  std::string description;
  std::vector<std::size_t> stations;  // indices into OperationsConfig::stations, in visit order
  // The robot's route to assist this operation (map frame, first point at the first station);
  // empty when the file has none.
  std::vector<msg::Point2D> reference;
};

struct OperationsConfig {
  std::string source;    // the file it came from
  std::string map_path;  // the site map (ROS map_server YAML), resolved against the file's folder
  GridSpec grid;
  std::vector<Workstation> stations;
  std::vector<Operation> operations;

  // Index of the operation or station with this name; -1 when there is none.
  [[nodiscard]] int find_operation(std::string_view name) const noexcept;
  [[nodiscard]] int find_station(std::string_view name) const noexcept;
};

// The file (config/cobot/operations.yaml):
//   map: ../maps/lab.yaml
//   grid: {origin: [x, y], cell_m: 0.5, cols: 16, rows: 19}
//   stations: [{name: ..., position: [x, y], radius_m: 0.4}, ...]
//   operations: [{name: ..., description: ..., stations: [name, ...]}, ...]
//   references: {operation name: [[x, y], ...], ...}      (optional)
// Every mistake is an error naming the file and the key (and the line). `source` names the
// text in messages; relative map paths stay relative when parsing text.
Result<OperationsConfig> parse_operations(std::string_view text, std::string_view source);
Result<OperationsConfig> load_operations(const std::string& path);

// A path whose operation is known (training, evaluation).
struct LabelledPath {
  std::size_t operation = 0;  // index into OperationsConfig::operations
  std::vector<float> xy;      // x0, y0, x1, y1, ...
  [[nodiscard]] std::size_t points() const noexcept { return xy.size() / 2; }
};

enum class FeatureEncoding : std::uint8_t {
  occupancy,        // channel 1 only: the thesis' drawn path
  occupancy_order,  // both channels
};
[[nodiscard]] const char* to_string(FeatureEncoding encoding) noexcept;
// "occupancy" or "occupancy_order"; false for anything else.
bool parse_encoding(std::string_view text, FeatureEncoding& encoding) noexcept;

// Length of the feature vector: cells, or twice that with the order channel.
[[nodiscard]] std::size_t feature_count(const GridSpec& grid, FeatureEncoding encoding) noexcept;

// The features of a path given as x0, y0, x1, y1, ... (map frame, metres); out must hold
// feature_count() values (the occupancy channel first, row-major, then the order channel).
// Points off the grid count in the nearest border cells; non-finite points are skipped. An
// empty path gives zeros. Allocates nothing (grids above kMaxGridCells cells give zeros).
void path_features(std::span<const float> xy, const GridSpec& grid, std::span<float> out,
                   FeatureEncoding encoding = FeatureEncoding::occupancy_order) noexcept;

}  // namespace sen3bot::cobot
