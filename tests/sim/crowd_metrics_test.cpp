// Crowd-navigation metrics on constructed runs whose answers are worked out by hand, the Wilson
// interval against published values, aggregation, and the legs a shin-height laser sees.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/crowd/legs.hpp"
#include "sen3bot/crowd/metrics.hpp"

namespace sen3bot::crowd {
namespace {

using mem::testing::AllocationScope;

constexpr double kDt = 0.05;
// Pioneer 3-DX: half length and half width.
constexpr double kHalfLength = 0.455 / 2.0;
constexpr double kHalfWidth = 0.381 / 2.0;

// The robot drives along y = 0 at 0.5 m/s, heading +x, from x = -3 to x = 3: step k (0..240)
// at x = -3 + 0.025 k, t = 0.05 k. Samples are at exact multiples so none lands on a zone edge.
constexpr int kStraightSteps = 241;

RunStep straight_step(int k, std::span<const PersonTruth> people) {
  RunStep s;
  s.time_s = kDt * k;
  s.robot = {-3.0 + 0.025 * k, 0.0, 0.0};
  s.v_m_s = 0.5;
  s.people = people;
  return s;
}

RunMetrics drive_past(const PersonTruth& person, const RunSetup& setup = {}) {
  const std::array<PersonTruth, 1> people{person};
  RunMeter meter;
  meter.start(setup);
  for (int k = 0; k < kStraightSteps; ++k) meter.observe(straight_step(k, people));
  return meter.finish(true, kDt * (kStraightSteps - 1));
}

TEST(PointMath, ConvexPolygonDistanceOutsideAnEdgeACornerAndInside) {
  const std::array<Point2D, 4> ccw{{{1, 1}, {-1, 1}, {-1, -1}, {1, -1}}};
  const std::array<Point2D, 4> cw{{{1, -1}, {-1, -1}, {-1, 1}, {1, 1}}};
  for (const auto& square : {ccw, cw}) {
    EXPECT_DOUBLE_EQ(msg::convex_polygon_distance(square, {3.0, 0.5}), 2.0);   // off the right edge
    EXPECT_DOUBLE_EQ(msg::convex_polygon_distance(square, {0.2, -1.5}), 0.5);  // off the bottom edge
    EXPECT_DOUBLE_EQ(msg::convex_polygon_distance(square, {4.0, 5.0}), 5.0);   // off a corner: 3-4-5
    EXPECT_DOUBLE_EQ(msg::convex_polygon_distance(square, {2.0, 1.0}), 1.0);   // on an edge's extension
    EXPECT_DOUBLE_EQ(msg::convex_polygon_distance(square, {0.5, -0.3}), 0.0);  // inside
    EXPECT_DOUBLE_EQ(msg::convex_polygon_distance(square, {1.0, 0.2}), 0.0);   // on the boundary
  }
  // A triangle: beyond the hypotenuse of (0,0) (2,0) (0,2), from (2,2) it is sqrt(2) away.
  const std::array<Point2D, 3> triangle{{{0, 0}, {2, 0}, {0, 2}}};
  EXPECT_NEAR(msg::convex_polygon_distance(triangle, {2.0, 2.0}), std::sqrt(2.0), 1e-12);
  EXPECT_DOUBLE_EQ(msg::convex_polygon_distance(triangle, {0.5, 0.5}), 0.0);
  // A segment and a point.
  const std::array<Point2D, 2> segment{{{0, 0}, {2, 0}}};
  EXPECT_DOUBLE_EQ(msg::convex_polygon_distance(segment, {1.0, 0.0}), 0.0);
  EXPECT_DOUBLE_EQ(msg::convex_polygon_distance(segment, {1.0, 0.7}), 0.7);
  EXPECT_DOUBLE_EQ(msg::convex_polygon_distance(std::span<const Point2D>(segment.data(), 1), {3.0, 4.0}), 5.0);
}

TEST(CrowdMetrics, BodyDistanceUsesTheRotatedFootprint) {
  const nav::Footprint pioneer = nav::Footprint::pioneer();
  // Heading +y: the front (half length) faces +y, a side (half width) faces +x.
  const Pose2D pose{1.0, 2.0, std::numbers::pi / 2.0};
  EXPECT_NEAR(body_distance(pioneer, pose, {1.0, 2.0 + kHalfLength + 0.5}, 0.25), 0.25, 1e-12);
  EXPECT_NEAR(body_distance(pioneer, pose, {1.0 + kHalfWidth + 0.5, 2.0}, 0.25), 0.25, 1e-12);
  // Off the front-left corner (-x, +y in the map) by 0.3 and 0.4: 0.5 to the corner.
  EXPECT_NEAR(body_distance(pioneer, pose, {1.0 - kHalfWidth - 0.3, 2.0 + kHalfLength + 0.4}, 0.25), 0.25, 1e-12);
  // The centre inside the footprint: overlapping by the whole radius.
  EXPECT_NEAR(body_distance(pioneer, pose, {1.05, 2.1}, 0.25), -0.25, 1e-12);
  // Partly overlapping a side: centre 0.1 off the edge.
  EXPECT_NEAR(body_distance(pioneer, pose, {1.0 + kHalfWidth + 0.1, 2.0}, 0.25), -0.15, 1e-12);
  // A footprint longer ahead and wider on the left (x -0.1..0.5, y -0.2..0.4) tells a wrong
  // rotation from the right one: heading +y puts its left at -x in the map.
  nav::Footprint lopsided;
  lopsided.vertices[0] = {0.5, 0.4};
  lopsided.vertices[1] = {-0.1, 0.4};
  lopsided.vertices[2] = {-0.1, -0.2};
  lopsided.vertices[3] = {0.5, -0.2};
  lopsided.vertex_count = 4;
  EXPECT_NEAR(body_distance(lopsided, pose, {1.0 - 0.4 - 0.5, 2.0}, 0.25), 0.25, 1e-12);  // left
  EXPECT_NEAR(body_distance(lopsided, pose, {1.0 + 0.2 + 0.5, 2.0}, 0.25), 0.25, 1e-12);  // right
  EXPECT_NEAR(body_distance(lopsided, pose, {1.0, 2.0 + 0.5 + 0.5}, 0.25), 0.25, 1e-12);  // ahead
  EXPECT_NEAR(body_distance(lopsided, pose, {1.0, 2.0 - 0.1 - 0.5}, 0.25), 0.25, 1e-12);  // behind
  // Any heading: a point placed 0.3 ahead of the front edge in the robot frame.
  const Pose2D turned{-1.0, 0.5, 0.7};
  const Pose2D ahead = msg::compose(turned, {0.5 + 0.3, 0.1, 0.0});
  EXPECT_NEAR(body_distance(lopsided, turned, {ahead.x_m, ahead.y_m}, 0.25), 0.05, 1e-12);
  // A circular robot: centre distance minus both radii.
  EXPECT_NEAR(body_distance(nav::Footprint::circle(0.3), {0.0, 0.0, 1.0}, {0.6, 0.8}, 0.25), 0.45, 1e-12);
}

TEST(CrowdMetrics, StraightPassAtAKnownOffset) {
  // The person 0.3 m beyond the robot's left side: body distance 0.3 while the side is abreast
  // (|x| <= half length), sqrt((|x| - 0.2275)^2 + 0.55^2) - 0.25 beyond.
  const PersonTruth person{{0.0, kHalfWidth + 0.25 + 0.3}, {}, 0.25, true};
  RunSetup setup;
  setup.dt_s = kDt;
  setup.time_limit_s = 30.0;
  setup.free_path_length_m = 6.0;
  setup.free_path_time_s = 6.0 / 0.7;  // at a 0.7 m/s maximum speed
  const RunMetrics m = drive_past(person, setup);

  EXPECT_NEAR(m.min_distance_m, 0.3, 1e-12);
  EXPECT_GE(m.min_distance_time_s, 6.0 - kHalfLength / 0.5 - 1e-9);  // first reached abreast
  EXPECT_LE(m.min_distance_time_s, 6.0 + kHalfLength / 0.5 + 1e-9);
  // Intimate zone (< 0.45): (|x| - 0.2275)^2 < 0.7^2 - 0.55^2 = 0.1875, |x| < 0.66051: the
  // samples |x| <= 0.65, k = 94..146, 53 of them. Personal (< 1.2): (|x| - 0.2275)^2 <
  // 1.45^2 - 0.55^2 = 1.8, |x| < 1.56914: |x| <= 1.55, 125 samples.
  EXPECT_NEAR(m.intimate_zone_s, 53 * kDt, 1e-9);
  EXPECT_NEAR(m.personal_zone_s, 125 * kDt, 1e-9);
  EXPECT_EQ(m.danger_frequency, 0.0);
  EXPECT_EQ(m.steps, 241u);

  EXPECT_NEAR(m.path_length_m, 6.0, 1e-9);
  EXPECT_NEAR(m.path_ratio, 1.0, 1e-9);
  EXPECT_TRUE(m.reached_goal);
  EXPECT_TRUE(m.success);
  EXPECT_FALSE(m.timeout);
  EXPECT_NEAR(m.time_to_goal_s, 12.0, 1e-9);
  EXPECT_NEAR(m.time_ratio, 12.0 / (6.0 / 0.7), 1e-9);
  EXPECT_EQ(m.contacts_any, 0u);
  EXPECT_EQ(m.cage_entries, 0u);
  EXPECT_NEAR(m.max_jerk_m_s3, 0.0, 1e-9);  // constant speed
}

TEST(CrowdMetrics, DangerFrequencyIsTheShareOfTimeCloserThan20cm) {
  // 0.1 m beyond the side: distance < 0.2 while (|x| - 0.2275)^2 < 0.45^2 - 0.35^2 = 0.08,
  // |x| < 0.51034: |x| <= 0.5, 41 of the 241 samples.
  const RunMetrics m = drive_past({{0.0, kHalfWidth + 0.25 + 0.1}, {}, 0.25, true}, {.dt_s = kDt});
  EXPECT_NEAR(m.min_distance_m, 0.1, 1e-12);
  EXPECT_NEAR(m.danger_frequency, 41.0 / 241.0, 1e-12);
}

TEST(CrowdMetrics, InvisiblePeopleAreIgnored) {
  const RunMetrics m = drive_past({{0.0, 0.0}, {}, 0.25, false}, {.dt_s = kDt});
  EXPECT_TRUE(std::isinf(m.min_distance_m));
  EXPECT_EQ(m.personal_zone_s, 0.0);
  EXPECT_EQ(m.danger_frequency, 0.0);
}

TEST(CrowdMetrics, TheClosestOfSeveralPeopleCounts) {
  // One far (3 m off), one that the robot's centre passes through.
  const std::array<PersonTruth, 2> people{{{{0.0, -3.0}, {}, 0.25, true}, {{1.0, 0.0}, {}, 0.25, true}}};
  RunMeter meter;
  meter.start({.dt_s = kDt});
  for (int k = 0; k < kStraightSteps; ++k) meter.observe(straight_step(k, people));
  EXPECT_NEAR(meter.metrics().min_distance_m, -0.25, 1e-12);
}

TEST(CrowdMetrics, AContactIsCountedOnceAndOnlyTheRobotsAreCollisions) {
  // A person the robot drives into at step 3 and overlaps until step 6; a second contact at
  // step 8 that the person made (the robot was not closing). The world keeps contact_by_robot
  // up during the first overlap: it must not count again.
  RunMeter meter;
  meter.start({.dt_s = kDt, .time_limit_s = 30.0});
  for (int k = 0; k < 10; ++k) {
    const bool overlapping = k >= 3 && k <= 6;
    const std::array<PersonTruth, 1> people{{{{overlapping ? 0.1 : 2.0, 0.0}, {}, 0.25, true}}};
    RunStep s;
    s.time_s = kDt * k;
    s.people = people;
    s.contact_started = k == 3 || k == 8;
    s.contact_by_robot = overlapping;
    meter.observe(s);
  }
  const RunMetrics& m = meter.finish(true, 10.0);
  EXPECT_EQ(m.contacts_any, 2u);
  EXPECT_EQ(m.contacts_by_robot, 1u);
  EXPECT_NEAR(m.min_distance_m, -0.25, 1e-12);
  EXPECT_TRUE(m.reached_goal);
  EXPECT_FALSE(m.success);  // any contact spoils the run
  EXPECT_FALSE(m.timeout);
}

TEST(CrowdMetrics, ContactsTheRobotDidNotCauseStillSpoilSuccess) {
  RunMeter meter;
  meter.start({.dt_s = kDt});
  RunStep s;
  meter.observe(s);
  s.contact_started = true;
  meter.observe(s);
  const RunMetrics& m = meter.finish(true, 5.0);
  EXPECT_EQ(m.contacts_any, 1u);
  EXPECT_EQ(m.contacts_by_robot, 0u);
  EXPECT_FALSE(m.success);
}

TEST(CrowdMetrics, CageEntriesAreCountedOnEntry) {
  RunMeter meter;
  meter.start({.dt_s = kDt});
  RunStep s;
  for (const bool in : {false, true, true, true, false, true, false, false, true, true}) {
    s.robot_in_cage = in;
    meter.observe(s);
  }
  EXPECT_EQ(meter.metrics().cage_entries, 3u);
  // Starting inside counts as an entry; staying inside does not add.
  meter.start({.dt_s = kDt});
  for (const bool in : {true, true, true}) {
    s.robot_in_cage = in;
    meter.observe(s);
  }
  EXPECT_EQ(meter.metrics().cage_entries, 1u);
}

TEST(CrowdMetrics, TimeoutIsNotASuccess) {
  RunMeter meter;
  RunStep s;
  // The limit passes without the goal.
  meter.start({.dt_s = kDt, .start_time_s = 100.0, .time_limit_s = 30.0, .free_path_time_s = 10.0});
  meter.observe(s);
  RunMetrics m = meter.finish(false, 130.0);
  EXPECT_TRUE(m.timeout);
  EXPECT_FALSE(m.success);
  EXPECT_EQ(m.time_to_goal_s, -1.0);
  EXPECT_EQ(m.time_ratio, -1.0);
  // Reached, but after the limit.
  meter.start({.dt_s = kDt, .start_time_s = 100.0, .time_limit_s = 30.0, .free_path_time_s = 10.0});
  meter.observe(s);
  m = meter.finish(true, 135.0);
  EXPECT_TRUE(m.timeout);
  EXPECT_FALSE(m.success);
  EXPECT_NEAR(m.time_to_goal_s, 35.0, 1e-12);
  EXPECT_NEAR(m.time_ratio, 3.5, 1e-12);
  // Given up early: neither.
  meter.start({.dt_s = kDt, .start_time_s = 100.0, .time_limit_s = 30.0});
  meter.observe(s);
  m = meter.finish(false, 110.0);
  EXPECT_FALSE(m.timeout);
  EXPECT_FALSE(m.success);
  // Reached just in time.
  meter.start({.dt_s = kDt, .start_time_s = 100.0, .time_limit_s = 30.0});
  meter.observe(s);
  m = meter.finish(true, 129.0);
  EXPECT_TRUE(m.success);
  EXPECT_FALSE(m.timeout);
}

TEST(CrowdMetrics, ConstantAccelerationHasNoJerkAndAStepInAccelerationHasItsJerk) {
  RunMeter meter;
  meter.start({.dt_s = kDt});
  RunStep s;
  for (int k = 0; k < 21; ++k) {
    s.v_m_s = 0.2 + 0.3 * kDt * k;
    s.w_rad_s = -0.1 + 0.7 * kDt * k;
    meter.observe(s);
  }
  EXPECT_NEAR(meter.metrics().max_jerk_m_s3, 0.0, 1e-9);
  EXPECT_NEAR(meter.metrics().mean_jerk_m_s3, 0.0, 1e-9);
  EXPECT_NEAR(meter.metrics().max_angular_jerk_rad_s3, 0.0, 1e-9);

  // Forward: +0.3 m/s^2 up to step 10, then -0.5 m/s^2: one jerk of 0.8 / 0.05 = 16 m/s^3
  // among the 19 finite differences of 21 speeds. Angular: 1 rad/s^2 then 0 from step 15:
  // one of 20 rad/s^3. Each must stay out of the other.
  meter.start({.dt_s = kDt});
  double v = 0.0;
  double w = 0.0;
  for (int k = 0; k < 21; ++k) {
    if (k > 0) {
      v += (k <= 10 ? 0.3 : -0.5) * kDt;
      w += (k <= 14 ? 1.0 : 0.0) * kDt;
    }
    s.v_m_s = v;
    s.w_rad_s = w;
    meter.observe(s);
  }
  const RunMetrics& m = meter.metrics();
  EXPECT_NEAR(m.max_jerk_m_s3, 16.0, 1e-9);
  EXPECT_NEAR(m.mean_jerk_m_s3, 16.0 / 19.0, 1e-9);
  EXPECT_NEAR(m.max_angular_jerk_rad_s3, 20.0, 1e-9);
  EXPECT_NEAR(m.mean_angular_jerk_rad_s3, 20.0 / 19.0, 1e-9);
}

TEST(CrowdMetrics, StartForgetsThePreviousRun) {
  RunMeter meter;
  meter.start({.dt_s = kDt});
  RunStep s;
  s.contact_started = true;
  s.robot_in_cage = true;
  meter.observe(s);
  s.robot.x_m = 1.0;
  meter.observe(s);
  ASSERT_EQ(meter.metrics().contacts_any, 2u);
  meter.start({.dt_s = kDt});
  EXPECT_EQ(meter.metrics().contacts_any, 0u);
  EXPECT_EQ(meter.metrics().steps, 0u);
  EXPECT_EQ(meter.metrics().path_length_m, 0.0);
  EXPECT_TRUE(std::isinf(meter.metrics().min_distance_m));
  // The cage and the last pose are forgotten too: inside again is a new entry, no jump in path.
  meter.observe(s);
  EXPECT_EQ(meter.metrics().cage_entries, 1u);
  EXPECT_EQ(meter.metrics().path_length_m, 0.0);
}

TEST(CrowdMetrics, ObservingAllocatesNothing) {
  std::array<PersonTruth, 8> people{};
  for (std::size_t i = 0; i < people.size(); ++i) people[i].position = {0.3 * static_cast<double>(i), 1.0};
  RunMeter meter;
  meter.start({.dt_s = kDt});
  AllocationScope scope;
  for (int k = 0; k < 2000; ++k) {
    RunStep s = straight_step(k % kStraightSteps, people);
    s.robot_in_cage = k % 7 == 0;
    meter.observe(s);
  }
  (void)meter.finish(true, 100.0);
  EXPECT_EQ(scope.allocations(), 0u);
}

TEST(CrowdMetrics, WilsonIntervalMatchesKnownValues) {
  // Wilson score intervals at z = 1.96, rounded to 4 places (the usual tabulated values; checked
  // against an independent evaluation of Wilson's formula).
  Interval ci = wilson_interval(0, 10);
  EXPECT_EQ(ci.lower, 0.0);
  EXPECT_NEAR(ci.upper, 0.2775, 5e-5);
  ci = wilson_interval(5, 10);
  EXPECT_NEAR(ci.lower, 0.2366, 5e-5);
  EXPECT_NEAR(ci.upper, 0.7634, 5e-5);
  ci = wilson_interval(10, 10);
  EXPECT_NEAR(ci.lower, 0.7225, 5e-5);
  EXPECT_EQ(ci.upper, 1.0);
  // By hand: p = 0.15, n = 20: centre 0.24604 / 1.19208, half 1.96 sqrt(0.008776) / 1.19208.
  ci = wilson_interval(3, 20);
  EXPECT_NEAR(ci.lower, 0.0524, 5e-5);
  EXPECT_NEAR(ci.upper, 0.3604, 5e-5);
  // z = 1 (68 %) narrows it: 5/10 gives 0.5 -+ 0.5 sqrt(0.025 + 0.0025) / 1.1.
  ci = wilson_interval(5, 10, 1.0);
  EXPECT_NEAR(ci.upper - 0.5, std::sqrt(0.0275) / 1.1, 1e-12);
  ci = wilson_interval(0, 0);
  EXPECT_EQ(ci.lower, 0.0);
  EXPECT_EQ(ci.upper, 1.0);
}

TEST(CrowdMetrics, QuartilesInterpolateLikeRAndNumpy) {
  std::vector<double> values{20.0, 10.0, 12.0, 11.0};  // sorted 10 11 12 20
  const Quartiles q = quartiles(values);
  EXPECT_EQ(q.n, 4u);
  EXPECT_DOUBLE_EQ(q.median, 11.5);
  EXPECT_DOUBLE_EQ(q.q1, 10.75);  // (n - 1) 0.25 = 0.75
  EXPECT_DOUBLE_EQ(q.q3, 14.0);   // 2.25: 12 + 0.25 * 8
  EXPECT_DOUBLE_EQ(q.iqr, 3.25);
  std::vector<double> odd{3.0, 1.0, 2.0};
  EXPECT_DOUBLE_EQ(quartiles(odd).median, 2.0);
  std::vector<double> none;
  EXPECT_TRUE(std::isnan(quartiles(none).median));
}

TEST(CrowdMetrics, AggregateOverRuns) {
  auto run = [](bool success, double time_s, double min_m, std::uint32_t by_robot, bool timeout) {
    RunMetrics r;
    r.success = success;
    r.reached_goal = success || by_robot > 0;
    r.time_to_goal_s = r.reached_goal ? time_s : -1.0;
    r.min_distance_m = min_m;
    r.contacts_by_robot = by_robot;
    r.contacts_any = by_robot;
    r.timeout = timeout;
    r.intimate_zone_s = min_m < 0.45 ? 1.0 : 0.0;
    r.personal_zone_s = 3.0;
    r.danger_frequency = min_m < 0.2 ? 0.3 : 0.0;
    return r;
  };
  const std::array<RunMetrics, 6> runs{run(true, 10.0, 0.5, 0, false),  run(true, 12.0, 0.3, 0, false),
                                       run(true, 20.0, 0.8, 0, false),  run(true, 11.0, 0.4, 0, false),
                                       run(false, 9.0, -0.1, 1, false), run(false, 0.0, 1.5, 0, true)};
  const Aggregate a = aggregate(runs);
  EXPECT_EQ(a.n, 6u);
  EXPECT_EQ(a.success.count, 4u);
  EXPECT_NEAR(a.success.rate, 4.0 / 6.0, 1e-12);
  const Interval success_ci = wilson_interval(4, 6);
  EXPECT_EQ(a.success.lower, success_ci.lower);
  EXPECT_EQ(a.success.upper, success_ci.upper);
  EXPECT_NEAR(a.success.lower, 0.3000, 5e-5);  // 4/6 at z = 1.96: [0.3000, 0.9032]
  EXPECT_NEAR(a.success.upper, 0.9032, 5e-5);
  EXPECT_EQ(a.collision.count, 1u);
  EXPECT_NEAR(a.collision.upper, wilson_interval(1, 6).upper, 1e-15);
  EXPECT_EQ(a.timeout.count, 1u);
  // Time to goal over the 4 successes only (the collided run's 9 s is left out): 10 11 12 20.
  EXPECT_EQ(a.time_to_goal_s.n, 4u);
  EXPECT_DOUBLE_EQ(a.time_to_goal_s.median, 11.5);
  EXPECT_DOUBLE_EQ(a.time_to_goal_s.iqr, 3.25);
  // Min distance over all 6: -0.1 0.3 0.4 0.5 0.8 1.5.
  EXPECT_EQ(a.min_distance_m.n, 6u);
  EXPECT_NEAR(a.min_distance_m.median, 0.45, 1e-12);
  EXPECT_NEAR(a.min_distance_m.q1, 0.325, 1e-12);
  EXPECT_NEAR(a.min_distance_m.q3, 0.725, 1e-12);
  EXPECT_NEAR(a.mean_intimate_zone_s, 3.0 / 6.0, 1e-12);  // 0.3 0.4 and -0.1 are under 0.45
  EXPECT_NEAR(a.mean_personal_zone_s, 3.0, 1e-12);
  EXPECT_NEAR(a.mean_danger_frequency, 0.3 / 6.0, 1e-12);

  const Aggregate empty = aggregate({});
  EXPECT_EQ(empty.n, 0u);
  EXPECT_TRUE(std::isnan(empty.time_to_goal_s.median));
}

// Legs.

double along(Point2D d, double heading) { return dot(d, Point2D{std::cos(heading), std::sin(heading)}); }
double across(Point2D d, double heading) { return dot(d, Point2D{-std::sin(heading), std::cos(heading)}); }

TEST(CrowdLegs, GaitRelationFollowsGrieveAndGear) {
  EXPECT_NEAR(step_frequency_hz(1.0), 1.6, 1e-12);
  EXPECT_NEAR(step_frequency_hz(1.3), 1.6 * std::pow(1.3, 0.58), 1e-12);
  EXPECT_NEAR(step_frequency_hz(1.3), 1.86, 0.01);  // about 112 steps/min
  EXPECT_NEAR(step_length_m(1.3) * step_frequency_hz(1.3), 1.3, 1e-12);
  EXPECT_NEAR(step_length_m(0.5), 0.467, 0.001);
  EXPECT_LT(step_frequency_hz(0.5), step_frequency_hz(1.3));
  EXPECT_EQ(step_length_m(0.0), 0.0);
  EXPECT_EQ(step_frequency_hz(0.0), 0.0);
  EXPECT_DOUBLE_EQ(step_length_m(3.0), step_length_m(kGaitMaxSpeedM_S));  // the cap
}

// Walks at `speed` along a diagonal for `seconds` and returns the spacing-sign changes per
// second (two per stride, so the step frequency), checking the geometry at every step.
double measured_step_frequency(double speed, double seconds) {
  const Point2D direction{0.6, 0.8};
  const Point2D velocity = speed * direction;
  const double heading = std::atan2(0.8, 0.6);
  const double dt = 0.01;
  Gait gait;
  Point2D centre{2.0, -1.0};
  double previous = 0.0;
  double first_crossing = -1.0;
  double last_crossing = -1.0;
  int crossings = 0;
  double widest = 0.0;
  const int steps = static_cast<int>(std::lround(seconds / dt));
  for (int k = 1; k <= steps; ++k) {
    advance(gait, velocity, dt);
    centre += dt * velocity;
    const auto legs = leg_centres(centre, gait, speed);
    const Point2D spacing = legs[0] - legs[1];
    const double s = along(spacing, heading);
    EXPECT_NEAR(across(spacing, heading), 2.0 * kLegSpreadM, 1e-9);  // left leg on the left
    EXPECT_LE(msg::norm(0.5 * (legs[0] + legs[1]) - centre), 0.1);
    widest = std::max(widest, std::abs(s));
    if (k > 1 && (s > 0.0) != (previous > 0.0)) {
      const double t = dt * (k - 1) + dt * previous / (previous - s);  // interpolated zero
      if (crossings == 0) first_crossing = t;
      last_crossing = t;
      ++crossings;
    }
    previous = s;
  }
  EXPECT_NEAR(widest, step_length_m(speed), 0.01 * step_length_m(speed));  // a step apart at most
  EXPECT_GE(crossings, 3);
  return (crossings - 1) / (last_crossing - first_crossing);
}

TEST(CrowdLegs, SpacingAlongTheHeadingOscillatesAtTheStepFrequency) {
  // f = 1.6 v^0.58: 1.071 Hz at 0.5 m/s, 1.864 Hz at 1.3 m/s.
  EXPECT_NEAR(measured_step_frequency(0.5, 10.0), 1.6 * std::pow(0.5, 0.58), 0.005);
  EXPECT_NEAR(measured_step_frequency(1.3, 10.0), 1.6 * std::pow(1.3, 0.58), 0.005);
}

TEST(CrowdLegs, StandingFreezesTheGaitWithTheFeetSideBySide) {
  Gait gait;
  const Point2D velocity{-0.9, 0.3};
  for (int k = 0; k < 37; ++k) advance(gait, velocity, 0.05);
  const double heading = std::atan2(0.3, -0.9);
  EXPECT_NEAR(gait.heading_rad, heading, 1e-12);
  ASSERT_GT(std::abs(std::sin(gait.phase_rad)), 0.1);  // stopped mid-stride
  const Gait stopped = gait;
  for (int k = 0; k < 20; ++k) advance(gait, {0.0, 0.0}, 0.05);
  EXPECT_EQ(gait.phase_rad, stopped.phase_rad);
  EXPECT_EQ(gait.heading_rad, stopped.heading_rad);
  Gait jitter = gait;
  advance(jitter, {0.01, -0.02}, 0.05);  // slower than kHeadingMinSpeedM_S: the heading stays
  EXPECT_EQ(jitter.heading_rad, stopped.heading_rad);
  const Point2D centre{4.0, 5.0};
  const auto legs = leg_centres(centre, gait, 0.0);
  EXPECT_NEAR(along(legs[0] - legs[1], heading), 0.0, 1e-12);
  EXPECT_NEAR(across(legs[0] - legs[1], heading), 0.2, 1e-12);
  EXPECT_NEAR(msg::norm(0.5 * (legs[0] + legs[1]) - centre), 0.0, 1e-12);
  // Walking on, the legs part again.
  const auto walking = leg_centres(centre, stopped, msg::norm(velocity));
  EXPECT_GT(std::abs(along(walking[0] - walking[1], heading)), 0.1);
}

TEST(CrowdLegs, PhaseIsAFunctionOfTheDistanceWalked) {
  // The same walk in 100 steps of 0.01 s and in 10 of 0.1 s: the same phase.
  Gait fine;
  Gait coarse;
  for (int k = 0; k < 100; ++k) advance(fine, {0.8, 0.0}, 0.01);
  for (int k = 0; k < 10; ++k) advance(coarse, {0.8, 0.0}, 0.1);
  EXPECT_NEAR(fine.phase_rad, coarse.phase_rad, 1e-9);
  // 0.8 m at 0.8 m/s: 0.8 / step length steps, pi each.
  EXPECT_NEAR(fine.phase_rad, std::fmod(std::numbers::pi * 0.8 / step_length_m(0.8), 2.0 * std::numbers::pi), 1e-9);
  // Phase 0 (setting off) has the feet side by side; a quarter cycle on, the left leg is a
  // step ahead.
  const auto off = leg_centres({0.0, 0.0}, Gait{0.0, 0.0}, 1.0);
  EXPECT_NEAR(off[0].x_m - off[1].x_m, 0.0, 1e-12);
  const auto quarter = leg_centres({0.0, 0.0}, Gait{std::numbers::pi / 2.0, 0.0}, 1.0);
  EXPECT_NEAR(quarter[0].x_m - quarter[1].x_m, step_length_m(1.0), 1e-12);
  EXPECT_NEAR(quarter[0].y_m - quarter[1].y_m, 2.0 * kLegSpreadM, 1e-12);
  // Deterministic: replaying the walk gives the same legs bit for bit.
  Gait again;
  for (int k = 0; k < 100; ++k) advance(again, {0.8, 0.0}, 0.01);
  const auto a = leg_centres({1.0, 1.0}, fine, 0.8);
  const auto b = leg_centres({1.0, 1.0}, again, 0.8);
  EXPECT_EQ(a[0].x_m, b[0].x_m);
  EXPECT_EQ(a[0].y_m, b[0].y_m);
  EXPECT_EQ(a[1].x_m, b[1].x_m);
  EXPECT_EQ(a[1].y_m, b[1].y_m);
}

}  // namespace
}  // namespace sen3bot::crowd
