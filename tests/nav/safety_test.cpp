#include <gtest/gtest.h>

#include <cmath>
#include <random>

#include "sen3bot/nav/safety.hpp"
#include "sen3bot/p2os/sonar.hpp"

namespace sen3bot::nav {
namespace {

constexpr hal::Nanos kSecond = 1'000'000'000;

struct Scene {
  ScanMessage msg;
  ProjectedScan view;
  SafetyInputs in;
  Scene() {
    msg.count = 181;
    msg.angle_min_rad = static_cast<float>(-M_PI / 2);
    msg.increment_rad = static_cast<float>(M_PI / 180);
    msg.range_max_m = 8.0f;
    for (std::size_t i = 0; i < 181; ++i) msg.ranges_m[i] = 5.0f;
    msg.stamp_ns = 10 * kSecond;
    view.assign(msg.view(), {});
    in.scan = &view;
    in.odom_stamp_ns = 10 * kSecond;
    in.now_ns = 10 * kSecond + kSecond / 10;
    in.requested = {0.4, 0.2, in.now_ns};
  }
};

TEST(Safety, PassesACommandWhenAllIsWell) {
  Scene s;
  const SafetyOutput out = SafetyFilter().filter(s.in);
  EXPECT_EQ(out.reasons, kSafetyNone);
  EXPECT_DOUBLE_EQ(out.command.v_m_s, 0.4);
  EXPECT_DOUBLE_EQ(out.command.w_rad_s, 0.2);
}

TEST(Safety, StopsOnAStaleLaserScan) {
  Scene s;
  SafetyFilter f;  // 0.2 s period: stale after 0.6 s
  s.in.now_ns = s.msg.stamp_ns + 590'000'000;
  s.in.odom_stamp_ns = s.in.now_ns;
  EXPECT_EQ(f.filter(s.in).reasons, kSafetyNone);
  s.in.now_ns = s.msg.stamp_ns + 610'000'000;
  s.in.odom_stamp_ns = s.in.now_ns;
  const SafetyOutput out = f.filter(s.in);
  EXPECT_TRUE(out.reasons & kSafetyScanStale);
  EXPECT_EQ(out.command.v_m_s, 0.0);
  EXPECT_EQ(out.command.w_rad_s, 0.0);
  s.in.scan = nullptr;
  EXPECT_TRUE(f.filter(s.in).reasons & kSafetyScanStale);
}

TEST(Safety, StopsOnEstopMotorsOdometryAndLostLocalization) {
  SafetyFilter f;
  {
    Scene s;
    s.in.estop = true;
    EXPECT_EQ(f.filter(s.in).reasons, kSafetyEstop);
    EXPECT_EQ(f.filter(s.in).command.v_m_s, 0.0);
  }
  {
    Scene s;
    s.in.motors_enabled = false;
    EXPECT_EQ(f.filter(s.in).reasons, kSafetyMotorsOff);
  }
  {
    Scene s;
    s.in.odom_stamp_ns = s.in.now_ns - kSecond;
    EXPECT_EQ(f.filter(s.in).reasons, kSafetyOdomStale);
  }
  {
    Scene s;
    s.in.localization_lost = true;
    const SafetyOutput out = f.filter(s.in);
    EXPECT_EQ(out.reasons, kSafetyLocalizationLost);
    EXPECT_EQ(out.command.w_rad_s, 0.0);
  }
}

TEST(Safety, AStopFromTheSafetyIoStopsTheRobot) {
  Scene s;
  for (std::uint32_t reason : {kSafetyEstopChain, kSafetyBumper, kSafetyIoLost, kSafetyResetNeeded}) {
    s.in.io_stops = reason;
    const SafetyOutput out = SafetyFilter().filter(s.in);
    EXPECT_EQ(out.reasons, reason);
    EXPECT_EQ(out.command.v_m_s, 0.0);
    EXPECT_EQ(out.command.w_rad_s, 0.0);
  }
}

msg::SafetyIo healthy_io() {
  msg::SafetyIo io;
  io.healthy = true;
  io.ever_healthy = true;
  return io;
}

TEST(SafetyLatch, AnEstopHoldsUntilReleasedAndThenReset) {
  SafetyLatch latch;
  msg::SafetyIo io = healthy_io();
  EXPECT_EQ(latch.update(&io), kSafetyNone);
  io.estop = true;
  EXPECT_EQ(latch.update(&io), kSafetyEstopChain);
  EXPECT_TRUE(latch.held());
  // Released, but no reset yet: still held, for ever.
  io.estop = false;
  for (int i = 0; i < 100; ++i) EXPECT_EQ(latch.update(&io), kSafetyResetNeeded);
  ++io.resets;
  EXPECT_EQ(latch.update(&io), kSafetyNone);
  EXPECT_FALSE(latch.held());
  EXPECT_EQ(latch.update(&io), kSafetyNone);
  EXPECT_EQ(latch.trips(), 1u);
}

TEST(SafetyLatch, AResetPressedWhileTheChainIsOpenDoesNotCount) {
  SafetyLatch latch;
  msg::SafetyIo io = healthy_io();
  io.estop = true;
  EXPECT_EQ(latch.update(&io), kSafetyEstopChain);
  ++io.resets;  // pressed while the e-stop is still in
  EXPECT_EQ(latch.update(&io), kSafetyEstopChain);
  io.estop = false;
  EXPECT_EQ(latch.update(&io), kSafetyResetNeeded);
  ++io.resets;
  EXPECT_EQ(latch.update(&io), kSafetyNone);
}

TEST(SafetyLatch, BumpersAndLostIoLatchToo) {
  SafetyLatch latch;
  msg::SafetyIo io = healthy_io();
  io.bumper = true;
  EXPECT_EQ(latch.update(&io), kSafetyBumper);
  io.bumper = false;
  EXPECT_EQ(latch.update(&io), kSafetyResetNeeded);
  ++io.resets;
  EXPECT_EQ(latch.update(&io), kSafetyNone);
  // The node lost after it was healthy (or the message stale: null): held.
  EXPECT_EQ(latch.update(nullptr), kSafetyIoLost);
  EXPECT_EQ(latch.update(&io), kSafetyResetNeeded);
  msg::SafetyIo lost = io;
  lost.healthy = false;
  EXPECT_EQ(latch.update(&lost), kSafetyIoLost);
  // A reset counted while the node was away (the counter moved) is not a reset after the loss.
  io.resets += 1;
  EXPECT_EQ(latch.update(&lost), kSafetyIoLost);
  EXPECT_EQ(latch.update(&io), kSafetyResetNeeded);
  ++io.resets;
  EXPECT_EQ(latch.update(&io), kSafetyNone);
  EXPECT_EQ(latch.trips(), 2u);  // the bumper, then the loss (the second loss came while held)
}

TEST(SafetyLatch, AnIoNodeNotYetUpStopsWithoutLatchingUnlessAskedTo) {
  msg::SafetyIo starting;  // not healthy, never was
  SafetyLatch latch;
  EXPECT_EQ(latch.update(nullptr), kSafetyIoLost);
  EXPECT_EQ(latch.update(&starting), kSafetyIoLost);
  EXPECT_FALSE(latch.held());
  msg::SafetyIo io = healthy_io();
  EXPECT_EQ(latch.update(&io), kSafetyNone);

  SafetyLatch strict(true);
  EXPECT_EQ(strict.update(&starting), kSafetyIoLost);
  EXPECT_TRUE(strict.held());
  EXPECT_EQ(strict.update(&io), kSafetyResetNeeded);
  ++io.resets;
  EXPECT_EQ(strict.update(&io), kSafetyNone);
}

TEST(Safety, StopsForAnObstacleAheadButNotBeside) {
  SafetyFilter f;
  Scene s;
  // A point 0.4 m straight ahead: 0.17 m past the front edge (0.2275 m), inside the stop zone.
  s.msg.ranges_m[90] = 0.4f;
  s.view.assign(s.msg.view(), {});
  SafetyOutput out = f.filter(s.in);
  EXPECT_TRUE(out.reasons & kSafetyObstacle);
  EXPECT_EQ(out.command.v_m_s, 0.0);
  // Reversing away is still allowed.
  s.in.requested.v_m_s = -0.05;
  out = f.filter(s.in);
  EXPECT_DOUBLE_EQ(out.command.v_m_s, -0.05);
  // The same point 60 degrees to the side is outside the corridor.
  Scene side;
  side.msg.ranges_m[150] = 0.9f;
  side.view.assign(side.msg.view(), {});
  out = f.filter(side.in);
  EXPECT_FALSE(out.reasons & kSafetyObstacle);
  EXPECT_DOUBLE_EQ(out.command.v_m_s, 0.4);
  // In the slow zone the speed is scaled, not zeroed. Requested 0.4 m/s with a 0.1 s old
  // scan: stop distance 0.25 + 0.4 * (0.1 + 0.1) + 0.1333 = 0.4633 m; half way into the
  // 0.35 m slow zone halves the speed.
  Scene slow;
  slow.msg.ranges_m[90] = static_cast<float>(0.2275 + 0.25 + 0.08 + 0.16 / 1.2 + 0.175);
  slow.view.assign(slow.msg.view(), {});
  slow.in.requested.w_rad_s = 0.0;
  out = f.filter(slow.in);
  EXPECT_TRUE(out.reasons & kSafetySlowed);
  EXPECT_NEAR(out.command.v_m_s, 0.4 * 0.5, 0.4 * 0.02 / 0.35);  // within one sweep step
}

TEST(Safety, NeverRaisesSpeed) {
  SafetyFilter f;
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> v(-1.0, 1.0);
  std::uniform_real_distribution<float> r(0.05f, 9.0f);
  for (int trial = 0; trial < 2000; ++trial) {
    Scene s;
    for (std::size_t i = 0; i < 181; ++i) s.msg.ranges_m[i] = r(rng);
    s.view.assign(s.msg.view(), {});
    s.in.requested = {v(rng), v(rng) * 2.0, s.in.now_ns};
    const SafetyOutput out = f.filter(s.in);
    EXPECT_LE(std::abs(out.command.v_m_s), std::abs(s.in.requested.v_m_s));
    EXPECT_LE(std::abs(out.command.w_rad_s), std::abs(s.in.requested.w_rad_s));
    EXPECT_GE(out.command.v_m_s * s.in.requested.v_m_s, 0.0);
    EXPECT_GE(out.command.w_rad_s * s.in.requested.w_rad_s, 0.0);
  }
}

}  // namespace
}  // namespace sen3bot::nav

namespace sen3bot::nav {
namespace {

TEST(Safety, FollowsTheCommandedArc) {
  SafetyFilter f;
  Scene s;
  s.msg.ranges_m[90] = 0.45f;  // straight ahead, 0.22 m past the front edge
  s.view.assign(s.msg.view(), {});
  s.in.requested = {0.1, 0.0, s.in.now_ns};
  EXPECT_TRUE(f.filter(s.in).reasons & kSafetyObstacle);
  s.in.requested = {0.1, 1.0, s.in.now_ns};  // a tight left arc (0.1 m radius) misses it
  const SafetyOutput out = f.filter(s.in);
  EXPECT_FALSE(out.reasons & kSafetyObstacle);
  EXPECT_GT(out.command.v_m_s, 0.0);
}

}  // namespace
}  // namespace sen3bot::nav

namespace sen3bot::nav {
namespace {

// The stop zone's depth the header documents.
double expected_stop_m(const SafetyConfig& c, double v, double age_s) {
  return c.stop_distance_m + v * (c.reaction_s + age_s) + v * v / (2.0 * c.decel_m_s2);
}

TEST(Safety, AnOldScanStopsWhereAFreshOneOnlySlows) {
  SafetyFilter f;
  Scene s;
  // 0.52 m of free travel straight ahead (front edge at 0.2275 m). At 0.4 m/s a fresh scan
  // gives a 0.4233 m stop zone; one 0.5 s old (the stale limit is 0.6 s) gives 0.6233 m.
  s.msg.ranges_m[90] = static_cast<float>(0.2275 + 0.52);
  s.in.requested = {0.4, 0.0, 0};
  s.msg.stamp_ns = 20 * kSecond;
  s.view.assign(s.msg.view(), {});
  s.in.odom_stamp_ns = 20 * kSecond;

  s.in.now_ns = 20 * kSecond;
  SafetyOutput out = f.filter(s.in);
  EXPECT_EQ(out.scan_age_s, 0.0);
  EXPECT_FALSE(out.reasons & kSafetyObstacle);
  EXPECT_TRUE(out.reasons & kSafetySlowed);
  EXPECT_GT(out.command.v_m_s, 0.0);
  EXPECT_LT(out.stop_distance_m, out.nearest_ahead_m);

  s.in.now_ns = 20 * kSecond + kSecond / 2;
  s.in.odom_stamp_ns = s.in.now_ns;
  out = f.filter(s.in);
  EXPECT_DOUBLE_EQ(out.scan_age_s, 0.5);
  EXPECT_TRUE(out.reasons & kSafetyObstacle);
  EXPECT_EQ(out.command.v_m_s, 0.0);
  EXPECT_GE(out.stop_distance_m, out.nearest_ahead_m);
}

TEST(Safety, StopZoneDepthFollowsSpeedReactionAndScanAge) {
  SafetyConfig config;
  config.reaction_s = 0.15;
  const SafetyFilter f(config);
  for (const double age_s : {0.0, 0.1, 0.35, 0.55}) {
    for (const double v : {0.0, 0.1, 0.25, 0.5, 0.8}) {
      Scene s;  // nothing within 5 m: the command passes and reports the depth it used
      s.in.now_ns = s.msg.stamp_ns + static_cast<hal::Nanos>(age_s * 1e9);
      s.in.odom_stamp_ns = s.in.now_ns;
      s.in.requested = {v, 0.0, s.in.now_ns};
      const SafetyOutput out = f.filter(s.in);
      ASSERT_EQ(out.reasons & kSafetyScanStale, 0u);
      EXPECT_NEAR(out.scan_age_s, age_s, 1e-9);
      EXPECT_NEAR(out.stop_distance_m, expected_stop_m(config, v, age_s), 1e-12) << "v " << v << " age " << age_s;
    }
  }
  // The measured speed counts when it is the larger.
  Scene s;
  s.in.measured_v_m_s = 0.6;
  s.in.requested = {0.2, 0.0, s.in.now_ns};
  EXPECT_NEAR(f.filter(s.in).stop_distance_m, expected_stop_m(config, 0.6, 0.1), 1e-12);
}

TEST(Safety, AScanStampedAheadOfNowHasNoNegativeAge) {
  SafetyFilter f;
  Scene s;
  s.in.now_ns = s.msg.stamp_ns - kSecond / 20;  // the laser's clock slightly ahead
  s.in.odom_stamp_ns = s.in.now_ns;
  s.in.requested = {0.3, 0.0, s.in.now_ns};
  const SafetyOutput out = f.filter(s.in);
  EXPECT_EQ(out.scan_age_s, 0.0);
  EXPECT_NEAR(out.stop_distance_m, expected_stop_m(f.config(), 0.3, 0.0), 1e-12);
}

TEST(Safety, AMoverComingTowardsTheRobotLengthensTheStopZone) {
  SafetyConfig config;
  config.reaction_s = 0.1;
  const SafetyFilter f(config);
  Scene s;
  s.in.pose = {2.0, 1.0, M_PI / 2};  // facing +y in the map
  s.in.requested = {0.4, 0.0, s.in.now_ns};
  msg::MovingObstacles movers;
  movers.stamp_ns = s.in.now_ns;
  movers.count = 1;
  // 3 m ahead, coming down at 0.8 m/s.
  movers.items[0] = {7, 2.0, 4.0, 0.0, -0.8, 0.15, 0.0, 0.0};
  s.in.movers = &movers;
  const double age_s = 0.1;
  const double v = 0.4;
  const SafetyOutput out = f.filter(s.in);
  EXPECT_NEAR(out.closing_speed_m_s, 0.8, 1e-9);
  EXPECT_NEAR(out.stop_distance_m,
              expected_stop_m(config, v, age_s) + 0.8 * (config.reaction_s + age_s + v / config.decel_m_s2), 1e-9);

  // Going away, beside the corridor, or behind: no closing speed.
  movers.items[0].vy_m_s = 0.8;
  EXPECT_EQ(f.filter(s.in).closing_speed_m_s, 0.0);
  movers.items[0] = {7, 3.0, 4.0, 0.0, -0.8, 0.15, 0.0, 0.0};
  EXPECT_EQ(f.filter(s.in).closing_speed_m_s, 0.0);
  movers.items[0] = {7, 2.0, 0.5, 0.0, 0.8, 0.15, 0.0, 0.0};
  EXPECT_EQ(f.filter(s.in).closing_speed_m_s, 0.0);
  // The nearest mover ahead decides.
  movers.count = 2;
  movers.items[0] = {7, 2.0, 4.0, 0.0, -0.8, 0.15, 0.0, 0.0};
  movers.items[1] = {8, 2.1, 2.5, 0.0, -0.3, 0.15, 0.0, 0.0};
  EXPECT_NEAR(f.filter(s.in).closing_speed_m_s, 0.3, 1e-9);
}

TEST(Safety, AClosingMoverStopsWhereAStillObstacleOnlySlows) {
  SafetyConfig config;
  const SafetyFilter f(config);
  Scene s;
  s.in.pose = {0.0, 0.0, 0.0};
  s.in.requested = {0.4, 0.0, s.in.now_ns};
  // A return 0.9 m ahead: beyond the stop zone of a still obstacle.
  for (std::size_t i = 85; i <= 95; ++i) s.msg.ranges_m[i] = 0.9f;
  s.view.assign(s.msg.view(), {});
  const SafetyOutput still = f.filter(s.in);
  EXPECT_EQ(still.reasons & kSafetyObstacle, 0u);
  EXPECT_GT(still.command.v_m_s, 0.0);
  msg::MovingObstacles movers;
  movers.stamp_ns = s.in.now_ns;
  movers.count = 1;
  movers.items[0] = {3, 1.0, 0.0, -0.8, 0.0, 0.1, 0.0, 0.0};
  s.in.movers = &movers;
  const SafetyOutput closing = f.filter(s.in);
  EXPECT_TRUE(closing.reasons & kSafetyObstacle);
  EXPECT_EQ(closing.command.v_m_s, 0.0);
}

// A return straight ahead `gap` m beyond the front of the body, and a mover there (radius 0.1)
// going across at vy with its own vx, as the tracker publishes it; the robot asks for 0.6 m/s.
SafetyOutput crossing(double gap, double vx, double vy) {
  const SafetyFilter f;
  Scene s;
  s.in.pose = {0.0, 0.0, 0.0};
  s.in.requested = {0.6, 0.0, s.in.now_ns};
  s.in.measured_v_m_s = 0.6;
  const double front = 0.455 / 2.0;
  s.msg.ranges_m[90] = static_cast<float>(front + gap);
  s.view.assign(s.msg.view(), {});
  msg::MovingObstacles movers;
  movers.stamp_ns = s.in.now_ns;
  movers.count = 1;
  // Where the scan saw it, 0.1 s ago, moved on to now.
  movers.items[0] = {4, front + gap + 0.05 + 0.1 * vx, 0.1 * vy, vx, vy, 0.1, 0.0, 0.0};
  s.in.movers = &movers;
  return f.filter(s.in);
}

TEST(Safety, AMoverGoneAcrossBeforeTheRobotGetsThereNeitherStopsNorSlows) {
  // 0.6 m/s with a 0.1 s old scan: a still return 0.5 m ahead is inside the stop distance.
  const SafetyOutput still = crossing(0.5, 0.0, 0.0);
  EXPECT_TRUE(still.reasons & kSafetyObstacle);
  EXPECT_EQ(still.command.v_m_s, 0.0);
  // Going across at 1.2 m/s it has left the corridor before the robot covers the 0.5 m.
  const SafetyOutput gone = crossing(0.5, 0.0, 1.2);
  EXPECT_EQ(gone.reasons, kSafetyNone);
  EXPECT_DOUBLE_EQ(gone.command.v_m_s, 0.6);
  // Too slow to be gone in time: it still stops the robot.
  const SafetyOutput slow = crossing(0.5, 0.0, 0.3);
  EXPECT_TRUE(slow.reasons & kSafetyObstacle);
  // Crossing but also coming towards the robot: it counts.
  const SafetyOutput towards = crossing(0.5, -0.5, 1.2);
  EXPECT_TRUE(towards.reasons & kSafetyObstacle);
  // Inside the fixed stop distance every point counts, crossing or not.
  const SafetyOutput near = crossing(0.2, 0.0, 1.2);
  EXPECT_TRUE(near.reasons & kSafetyObstacle);
  EXPECT_EQ(near.command.v_m_s, 0.0);
}

// A person (radius 0.25 m) at (x, y) in the body frame walking at (vx, vy), the laser clear;
// the robot, at 0.3 m/s, asks for (v, w).
SafetyOutput approaching(double x, double y, double vx, double vy, double v, double w, const SafetyConfig& config = {}) {
  const SafetyFilter f(config);
  Scene s;
  s.in.pose = {0.0, 0.0, 0.0};
  s.in.requested = {v, w, s.in.now_ns};
  s.in.measured_v_m_s = 0.3;
  msg::MovingObstacles movers;
  movers.stamp_ns = s.in.now_ns;
  movers.count = 1;
  movers.items[0] = {7, x, y, vx, vy, 0.25, 0.0, 0.0};
  s.in.movers = &movers;
  return f.filter(s.in);
}

TEST(Safety, StopsForAWalkerComingFromTheSideThatBrakingAvoids) {
  // Crossing 0.5 m ahead of the axle from the right at 1 m/s: going on at 0.3 m/s puts the
  // nose into its way; braking now keeps it out.
  const SafetyOutput on = approaching(0.6, -1.0, 0.0, 1.0, 0.3, 0.0);
  EXPECT_TRUE(on.reasons & kSafetyMoverApproach);
  EXPECT_EQ(on.command.v_m_s, 0.0);
  EXPECT_EQ(on.command.w_rad_s, 0.0);
  // Turning towards it is refused as well; the same walker 3 m to the side is not a matter.
  EXPECT_TRUE(approaching(0.6, -1.0, 0.0, 1.0, 0.2, -0.5).reasons & kSafetyMoverApproach);
  const SafetyOutput far = approaching(0.6, -4.0, 0.0, 1.0, 0.3, 0.0);
  EXPECT_EQ(far.reasons, kSafetyNone);
  EXPECT_DOUBLE_EQ(far.command.v_m_s, 0.3);
  // A walker that passes well ahead before the robot gets there does not stop it.
  EXPECT_EQ(approaching(1.6, -0.6, 0.0, 1.0, 0.3, 0.0).reasons, kSafetyNone);
  // A track slower than 0.3 m/s (a still box whose faces come into view) is the corridor's.
  EXPECT_EQ(approaching(0.5, 0.35, 0.0, -0.1, 0.3, 0.0).reasons, kSafetyNone);
  EXPECT_TRUE(approaching(0.5, 0.35, 0.0, -0.5, 0.3, 0.0).reasons & kSafetyMoverApproach);
}

TEST(Safety, MovingAwayFromAWalkerThatCatchesUpStaysAllowed) {
  // Behind the robot and faster than it: braking would only meet it sooner.
  const SafetyOutput away = approaching(-0.8, 0.0, 0.8, 0.0, 0.3, 0.0);
  EXPECT_EQ(away.reasons & kSafetyMoverApproach, 0u);
  EXPECT_DOUBLE_EQ(away.command.v_m_s, 0.3);
  // Backing away from one walking up to the front is allowed too (capped as any reverse).
  const SafetyOutput back = approaching(1.0, 0.0, -0.6, 0.0, -0.1, 0.0);
  EXPECT_EQ(back.reasons & kSafetyMoverApproach, 0u);
  EXPECT_DOUBLE_EQ(back.command.v_m_s, -0.1);
}

TEST(Safety, TheApproachCheckCanBeTurnedOff) {
  SafetyConfig c;
  c.approach_horizon_s = 0.0;
  EXPECT_EQ(approaching(0.6, -1.0, 0.0, 1.0, 0.3, 0.0, c).reasons, kSafetyNone);
}

// The door scene: a walker 0.45 m beyond the robot's nose and 0.5 m to its right, coming across
// at 0.5 m/s, tracked but not yet a mover (it has not yet travelled far from where it came into
// view), the robot at 0.5 m/s.
SafetyOutput candidate_ahead(const SafetyConfig& config) {
  const SafetyFilter f(config);
  Scene s;
  s.in.pose = {0.0, 0.0, 0.0};
  s.in.requested = {0.5, 0.0, s.in.now_ns};
  s.in.measured_v_m_s = 0.5;
  msg::MovingObstacles movers;
  movers.stamp_ns = s.in.now_ns;
  movers.count = 0;
  movers.candidate_count = 1;
  movers.items[0] = {3, 0.9, -0.5, 0.0, 0.5, 0.25, 0.0, 0.0};
  s.in.movers = &movers;
  return f.filter(s.in);
}

TEST(Safety, TheApproachCheckStopsForACandidateMover) {
  const SafetyOutput on = candidate_ahead({});
  EXPECT_TRUE(on.reasons & kSafetyMoverApproach);
  EXPECT_EQ(on.command.v_m_s, 0.0);
  // Only the approach check reads candidates: not the closing speed of the stop zone.
  EXPECT_EQ(on.closing_speed_m_s, 0.0);
  SafetyConfig c;
  c.approach_candidates = false;
  const SafetyOutput off = candidate_ahead(c);
  EXPECT_EQ(off.reasons, kSafetyNone);
  EXPECT_DOUBLE_EQ(off.command.v_m_s, 0.5);
}


// --- Virtual cages ---

// A person at (x, y) in the robot's frame (the robot at the origin facing +x) with a 0.725 m
// cage (a 0.45 m wide person and the 0.5 m safety radius): 0.825 m with the default margin.
// The cage checks alone, without the speed and separation limit (tested on its own below).
SafetyConfig cages_only() {
  SafetyConfig c;
  c.separation_spread_m_s = -1.0;
  return c;
}

SafetyOutput near_person(double x, double y, double vx, double vy, double v, double w, double measured_v,
                         const SafetyConfig& config = cages_only()) {
  const SafetyFilter f(config);
  Scene s;
  s.in.requested = {v, w, s.in.now_ns};
  s.in.measured_v_m_s = measured_v;
  msg::People people;
  people.stamp_ns = s.in.now_ns;
  people.count = 1;
  people.items[0].id = 3;
  people.items[0].x_m = x;
  people.items[0].y_m = y;
  people.items[0].vx_m_s = vx;
  people.items[0].vy_m_s = vy;
  people.items[0].width_m = 0.45;
  people.items[0].cage_radius_m = 0.725;
  s.in.people = &people;
  return f.filter(s.in);
}

TEST(Safety, TheRobotKeepsTheDistanceItNeedsToStopOutsideACage) {
  // At 0.4 m/s the command takes 0.1 s to reach the wheels and braking at 0.6 m/s^2 then
  // covers 0.133 m: 0.173 m in all. The nose is 0.2275 m ahead of the centre, the keep-out
  // 0.825 m around the person: 1.0525 m between the nose and the person's centre.
  const SafetyOutput room = near_person(1.0525 + 0.25, 0.0, 0.0, 0.0, 0.4, 0.0, 0.4);
  EXPECT_EQ(room.reasons, kSafetyNone);
  EXPECT_DOUBLE_EQ(room.command.v_m_s, 0.4);
  // 0.15 m to spare: going on would end 2 cm inside, braking now stops 2 cm short.
  const SafetyOutput tight = near_person(1.0525 + 0.15, 0.0, 0.0, 0.0, 0.4, 0.0, 0.4);
  EXPECT_TRUE(tight.reasons & kSafetyCage);
  EXPECT_EQ(tight.command.v_m_s, 0.0);
  EXPECT_EQ(tight.command.w_rad_s, 0.0);
  // Slowing down there is allowed (it stops sooner than braking from 0.4 m/s would), and so
  // is backing away or passing a person well to the side.
  EXPECT_EQ(near_person(1.0525 + 0.15, 0.0, 0.0, 0.0, 0.05, 0.0, 0.4).reasons & kSafetyCage, 0u);
  EXPECT_EQ(near_person(1.0, 0.0, 0.0, 0.0, -0.1, 0.0, 0.0).reasons & kSafetyCage, 0u);
  EXPECT_EQ(near_person(1.0, 1.6, 0.0, 0.0, 0.4, 0.0, 0.4).reasons, kSafetyNone);
  // Inside the keep-out already (the person stepped closer, or was placed closer), creeping
  // on is refused however slow; backing off is not.
  EXPECT_TRUE(near_person(1.0525 - 0.05, 0.0, 0.0, 0.0, 0.02, 0.0, 0.0).reasons & kSafetyCage);
  EXPECT_EQ(near_person(1.0525 - 0.05, 0.0, 0.0, 0.0, -0.05, 0.0, 0.0).reasons & kSafetyCage, 0u);
  // Turned off, a cage is the planners' alone.
  SafetyConfig off = cages_only();
  off.cage_margin_m = -1.0;
  EXPECT_EQ(near_person(1.0525 + 0.15, 0.0, 0.0, 0.0, 0.4, 0.0, 0.4, off).reasons, kSafetyNone);
}

TEST(Safety, AWalkersCageOnItsWayStopsTheRobotWhenBrakingKeepsFartherOut) {
  // Crossing from the right at 1 m/s, 1.3 m to the side: within a second its cage covers
  // the robot's way ahead; stopping now leaves more room.
  const SafetyOutput on = near_person(0.8, -1.3, 0.0, 1.0, 0.3, 0.0, 0.3);
  EXPECT_TRUE(on.reasons & kSafetyCage);
  EXPECT_EQ(on.command.v_m_s, 0.0);
  // Walking away from the robot's way, the same person is no matter.
  EXPECT_EQ(near_person(0.8, -1.3, 0.0, -1.0, 0.3, 0.0, 0.3).reasons, kSafetyNone);
  // A robot asked to stand is never refused anything: a walker stepping up to it is theirs.
  EXPECT_EQ(near_person(0.5, 0.0, -1.0, 0.0, 0.0, 0.0, 0.0).reasons, kSafetyNone);
}

TEST(Safety, AMoverAtWalkingSpeedIsCagedAsAPersonWhenTheFirmwareTracksPeople) {
  // Coming head-on at 0.5 m/s, 1.5 m ahead, 0.25 m radius: the approach check (0.1 m margin
  // around the body) lets the robot on; caged as a person (0.5 m more) it stops.
  SafetyConfig c = cages_only();
  c.mover_cage_m = 0.5;
  const SafetyOutput caged = approaching(1.5, 0.0, -0.5, 0.0, 0.3, 0.0, c);
  EXPECT_EQ(caged.reasons & kSafetyMoverApproach, 0u);
  EXPECT_TRUE(caged.reasons & kSafetyCage);
  EXPECT_EQ(caged.command.v_m_s, 0.0);
  // Without people tracking (the default) a mover has no cage.
  EXPECT_EQ(approaching(1.5, 0.0, -0.5, 0.0, 0.3, 0.0).reasons & kSafetyCage, 0u);
  // Nor has a slow one (a still box's faces coming into view).
  EXPECT_EQ(approaching(1.5, 0.0, -0.1, 0.0, 0.3, 0.0, c).reasons & kSafetyCage, 0u);
}

// --- Speed and separation (ISO/TS 15066) ---

TEST(SafetySeparation, TheLimitKeepsTheSeparationFormulaTight) {
  // v_h (T + v/a) + v T + v^2/(2a) = S at the limit; nothing left for standing when v_h T >= S.
  const double v = SafetyFilter::separation_speed(0.9475, 0.8, 0.2, 0.6);
  EXPECT_NEAR(0.8 * (0.2 + v / 0.6) + v * 0.2 + v * v / 1.2, 0.9475, 1e-12);
  EXPECT_EQ(SafetyFilter::separation_speed(0.15, 0.8, 0.2, 0.6), 0.0);
  EXPECT_EQ(SafetyFilter::separation_speed(-0.3, 0.0, 0.2, 0.6), 0.0);
  // A standing person with no spread: the robot's own stopping distance alone.
  const double still = SafetyFilter::separation_speed(0.5, 0.0, 0.2, 0.6);
  EXPECT_NEAR(still * 0.2 + still * still / 1.2, 0.5, 1e-12);
}

TEST(SafetySeparation, AWalkerComingHeadOnCapsTheSpeedAsComputedByHand) {
  // Walking at the robot at 0.5 m/s, 2 m ahead of its centre: the nose is 0.2275 m ahead and
  // the keep-out 0.825 m, so the gap S is 0.9475 m. T = 0.1 s (command) + 0.1 s (the scan's
  // age), a = 0.6 m/s^2, v_h = 0.5 + 0.3 (the spread) = 0.8 m/s:
  //   0.8 (0.2 + v/0.6) + 0.2 v + v^2/1.2 = 0.9475  =>  v = 0.418 m/s.
  const SafetyOutput out = near_person(2.0, 0.0, -0.5, 0.0, 0.5, 0.1, 0.5, SafetyConfig{});
  EXPECT_TRUE(out.reasons & kSafetySeparation);
  EXPECT_NEAR(out.command.v_m_s, 0.418, 0.001);
  EXPECT_NEAR(out.command.w_rad_s, 0.1 * out.command.v_m_s / 0.5, 1e-9) << "the arc is kept";
  EXPECT_NEAR(out.separation_gap_m, 0.9475, 1e-9);
  EXPECT_NEAR(out.separation_approach_m_s, 0.8, 1e-9);
  EXPECT_NEAR(out.separation_cap_m_s, out.command.v_m_s, 1e-12);
  // Standing, the same person lets it go faster; 3 m off, not limited at all.
  const SafetyOutput standing = near_person(2.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.5, SafetyConfig{});
  EXPECT_GT(standing.command.v_m_s, 0.418 + 0.05);
  EXPECT_EQ(standing.separation_approach_m_s, 0.0) << "a standing person's step is the cage's";
  const SafetyOutput far = near_person(3.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.5, SafetyConfig{});
  EXPECT_EQ(far.reasons, kSafetyNone);
  EXPECT_DOUBLE_EQ(far.command.v_m_s, 0.5);
  EXPECT_GT(far.separation_cap_m_s, 0.5) << "the terms are reported even when they do not bite";
}

TEST(SafetySeparation, OnlyTheSpeedTowardsThePersonCounts) {
  // 45 degrees off the heading: the limit is on v cos 45.
  const double d = 2.0 / std::sqrt(2.0);
  const SafetyOutput diagonal = near_person(d, d, 0.0, 0.0, 0.5, 0.0, 0.5, SafetyConfig{});
  const SafetyOutput ahead = near_person(2.0, 0.0, 0.0, 0.0, 0.5, 0.0, 0.5, SafetyConfig{});
  EXPECT_GT(diagonal.separation_cap_m_s, ahead.separation_cap_m_s);
  // Abeam or behind, driving on is never limited; nor is backing away from one ahead.
  EXPECT_EQ(near_person(0.0, 1.2, 0.0, 0.0, 0.3, 0.0, 0.3, SafetyConfig{}).reasons & kSafetySeparation, 0u);
  EXPECT_EQ(near_person(-1.0, 0.0, 0.8, 0.0, 0.3, 0.0, 0.3, SafetyConfig{}).reasons & kSafetySeparation, 0u);
  const SafetyOutput back = near_person(1.1, 0.0, -0.8, 0.0, -0.1, 0.0, 0.0, SafetyConfig{});
  EXPECT_EQ(back.reasons & kSafetySeparation, 0u);
  EXPECT_DOUBLE_EQ(back.command.v_m_s, -0.1);
  // So close that even standing does not keep it: nothing towards them at all, but it may
  // turn on the spot to face away.
  // (The cage check alone on the walker's way, over 0 s, lets the turn through.)
  SafetyConfig now_only;
  now_only.cage_horizon_s = 0.0;
  const SafetyOutput close = near_person(1.25, 0.0, -0.8, 0.0, 0.2, 0.3, 0.0, now_only);
  EXPECT_TRUE(close.reasons & kSafetySeparation);
  EXPECT_EQ(close.command.v_m_s, 0.0);
  EXPECT_DOUBLE_EQ(close.command.w_rad_s, 0.3);
}

TEST(SafetySeparation, WalkingMoversAndCandidatesCountWhenPeopleAreTracked) {
  SafetyConfig c;
  c.mover_cage_m = 0.5;
  // A walker coming head-on 2.5 m ahead, not (yet) known as a person.
  EXPECT_TRUE(approaching(2.5, 0.0, -0.8, 0.0, 0.5, 0.0, c).reasons & kSafetySeparation);
  // Without people tracking, movers keep the checks they had; a slow track is the corridor's.
  EXPECT_EQ(approaching(2.5, 0.0, -0.8, 0.0, 0.5, 0.0).reasons & kSafetySeparation, 0u);
  EXPECT_EQ(approaching(2.5, 0.0, -0.1, 0.0, 0.5, 0.0, c).reasons & kSafetySeparation, 0u);
  // Turned off.
  c.separation_spread_m_s = -1.0;
  EXPECT_EQ(approaching(2.5, 0.0, -0.8, 0.0, 0.5, 0.0, c).reasons & kSafetySeparation, 0u);
}

}  // namespace
}  // namespace sen3bot::nav

namespace sen3bot::nav {
namespace {

// The P3-DX ring with one echo: disc `d` reads range_m, read `age_s` ago.
msg::Sonar ring_with_echo(std::size_t d, double range_m, hal::Nanos now_ns, double age_s = 0.1) {
  msg::Sonar s;
  s.count = 16;
  for (std::size_t i = 0; i < 16; ++i) {
    const p2os::SonarMount& m = p2os::kP3dxSonar[i];
    s.mount[i] = {m.x_mm / 1000.0, m.y_mm / 1000.0, m.heading_deg * M_PI / 180.0};
    s.range_m[i] = s.max_range_m;
    s.stamp_ns[i] = now_ns - 100'000'000;
  }
  s.range_m[d] = range_m;
  s.stamp_ns[d] = now_ns - static_cast<hal::Nanos>(age_s * 1e9);
  return s;
}

TEST(SafetySonar, AnEchoRightBehindStopsAReversingRobot) {
  Scene s;
  s.in.requested = {-0.1, 0.0, s.in.now_ns};
  // Someone 0.2 m from rear disc 11 (which sits 0.03 m behind the footprint): within the
  // 0.25 m stop zone behind the body.
  const msg::Sonar ring = ring_with_echo(11, 0.2, s.in.now_ns);
  s.in.sonar = &ring;
  const SafetyOutput out = SafetyFilter().filter(s.in);
  EXPECT_EQ(out.command.v_m_s, 0.0);
  EXPECT_NE(out.reasons & kSafetySonar, 0u);
  // Forward is the laser's business: the same echo does not stop it.
  s.in.requested = {0.3, 0.0, s.in.now_ns};
  EXPECT_EQ(SafetyFilter().filter(s.in).command.v_m_s, 0.3);
}

TEST(SafetySonar, AWatchedBackLetsItReverseFasterAndStillStopsForAnEcho) {
  Scene s;
  s.in.requested = {-0.4, 0.0, s.in.now_ns};
  // No sonar: the back-off speed.
  SafetyOutput out = SafetyFilter().filter(s.in);
  EXPECT_DOUBLE_EQ(out.command.v_m_s, -0.1);
  EXPECT_TRUE(out.reasons & kSafetyReverseCapped);
  // Every rear disc fresh and clear: sonar_reverse_m_s.
  const msg::Sonar clear = ring_with_echo(11, 5.0, s.in.now_ns);
  s.in.sonar = &clear;
  out = SafetyFilter().filter(s.in);
  EXPECT_DOUBLE_EQ(out.command.v_m_s, -SafetyConfig{}.sonar_reverse_m_s);
  // One rear disc stale: back to the back-off speed.
  const msg::Sonar stale = ring_with_echo(12, 5.0, s.in.now_ns, 2.0);
  s.in.sonar = &stale;
  EXPECT_DOUBLE_EQ(SafetyFilter().filter(s.in).command.v_m_s, -0.1);
  // At the faster speed the stop reach is longer: an echo 0.3 m behind stops it.
  const msg::Sonar near = ring_with_echo(11, 0.3, s.in.now_ns);
  s.in.sonar = &near;
  out = SafetyFilter().filter(s.in);
  EXPECT_EQ(out.command.v_m_s, 0.0);
  EXPECT_TRUE(out.reasons & kSafetySonar);
}

TEST(SafetySonar, FarStaleOrSideEchoesLetItReverse) {
  Scene s;
  s.in.requested = {-0.1, 0.0, s.in.now_ns};
  for (const msg::Sonar& ring : {ring_with_echo(11, 1.5, s.in.now_ns),          // far behind
                                 ring_with_echo(11, 0.25, s.in.now_ns, 2.0),     // too old to trust
                                 ring_with_echo(8, 0.4, s.in.now_ns)}) {         // beside, not behind
    s.in.sonar = &ring;
    const SafetyOutput out = SafetyFilter().filter(s.in);
    EXPECT_DOUBLE_EQ(out.command.v_m_s, -0.1);
    EXPECT_EQ(out.reasons & kSafetySonar, 0u);
  }
  // And one just past the stop zone: 0.25 m from the disc, 0.27 m behind the body.
  {
    const msg::Sonar ring = ring_with_echo(11, 0.25, s.in.now_ns);
    s.in.sonar = &ring;
    EXPECT_DOUBLE_EQ(SafetyFilter().filter(s.in).command.v_m_s, -0.1);
  }
}

TEST(SafetySonar, AnEchoInsideTheTurnCircleRefusesTurningOnTheSpot) {
  Scene s;
  s.in.requested = {0.0, 0.5, s.in.now_ns};
  // Disc 9 (rear left, 130 degrees off) sees something 0.1 m out: inside the circle the
  // corners sweep.
  const msg::Sonar ring = ring_with_echo(9, 0.1, s.in.now_ns);
  s.in.sonar = &ring;
  EXPECT_EQ(SafetyFilter().filter(s.in).command.w_rad_s, 0.0);
  const msg::Sonar clear = ring_with_echo(9, 0.6, s.in.now_ns);
  s.in.sonar = &clear;
  EXPECT_EQ(SafetyFilter().filter(s.in).command.w_rad_s, 0.5);
}

}  // namespace
}  // namespace sen3bot::nav
