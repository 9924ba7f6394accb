#include <gtest/gtest.h>

#include <initializer_list>

#include "fixtures.hpp"
#include "sen3bot/ssc/people_map.hpp"

namespace sen3bot::ssc {
namespace {

constexpr Nanos kMs = hal::millis(1);

PeopleReport report(RobotId robot, Nanos stamp, std::initializer_list<PersonObservation> people) {
  PeopleReport r;
  r.robot = robot;
  r.stamp = stamp;
  for (const PersonObservation& p : people) (void)r.people.push_back(p);
  return r;
}

TEST(SscPeopleMap, TwoRobotsSeeingOnePersonGiveOneTrack) {
  PeopleMap map;
  map.update(report(0, 0, {{2.0, 3.0, 0, 0, 7}}));
  map.update(report(1, 10 * kMs, {{2.25, 3.1, 0, 0, 42}}));  // the other robot's localisation is 0.27 m off
  ASSERT_EQ(map.tracks().size(), 1u);
  EXPECT_EQ(map.tracks()[0].seen_by, 0b11u);
  // Both keep reporting for a while: still one.
  for (int i = 1; i <= 20; ++i) {
    map.update(report(0, i * 100 * kMs, {{2.0, 3.0, 0, 0, 7}}));
    map.update(report(1, i * 100 * kMs + 5 * kMs, {{2.25, 3.1, 0, 0, 42}}));
  }
  EXPECT_EQ(map.tracks().size(), 1u);
  EXPECT_FALSE(map.tracks()[0].dynamic);
}

TEST(SscPeopleMap, ConvergingDuplicatesMerge) {
  // Each robot first sees the person 0.9 m from where the other does (beyond the gate), then
  // their estimates agree: one track, the older one's id.
  PeopleMap map;
  map.update(report(0, 0, {{0.0, 0, 0, 0, 1}}));
  map.update(report(1, 10 * kMs, {{0.9, 0, 0, 0, 1}}));
  ASSERT_EQ(map.tracks().size(), 2u);
  const std::uint32_t older = map.tracks()[0].id;
  for (int i = 1; i <= 5; ++i) {
    map.update(report(0, i * 100 * kMs, {{0.3, 0, 0, 0, 1}}));
    map.update(report(1, i * 100 * kMs, {{0.35, 0, 0, 0, 1}}));
  }
  ASSERT_EQ(map.tracks().size(), 1u);
  EXPECT_EQ(map.tracks()[0].id, older);
  EXPECT_EQ(map.tracks()[0].seen_by, 0b11u);

  // A person walking out of every robot's view is kept (until the timeout), not merged.
  PeopleMap kept;
  kept.update(report(0, 0, {{0, 0, 0, 0, 1}, {3, 0, 0, 0, 2}}));
  kept.update(report(0, 100 * kMs, {{0, 0, 0, 0, 1}}));
  EXPECT_EQ(kept.tracks().size(), 2u);
}

TEST(SscPeopleMap, TwoPeopleCloseTogetherStayTwo) {
  PeopleMap map;  // gate 0.7 m
  // One robot sees two people 0.5 m apart (inside the gate of each other): still two.
  map.update(report(0, 0, {{1.0, 1.0, 0, 0, 1}, {1.5, 1.0, 0, 0, 2}}));
  EXPECT_EQ(map.tracks().size(), 2u);
  // Another robot sees the same two people: no new tracks, each joins its own.
  map.update(report(1, 50 * kMs, {{1.05, 1.0, 0, 0, 9}, {1.55, 1.0, 0, 0, 8}}));
  ASSERT_EQ(map.tracks().size(), 2u);
  EXPECT_EQ(map.tracks()[0].seen_by, 0b11u);
  EXPECT_EQ(map.tracks()[1].seen_by, 0b11u);
  // Two people 0.8 m apart, each seen by a different robot only: beyond the gate, two tracks.
  PeopleMap apart;
  apart.update(report(0, 0, {{5.0, 0, 0, 0, 1}}));
  apart.update(report(1, 0, {{5.8, 0, 0, 0, 1}}));
  EXPECT_EQ(apart.tracks().size(), 2u);
  // With a smaller gate the close pair of the first case is two as well when seen by two robots.
  PeopleMapConfig tight;
  tight.gate = 0.3;
  PeopleMap small_gate(tight);
  small_gate.update(report(0, 0, {{1.0, 1.0, 0, 0, 1}}));
  small_gate.update(report(1, 0, {{1.5, 1.0, 0, 0, 1}}));
  EXPECT_EQ(small_gate.tracks().size(), 2u);
}

TEST(SscPeopleMap, PredictionKeepsAWalkerOnOneTrack) {
  PeopleMap map;
  // 1.2 m/s along x, reports every 0.5 s (0.6 m per report) alternating between robots;
  // the second robot sees it 0.2 m off.
  for (int i = 0; i <= 10; ++i) {
    const double x = 1.2 * 0.5 * i;
    map.update(report(static_cast<RobotId>(i % 2), i * 500 * kMs, {{x, i % 2 ? 0.2 : 0.0, 1.2, 0, 3}}));
  }
  ASSERT_EQ(map.tracks().size(), 1u);
  EXPECT_TRUE(map.tracks()[0].dynamic);
}

TEST(SscPeopleMap, StaticTurnsDynamicAfterMovingTheThreshold) {
  PeopleMap map;  // 1 m
  map.update(report(0, 0, {{0, 0, 0, 0, 1}}));
  for (int i = 1; i <= 9; ++i) {
    map.update(report(0, i * 100 * kMs, {{0.1 * i, 0, 0, 0, 1}}));
    EXPECT_FALSE(map.tracks()[0].dynamic) << i;
  }
  // Wandering back and forth within 1 m keeps it static...
  map.update(report(0, 1000 * kMs, {{0.5, 0.6, 0, 0, 1}}));
  EXPECT_FALSE(map.tracks()[0].dynamic);
  // ...past 1 m it is dynamic, and stays so when it comes back.
  for (int i = 0; i < 5; ++i) map.update(report(0, (1100 + 100 * i) * kMs, {{1.3, 0.2, 0, 0, 1}}));
  EXPECT_TRUE(map.tracks()[0].dynamic);
  for (int i = 0; i < 5; ++i) map.update(report(0, (1600 + 100 * i) * kMs, {{0.0, 0.0, 0, 0, 1}}));
  EXPECT_TRUE(map.tracks()[0].dynamic);

  // The threshold is configurable.
  PeopleMapConfig loose;
  loose.dynamic_distance = 2.0;
  PeopleMap wide(loose);
  wide.update(report(0, 0, {{0, 0, 0, 0, 1}}));
  for (int i = 1; i <= 15; ++i) wide.update(report(0, i * 100 * kMs, {{0.1 * i, 0, 0, 0, 1}}));
  EXPECT_FALSE(wide.tracks()[0].dynamic);
}

TEST(SscPeopleMap, UnseenTracksTimeOut) {
  PeopleMap map;  // 2 s
  map.update(report(0, 0, {{0, 0, 0, 0, 1}}));
  map.update(report(1, hal::seconds(1), {{5, 5, 0, 0, 1}}));
  map.expire(hal::seconds(2));
  EXPECT_EQ(map.tracks().size(), 2u);
  map.expire(hal::seconds(2) + kMs);
  ASSERT_EQ(map.tracks().size(), 1u);
  EXPECT_EQ(map.tracks()[0].position.x_m, 5);
  map.expire(hal::seconds(3));
  EXPECT_EQ(map.tracks().size(), 1u);
  map.expire(hal::seconds(3) + kMs);
  EXPECT_TRUE(map.tracks().empty());
}

TEST(SscPeopleMap, CapacityIsBoundedAndOverflowCounted) {
  PeopleMapConfig config;
  config.max_tracks = 3;
  PeopleMap map(config);
  map.update(report(0, 0, {{0, 0, 0, 0, 1}, {2, 0, 0, 0, 2}, {4, 0, 0, 0, 3}, {6, 0, 0, 0, 4}, {8, 0, 0, 0, 5}}));
  EXPECT_EQ(map.tracks().size(), 3u);
  EXPECT_EQ(map.overflow(), 2u);
  // Known people still update.
  map.update(report(0, 100 * kMs, {{0.1, 0, 0, 0, 1}}));
  EXPECT_EQ(map.overflow(), 2u);

  // The full default capacity: 128 people, every further one counted.
  PeopleMap full;
  for (int batch = 0; batch < 5; ++batch) {
    PeopleReport r;
    r.robot = 2;
    r.stamp = 0;
    for (int i = 0; i < 32; ++i) (void)r.people.push_back({batch * 10.0, i * 2.0, 0, 0, static_cast<std::uint32_t>(i)});
    full.update(r);
  }
  EXPECT_EQ(full.tracks().size(), kMaxTracks);
  EXPECT_EQ(full.overflow(), 5u * 32 - kMaxTracks);
}

TEST(SscPeopleMap, PeopleInAnArea) {
  PeopleMap map;
  map.update(report(0, 0, {{1, 1, 0, 0, 1}, {3, 1, 0, 0, 2}, {9, 9, 0, 0, 3}}));
  for (int i = 1; i <= 12; ++i) map.update(report(0, i * 100 * kMs, {{1, 1, 0, 0, 1}, {3, 1 + 0.1 * i, 0, 0, 2}, {9, 9, 0, 0, 3}}));
  const Polygon zone = testing::rect(0, 0, 4, 4);
  const AreaPeople in = map.in_area(zone.as_span());
  EXPECT_EQ(in.count, 2);
  EXPECT_EQ(in.dynamic, 1);
  EXPECT_TRUE(in.any_dynamic());
  EXPECT_FALSE(map.in_area(testing::rect(20, 20, 21, 21).as_span()).any());
}

}  // namespace
}  // namespace sen3bot::ssc
