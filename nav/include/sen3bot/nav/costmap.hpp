#pragma once
// Layered costmaps with Nav2's cost semantics. A LayeredCostmap owns the master grid; each
// update resets it and lets every layer, in order, write or combine its costs into it.
// Layers size their buffers from the master in init(); update() never allocates.
//
// Costs: 0 free .. 252 (kMaxNonObstacle) graded, 253 inscribed (the robot centre there means
// a collision), 254 lethal (an obstacle), 255 no information.
//
// The grid may be rotated in the map frame by a map's origin yaw; every world<->cell
// conversion goes through its GridGeometry. A rolling window keeps its origin on the static
// map's cell lattice (and its yaw), so cells line up.
#include <cmath>
#include <cstdint>
#include <memory_resource>
#include <span>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/mem/static_vector.hpp"
#include "sen3bot/msg/navigation.hpp"
#include "sen3bot/nav/distance_transform.hpp"
#include "sen3bot/nav/geometry.hpp"
#include "sen3bot/nav/grid_geometry.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/nav/projected_scan.hpp"

namespace sen3bot::nav {

inline constexpr std::uint8_t kFreeCost = 0;
inline constexpr std::uint8_t kMaxNonObstacleCost = 252;
inline constexpr std::uint8_t kInscribedCost = 253;
inline constexpr std::uint8_t kLethalCost = 254;
inline constexpr std::uint8_t kNoInformationCost = 255;

class Costmap2D {
 public:
  // Takes width * height bytes from resource (once).
  Status init(int width, int height, double resolution_m, std::pmr::memory_resource& resource, double yaw_rad = 0.0);

  [[nodiscard]] const GridGeometry& geometry() const noexcept { return geometry_; }
  [[nodiscard]] int width() const noexcept { return geometry_.width(); }
  [[nodiscard]] int height() const noexcept { return geometry_.height(); }
  [[nodiscard]] double resolution_m() const noexcept { return geometry_.resolution_m(); }
  [[nodiscard]] double origin_x_m() const noexcept { return geometry_.origin_x_m(); }
  [[nodiscard]] double origin_y_m() const noexcept { return geometry_.origin_y_m(); }
  [[nodiscard]] double yaw_rad() const noexcept { return geometry_.origin_yaw_rad(); }
  void set_origin(double x_m, double y_m) noexcept { geometry_.set_origin(x_m, y_m); }
  [[nodiscard]] std::size_t size() const noexcept { return cells_.size(); }
  [[nodiscard]] bool in_bounds(int col, int row) const noexcept { return geometry_.in_bounds(col, row); }
  [[nodiscard]] std::size_t index(int col, int row) const noexcept { return geometry_.index(col, row); }
  [[nodiscard]] std::uint8_t at(int col, int row) const noexcept { return cells_[index(col, row)]; }
  void set(int col, int row, std::uint8_t cost) noexcept { cells_[index(col, row)] = cost; }
  [[nodiscard]] std::span<std::uint8_t> cells() noexcept { return cells_; }
  [[nodiscard]] std::span<const std::uint8_t> cells() const noexcept { return cells_; }
  void fill(std::uint8_t cost) noexcept;

  bool world_to_cell(double x_m, double y_m, int& col, int& row) const noexcept {
    return geometry_.world_to_cell(x_m, y_m, col, row);
  }
  void cell_to_world(int col, int row, double& x_m, double& y_m) const noexcept {
    geometry_.cell_to_world(col, row, x_m, y_m);
  }

 private:
  GridGeometry geometry_;
  std::span<std::uint8_t> cells_;
};

// What one costmap update sees. scan may be null (no new scan this cycle).
struct CostmapInputs {
  Pose2D robot_pose;  // map frame
  Pose2D scan_pose;   // map frame: where the robot was when the scan was taken
  const ProjectedScan* scan = nullptr;
  hal::Nanos now_ns = 0;  // the update's time (layers that predict motion paint for it)
  const msg::Sonar* sonar = nullptr;  // the ring's latest readings (body frame), if any
};

// A plug-in layer. Later layers (dynamic obstacles, people) implement this too.
class CostmapLayer {
 public:
  virtual ~CostmapLayer() = default;
  [[nodiscard]] virtual const char* name() const noexcept = 0;
  // Sizes the layer's buffers for the master grid (which is already initialised).
  virtual Status init(const Costmap2D& master, std::pmr::memory_resource& resource) = 0;
  // A rolling window moved by (cols, rows) cells: content must move by (-cols, -rows).
  virtual void on_window_moved(int shift_cols, int shift_rows) noexcept {
    (void)shift_cols;
    (void)shift_rows;
  }
  // Writes or combines this layer's costs into master. Must not allocate.
  virtual void update(Costmap2D& master, const CostmapInputs& inputs) noexcept = 0;
};

struct CostmapConfig {
  bool rolling = false;         // true: a window centred on the robot; false: fixed extent
  double width_m = 6.0;         // rolling window size (the local costmap default: 6 x 6 m)
  double height_m = 6.0;
  double resolution_m = 0.05;   // rolling windows must use the static map's resolution
  double origin_x_m = 0.0;      // fixed costmaps: lower-left corner
  double origin_y_m = 0.0;
  double lattice_x_m = 0.0;     // rolling windows snap to this point's cell lattice: the
  double lattice_y_m = 0.0;     // static map's origin
  double yaw_rad = 0.0;         // the grid's rotation in the map frame: the static map's yaw
};

class LayeredCostmap {
 public:
  static constexpr std::size_t kMaxLayers = 8;

  // Layers are added before init() and must outlive the costmap.
  Status add_layer(CostmapLayer& layer);
  // A costmap sized from config: rolling, or fixed at origin_x/y_m.
  Status init(const CostmapConfig& config, std::pmr::memory_resource& resource);
  // A fixed costmap covering the map cell for cell (the global costmap).
  Status init_over_map(const OccupancyMap& map, std::pmr::memory_resource& resource);

  // Moves a rolling window to the robot, then runs the layers in order.
  void update(const CostmapInputs& inputs) noexcept;

  [[nodiscard]] const Costmap2D& costmap() const noexcept { return master_; }
  [[nodiscard]] Costmap2D& costmap() noexcept { return master_; }
  [[nodiscard]] bool rolling() const noexcept { return config_.rolling; }

 private:
  Status init_layers(std::pmr::memory_resource& resource);
  void move_window(double robot_x_m, double robot_y_m) noexcept;

  CostmapConfig config_;
  Costmap2D master_;
  mem::StaticVector<CostmapLayer*, kMaxLayers> layers_;
  bool window_placed_ = false;
};

// --- Layers -------------------------------------------------------------------------------

// The map: occupancy >= lethal_threshold -> 254, unknown -> 255 (track_unknown) or free,
// anything else free. A rolling window copies its part of the map.
struct StaticLayerConfig {
  int lethal_threshold = 100;   // Nav2's lethal_cost_threshold
  bool track_unknown = false;   // Nav2 default false (global bringup: true)
};

class StaticLayer final : public CostmapLayer {
 public:
  StaticLayer(const OccupancyMap& map, StaticLayerConfig config = {}) noexcept : map_(map), config_(config) {}
  [[nodiscard]] const char* name() const noexcept override { return "static"; }
  Status init(const Costmap2D& master, std::pmr::memory_resource& resource) override;
  void update(Costmap2D& master, const CostmapInputs& inputs) noexcept override;

 private:
  const OccupancyMap& map_;
  StaticLayerConfig config_;
  std::span<std::uint8_t> costs_;  // the whole map converted once, for fast window copies
};

// Laser endpoints marked lethal, free space cleared by Bresenham rays from the sensor.
struct ObstacleLayerConfig {
  double obstacle_max_range_m = 2.5;   // Nav2 default: endpoints farther than this are not marked
  double obstacle_min_range_m = 0.0;
  double raytrace_max_range_m = 3.0;   // Nav2 default: clearing stops here
  double raytrace_min_range_m = 0.0;
  bool clear_no_return = true;         // "no return" beams clear up to raytrace_max_range_m
  bool footprint_clearing = true;      // clear marks under the robot (within the inscribed radius)
  double footprint_clearing_radius_m = 0.19;
  // The laser sees only ahead of its mount: a mark left beside or behind the robot (someone who
  // walked past it) is never raytraced away and can hold the robot in place. A sonar echo says
  // its cone is empty up to the echo: marks there nearer than the echo less sonar_margin_m are
  // cleared. Only echoes clear (a reading at the ring's maximum may be a miss off a slanted
  // face), only fresh ones, and never a mark this update's scan made.
  bool sonar_clearing = true;
  double sonar_half_angle_rad = 0.1309;  // 7.5 degrees: half the P3-DX transducer's 15 degree cone
  double sonar_margin_m = 0.15;
  double sonar_max_age_s = 0.5;
};

class ObstacleLayer final : public CostmapLayer {
 public:
  explicit ObstacleLayer(ObstacleLayerConfig config = {}) noexcept : config_(config) {}
  [[nodiscard]] const char* name() const noexcept override { return "obstacle"; }
  Status init(const Costmap2D& master, std::pmr::memory_resource& resource) override;
  void on_window_moved(int shift_cols, int shift_rows) noexcept override;
  void update(Costmap2D& master, const CostmapInputs& inputs) noexcept override;
  void clear() noexcept;
  [[nodiscard]] std::uint8_t mark(int col, int row) const noexcept { return grid_.at(col, row); }
  [[nodiscard]] const ObstacleLayerConfig& config() const noexcept { return config_; }
  // Per cell of the window: 1 once a beam has passed through it (the laser saw it free) since
  // it entered the window. Something there now moved in; a face never seen through may just
  // have come into view (the dynamic obstacle layer tells the two apart with it).
  [[nodiscard]] std::span<const std::uint8_t> seen_free() const noexcept { return seen_free_; }

 private:
  void raytrace(int c0, int r0, int c1, int r1, int max_cells) noexcept;
  void clear_sonar_cones(const CostmapInputs& inputs) noexcept;
  void shift_grid(std::span<std::uint8_t> cells, int shift_cols, int shift_rows) noexcept;

  ObstacleLayerConfig config_;
  Costmap2D grid_;                    // persistent marks (0 or 254), same geometry as the master
  std::span<std::uint8_t> seen_free_;  // see seen_free()
  std::span<std::uint8_t> scratch_;   // for window shifts
};

// Inflation with Nav2 semantics: exact Euclidean distance transform from lethal cells, then
// 254 on the obstacle, 253 within the inscribed radius, 252*exp(-csf*(d - r_inscribed))
// up to the inflation radius, max-combined with the master.
struct InflationLayerConfig {
  double inflation_radius_m = 0.6;
  double cost_scaling_factor = 5.0;  // Nav2 default 10 (bringup 3); 5 keeps paths off walls
  double inscribed_radius_m = 0.1905;  // the Pioneer footprint's inscribed radius
};

class InflationLayer final : public CostmapLayer {
 public:
  explicit InflationLayer(InflationLayerConfig config = {}) noexcept : config_(config) {}
  [[nodiscard]] const char* name() const noexcept override { return "inflation"; }
  Status init(const Costmap2D& master, std::pmr::memory_resource& resource) override;
  void update(Costmap2D& master, const CostmapInputs& inputs) noexcept override;
  // The cost Nav2 gives a cell at distance_m from the nearest obstacle.
  [[nodiscard]] static std::uint8_t cost_at(double distance_m, const InflationLayerConfig& config) noexcept;
  // The same as the layer's update applied to a grid (shared with tests and planners).
  void inflate(Costmap2D& grid) noexcept;

 private:
  InflationLayerConfig config_;
  DistanceTransform transform_;
  std::span<float> distance2_;  // squared distance in cells to the nearest lethal cell
  std::span<std::uint8_t> lut_;  // cost by squared cell distance
  int radius_cells_ = 0;
};

}  // namespace sen3bot::nav
