#pragma once
// Scan-to-submap matching as the scan arrives: a correlative search over a small window around
// the motion prior (every cell step and every angle step a point at the scan's far end moves
// about one cell), then a Gauss-Newton refinement on the bilinear probability surface, pulled
// gently towards the search's answer. The search finds the basin; the refinement the sub-cell
// pose.
#include <cstddef>
#include <memory_resource>
#include <span>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/slam/grid.hpp"

namespace sen3bot::slam {

struct LocalMatchConfig {
  double linear_window_m = 0.15;
  double angular_window_rad = 0.17;  // about 10 degrees
  // The search's penalty for leaving the prior: score * exp(-(w_t d^2 + w_r a^2)).
  double search_translation_weight = 0.1;
  double search_rotation_weight = 0.1;
  // The refinement's pull towards the search's pose, against the mean squared (1 - p).
  double refine_translation_weight = 10.0;
  double refine_rotation_weight = 40.0;
  int refine_iterations = 10;
};

struct Match {
  nav::Pose2D pose;
  double score = 0.0;  // mean probability of the cells the points fall in
};

// The turn that moves a point at `range_m` by one cell: the search's angle step.
double angular_step(double resolution_m, double range_m) noexcept;

// The mean probability of the cells the points fall in, the scan at `pose` of the grid's frame.
double match_score(const ProbabilityView& grid, const nav::Pose2D& pose, std::span<const PointF> points) noexcept;

// Gauss-Newton from `start`; the answer never scores below the start.
Match refine_match(const ProbabilityView& grid, const nav::Pose2D& start, std::span<const PointF> points,
                   double translation_weight, double rotation_weight, int iterations) noexcept;

class ScanMatcher {
 public:
  Status init(std::pmr::memory_resource& arena, std::size_t max_points, const LocalMatchConfig& config);
  // `prior`: the scan's pose in the grid's frame as odometry predicts it; points in the scan's frame.
  [[nodiscard]] Match match(const ProbabilityView& grid, const nav::Pose2D& prior,
                            std::span<const PointF> points) noexcept;
  [[nodiscard]] const LocalMatchConfig& config() const noexcept { return config_; }

 private:
  LocalMatchConfig config_;
  std::span<int> cols_;
  std::span<int> rows_;
  std::span<float> sums_;
};

}  // namespace sen3bot::slam
