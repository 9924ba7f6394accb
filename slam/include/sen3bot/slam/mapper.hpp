#pragma once
// Laser SLAM: each scan is matched into the submap being built, inserted, and becomes a node of
// a pose graph tied to the submaps it went into; finished submaps are searched for loop
// closures with the scans of other times, and the graph is solved again when one is found.
// The map is drawn at the end from every scan at its solved pose.
//
// Memory: everything but the pose graph comes from the arena given to init() (bytes_for() says
// how much for a configuration and capacity); the graph reserves its own arrays at init(), and
// its solver allocates inside Eigen when it runs (pose_graph.hpp).
#include <cstddef>
#include <cstdint>
#include <memory_resource>
#include <optional>
#include <span>
#include <string>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/slam/branch_bound.hpp"
#include "sen3bot/slam/grid.hpp"
#include "sen3bot/slam/laser_record.hpp"
#include "sen3bot/slam/pose_graph.hpp"
#include "sen3bot/slam/scan_matcher.hpp"

namespace sen3bot::slam {

struct MapperConfig {
  double resolution_m = 0.05;
  int submap_side_cells = 1024;  // a submap being built: 51.2 m a side at 0.05 m
  int scans_per_submap = 30;     // a new submap starts every this many scans; each takes twice as many
  double min_range_m = 0.1;      // returns used; nearer ones are the robot or noise
  double max_range_m = 20.0;
  // The scan-to-submap match uses returns nearer than this fraction of the range (mapper.cpp).
  double match_range_fraction = 0.75;
  InsertionConfig insertion;
  LocalMatchConfig local;
  LoopSearchConfig loop;
  double loop_min_score = 0.6;      // a loop closure's scan must fit at least this well
  double loop_ambiguity = 0.93;     // a distinct second fit this close to the best rejects it
  double loop_exclusion_m = 0.5;    // "distinct": this far away, or
  double loop_exclusion_rad = 0.2;  // this far turned
  int loop_every_n_scans = 10;      // which scans are tried against older submaps
  int loops_per_submap = 3;         // closures a submap takes from one batch of scans (more add little)
  double loop_max_distance_m = 6.0; // from the scan to the middle of a submap's scans
  // The graph's trust: a scan in the submap it was matched into, and a loop closure (Huber).
  double local_sigma_xy_m = 0.02;
  double local_sigma_theta_rad = 0.005;
  double loop_sigma_xy_m = 0.05;
  double loop_sigma_theta_rad = 0.02;
  double loop_huber_scale = 1.5;
};

struct MapperCapacity {
  std::size_t scans = 0;
  std::size_t beams = 361;                      // returns kept per scan at most
  std::size_t submaps = 0;                      // 0: from scans and scans_per_submap
  std::size_t finished_submap_bytes = 64u << 20;  // the finished submaps' cropped grids, together
};

struct MapperStats {
  std::size_t scans = 0;
  std::size_t submaps = 0;
  std::size_t loop_searches = 0;
  std::size_t loops_accepted = 0;
  std::size_t loops_rejected_ambiguous = 0;  // a distinct second fit nearly as good
  std::size_t optimisations = 0;
  double optimisation_s = 0.0;
  double matching_s = 0.0;  // scan-to-submap matching and insertion
  double loop_search_s = 0.0;
};

// How a probability byte of the drawn map reads: occupied (100), free (0) or unknown (-1).
std::int8_t occupancy_of(std::uint8_t byte) noexcept;

class Mapper {
 public:
  [[nodiscard]] static std::size_t bytes_for(const MapperConfig& config, const MapperCapacity& capacity) noexcept;
  Status init(std::pmr::memory_resource& arena, const MapperConfig& config, const MapperCapacity& capacity);

  // One scan, in the order of the drive.
  Status add(const LaserRecord& scan);
  // Finishes the submaps still open, searches them, and solves the graph once more.
  Status finish();

  [[nodiscard]] std::size_t scan_count() const noexcept { return node_count_; }
  [[nodiscard]] nav::Pose2D scan_pose(std::size_t scan) const;  // in the map frame (the first scan's pose)
  [[nodiscard]] const MapperStats& stats() const noexcept { return stats_; }

  // Every scan at its solved pose, as an occupancy map with a margin of unknown cells
  // (allocates: done once, at the end of a drive): 100 wall, 0 free, -1 unknown (occupancy_of).
  [[nodiscard]] Result<nav::OccupancyMap> render(double resolution_m) const;

 private:
  struct Node {
    nav::Pose2D local;        // where the front end put it
    nav::Pose2D mount;        // the scanner in the robot frame
    std::uint32_t graph = 0;  // its pose graph node
    std::uint32_t first_point = 0;
    std::uint32_t point_count = 0;
  };
  struct Submap {
    nav::Pose2D local;         // heading 0: the grid is axis-aligned in it
    std::uint32_t graph = 0;
    int grid = -1;             // the build grid while open
    ProbabilityView finished;  // the cropped grid once finished
    std::uint32_t first_node = 0;
    std::uint32_t scans = 0;
    double sum_x = 0.0;        // its scans' local positions, for the middle
    double sum_y = 0.0;
  };

  Status start_submap(const nav::Pose2D& at);
  Status finish_oldest();
  Status search_loops(std::size_t submap, std::size_t first_new_node);
  Status try_loop(std::size_t submap, std::size_t node);
  Status optimise(int iterations);
  [[nodiscard]] nav::Pose2D global_estimate(const nav::Pose2D& local) const noexcept;
  [[nodiscard]] nav::Pose2D graph_pose(std::uint32_t id) const { return graph_->pose(id); }
  [[nodiscard]] nav::Point2D submap_middle(const Submap& s) const noexcept;
  [[nodiscard]] std::span<const PointF> points_of(const Node& n) const noexcept {
    return {points_.data() + n.first_point, n.point_count};
  }

  MapperConfig config_;
  MapperCapacity capacity_;
  std::pmr::memory_resource* arena_ = nullptr;
  BuildGrid grids_[2];
  bool grid_used_[2] = {false, false};
  ScanMatcher matcher_;
  BranchBound loops_;
  std::optional<PoseGraph> graph_;
  std::span<Node> nodes_;
  std::span<PointF> points_;
  std::span<PointF> scratch_;
  std::span<Submap> submaps_;
  std::size_t node_count_ = 0;
  std::size_t point_count_ = 0;
  std::size_t submap_count_ = 0;
  std::size_t active_[2] = {0, 0};  // submap indices, oldest first
  std::size_t active_count_ = 0;
  std::size_t searched_up_to_ = 0;  // nodes before this were searched against older submaps
  nav::Pose2D last_odometry_;
  nav::Pose2D correction_;          // local frame -> map frame, from the last solve
  MapperStats stats_;
};

// Every scan's solved pose, `index x y theta` a line in the input's order (metres, radians), in
// the frame `frame` places the mapper's in (identity: the first scan's pose). Errc::io when the
// file cannot be written.
Status write_poses(const Mapper& mapper, const std::string& path, const nav::Pose2D& frame = {});

}  // namespace sen3bot::slam
