// People kept while out of view: a confirmed track not seen for expire_s is kept, hidden, while
// its place has not been seen empty (by the laser or the sonar), up to the sigma and time caps.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/mem/budget_arena.hpp"
#include "sen3bot/nav/nav_tasks.hpp"
#include "sen3bot/nav/people.hpp"

namespace sen3bot::nav {
namespace {

constexpr hal::Nanos kSecond = 1'000'000'000;

// A 361-beam, 180-degree scan from a laser at the origin facing +x: a wall at wall_m ahead,
// and something at near_m across the bearings in near (radians).
struct Scan {
  Scan(double wall_m, double near_m, std::vector<std::pair<double, double>> near, hal::Nanos stamp)
      : ranges(361), stamp_ns(stamp) {
    for (std::size_t i = 0; i < ranges.size(); ++i) {
      const double a = -std::numbers::pi / 2 + static_cast<double>(i) * std::numbers::pi / 360.0;
      ranges[i] = static_cast<float>(std::min(wall_m / std::max(std::cos(a), 0.05), 29.0));
      for (const auto& [lo, hi] : near)
        if (a >= lo && a <= hi) ranges[i] = static_cast<float>(near_m);
    }
  }
  [[nodiscard]] msg::ScanView view() const {
    return {ranges, static_cast<float>(-std::numbers::pi / 2), static_cast<float>(std::numbers::pi / 360.0), 0.05f, 30.0f, stamp_ns};
  }
  std::vector<float> ranges;
  hal::Nanos stamp_ns;
};

// The tracker's configuration with hidden people kept (off by default).
PersonTrackerConfig kept() {
  PersonTrackerConfig c;
  c.keep_hidden = true;
  return c;
}

struct HiddenTracker {
  explicit HiddenTracker(PersonTrackerConfig c = kept()) : config(c) { EXPECT_TRUE(tracker.init(c, arena)); }
  // A person standing at (x, y), 0.5 m wide, seen by the camera 5 times at 10 Hz from `from`.
  hal::Nanos stand(double x, double y, hal::Nanos from, int fixes = 5) {
    for (int k = 0; k < fixes; ++k) {
      PersonFix f;
      f.x_m = x;
      f.y_m = y;
      f.width_m = 0.5;
      f.points = 10;
      tracker.update(std::span(&f, 1), from += kSecond / 10);
    }
    return from;
  }
  msg::People publish(hal::Nanos now) {
    msg::People people;
    tracker.publish(now, people);
    return people;
  }
  PersonTrackerConfig config;
  mem::BudgetArena arena{"people", 64 * 1024};
  PersonTracker tracker;
};

SensorCoverage laser_only(const msg::ScanView& view) {
  SensorCoverage c;
  c.scan = &view;
  return c;
}

// A person walks behind a rack: the laser's beams towards them end at the rack, nearer than
// they are, so the place is not seen and they are kept, hidden, with a growing cage. An
// unconfirmed track beside them still ends at expire_s. A wall just behind the place does not
// prove it empty (they may stand against it); a scan that sees past the place does.
TEST(HiddenPeople, APersonBehindARackIsKeptUntilThePlaceIsSeenEmpty) {
  HiddenTracker t;
  hal::Nanos now = 0;
  // Walking +y at 0.5 m/s along x = 3 to (3, 0), seen by the camera at 10 Hz.
  for (int k = 0; k <= 20; ++k) {
    PersonFix f;
    f.x_m = 3.0;
    f.y_m = -1.0 + 0.05 * k;
    f.width_m = 0.5;
    f.points = 10;
    t.tracker.update(std::span(&f, 1), now += kSecond / 10);
  }
  const hal::Nanos last_fix = now;
  // A stray box, seen twice (never confirmed), at (2, -2).
  PersonFix stray;
  stray.x_m = 2.0;
  stray.y_m = -2.0;
  stray.width_m = 0.5;
  t.tracker.update(std::span(&stray, 1), now);
  t.tracker.update(std::span(&stray, 1), now + kSecond / 20);
  ASSERT_EQ(t.tracker.tracks().size(), 2u);
  const double base_cage = 0.25 + t.config.safety_radius_m;

  // The rack: returns at 1.5 m from 0 to 25 degrees, across the walker's bearing (about 9.5
  // degrees once they coasted to (3, 0.5)).
  const Scan rack(6.0, 1.5, {{0.0, 25.0 * std::numbers::pi / 180.0}}, last_fix + 2 * kSecond);
  t.tracker.expire(last_fix + 2 * kSecond + kSecond / 2, laser_only(rack.view()));
  ASSERT_EQ(t.tracker.tracks().size(), 1u) << "the stray, unconfirmed, ended at expire_s";
  EXPECT_TRUE(t.tracker.tracks()[0].hidden);
  msg::People people = t.publish(last_fix + 2 * kSecond + kSecond / 2);
  ASSERT_EQ(people.count, 1u);
  const msg::TrackedPerson& p = people.items[0];
  EXPECT_TRUE(p.hidden);
  EXPECT_NEAR(p.x_m, 3.0, 0.1);
  EXPECT_NEAR(p.y_m, 0.5, 0.15) << "coasted for coast_s, then held";
  EXPECT_EQ(p.vy_m_s, 0.0) << "held: no velocity";
  EXPECT_GT(p.position_sigma_m, 0.3);
  EXPECT_GT(p.cage_radius_m, base_cage + 0.2);
  EXPECT_LE(p.cage_radius_m, base_cage + t.config.hidden_cage_growth_m + 1e-12);

  // The rack gone, a wall 0.4 m behind the place: the beam ends at it, not past the body and
  // its uncertainty.
  const Scan wall(3.4, 0.0, {}, last_fix + 3 * kSecond);
  t.tracker.expire(last_fix + 3 * kSecond, laser_only(wall.view()));
  ASSERT_EQ(t.tracker.tracks().size(), 1u);
  EXPECT_EQ(t.tracker.seen_empty(), 0u);

  // The laser sees the far wall at 8 m through the place: nobody there.
  const Scan clear(8.0, 0.0, {}, last_fix + 3 * kSecond + kSecond / 10);
  t.tracker.expire(last_fix + 3 * kSecond + kSecond / 10, laser_only(clear.view()));
  EXPECT_EQ(t.tracker.tracks().size(), 0u);
  EXPECT_EQ(t.tracker.seen_empty(), 1u);
  EXPECT_EQ(t.tracker.forgotten(), 0u);
}

// A scan taken before the last fix saw the place before the person came: no evidence.
TEST(HiddenPeople, OnlyAScanAfterTheLastFixCanShowThePlaceEmpty) {
  HiddenTracker t;
  const hal::Nanos last_fix = t.stand(3.0, 0.0, 0);
  const Scan old_clear(8.0, 0.0, {}, last_fix - kSecond / 10);
  t.tracker.expire(last_fix + 3 * kSecond, laser_only(old_clear.view()));
  ASSERT_EQ(t.tracker.tracks().size(), 1u);
  EXPECT_TRUE(t.tracker.tracks()[0].hidden);
  // Nothing left to tell hidden from gone (no scan, no sonar): ended as before.
  t.tracker.expire(last_fix + 3 * kSecond + kSecond / 10);
  EXPECT_EQ(t.tracker.tracks().size(), 0u);
}

// Behind the robot the laser cannot see (its field is the front half): the person is kept while
// no sonar covers the place, kept alive past hidden_max_s by rear echoes from about their
// distance, and released by a rear reading well past them. All without allocating.
TEST(HiddenPeople, APersonBehindTheRobotIsKeptByRearEchoesAndReleasedByAReadingPastThem) {
  PersonTrackerConfig config;
  config.keep_hidden = true;
  config.hidden_max_s = 3.0;
  HiddenTracker t(config);
  // Standing 2 m behind the robot (at the origin, facing +x, the laser on its centre).
  const hal::Nanos last_fix = t.stand(-2.0, 0.0, 0);
  const Scan ahead(6.0, 0.0, {}, last_fix + kSecond);
  msg::Sonar sonar;
  sonar.count = 2;
  sonar.max_range_m = 5.0;
  sonar.mount[0] = {-0.2, 0.0, std::numbers::pi};          // straight back
  sonar.mount[1] = {-0.15, 0.15, std::numbers::pi / 2.0};  // left
  sonar.stamp_ns = {-1, -1};                  // not fired yet
  SensorCoverage coverage;
  coverage.sonar = &sonar;
  coverage.robot_pose = {0.0, 0.0, 0.0};

  mem::testing::AllocationScope scope;
  hal::Nanos now = last_fix + 2 * kSecond + kSecond / 2;
  msg::ScanView view = ahead.view();
  coverage.scan = &view;
  t.tracker.expire(now, coverage);
  ASSERT_EQ(t.tracker.tracks().size(), 1u) << "out of the laser's field, and no sonar reading";
  EXPECT_TRUE(t.tracker.tracks()[0].hidden);
  // The left disc reads nothing to 5 m, but its cone is nowhere near the place.
  sonar.stamp_ns[1] = now;
  sonar.range_m[1] = 5.0;
  t.tracker.expire(now, coverage);
  ASSERT_EQ(t.tracker.tracks().size(), 1u);

  // Echoes from the body's near side (1.8 m from the disc, less the body's 0.25 m radius, a
  // little off) every half second until 8 s after the last fix: kept past hidden_max_s.
  msg::People people;
  for (now = last_fix + 3 * kSecond; now <= last_fix + 8 * kSecond; now += kSecond / 2) {
    sonar.stamp_ns[0] = now;
    sonar.range_m[0] = 1.55 + 0.2;
    view.stamp_ns = now;
    t.tracker.expire(now, coverage);
    t.tracker.publish(now, people);
    ASSERT_EQ(t.tracker.tracks().size(), 1u) << static_cast<double>(now - last_fix) * 1e-9;
  }
  EXPECT_EQ(scope.allocations(), 0u);
  ASSERT_EQ(people.count, 1u);
  EXPECT_TRUE(people.items[0].hidden);
  EXPECT_NEAR(people.items[0].x_m, -2.0, 1e-9);
  // Something nearer than the person (an echo at 0.8 m) neither keeps nor releases them; the
  // clock set by the last echo runs on.
  sonar.range_m[0] = 0.8;
  t.tracker.expire(now, coverage);
  EXPECT_EQ(t.tracker.tracks().size(), 1u);
  // The rear disc reads 4.5 m: it looked well past the place.
  now += kSecond / 2;
  sonar.stamp_ns[0] = now;
  sonar.range_m[0] = 4.5;
  t.tracker.expire(now, coverage);
  EXPECT_EQ(t.tracker.tracks().size(), 0u);
  EXPECT_EQ(t.tracker.seen_empty(), 1u);
}

// Without echoes the same person is forgotten hidden_max_s after hiding; a stale reading (older
// than sonar_max_age_s) is no echo.
TEST(HiddenPeople, AHiddenPersonIsForgottenAfterHiddenMaxS) {
  PersonTrackerConfig config;
  config.keep_hidden = true;
  config.hidden_max_s = 3.0;
  HiddenTracker t(config);
  const hal::Nanos last_fix = t.stand(-2.0, 0.0, 0);
  const Scan ahead(6.0, 0.0, {}, last_fix + kSecond);
  msg::Sonar sonar;
  sonar.count = 1;
  sonar.mount[0] = {-0.2, 0.0, std::numbers::pi};
  sonar.range_m[0] = 1.6;
  sonar.stamp_ns[0] = last_fix + kSecond / 10;  // one echo just after the last fix
  const msg::ScanView view = ahead.view();
  SensorCoverage coverage = laser_only(view);
  coverage.sonar = &sonar;
  const hal::Nanos hidden_at = last_fix + 2 * kSecond + kSecond / 10;
  t.tracker.expire(hidden_at, coverage);
  ASSERT_EQ(t.tracker.tracks().size(), 1u);
  t.tracker.expire(hidden_at + 2 * kSecond + 9 * kSecond / 10, coverage);
  ASSERT_EQ(t.tracker.tracks().size(), 1u);
  t.tracker.expire(hidden_at + 3 * kSecond + kSecond / 10, coverage);
  EXPECT_EQ(t.tracker.tracks().size(), 0u);
  EXPECT_EQ(t.tracker.forgotten(), 1u);
  EXPECT_EQ(t.tracker.seen_empty(), 0u);
}

// Unseen, the position's sigma grows (held: by hidden_wander_m2_s a second); the cage grows
// with it up to hidden_cage_growth_m, and past hidden_max_sigma_m the person is forgotten.
TEST(HiddenPeople, TheSigmaGrowsTheCageUpToItsCapAndEndsTheTrackAtItsOwn) {
  PersonTrackerConfig config;
  config.keep_hidden = true;
  config.hidden_max_s = 100.0;
  config.hidden_max_sigma_m = 0.8;
  config.hidden_cage_growth_m = 0.5;
  config.hidden_wander_m2_s = 0.1;
  HiddenTracker t(config);
  const hal::Nanos last_fix = t.stand(3.0, 0.0, 0);
  const Scan rack(6.0, 1.5, {{-0.2, 0.2}}, last_fix + kSecond);
  const double base_cage = 0.25 + config.safety_radius_m;
  double sigma_before = 0.0;
  for (const double age_s : {2.5, 3.0, 4.0, 5.0, 6.0}) {
    const hal::Nanos now = last_fix + static_cast<hal::Nanos>(age_s * 1e9);
    t.tracker.expire(now, laser_only(rack.view()));
    ASSERT_EQ(t.tracker.tracks().size(), 1u) << age_s;
    const msg::People people = t.publish(now);
    ASSERT_EQ(people.count, 1u);
    const msg::TrackedPerson& p = people.items[0];
    EXPECT_NEAR(p.position_sigma_m, std::sqrt(0.1 * age_s), 0.02) << age_s;
    EXPECT_GT(p.position_sigma_m, sigma_before);
    sigma_before = p.position_sigma_m;
    EXPECT_NEAR(p.cage_radius_m, base_cage + std::min(p.position_sigma_m, 0.5), 1e-9) << age_s;
  }
  // sqrt(0.1 * 6.5) = 0.81 m
  t.tracker.expire(last_fix + 6 * kSecond + kSecond / 2, laser_only(rack.view()));
  EXPECT_EQ(t.tracker.tracks().size(), 0u);
  EXPECT_EQ(t.tracker.forgotten(), 1u);
}

// A fix near a hidden track's place is the person again: a track, not hidden. And with every
// slot taken, a person seen takes the place of the one hidden longest.
TEST(HiddenPeople, AFixEndsTheHidingAndAPersonSeenTakesAHiddenOnesSlot) {
  PersonTrackerConfig config;
  config.keep_hidden = true;
  config.max_tracks = 2;
  HiddenTracker t(config);
  hal::Nanos now = t.stand(3.0, 0.0, 0);
  now = t.stand(3.0, 2.0, now + kSecond);
  const Scan rack(6.0, 1.0, {{-0.3, 0.8}}, now);
  now += 2 * kSecond + kSecond / 2;
  t.tracker.expire(now, laser_only(rack.view()));
  ASSERT_EQ(t.tracker.tracks().size(), 2u);
  EXPECT_TRUE(t.tracker.tracks()[0].hidden);
  EXPECT_TRUE(t.tracker.tracks()[1].hidden);
  // The second seen again, 0.3 m from where they were.
  now = t.stand(3.3, 2.0, now, 1);
  ASSERT_EQ(t.tracker.tracks().size(), 2u);
  EXPECT_EQ(t.tracker.tracks()[1].id, 2u);
  EXPECT_FALSE(t.tracker.tracks()[1].hidden);
  EXPECT_TRUE(t.publish(now).items[0].hidden);
  EXPECT_FALSE(t.publish(now).items[1].hidden);
  // Someone new at (1, -1): the first, hidden longest, makes room.
  now = t.stand(1.0, -1.0, now, 1);
  ASSERT_EQ(t.tracker.tracks().size(), 2u);
  EXPECT_EQ(t.tracker.tracks()[0].id, 3u);
  EXPECT_EQ(t.tracker.tracks()[1].id, 2u);
  EXPECT_EQ(t.tracker.forgotten(), 1u);
}

// Keeping switched off: the old rule, every track ends expire_s after its last fix.
TEST(HiddenPeople, SwitchedOffEveryTrackEndsAtExpireS) {
  PersonTrackerConfig config;
  config.keep_hidden = false;
  HiddenTracker t(config);
  const hal::Nanos last_fix = t.stand(3.0, 0.0, 0);
  const Scan rack(6.0, 1.5, {{-0.2, 0.2}}, last_fix + kSecond);
  t.tracker.expire(last_fix + 2 * kSecond + kSecond / 10, laser_only(rack.view()));
  EXPECT_EQ(t.tracker.tracks().size(), 0u);

  PersonTrackerConfig bad;
  bad.hidden_max_sigma_m = 0.0;
  mem::BudgetArena arena{"people", 64 * 1024};
  PersonTracker refused;
  const Status s = refused.init(bad, arena);
  ASSERT_FALSE(s);
  EXPECT_NE(std::string(s.error().c_str()).find("hidden_max_sigma_m"), std::string::npos);
  bad = {};
  bad.sonar_half_angle_rad = std::numbers::pi / 2.0;
  EXPECT_FALSE(refused.init(bad, arena));
}

// On the bus: the task gives the tracker its newest posed scan and the sonar ring. A person seen
// 2 m ahead is hidden by a post the robot's laser sees first, and released when a front disc,
// whose cone passes beside the post, reads well past them.
TEST(HiddenPeople, ThePeopleTaskKeepsAPersonBehindAPostUntilTheSonarLooksPast) {
  const OccupancyMap map(200, 200, 0.05, 0.0, 0.0);
  tasks::Topic<msg::ScanMessage> scans;
  tasks::Topic<msg::PoseEstimate> poses;
  tasks::Topic<msg::PersonDetections> detections;
  tasks::Topic<msg::People> people;
  tasks::Topic<msg::Sonar> sonar;
  PeopleTaskConfig with_hidden;
  with_hidden.tracker.keep_hidden = true;
  PeopleTask task(with_hidden, map, {.scan = scans, .pose = poses, .detections = detections, .people = people, .sonar = &sonar});
  mem::BudgetArena arena{"people task", 1 << 20};
  ASSERT_TRUE(task.init(arena));
  const Pose2D robot{1.0, 5.0, 0.0};
  hal::Nanos now = 0;
  std::uint64_t cycle = 0;
  // A scan from the robot, posed by the localization at once.
  const auto scan_and_pose = [&](const Scan& s) {
    msg::ScanMessage m;
    std::copy(s.ranges.begin(), s.ranges.end(), m.ranges_m.begin());
    m.count = static_cast<std::uint16_t>(s.ranges.size());
    m.angle_min_rad = static_cast<float>(-std::numbers::pi / 2);
    m.increment_rad = static_cast<float>(std::numbers::pi / 360.0);
    m.range_min_m = 0.05f;
    m.range_max_m = 30.0f;
    m.stamp_ns = now;
    scans.publish(m, now);
    msg::PoseEstimate e;
    e.valid = true;
    e.pose = e.scan_pose = robot;
    e.scan_stamp_ns = now;
    poses.publish(e, now);
  };
  tasks::Sample<msg::People> got;
  // Legs 2 m ahead in front of a wall at 4 m, and a box around them, at 10 Hz for a second.
  for (int k = 0; k < 10; ++k) {
    now += kSecond / 10;
    scan_and_pose(Scan(4.0, 2.0, {{-0.06, 0.06}}, now));
    msg::PersonDetections frame;
    double ul = 0, vl = 0, ur = 0, vr = 0;
    ASSERT_TRUE(task.fusion().projection().project(2.0, 0.25, ul, vl));
    ASSERT_TRUE(task.fusion().projection().project(2.0, -0.25, ur, vr));
    frame.boxes[0] = {static_cast<float>(ul), 0.0f, static_cast<float>(ur), 719.0f, 0.9f, 0};
    frame.count = 1;
    frame.capture_ns = now;
    detections.publish(frame, now);
    task.step({now, now, cycle++});
  }
  ASSERT_TRUE(people.read(got));
  ASSERT_EQ(got.value.count, 1u);
  EXPECT_FALSE(got.value.items[0].hidden);
  EXPECT_NEAR(got.value.items[0].x_m, 3.0 + 0.1, 0.15);
  // A post 1 m ahead, 0.25 m wide, hides them from the laser; no boxes. Past expire_s: hidden.
  for (int k = 0; k < 30; ++k) {
    now += kSecond / 10;
    scan_and_pose(Scan(4.0, 1.0, {{-0.125, 0.125}}, now));
    task.step({now, now, cycle++});
  }
  ASSERT_TRUE(people.read(got));
  ASSERT_EQ(got.value.count, 1u);
  EXPECT_TRUE(got.value.items[0].hidden);
  EXPECT_GT(got.value.items[0].position_sigma_m, 0.0);
  // The front-left disc, 0.15 m left of the laser and turned 4.5 degrees right, reads 4.5 m.
  msg::Sonar ring;
  ring.count = 1;
  ring.mount[0] = {0.1, 0.15, -4.5 * std::numbers::pi / 180.0};
  ring.range_m[0] = 4.5;
  ring.stamp_ns[0] = now;
  sonar.publish(ring, now);
  now += kSecond / 10;
  scan_and_pose(Scan(4.0, 1.0, {{-0.125, 0.125}}, now));
  task.step({now, now, cycle++});
  ASSERT_TRUE(people.read(got));
  EXPECT_EQ(got.value.count, 0u);
  EXPECT_EQ(task.tracker().seen_empty(), 1u);
}

}  // namespace
}  // namespace sen3bot::nav
