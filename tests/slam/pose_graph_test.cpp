// The pose graph optimiser: exact solutions of noise-free and hand-solvable graphs, a long
// drifting odometry chain closed by loop closures, wrong closures under Huber and squared
// losses, errors, determinism and the solve time.
#include "sen3bot/slam/pose_graph.hpp"

#include <gtest/gtest.h>

#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <limits>
#include <numbers>
#include <random>
#include <vector>

#include "alloc_counter.hpp"

namespace sen3bot::slam {
namespace {

using nav::Pose2D;

PoseEdge pg_edge(std::uint32_t from, std::uint32_t to, const Pose2D& z, double sigma_xy, double sigma_theta,
                 double huber = 0.0) {
  return {from, to, z, 1.0 / (sigma_xy * sigma_xy), 1.0 / (sigma_theta * sigma_theta), huber};
}

double pg_position_rms(const PoseGraph& g, const std::vector<Pose2D>& want) {
  double sum = 0.0;
  for (std::uint32_t i = 0; i < want.size(); ++i) {
    sum += std::pow(g.pose(i).x_m - want[i].x_m, 2) + std::pow(g.pose(i).y_m - want[i].y_m, 2);
  }
  return std::sqrt(sum / static_cast<double>(want.size()));
}

std::vector<Pose2D> pg_poses(const PoseGraph& g) {
  std::vector<Pose2D> out;
  for (std::uint32_t i = 0; i < g.node_count(); ++i) out.push_back(g.pose(i));
  return out;
}

// A point at arc length s of a 60 m stadium: 15 m straights joined by half circles of 15/pi m.
Pose2D pg_stadium(double s) {
  const double r = 15.0 / std::numbers::pi;
  s = std::fmod(s, 60.0);
  if (s < 15.0) return {s, 0.0, 0.0};
  if (s < 30.0) {
    const double a = (s - 15.0) / r;
    return {15.0 + r * std::sin(a), r - r * std::cos(a), a};
  }
  if (s < 45.0) return {15.0 - (s - 30.0), 2.0 * r, std::numbers::pi};
  const double a = (s - 45.0) / r;
  return {-r * std::sin(a), r + r * std::cos(a), std::numbers::pi + a};
}

// Five laps of the stadium, 2000 scans 0.15 m apart, each lap 0.25 m to the left of the last.
// The relative poses between scans carry noise and a heading bias that drifts from 0.3 to 0.6 mrad
// per scan: dead reckoning ends 0.9 rad and metres off. 20 loop closures join a scan to the same
// place one lap before, evenly spread from the start (a stretch before the first closure would
// keep its heading error and turn the whole map about node 0) to the end; 5 wrong ones join scans
// metres apart as if they were half a metre apart.
//
// Closures between laps tell that the laps look alike, not what they look like: a bias that
// repeats with every lap would bend them all alike, unseen. One that drifts slowly is nearly
// constant along a lap, and that the closures do see.
struct LongRun {
  static constexpr std::uint32_t kNodes = 2000;
  // The sigmas the edges are weighted by. The simulated errors are smaller, as a SLAM's matchers
  // are weighted for their worst case, and the odometry's heading sigma is wide enough for the
  // bias it has to absorb.
  static constexpr double kOdomSigmaXy = 0.005;
  static constexpr double kOdomSigmaTheta = 0.002;
  static constexpr double kLoopSigmaXy = 0.02;
  static constexpr double kLoopSigmaTheta = 0.003;
  static constexpr double kOdomNoiseXy = 0.001;
  static constexpr double kOdomNoiseTheta = 0.0001;
  static constexpr double kLoopNoise = 0.5;  // of the sigmas
  static constexpr double kHuber = 1.0;

  std::vector<Pose2D> truth;
  std::vector<Pose2D> dead_reckoning;
  std::vector<PoseEdge> odometry;
  std::vector<PoseEdge> closures;
  std::vector<PoseEdge> wrong;

  LongRun() {
    std::mt19937 rng(20240611);
    std::normal_distribution<double> unit(0.0, 1.0);
    for (std::uint32_t i = 0; i < kNodes; ++i) {
      Pose2D p = pg_stadium(0.15 * i);
      const double lap = std::floor(0.15 * i / 60.0);
      p.y_m += 0.25 * lap;
      truth.push_back(p);
    }
    dead_reckoning.push_back(truth[0]);
    for (std::uint32_t i = 0; i + 1 < kNodes; ++i) {
      Pose2D z = nav::relative_pose(truth[i], truth[i + 1]);
      const double bias = 0.0003 + 0.0003 * i / kNodes;
      z.x_m += kOdomNoiseXy * unit(rng);
      z.y_m += kOdomNoiseXy * unit(rng);
      z.theta_rad += bias + kOdomNoiseTheta * unit(rng);
      odometry.push_back(pg_edge(i, i + 1, z, kOdomSigmaXy, kOdomSigmaTheta));
      dead_reckoning.push_back(nav::apply_motion(dead_reckoning.back(), z));
    }
    for (std::uint32_t j = 0; j < 20; ++j) {
      const std::uint32_t to = 400 + 84 * j;
      const std::uint32_t from = to - 400;
      Pose2D z = nav::relative_pose(truth[from], truth[to]);
      z.x_m += kLoopNoise * kLoopSigmaXy * unit(rng);
      z.y_m += kLoopNoise * kLoopSigmaXy * unit(rng);
      z.theta_rad += kLoopNoise * kLoopSigmaTheta * unit(rng);
      closures.push_back(pg_edge(from, to, z, kLoopSigmaXy, kLoopSigmaTheta));
    }
    // Scans metres apart matched as if they were half a metre apart.
    const std::uint32_t pairs[5][2] = {{300, 950}, {520, 1330}, {700, 1790}, {1100, 1560}, {1250, 1900}};
    for (const auto& pair : pairs) {
      wrong.push_back(pg_edge(pair[0], pair[1], {0.5, 0.2, 0.1}, kLoopSigmaXy, kLoopSigmaTheta));
    }
  }

  // The graph from dead reckoning; loop closures robust when huber.
  PoseGraph graph(bool with_wrong, bool huber) const {
    PoseGraph g(kNodes, kNodes + 40);
    for (const Pose2D& p : dead_reckoning) EXPECT_TRUE(g.add_node(p).ok());
    for (const PoseEdge& e : odometry) EXPECT_TRUE(g.add_edge(e).ok());
    for (PoseEdge e : closures) {
      e.huber_scale = huber ? kHuber : 0.0;
      EXPECT_TRUE(g.add_edge(e).ok());
    }
    if (with_wrong) {
      for (PoseEdge e : wrong) {
        e.huber_scale = huber ? kHuber : 0.0;
        EXPECT_TRUE(g.add_edge(e).ok());
      }
    }
    return g;
  }
};

const LongRun& long_run() {
  static const LongRun run;
  return run;
}

SolveSummary solved(PoseGraph& g, const SolveOptions& options = {}) {
  Result<SolveSummary> r = g.optimize(options);
  EXPECT_TRUE(r.ok()) << (r.ok() ? "" : r.error().c_str());
  return r.ok() ? *r : SolveSummary{};
}

TEST(PoseGraph, NoiseFreeSquareLoopConvergesToTheExactPoses) {
  // A 2 m square walked anticlockwise, 8 nodes, turned so that the headings wrap through +-pi.
  const Pose2D local[8] = {{0, 0, 0},
                           {1, 0, 0},
                           {2, 0, std::numbers::pi / 2},
                           {2, 1, std::numbers::pi / 2},
                           {2, 2, std::numbers::pi},
                           {1, 2, std::numbers::pi},
                           {0, 2, -std::numbers::pi / 2},
                           {0, 1, -std::numbers::pi / 2}};
  const Pose2D placement{0.5, -1.2, 2.9};
  std::vector<Pose2D> truth;
  for (const Pose2D& p : local) truth.push_back(nav::apply_motion(placement, p));

  PoseGraph g(8, 16);
  for (std::uint32_t i = 0; i < 8; ++i) {
    const double k = i == 0 ? 0.0 : 1.0;  // node 0 is the fixed origin
    const Pose2D start{truth[i].x_m + 0.3 * k * std::sin(i * 1.7),  //
                       truth[i].y_m - 0.25 * k * std::cos(i * 2.3),
                       truth[i].theta_rad + 0.3 * k * std::sin(i * 0.9 + 0.4)};
    ASSERT_EQ(*g.add_node(start), i);
  }
  for (std::uint32_t i = 0; i < 8; ++i) {
    const std::uint32_t j = (i + 1) % 8;
    ASSERT_TRUE(g.add_edge(pg_edge(i, j, nav::relative_pose(truth[i], truth[j]), 0.05, 0.02)).ok());
  }
  ASSERT_TRUE(g.add_edge(pg_edge(1, 5, nav::relative_pose(truth[1], truth[5]), 0.1, 0.05)).ok());
  ASSERT_TRUE(g.add_edge(pg_edge(6, 3, nav::relative_pose(truth[6], truth[3]), 0.1, 0.05, 2.0)).ok());

  const SolveSummary s = solved(g);
  EXPECT_TRUE(s.converged);
  EXPECT_GT(s.initial_cost, 100.0);
  EXPECT_LT(s.final_cost, 1e-18);
  EXPECT_EQ(s.final_cost, g.cost());
  for (std::uint32_t i = 0; i < 8; ++i) {
    EXPECT_NEAR(g.pose(i).x_m, truth[i].x_m, 1e-9) << i;
    EXPECT_NEAR(g.pose(i).y_m, truth[i].y_m, 1e-9) << i;
    EXPECT_NEAR(nav::normalize_angle(g.pose(i).theta_rad - truth[i].theta_rad), 0.0, 1e-9) << i;
  }
  EXPECT_EQ(g.pose(0), truth[0]);
  std::printf("square loop: cost %.3g -> %.3g in %d iterations\n", s.initial_cost, s.final_cost,
              s.iterations);
}

TEST(PoseGraph, ConflictingMeasurementsGiveTheWeightedMean) {
  // Node 1 measured twice from the fixed node 0 (heading 0): each coordinate decouples into a
  // weighted mean, x = (1 * 1.0 + 3 * 1.3) / 4, y = (1 * 0.2 + 3 * -0.1) / 4,
  // theta = (2 * 0.3 + 1 * -0.15) / 3 (weights 1/sigma^2).
  PoseGraph g(2, 2);
  ASSERT_TRUE(g.add_node({0, 0, 0}).ok());
  ASSERT_TRUE(g.add_node({0.4, 0.5, -0.6}).ok());
  ASSERT_TRUE(g.add_edge({0, 1, {1.0, 0.2, 0.3}, 1.0, 2.0}).ok());
  ASSERT_TRUE(g.add_edge({0, 1, {1.3, -0.1, -0.15}, 3.0, 1.0}).ok());
  const SolveSummary s = solved(g, {.max_iterations = 50, .relative_cost_tolerance = 1e-14});
  EXPECT_TRUE(s.converged);
  const Pose2D p = g.pose(1);
  EXPECT_NEAR(p.x_m, 1.225, 1e-12);
  EXPECT_NEAR(p.y_m, -0.025, 1e-12);
  EXPECT_NEAR(p.theta_rad, 0.15, 1e-12);
  // The cost by hand: 1/2 sum w r^2, s the edges' squared whitened residuals.
  const double x = p.x_m;
  const double y = p.y_m;
  const double t = p.theta_rad;
  const double s0 = std::pow(x - 1.0, 2) + std::pow(y - 0.2, 2) + 2.0 * std::pow(t - 0.3, 2);
  const double s1 = 3.0 * (std::pow(x - 1.3, 2) + std::pow(y + 0.1, 2)) + std::pow(t + 0.15, 2);
  EXPECT_NEAR(g.cost(), 0.5 * (s0 + s1), 1e-14);
  EXPECT_NEAR(g.edge_residual(0).whitened_norm, std::sqrt(s0), 1e-14);
}

TEST(PoseGraph, HuberBoundsTheOutliersPull) {
  // x: weight 10 at 1.0, and weight 4 at 3.0 under Huber scale 1. Beyond the scale the second
  // pulls with k sqrt(w) = 2, so 10 (x - 1) = 2: x = 1.2 (where its whitened residual, 3.6, is
  // indeed beyond 1). Squared, x would be the mean (10 + 12) / 14.
  for (const double huber : {1.0, 0.0}) {
    PoseGraph g(2, 2);
    ASSERT_TRUE(g.add_node({0, 0, 0}).ok());
    ASSERT_TRUE(g.add_node({2.0, 0.1, 0.1}).ok());
    ASSERT_TRUE(g.add_edge({0, 1, {1.0, 0.0, 0.0}, 10.0, 10.0}).ok());
    ASSERT_TRUE(g.add_edge({0, 1, {3.0, 0.0, 0.0}, 4.0, 4.0, huber}).ok());
    const SolveSummary s = solved(g, {.max_iterations = 100, .relative_cost_tolerance = 1e-15});
    EXPECT_TRUE(s.converged);
    EXPECT_NEAR(g.pose(1).x_m, huber > 0 ? 1.2 : 22.0 / 14.0, 1e-7);
    EXPECT_NEAR(g.pose(1).y_m, 0.0, 1e-9);
    EXPECT_NEAR(g.pose(1).theta_rad, 0.0, 1e-9);
    EXPECT_FALSE(g.edge_residual(0).down_weighted);
    EXPECT_EQ(g.edge_residual(1).down_weighted, huber > 0);
    if (huber > 0) {
      EXPECT_NEAR(g.edge_residual(1).whitened_norm, 3.6, 1e-8);
      // Huber's cost: 1/2 10 0.2^2 + (2 k n - k^2) / 2 with n = 3.6.
      EXPECT_NEAR(g.cost(), 0.5 * 10.0 * 0.04 + (2.0 * 3.6 - 1.0) / 2.0, 1e-8);
    }
  }
}

TEST(PoseGraph, SolutionIsAStationaryPointOfTheCost) {
  // A small noisy graph with a robust edge: at the solution the cost's numerical gradient in
  // every free coordinate vanishes.
  PoseGraph g(5, 8);
  const Pose2D start[5] = {{0, 0, 0}, {1.1, 0.1, 0.2}, {2.0, 0.6, 0.9}, {2.2, 1.7, 1.9}, {1.0, 1.9, 3.0}};
  for (const Pose2D& p : start) ASSERT_TRUE(g.add_node(p).ok());
  ASSERT_TRUE(g.add_edge({0, 1, {1.0, 0.05, 0.25}, 100, 400}).ok());
  ASSERT_TRUE(g.add_edge({1, 2, {1.02, 0.1, 0.6}, 100, 400}).ok());
  ASSERT_TRUE(g.add_edge({2, 3, {0.9, -0.08, 1.1}, 100, 400}).ok());
  ASSERT_TRUE(g.add_edge({3, 4, {1.05, 0.02, 1.0}, 100, 400}).ok());
  ASSERT_TRUE(g.add_edge({4, 0, {1.7, 1.1, 2.9}, 25, 100, 1.5}).ok());
  ASSERT_TRUE(g.add_edge({1, 3, {1.6, 1.4, 1.6}, 25, 100}).ok());
  const SolveSummary s = solved(g, {.max_iterations = 50, .relative_cost_tolerance = 1e-14});
  EXPECT_TRUE(s.converged);
  EXPECT_GT(s.final_cost, 1.0);  // conflicting: no exact fit
  const double h = 1e-6;
  for (std::uint32_t n = 1; n < 5; ++n) {
    for (int c = 0; c < 3; ++c) {
      const Pose2D at = g.pose(n);
      Pose2D plus = at;
      Pose2D minus = at;
      (c == 0 ? plus.x_m : c == 1 ? plus.y_m : plus.theta_rad) += h;
      (c == 0 ? minus.x_m : c == 1 ? minus.y_m : minus.theta_rad) -= h;
      ASSERT_TRUE(g.set_pose(n, plus).ok());
      const double up = g.cost();
      ASSERT_TRUE(g.set_pose(n, minus).ok());
      const double down = g.cost();
      ASSERT_TRUE(g.set_pose(n, at).ok());
      EXPECT_NEAR((up - down) / (2 * h), 0.0, 1e-5) << "node " << n << " coordinate " << c;
    }
  }
}

TEST(PoseGraph, FixedNodesKeepTheirPoses) {
  PoseGraph g(3, 3);
  ASSERT_TRUE(g.add_node({0, 0, 0}).ok());
  ASSERT_TRUE(g.add_node({1.5, 0.2, 0.1}).ok());
  ASSERT_TRUE(g.add_node({2.5, 0.0, 0.0}).ok());
  EXPECT_TRUE(g.fixed(0));
  EXPECT_FALSE(g.fixed(1));
  ASSERT_TRUE(g.set_fixed(2).ok());
  ASSERT_TRUE(g.add_edge({0, 1, {1, 0, 0}}).ok());
  ASSERT_TRUE(g.add_edge({1, 2, {1, 0, 0}}).ok());
  const SolveSummary s = solved(g, {.max_iterations = 50, .relative_cost_tolerance = 1e-14});
  EXPECT_TRUE(s.converged);
  EXPECT_EQ(g.pose(2), (Pose2D{2.5, 0.0, 0.0}));
  EXPECT_NEAR(g.pose(1).x_m, 1.25, 1e-9);
  // Free node 0 too: with node 2 fixed the graph still has its gauge.
  ASSERT_TRUE(g.set_fixed(0, false).ok());
  ASSERT_TRUE(g.set_pose(1, {0.3, 0.3, 0.3}).ok());
  const SolveSummary again = solved(g, {.max_iterations = 50, .relative_cost_tolerance = 1e-14});
  EXPECT_TRUE(again.converged);
  EXPECT_LT(again.final_cost, 1e-18);
  EXPECT_NEAR(g.pose(0).x_m, 0.5, 1e-9);
  EXPECT_NEAR(g.pose(1).x_m, 1.5, 1e-9);
}

TEST(PoseGraph, LongDriftingChainIsPulledBackByLoopClosures) {
  const LongRun& run = long_run();
  PoseGraph g = run.graph(false, false);
  const double before = pg_position_rms(g, run.truth);
  const SolveSummary s = solved(g);
  const double after = pg_position_rms(g, run.truth);
  std::printf("2000 nodes, 20 closures: RMS %.3f m -> %.4f m, cost %.4g -> %.4g, %d iterations, %.1f ms\n",
              before, after, s.initial_cost, s.final_cost, s.iterations, s.seconds * 1e3);
  EXPECT_TRUE(s.converged);
  EXPECT_GT(before, 3.0);
  // What the data allow: the random walk of the odometry between closures stays (other seeds
  // give 1.5 to 7 cm).
  EXPECT_LT(after, 0.08);
}

TEST(PoseGraph, HuberIgnoresWrongLoopClosuresThatBendASquaredLossMap) {
  const LongRun& run = long_run();
  PoseGraph clean = run.graph(false, false);
  (void)solved(clean);
  const std::vector<Pose2D> reference = pg_poses(clean);

  // Cold: every closure at once from dead reckoning. Warm: the wrong closures arrive after the
  // map was solved with the right ones, and the graph is solved again from there.
  for (const bool warm : {false, true}) {
    PoseGraph robust = run.graph(!warm, true);
    PoseGraph squared = run.graph(!warm, false);
    if (warm) {
      (void)solved(robust);
      (void)solved(squared);
      for (PoseEdge e : run.wrong) {
        ASSERT_TRUE(squared.add_edge(e).ok());
        e.huber_scale = run.kHuber;
        ASSERT_TRUE(robust.add_edge(e).ok());
      }
    }
    const SolveSummary rs = solved(robust, {.max_iterations = 100});
    const SolveSummary ss = solved(squared, {.max_iterations = 100});
    const double robust_off = pg_position_rms(robust, reference);
    const double squared_off = pg_position_rms(squared, reference);
    std::printf("%s, 5 wrong closures: RMS from the clean solution %.4f m (Huber, %d iterations), %.3f m "
                "(squared, %d iterations); from the truth %.4f m, %.3f m\n",
                warm ? "warm" : "cold", robust_off, rs.iterations, squared_off, ss.iterations,
                pg_position_rms(robust, run.truth), pg_position_rms(squared, run.truth));
    EXPECT_TRUE(rs.converged);
    EXPECT_TRUE(ss.converged);
    // Huber bounds a wrong closure's pull (to its scale times sqrt(weight)), it does not cancel it:
    // the map gives a little, in proportion to the scale.
    EXPECT_LT(robust_off, 0.05);
    EXPECT_LT(pg_position_rms(robust, run.truth), 0.1);
    EXPECT_GT(squared_off, 1.0);
    // The report of rejected closures: the wrong ones (the last five edges) stand out.
    const std::size_t first_wrong = robust.edge_count() - run.wrong.size();
    double largest_right = 0.0;
    double smallest_wrong = 1e300;
    for (std::size_t e = 0; e < robust.edge_count(); ++e) {
      const EdgeResidual r = robust.edge_residual(e);
      if (e < first_wrong) largest_right = std::max(largest_right, r.whitened_norm);
      if (e >= first_wrong) {
        smallest_wrong = std::min(smallest_wrong, r.whitened_norm);
        EXPECT_TRUE(r.down_weighted) << e;
      }
    }
    std::printf("  whitened residuals: right edges up to %.2f, wrong closures from %.1f\n", largest_right,
                smallest_wrong);
    EXPECT_GT(smallest_wrong, 20.0 * largest_right);
  }
}

TEST(PoseGraph, ResolveAfterNewClosuresMatchesOneSolveOfAll) {
  // The solver's cached ordering must be dropped when closures arrive.
  const LongRun& run = long_run();
  PoseGraph all = run.graph(false, false);
  (void)solved(all, {.max_iterations = 50, .relative_cost_tolerance = 1e-12});

  PoseGraph staged(LongRun::kNodes, LongRun::kNodes + 40);
  for (const Pose2D& p : run.dead_reckoning) ASSERT_TRUE(staged.add_node(p).ok());
  for (const PoseEdge& e : run.odometry) ASSERT_TRUE(staged.add_edge(e).ok());
  for (std::size_t i = 0; i < 10; ++i) ASSERT_TRUE(staged.add_edge(run.closures[i]).ok());
  (void)solved(staged, {.max_iterations = 50});
  for (std::size_t i = 10; i < run.closures.size(); ++i) ASSERT_TRUE(staged.add_edge(run.closures[i]).ok());
  const SolveSummary s = solved(staged, {.max_iterations = 50, .relative_cost_tolerance = 1e-12});
  EXPECT_TRUE(s.converged);
  EXPECT_LT(pg_position_rms(staged, pg_poses(all)), 1e-6);
}

TEST(PoseGraph, CapacityAndInvalidInputAreErrors) {
  PoseGraph g(2, 1);
  ASSERT_TRUE(g.add_node({0, 0, 0}).ok());
  const Result<std::uint32_t> bad = g.add_node({std::nan(""), 0, 0});
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code(), Errc::invalid_argument);
  ASSERT_TRUE(g.add_node({1, 0, 0}).ok());
  const Result<std::uint32_t> full = g.add_node({2, 0, 0});
  ASSERT_FALSE(full.ok());
  EXPECT_EQ(full.error().code(), Errc::capacity);
  EXPECT_EQ(g.node_count(), 2u);

  const double inf = std::numeric_limits<double>::infinity();
  const PoseEdge invalid[] = {
      {0, 2, {1, 0, 0}},                     // no node 2
      {1, 1, {0, 0, 0}},                     // a node to itself
      {0, 1, {std::nan(""), 0, 0}},          // measurement not finite
      {0, 1, {1, 0, inf}},                   //
      {0, 1, {1, 0, 0}, 0.0, 1.0},           // weights must be positive
      {0, 1, {1, 0, 0}, 1.0, -2.0},          //
      {0, 1, {1, 0, 0}, inf, 1.0},           // and finite
      {0, 1, {1, 0, 0}, 1.0, std::nan("")},  //
      {0, 1, {1, 0, 0}, 1.0, 1.0, -1.0},     // Huber scale not negative
      {0, 1, {1, 0, 0}, 1.0, 1.0, inf},      //
  };
  for (const PoseEdge& e : invalid) {
    const Status st = g.add_edge(e);
    ASSERT_FALSE(st.ok());
    EXPECT_EQ(st.error().code(), Errc::invalid_argument) << st.error().c_str();
  }
  EXPECT_EQ(g.edge_count(), 0u);
  ASSERT_TRUE(g.add_edge({0, 1, {1, 0, 0}}).ok());
  const Status st = g.add_edge({1, 0, {-1, 0, 0}});
  ASSERT_FALSE(st.ok());
  EXPECT_EQ(st.error().code(), Errc::capacity);
  EXPECT_EQ(g.edge_count(), 1u);

  EXPECT_EQ(g.set_fixed(2).error().code(), Errc::invalid_argument);
  EXPECT_EQ(g.set_pose(2, {0, 0, 0}).error().code(), Errc::invalid_argument);
  EXPECT_EQ(g.set_pose(1, {0, inf, 0}).error().code(), Errc::invalid_argument);
  Result<SolveSummary> r = g.optimize({.max_iterations = -1});
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code(), Errc::invalid_argument);
  r = g.optimize({.relative_cost_tolerance = std::nan("")});
  ASSERT_FALSE(r.ok());
  EXPECT_EQ(r.error().code(), Errc::invalid_argument);

  // An empty graph and one with every node fixed solve to nothing.
  PoseGraph empty(0, 0);
  EXPECT_TRUE(solved(empty).converged);
  ASSERT_TRUE(g.set_fixed(1).ok());
  const SolveSummary none = solved(g);
  EXPECT_TRUE(none.converged);
  EXPECT_EQ(none.iterations, 0);
  EXPECT_EQ(g.pose(1), (Pose2D{1, 0, 0}));
}

TEST(PoseGraph, SolvesAreBitIdentical) {
  const LongRun& run = long_run();
  PoseGraph a = run.graph(true, true);
  PoseGraph b = run.graph(true, true);
  const SolveSummary sa = solved(a);
  const SolveSummary sb = solved(b);
  EXPECT_EQ(sa.iterations, sb.iterations);
  EXPECT_EQ(std::memcmp(&sa.final_cost, &sb.final_cost, sizeof(double)), 0);
  const std::vector<Pose2D> first = pg_poses(a);
  const std::vector<Pose2D> second = pg_poses(b);
  EXPECT_EQ(std::memcmp(first.data(), second.data(), first.size() * sizeof(Pose2D)), 0);
  // The same graph again from the same start, now through its kept ordering.
  for (std::uint32_t i = 0; i < run.dead_reckoning.size(); ++i) {
    ASSERT_TRUE(a.set_pose(i, run.dead_reckoning[i]).ok());
  }
  (void)solved(a);
  const std::vector<Pose2D> third = pg_poses(a);
  EXPECT_EQ(std::memcmp(first.data(), third.data(), first.size() * sizeof(Pose2D)), 0);
}

TEST(PoseGraph, SolveTimeOfTheLongChain) {
  // Printed, not asserted: the cold solve (ordering and analysis), a warm solve of the same graph
  // that has nothing left to do, and a warm start after five new closures (a new analysis).
  const LongRun& run = long_run();
  PoseGraph g(LongRun::kNodes, LongRun::kNodes + 40);
  for (const Pose2D& p : run.dead_reckoning) ASSERT_TRUE(g.add_node(p).ok());
  for (const PoseEdge& e : run.odometry) ASSERT_TRUE(g.add_edge(e).ok());
  for (std::size_t i = 0; i < 15; ++i) ASSERT_TRUE(g.add_edge(run.closures[i]).ok());
  const auto report = [&](const char* what) {
    mem::testing::AllocationScope scope;
    const SolveSummary s = solved(g);
    std::printf("%-28s %6.2f ms, %2d iterations (%.2f ms each); operator new %3llu, malloc %3llu\n", what,
                s.seconds * 1e3, s.iterations, s.iterations > 0 ? s.seconds * 1e3 / s.iterations : 0.0,
                static_cast<unsigned long long>(scope.allocations()),
                static_cast<unsigned long long>(scope.malloc_calls()));
  };
  report("cold, from dead reckoning:");
  report("warm, nothing changed:");
  for (std::size_t i = 15; i < run.closures.size(); ++i) ASSERT_TRUE(g.add_edge(run.closures[i]).ok());
  report("warm, after 5 new closures:");
  for (std::uint32_t i = 1; i < 40; ++i) ASSERT_TRUE(g.set_pose(i * 50, run.dead_reckoning[i * 50]).ok());
  report("warm, 39 poses disturbed:");
}

}  // namespace
}  // namespace sen3bot::slam
