#include <gtest/gtest.h>

#include <initializer_list>
#include <vector>

#include "fixtures.hpp"
#include "sen3bot/ssc/allocation.hpp"

namespace sen3bot::ssc {
namespace {

// The area is the unit square at the origin; robots stand along x at their distance from it.
const Polygon kArea = testing::rect(-1, -1, 0, 0);

Candidate at(RobotId id, double distance, std::uint8_t priority, bool available = true) {
  return {id, {distance, -0.5}, priority, available};
}

std::vector<RobotId> ids(const Selection& s) { return {s.robots.begin(), s.robots.end()}; }

TEST(SscAllocation, Figure27) {
  const struct {
    const char* name;
    std::vector<Candidate> robots;
    std::size_t n;
    std::vector<RobotId> expected;
    std::size_t swaps;
  } cases[] = {
      {"nearest first", {at(1, 9, 2), at(2, 3, 2), at(3, 6, 2)}, 2, {2, 3}, 0},
      {"p = 0 never taken", {at(1, 1, 0), at(2, 8, 2), at(3, 2, 0)}, 2, {2}, 0},
      {"p = 1 swapped for a farther p = 2", {at(1, 2, 1), at(2, 7, 2)}, 1, {2}, 1},
      {"p = 1 kept without a p = 2", {at(1, 2, 1), at(2, 4, 1), at(3, 1, 0)}, 1, {1}, 0},
      {"the farther p = 1 goes first", {at(1, 2, 1), at(2, 3, 1), at(3, 9, 2)}, 2, {1, 3}, 1},
      {"p = 2 already taken are kept", {at(1, 2, 2), at(2, 3, 2), at(3, 4, 2)}, 2, {1, 2}, 0},
      {"not enough robots", {at(1, 2, 2), at(2, 1, 0)}, 2, {1}, 0},
      {"unavailable robots skipped", {at(1, 1, 2, false), at(2, 5, 2)}, 1, {2}, 0},
      {"none wanted", {at(1, 1, 2)}, 0, {}, 0},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(c.name);
    const Selection s = select_robots(c.robots, kArea.as_span(), c.n);
    EXPECT_EQ(ids(s), c.expected);
    EXPECT_EQ(s.swaps.size(), c.swaps);
  }
  const Selection swapped = select_robots(std::vector{at(1, 2, 1), at(2, 7, 2)}, kArea.as_span(), 1);
  ASSERT_EQ(swapped.swaps.size(), 1u);
  EXPECT_EQ(swapped.swaps[0].taken, 2);
  EXPECT_EQ(swapped.swaps[0].passed_over, 1);
  // A site may cap the detour a swap costs.
  AllocationConfig capped;
  capped.max_swap_extra_distance = 3;
  EXPECT_EQ(ids(select_robots(std::vector{at(1, 2, 1), at(2, 7, 2)}, kArea.as_span(), 1, capped)), std::vector<RobotId>{1});
  EXPECT_EQ(ids(select_robots(std::vector{at(1, 2, 1), at(2, 4, 2)}, kArea.as_span(), 1, capped)), std::vector<RobotId>{2});
}

TEST(SscAllocation, AmrTaskGoesToTheNearestAvailable) {
  const std::vector<Candidate> robots{at(1, 5, 2), at(2, 2, 2, false), at(3, 3, 1)};
  EXPECT_EQ(select_for_task(robots, {0, 0}), 3);
  EXPECT_EQ(select_for_task(std::vector{at(1, 1, 2, false)}, {0, 0}), kNone);
}

TEST(SscAllocation, SuspendedWorkIsStackedAndResumed) {
  RobotTasks t;
  EXPECT_EQ(t.priority(), kLowest);  // no task: idle
  const Task work{7, TaskKind::amr, 2, {1, 1, 0}, kNone, 70};
  ASSERT_TRUE(t.start(work).ok);
  EXPECT_EQ(t.priority(), 2);
  const Task urgent{8, TaskKind::amr, 1, {2, 2, 0}, kNone, 80};
  const auto first = t.start(urgent);
  ASSERT_TRUE(first.suspended);
  EXPECT_EQ(first.suspended->id, 7u);
  const Task monitor{9, TaskKind::monitor, 0, {3, 3, 0}, 4, 0};
  EXPECT_EQ(t.start(monitor).suspended->id, 8u);
  ASSERT_EQ(t.suspended().size(), 2u);
  EXPECT_EQ(t.priority(), 0);
  // Released: the most recent work comes back first.
  t.finish();
  EXPECT_EQ(t.resume()->id, 8u);
  t.finish();
  EXPECT_EQ(t.resume()->id, 7u);
  t.finish();
  EXPECT_FALSE(t.resume());
  // A home task is replaced, not suspended.
  ASSERT_TRUE(t.start({10, TaskKind::home, 2, {}, kNone, 0}).ok);
  EXPECT_FALSE(t.start(monitor).suspended);
  EXPECT_TRUE(t.suspended().empty());
  // A full stack refuses.
  RobotTasks full;
  for (TaskId i = 1; i <= kMaxSuspended + 1; ++i) ASSERT_TRUE(full.start({i, TaskKind::amr, 2, {}, kNone, 0}).ok);
  EXPECT_TRUE(full.stack_full_for_new_task());
  EXPECT_FALSE(full.start(monitor).ok);
  EXPECT_EQ(full.current()->id, kMaxSuspended + 1);
}

TEST(SscAllocation, StandingRules) {
  const StandingConfig config;  // 20 % low, 80 % charged
  RobotTasks idle;
  EXPECT_EQ(standing_rule(idle, 50, config), StandingAction::go_home);
  EXPECT_EQ(standing_rule(idle, 19, config), StandingAction::charge);
  RobotTasks busy;
  (void)busy.start({1, TaskKind::amr, 1, {}, kNone, 0});
  EXPECT_EQ(standing_rule(busy, 50, config), StandingAction::none);
  EXPECT_EQ(standing_rule(busy, 10, config), StandingAction::charge);
  RobotTasks charging;
  (void)charging.start({2, TaskKind::charge, 0, {}, kNone, 0});
  EXPECT_EQ(standing_rule(charging, 10, config), StandingAction::none);
  EXPECT_EQ(standing_rule(charging, 79, config), StandingAction::none);
  EXPECT_EQ(standing_rule(charging, 80, config), StandingAction::charged);
  RobotTasks waiting;
  (void)waiting.start({3, TaskKind::amr, 2, {}, kNone, 0});
  (void)waiting.start({4, TaskKind::monitor, 1, {}, 1, 0});
  waiting.finish();
  EXPECT_EQ(standing_rule(waiting, 60, config), StandingAction::resume);
}

}  // namespace
}  // namespace sen3bot::ssc
