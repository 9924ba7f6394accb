// The referee's record of a run, fed ground truth by hand: the true pose at a fixed interval
// with its heading, the estimate's path, and where each contact began.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>

#include "sen3bot/sim/referee.hpp"

namespace sen3bot::sim {
namespace {

GroundTruth at(double t_s, double x_m, double theta_rad = 0) {
  GroundTruth truth;
  truth.stamp_ns = static_cast<hal::Nanos>(t_s * 1e9 + 0.5);
  truth.pose = {x_m, 1.0, theta_rad};
  truth.speed_m_s = 0.2;
  truth.clearance_m = 1.0;
  truth.nearest_person_m = 5.0;
  return truth;
}

TEST(Referee, KeepsTheTruePoseEveryQuarterSecondWithItsHeading) {
  auto referee = std::make_unique<Referee>();  // its records are large for a stack
  for (int step = 0; step <= 200; ++step) {  // 1 s of 5 ms world steps
    const double t = step * 0.005;
    referee->observe(at(t, 0.2 * t, 0.5 * t));
  }
  ASSERT_EQ(referee->poses().size(), 5u);
  for (int i = 0; i < 5; ++i) {
    const TimedPose& p = referee->poses()[static_cast<std::size_t>(i)];
    EXPECT_NEAR(p.t_s, 0.25 * i, 1e-9);
    EXPECT_NEAR(p.pose.x_m, 0.05 * i, 1e-9);
    EXPECT_NEAR(p.pose.theta_rad, 0.125 * i, 1e-9);
  }
}

TEST(Referee, ACarryBreaksTheDrivenPathAndIsNotDistanceDriven) {
  auto referee = std::make_unique<Referee>();
  for (int step = 0; step <= 100; ++step) referee->observe(at(step * 0.005, 0.2 * step * 0.005));  // 0.1 m
  GroundTruth carried = at(0.505, 5.0);
  carried.kidnapped_ns = carried.stamp_ns;
  referee->observe(carried);
  for (int step = 102; step <= 200; ++step) {
    GroundTruth t = at(step * 0.005, 5.0 + 0.2 * (step - 101) * 0.005);
    t.kidnapped_ns = carried.stamp_ns;
    referee->observe(t);
  }
  const auto track = referee->track();
  std::size_t breaks = 0, break_at = 0;
  for (std::size_t i = 0; i < track.size(); ++i)
    if (!std::isfinite(track[i].x_m)) ++breaks, break_at = i;
  ASSERT_EQ(breaks, 1u);
  EXPECT_LT(track[break_at - 1].x_m, 0.2);
  EXPECT_DOUBLE_EQ(track[break_at + 1].x_m, 5.0);
  EXPECT_GT(track.back().x_m, 5.05);  // the track goes on after the break
  EXPECT_NEAR(referee->report().true_path_length_m, 0.1 + 0.099, 1e-6);
}

TEST(Referee, TheEstimatesPathAPointPerFiveCentimetresOfValidEstimates) {
  auto referee = std::make_unique<Referee>();
  tasks::Topic<msg::PoseEstimate> estimate;
  referee->watch_estimate(&estimate);
  for (int step = 0; step < 20; ++step) {
    msg::PoseEstimate e;
    e.pose = {0.02 * step, 2.0, 0};  // 2 cm a step: every third step is 5 cm on
    e.valid = step != 6;             // one invalid estimate is skipped
    estimate.publish(e, step);
    referee->observe(at(step * 0.005, 0));
  }
  std::vector<double> xs;
  for (const msg::Point2D& p : referee->estimate_track()) xs.push_back(p.x_m);
  ASSERT_EQ(xs.size(), 7u);
  EXPECT_NEAR(xs[0], 0.0, 1e-9);
  EXPECT_NEAR(xs[1], 0.06, 1e-9);
  EXPECT_NEAR(xs[2], 0.14, 1e-9);  // 0.12 was the invalid one
  EXPECT_NEAR(xs[6], 0.38, 1e-9);
  EXPECT_NEAR(referee->estimate_track()[0].y_m, 2.0, 1e-9);
}

TEST(Referee, WhereEachContactBeganAndWhetherTheRobotMoved) {
  auto referee = std::make_unique<Referee>();
  GroundTruth t = at(0.0, 0.0);
  referee->observe(t);
  t = at(0.005, 0.1);
  t.contacts = 1;  // touched while standing
  t.in_contact = true;
  referee->observe(t);
  t = at(0.010, 0.2);
  t.contacts = 1;  // the same contact goes on
  referee->observe(t);
  t = at(0.015, 0.3, 1.0);
  t.contacts = 2;
  t.moving_contacts = 1;
  t.contact_person = true;
  referee->observe(t);
  ASSERT_EQ(referee->contact_poses().size(), 2u);
  EXPECT_FALSE(referee->contact_poses()[0].person);
  EXPECT_TRUE(referee->contact_poses()[1].person);
  EXPECT_NEAR(referee->contact_poses()[0].pose.x_m, 0.1, 1e-9);
  EXPECT_NEAR(referee->contact_poses()[0].t_s, 0.005, 1e-9);
  EXPECT_FALSE(referee->contact_poses()[0].moving);
  EXPECT_NEAR(referee->contact_poses()[1].pose.x_m, 0.3, 1e-9);
  EXPECT_NEAR(referee->contact_poses()[1].pose.theta_rad, 1.0, 1e-9);
  EXPECT_TRUE(referee->contact_poses()[1].moving);
  EXPECT_EQ(referee->report().contacts, 2u);
  EXPECT_EQ(referee->report().moving_contacts, 1u);
}

}  // namespace
}  // namespace sen3bot::sim
