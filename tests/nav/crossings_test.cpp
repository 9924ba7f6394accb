// The crossing gate and the lanes: constructed crossings of a straight path along +x from the
// robot at the origin, a walker crossing it at x = 2 m.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory_resource>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/nav/crossings.hpp"

namespace sen3bot::nav {
namespace {

constexpr double kBodyM = 0.3;  // the Pioneer's circumscribed radius, about
constexpr double kMaxV = 0.5;
constexpr double kAcc = 0.6;

struct Bench {
  std::vector<msg::PathPoint> path;
  std::pmr::monotonic_buffer_resource arena{1 << 20};
  LaneMap lanes;
  CrossingGate gate;
  Bench() {
    for (int i = 1; i <= 60; ++i) path.push_back({static_cast<float>(0.1 * i), 0.0f});
    EXPECT_TRUE(lanes.init({}, -5.0, -5.0, 15.0, 10.0, arena));
    CrossingConfig on;
    on.enabled = true;
    EXPECT_TRUE(gate.init(on, kBodyM, kMaxV, kAcc));
  }
  // The robot at (x, 0) heading +x at v; the path from the point ahead of it on.
  CrossingDecision decide(double v, std::vector<CrossingTrack> tracks, double now_s = 100.0, double x = 0.0) {
    tracks_ = std::move(tracks);
    const auto ahead = std::find_if(path.begin(), path.end(), [x](const msg::PathPoint& p) { return p.x_m > x + 1e-3; });
    return gate.decide({{x, 0.0, 0.0}, v, std::span<const msg::PathPoint>(&*ahead, static_cast<std::size_t>(path.end() - ahead)),
                        tracks_, &lanes, now_s});
  }
  // A walker's lane along x = at, walked from y = -3 to 3 at now_s.
  void draw_lane(double at, double now_s = 100.0) {
    for (double y = -3.0; y <= 3.0; y += 0.05) lanes.walk(at, y, 0.23, now_s);
  }

 private:
  std::vector<CrossingTrack> tracks_;
};

// A person crossing at x = 2 m, now at y = from_y, at speed along +y; cage 0.73 m.
CrossingTrack walker(double from_y, double speed, double x = 2.0) { return {1, x, from_y, 0.0, speed, 0.73, 0.23}; }

TEST(Crossings, NobodyCrossingLeavesTheRobotAlone) {
  Bench b;
  const CrossingDecision d = b.decide(0.5, {});
  EXPECT_EQ(d.action, Crossing::clear);
  EXPECT_TRUE(std::isinf(d.v_cap_m_s));
  // A person standing on the path is the costmap's and the cages' business, not the gate's.
  EXPECT_EQ(b.decide(0.5, {walker(0.0, 0.0)}).action, Crossing::clear);
}

TEST(Crossings, ASlowPersonFarAwayOrOneWhoPassesFirstDoesNotHoldTheRobot) {
  Bench b;
  // 4.5 m out at 0.4 m/s: at the path in 11 s, long after the robot (there in about 5 s).
  const CrossingDecision slow = b.decide(0.5, {walker(-4.5, 0.4)});
  EXPECT_TRUE(slow.action == Crossing::clear || slow.action == Crossing::go) << msg::to_string(slow.action);
  EXPECT_TRUE(std::isinf(slow.v_cap_m_s));
  // 1.6 m out at 1.3 m/s: across the path 1.2 s from now and gone when the robot gets there.
  const CrossingDecision fast = b.decide(0.5, {walker(-1.6, 1.3)});
  EXPECT_EQ(fast.action, Crossing::go);
  EXPECT_TRUE(std::isinf(fast.v_cap_m_s));
}

TEST(Crossings, AFastPersonCloseMakesItWaitBeforeTheirWay) {
  Bench b;
  // At the path in 4 s, when the robot at 0.5 m/s gets there.
  const CrossingDecision d = b.decide(0.5, {walker(-4.0, 1.0)});
  ASSERT_EQ(d.action, Crossing::wait);
  // It stops outside the person's keep-out (cage + body + margin) of their line, x = 2 m.
  EXPECT_LE(d.wait_at_m, 2.0 - (0.73 + kBodyM + 0.1) + 1e-9);
  EXPECT_GT(d.wait_at_m, 0.5);
  // From the cap it brakes to a stop there: v^2 / 2a within the wait point, less the reaction.
  const CrossingConfig& c = b.gate.config();
  EXPECT_NEAR(d.v_cap_m_s, std::sqrt(2.0 * c.decel_m_s2 * (d.wait_at_m - 0.5 * c.reaction_s)), 1e-9);
  // Once they have passed, it goes.
  EXPECT_EQ(b.decide(0.0, {walker(1.0, 1.3)}, 100.0, d.wait_at_m).action, Crossing::go);
}

TEST(Crossings, AWalkerAlongThePathIsNotCrossingIt) {
  Bench b;
  // An operator 1.5 m ahead walking on along the path, or someone coming down it: following
  // and meeting are the DWA's and the cages' (the gate would hold a following robot back).
  EXPECT_EQ(b.decide(0.5, {{1, 1.5, 0.0, 0.8, 0.0, 0.73, 0.23}}).action, Crossing::clear);
  EXPECT_EQ(b.decide(0.5, {{1, 3.0, 0.0, -1.0, 0.0, 0.73, 0.23}}).action, Crossing::clear);
  // At 45 degrees across it they cross.
  EXPECT_NE(b.decide(0.5, {{1, 1.0, -3.0, 0.7, 0.7, 0.73, 0.23}}).action, Crossing::clear);
}

TEST(Crossings, AnOperatorLeadingRoundATurnIsNotCrossing) {
  // The path (the operator's trail) runs 2 m along +x, then turns to +y. The operator walks
  // it 1.5 m ahead: their straight prediction cuts across the part after the turn, and a gate
  // that took that for a crossing held the following robot back until it lost them.
  Bench b;
  b.path.clear();
  for (int i = 1; i <= 20; ++i) b.path.push_back({static_cast<float>(0.1 * i), 0.0f});
  for (int i = 1; i <= 30; ++i) b.path.push_back({2.0f, static_cast<float>(0.1 * i)});
  EXPECT_EQ(b.decide(0.4, {{1, 1.5, 0.0, 0.8, 0.0, 0.73, 0.23}}).action, Crossing::clear);
  // Someone off the path, walking the same way towards the later part, does cross it there.
  EXPECT_NE(b.decide(0.4, {{1, 0.5, 1.5, 0.8, 0.0, 0.73, 0.23}}).action, Crossing::clear);
  // Past the turn, walking up the second leg: still along it.
  EXPECT_EQ(b.decide(0.4, {{1, 2.0, 1.0, 0.0, 0.8, 0.73, 0.23}}).action, Crossing::clear);
}

TEST(Crossings, ItNeverWaitsInsideALane) {
  Bench b;
  // A lane along x = 1.2 m, walked a minute ago, before the crossing at x = 2 m.
  b.draw_lane(1.2, 40.0);
  const CrossingDecision d = b.decide(0.3, {walker(-4.0, 1.0)});
  ASSERT_EQ(d.action, Crossing::wait);
  EXPECT_FALSE(b.lanes.in_band(d.wait_at_m, 0.0, kBodyM - 1e-6, 100.0)) << "waits at " << d.wait_at_m;
  // The band's edge, to the lanes' cell.
  EXPECT_LE(d.wait_at_m + kBodyM, 1.2 - 0.23 - b.lanes.config().half_width_m + b.lanes.cell_m() + 1e-9);
  // Without the lane it would have waited in it.
  Bench open;
  const CrossingDecision there = open.decide(0.3, {walker(-4.0, 1.0)});
  ASSERT_EQ(there.action, Crossing::wait);
  EXPECT_TRUE(b.lanes.in_band(there.wait_at_m, 0.0, kBodyM, 100.0)) << "waits at " << there.wait_at_m;
}

TEST(Crossings, TwoLanesTooCloseToStandBetweenAreOne) {
  Bench b;
  // The gap between the two bands (about 0.35 m) is narrower than the robot.
  b.draw_lane(1.0);
  b.draw_lane(2.0);
  // At the path in 6 s, about when the robot gets there.
  const CrossingDecision d = b.decide(0.0, {walker(-6.0, 1.0, 2.9)});
  ASSERT_EQ(d.action, Crossing::wait);
  EXPECT_LE(d.wait_at_m + kBodyM, 1.0 - 0.33 + b.lanes.cell_m() + 1e-9) << "waits at " << d.wait_at_m;
  // With the second lane 1.5 m on, the robot fits between them.
  Bench wide;
  wide.draw_lane(1.0);
  wide.draw_lane(2.5);
  const CrossingDecision w = wide.decide(0.0, {walker(-6.0, 1.0, 3.4)});
  ASSERT_EQ(w.action, Crossing::wait);
  EXPECT_GT(w.wait_at_m - kBodyM, 1.0 + 0.33 - 1e-9) << "waits at " << w.wait_at_m;
  EXPECT_FALSE(wide.lanes.in_band(w.wait_at_m, 0.0, kBodyM - 1e-6, 100.0));  // the gate checks its own sample there
}

TEST(Crossings, LanesFadeAMinuteOrTwoAfterTheLastWalker) {
  Bench b;
  b.draw_lane(2.0, 100.0);
  EXPECT_NEAR(b.lanes.weight(2.0, 0.0, 100.0), 1.0, 1e-9);
  EXPECT_NEAR(b.lanes.weight(2.0, 0.0, 160.0), std::exp(-1.0), 1e-6);
  const double fades_s = -b.lanes.config().decay_s * std::log(b.lanes.config().band_weight);
  EXPECT_TRUE(b.lanes.in_band(2.0, 0.0, 0.0, 100.0 + fades_s - 1.0));
  EXPECT_FALSE(b.lanes.in_band(2.0, 0.0, 0.0, 100.0 + fades_s + 1.0));
  EXPECT_FALSE(b.lanes.in_band(2.6, 0.0, 0.2, 100.0)) << "the band is the body plus the sway, no wider";
}

TEST(Crossings, APointIsInABandExactlyWhenItsCellIs) {
  // A point on a cell's edge, however the edge rounds, belongs to the cell its index names.
  Bench b;
  b.draw_lane(2.0);
  int inside = 0;
  for (int i = 0; i <= 2000; ++i) {
    const double x = 1.0 + 0.001 * i;
    for (const double y : {0.0, 0.1, -0.3, 1.7}) {
      const bool walked = b.lanes.weight(x, y, 100.0) > 0.5;
      EXPECT_EQ(b.lanes.in_band(x, y, 0.0, 100.0), walked) << x << ", " << y;
      inside += walked ? 1 : 0;
    }
  }
  EXPECT_GT(inside, 1000);
}

// --- Making way ---

MakeWayConfig making_way() {
  MakeWayConfig c;
  c.enabled = true;
  return c;
}
// The robot standing at the origin facing +y (across a walker's way along x).
MakeWayDecision way_for(std::vector<CrossingTrack> tracks, double heading = M_PI / 2,
                        const MakeWayConfig& c = making_way()) {
  return make_way(c, {0.0, 0.0, heading}, 0.0, kBodyM, tracks);
}
// A walker at (x, y) walking west (-x) at speed.
CrossingTrack westward(double x, double y, double speed = 1.0, std::uint32_t id = 1) {
  return {id, x, y, -speed, 0.0, 0.73, 0.23};
}

TEST(Crossings, AStandingRobotInAWalkersWayMovesOutAheadWhenThereIsTime) {
  // Their way passes 0.2 m ahead of the robot's centre; they are 5 m off at 1 m/s.
  const MakeWayDecision d = way_for({westward(5.0, 0.2)});
  ASSERT_EQ(d.move, MakeWayMove::forward);
  EXPECT_EQ(d.track_id, 1u);
  EXPECT_GT(d.v_m_s, 0.0);
  EXPECT_GT(d.arrives_s, 3.0);
  // Where it ends, their sweep no longer covers it.
  const MakeWayDecision after =
      make_way(making_way(), {0.0, d.exit_m + 0.02, M_PI / 2}, 0.0, kBodyM, std::vector{westward(5.0, 0.2)});
  EXPECT_EQ(after.move, MakeWayMove::none);
  // Backing out would have been shorter (their way is 0.2 m ahead of the centre), but going
  // on is in time too and keeps the robot on its way.
  EXPECT_GT(d.exit_m, 0.2 + 0.23 + kBodyM);
  EXPECT_EQ(way_for({westward(5.0, -0.2)}).move, MakeWayMove::forward);
}

TEST(Crossings, NoTimeToGetOutMeansStandingStill) {
  const MakeWayDecision d = way_for({westward(1.2, 0.0)});
  EXPECT_EQ(d.move, MakeWayMove::stay);
  EXPECT_EQ(d.v_m_s, 0.0);
  // Facing along their way, moving along its axis gets it out no faster.
  EXPECT_EQ(way_for({westward(5.0, 0.1)}, M_PI).move, MakeWayMove::stay);
}

TEST(Crossings, WalkersGoingAwayOrPassingWideNeedNoWay) {
  EXPECT_EQ(way_for({westward(-2.0, 0.0)}).move, MakeWayMove::none);   // already past
  EXPECT_EQ(way_for({westward(5.0, 2.5)}).move, MakeWayMove::none);    // far to the side
  EXPECT_EQ(way_for({westward(5.0, 0.0, 0.1)}).move, MakeWayMove::none);  // a still track
  EXPECT_EQ(way_for({westward(5.0, 0.0)}, M_PI / 2, MakeWayConfig{}).move, MakeWayMove::none) << "off by default";
}

TEST(Crossings, ItBacksOutWhenTheWayAheadIsAnotherWalkersWay) {
  // A second walker's way lies where moving out ahead would end (the first walker's way is
  // 0.2 m behind the centre, so ahead is the short way out).
  const MakeWayDecision d = way_for({westward(5.5, -0.2, 0.8), westward(6.0, 1.3, 1.0, 2)});
  ASSERT_EQ(d.move, MakeWayMove::backward);
  EXPECT_LT(d.v_m_s, 0.0);
  EXPECT_LT(d.exit_m, 0.0);
}

TEST(Crossings, TooLateToStopBeforeTheKeepOutItStopsShortOfTheirWayOrNotAtAll) {
  Bench b;
  // At full speed 0.9 m on, inside the walker's keep-out of their line (x = 2 m): braking
  // now ends 0.38 m on, short of their body's sweep (0.53 m from the line). It brakes.
  const CrossingDecision short_of = b.decide(0.5, {walker(-4.0, 1.0)}, 100.0, 0.9);
  EXPECT_EQ(short_of.action, Crossing::wait);
  EXPECT_EQ(short_of.v_cap_m_s, 0.0);
  // 0.4 m farther on, braking would end in their way: the gate leaves it to the DWA and the
  // safety filter rather than stand it there.
  const CrossingDecision in_way = b.decide(0.5, {walker(-4.0, 1.0)}, 100.0, 1.3);
  EXPECT_EQ(in_way.action, Crossing::commit);
  EXPECT_TRUE(std::isinf(in_way.v_cap_m_s));
  // Standing in it, the same.
  EXPECT_EQ(b.decide(0.0, {walker(-1.2, 1.3)}, 100.0, 2.0).action, Crossing::commit);
  // From the start it can still stop before the keep-out, and the cap lets it drive on.
  const CrossingDecision early = b.decide(0.5, {walker(-4.0, 1.0)}, 100.0, 0.0);
  EXPECT_EQ(early.action, Crossing::wait);
  EXPECT_GT(early.v_cap_m_s, 0.5);
}

TEST(Crossings, DecidingAndDrawingLanesAllocateNothing) {
  Bench b;
  const std::vector<CrossingTrack> tracks = {walker(-4.0, 1.0), walker(-1.6, 1.3, 3.0), walker(2.0, -0.8, 1.5)};
  const CrossingInputs in{{0.0, 0.0, 0.0}, 0.5, b.path, tracks, &b.lanes, 100.0};
  mem::testing::AllocationScope scope;
  for (int i = 0; i < 100; ++i) {
    for (const CrossingTrack& t : tracks) b.lanes.walk(t.x_m, t.y_m, t.body_m, 100.0 + 0.1 * i);
    (void)b.gate.decide(in);
  }
  EXPECT_EQ(scope.allocations(), 0u);
}

TEST(Crossings, ABadConfigurationIsAClearError) {
  CrossingGate g;
  CrossingConfig c;
  c.sample_m = 0.0;
  EXPECT_FALSE(g.init(c, kBodyM, kMaxV, kAcc));
  c = {};
  c.lookahead_m = 100.0;
  const Status s = g.init(c, kBodyM, kMaxV, kAcc);
  ASSERT_FALSE(s);
  EXPECT_NE(std::string(s.error().message()).find("lookahead_m"), std::string::npos);
  LaneMap lanes;
  std::pmr::monotonic_buffer_resource arena{1024};
  LaneConfig l;
  l.band_weight = 1.5;
  EXPECT_FALSE(lanes.init(l, 0.0, 0.0, 10.0, 10.0, arena));
}

TEST(Crossings, ALargeSiteGetsCoarserLanesNotMoreMemory) {
  std::pmr::monotonic_buffer_resource arena{1 << 20};
  LaneMap lanes;
  ASSERT_TRUE(lanes.init({}, 0.0, 0.0, 100.0, 100.0, arena));
  EXPECT_LE(static_cast<std::size_t>(lanes.columns()) * static_cast<std::size_t>(lanes.rows()), lanes.config().max_cells);
  EXPECT_LE(lanes.bytes(), lanes.config().max_cells * sizeof(float));
  EXPECT_GE(lanes.cell_m() * lanes.columns(), 100.0);
  lanes.walk(50.0, 50.0, 0.23, 1.0);
  EXPECT_TRUE(lanes.in_band(50.0, 50.0, 0.0, 1.0));
  EXPECT_FALSE(lanes.in_band(52.0, 50.0, 0.0, 1.0));
}

}  // namespace
}  // namespace sen3bot::nav
