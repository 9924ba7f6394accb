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
#include <cstdint>
#include <memory_resource>
#include <span>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/msg/navigation.hpp"
#include "sen3bot/msg/people.hpp"
#include "sen3bot/nav/assignment.hpp"
#include "sen3bot/nav/costmap.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/nav/mover_cost.hpp"
#include "sen3bot/nav/mover_detection.hpp"
#include "sen3bot/nav/mover_tracker.hpp"

namespace sen3bot::nav {

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
