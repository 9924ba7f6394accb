#pragma once
// The 2D pose graph the SLAM's maps are solved on: nodes are poses in the map frame (one per
// laser scan, one per submap origin), edges are relative-pose measurements between two nodes.
// optimize() moves the free nodes to the least-squares poses (Levenberg-Marquardt on a sparse
// Cholesky factorisation), starting from the poses the nodes hold now, so a graph solved again
// after new loop closures starts where the last solve ended.
//
// Edge e from node a to node b with measurement z (b in a's frame) has the residual
//   r = [ R(theta_a)^T (t_b - t_a) - z_t ;  normalize(theta_b - theta_a - z_theta) ]
// and the cost 1/2 rho(s), s = w_xy (r_x^2 + r_y^2) + w_theta r_theta^2 (the squared whitened
// residual). rho(s) = s for the squared loss; Huber with scale k is rho(s) = s while sqrt(s) <= k
// and 2 k sqrt(s) - k^2 beyond, so a wrong loop closure pulls with a bounded force.
//
// Memory: the node and edge arrays and the solver's triplet list are reserved at construction
// (about 400 bytes per edge and 50 per node of capacity). optimize() still allocates inside
// Eigen on every iteration (pose_graph.cpp lists where), so it belongs on a background thread.
// Not thread-safe; one graph per thread.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <vector>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/nav/geometry.hpp"

namespace sen3bot::slam {

struct PoseEdge {
  std::uint32_t from = 0;
  std::uint32_t to = 0;
  nav::Pose2D measurement;    // pose(to) in pose(from)'s frame
  double weight_xy = 1.0;     // 1 / sigma^2 of x and y (m^-2)
  double weight_theta = 1.0;  // 1 / sigma^2 of the heading (rad^-2)
  double huber_scale = 0.0;   // 0: squared loss; > 0: Huber on the whitened residual norm
};

struct SolveOptions {
  int max_iterations = 20;  // steps tried, accepted or not
  // Converged when an accepted step lowers the cost by less than this fraction of it.
  double relative_cost_tolerance = 1e-6;
};

struct SolveSummary {
  double initial_cost = 0.0;
  double final_cost = 0.0;
  int iterations = 0;
  bool converged = false;  // a tolerance was met (false: max_iterations ran out, or no step helped)
  double seconds = 0.0;    // wall time of the whole call
};

// One edge at the current poses: what a report of loop closures lists.
struct EdgeResidual {
  double whitened_norm = 0.0;  // sqrt(s) above
  bool down_weighted = false;  // beyond its Huber scale: the solver trusts it less than a squared loss would
};

class PoseGraph {
 public:
  // Capacities are fixed: nodes and edges beyond them are refused (Errc::capacity).
  PoseGraph(std::size_t max_nodes, std::size_t max_edges);
  ~PoseGraph();
  PoseGraph(PoseGraph&&) noexcept;  // a moved-from graph may only be assigned to or destroyed
  PoseGraph& operator=(PoseGraph&&) noexcept;
  PoseGraph(const PoseGraph&) = delete;
  PoseGraph& operator=(const PoseGraph&) = delete;

  // A node at its first estimate; ids count from 0. Node 0 is fixed (it holds the map's origin).
  Result<std::uint32_t> add_node(const nav::Pose2D& initial);
  // Both nodes must exist and differ; the measurement finite, the weights finite and positive,
  // the Huber scale finite and not negative (else Errc::invalid_argument).
  Status add_edge(const PoseEdge& edge);
  // A fixed node keeps its pose through optimize(). At least one node should stay fixed: with
  // none, the graph may slide as a whole (only the damping holds it).
  Status set_fixed(std::uint32_t node, bool fixed = true);
  Status set_pose(std::uint32_t node, const nav::Pose2D& pose);

  // Levenberg-Marquardt from the current poses. Errc::invalid_argument for options out of range
  // or a cost that is not finite at the start.
  Result<SolveSummary> optimize(const SolveOptions& options = {});

  // node < node_count(), edge < edge_count().
  [[nodiscard]] const nav::Pose2D& pose(std::uint32_t node) const { return poses_[node]; }
  [[nodiscard]] bool fixed(std::uint32_t node) const { return fixed_[node] != 0; }
  [[nodiscard]] const PoseEdge& edge(std::size_t index) const { return edges_[index]; }
  [[nodiscard]] std::size_t node_count() const noexcept { return poses_.size(); }
  [[nodiscard]] std::size_t edge_count() const noexcept { return edges_.size(); }

  // The total cost at the current poses, robust losses applied.
  [[nodiscard]] double cost() const;
  [[nodiscard]] EdgeResidual edge_residual(std::size_t edge) const;

 private:
  struct Solver;  // Eigen's matrices and factorisation, kept between solves

  void index_variables();
  void linearize();
  [[nodiscard]] double total_cost(const std::vector<nav::Pose2D>& poses) const;

  std::size_t max_nodes_ = 0;
  std::size_t max_edges_ = 0;
  std::vector<nav::Pose2D> poses_;
  std::vector<std::uint8_t> fixed_;  // 0 or 1 per node
  std::vector<PoseEdge> edges_;
  std::unique_ptr<Solver> solver_;
  bool structure_changed_ = true;  // the linear system's pattern must be built and analysed again
};

}  // namespace sen3bot::slam
