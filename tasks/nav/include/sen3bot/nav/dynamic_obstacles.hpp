#pragma once
// Dynamic Obstacle Layer (navigation.md §4): finds what moves in the local costmap, tracks it
// and paints the space it is about to occupy as expensive. Three pure stages, then the layer
// that runs them inside the costmap update:
//
//   master (static + obstacle marks) as an image C(t): 255 where lethal, 0 elsewhere
//     -> BackgroundSubtractor: fast and slow running averages per cell, each mixing the cell
//        with its 8 neighbours; dynamic when P_f > c1 and P_f - P_s > c2, unless masked (next
//        to the static map, or never seen free by the laser: ObstacleLayer::seen_free())
//     -> BlobFinder: dynamic cells linked within blob_link_cells grouped into blobs
//        (centroid, area, extent)
//     -> MoverTracker: blob centroids matched to tracks by the Hungarian algorithm with a gate;
//        a constant-velocity Kalman filter per track; M hits confirm; a confirmed track that
//        has left its birth place is a mover; coasting tracks die (later out of view)
//     -> paint_mover(): the source's asymmetric Gaussian (front and back half-planes) around
//        each mover, lengthened ahead by what it covers in front_horizon_s
//
// The averages live on the local costmap's cells, which keep a fixed world lattice: when the
// rolling window moves they are shifted with it, and cells that come into the window start at
// the value they show then, so a wall entering the window is not "new".
//
// Every buffer comes from the memory resource in init(); update() never allocates.
#include <Eigen/Core>
#include <cstdint>
#include <memory_resource>
#include <span>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/msg/navigation.hpp"
#include "sen3bot/msg/people.hpp"
#include "sen3bot/nav/costmap.hpp"
#include "sen3bot/nav/map.hpp"

namespace sen3bot::nav {

// --- Detection --------------------------------------------------------------------------------

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

// --- Assignment -------------------------------------------------------------------------------

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

// --- Tracking ---------------------------------------------------------------------------------

struct DolTrackerConfig {
  std::size_t max_tracks = 16;
  std::size_t max_blobs = 32;
  double gate_m = 1.0;             // a blob farther than this from a track's prediction is not it
  // Hits before a tentative track is confirmed. A static object coming into view is dynamic
  // for 3 updates with the default averages (P_s catches up), so 4 keeps it out.
  int confirm_hits = 4;
  double max_coast_s = 0.6;        // unmatched for longer where the laser should see it: deleted
  double max_coast_unseen_s = 4.0; // the same where it cannot (beside or behind the robot, out
                                   // of range): its prediction goes on meanwhile
  double accel_sigma_m_s2 = 1.0;   // white-noise acceleration (process noise)
  double measurement_sigma_m = 0.07;
  double initial_velocity_sigma_m_s = 1.5;
  double min_radius_m = 0.1;       // a track's size from its blobs' extent, clamped
  double max_radius_m = 0.6;
  // A confirmed track becomes a mover (painted, published) once it is faster than
  // moving_min_speed_m_s and has left where it was born: it is moving_min_travel_m away and
  // the laser sees no mark within vacated_radius_m of its birth place any more, or it is
  // moving_far_travel_m away (measured on blob centroids, not on the filter). It stays one
  // while it is hit at least every publish_max_coast_s, or, out of the laser's view, while it
  // lives. Why: the laser's marks on a still object flicker as the robot passes it, and a
  // box's faces come into view one after another, so their blobs wander by up to the object's
  // size, but they never leave the place where they were first seen.
  double moving_min_speed_m_s = 0.15;
  double moving_min_travel_m = 0.3;
  double moving_far_travel_m = 0.45;
  double vacated_radius_m = 0.1;
  double publish_max_coast_s = 0.6;
  // The axis a track travels along: the line fitted (least squares, principal direction)
  // through its measured centroids, each older one weighed down by exp(-d / axis_memory_m)
  // for the distance d the track has travelled since. Once the fitted segment is
  // axis_min_travel_m long and at least four times as long as it is wide, a velocity within
  // axis_max_angle_rad of the axis is turned onto it, in the state after every correction
  // and every coasting step, and so in what is published and painted; a track coasting
  // unseen is also held on the line, at the along-axis speed it kept while in view.
  // Why: a box seen at the edge of the laser's field of view, or half hidden, shows less and
  // less of itself; its centroid slides sideways and lags, and a coasting track would drift
  // with it out of its lane and fall behind the box.
  double axis_memory_m = 3.0;
  double axis_min_travel_m = 0.5;
  double axis_max_angle_rad = 0.5;
  // A track the camera vouches for is a mover at once (MoverTracker::vouch): hit by the newest
  // scan at least vouch_min_hits times, within vouch_reach_m of a walking person the camera and
  // laser placed, moving their way (velocities within vouch_max_angle_rad, speeds within a
  // factor of vouch_speed_ratio) and at least moving_min_speed_m_s. Why: a walker coming into
  // view is a person in the camera after three frames (0.3 s), a mover for the laser alone only
  // after confirm_hits scans and moving_min_travel_m (about 1 s at 5 scans/s); still boxes
  // are never people and never move their way. Off: on people-crossing it changed nothing
  // measurable (the laser tracks the workers before the camera confirms them there), and a
  // wrongly vouched still object would have its cells left to the mover check.
  bool camera_vouches = false;
  int vouch_min_hits = 2;
  double vouch_reach_m = 0.5;
  double vouch_max_angle_rad = 0.6;
  double vouch_speed_ratio = 2.0;
};

// A walking person as the camera and laser placed them, predicted to a scan's time.
struct Vouch {
  double x_m = 0.0, y_m = 0.0, vx_m_s = 0.0, vy_m_s = 0.0;
};

struct DolTrack {
  std::uint32_t id = 0;
  bool confirmed = false;
  int hits = 0;
  hal::Nanos stamp_ns = 0;      // time of x and P
  hal::Nanos last_hit_ns = 0;
  Eigen::Matrix<double, 4, 1> x = Eigen::Matrix<double, 4, 1>::Zero();  // x, y, vx, vy (world)
  Eigen::Matrix<double, 4, 4> P = Eigen::Matrix<double, 4, 4>::Identity();
  double radius_m = 0.1;
  Eigen::Matrix<double, 2, 1> birth = Eigen::Matrix<double, 2, 1>::Zero();  // first position
  Eigen::Matrix<double, 2, 1> seen = Eigen::Matrix<double, 2, 1>::Zero();   // last blob centroid
  // The axis fit (axis_memory_m): weighed sums of the centroids relative to birth.
  double axis_weight = 1.0;
  Eigen::Matrix<double, 2, 1> axis_sum = Eigen::Matrix<double, 2, 1>::Zero();
  Eigen::Matrix<double, 2, 2> axis_squares = Eigen::Matrix<double, 2, 2>::Zero();
  double axis_speed_m_s = 0.0;  // along the axis, averaged while in view
  bool mover = false;  // has shown that it moves (MoverTracker::classify)
  bool in_view = true;  // where the laser should see it, at the last update
};

// Where the laser looked: a sector around the sensor (world frame).
struct LaserView {
  double x_m = 0.0;
  double y_m = 0.0;
  double heading_rad = 0.0;
  double half_angle_rad = 3.2;  // > pi: all around
  double range_m = 1e9;
};

class MoverTracker {
 public:
  Status init(const DolTrackerConfig& config, std::pmr::memory_resource& resource);
  // Predicts every track to stamp_ns, matches the blobs, corrects, births and deaths.
  // Blobs past max_blobs are ignored. A tentative track that misses a scan is deleted at once
  // (a real mover shows up in every scan; clutter rarely twice in a row); a confirmed one
  // coasts for max_coast_s, or max_coast_unseen_s outside view (where the laser looked for
  // these blobs). Pairs farther apart than gate_m all cost the same in the assignment, so
  // one far pair cannot pull the matching away from the near ones.
  void update(std::span<const Blob> blobs, hal::Nanos stamp_ns, const LaserView& view = {}) noexcept;
  [[nodiscard]] std::span<const DolTrack> tracks() const noexcept { return {tracks_.data(), count_}; }
  // Marks the confirmed tracks that have shown they move, given the image the blobs came
  // from (255: marked) on its grid (see DolTrackerConfig).
  void classify(std::span<const std::uint8_t> image, const GridGeometry& geometry) noexcept;
  // Makes movers of the tracks the people vouch for (DolTrackerConfig::camera_vouches);
  // returns how many it made. After classify(), with the people predicted to the last update.
  std::size_t vouch(std::span<const Vouch> people) noexcept;
  // Whether a track counts as a mover now (classified, and hit recently).
  [[nodiscard]] bool moving(const DolTrack& track) const noexcept;
  // Whether a track is a candidate: confirmed, hit by the newest update and faster than
  // moving_min_speed_m_s, but not (yet) a mover.
  [[nodiscard]] bool candidate(const DolTrack& track) const noexcept;
  // A track's position predicted to stamp_ns (constant velocity), without changing it; a
  // stamp before the track's own gives its current position.
  [[nodiscard]] static Eigen::Matrix<double, 2, 1> predict_position(const DolTrack& track, hal::Nanos stamp_ns) noexcept;
  // The whole state and covariance predicted to stamp_ns (the filter's prediction step).
  [[nodiscard]] DolTrack predicted(const DolTrack& track, hal::Nanos stamp_ns) const noexcept;
  void clear() noexcept { count_ = 0; }
  // The track's velocity, held to its travel axis (DolTrackerConfig::axis_memory_m).
  [[nodiscard]] Eigen::Matrix<double, 2, 1> velocity(const DolTrack& track) const noexcept;
  // The track's velocity reversed: a coasting mover predicted into a wall has turned there.
  void turn_back(std::size_t index) noexcept;

 private:
  struct Axis {
    Eigen::Matrix<double, 2, 1> centre;
    Eigen::Matrix<double, 2, 1> direction;  // unit
  };
  [[nodiscard]] bool axis(const DolTrack& track, Axis& out) const noexcept;  // false: none yet
  // Adds the centroid z (before track.seen becomes z) to the axis fit.
  void follow_axis(DolTrack& track, const Eigen::Matrix<double, 2, 1>& z) const noexcept;
  // axis() exists and the filter's velocity lies within axis_max_angle_rad of it.
  [[nodiscard]] bool along_axis(const DolTrack& track, Axis& out) const noexcept;
  // The state's velocity := velocity(track); measured: the along-axis speed is averaged;
  // unseen: the position goes onto the line, and the speed up to that average.
  enum class Hold : std::uint8_t { measured, coasting, unseen };
  void hold_to_axis(DolTrack& track, Hold hold) const noexcept;

  DolTrackerConfig config_;
  Hungarian hungarian_;
  std::span<DolTrack> tracks_;
  std::size_t count_ = 0;
  std::uint32_t next_id_ = 1;
  hal::Nanos last_update_ns_ = 0;
  std::span<double> cost_;
  std::span<int> assignment_;
  std::span<std::uint8_t> blob_used_;
};

// --- Cost ---------------------------------------------------------------------------------------

// The asymmetric Gaussian: with d the distance from the centroid and θ_c the velocity direction,
//   Φ(q) = A exp(-[d cos(θ-θ_c)]² / (2 σx²) - [d sin(θ-θ_c)]² / (2 σy²))
// front half-plane: σx² = (1 + r) sigma2_front_x, σy² = (1 - r/2) sigma2_front_y
// back half-plane:  σx² = (1 - r) sigma2_back_x,  σy² = (1 - r/4) sigma2_back_y
// r = min(1, speed / max_speed_m_s). Ahead, the Gaussian starts front_horizon_s * speed in
// front of the centroid (flat before it): the space the mover reaches in that time.
// A is min(amplitude, 252). "Front" is the half-plane where d cos(θ-θc) > 0; at zero velocity
// θc = 0 and r = 0 (the layer paints only tracks of at least min_speed_m_s). Each σ² is kept
// at least 1e-4 m² so that r = 1 behind the mover stays finite.
struct DolCostConfig {
  double amplitude = 252.0;        // kMaxNonObstacleCost: painted cells are never lethal...
  double cutoff = 30.0;            // ...and cells below this are left alone
  double sigma2_front_x_m2 = 1.0;  // the source's 2.0, 0.7, 0.5, 0.9 m² with its exponent
  double sigma2_front_y_m2 = 0.35; // factor csf * 0.2 = 2 folded in
  double sigma2_back_x_m2 = 0.25;
  double sigma2_back_y_m2 = 0.45;
  double max_speed_m_s = 2.0;
  double front_horizon_s = 1.0;    // 0: the source's shape
  double lethal_radius_m = 0.1;    // ...except this core around the predicted centre: 254
  double min_speed_m_s = 0.1;      // slower tracks are painted as a core only
};

// The Gaussian's value at (x_m, y_m) for a mover at (cx, cy) moving with (vx, vy); 0 below cutoff.
[[nodiscard]] double mover_cost(const DolCostConfig& config, double cx, double cy, double vx, double vy, double x_m,
                                double y_m) noexcept;
// Max-merges mover_cost over the grid cells around the mover into grid (never lowers a cell).
// Visits only the cells whose centre lies in the box around the mover outside which the
// Gaussian is below cutoff.
void paint_mover(const DolCostConfig& config, double cx, double cy, double vx, double vy, Costmap2D& grid) noexcept;

// --- The layer ----------------------------------------------------------------------------------

struct DynamicObstacleConfig {
  bool enabled = true;
  DolDetectorConfig detector;
  DolTrackerConfig tracker;
  DolCostConfig cost;
};

// Between the obstacle layer and inflation: reads the master (static map and laser marks) as
// C(t) on each new scan, detects and tracks (at the scan's stamp), then paints every mover
// (MoverTracker::moving) predicted to inputs.now_ns: the Gaussian when at least
// cost.min_speed_m_s fast, and a lethal core. Without a new scan it only repaints the
// predictions. Disabled (config.enabled false), it takes no memory and does nothing.
class DynamicObstacleLayer final : public CostmapLayer {
 public:
  // static_map: for the static mask (may be null: no mask). observations: the obstacle layer
  // of the same costmap; with it, only cells the laser has seen free can become dynamic
  // (may be null). Both must outlive the layer.
  DynamicObstacleLayer(const DynamicObstacleConfig& config, const OccupancyMap* static_map,
                       const ObstacleLayer* observations = nullptr) noexcept
      : config_(config), static_map_(static_map), observations_(observations) {}
  [[nodiscard]] const char* name() const noexcept override { return "dynamic_obstacles"; }
  Status init(const Costmap2D& master, std::pmr::memory_resource& resource) override;
  void on_window_moved(int shift_cols, int shift_rows) noexcept override;
  void update(Costmap2D& master, const CostmapInputs& inputs) noexcept override;

  [[nodiscard]] std::span<const DolTrack> tracks() const noexcept { return tracker_.tracks(); }
  [[nodiscard]] std::span<const Blob> blobs() const noexcept { return blobs_; }
  [[nodiscard]] std::span<const std::uint8_t> dynamic_cells() const noexcept { return dynamic_; }
  [[nodiscard]] const BackgroundSubtractor& detector() const noexcept { return detector_; }
  [[nodiscard]] const DynamicObstacleConfig& config() const noexcept { return config_; }
  // The movers predicted to stamp_ns (state and covariance), for the planner and the safety
  // filter, then the candidates (MovingObstacles::candidate_count) in the slots left; count 0
  // when the layer is disabled.
  void movers(hal::Nanos stamp_ns, msg::MovingObstacles& out) const noexcept;
  // Blobs found since init(), summed over the scans.
  [[nodiscard]] std::uint64_t detections() const noexcept { return detections_; }
  // Before init: the tracked people (camera and laser) that may vouch for a track
  // (DolTrackerConfig::camera_vouches); must outlive the layer.
  void vouch_with(const msg::People* people) noexcept { people_ = people; }
  // Tracks made movers by the people's word since init().
  [[nodiscard]] std::uint64_t vouched() const noexcept { return vouched_; }

 private:
  // How far ahead of a coasting mover its way is checked for a wall.
  static constexpr double kWallLookahead_m = 0.2;
  [[nodiscard]] bool near_wall(double x_m, double y_m) const noexcept;
  // A mover out of sight whose prediction runs into the static map turns back there, as
  // something going back and forth along an aisle does; it does not go through the wall.
  void turn_back_at_walls(hal::Nanos stamp_ns) noexcept;
  // One track predicted to stamp_ns, as published.
  void put(const DolTrack& track, hal::Nanos stamp_ns, msg::MovingObstacle& m) const noexcept;

  DynamicObstacleConfig config_;
  const OccupancyMap* static_map_;
  const ObstacleLayer* observations_;
  BackgroundSubtractor detector_;
  BlobFinder blob_finder_;
  MoverTracker tracker_;
  std::span<std::uint8_t> image_;
  std::span<std::uint8_t> dynamic_;
  std::span<std::uint8_t> mask_;           // per window cell: near the static map
  std::span<std::uint8_t> map_near_;       // per static-map cell: within the mask radius
  std::span<const Blob> blobs_;
  std::uint64_t detections_ = 0;
  const msg::People* people_ = nullptr;
  std::uint64_t vouched_ = 0;
  bool active_ = false;                    // enabled and initialised
};

}  // namespace sen3bot::nav
