#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <random>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/mem/budget_arena.hpp"
#include "sen3bot/nav/localization.hpp"
#include "sen3bot/world/world.hpp"

namespace sen3bot::nav {
namespace {

TEST(Kld, QuantileAndBound) {
  EXPECT_NEAR(normal_quantile(0.99), 2.326348, 1e-5);
  EXPECT_NEAR(normal_quantile(0.5), 0.0, 1e-9);
  EXPECT_NEAR(normal_quantile(0.01), -2.326348, 1e-5);
  // AMCL's defaults (err 0.05, "pf_z" 0.99 used as z): the anchor table's numbers.
  EXPECT_EQ(kld_particle_count(10, 0.05, 0.99, 1, 100000), 131u);
  EXPECT_EQ(kld_particle_count(50, 0.05, 0.99, 1, 100000), 588u);
  EXPECT_EQ(kld_particle_count(100, 0.05, 0.99, 1, 100000), 1129u);
  EXPECT_EQ(kld_particle_count(100, 0.05, 0.99, 500, 1000), 1000u);
  EXPECT_EQ(kld_particle_count(1, 0.05, 0.99, 500, 1000), 500u);
}

// Drives a ground-truth pose along a polyline in the lab and feeds MCL noisy odometry and
// ideal-but-noisy scans; returns per-update errors after `settle` updates.
struct TrackResult {
  double rms_xy_m = 0.0;
  double rms_theta_rad = 0.0;
  double final_error_m = 0.0;
  std::uint32_t updates = 0;
  bool allocation_free = true;
  std::vector<double> errors_xy_m;       // per update
  std::vector<double> errors_theta_rad;
  std::size_t injected_max = 0;          // random particles at one resampling
  bool reported_lost = false;
  std::size_t kidnapped_at = 0;          // the first update after the kidnapping
};

// Updates after the kidnapping until the estimate is within 0.3 m and 10 degrees of the truth
// and stays there to the end; -1 if it never settles.
int settled_from(const TrackResult& r) {
  int from = -1;
  for (std::size_t i = r.kidnapped_at; i < r.errors_xy_m.size(); ++i) {
    const bool close = r.errors_xy_m[i] < 0.3 && std::abs(r.errors_theta_rad[i]) < 10.0 * M_PI / 180.0;
    if (!close) from = -1;
    else if (from < 0) from = static_cast<int>(i - r.kidnapped_at);
  }
  return from;
}

const std::vector<Point2D> kLowerRoute = {{2.5, 1.0}, {2.5, 4.0}, {4.2, 4.2}, {4.2, 3.0}, {3.0, 3.0}, {3.0, 1.0}, {2.5, 1.0}};

// Drives each route in turn `laps` times; between routes the truth is carried to the next
// route's start (facing its second point) and odometry is not told: a kidnapping.
TrackResult track(MclConfig cfg, std::uint32_t settle, bool global,
                  const std::vector<std::vector<Point2D>>& routes = {kLowerRoute}, int laps = 2) {
  auto map = load_map(SEN3BOT_SOURCE_DIR "/config/maps/lab.yaml");
  EXPECT_TRUE(map.ok());
  world::WorldConfig wc;
  wc.range_noise_sigma_m = 0.01;
  wc.seed = 3;
  world::World truth(*map, wc);
  mem::BudgetArena arena("mcl", MonteCarloLocalization::storage_bytes(cfg, *map));
  MonteCarloLocalization mcl;
  EXPECT_TRUE(mcl.init(cfg, *map, arena));
  if (global) mcl.global_initialize();
  std::mt19937_64 rng(11);
  std::normal_distribution<double> odo_noise(0.0, 0.01);
  Pose2D pose{routes[0][0].x_m, routes[0][0].y_m, M_PI / 2.0};
  Pose2D odom = pose;  // odometry starts equal to the map pose; it drifts from there
  std::vector<float> ranges(361);
  ScanMessage msg;
  msg.count = 361;
  msg.angle_min_rad = static_cast<float>(-M_PI / 2.0);
  msg.increment_rad = static_cast<float>(M_PI / 360.0);
  msg.range_max_m = 8.0f;
  double sum_xy = 0.0;
  double sum_t = 0.0;
  std::uint32_t counted = 0;
  TrackResult result;
  hal::Nanos t_ns = 0;
  const auto step_to = [&](const Pose2D& next) {
    // Odometry sees the true motion in the robot frame, with noise on each step.
    const double c = std::cos(pose.theta_rad);
    const double s = std::sin(pose.theta_rad);
    const double fx = c * (next.x_m - pose.x_m) + s * (next.y_m - pose.y_m);
    const double fy = -s * (next.x_m - pose.x_m) + c * (next.y_m - pose.y_m);
    const double dth = normalize_angle(next.theta_rad - pose.theta_rad);
    const double nfx = fx * (1.0 + odo_noise(rng));
    const double ndth = dth * (1.0 + odo_noise(rng)) + 0.1 * odo_noise(rng) * std::abs(fx);
    odom.x_m += std::cos(odom.theta_rad) * nfx - std::sin(odom.theta_rad) * fy;
    odom.y_m += std::sin(odom.theta_rad) * nfx + std::cos(odom.theta_rad) * fy;
    odom.theta_rad = normalize_angle(odom.theta_rad + ndth);
    pose = next;
    t_ns += 100'000'000;
    truth.noisy_scan(pose, msg.angle_min_rad, msg.increment_rad, msg.count, msg.range_max_m, std::span<float>(msg.ranges_m.data(), msg.count));
    ProjectedScan view;
    view.assign(msg.view(), cfg.laser_mount);
    const Odometry o{odom.x_m, odom.y_m, odom.theta_rad, 0.0, 0.0, t_ns, true};
    mem::testing::AllocationScope scope;
    const bool updated = mcl.update(o, &view);
    if (scope.allocations() != 0) result.allocation_free = false;
    const PoseEstimate e = mcl.estimate();
    if (updated) {
      result.errors_xy_m.push_back(std::hypot(e.pose.x_m - pose.x_m, e.pose.y_m - pose.y_m));
      result.errors_theta_rad.push_back(normalize_angle(e.pose.theta_rad - pose.theta_rad));
      result.injected_max = std::max(result.injected_max, mcl.injected());
      result.reported_lost = result.reported_lost || e.lost;
    }
    if (updated && std::getenv("MCL_TRACE") != nullptr) std::printf("u%u true %.3f %.3f %.3f est %.3f %.3f %.3f n %u sd %.3f pz %.3f slow %.3f fast %.3f inj %.2f lost %d\n", e.updates, pose.x_m, pose.y_m, pose.theta_rad, e.pose.x_m, e.pose.y_m, e.pose.theta_rad, e.particles, std::sqrt(e.cov_xx), e.likelihood, e.likelihood_slow, e.likelihood_fast, e.injection, e.lost);
    if (updated && e.updates > settle) {
      const double exy = std::hypot(e.pose.x_m - pose.x_m, e.pose.y_m - pose.y_m);
      const double et = normalize_angle(e.pose.theta_rad - pose.theta_rad);
      sum_xy += exy * exy;
      sum_t += et * et;
      ++counted;
    }
  };
  for (std::size_t leg = 0; leg < routes.size(); ++leg) {
   const std::vector<Point2D>& route = routes[leg];
   if (leg > 0) {
     pose = {route[0].x_m, route[0].y_m, std::atan2(route[1].y_m - route[0].y_m, route[1].x_m - route[0].x_m)};
     result.kidnapped_at = result.errors_xy_m.size();
   }
   for (int lap = 0; lap < laps; ++lap) {
    for (std::size_t i = 1; i < route.size(); ++i) {
      const Point2D a = route[i - 1];
      const Point2D b = route[i];
      const double heading = std::atan2(b.y_m - a.y_m, b.x_m - a.x_m);
      // Turn on the spot in 0.1 rad steps, then drive in 0.05 m steps.
      while (std::abs(normalize_angle(heading - pose.theta_rad)) > 1e-9) {
        const double d = std::clamp(normalize_angle(heading - pose.theta_rad), -0.1, 0.1);
        step_to({pose.x_m, pose.y_m, normalize_angle(pose.theta_rad + d)});
      }
      const double len = std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
      const int steps = static_cast<int>(std::ceil(len / 0.05));
      for (int k = 1; k <= steps; ++k) {
        const double t = static_cast<double>(k) / steps;
        step_to({a.x_m + t * (b.x_m - a.x_m), a.y_m + t * (b.y_m - a.y_m), heading});
      }
    }
   }
  }
  const PoseEstimate e = mcl.estimate();
  result.final_error_m = std::hypot(e.pose.x_m - pose.x_m, e.pose.y_m - pose.y_m);
  result.updates = e.updates;
  result.rms_xy_m = counted > 0 ? std::sqrt(sum_xy / counted) : 1e9;
  result.rms_theta_rad = counted > 0 ? std::sqrt(sum_t / counted) : 1e9;
  return result;
}

TEST(Mcl, TracksWithinFiveCentimetresAndTwoDegrees) {
  MclConfig cfg;
  cfg.initial_pose = {2.5, 1.0, M_PI / 2.0};
  cfg.initial_std_xy_m = 0.05;
  cfg.initial_std_theta_rad = 0.03;
  cfg.update_min_d_m = 0.1;
  cfg.update_min_a_rad = 0.1;
  cfg.sigma_hit_m = 0.05;
  // The simulated odometry drifts about 1 %: AMCL's default alphas (0.2) would spread the
  // particles far more than it does.
  cfg.alpha1 = cfg.alpha2 = cfg.alpha3 = cfg.alpha4 = 0.05;
  const TrackResult r = track(cfg, 3, false);
  std::printf("tracking RMS %.4f m, %.3f deg over %u updates\n", r.rms_xy_m, r.rms_theta_rad * 180.0 / M_PI, r.updates);
  EXPECT_GT(r.updates, 50u);
  EXPECT_LT(r.rms_xy_m, 0.05);
  EXPECT_LT(r.rms_theta_rad, 2.0 * M_PI / 180.0);
  EXPECT_TRUE(r.allocation_free);
}

TEST(Mcl, ConvergesFromAWrongInitialGuess) {
  MclConfig cfg;
  cfg.initial_pose = {2.9, 0.7, M_PI / 2.0 + 0.25};  // 0.5 m and 14 degrees off
  cfg.initial_std_xy_m = 0.5;
  cfg.initial_std_theta_rad = 0.3;
  cfg.update_min_d_m = 0.1;
  cfg.update_min_a_rad = 0.1;
  const TrackResult r = track(cfg, 15, false);  // converged within 15 updates
  EXPECT_LT(r.rms_xy_m, 0.1);
  EXPECT_LT(r.final_error_m, 0.1);
}

// Tracking in the lower work area, then carried through the wall into the upper storage area
// (odometry not told) and driven on there: the filter keeps following odometry in the wrong
// room, and only random-particle injection gets it out.
TrackResult kidnapped(bool recovery) {
  MclConfig cfg;
  cfg.initial_pose = {2.5, 1.0, M_PI / 2.0};
  cfg.initial_std_xy_m = 0.05;
  cfg.initial_std_theta_rad = 0.03;
  cfg.update_min_d_m = 0.1;
  cfg.update_min_a_rad = 0.1;
  cfg.recovery_alpha_slow = recovery ? 0.001 : 0.0;
  cfg.recovery_alpha_fast = recovery ? 0.1 : 0.0;
  const std::vector<Point2D> upper = {{4.0, 7.0}, {4.0, 5.4}, {1.0, 5.4}, {4.5, 5.4}, {4.5, 8.8}, {3.0, 8.8}, {3.0, 5.4}};
  return track(cfg, 0, false, {kLowerRoute, upper}, 1);
}

TEST(Mcl, RecoversFromAKidnappingOnlyWithInjection) {
  const TrackResult on = kidnapped(true);
  const TrackResult off = kidnapped(false);
  const int settled = settled_from(on);
  std::printf("kidnapped after %zu updates: recovery on settles %d updates later (of %zu; at most %zu random "
              "particles, lost %d); off: final error %.2f m\n",
              on.kidnapped_at, settled, on.errors_xy_m.size() - on.kidnapped_at, on.injected_max, on.reported_lost,
              off.final_error_m);
  ASSERT_GE(settled, 0);
  EXPECT_LE(settled, 60);
  EXPECT_GT(on.injected_max, 0u);
  EXPECT_TRUE(on.reported_lost);
  EXPECT_TRUE(on.allocation_free);  // the injection path allocates nothing either
  EXPECT_LT(settled_from(off), 0);
  EXPECT_GT(off.final_error_m, 1.0);
  EXPECT_EQ(off.injected_max, 0u);
}

TEST(Mcl, TrackingInjectsLittle) {
  // Tracking correctly, the likelihood holds and injection stays rare: the estimate is no worse.
  MclConfig cfg;
  cfg.recovery_alpha_slow = 0.001;
  cfg.recovery_alpha_fast = 0.1;
  cfg.initial_pose = {2.5, 1.0, M_PI / 2.0};
  cfg.initial_std_xy_m = 0.05;
  cfg.initial_std_theta_rad = 0.03;
  cfg.update_min_d_m = 0.1;
  cfg.update_min_a_rad = 0.1;
  const TrackResult r = track(cfg, 3, false);
  std::printf("tracking with recovery on: RMS %.4f m, at most %zu random particles at once, lost %d\n", r.rms_xy_m,
              r.injected_max, r.reported_lost);
  EXPECT_LT(r.rms_xy_m, 0.1);
  EXPECT_FALSE(r.reported_lost);
}

TEST(Mcl, RejectsBadRecoveryRates) {
  auto map = load_map(SEN3BOT_SOURCE_DIR "/config/maps/lab.yaml");
  ASSERT_TRUE(map.ok());
  const auto rejected = [&](double slow, double fast, double ratio) {
    MclConfig cfg;
    cfg.recovery_alpha_slow = slow;
    cfg.recovery_alpha_fast = fast;
    cfg.lost_likelihood_ratio = ratio;
    mem::BudgetArena arena("mcl", MonteCarloLocalization::storage_bytes(cfg, *map));
    MonteCarloLocalization mcl;
    return !mcl.init(cfg, *map, arena).ok();
  };
  EXPECT_TRUE(rejected(0.1, 0.001, 0.5));   // slow faster than fast
  EXPECT_TRUE(rejected(-0.1, 0.1, 0.5));
  EXPECT_TRUE(rejected(0.001, 1.5, 0.5));
  EXPECT_TRUE(rejected(0.001, 0.1, 1.0));
  EXPECT_FALSE(rejected(0.001, 0.1, 0.5));
  EXPECT_FALSE(rejected(0.0, 0.1, 0.5));    // off
}

}  // namespace
}  // namespace sen3bot::nav

namespace sen3bot::nav {
namespace {

TEST(Mcl, GlobalInitializationIsReportedLost) {
  auto map = load_map(SEN3BOT_SOURCE_DIR "/config/maps/lab.yaml");
  ASSERT_TRUE(map.ok());
  MclConfig cfg;
  mem::BudgetArena arena("mcl", MonteCarloLocalization::storage_bytes(cfg, *map));
  MonteCarloLocalization mcl;
  ASSERT_TRUE(mcl.init(cfg, *map, arena));
  EXPECT_FALSE(mcl.estimate().lost);
  EXPECT_EQ(mcl.particle_count(), cfg.min_particles);
  mcl.global_initialize();
  EXPECT_TRUE(mcl.estimate().lost);
  EXPECT_EQ(mcl.particle_count(), cfg.max_particles);
}

}  // namespace
}  // namespace sen3bot::nav

#include "sen3bot/nav/odometry_history.hpp"

namespace sen3bot::nav {
namespace {

// Turning on the spot right in front of an unmapped 0.4 m box, a quarter of the scan on it:
// beam skipping leaves those beams out, so the estimate stays where the robot is.
double worst_error_turning_at_a_box(bool beam_skip, bool with_box = true) {
  auto map = load_map(SEN3BOT_SOURCE_DIR "/config/maps/lab.yaml");
  EXPECT_TRUE(map.ok());
  world::WorldConfig wc;
  wc.range_noise_sigma_m = 0.01;
  world::World truth(*map, wc);
  world::MoverScript box;
  box.path = {{2.85, 3.9}};
  box.size_m = 0.4;
  box.shape = world::MoverShape::square;
  if (with_box) truth.add_mover(box);
  truth.set_time(0.0);
  MclConfig cfg;
  cfg.beam_skip = beam_skip;
  cfg.initial_pose = {3.05, 4.5, -M_PI / 2.0};
  cfg.initial_std_xy_m = 0.05;
  cfg.initial_std_theta_rad = 0.05;
  cfg.update_min_a_rad = 0.1;
  cfg.laser_mount = {0.16, 0.0, 0.0};
  mem::BudgetArena arena("mcl", MonteCarloLocalization::storage_bytes(cfg, *map));
  MonteCarloLocalization mcl;
  EXPECT_TRUE(mcl.init(cfg, *map, arena));
  ScanMessage msg;
  msg.count = 361;
  msg.angle_min_rad = static_cast<float>(-M_PI / 2.0);
  msg.increment_rad = static_cast<float>(M_PI / 360.0);
  msg.range_max_m = 8.0f;
  double worst = 0.0;
  Pose2D pose = cfg.initial_pose;
  for (int k = 0; k <= 60; ++k) {  // 0.05 rad steps: -90 deg round to -262 deg
    pose.theta_rad = normalize_angle(-M_PI / 2.0 - 0.05 * k);
    const Pose2D sensor = compose(pose, cfg.laser_mount);
    truth.noisy_scan(sensor, msg.angle_min_rad, msg.increment_rad, msg.count, msg.range_max_m,
                     std::span<float>(msg.ranges_m.data(), msg.count));
    ProjectedScan view;
    view.assign(msg.view(), cfg.laser_mount);
    (void)mcl.update({pose.x_m, pose.y_m, pose.theta_rad, 0.0, -0.5, k * 100'000'000LL, true}, &view);
    const PoseEstimate e = mcl.estimate();
    worst = std::max(worst, std::hypot(e.pose.x_m - pose.x_m, e.pose.y_m - pose.y_m));
  }
  return worst;
}

TEST(Mcl, BeamSkippingIgnoresAnUnmappedBoxCloseAhead) {
  const double with = worst_error_turning_at_a_box(true);
  const double without = worst_error_turning_at_a_box(false);
  const double no_box = worst_error_turning_at_a_box(true, false);
  std::printf("turning 0.4 m from an unmapped box: worst error %.3f m with beam skipping, %.3f m without (%.3f m with no box)\n",
              with, without, no_box);
  EXPECT_LT(with, 0.05);
  EXPECT_GT(without, 0.1);  // the box drags the estimate when every beam counts
  EXPECT_LT(no_box, 0.05);
}

TEST(OdometryHistory, InterpolatesBetweenSamplesAndExtrapolatesALittle) {
  OdometryHistory h;
  Pose2D p;
  EXPECT_FALSE(h.pose_at(0, p));
  // 0.5 m/s straight along x, then turning, one sample per 100 ms.
  for (int i = 0; i < 10; ++i) h.push({0.05 * i, 0.0, i < 5 ? 0.0 : 0.1 * (i - 4), 0.5, i < 5 ? 0.0 : 1.0, i * 100'000'000LL, true});
  h.push({9.0, 9.0, 0.0, 0.0, 0.0, 500'000'000LL, true});  // older than the newest: ignored
  h.push({9.0, 9.0, 0.0, 0.0, 0.0, 0, false});             // not valid: ignored
  EXPECT_EQ(h.size(), 10u);
  ASSERT_TRUE(h.pose_at(125'000'000LL, p));
  EXPECT_NEAR(p.x_m, 0.0625, 1e-9);
  EXPECT_NEAR(p.theta_rad, 0.0, 1e-12);
  ASSERT_TRUE(h.pose_at(650'000'000LL, p));
  EXPECT_NEAR(p.theta_rad, 0.25, 1e-9);
  // 0.1 s past the newest sample (0.45 m, 0.5 rad, 0.5 m/s, 1 rad/s).
  ASSERT_TRUE(h.pose_at(1'000'000'000LL, p));
  EXPECT_NEAR(p.theta_rad, 0.6, 1e-9);
  EXPECT_NEAR(p.x_m, 0.45 + 0.05 * std::cos(0.55), 1e-9);
  EXPECT_FALSE(h.pose_at(2'000'000'000LL, p));  // too far ahead
  EXPECT_FALSE(h.pose_at(-1, p));               // older than every sample
  // The ring keeps the newest kCapacity samples.
  for (int i = 10; i < 10 + static_cast<int>(OdometryHistory::kCapacity); ++i)
    h.push({0.05 * i, 0.0, 0.0, 0.5, 0.0, i * 100'000'000LL, true});
  EXPECT_EQ(h.size(), OdometryHistory::kCapacity);
  EXPECT_FALSE(h.pose_at(900'000'000LL, p));
  ASSERT_TRUE(h.pose_at(1'050'000'000LL, p));
  EXPECT_NEAR(p.x_m, 0.525, 1e-9);
}

TEST(OdometryHistory, RelativeAndApplyInvertEachOther) {
  const Pose2D a{1.0, -2.0, 2.5};
  const Pose2D b{-0.5, 0.7, -2.9};
  const Pose2D d = relative_pose(a, b);
  const Pose2D back = apply_motion(a, d);
  EXPECT_NEAR(back.x_m, b.x_m, 1e-12);
  EXPECT_NEAR(back.y_m, b.y_m, 1e-12);
  EXPECT_NEAR(normalize_angle(back.theta_rad - b.theta_rad), 0.0, 1e-12);
}

}  // namespace
}  // namespace sen3bot::nav
