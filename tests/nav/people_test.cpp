// Camera-laser fusion: the thesis' projection, people placed from the returns in their boxes,
// and the tracks with their cages.
#include <gtest/gtest.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/mem/budget_arena.hpp"
#include "sen3bot/nav/nav_tasks.hpp"
#include "sen3bot/nav/people.hpp"

namespace sen3bot::nav {
namespace {


TEST(CameraProjection, TheThesisCalibrationGivesTheHandComputedPixels) {
  CameraProjection camera;
  ASSERT_TRUE(camera.set({}));
  // c = K (Phi^-1 L - Delta) with L = (-left, 0, forward), worked out by hand (Phi^-1 by the
  // adjugate: det Phi = 0.999968).
  const struct {
    double forward, left, u, v;
  } cases[] = {{2.0, 0.0, 742.186, 146.737}, {1.0, 0.5, 73.666, 286.553}, {6.0, -1.0, 954.417, 55.936},
               {3.0, 0.2, 648.083, 101.100}};
  for (const auto& c : cases) {
    double u = 0, v = 0;
    ASSERT_TRUE(camera.project(c.forward, c.left, u, v)) << c.forward << ", " << c.left;
    EXPECT_NEAR(u, c.u, 0.01) << c.forward << ", " << c.left;
    EXPECT_NEAR(v, c.v, 0.01) << c.forward << ", " << c.left;
  }
}

TEST(CameraProjection, BehindTheCameraOrOutsideTheImageNeverMatches) {
  CameraProjection camera;
  ASSERT_TRUE(camera.set({}));
  double u = 0, v = 0;
  EXPECT_FALSE(camera.project(-2.0, 0.0, u, v));  // behind
  EXPECT_FALSE(camera.project(0.0, 1.0, u, v));   // beside the laser: depth 0
  EXPECT_FALSE(camera.project(1.0, 2.0, u, v));   // far left of the image
  EXPECT_FALSE(camera.project(1.0, -2.0, u, v));  // far right
  EXPECT_FALSE(camera.project(0.3, 0.0, u, v));   // below the image's bottom edge
  CameraCalibration singular;
  singular.phi = {1, 0, 0, 0, 0, 0, 0, 0, 1};
  EXPECT_FALSE(camera.set(singular));
}

// A 361-beam, 180-degree scan: a wall at wall_m everywhere, and legs at leg_m across the
// bearings in legs (radians).
std::vector<float> scan_ranges(double wall_m, double leg_m, std::vector<std::pair<double, double>> legs) {
  std::vector<float> r(361);
  for (std::size_t i = 0; i < r.size(); ++i) {
    const double a = -std::numbers::pi / 2 + static_cast<double>(i) * std::numbers::pi / 360.0;
    r[i] = static_cast<float>(wall_m / std::max(std::cos(a), 0.05));  // a straight wall ahead
    for (const auto& [lo, hi] : legs)
      if (a >= lo && a <= hi) r[i] = static_cast<float>(leg_m);
  }
  return r;
}

msg::ScanView view_of(const std::vector<float>& r, hal::Nanos stamp) {
  return {r, static_cast<float>(-std::numbers::pi / 2), static_cast<float>(std::numbers::pi / 360.0), 0.05f, 30.0f, stamp};
}

// The box a detector would draw around a person standing at (forward, left), 0.5 m wide.
msg::PersonBox box_around(const CameraProjection& camera, double forward, double left) {
  double ul = 0, vl = 0, ur = 0, vr = 0;
  EXPECT_TRUE(camera.project(forward, left + 0.25, ul, vl));
  EXPECT_TRUE(camera.project(forward, left - 0.25, ur, vr));
  // Tall enough for every return near that range in the laser's plane.
  return {static_cast<float>(ul), 0.0f, static_cast<float>(ur), 719.0f, 0.9f, 0};
}

struct Fusion {
  explicit Fusion(const OccupancyMap* map = nullptr, FusionConfig config = {}) {
    EXPECT_TRUE(fusion.init(config, {}, map, 401, arena));
  }
  mem::BudgetArena arena{"fusion", 64 * 1024};
  PeopleFusion fusion;
};

TEST(PeopleFusion, ABoxOnLegsGivesTheLegsPosition) {
  Fusion f;
  // Legs 2.5 m ahead, 0.3 m to the left (two legs: two narrow bearing ranges), wall at 6 m.
  const double bearing = std::atan2(0.3, 2.5);
  const std::vector<float> r =
      scan_ranges(6.0, std::hypot(2.5, 0.3), {{bearing - 0.05, bearing - 0.02}, {bearing + 0.02, bearing + 0.05}});
  msg::PersonDetections frame;
  frame.boxes[0] = box_around(f.fusion.projection(), 2.5, 0.3);
  frame.count = 1;
  frame.capture_ns = 1'000'000'000;
  PersonFix fixes[4];
  // The laser at (1, 2) on the map, facing +y: forward is +y, left is -x.
  const std::size_t n = f.fusion.fuse(view_of(r, 1'020'000'000), {1.0, 2.0, std::numbers::pi / 2}, frame, fixes);
  ASSERT_EQ(n, 1u);
  // Between the legs and 0.05-0.15 m behind their fronts, along the ray: where the body is.
  const double along = ((fixes[0].x_m - 1.0) * -0.3 + (fixes[0].y_m - 2.0) * 2.5) / std::hypot(2.5, 0.3);
  const double across = ((fixes[0].x_m - 1.0) * 2.5 - (fixes[0].y_m - 2.0) * -0.3) / std::hypot(2.5, 0.3);
  EXPECT_NEAR(across, 0.0, 0.02);
  EXPECT_GT(along - std::hypot(2.5, 0.3), 0.05);
  EXPECT_LT(along - std::hypot(2.5, 0.3), 0.15);
  EXPECT_GE(fixes[0].points, 6);
  EXPECT_NEAR(fixes[0].width_m, 0.5, 0.05);
  EXPECT_EQ(f.fusion.count(BoxVerdict::located), 1u);
}

TEST(PeopleFusion, ABoxWithOnlyTheMapsBackgroundGivesNobody) {
  // The map: a wall 4 m ahead of the laser at (0, 5) facing +x.
  OccupancyMap map(200, 200, 0.05, 0.0, 0.0);
  for (int row = 0; row < 200; ++row)
    for (int col = 80; col < 82; ++col) map.set(col, row, 100);
  Fusion f(&map);
  const std::vector<float> empty = scan_ranges(4.0, 0.0, {});
  msg::PersonDetections frame;
  frame.boxes[0] = box_around(f.fusion.projection(), 3.0, 0.0);
  frame.count = 1;
  PersonFix fixes[2];
  EXPECT_EQ(f.fusion.fuse(view_of(empty, 0), {0.0, 5.0, 0.0}, frame, fixes), 0u);
  EXPECT_EQ(f.fusion.count(BoxVerdict::no_returns), 1u);
  // Someone in front of that wall is found, the wall behind them left out.
  const std::vector<float> legs = scan_ranges(4.0, 3.0, {{-0.04, 0.04}});
  ASSERT_EQ(f.fusion.fuse(view_of(legs, 0), {0.0, 5.0, 0.0}, frame, fixes), 1u);
  EXPECT_GT(fixes[0].x_m, 3.05);  // behind the returns, not on them
  EXPECT_LT(fixes[0].x_m, 3.15);
  EXPECT_NEAR(fixes[0].y_m, 5.0, 0.03);
}

// A round body (the simulated person: a disc) is placed at its centre, not on its near side,
// from 1.2 to 6 m and across the image, within 5 cm (half the fusion's target error).
TEST(PeopleFusion, ARoundBodyIsPlacedAtItsCentre) {
  Fusion f;
  for (const double radius : {0.15, 0.225}) {
    for (const double forward : {1.2, 2.5, 4.0, 6.0}) {
      for (const double across : {-0.15, 0.0, 0.25}) {  // within the camera's view
        const double left = across * forward;
        std::vector<float> r(361);
        const double d = std::hypot(forward, left);
        for (std::size_t i = 0; i < r.size(); ++i) {
          const double a = -std::numbers::pi / 2 + static_cast<double>(i) * std::numbers::pi / 360.0;
          // Ray (cos a, sin a) against the circle at (forward, left).
          const double b = forward * std::cos(a) + left * std::sin(a);
          const double disc = b * b - (d * d - radius * radius);
          r[i] = disc >= 0.0 ? static_cast<float>(b - std::sqrt(disc)) : 29.0f;
        }
        msg::PersonDetections frame;
        frame.boxes[0] = box_around(f.fusion.projection(), forward, left);
        frame.count = 1;
        PersonFix fixes[2];
        ASSERT_EQ(f.fusion.fuse(view_of(r, 0), {0.0, 0.0, 0.0}, frame, fixes), 1u) << forward << ", " << left;
        EXPECT_NEAR(fixes[0].x_m, forward, 0.05) << radius << " at " << forward << ", " << left;
        EXPECT_NEAR(fixes[0].y_m, left, 0.05) << radius << " at " << forward << ", " << left;
      }
    }
  }
}

// A body partly hidden behind something nearer (a post, another person) is marked partial:
// the mean of its returns is off towards the part in view, its range is not.
TEST(PeopleFusion, ABodyCutBySomethingNearerIsPartial) {
  Fusion f;
  const auto body = [](double post_from, double post_to) {
    // A disc of radius 0.225 at 3 m straight ahead; a post 1.5 m ahead across the bearings given.
    std::vector<float> r(361);
    for (std::size_t i = 0; i < r.size(); ++i) {
      const double a = -std::numbers::pi / 2 + static_cast<double>(i) * std::numbers::pi / 360.0;
      const double b = 3.0 * std::cos(a);
      const double disc = b * b - (9.0 - 0.225 * 0.225);
      r[i] = disc >= 0.0 ? static_cast<float>(b - std::sqrt(disc)) : 29.0f;
      if (a >= post_from && a <= post_to) r[i] = 1.5f;
    }
    return r;
  };
  msg::PersonDetections frame;
  frame.boxes[0] = box_around(f.fusion.projection(), 3.0, 0.0);
  frame.count = 1;
  PersonFix fixes[2];
  const std::vector<float> clear = body(1.0, 1.1);  // the post far off to the side
  ASSERT_EQ(f.fusion.fuse(view_of(clear, 0), {0.0, 0.0, 0.0}, frame, fixes), 1u);
  EXPECT_FALSE(fixes[0].partial);
  EXPECT_NEAR(fixes[0].ray_x, 1.0, 1e-3);
  EXPECT_NEAR(fixes[0].ray_y, 0.0, 1e-3);
  // The post hides the body's left half and the detector boxes the right half it sees: the
  // fix is off to the right, and says so.
  const std::vector<float> hidden = body(0.03, 0.3);
  double u0 = 0, u1 = 0, v = 0;
  ASSERT_TRUE(f.fusion.projection().project(3.0, -0.01, u0, v));
  ASSERT_TRUE(f.fusion.projection().project(3.0, -0.3, u1, v));
  frame.boxes[0] = {static_cast<float>(u0), 0.0f, static_cast<float>(u1), 719.0f, 0.9f, 0};
  ASSERT_EQ(f.fusion.fuse(view_of(hidden, 0), {0.0, 0.0, 0.0}, frame, fixes), 1u);
  EXPECT_TRUE(fixes[0].partial);
  EXPECT_LT(fixes[0].y_m, -0.03);
  EXPECT_NEAR(std::hypot(fixes[0].x_m, fixes[0].y_m), 3.0, 0.08);
}

TEST(PeopleFusion, EachRejectedBoxIsCountedWithItsReason) {
  FusionConfig config;
  config.match_window_s = 0.15;
  Fusion f(nullptr, config);
  const std::vector<float> r = scan_ranges(6.0, 2.0, {{-0.04, 0.04}});
  msg::PersonDetections frame;
  frame.boxes[0] = box_around(f.fusion.projection(), 2.0, 0.0);
  frame.boxes[1] = frame.boxes[0];
  frame.boxes[1].class_id = 56;  // a chair
  frame.boxes[2] = frame.boxes[0];
  frame.boxes[2].confidence = 0.1f;
  frame.count = 3;
  frame.capture_ns = 5'000'000'000;
  PersonFix fixes[4];
  // The scan 0.149 s after the frame: in the window.
  EXPECT_EQ(f.fusion.fuse(view_of(r, 5'149'000'000), {}, frame, fixes), 1u);
  EXPECT_EQ(f.fusion.count(BoxVerdict::located), 1u);
  EXPECT_EQ(f.fusion.count(BoxVerdict::other_class), 1u);
  EXPECT_EQ(f.fusion.count(BoxVerdict::low_confidence), 1u);
  // 0.151 s after, or before: outside it.
  EXPECT_EQ(f.fusion.fuse(view_of(r, 5'151'000'000), {}, frame, fixes), 0u);
  EXPECT_EQ(f.fusion.fuse(view_of(r, 4'849'000'000), {}, frame, fixes), 0u);
  EXPECT_EQ(f.fusion.count(BoxVerdict::out_of_window), 2u);
  EXPECT_EQ(f.fusion.count(BoxVerdict::other_class), 3u);
  EXPECT_EQ(f.fusion.count(BoxVerdict::located), 1u);
  // Nothing but beams out of range in the box: nobody.
  const std::vector<float> none(361, 50.0f);
  EXPECT_EQ(f.fusion.fuse(view_of(none, 5'000'000'000), {}, frame, fixes), 0u);
  EXPECT_EQ(f.fusion.count(BoxVerdict::no_returns), 1u);
}

TEST(PeopleFusion, FusingAllocatesNothing) {
  Fusion f;
  const std::vector<float> r = scan_ranges(6.0, 2.0, {{-0.04, 0.04}});
  msg::PersonDetections frame;
  for (int i = 0; i < 8; ++i)
    frame.boxes[static_cast<std::size_t>(i)] = box_around(f.fusion.projection(), 2.0, -0.5 + 0.125 * i);
  frame.count = 8;
  PersonFix fixes[8];
  mem::testing::AllocationScope scope;
  (void)f.fusion.fuse(view_of(r, 0), {}, frame, fixes);
  EXPECT_EQ(scope.allocations(), 0u);
}

// --- Tracking ---

struct Tracker {
  explicit Tracker(PersonTrackerConfig config = {}) { EXPECT_TRUE(tracker.init(config, arena)); }
  mem::BudgetArena arena{"people", 64 * 1024};
  PersonTracker tracker;
};

PersonFix fix_at(double x, double y, double width = 0.5) {
  PersonFix f;
  f.x_m = x;
  f.y_m = y;
  f.width_m = width;
  f.points = 10;
  return f;
}

TEST(PersonTracker, StaticUntilMovedFartherThanTheThresholdFromWhereFirstSeen) {
  PersonTrackerConfig config;
  config.fix_sigma_m = 1e-5;  // the fix is the position: the threshold is exact
  config.dynamic_after_m = 1.0;
  Tracker t(config);
  hal::Nanos now = 0;
  for (const double x : {0.0, 0.25, 0.5, 0.75, 1.0 - 1e-6}) {
    const PersonFix f = fix_at(2.0 + x, 3.0);
    t.tracker.update(std::span(&f, 1), now += 100'000'000);
  }
  ASSERT_EQ(t.tracker.tracks().size(), 1u);
  EXPECT_EQ(t.tracker.tracks()[0].state, msg::PersonState::static_person);  // just short of 1 m
  const PersonFix beyond = fix_at(3.0 + 1e-6, 3.0);
  t.tracker.update(std::span(&beyond, 1), now += 100'000'000);
  EXPECT_EQ(t.tracker.tracks()[0].state, msg::PersonState::dynamic_person);
  // It stays dynamic: the person has shown that they move.
  const PersonFix back = fix_at(2.5, 3.0);
  t.tracker.update(std::span(&back, 1), now += 100'000'000);
  EXPECT_EQ(t.tracker.tracks()[0].state, msg::PersonState::dynamic_person);
  EXPECT_EQ(t.tracker.tracks()[0].id, 1u);
}

TEST(PersonTracker, TwoPeopleKeepTheirIdsAndCagesExpireWithoutDetections) {
  PersonTrackerConfig config;
  config.expire_s = 1.0;
  config.safety_radius_m = 0.4;
  Tracker t(config);
  hal::Nanos now = 0;
  // Walking towards each other along parallel lines 1.2 m apart, 1 m/s each, 10 Hz.
  for (int k = 0; k < 30; ++k) {
    const PersonFix fixes[2] = {fix_at(0.1 * k, 0.0, 0.6), fix_at(3.0 - 0.1 * k, 1.2, 0.4)};
    t.tracker.update(fixes, now += 100'000'000);
  }
  ASSERT_EQ(t.tracker.tracks().size(), 2u);
  EXPECT_EQ(t.tracker.started(), 2u);
  msg::People people;
  t.tracker.publish(now, people);
  ASSERT_EQ(people.count, 2);
  for (std::size_t i = 0; i < 2; ++i) {
    const msg::TrackedPerson& p = people.items[i];
    if (p.id == 1) {
      EXPECT_NEAR(p.x_m, 2.9, 0.05);
      EXPECT_NEAR(p.y_m, 0.0, 0.05);
      EXPECT_NEAR(p.vx_m_s, 1.0, 0.1);
      EXPECT_NEAR(p.cage_radius_m, 0.3 + 0.4, 1e-9);
    } else {
      EXPECT_EQ(p.id, 2u);
      EXPECT_NEAR(p.x_m, 0.1, 0.05);
      EXPECT_NEAR(p.vx_m_s, -1.0, 0.1);
      EXPECT_NEAR(p.cage_radius_m, 0.2 + 0.4, 1e-9);
    }
    EXPECT_EQ(p.state, msg::PersonState::dynamic_person);
  }
  // Seen no more: the cages last expire_s, then end.
  t.tracker.expire(now + 900'000'000);
  EXPECT_EQ(t.tracker.tracks().size(), 2u);
  mem::testing::AllocationScope scope;
  t.tracker.expire(now + 1'100'000'000);
  t.tracker.publish(now + 1'100'000'000, people);
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(t.tracker.tracks().size(), 0u);
  EXPECT_EQ(people.count, 0);
}

// The Kalman filter: a walker seen from a standing start has their pace within a second; a
// fix whose body was cut moves the track along the ray, hardly across it.
TEST(PersonTracker, AWalkersVelocityIsFoundInASecondAndAPartialFixMovesOnlyTheRange) {
  Tracker t;
  hal::Nanos now = 0;
  for (int k = 0; k <= 5; ++k) {  // 1 m/s along +x at 5 fixes a second
    const PersonFix f = fix_at(2.0 + 0.2 * k, 3.0);
    t.tracker.update(std::span(&f, 1), now += 200'000'000);
  }
  ASSERT_EQ(t.tracker.tracks().size(), 1u);
  EXPECT_NEAR(t.tracker.tracks()[0].velocity.x_m, 1.0, 0.1);
  EXPECT_NEAR(t.tracker.tracks()[0].at.x_m, 3.0, 0.03);
  // Standing still from then on, seen from (3, 0) so the ray is +y: a fix 0.3 m to the side
  // (across the ray) and 0.1 m farther (along it), cut short by something nearer.
  Tracker still;
  for (int k = 0; k < 10; ++k) {
    const PersonFix f = fix_at(3.0, 3.0);
    still.tracker.update(std::span(&f, 1), now += 200'000'000);
  }
  PersonFix cut = fix_at(3.3, 3.1);
  cut.ray_x = 0.0;
  cut.ray_y = 1.0;
  cut.partial = true;
  still.tracker.update(std::span(&cut, 1), now += 200'000'000);
  const PersonTracker::Track& moved = still.tracker.tracks()[0];
  // The same fix, whole, moves it across as far as along.
  Tracker whole;
  for (int k = 0; k < 10; ++k) {
    const PersonFix f = fix_at(3.0, 3.0);
    whole.tracker.update(std::span(&f, 1), now += 200'000'000);
  }
  cut.partial = false;
  whole.tracker.update(std::span(&cut, 1), now += 200'000'000);
  const PersonTracker::Track& full = whole.tracker.tracks()[0];
  EXPECT_NEAR(moved.at.y_m - 3.0, full.at.y_m - 3.0, 0.01);  // the range: taken alike
  EXPECT_GT(full.at.x_m - 3.0, 0.15);
  EXPECT_LT(moved.at.x_m - 3.0, 0.5 * (full.at.x_m - 3.0));  // across: much less
}

TEST(PersonTracker, AFixOutsideTheGateStartsANewTrackAndBadConfigurationsAreRefused) {
  Tracker t;
  const PersonFix a = fix_at(0.0, 0.0);
  const PersonFix b = fix_at(2.0, 0.0);
  t.tracker.update(std::span(&a, 1), 100'000'000);
  t.tracker.update(std::span(&b, 1), 200'000'000);
  EXPECT_EQ(t.tracker.tracks().size(), 2u);
  mem::BudgetArena arena("bad", 4096);
  PersonTracker bad;
  PersonTrackerConfig config;
  config.max_tracks = 40;
  EXPECT_FALSE(bad.init(config, arena));
  config = {};
  config.fix_sigma_m = 0.0;
  EXPECT_FALSE(bad.init(config, arena));
  config = {};
  config.accel_sigma_m_s2 = -1.0;
  EXPECT_FALSE(bad.init(config, arena));
}

// --- The cages ---

// A stray box (a false detection) is not a person: a track is published from its third box on.
TEST(PersonTracker, ATrackIsPublishedOnlyOnceConfirmed) {
  PersonTrackerConfig config;
  config.confirm_hits = 3;
  Tracker t(config);
  msg::People people;
  hal::Nanos now = 0;
  for (int k = 1; k <= 3; ++k) {
    const PersonFix f = fix_at(2.0, 3.0);
    t.tracker.update(std::span(&f, 1), now += 100'000'000);
    t.tracker.publish(now, people);
    EXPECT_EQ(people.count, k < 3 ? 0u : 1u) << k;
  }
  // A single box elsewhere starts a track that is never published.
  const PersonFix stray = fix_at(6.0, 1.0);
  t.tracker.update(std::span(&stray, 1), now += 100'000'000);
  t.tracker.publish(now, people);
  EXPECT_EQ(t.tracker.tracks().size(), 2u);
  ASSERT_EQ(people.count, 1u);
  EXPECT_NEAR(people.items[0].x_m, 2.0, 1e-9);
}

// A confirmed person who leaves the camera's view is followed by the laser (position and
// velocity, not width) for laser_follow_s after the last box, and the track lives on while the
// laser finds them; an unconfirmed track is never followed.
TEST(PersonTracker, TheLaserFollowsAPersonOutOfViewForAWhile) {
  PersonTrackerConfig config;
  config.laser_follow_s = 2.0;
  config.expire_s = 1.0;
  config.dynamic_after_m = 0.15;  // walking from the start
  Tracker t(config);
  hal::Nanos now = 0;
  for (int k = 0; k < 3; ++k) {
    const PersonFix f = fix_at(2.0 + 0.1 * k, 3.0, 0.4);
    t.tracker.update(std::span(&f, 1), now += 100'000'000);
  }
  const PersonFix stray = fix_at(6.0, 1.0);
  t.tracker.update(std::span(&stray, 1), now);
  Point2D predicted[4];
  std::uint8_t which[4];
  // Walking on at 1 m/s, seen only by the laser.
  double x = 2.2;
  for (int k = 0; k < 15; ++k) {
    now += 100'000'000;
    x += 0.1;
    const std::size_t n = t.tracker.followable(now, predicted, which);
    ASSERT_EQ(n, 1u) << k;  // the stray one is not followed
    EXPECT_NEAR(predicted[0].x_m, x, 0.1);
    t.tracker.follow(which[0], fix_at(x, 3.0, 9.0), now);
  }
  ASSERT_GE(t.tracker.tracks().size(), 1u);
  const PersonTracker::Track& track = t.tracker.tracks()[0];
  EXPECT_NEAR(track.at.x_m, x, 0.05);
  EXPECT_NEAR(track.velocity.x_m, 1.0, 0.15);
  EXPECT_NEAR(track.width_m, 0.4, 1e-9);  // the laser's fix has no width
  // 2 s after the last box: no longer followed, and it expires expire_s after the last fix.
  now += 600'000'000;
  EXPECT_EQ(t.tracker.followable(now, predicted, which), 0u);
  t.tracker.expire(now + 1'100'000'000);
  EXPECT_EQ(t.tracker.tracks().size(), 0u);
}

// Unseen, a standing person's cage stays where they stood, whatever their fixes' noise says
// about velocity; a walking one is carried on for coast_s, then held.
TEST(PersonTracker, StandingPeopleAreHeldAndWalkersCoastOnlyAWhile) {
  PersonTrackerConfig config;
  config.dynamic_after_m = 1.0;
  config.coast_s = 1.0;
  config.expire_s = 5.0;
  Tracker t(config);
  hal::Nanos now = 0;
  // Standing at (2, 3) with 3 cm of jitter, then a last fix 5 cm off.
  for (const double dx : {0.0, 0.03, -0.03, 0.02, 0.05}) {
    const PersonFix f = fix_at(2.0 + dx, 3.0);
    t.tracker.update(std::span(&f, 1), now += 100'000'000);
  }
  ASSERT_NE(t.tracker.tracks()[0].velocity.x_m, 0.0);  // the jitter's velocity
  msg::People people;
  t.tracker.publish(now + 3'000'000'000, people);
  ASSERT_EQ(people.count, 1u);
  EXPECT_EQ(people.items[0].state, msg::PersonState::static_person);
  EXPECT_NEAR(people.items[0].x_m, t.tracker.tracks()[0].at.x_m, 1e-12);
  EXPECT_EQ(people.items[0].vx_m_s, 0.0);
  // Walking at 1 m/s along +y from (6, 0): dynamic after 1 m, then unseen.
  Tracker w(config);
  now = 0;
  for (int k = 0; k <= 15; ++k) {
    const PersonFix f = fix_at(6.0, 0.1 * k);
    w.tracker.update(std::span(&f, 1), now += 100'000'000);
  }
  const double last_y = w.tracker.tracks()[0].at.y_m;
  w.tracker.publish(now + 500'000'000, people);
  EXPECT_EQ(people.items[0].state, msg::PersonState::dynamic_person);
  EXPECT_NEAR(people.items[0].y_m, last_y + 0.5, 0.08);
  EXPECT_NEAR(people.items[0].vy_m_s, 1.0, 0.15);
  w.tracker.publish(now + 3'000'000'000, people);
  EXPECT_NEAR(people.items[0].y_m, last_y + 1.0, 0.15);  // held after coast_s
}

TEST(PeopleFusion, TheLaserAloneFindsTheBodyNearEachPrediction) {
  OccupancyMap map(200, 200, 0.05, 0.0, 0.0);
  for (int row = 0; row < 200; ++row)
    for (int col = 80; col < 82; ++col) map.set(col, row, 100);  // a wall at x = 4 m
  Fusion f(&map);
  // A round body of radius 0.2 at (2.5, 5.5) seen from (0, 5) facing +x, the wall behind it.
  std::vector<float> r(361);
  for (std::size_t i = 0; i < r.size(); ++i) {
    const double a = -std::numbers::pi / 2 + static_cast<double>(i) * std::numbers::pi / 360.0;
    const double b = 2.5 * std::cos(a) + 0.5 * std::sin(a);
    const double disc = b * b - (2.5 * 2.5 + 0.5 * 0.5 - 0.04);
    r[i] = disc >= 0.0 ? static_cast<float>(b - std::sqrt(disc)) : static_cast<float>(4.0 / std::max(std::cos(a), 0.05));
  }
  const Point2D predicted[3] = {{2.35, 5.6}, {3.9, 5.0}, {1.0, 3.0}};  // near the body, on the wall, nothing
  PersonFix fixes[3];
  EXPECT_EQ(f.fusion.follow(view_of(r, 0), {0.0, 5.0, 0.0}, predicted, 0.45, fixes), 1u);
  EXPECT_NEAR(fixes[0].x_m, 2.5, 0.05);
  EXPECT_NEAR(fixes[0].y_m, 5.5, 0.05);
  EXPECT_EQ(fixes[1].points, 0);  // the map's wall is background
  EXPECT_EQ(fixes[2].points, 0);
  mem::testing::AllocationScope scope;
  (void)f.fusion.follow(view_of(r, 0), {0.0, 5.0, 0.0}, predicted, 0.45, fixes);
  EXPECT_EQ(scope.allocations(), 0u);
}

// The people layer under an inflation layer on a fixed 6 x 6 m grid.
struct CageGrid {
  explicit CageGrid(const msg::People& people, PeopleLayerConfig config = {}) : layer(people, config) {
    EXPECT_TRUE(costmap.add_layer(layer));
    EXPECT_TRUE(costmap.add_layer(inflation));
    CostmapConfig grid;
    grid.rolling = false;
    grid.width_m = 6.0;
    grid.height_m = 6.0;
    EXPECT_TRUE(costmap.init(grid, arena));
  }
  std::uint8_t cost_at(double x, double y) const {
    int col = 0, row = 0;
    EXPECT_TRUE(costmap.costmap().world_to_cell(x, y, col, row));
    return costmap.costmap().at(col, row);
  }
  PeopleLayer layer;
  InflationLayer inflation;
  LayeredCostmap costmap;
  mem::BudgetArena arena{"costmap", 1 << 20};
};

TEST(PeopleLayer, ACageIsALethalDiscThatFollowsThePersonAndExpires) {
  msg::People people;
  PeopleLayerConfig config;
  config.expire_s = 1.0;
  CageGrid g(people, config);
  PeopleLayer& layer = g.layer;
  LayeredCostmap& costmap = g.costmap;
  const auto cost_at = [&](double x, double y) { return g.cost_at(x, y); };
  // One person at (3, 3), 0.4 m wide, cage radius 0.2 + 0.5 m, walking +x at 1 m/s.
  people.count = 1;
  people.stamp_ns = 1'000'000'000;
  people.items[0] = {1, 3.0, 3.0, 1.0, 0.0, 0.4, 0.7, msg::PersonState::dynamic_person, 1'000'000'000, 12};
  costmap.update({{0.5, 0.5, 0.0}, {0.5, 0.5, 0.0}, nullptr, 1'000'000'000});
  EXPECT_EQ(layer.cages(), 1u);
  EXPECT_EQ(cost_at(3.0, 3.0), kLethalCost);
  EXPECT_EQ(cost_at(3.0 + 0.65, 3.0), kLethalCost);
  EXPECT_EQ(cost_at(3.0, 3.0 - 0.65), kLethalCost);
  EXPECT_LT(cost_at(3.0 + 0.75, 3.0), kLethalCost);    // outside the disc...
  EXPECT_GT(cost_at(3.0 + 0.75, 3.0), kFreeCost);      // ...inflated around it
  EXPECT_EQ(cost_at(1.0, 1.0), kFreeCost);
  // Half a second later without a new fix: painted where the velocity takes the person.
  costmap.update({{0.5, 0.5, 0.0}, {0.5, 0.5, 0.0}, nullptr, 1'500'000'000});
  EXPECT_EQ(cost_at(3.5 + 0.65, 3.0), kLethalCost);
  EXPECT_LT(cost_at(3.5 - 0.75, 3.0), kLethalCost);
  // Not seen for longer than expire_s: no cage.
  mem::testing::AllocationScope scope;
  costmap.update({{0.5, 0.5, 0.0}, {0.5, 0.5, 0.0}, nullptr, 2'100'000'000});
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(layer.cages(), 0u);
  EXPECT_EQ(cost_at(4.1, 3.0), kFreeCost);
}

// A hidden person (kept by the tracker past expire_s) keeps their cage while the list itself is
// current; not hidden, the same person is gone.
TEST(PeopleLayer, AHiddenPersonsCageLastsWhileTheListIsCurrent) {
  msg::People people;
  PeopleLayerConfig config;
  config.expire_s = 1.0;
  CageGrid g(people, config);
  const auto cost_at = [&](double x, double y) { return g.cost_at(x, y); };
  people.count = 1;
  people.stamp_ns = 10'000'000'000;
  people.items[0] = {1, 3.0, 3.0, 0.0, 0.0, 0.4, 0.9, msg::PersonState::static_person, 2'000'000'000, 12};
  people.items[0].hidden = true;
  people.items[0].position_sigma_m = 0.4;
  g.costmap.update({{0.5, 0.5, 0.0}, {0.5, 0.5, 0.0}, nullptr, 10'000'000'000});
  EXPECT_EQ(g.layer.cages(), 1u);
  EXPECT_EQ(cost_at(3.0 + 0.85, 3.0), kLethalCost);
  people.items[0].hidden = false;
  g.costmap.update({{0.5, 0.5, 0.0}, {0.5, 0.5, 0.0}, nullptr, 10'000'000'000});
  EXPECT_EQ(g.layer.cages(), 0u) << "not seen for 8 s and not hidden: gone";
  people.items[0].hidden = true;
  g.costmap.update({{0.5, 0.5, 0.0}, {0.5, 0.5, 0.0}, nullptr, 11'100'000'000});
  EXPECT_EQ(g.layer.cages(), 0u) << "the list is older than expire_s";
}

// A person 0.6 m from the robot (closer than cage plus robot): the cage shrinks to stop
// robot_clearance_m from the robot's centre, so the robot is not left inside a lethal region
// and can move away; backed off, the full cage is there again.
TEST(PeopleLayer, ACageNeverSwallowsTheRobot) {
  msg::People people;
  CageGrid g(people);
  const PeopleLayer& layer = g.layer;
  LayeredCostmap& costmap = g.costmap;
  const auto cost_at = [&](double x, double y) { return g.cost_at(x, y); };
  people.count = 1;
  people.stamp_ns = 1'000'000'000;
  people.items[0] = {1, 3.0, 3.0, 0.0, 0.0, 0.4, 0.7, msg::PersonState::static_person, 1'000'000'000, 12};
  const Pose2D robot{2.4, 3.0, 0.0};
  costmap.update({robot, robot, nullptr, 1'000'000'000});
  EXPECT_EQ(layer.cages(), 1u);
  EXPECT_EQ(cost_at(3.0, 3.0), kLethalCost);
  EXPECT_EQ(cost_at(3.3, 3.0), kLethalCost);         // 0.35 - 0.05 m: 0.6 - 0.25 is the radius now
  EXPECT_LT(cost_at(2.4, 3.0), kInscribedCost);      // the robot's centre can move
  EXPECT_LT(cost_at(2.2, 3.0), cost_at(2.4, 3.0));   // and away is cheaper
  // The robot backs off to 1.5 m: the full 0.7 m cage again.
  const Pose2D away{1.5, 3.0, 0.0};
  costmap.update({away, away, nullptr, 1'000'000'000});
  EXPECT_EQ(cost_at(3.0 - 0.65, 3.0), kLethalCost);
}

// --- Relayed people (perfect perception) ---

TEST(PeopleRelay, RepublishesTheSourcesPeopleWithTheTrackersCagesUntilTheListIsStale) {
  PersonTrackerConfig config;
  config.safety_radius_m = 0.5;
  config.min_width_m = 0.4;
  config.expire_s = 2.0;
  tasks::Topic<msg::People> source;
  tasks::Topic<msg::People> out;
  PeopleRelayTask relay(config, source, out);
  mem::BudgetArena arena{"people", 1024};
  ASSERT_TRUE(relay.init(arena));
  tasks::Sample<msg::People> got;

  relay.step({0, 0, 0});
  ASSERT_TRUE(out.read(got));
  EXPECT_EQ(got.value.count, 0u) << "nothing published yet: nobody";

  msg::People truth;
  truth.count = 2;
  truth.items[0] = {.id = 7, .x_m = 1.0, .y_m = 2.0, .vx_m_s = 1.2, .vy_m_s = 0.0, .width_m = 0.6};
  truth.items[0].state = msg::PersonState::dynamic_person;
  truth.items[1] = {.id = 9, .x_m = 3.0, .y_m = -1.0, .width_m = 0.2};
  source.publish(truth, hal::millis(100));
  mem::testing::AllocationScope scope;
  relay.step({hal::millis(150), hal::millis(150), 1});
  EXPECT_EQ(scope.allocations(), 0u);
  ASSERT_TRUE(out.read(got));
  EXPECT_EQ(got.stamp_ns, hal::millis(150));
  ASSERT_EQ(got.value.count, 2u);
  EXPECT_EQ(got.value.items[0].id, 7u);
  EXPECT_DOUBLE_EQ(got.value.items[0].vx_m_s, 1.2);
  EXPECT_EQ(got.value.items[0].state, msg::PersonState::dynamic_person);
  EXPECT_DOUBLE_EQ(got.value.items[0].cage_radius_m, 0.3 + 0.5);
  EXPECT_DOUBLE_EQ(got.value.items[1].cage_radius_m, 0.2 + 0.5) << "at least min_width_m wide";

  relay.step({hal::millis(2200), hal::millis(2200), 2});
  ASSERT_TRUE(out.read(got));
  EXPECT_EQ(got.value.count, 0u) << "a list older than expire_s is nobody";

  PersonTrackerConfig bad = config;
  bad.expire_s = 0.0;
  PeopleRelayTask refused(bad, source, out);
  EXPECT_FALSE(refused.init(arena));
}

}  // namespace
}  // namespace sen3bot::nav
