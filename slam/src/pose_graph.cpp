// Levenberg-Marquardt on the pose graph's normal equations, robust losses by iteratively
// reweighted least squares.
//
// Each linearisation builds H = sum J^T W J and g = sum J^T W r over the edges (W: the edge's
// weights times its Huber weight at the current residual), fixed nodes left out of the unknowns.
// H goes to Eigen as triplets of its lower triangle; the step solves (H + lambda (diag H + eps)) d
// = -g, the damping applied through SimplicialLDLT's diagonal shift, so a rejected step only
// factorises again. The AMD ordering and symbolic analysis are kept until the edges, the nodes or
// the fixed set change.
//
// What still allocates (Eigen 3.4; counted on the 2000-node graph of the tests, as malloc calls):
// - each linearisation, about 10: setFromTriplets builds a transposed temporary with its counts
//   and copies it into fresh storage for the result, freeing the old;
// - each factorisation, 4: SimplicialLDLT::factorize's permuted copy of H (and its work vectors
//   too once the unknowns pass ~16000, Eigen's 128 KiB stack limit);
// - each linear solve, 1: the mask of the in-place inverse permutation;
// - after a change of structure: the ordering, the symbolic analysis and the vectors' resizes.
// The triplets, the poses and the index map reuse the members reserved at construction.
#include "sen3bot/slam/pose_graph.hpp"

#include <Eigen/SparseCholesky>
#include <Eigen/SparseCore>
#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>
#include <utility>

namespace sen3bot::slam {
namespace {

// Damping: the first lambda, and the range it moves in before a solve gives up.
constexpr double kInitialDamping = 1e-4;
constexpr double kMinDamping = 1e-12;
constexpr double kMaxDamping = 1e16;
// Added to the damped diagonal so a node no edge reaches still has a pivot.
constexpr double kDiagonalFloor = 1e-6;
// A step this small relative to the unknowns cannot change them: converged.
constexpr double kStepTolerance = 1e-12;
// Eigen indexes the unknowns, 3 per node, with int.
constexpr std::size_t kMaxGraphNodes = static_cast<std::size_t>(std::numeric_limits<int>::max() / 3);
// Entries of H per edge in the lower triangle: two 3x3 diagonal blocks (6 each) and one full block.
constexpr std::size_t kTripletsPerEdge = 21;

// An edge's residual at two poses, with what its Jacobian needs.
struct EdgeError {
  double rx = 0.0;
  double ry = 0.0;
  double rtheta = 0.0;
  double cos_from = 1.0;
  double sin_from = 0.0;
  double dx = 0.0;  // t_to - t_from, map frame
  double dy = 0.0;
};

EdgeError edge_error(const PoseEdge& e, const nav::Pose2D& from, const nav::Pose2D& to) {
  EdgeError err;
  err.cos_from = std::cos(from.theta_rad);
  err.sin_from = std::sin(from.theta_rad);
  err.dx = to.x_m - from.x_m;
  err.dy = to.y_m - from.y_m;
  err.rx = err.cos_from * err.dx + err.sin_from * err.dy - e.measurement.x_m;
  err.ry = -err.sin_from * err.dx + err.cos_from * err.dy - e.measurement.y_m;
  err.rtheta = nav::normalize_angle(to.theta_rad - from.theta_rad - e.measurement.theta_rad);
  return err;
}

double whitened_squared_norm(const PoseEdge& e, const EdgeError& err) {
  return e.weight_xy * (err.rx * err.rx + err.ry * err.ry) + e.weight_theta * err.rtheta * err.rtheta;
}

// 1/2 rho(s).
double robust_cost(const PoseEdge& e, double s) {
  if (e.huber_scale > 0.0 && s > e.huber_scale * e.huber_scale) {
    return e.huber_scale * std::sqrt(s) - 0.5 * e.huber_scale * e.huber_scale;
  }
  return 0.5 * s;
}

// rho'(s): the reweighting of IRLS (1 inside the Huber scale, scale / norm beyond).
double robust_weight(const PoseEdge& e, double s) {
  if (e.huber_scale > 0.0 && s > e.huber_scale * e.huber_scale) return e.huber_scale / std::sqrt(s);
  return 1.0;
}

bool finite_pose(const nav::Pose2D& p) {
  return std::isfinite(p.x_m) && std::isfinite(p.y_m) && std::isfinite(p.theta_rad);
}

}  // namespace

struct PoseGraph::Solver {
  using Matrix = Eigen::SparseMatrix<double, Eigen::ColMajor, int>;

  std::vector<Eigen::Triplet<double, int>> triplets;
  Matrix hessian;  // lower triangle
  Eigen::SimplicialLDLT<Matrix, Eigen::Lower, Eigen::AMDOrdering<int>> ldlt;
  bool analyzed = false;
  Eigen::VectorXd descent;   // -g
  Eigen::VectorXd diagonal;  // diag H, for the damping's share of the predicted decrease
  Eigen::VectorXd step;
  std::vector<int> variable;  // per node: its first unknown, -1 when fixed
  int unknowns = 0;
  std::vector<nav::Pose2D> candidate;  // the poses after a step, until it is accepted

  // The damped step: (H + lambda (diag H + eps)) d = -g, the damping applied by the
  // factorisation's diagonal shift, so H itself stays as linearised. False if it failed.
  bool solve_step(double lambda) {
    ldlt.setShift(lambda * kDiagonalFloor, 1.0 + lambda);
    ldlt.factorize(hessian);
    if (ldlt.info() != Eigen::Success) return false;
    step = ldlt.solve(descent);
    return step.allFinite();
  }

  // The linear model's decrease for the step: 1/2 d^T (lambda D d - g).
  [[nodiscard]] double predicted_decrease(double lambda) const {
    return 0.5 * step.dot(lambda * (diagonal.array() + kDiagonalFloor).matrix().cwiseProduct(step) + descent);
  }

  // A step this small against the free poses' own size (metres and radians alike) moves nothing.
  [[nodiscard]] bool negligible_step(const std::vector<nav::Pose2D>& poses) const {
    double size = 0.0;
    for (std::size_t n = 0; n < poses.size(); ++n) {
      if (variable[n] < 0) continue;
      const nav::Pose2D& p = poses[n];
      size += p.x_m * p.x_m + p.y_m * p.y_m + p.theta_rad * p.theta_rad;
    }
    return step.norm() <= kStepTolerance * (std::sqrt(size) + kStepTolerance);
  }

  // candidate = poses + step.
  void take_step(const std::vector<nav::Pose2D>& poses) {
    candidate = poses;
    for (std::size_t n = 0; n < poses.size(); ++n) {
      const int v = variable[n];
      if (v < 0) continue;
      nav::Pose2D& p = candidate[n];
      p.x_m += step[v];
      p.y_m += step[v + 1];
      p.theta_rad = nav::normalize_angle(p.theta_rad + step[v + 2]);
    }
  }
};

PoseGraph::PoseGraph(std::size_t max_nodes, std::size_t max_edges)
    : max_nodes_(max_nodes), max_edges_(max_edges), solver_(std::make_unique<Solver>()) {
  poses_.reserve(max_nodes);
  fixed_.reserve(max_nodes);
  edges_.reserve(max_edges);
  solver_->triplets.reserve(kTripletsPerEdge * max_edges);
  solver_->variable.reserve(max_nodes);
  solver_->candidate.reserve(max_nodes);
}

PoseGraph::~PoseGraph() = default;
PoseGraph::PoseGraph(PoseGraph&&) noexcept = default;
PoseGraph& PoseGraph::operator=(PoseGraph&&) noexcept = default;

Result<std::uint32_t> PoseGraph::add_node(const nav::Pose2D& initial) {
  if (poses_.size() >= max_nodes_ || poses_.size() >= kMaxGraphNodes) {
    return Error::format(Errc::capacity, "pose graph: node capacity %zu reached",
                         std::min(max_nodes_, kMaxGraphNodes));
  }
  if (!finite_pose(initial)) return Error(Errc::invalid_argument, "pose graph: a node's pose is not finite");
  const auto id = static_cast<std::uint32_t>(poses_.size());
  poses_.push_back({initial.x_m, initial.y_m, nav::normalize_angle(initial.theta_rad)});
  fixed_.push_back(id == 0 ? 1 : 0);  // the gauge: the map's origin stays where it is
  structure_changed_ = true;
  return id;
}

Status PoseGraph::add_edge(const PoseEdge& edge) {
  if (edges_.size() >= max_edges_) {
    return Error::format(Errc::capacity, "pose graph: edge capacity %zu reached", max_edges_);
  }
  if (edge.from >= poses_.size() || edge.to >= poses_.size() || edge.from == edge.to) {
    return Error::format(Errc::invalid_argument, "pose graph: edge %u -> %u: unknown or equal nodes (%zu)",
                         edge.from, edge.to, poses_.size());
  }
  if (!finite_pose(edge.measurement) || !std::isfinite(edge.weight_xy) || !std::isfinite(edge.weight_theta) ||
      !(edge.weight_xy > 0.0) || !(edge.weight_theta > 0.0) || !std::isfinite(edge.huber_scale) ||
      !(edge.huber_scale >= 0.0)) {
    return Error::format(Errc::invalid_argument,
                         "pose graph: edge %u -> %u needs a finite measurement, finite positive weights "
                         "(%g, %g) and a finite Huber scale >= 0 (%g)",
                         edge.from, edge.to, edge.weight_xy, edge.weight_theta, edge.huber_scale);
  }
  edges_.push_back(edge);
  structure_changed_ = true;
  return Status::success();
}

Status PoseGraph::set_fixed(std::uint32_t node, bool fixed) {
  if (node >= poses_.size()) {
    return Error::format(Errc::invalid_argument, "pose graph: no node %u (%zu nodes)", node, poses_.size());
  }
  const std::uint8_t flag = fixed ? 1 : 0;
  if (fixed_[node] != flag) {
    fixed_[node] = flag;
    structure_changed_ = true;
  }
  return Status::success();
}

Status PoseGraph::set_pose(std::uint32_t node, const nav::Pose2D& pose) {
  if (node >= poses_.size()) {
    return Error::format(Errc::invalid_argument, "pose graph: no node %u (%zu nodes)", node, poses_.size());
  }
  if (!finite_pose(pose)) {
    return Error::format(Errc::invalid_argument, "pose graph: node %u's pose is not finite", node);
  }
  poses_[node] = {pose.x_m, pose.y_m, nav::normalize_angle(pose.theta_rad)};
  return Status::success();
}

double PoseGraph::total_cost(const std::vector<nav::Pose2D>& poses) const {
  double sum = 0.0;
  for (const PoseEdge& e : edges_) {
    sum += robust_cost(e, whitened_squared_norm(e, edge_error(e, poses[e.from], poses[e.to])));
  }
  return sum;
}

double PoseGraph::cost() const { return total_cost(poses_); }

EdgeResidual PoseGraph::edge_residual(std::size_t edge) const {
  const PoseEdge& e = edges_[edge];
  const double norm = std::sqrt(whitened_squared_norm(e, edge_error(e, poses_[e.from], poses_[e.to])));
  return {norm, e.huber_scale > 0.0 && norm > e.huber_scale};
}

// Numbers the free nodes' unknowns (3 each, in node order) and sizes the vectors.
void PoseGraph::index_variables() {
  Solver& s = *solver_;
  s.variable.resize(poses_.size());
  int next = 0;
  for (std::size_t n = 0; n < poses_.size(); ++n) {
    s.variable[n] = fixed_[n] != 0 ? -1 : next;
    if (fixed_[n] == 0) next += 3;
  }
  s.unknowns = next;
  s.hessian.resize(next, next);
  s.descent.resize(next);
  s.diagonal.resize(next);
  s.step.resize(next);
  s.analyzed = false;
}

// H, -g and diag H at the current poses. Every edge emits the same triplets whatever their
// values, so the pattern, and with it the symbolic analysis, holds while the structure does.
void PoseGraph::linearize() {
  Solver& s = *solver_;
  s.triplets.clear();
  s.descent.setZero();
  s.diagonal.setZero();
  for (const PoseEdge& e : edges_) {
    const int va = s.variable[e.from];
    const int vb = s.variable[e.to];
    if (va < 0 && vb < 0) continue;
    const EdgeError err = edge_error(e, poses_[e.from], poses_[e.to]);
    const double k = robust_weight(e, whitened_squared_norm(e, err));
    const Eigen::Vector3d w(k * e.weight_xy, k * e.weight_xy, k * e.weight_theta);
    const Eigen::Vector3d r(err.rx, err.ry, err.rtheta);
    const double c = err.cos_from;
    const double sn = err.sin_from;
    Eigen::Matrix3d ja;
    ja << -c, -sn, -sn * err.dx + c * err.dy,  //
        sn, -c, -c * err.dx - sn * err.dy,     //
        0.0, 0.0, -1.0;
    Eigen::Matrix3d jb;
    jb << c, sn, 0.0,  //
        -sn, c, 0.0,   //
        0.0, 0.0, 1.0;
    const Eigen::Matrix3d wja = w.asDiagonal() * ja;
    const Eigen::Matrix3d wjb = w.asDiagonal() * jb;
    const Eigen::Vector3d wr = w.cwiseProduct(r);
    const auto add_diagonal_block = [&](int v, const Eigen::Matrix3d& j, const Eigen::Matrix3d& wj) {
      const Eigen::Matrix3d h = j.transpose() * wj;
      for (int row = 0; row < 3; ++row) {
        for (int col = 0; col <= row; ++col) s.triplets.emplace_back(v + row, v + col, h(row, col));
      }
      s.descent.segment<3>(v) -= j.transpose() * wr;
      s.diagonal.segment<3>(v) += h.diagonal();
    };
    if (va >= 0) add_diagonal_block(va, ja, wja);
    if (vb >= 0) add_diagonal_block(vb, jb, wjb);
    if (va >= 0 && vb >= 0) {
      const Eigen::Matrix3d hab = ja.transpose() * wjb;  // rows: from's unknowns, columns: to's
      for (int i = 0; i < 3; ++i) {
        for (int j = 0; j < 3; ++j) {
          if (va > vb) {
            s.triplets.emplace_back(va + i, vb + j, hab(i, j));
          } else {
            s.triplets.emplace_back(vb + j, va + i, hab(i, j));
          }
        }
      }
    }
  }
  s.hessian.setFromTriplets(s.triplets.begin(), s.triplets.end());
}

Result<SolveSummary> PoseGraph::optimize(const SolveOptions& options) {
  const auto start = std::chrono::steady_clock::now();
  if (options.max_iterations < 0 || !(options.relative_cost_tolerance >= 0.0)) {
    return Error::format(Errc::invalid_argument,
                         "pose graph: max_iterations %d (>= 0) and relative_cost_tolerance %g (>= 0)",
                         options.max_iterations, options.relative_cost_tolerance);
  }
  SolveSummary summary;
  double current = total_cost(poses_);
  if (!std::isfinite(current)) {
    return Error(Errc::invalid_argument, "pose graph: the cost at the current poses is not finite");
  }
  summary.initial_cost = current;
  Solver& s = *solver_;
  if (structure_changed_) {
    index_variables();
    structure_changed_ = false;
  }
  double lambda = kInitialDamping;
  double lambda_growth = 2.0;
  bool relinearize = true;
  while (s.unknowns > 0 && summary.iterations < options.max_iterations) {
    if (current <= 0.0) {
      summary.converged = true;
      break;
    }
    if (relinearize) {
      linearize();
      if (!s.analyzed) {
        s.ldlt.analyzePattern(s.hessian);
        s.analyzed = true;
      }
      relinearize = false;
    }
    ++summary.iterations;
    if (s.solve_step(lambda)) {
      if (s.negligible_step(poses_)) {
        summary.converged = true;
        break;
      }
      s.take_step(poses_);
      const double next = total_cost(s.candidate);
      const double predicted = s.predicted_decrease(lambda);
      if (std::isfinite(next) && next < current && predicted > 0.0) {
        const double rho = (current - next) / predicted;
        const double relative_decrease = (current - next) / current;
        std::swap(poses_, s.candidate);  // both reserved to max_nodes: no allocation
        current = next;
        // Nielsen's update: less damping as far as the model proved right.
        lambda = std::max(kMinDamping, lambda * std::max(1.0 / 3.0, 1.0 - std::pow(2.0 * rho - 1.0, 3)));
        lambda_growth = 2.0;
        relinearize = true;
        if (relative_decrease <= options.relative_cost_tolerance) {
          summary.converged = true;
          break;
        }
        continue;
      }
    }
    // Rejected (or not solvable): more damping, a shorter step nearer the gradient's direction.
    lambda *= lambda_growth;
    lambda_growth *= 2.0;
    if (lambda > kMaxDamping) break;  // no step lowers the cost: a minimum to numerical precision
  }
  if (s.unknowns == 0) summary.converged = true;
  summary.final_cost = current;
  summary.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  return summary;
}

}  // namespace sen3bot::slam
