// The online SGP's trigger: a person near and a deviation from the safe path, held for the
// delay; never for an obstacle alone, never for a far person; then a cooldown.
#include <gtest/gtest.h>

#include <limits>
#include <vector>

#include "sen3bot/nav/osgp.hpp"

namespace sen3bot::nav {
namespace {

constexpr hal::Nanos kMs = 1'000'000;
constexpr Point2D kGoal{12.0, 0.0};  // the safe path (0, 0) - (10, 0) goes on to it

msg::People person_at(double x, double y, hal::Nanos seen_ns) {
  msg::People people;
  people.count = 1;
  people.items[0].id = 1;
  people.items[0].x_m = x;
  people.items[0].y_m = y;
  people.items[0].last_seen_ns = seen_ns;
  return people;
}

TEST(Osgp, DistanceToThePathIsToItsNearestSegment) {
  const std::vector<Point2D> path = {{0, 0}, {4, 0}, {4, 3}};
  EXPECT_NEAR(distance_to_path({2, 1}, path), 1.0, 1e-12);
  EXPECT_NEAR(distance_to_path({5, 2}, path), 1.0, 1e-12);
  EXPECT_NEAR(distance_to_path({-3, 4}, path), 5.0, 1e-12);
  EXPECT_EQ(distance_to_path({0, 0}, {}), std::numeric_limits<double>::infinity());
}

TEST(Osgp, APersonNearWhileOffThePathTriggersAfterTheDelayThenCoolsDown) {
  OsgpConfig config;
  config.delay_s = 1.0;
  config.cooldown_s = 5.0;
  OsgpTrigger trigger(config);
  const std::vector<Point2D> path = {{0, 0}, {10, 0}};
  hal::Nanos now = 0;
  // On the path with a person beside it: nothing.
  EXPECT_EQ(trigger.update({2, 0.1, 0}, path, kGoal, person_at(3, 1, now), now), OsgpOutcome::on_path);
  // Past the path's end on the approach to the goal is on the route too.
  EXPECT_EQ(trigger.update({11, 0.1, 0}, path, kGoal, person_at(11.5, 1, now), now), OsgpOutcome::on_path);
  // Pushed 0.6 m off it by the person: wait the delay, then fire once.
  OsgpOutcome last = OsgpOutcome::on_path;
  int fired_at = -1;
  for (int k = 1; k <= 20; ++k) {
    now = k * 100 * kMs;
    last = trigger.update({2 + 0.1 * k, 0.6, 0}, path, kGoal, person_at(3.5, -0.2, now), now);
    if (last == OsgpOutcome::triggered) {
      fired_at = k;
      break;
    }
    EXPECT_EQ(last, OsgpOutcome::waiting) << k;
  }
  EXPECT_EQ(fired_at, 11);  // armed at 0.1 s, 1.0 s later
  // Still off the path, still near: the cooldown holds.
  now += 1000 * kMs;
  EXPECT_EQ(trigger.update({4, 0.6, 0}, path, kGoal, person_at(4.5, 0, now), now), OsgpOutcome::cooling_down);
  EXPECT_EQ(trigger.count(OsgpOutcome::triggered), 1u);
  EXPECT_EQ(trigger.count(OsgpOutcome::waiting), 10u);
}

TEST(Osgp, AnObstacleAloneOrAFarPersonNeverTriggers) {
  OsgpConfig config;
  config.delay_s = 0.5;
  config.trigger_distance_m = 2.0;
  OsgpTrigger trigger(config);
  const std::vector<Point2D> path = {{0, 0}, {10, 0}};
  msg::People nobody;
  for (int k = 0; k < 50; ++k) {
    const hal::Nanos now = k * 100 * kMs;
    EXPECT_EQ(trigger.update({2, 0.8, 0}, path, kGoal, nobody, now), OsgpOutcome::deviated_no_person);
    // A person 5 m away is caged, but no reason to re-plan.
    EXPECT_EQ(trigger.update({2, 0.8, 0}, path, kGoal, person_at(7, 0.8, now), now), OsgpOutcome::deviated_no_person);
  }
  // A person near but not seen for longer than person_timeout_s does not count either.
  EXPECT_EQ(trigger.update({2, 0.8, 0}, path, kGoal, person_at(2.5, 0.8, 0), 5000 * kMs), OsgpOutcome::deviated_no_person);
  EXPECT_EQ(trigger.count(OsgpOutcome::triggered), 0u);
}

// The person passed goes out of view (no track at all) before the robot is 0.4 m off the path:
// having been near counts for person_timeout_s.
TEST(Osgp, APersonPassedAndLostFromViewStillCounts) {
  OsgpConfig config;
  config.delay_s = 1.0;
  config.person_timeout_s = 4.0;
  OsgpTrigger trigger(config);
  const std::vector<Point2D> path = {{0, 0}, {10, 0}};
  EXPECT_EQ(trigger.update({1, 0.1, 0}, path, kGoal, person_at(2.5, 0, 0), 0), OsgpOutcome::on_path);
  const msg::People nobody;
  EXPECT_EQ(trigger.update({2, 0.6, 0}, path, kGoal, nobody, 1500 * kMs), OsgpOutcome::waiting);
  EXPECT_EQ(trigger.update({2.5, 0.7, 0}, path, kGoal, nobody, 2600 * kMs), OsgpOutcome::triggered);
  // Long after, nobody near: an obstacle's deviation again.
  EXPECT_EQ(trigger.update({5, 0.7, 0}, path, kGoal, nobody, 9000 * kMs), OsgpOutcome::deviated_no_person);
}

TEST(Osgp, BackOnThePathDisarms) {
  OsgpConfig config;
  config.delay_s = 1.0;
  OsgpTrigger trigger(config);
  const std::vector<Point2D> path = {{0, 0}, {10, 0}};
  EXPECT_EQ(trigger.update({2, 0.6, 0}, path, kGoal, person_at(3, 0, 0), 0), OsgpOutcome::waiting);
  EXPECT_EQ(trigger.update({2, 0.1, 0}, path, kGoal, person_at(3, 0, 500 * kMs), 500 * kMs), OsgpOutcome::on_path);
  // Off again: the delay counts from now, not from the first time.
  EXPECT_EQ(trigger.update({2, 0.6, 0}, path, kGoal, person_at(3, 0, 900 * kMs), 900 * kMs), OsgpOutcome::waiting);
  EXPECT_EQ(trigger.update({2, 0.6, 0}, path, kGoal, person_at(3, 0, 1500 * kMs), 1500 * kMs), OsgpOutcome::waiting);
  EXPECT_EQ(trigger.update({2, 0.6, 0}, path, kGoal, person_at(3, 0, 1900 * kMs), 1900 * kMs), OsgpOutcome::triggered);
}

}  // namespace
}  // namespace sen3bot::nav
