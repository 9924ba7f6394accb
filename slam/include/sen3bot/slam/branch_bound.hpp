#pragma once
// Loop-closure search: where in a finished submap does a scan fit best, over a window metres
// wide and tens of degrees? Branch and bound over a stack of max-pooled copies of the submap
// (as Cartographer's fast correlative matcher): a coarse cell holds the best probability of the
// 2^k x 2^k fine cells it covers, so a coarse candidate's score bounds every fine pose below it,
// and whole regions are dropped when their bound cannot beat the best found so far.
#include <cstddef>
#include <cstdint>
#include <memory_resource>
#include <optional>
#include <span>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/slam/grid.hpp"
#include "sen3bot/slam/scan_matcher.hpp"

namespace sen3bot::slam {

struct LoopSearchConfig {
  double linear_window_m = 3.5;
  double angular_window_rad = 0.35;  // about 20 degrees
  int depth = 6;                     // coarsest level: 2^depth cells a side
  // The angle step moves a point this far away by a cell: farther points move more between two
  // steps, and the refinement after the search takes up the difference.
  double angle_step_range_m = 10.0;
  int search_points = 90;  // the scan's points the search scores, evenly taken
};

// A pose region a search must not answer from (the best answer of an earlier search, when
// asking whether a second, distinct fit exists).
struct Exclusion {
  nav::Pose2D centre;
  double radius_m = 0.0;
  double angle_rad = 0.0;
};

class BranchBound {
 public:
  // Memory for submaps up to max_cells_side cells a side and scans of max_points points.
  Status init(std::pmr::memory_resource& arena, int max_cells_side, std::size_t max_points, double resolution_m,
              const LoopSearchConfig& config);

  // Builds the max-pooled levels of a submap (each search of that submap reuses them).
  Status prepare(const ProbabilityView& submap) noexcept;
  // The best pose within the window around `guess` (the scan's pose in the submap frame)
  // scoring at least min_score, outside `exclusion` if one is given; none when there is none.
  [[nodiscard]] std::optional<Match> search(const nav::Pose2D& guess, std::span<const PointF> points, double min_score,
                                            const Exclusion* exclusion = nullptr) noexcept;
  [[nodiscard]] const LoopSearchConfig& config() const noexcept { return config_; }
  // The prepared level's byte at (col, row) of the submap's cells (what the search bounds with).
  [[nodiscard]] std::uint8_t level_byte(int level, int col, int row) const noexcept;
  // Candidates scored in the last search (its cost).
  [[nodiscard]] std::size_t last_scored() const noexcept { return scored_; }

 private:
  struct Candidate {
    int angle = 0;  // index into the rotated scans
    int dx = 0;     // offset of the candidate's lower-left fine cell, in cells
    int dy = 0;
    float score = 0.0F;
  };
  float bound(int level, const Candidate& c) const noexcept;
  void descend(int level, const Candidate& c, double min_score, Candidate& best, const Exclusion* exclusion,
               const nav::Pose2D& guess) noexcept;
  [[nodiscard]] nav::Pose2D pose_of(const Candidate& c, const nav::Pose2D& guess) const noexcept;

  LoopSearchConfig config_;
  int max_side_ = 0;
  int pad_ = 0;     // 2^depth - 1 cells below and left of the submap in every level
  int stride_ = 0;  // cells per level row
  int width_ = 0;   // the prepared submap's size
  int height_ = 0;
  ProbabilityView submap_;
  std::span<std::uint8_t> levels_;  // depth + 1 levels of (max_side + pad) ^ 2 bytes
  std::size_t level_size_ = 0;
  std::span<int> cols_;             // rotated scans: angle-major, max_points each
  std::span<int> rows_;
  std::span<Candidate> top_;
  double resolution_m_ = 0.05;
  int max_angles_ = 0;
  std::size_t max_points_ = 0;
  std::size_t points_ = 0;
  int angle_count_ = 0;
  double angle_step_ = 0.0;
  int window_cells_ = 0;
  std::size_t scored_ = 0;
};

}  // namespace sen3bot::slam
