#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <numbers>
#include <random>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/crowd/orca.hpp"

namespace sen3bot::crowd {
namespace {

constexpr double kTau = 5.0;

// Uniform in [0, 1) from the generator's top 53 bits: the same numbers on every standard library.
double uniform(std::mt19937_64& rng) { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }
double uniform(std::mt19937_64& rng, double lo, double hi) { return lo + (hi - lo) * uniform(rng); }

// The paper's ORCA without CrowdNav's 1 cm radius margin, for the hand-worked numbers.
OrcaParams pure() {
  OrcaParams p;
  p.radius_padding_m = 0.0;
  return p;
}

double worst_violation(std::span<const OrcaHalfPlane> planes, Point2D v) {
  double worst = -1e300;
  for (const OrcaHalfPlane& h : planes) worst = std::max(worst, -dot(v - h.point, h.normal));
  return worst;
}

// Worked case. A at (-2, 0) moving (1, 0), B at (2, 0) moving (-1, 0), radii 0.3, tau 5 s.
//   p = p_B - p_A = (4, 0), r = 0.6, v = v_A - v_B = (2, 0).
//   Cut-off disc D(p/tau, r/tau): centre (0.8, 0), radius 0.12; w = v - p/tau = (1.2, 0) and
//   w . p = 4.8 > 0, so a leg is nearest. v lies on the axis (cross(p, w) = 0): the right leg.
//   sin a = r/|p| = 0.15, cos a = sqrt(1 - 0.0225) = sqrt(0.9775) = 0.98868599...
//   Right leg d = (cos a, -sin a); v projects to (2 cos a) d, so
//     u = (2 cos a) d - v = (2 cos^2 a - 2, -2 sin a cos a) = (-0.045, -0.3 cos a),
//   |u| = 2 sin a = 0.3, and the outward normal (d turned clockwise) n = (-sin a, -cos a) = (-0.15, -cos a).
//   ORCA_A = {v : (v - (v_A + u/2)) . n >= 0}: v_A = (1, 0) = preferred breaks it by |u|/2 = 0.15,
//   and u is along n, so the nearest allowed velocity is v_A + u/2 = (0.9775, -0.15 cos a)
//   = (0.9775, -0.14830290) with speed cos a < 1 (the speed limit does not bind). B mirrors it
//   through the origin. With B not reacting (rho = 1) it is v_A + u = (0.955, -0.3 cos a), speed 1.
TEST(Orca, WorkedHeadOnPair) {
  const double cos_a = std::sqrt(0.9775);
  OrcaAgent a{{-2.0, 0.0}, {1.0, 0.0}, {1.0, 0.0}};
  const OrcaNeighbor b{{2.0, 0.0}, {-1.0, 0.0}, 0.3, 0.5};
  const OrcaHalfPlane h = orca_half_plane(a, b, kTau, 0.25);
  EXPECT_NEAR(h.u.x_m, -0.045, 1e-12);
  EXPECT_NEAR(h.u.y_m, -0.3 * cos_a, 1e-12);
  EXPECT_NEAR(h.normal.x_m, -0.15, 1e-12);
  EXPECT_NEAR(h.normal.y_m, -cos_a, 1e-12);
  EXPECT_NEAR(h.point.x_m, 0.9775, 1e-12);
  EXPECT_NEAR(h.point.y_m, -0.15 * cos_a, 1e-12);

  const Point2D v = new_velocity(a, std::span(&b, 1), pure(), 0.25);
  EXPECT_NEAR(v.x_m, 0.9775, 1e-6);
  EXPECT_NEAR(v.y_m, -0.14830290, 1e-6);

  std::array<OrcaAgent, 2> pair{a, OrcaAgent{{2.0, 0.0}, {-1.0, 0.0}, {-1.0, 0.0}}};
  ASSERT_TRUE(orca_step(pair, {}, pure(), 0.25));
  EXPECT_NEAR(pair[0].velocity.x_m, 0.9775, 1e-6);
  EXPECT_NEAR(pair[0].velocity.y_m, -0.14830290, 1e-6);
  EXPECT_NEAR(pair[1].velocity.x_m, -0.9775, 1e-6);
  EXPECT_NEAR(pair[1].velocity.y_m, 0.14830290, 1e-6);
  EXPECT_NEAR(pair[0].position.x_m, -2.0 + 0.25 * 0.9775, 1e-6);
  EXPECT_NEAR(pair[0].position.y_m, -0.25 * 0.14830290, 1e-6);

  const std::array<OrcaDisc, 1> robot{OrcaDisc{{2.0, 0.0}, {-1.0, 0.0}, 0.3}};
  std::array<OrcaAgent, 1> alone{a};
  ASSERT_TRUE(orca_step(alone, robot, pure(), 0.25));
  EXPECT_NEAR(alone[0].velocity.x_m, 0.955, 1e-6);
  EXPECT_NEAR(alone[0].velocity.y_m, -0.3 * cos_a, 1e-6);
  EXPECT_LE(norm(alone[0].velocity), 1.0 + 1e-12);

  // The default margin is the same as bodies 1 cm larger.
  OrcaAgent wide = a;
  wide.radius_m = 0.31;
  const OrcaNeighbor wide_b{{2.0, 0.0}, {-1.0, 0.0}, 0.31, 0.5};
  const Point2D padded = new_velocity(a, std::span(&b, 1), {}, 0.25);
  const Point2D widened = new_velocity(wide, std::span(&wide_b, 1), pure(), 0.25);
  EXPECT_NEAR(padded.x_m, widened.x_m, 1e-12);
  EXPECT_NEAR(padded.y_m, widened.y_m, 1e-12);
  EXPECT_LT(padded.y_m, v.y_m - 1e-3);
}

TEST(Orca, WithoutNeighboursThePreferredVelocityClampedToTheSpeedLimit) {
  OrcaAgent a{{0.0, 0.0}, {0.0, 0.0}, {0.6, -0.3}};
  Point2D v = new_velocity(a, {}, pure(), 0.25);
  EXPECT_DOUBLE_EQ(v.x_m, 0.6);
  EXPECT_DOUBLE_EQ(v.y_m, -0.3);
  a.preferred_velocity = {3.0, 4.0};
  v = new_velocity(a, {}, pure(), 0.25);
  EXPECT_NEAR(v.x_m, 0.6, 1e-12);
  EXPECT_NEAR(v.y_m, 0.8, 1e-12);
  // A person on a collision course beyond neighbor_distance is not a neighbour.
  a.preferred_velocity = {1.0, 0.0};
  a.velocity = {1.0, 0.0};
  // Closing at 2 m/s from 10.5 m it would touch within 5 s (9.9 m needs 1.98 m/s); on the axis
  // the cut-off arc is nearest, u = (-0.02, 0), so once it counts the agent slows by 0.01 m/s.
  const OrcaNeighbor far{{10.5, 0.0}, {-1.0, 0.0}, 0.3, 0.5};
  v = new_velocity(a, std::span(&far, 1), pure(), 0.25);
  EXPECT_DOUBLE_EQ(v.x_m, 1.0);
  EXPECT_DOUBLE_EQ(v.y_m, 0.0);
  OrcaParams wider = pure();
  wider.neighbor_distance_m = 11.0;
  v = new_velocity(a, std::span(&far, 1), wider, 0.25);
  EXPECT_NEAR(v.x_m, 0.99, 1e-12);
  EXPECT_NEAR(v.y_m, 0.0, 1e-12);
}

// Off the axis (no tie) and with the speed limit out of the way, the chosen velocity moves by
// exactly rho u: a disc that does not react leaves the agent twice the change of a reciprocating one.
TEST(Orca, NonReciprocatingDiscTakesTheWholeAvoidance) {
  OrcaAgent a{{0.0, 0.0}, {1.0, 0.0}, {1.0, 0.0}, 0.3, 2.0};
  OrcaNeighbor b{{2.0, 0.3}, {-0.8, 0.1}, 0.3, 0.5};
  const OrcaHalfPlane h = orca_half_plane(a, b, kTau, 0.25);
  ASSERT_GT(norm(h.u), 0.05);  // the constraint binds
  EXPECT_NEAR(h.point.x_m - a.velocity.x_m, 0.5 * h.u.x_m, 1e-12);
  EXPECT_NEAR(h.point.y_m - a.velocity.y_m, 0.5 * h.u.y_m, 1e-12);
  const Point2D half = new_velocity(a, std::span(&b, 1), pure(), 0.25) - a.preferred_velocity;
  b.responsibility = 1.0;
  const OrcaHalfPlane full_plane = orca_half_plane(a, b, kTau, 0.25);
  EXPECT_NEAR(full_plane.point.x_m - a.velocity.x_m, h.u.x_m, 1e-12);
  EXPECT_NEAR(full_plane.point.y_m - a.velocity.y_m, h.u.y_m, 1e-12);
  const Point2D full = new_velocity(a, std::span(&b, 1), pure(), 0.25) - a.preferred_velocity;
  EXPECT_NEAR(half.x_m, 0.5 * h.u.x_m, 1e-9);
  EXPECT_NEAR(half.y_m, 0.5 * h.u.y_m, 1e-9);
  EXPECT_NEAR(full.x_m, 2.0 * half.x_m, 1e-9);
  EXPECT_NEAR(full.y_m, 2.0 * half.y_m, 1e-9);
  // The same through orca_step: the disc as `others`.
  std::array<OrcaAgent, 1> alone{a};
  const std::array<OrcaDisc, 1> disc{OrcaDisc{b.position, b.velocity, 0.3}};
  ASSERT_TRUE(orca_step(alone, disc, pure(), 0.25));
  EXPECT_NEAR(alone[0].velocity.x_m - 1.0, full.x_m, 1e-12);
  EXPECT_NEAR(alone[0].velocity.y_m, full.y_m, 1e-12);
}

// The cut-off arc: A still, B 4 m ahead closing at 0.7 m/s. w = (0.7, 0) - (0.8, 0) = (-0.1, 0)
// points back at the origin and (w . p)^2 = 0.16 > r^2 |w|^2 = 0.0036: the arc is nearest.
// Contact needs 3.4 m closed within 5 s, 0.68 m/s: u = (-0.02, 0), n = (-1, 0).
// Overlap: A and B still, 0.4 m apart (r = 0.6), dt 0.25: w = -p/dt = (-1.6, 0), r/dt = 2.4, so
// u = (-0.8, 0): each backs off at 0.4 m/s and they just touch after one step.
TEST(Orca, CutOffArcAndOverlapCases) {
  const OrcaAgent a{{0.0, 0.0}, {0.0, 0.0}, {0.0, 0.0}};
  const OrcaHalfPlane arc = orca_half_plane(a, {{4.0, 0.0}, {-0.7, 0.0}, 0.3, 0.5}, kTau, 0.25);
  EXPECT_NEAR(arc.u.x_m, -0.02, 1e-12);
  EXPECT_NEAR(arc.u.y_m, 0.0, 1e-12);
  EXPECT_NEAR(arc.normal.x_m, -1.0, 1e-12);
  EXPECT_NEAR(arc.point.x_m, -0.01, 1e-12);

  const OrcaHalfPlane overlap = orca_half_plane(a, {{0.4, 0.0}, {0.0, 0.0}, 0.3, 0.5}, kTau, 0.25);
  EXPECT_NEAR(overlap.u.x_m, -0.8, 1e-12);
  EXPECT_NEAR(overlap.u.y_m, 0.0, 1e-12);
  std::array<OrcaAgent, 2> pair{a, OrcaAgent{{0.4, 0.0}, {0.0, 0.0}, {0.0, 0.0}}};
  ASSERT_TRUE(orca_step(pair, {}, pure(), 0.25));
  EXPECT_NEAR(pair[0].velocity.x_m, -0.4, 1e-12);
  EXPECT_NEAR(pair[1].velocity.x_m, 0.4, 1e-12);
  EXPECT_NEAR(norm(pair[1].position - pair[0].position), 0.6, 1e-12);
}

// Opposite half-planes v.x >= 0.5 and v.x <= -0.5 cannot both hold: the least worst violation is
// 0.5 at v.x = 0, and along that line every velocity is as good, so the one nearest the preferred.
TEST(Orca, InfeasibleHalfPlanesBreakTheWorstLeast) {
  const std::array<OrcaHalfPlane, 2> planes{OrcaHalfPlane{{0.5, 0.0}, {1.0, 0.0}, {}},
                                            OrcaHalfPlane{{-0.5, 0.0}, {-1.0, 0.0}, {}}};
  const Point2D v = solve_velocity(planes, {0.3, 0.2}, 1.0);
  EXPECT_NEAR(v.x_m, 0.0, 1e-12);
  EXPECT_NEAR(v.y_m, 0.2, 1e-12);
  EXPECT_NEAR(worst_violation(planes, v), 0.5, 1e-12);
}

// Random single-agent problems (neighbours near and overlapping, both kinds of responsibility)
// against a 0.01 m/s grid over the speed disc: when the half-planes leave room the answer lies in
// all of them, within the speed limit and no grid velocity there is nearer the preferred one;
// otherwise no grid velocity breaks the worst half-plane less.
TEST(Orca, SolverMatchesBruteForce) {
  std::mt19937_64 rng(7);
  constexpr double kStep = 0.01;
  int feasible_bound = 0;  // feasible with the preferred velocity outside some half-plane
  int infeasible = 0;
  for (int scene = 0; scene < 150; ++scene) {
    OrcaAgent a{{0.0, 0.0},
                {uniform(rng, -1.0, 1.0), uniform(rng, -1.0, 1.0)},
                {uniform(rng, -1.3, 1.3), uniform(rng, -1.3, 1.3)}};
    a.velocity = std::min(1.0, norm(a.velocity)) * unit_or(a.velocity, {});
    const std::size_t count = 1 + rng() % 6;
    std::array<OrcaHalfPlane, 6> store{};
    for (std::size_t k = 0; k < count; ++k) {
      const OrcaNeighbor b{{uniform(rng, -2.5, 2.5), uniform(rng, -2.5, 2.5)},
                           {uniform(rng, -1.0, 1.0), uniform(rng, -1.0, 1.0)},
                           0.3,
                           rng() % 2 == 0 ? 0.5 : 1.0};
      store[k] = orca_half_plane(a, b, kTau, 0.25);
    }
    const std::span<const OrcaHalfPlane> planes(store.data(), count);
    const Point2D v = solve_velocity(planes, a.preferred_velocity, 1.0);
    ASSERT_LE(norm(v), 1.0 + 1e-9) << "scene " << scene;
    double grid_best = 1e300;       // nearest feasible grid velocity to the preferred one
    double grid_min_worst = 1e300;  // least worst violation on the grid
    for (int i = -100; i <= 100; ++i) {
      for (int j = -100; j <= 100; ++j) {
        const Point2D g{i * kStep, j * kStep};
        if (norm_squared(g) > 1.0) continue;
        const double w = worst_violation(planes, g);
        grid_min_worst = std::min(grid_min_worst, w);
        if (w <= 0.0) grid_best = std::min(grid_best, norm(g - a.preferred_velocity));
      }
    }
    const double worst = worst_violation(planes, v);
    if (worst <= 1e-9) {
      if (worst_violation(planes, a.preferred_velocity) > 0.0) ++feasible_bound;
      EXPECT_LE(norm(v - a.preferred_velocity), grid_best + 1e-9) << "scene " << scene;
    } else {
      ++infeasible;
      EXPECT_GT(grid_min_worst, 0.0) << "scene " << scene;
      EXPECT_LE(worst, grid_min_worst + 1e-9) << "scene " << scene;
      EXPECT_GE(worst, grid_min_worst - kStep * std::numbers::sqrt2) << "scene " << scene;
    }
  }
  EXPECT_GE(feasible_bound, 30);
  EXPECT_GE(infeasible, 10);
}

std::array<OrcaAgent, 5> random_scene(std::mt19937_64& rng) {
  std::array<OrcaAgent, 5> s{};
  for (OrcaAgent& a : s) {
    a.position = {uniform(rng, -2.0, 2.0), uniform(rng, -2.0, 2.0)};
    a.velocity = {uniform(rng, -0.7, 0.7), uniform(rng, -0.7, 0.7)};
    a.preferred_velocity = {uniform(rng, -1.2, 1.2), uniform(rng, -1.2, 1.2)};
  }
  return s;
}

// Mirroring the scene in the x axis, or turning it a quarter (both exact in floating point),
// mirrors or turns every new velocity.
TEST(Orca, MirroredAndRotatedScenesGiveMirroredAndRotatedVelocities) {
  std::mt19937_64 rng(11);
  const auto mirror = [](Point2D p) { return Point2D{p.x_m, -p.y_m}; };
  const auto turn = [](Point2D p) { return Point2D{-p.y_m, p.x_m}; };
  const std::array<OrcaDisc, 1> robot{OrcaDisc{{0.3, -0.2}, {0.4, 0.1}, 0.35}};
  for (int scene = 0; scene < 200; ++scene) {
    std::array<OrcaAgent, 5> base = random_scene(rng);
    std::array<OrcaAgent, 5> mirrored = base;
    std::array<OrcaAgent, 5> turned = base;
    for (std::size_t i = 0; i < base.size(); ++i) {
      mirrored[i].position = mirror(base[i].position);
      mirrored[i].velocity = mirror(base[i].velocity);
      mirrored[i].preferred_velocity = mirror(base[i].preferred_velocity);
      turned[i].position = turn(base[i].position);
      turned[i].velocity = turn(base[i].velocity);
      turned[i].preferred_velocity = turn(base[i].preferred_velocity);
    }
    const std::array<OrcaDisc, 1> robot_m{OrcaDisc{mirror(robot[0].position), mirror(robot[0].velocity), 0.35}};
    const std::array<OrcaDisc, 1> robot_t{OrcaDisc{turn(robot[0].position), turn(robot[0].velocity), 0.35}};
    ASSERT_TRUE(orca_step(base, robot, {}, 0.25));
    ASSERT_TRUE(orca_step(mirrored, robot_m, {}, 0.25));
    ASSERT_TRUE(orca_step(turned, robot_t, {}, 0.25));
    for (std::size_t i = 0; i < base.size(); ++i) {
      EXPECT_LE(norm(base[i].velocity), 1.0 + 1e-12);
      EXPECT_NEAR(norm(mirror(base[i].velocity) - mirrored[i].velocity), 0.0, 1e-9) << scene << " " << i;
      EXPECT_NEAR(norm(turn(base[i].velocity) - turned[i].velocity), 0.0, 1e-9) << scene << " " << i;
    }
  }
}

// CrowdNav's circle crossing with the robot invisible (humans only): each human starts on a
// circle of radius 4 m at a uniformly random angle, each coordinate shifted by U(-0.5, 0.5) m,
// and walks to the point opposite its start through the centre. A start within
// 2 r + 0.2 m (discomfort distance) of another human's start or goal is drawn again. Humans
// want the goal direction at 1 m/s, or the whole remaining offset per second within 1 m
// (CrowdNav's ORCA policy), stand once there, and have arrived within r of the goal.
// Contact: centres closer than 2 r at any instant (straight-line motion within a step).
struct CrossingRun {
  bool contact = false;
  bool timeout = false;
  double arrival_sum_s = 0.0;  // over humans that arrived
  int arrived = 0;
  double all_arrived_s = 0.0;
  double max_speed_m_s = 0.0;
  std::array<Point2D, 5> final_positions{};
};

CrossingRun orca_circle_crossing(std::uint64_t seed, double dt) {
  constexpr std::size_t kHumans = 5;
  constexpr double kRadius = 0.3;
  std::mt19937_64 rng(seed);
  std::array<OrcaAgent, kHumans> humans{};
  std::array<Point2D, kHumans> goals{};
  for (std::size_t i = 0; i < kHumans; ++i) {
    for (;;) {
      const double angle = 2.0 * std::numbers::pi * uniform(rng);
      const Point2D p{4.0 * std::cos(angle) + uniform(rng, -0.5, 0.5), 4.0 * std::sin(angle) + uniform(rng, -0.5, 0.5)};
      bool clear = true;
      for (std::size_t j = 0; j < i; ++j) {
        const double gap = 2.0 * kRadius + 0.2;
        clear = clear && norm(p - humans[j].position) >= gap && norm(p - goals[j]) >= gap;
      }
      if (!clear) continue;
      humans[i] = OrcaAgent{p, {}, {}, kRadius, 1.0};
      goals[i] = -p;
      break;
    }
  }
  CrossingRun run;
  std::array<double, kHumans> arrival{};
  arrival.fill(-1.0);
  const auto steps = static_cast<int>(std::lround(25.0 / dt));
  for (int step = 1; step <= steps; ++step) {
    std::array<Point2D, kHumans> before{};
    for (std::size_t i = 0; i < kHumans; ++i) {
      const Point2D to_goal = goals[i] - humans[i].position;
      const double d = norm(to_goal);
      humans[i].preferred_velocity = d > 1.0 ? (1.0 / d) * to_goal : to_goal;
      before[i] = humans[i].position;
    }
    orca_step(humans, {}, {}, dt);
    const double t = step * dt;
    for (std::size_t i = 0; i < kHumans; ++i) {
      run.max_speed_m_s = std::max(run.max_speed_m_s, norm(humans[i].velocity));
      for (std::size_t j = i + 1; j < kHumans; ++j) {
        // Closest approach of straight-line relative motion from a to b within the step.
        const Point2D a = before[j] - before[i];
        const Point2D e = (humans[j].position - humans[i].position) - a;
        const double s = norm_squared(e) > 0.0 ? std::clamp(-dot(a, e) / norm_squared(e), 0.0, 1.0) : 0.0;
        if (norm(a + s * e) < 2.0 * kRadius) run.contact = true;
      }
      if (arrival[i] < 0.0 && norm(goals[i] - humans[i].position) < kRadius) {
        arrival[i] = t;
        run.arrival_sum_s += t;
        ++run.arrived;
      }
    }
    if (run.arrived == static_cast<int>(kHumans)) {
      run.all_arrived_s = t;
      break;
    }
  }
  run.timeout = run.arrived < static_cast<int>(kHumans);
  for (std::size_t i = 0; i < kHumans; ++i) run.final_positions[i] = humans[i].position;
  return run;
}

struct CrossingStats {
  int runs = 0;
  int contact_runs = 0;
  int timeout_runs = 0;
  double mean_arrival_s = 0.0;      // per human that arrived
  double mean_all_arrived_s = 0.0;  // per run in which all arrived
  double max_speed_m_s = 0.0;
};

CrossingStats crossing_stats(int runs, double dt) {
  CrossingStats s;
  s.runs = runs;
  double arrival_sum = 0.0;
  int arrived = 0;
  double all_sum = 0.0;
  for (int r = 0; r < runs; ++r) {
    const CrossingRun run = orca_circle_crossing(static_cast<std::uint64_t>(r), dt);
    s.contact_runs += run.contact ? 1 : 0;
    s.timeout_runs += run.timeout ? 1 : 0;
    arrival_sum += run.arrival_sum_s;
    arrived += run.arrived;
    if (!run.timeout) all_sum += run.all_arrived_s;
    s.max_speed_m_s = std::max(s.max_speed_m_s, run.max_speed_m_s);
  }
  s.mean_arrival_s = arrival_sum / std::max(arrived, 1);
  s.mean_all_arrived_s = all_sum / std::max(runs - s.timeout_runs, 1);
  std::printf("circle crossing dt %.2f s: %d runs, %d with contact, %d timed out, "
              "mean arrival %.2f s, all arrived %.2f s\n",
              dt, runs, s.contact_runs, s.timeout_runs, s.mean_arrival_s, s.mean_all_arrived_s);
  return s;
}

TEST(Orca, CrowdNavCircleCrossingHumansOnly) {
  for (const double dt : {0.25, 0.1}) {
    const CrossingStats s = crossing_stats(500, dt);
    EXPECT_LE(s.contact_runs, 5) << "dt " << dt;  // at least 99 % of runs without contact
    EXPECT_LE(s.timeout_runs, 5) << "dt " << dt;
    EXPECT_LE(s.max_speed_m_s, 1.0 + 1e-9);
    // The straight walk is 8 m at 1 m/s less the last metre's slowing and the arrival radius.
    EXPECT_GT(s.mean_arrival_s, 7.0) << "dt " << dt;
    EXPECT_LT(s.mean_arrival_s, 12.0) << "dt " << dt;
  }
}

TEST(Orca, DeterministicForASeed) {
  const CrossingRun a = orca_circle_crossing(42, 0.25);
  const CrossingRun b = orca_circle_crossing(42, 0.25);
  for (std::size_t i = 0; i < a.final_positions.size(); ++i) {
    EXPECT_EQ(a.final_positions[i].x_m, b.final_positions[i].x_m);
    EXPECT_EQ(a.final_positions[i].y_m, b.final_positions[i].y_m);
  }
  EXPECT_EQ(a.arrival_sum_s, b.arrival_sum_s);
}

TEST(Orca, StepAndSolverDoNotAllocate) {
  std::mt19937_64 rng(3);
  std::vector<OrcaAgent> crowd(kMaxOrcaAgents);
  for (OrcaAgent& a : crowd) {
    a.position = {uniform(rng, -5.0, 5.0), uniform(rng, -5.0, 5.0)};
    a.preferred_velocity = {uniform(rng, -1.0, 1.0), uniform(rng, -1.0, 1.0)};
  }
  const std::array<OrcaDisc, 1> robot{OrcaDisc{{0.0, 0.0}, {0.5, 0.0}, 0.35}};
  const std::array<OrcaNeighbor, 2> near{OrcaNeighbor{{0.5, 0.0}, {}, 0.3, 0.5},
                                         OrcaNeighbor{{-0.5, 0.0}, {}, 0.3, 1.0}};
  OrcaParams many;
  many.max_neighbors = 100;  // capped at kMaxOrcaNeighbors
  Point2D v;
  {
    const mem::testing::AllocationScope scope;
    for (int step = 0; step < 20; ++step) ASSERT_TRUE(orca_step(crowd, robot, many, 0.1));
    v = new_velocity(crowd[0], near, {}, 0.1);
    EXPECT_EQ(scope.allocations(), 0u);
    if (mem::testing::counts_malloc()) {
      EXPECT_EQ(scope.malloc_calls(), 0u);
    }
  }
  EXPECT_LE(norm(v), 1.0 + 1e-12);
  // Too many agents: refused, nothing changes.
  crowd.push_back(crowd[0]);
  const Point2D kept = crowd[1].position;
  EXPECT_FALSE(orca_step(crowd, robot, {}, 0.1));
  EXPECT_EQ(crowd[1].position.x_m, kept.x_m);
}

}  // namespace
}  // namespace sen3bot::crowd
