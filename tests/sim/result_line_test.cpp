// The result line under a report figure's title: what a reader checks first.
#include <gtest/gtest.h>

#include "report_figure.hpp"

namespace sen3bot::sim {
namespace {

using firmware::MissionReport;
using firmware::MissionState;

TEST(ResultLine, OneGoalReached) {
  MissionReport r;
  r.state = MissionState::complete;
  r.goals_reached = 1;
  r.goal_time_s[0] = 41.26;
  r.plans = 3;
  r.recoveries = 1;
  RefereeReport truth;
  truth.min_clearance_m = 0.141;
  EXPECT_EQ(result_line(r, 1, truth), "goal reached in 41.3 s, 0 contacts, 1 recovery, 2 replans, min clearance 0.14 m");
}

TEST(ResultLine, ContactsAndAFailedGoal) {
  MissionReport r;
  r.state = MissionState::failed;
  r.plans = 2;
  RefereeReport truth;
  truth.contacts = 3;
  truth.moving_contacts = 1;
  truth.min_clearance_m = 0;
  EXPECT_EQ(result_line(r, 1, truth),
            "goal not reached (failed), 3 contacts (1 by the robot), 0 recoveries, 1 replan, min clearance 0.00 m");
}

TEST(ResultLine, SeveralGoalsAddTheirTimes) {
  MissionReport r;
  r.state = MissionState::complete;
  r.goals_reached = 2;
  r.goal_time_s[0] = 14.0;
  r.goal_time_s[1] = 17.0;
  r.plans = 12;
  r.recoveries = 7;
  RefereeReport truth;
  truth.contacts = 1;
  truth.min_clearance_m = 0.004;
  EXPECT_EQ(result_line(r, 2, truth),
            "2 of 2 goals reached in 31.0 s, 1 contact (0 by the robot), 7 recoveries, 11 replans, min clearance 0.00 m");
}

}  // namespace
}  // namespace sen3bot::sim
