// The collaboration mode's rules: where the robot may wait for an operator, who toggles it.
#include "sen3bot/cobot/mode.hpp"

#include <gtest/gtest.h>

#include <vector>

#include "alloc_counter.hpp"

namespace sen3bot::cobot {
namespace {

using msg::CobotMode;

constexpr std::uint32_t kOperatorAnna = 7;
constexpr std::uint32_t kOperatorBruno = 9;

TriggerEvent request_by(std::uint32_t id) {
  TriggerEvent e;
  e.kind = TriggerEventKind::request;
  e.operator_id = id;
  return e;
}

class ModeTest : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_TRUE(mode.init(ModeConfig{})); }
  ModeOutput step(AreaType area, bool idle, std::vector<TriggerEvent> events = {}) {
    ModeInput input;
    input.now_ns = now += hal::millis(100);
    input.area = area;
    input.idle = idle;
    input.trigger_events = events;
    return mode.update(input);
  }
  static bool has(const ModeOutput& out, ModeEventKind kind) {
    for (const ModeEvent& e : out.events)
      if (e.kind == kind) return true;
    return false;
  }
  // Idle in a type-2 area, then Anna's request.
  void collaborate_with_anna() {
    ASSERT_EQ(step(AreaType::sub_critical_2, true).mode, CobotMode::wait4col);
    const ModeOutput out = step(AreaType::sub_critical_2, true, {request_by(kOperatorAnna)});
    ASSERT_EQ(out.mode, CobotMode::collaborative);
    ASSERT_TRUE(has(out, ModeEventKind::toggled_on));
    ASSERT_EQ(out.operator_id, kOperatorAnna);
  }
  CollaborationMode mode;
  hal::Nanos now = 0;
};

TEST_F(ModeTest, IdleInASubCriticalAreaWaitsForAnOperator) {
  const ModeOutput out = step(AreaType::sub_critical_2, true);
  EXPECT_EQ(out.mode, CobotMode::wait4col);
  EXPECT_TRUE(has(out, ModeEventKind::entered_wait4col));
  EXPECT_TRUE(mode.accepts_requests());
}

TEST_F(ModeTest, NeverWaitsInACriticalAreaOrOutsideASubCriticalOne) {
  for (AreaType area : {AreaType::critical_1_1, AreaType::critical_1_2, AreaType::none, AreaType::not_monitored_3}) {
    for (int i = 0; i < 20; ++i) {
      const ModeOutput out = step(area, true, {request_by(kOperatorAnna)});
      EXPECT_EQ(out.mode, CobotMode::cooperative) << to_string(area);
      EXPECT_FALSE(has(out, ModeEventKind::toggled_on)) << to_string(area);
    }
    EXPECT_FALSE(mode.accepts_requests());
  }
  EXPECT_EQ(mode.refusals(ModeRefusal::not_waiting), 80u);
}

TEST_F(ModeTest, BusyOrDisabledRobotsDoNotWait) {
  EXPECT_EQ(step(AreaType::sub_critical_2, false).mode, CobotMode::cooperative);
  ModeConfig off;
  off.wait4col_enabled = false;
  ASSERT_TRUE(mode.init(off));
  EXPECT_EQ(step(AreaType::sub_critical_2, true).mode, CobotMode::cooperative);
}

TEST_F(ModeTest, LeavingTheAreaOrGettingAGoalEndsTheWait) {
  ASSERT_EQ(step(AreaType::sub_critical_2, true).mode, CobotMode::wait4col);
  ModeOutput out = step(AreaType::sub_critical_2, false);
  EXPECT_EQ(out.mode, CobotMode::cooperative);
  EXPECT_TRUE(has(out, ModeEventKind::left_wait4col));

  ASSERT_EQ(step(AreaType::sub_critical_2, true).mode, CobotMode::wait4col);
  out = step(AreaType::critical_1_2, true);
  EXPECT_EQ(out.mode, CobotMode::cooperative);
  EXPECT_TRUE(has(out, ModeEventKind::left_wait4col));
}

TEST_F(ModeTest, ARequestInTheCycleAGoalComesFindsTheRobotNoLongerWaiting) {
  ASSERT_EQ(step(AreaType::sub_critical_2, true).mode, CobotMode::wait4col);
  const ModeOutput out = step(AreaType::sub_critical_2, false, {request_by(kOperatorAnna)});
  EXPECT_EQ(out.mode, CobotMode::cooperative);
  EXPECT_EQ(mode.refusals(ModeRefusal::not_waiting), 1u);
}

TEST_F(ModeTest, TheSameOperatorTogglesOnAndOffAndTheTaskResumes) {
  collaborate_with_anna();
  // Collaborative whether or not the robot moves.
  EXPECT_EQ(step(AreaType::sub_critical_2, false).mode, CobotMode::collaborative);
  EXPECT_FALSE(step(AreaType::sub_critical_2, true).resume);
  const ModeOutput off = step(AreaType::sub_critical_2, false, {request_by(kOperatorAnna)});
  EXPECT_EQ(off.mode, CobotMode::cooperative);
  EXPECT_EQ(off.operator_id, 0u);
  EXPECT_TRUE(off.resume);
  EXPECT_TRUE(has(off, ModeEventKind::toggled_off));
  EXPECT_EQ(mode.toggles(), 2u);
  // Resumed: it drives to its goal (not idle), so it does not wait.
  EXPECT_EQ(step(AreaType::sub_critical_2, false).mode, CobotMode::cooperative);
}

TEST_F(ModeTest, ToggledOffWithNoTaskLeftItOffersItselfAgainFromTheNextCycle) {
  collaborate_with_anna();
  const ModeOutput off = step(AreaType::sub_critical_2, true, {request_by(kOperatorAnna)});
  EXPECT_EQ(off.mode, CobotMode::cooperative);
  EXPECT_TRUE(off.resume);
  EXPECT_EQ(step(AreaType::sub_critical_2, true).mode, CobotMode::wait4col);
}

TEST_F(ModeTest, AnotherOperatorIsRefused) {
  collaborate_with_anna();
  const ModeOutput out = step(AreaType::sub_critical_2, false, {request_by(kOperatorBruno)});
  EXPECT_EQ(out.mode, CobotMode::collaborative);
  EXPECT_EQ(out.operator_id, kOperatorAnna);
  EXPECT_FALSE(out.resume);
  ASSERT_TRUE(has(out, ModeEventKind::refused));
  EXPECT_EQ(out.events[0].refusal, ModeRefusal::not_the_operator);
  EXPECT_EQ(out.events[0].operator_id, kOperatorBruno);
  EXPECT_EQ(mode.refusals(ModeRefusal::not_the_operator), 1u);
}

TEST_F(ModeTest, CollaborativeInACriticalAreaGoesBackToCooperative) {
  collaborate_with_anna();
  const ModeOutput out = step(AreaType::critical_1_1, false);
  EXPECT_EQ(out.mode, CobotMode::cooperative);
  EXPECT_TRUE(out.resume);
  EXPECT_TRUE(has(out, ModeEventKind::aborted));
  EXPECT_EQ(mode.aborts(), 1u);
  EXPECT_EQ(step(AreaType::critical_1_1, true).mode, CobotMode::cooperative);
}

TEST_F(ModeTest, UpdatesAllocateNothing) {
  const std::array<TriggerEvent, 1> anna{request_by(kOperatorAnna)};
  std::uint32_t collaborative_cycles = 0;
  mem::testing::AllocationScope scope;
  for (int i = 0; i < 1000; ++i) {
    ModeInput input;
    input.now_ns = hal::millis(100) * i;
    input.area = AreaType::sub_critical_2;
    input.idle = true;
    if (i % 10 == 5) input.trigger_events = anna;
    collaborative_cycles += mode.update(input).mode == CobotMode::collaborative ? 1 : 0;
  }
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(collaborative_cycles, 500u);
}

}  // namespace
}  // namespace sen3bot::cobot
