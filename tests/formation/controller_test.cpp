#include "sen3bot/formation/controller.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <random>
#include <vector>

#include "alloc_counter.hpp"
#include "kinematic.hpp"
#include "sen3bot/formation/examples.hpp"

namespace sen3bot::formation {
namespace {

using testing::KinematicResult;
using testing::run_kinematic;

constexpr double kPi = std::numbers::pi;

std::vector<Pose> starts_of(const Example& e) {
  return {e.starts.begin(), e.starts.begin() + static_cast<long>(e.config.robots)};
}

std::vector<Vec2> points_of(const std::vector<Pose>& poses, double l) {
  std::vector<Vec2> p;
  for (const Pose& q : poses) p.push_back(point_p(q, l));
  return p;
}

ControllerConfig open_room(TaskKind task, std::size_t robots) {
  ControllerConfig c;
  c.task = task;
  c.robots = robots;
  c.workspace = {-10.0, -10.0, 10.0, 10.0};
  return c;
}

TEST(FormationConfig, RefusesWhatCannotWorkWithTheFieldNamed) {
  Controller k;
  ControllerConfig c = open_room(TaskKind::targets, 0);
  EXPECT_NE(k.configure(c).error().message().find("robots"), std::string::npos);
  c.robots = 2;
  c.targets[0] = {0.0, 0.0};
  c.targets[1] = {0.5, 0.0};  // closer than two body circles
  EXPECT_NE(k.configure(c).error().message().find("targets[0] and [1]"), std::string::npos);
  c.targets[1] = {9.8, 0.0};  // in the wall's barrier
  EXPECT_NE(k.configure(c).error().message().find("targets[1]"), std::string::npos);
  c.targets[1] = {3.0, 0.0};
  EXPECT_TRUE(k.configure(c));
  c.offset_m = 0.0;
  EXPECT_NE(k.configure(c).error().message().find("offset_m"), std::string::npos);
  c.offset_m = 0.1;
  c.mu = 1.0;
  EXPECT_NE(k.configure(c).error().message().find("mu"), std::string::npos);
  c.mu = 0.5;
  c.gain_set_count = 1;
  c.gain_sets[0].swirl_rad = kPi / 2.0;  // would no longer push apart
  EXPECT_NE(k.configure(c).error().message().find("gain_sets[0]"), std::string::npos);

  ControllerConfig patrol = open_room(TaskKind::patrol, 3);
  patrol.curve = nav::SafeCurve::line({-1.0, 0.0}, {1.0, 0.0});
  EXPECT_NE(k.configure(patrol).error().message().find("closed"), std::string::npos);
  patrol.curve = nav::SafeCurve::circle({0.0, 0.0}, 9.8);  // through the walls
  patrol.curve_start = {9.8, 0.0};
  EXPECT_NE(k.configure(patrol).error().message().find("curve"), std::string::npos);
  patrol.curve = nav::SafeCurve::circle({0.0, 0.0}, 0.3);  // no room for three
  patrol.curve_start = {0.3, 0.0};
  EXPECT_NE(k.configure(patrol).error().message().find("too short"), std::string::npos);

  ControllerConfig leader = open_room(TaskKind::leader, 3);
  leader.curve = nav::SafeCurve::circle({0.0, 0.0}, 2.0);
  leader.curve_start = {2.0, 0.0};
  leader.offsets[1] = {-1.0, 0.5};
  leader.offsets[2] = {-1.0, 0.6};  // on top of the other follower
  EXPECT_NE(k.configure(leader).error().message().find("offsets[1] and [2]"), std::string::npos);
  leader.offsets[2] = {-1.0, -0.8};
  EXPECT_TRUE(k.configure(leader));
}

TEST(FormationCurve, TracedEvenlyByLengthOnTheCurve) {
  Controller k;
  ControllerConfig c = open_room(TaskKind::patrol, 3);
  c.curve = nav::SafeCurve::ellipse({0.5, -0.5}, 3.0, 1.5, 0.3);
  c.curve_start = {0.0, 3.0};
  ASSERT_TRUE(k.configure(c));
  // Ramanujan's approximation of the perimeter.
  const double a = 3.0, b = 1.5, h = (a - b) * (a - b) / ((a + b) * (a + b));
  const double perimeter = kPi * (a + b) * (1.0 + 3.0 * h / (10.0 + std::sqrt(4.0 - 3.0 * h)));
  EXPECT_NEAR(k.curve_length_m(), perimeter, 1e-3 * perimeter);
  const auto pts = k.curve_points();
  ASSERT_EQ(pts.size(), kCurveSamples);
  for (std::size_t i = 0; i < pts.size(); ++i) {
    const Vec2 q = pts[i], r = pts[(i + 1) % pts.size()];
    ASSERT_NEAR(c.curve.value(q.x_m, q.y_m), 0.0, 1e-6);
    ASSERT_NEAR(std::hypot(r.x_m - q.x_m, r.y_m - q.y_m), perimeter / kCurveSamples, 0.02 * perimeter / kCurveSamples);
  }
}

TEST(FormationField, WithNoBarrierNearTheDecreaseIsTheTaskFieldsOwn) {
  // Away from walls and each other only the task field acts: <grad V, f> = -rho / eta exactly,
  // and it is negative off the task's set (the Lyapunov decrease of docs/formation.md).
  for (const TaskKind task : {TaskKind::targets, TaskKind::patrol, TaskKind::leader}) {
    Controller k;
    ControllerConfig c = open_room(task, 3);
    c.targets[0] = {-4.0, 0.0};
    c.targets[1] = {0.0, 4.0};
    c.targets[2] = {4.0, 0.0};
    c.curve = nav::SafeCurve::circle({0.0, 0.0}, 4.0);
    c.curve_start = {4.0, 0.0};
    c.offsets[1] = {-1.5, 1.5};
    c.offsets[2] = {-1.5, -1.5};
    ASSERT_TRUE(k.configure(c));
    std::vector<Pose> start = {{3.0, 1.0, 0.0}, {-2.0, 3.0, 1.0}, {-1.0, -3.5, 2.0}};
    k.reset(start, 0.0);
    std::mt19937_64 rng(3);
    std::uniform_real_distribution<double> jitter(-0.5, 0.5);
    for (int trial = 0; trial < 200; ++trial) {
      std::vector<Vec2> p = points_of(start, c.offset_m);
      for (Vec2& q : p) q = {q.x_m + jitter(rng), q.y_m + jitter(rng)};
      if (task == TaskKind::leader) {  // followers near their offsets, clear of each other
        p[1] = {p[0].x_m + c.offsets[1].x_m + jitter(rng) * 0.4, p[0].y_m + c.offsets[1].y_m + jitter(rng) * 0.4};
        p[2] = {p[0].x_m + c.offsets[2].x_m + jitter(rng) * 0.4, p[0].y_m + c.offsets[2].y_m + jitter(rng) * 0.4};
      }
      const double l = k.decrease(p, 0);
      const double r = k.rho(p);
      ASSERT_LT(l, 0.0) << "task " << static_cast<int>(task);
      ASSERT_NEAR(l, -r / c.eta, 1e-9 * (1.0 + std::fabs(l)));
      ASSERT_GT(k.lyapunov(p), 0.0);
    }
  }
}

TEST(FormationField, BarrierAlwaysPushesTwoCloseRobotsApart) {
  // Whatever the gain set (swirl included), the relative velocity of two robots near contact
  // has a separating component, growing without bound towards the barrier's zero.
  Controller k;
  ControllerConfig c = open_room(TaskKind::targets, 2);
  c.targets[0] = {5.0, 0.0};
  c.targets[1] = {-5.0, 0.0};
  ASSERT_TRUE(k.configure(c));
  const double zero = 2.0 * (c.radius_m + c.offset_m) + c.margin_m;
  double previous = 0.0;
  for (const double gap : {0.2, 0.05, 0.005, 0.002, 0.001}) {
    const std::vector<Vec2> p = {{-(zero + gap) / 2.0, 0.0}, {(zero + gap) / 2.0, 0.0}};
    double weakest = 1e300;
    for (std::size_t g = 0; g < k.gain_sets().size(); ++g) {
      std::vector<Vec2> u(2);
      k.field(p, g, u);
      weakest = std::min(weakest, u[1].x_m - u[0].x_m);  // d|p1 - p0|/dt
    }
    if (gap <= 0.005) {
      EXPECT_GT(weakest, 0.0) << "gap " << gap;
      EXPECT_GT(weakest, previous) << "gap " << gap;
    }
    previous = weakest;
  }
}

TEST(FormationHybrid, SwitchesExactlyWhenTheDecreaseConditionFails) {
  // Two robots swap places head on along the x axis. With the nominal gains the repulsion
  // lies along the attraction and eats the decrease as they close in; the step where
  // <grad V, f(x, k0)> > -mu rho first holds is the one where the rule must jump, not before.
  Controller k;
  ControllerConfig c = open_room(TaskKind::targets, 2);
  c.targets[0] = {4.0, 0.0};
  c.targets[1] = {-4.0, 0.0};
  c.min_dwell_s = 0.0;
  ASSERT_TRUE(k.configure(c));
  std::vector<Pose> poses = {{-4.0, 0.0, 0.0}, {4.0, 0.0, kPi}};
  k.reset(poses, 0.0);
  std::vector<Unicycle> cmd(2);
  bool fired = false;
  double t = 0.0;
  for (double x = 3.9; x > 0.426 && !fired; x -= 0.002) {
    poses = {{-x - c.offset_m, 0.0, 0.0}, {x + c.offset_m, 0.0, kPi}};
    const std::vector<Vec2> p = points_of(poses, c.offset_m);
    const bool fails = k.decrease(p, 0) > -c.mu * k.rho(p);
    const StepInfo& info = k.step(t += 0.1, poses, cmd);
    ASSERT_EQ(info.switched, fails) << "at x = " << x;
    if (info.switched) {
      fired = true;
      EXPECT_NE(info.gain_set, 0u);
      // The set it jumped to meets the full rho there (Assumption 2 holds in this case).
      EXPECT_FALSE(info.unresolved);
      EXPECT_LE(k.decrease(p, info.gain_set), -k.rho(p));
      EXPECT_NE(k.gain_sets()[info.gain_set].swirl_rad, 0.0);
    }
  }
  EXPECT_TRUE(fired);
  EXPECT_EQ(k.switches(), 1u);
}

TEST(FormationHybrid, DoesNotSwitchWhileTheConditionHolds) {
  Controller k;
  ControllerConfig c = open_room(TaskKind::targets, 2);
  c.targets[0] = {4.0, 2.0};
  c.targets[1] = {-4.0, -2.0};
  ASSERT_TRUE(k.configure(c));
  const std::vector<Pose> poses = {{-4.0, 2.0, 0.0}, {4.0, -2.0, kPi}};  // far apart, paths parallel
  const KinematicResult r = testing::run_kinematic(k, poses, 60.0);
  EXPECT_EQ(r.switches, 0u);
  EXPECT_LE(r.final_error_m, 0.05);
}

TEST(FormationHybrid, TheSwitchBreaksAHeadOnStandOffTheNominalGainsCannot) {
  ControllerConfig c = open_room(TaskKind::targets, 2);
  c.targets[0] = {4.0, 0.0};
  c.targets[1] = {-4.0, 0.0};
  const std::vector<Pose> poses = {{-4.1, 0.0, 0.0}, {4.1, 0.0, kPi}};
  Controller hybrid;
  ASSERT_TRUE(hybrid.configure(c));
  const KinematicResult with = testing::run_kinematic(hybrid, poses, 120.0);
  EXPECT_GE(with.switches, 1u);
  EXPECT_LE(with.final_error_m, 0.05);
  EXPECT_GE(with.min_axle_distance_m, 2.0 * c.radius_m);

  ControllerConfig only_nominal = c;
  only_nominal.gain_set_count = 1;
  only_nominal.gain_sets[0] = default_gain_sets()[0];
  Controller fixed;
  ASSERT_TRUE(fixed.configure(only_nominal));
  const KinematicResult without = testing::run_kinematic(fixed, poses, 120.0);
  EXPECT_EQ(without.switches, 0u);
  EXPECT_GT(without.final_error_m, 1.0);  // stuck face to face
  EXPECT_GE(without.min_axle_distance_m, 2.0 * c.radius_m);
}

// The thesis' examples on ideal unicycles with 0.2 s of latency: every target and bound of
// docs/formation.md over the nominal and 50 perturbed starts each.
class FormationExamples : public ::testing::TestWithParam<int> {};

TEST_P(FormationExamples, MeetTheirBoundsFromFiftyPerturbedStarts) {
  const Example e = example(GetParam());
  Controller k;
  ASSERT_TRUE(k.configure(e.config));
  std::mt19937_64 rng(static_cast<std::uint64_t>(GetParam()));
  double worst_distance = 1e9, worst_clearance = 1e9, worst_error = 0.0, worst_converge = 0.0;
  for (int run = 0; run <= 50; ++run) {
    const std::vector<Pose> start = run == 0 ? starts_of(e) : testing::perturbed_starts(e, rng);
    const KinematicResult r = run_kinematic(k, start, e.duration_s);
    worst_distance = std::min(worst_distance, r.min_axle_distance_m);
    worst_clearance = std::min(worst_clearance, r.min_wall_clearance_m);
    worst_error = std::max(worst_error, r.final_error_m);
    worst_converge = std::max(worst_converge, r.converge_s);
    ASSERT_GE(r.converge_s, 0.0) << "run " << run << " did not converge: error " << r.final_error_m;
  }
  EXPECT_GE(worst_distance, 2.0 * e.config.radius_m);
  EXPECT_GT(worst_clearance, 0.0);
  EXPECT_LE(worst_error, 0.05);
  RecordProperty("worst_distance_m", std::to_string(worst_distance));
  RecordProperty("worst_converge_s", std::to_string(worst_converge));
  std::printf("example %d: worst distance %.3f m, wall clearance %.3f m, error %.4f m, converged by %.1f s\n",
              GetParam(), worst_distance, worst_clearance, worst_error, worst_converge);
}

INSTANTIATE_TEST_SUITE_P(Thesis, FormationExamples, ::testing::Values(1, 2, 3));

TEST(FormationPatrol, KeepsTheRobotsEvenlySpacedInTheirOrder) {
  const Example e = example(2);
  Controller k;
  ASSERT_TRUE(k.configure(e.config));
  const KinematicResult r = run_kinematic(k, starts_of(e), e.duration_s);
  const std::vector<Vec2> p = points_of(r.final_poses, e.config.offset_m);
  // Each robot's slot is one third of the curve from the next.
  for (std::size_t i = 0; i < 3; ++i) {
    const Vec2 want = k.desired(p, i);
    EXPECT_LE(std::hypot(p[i].x_m - want.x_m, p[i].y_m - want.y_m), 0.05);
  }
}

TEST(FormationStep, AllocatesNothingAndStopsOnNonsense) {
  const Example e = example(1);
  Controller k;
  ControllerConfig c = e.config;
  ASSERT_TRUE(k.configure(c));
  std::vector<Pose> poses = starts_of(e);
  std::vector<Unicycle> cmd(poses.size());
  k.reset(poses, 0.0);
  {
    mem::testing::AllocationScope scope;
    for (int i = 0; i < 1000; ++i) {
      k.step(0.1 * i, poses, cmd);
      for (std::size_t j = 0; j < poses.size(); ++j) poses[j].theta_rad += 0.01;
    }
    EXPECT_EQ(scope.allocations(), 0u);
    if (mem::testing::counts_malloc()) {
      EXPECT_EQ(scope.malloc_calls(), 0u);
    }
  }
  poses[2].x_m = NAN;
  const StepInfo& info = k.step(200.0, poses, cmd);
  EXPECT_EQ(info.scale, 0.0);
  for (const Unicycle& u : cmd) EXPECT_EQ(u.v == 0.0 && u.w == 0.0, true);
}

}  // namespace
}  // namespace sen3bot::formation
