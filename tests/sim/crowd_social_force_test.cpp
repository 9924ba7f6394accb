// The social force model: single forces against hand computations with Helbing, Farkas & Vicsek
// 2000's constants (m = 80 kg, tau = 0.5 s, A = 2000 N, B = 0.08 m, k = 1.2e5 kg/s^2,
// kappa = 2.4e5 kg/(m s)) and lambda = 0.5, then whole walks: passing, giving way to a robot
// (or not, when blind), free speed, determinism, order independence, no allocation.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstring>
#include <initializer_list>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/crowd/social_force.hpp"

namespace sen3bot::crowd {
namespace {

using mem::testing::AllocationScope;

Walker walker_at(Point2D position, std::initializer_list<Point2D> goals) {
  Walker w;
  w.position = position;
  EXPECT_TRUE(set_route(w, std::span<const Point2D>(goals.begin(), goals.size())).ok());
  return w;
}

TEST(CrowdSocialForce, ForceFromAnotherPersonMatchesHandComputation) {
  const SocialForceModel model;
  // i at the origin heading for (10, 0), at rest; j at (0.6, 0.3), both r = 0.25 m.
  //   d = sqrt(0.6^2 + 0.3^2) = 0.670820,  n_ij = (-0.894427, -0.447214)
  //   cos phi = -n_ij . e_i = 0.894427,  w = 0.5 + 0.5 (1 + 0.894427) / 2 = 0.973607
  //   |f| = 2000 N * exp((0.5 - 0.670820) / 0.08) * w = 2000 * 0.118214 * 0.973607 = 230.189 N
  //   f_ij = 230.189 * n_ij = (-205.887, -102.944) N
  // Driving: m v0 e / tau = 80 * 1.3 / 0.5 = 208 N along +x.
  std::vector<Walker> walkers{walker_at({0.0, 0.0}, {{10.0, 0.0}}), walker_at({0.6, 0.3}, {{0.6, 10.0}})};
  const Point2D pair = model.walker_force(walkers[0], walkers[1]);
  EXPECT_NEAR(pair.x_m, -205.8871, 1e-3);
  EXPECT_NEAR(pair.y_m, -102.9436, 1e-3);
  const Point2D drive = model.driving_force(walkers[0]);
  EXPECT_NEAR(drive.x_m, 208.0, 1e-9);
  EXPECT_NEAR(drive.y_m, 0.0, 1e-12);
  const Point2D total = model.force_on(0, walkers, {}, nullptr);
  EXPECT_NEAR(total.x_m, 208.0 - 205.8871, 1e-3);
  EXPECT_NEAR(total.y_m, -102.9436, 1e-3);

  // Bodies in contact: j at (0.45, 0) so g = 0.5 - 0.45 = 0.05 m; v_i = (1, 0), v_j = (-1, 0.2).
  //   n_ij = (-1, 0), t_ij = (0, -1), w = 1 (straight ahead)
  //   social 2000 * exp(0.05 / 0.08) = 2000 * 1.868246 = 3736.492 N, body k g = 6000 N
  //   friction kappa g ((v_j - v_i) . t_ij) t_ij = 2.4e5 * 0.05 * (-0.2) * (0, -1) = (0, 2400) N
  //   f_ij = (-9736.492, 2400) N
  Walker i = walker_at({0.0, 0.0}, {{10.0, 0.0}});
  i.velocity = {1.0, 0.0};
  Walker j = walker_at({0.45, 0.0}, {{-10.0, 0.0}});
  j.velocity = {-1.0, 0.2};
  const Point2D contact = model.walker_force(i, j);
  EXPECT_NEAR(contact.x_m, -9736.492, 1e-3);
  EXPECT_NEAR(contact.y_m, 2400.0, 1e-6);
}

// Companions' attraction (Moussaïd et al. 2010): m beta towards the group's centre once farther
// from it than (N - 1) / 2 m; 80 kg * 1 m/s^2 = 80 N.
TEST(CrowdSocialForce, CompanionsArePulledTogetherOnlyWhenApart) {
  const SocialForceModel model;
  std::vector<Walker> walkers{walker_at({0.0, 0.0}, {{10.0, 0.0}}), walker_at({0.0, 1.4}, {{10.0, 1.4}}),
                              walker_at({0.0, -1.0}, {{10.0, -1.0}})};
  walkers[0].group = walkers[1].group = 3;
  // Two, 1.4 m apart: 0.7 m from the centre, more than 0.5 m.
  Point2D f = model.group_force(0, walkers);
  EXPECT_NEAR(f.x_m, 0.0, 1e-12);
  EXPECT_NEAR(f.y_m, 80.0, 1e-9);
  EXPECT_NEAR(model.group_force(1, walkers).y_m, -80.0, 1e-9);
  EXPECT_EQ(model.group_force(2, walkers).y_m, 0.0) << "alone";
  // 0.8 m apart: 0.4 m from the centre, near enough.
  walkers[1].position = {0.0, 0.8};
  EXPECT_EQ(norm(model.group_force(0, walkers)), 0.0);
  // Three at y = 0, 0.8 and -0.2 m: the centre is 0.2 m from the first, within (3 - 1) / 2 = 1 m.
  walkers[2].group = 3;
  walkers[2].position = {0.0, -0.2};
  EXPECT_EQ(norm(model.group_force(0, walkers)), 0.0);
  // A companion out of the scene does not count: alone again.
  walkers[1].position = {0.0, 3.0};
  walkers[2].active = false;
  walkers[1].active = false;
  EXPECT_EQ(norm(model.group_force(0, walkers)), 0.0);
}

TEST(CrowdSocialForce, ForceFromWallMatchesHandComputation) {
  const SocialForceModel model;
  const Wall wall{{-5.0, 0.0}, {5.0, 0.0}};
  // Walker (r = 0.25 m) 0.4 m from the wall: n = (0, 1), 2000 * exp((0.25 - 0.4) / 0.08)
  //   = 2000 * 0.153355 = 306.710 N along +y; walls have no anisotropy.
  Walker w = walker_at({1.0, 0.4}, {{1.0, -10.0}});  // even heading into the wall
  Point2D f = model.wall_force(w, wall);
  EXPECT_NEAR(f.x_m, 0.0, 1e-12);
  EXPECT_NEAR(f.y_m, 306.7099, 1e-3);
  // Past the end of the segment the nearest point is the end point (5, 0): walker at (5.3, 0.4),
  //   d = 0.5, n = (0.6, 0.8), 2000 * exp((0.25 - 0.5) / 0.08) = 2000 * 0.0439369 = 87.874 N.
  w.position = {5.3, 0.4};
  f = model.wall_force(w, wall);
  EXPECT_NEAR(f.x_m, 0.6 * 87.8738, 1e-3);
  EXPECT_NEAR(f.y_m, 0.8 * 87.8738, 1e-3);
  // Pressed into it: centre 0.2 m away (g = 0.05 m), sliding along at v = (1, 0).
  //   normal 2000 * exp(0.05 / 0.08) + 1.2e5 * 0.05 = 3736.492 + 6000 = 9736.492 N along +y
  //   friction -kappa g (v . t) t with t = (-1, 0): -2.4e5 * 0.05 * (-1) * (-1, 0) = (-12000, 0) N
  w.position = {0.0, 0.2};
  w.velocity = {1.0, 0.0};
  f = model.wall_force(w, wall);
  EXPECT_NEAR(f.x_m, -12000.0, 1e-6);
  EXPECT_NEAR(f.y_m, 9736.492, 1e-3);
}

TEST(CrowdSocialForce, NeighbourInFrontPushesHarderThanBehind) {
  const SocialForceModel model;
  // 0.8 m apart, r_ij = 0.5: 2000 * exp(-0.3 / 0.08) = 47.0355 N; in front w = 1, behind w = lambda.
  const Walker me = walker_at({0.0, 0.0}, {{10.0, 0.0}});
  const Walker ahead = walker_at({0.8, 0.0}, {{10.0, 0.0}});
  const Walker behind = walker_at({-0.8, 0.0}, {{10.0, 0.0}});
  const Point2D front = model.walker_force(me, ahead);
  const Point2D back = model.walker_force(me, behind);
  EXPECT_NEAR(front.x_m, -47.0355, 1e-3);
  EXPECT_NEAR(back.x_m, 0.5 * 47.0355, 1e-3);
  EXPECT_GT(msg::norm(front), 1.9 * msg::norm(back));
}

TEST(CrowdSocialForce, HeadOnWalkersPassWithoutTouchingAndArrive) {
  const SocialForceModel model;
  std::vector<Walker> walkers{walker_at({0.0, 0.0}, {{10.0, 0.0}}), walker_at({10.0, 0.05}, {{0.0, 0.05}})};
  const double contact = walkers[0].radius_m + walkers[1].radius_m;
  double closest = 1e9;
  double lateral = 0.0;
  for (int k = 0; k < 3000 && !(reached_final_goal(walkers[0]) && reached_final_goal(walkers[1])); ++k) {
    ASSERT_TRUE(model.step(walkers, {}, nullptr, 0.01).ok());
    closest = std::min(closest, geometry::distance(walkers[0].position, walkers[1].position));
    lateral = std::max(lateral, std::abs(walkers[0].position.y_m - walkers[1].position.y_m));
  }
  EXPECT_GT(closest, contact);
  EXPECT_GT(lateral, contact);  // they stepped aside rather than squeezing through
  EXPECT_TRUE(reached_final_goal(walkers[0]));
  EXPECT_TRUE(reached_final_goal(walkers[1]));
}

// Walks one walker from (0, 0) to (10, 0) past a robot standing at (5, 0.05); returns the
// closest approach of the centres and whether the walker arrived.
std::pair<double, bool> walk_past_standing_robot(bool sees_robot) {
  const SocialForceModel model;
  const RobotDisc robot{{5.0, 0.05}, {0.0, 0.0}, 0.3};
  std::vector<Walker> walkers{walker_at({0.0, 0.0}, {{10.0, 0.0}})};
  walkers[0].sees_robot = sees_robot;
  double closest = 1e9;
  for (int k = 0; k < 3000 && !reached_final_goal(walkers[0]); ++k) {
    EXPECT_TRUE(model.step(walkers, {}, &robot, 0.01).ok());
    closest = std::min(closest, geometry::distance(walkers[0].position, robot.centre));
  }
  return {closest, reached_final_goal(walkers[0])};
}

TEST(CrowdSocialForce, WalkerGoesAroundARobotItSees) {
  const auto [closest, arrived] = walk_past_standing_robot(true);
  EXPECT_GT(closest, 0.25 + 0.3);
  EXPECT_TRUE(arrived);
}

TEST(CrowdSocialForce, BlindWalkerWalksThroughTheRobotsPlace) {
  const auto [closest, arrived] = walk_past_standing_robot(false);
  EXPECT_LT(closest, 0.25 + 0.3);
  EXPECT_LT(closest, 0.06);  // straight on: the robot's 0.05 m offset is all that separates them
  EXPECT_TRUE(arrived);
}

TEST(CrowdSocialForce, FreeWalkerReachesDesiredSpeed) {
  const SocialForceModel model;
  std::vector<Walker> walkers{walker_at({0.0, 0.0}, {{30.0, 0.0}})};
  walkers[0].desired_speed_m_s = 1.1;
  for (int k = 0; k < 30; ++k) ASSERT_TRUE(model.step(walkers, {}, nullptr, 0.1).ok());
  // v(t) = v0 (1 - exp(-t / tau)): after 3 s that is 99.8 % of v0.
  EXPECT_NEAR(msg::norm(walkers[0].velocity), 1.1, 0.11);
  EXPECT_NEAR(walkers[0].velocity.x_m, 1.1 * (1.0 - std::exp(-3.0 / 0.5)), 0.01);
  EXPECT_NEAR(walkers[0].velocity.y_m, 0.0, 1e-12);
  // Over the 3 s it covered v0 (t - tau (1 - exp(-t / tau))) = 1.1 * 2.50124 = 2.751 m.
  EXPECT_NEAR(walkers[0].position.x_m, 2.751, 0.02);
}

TEST(CrowdSocialForce, RouteAdvancesThroughWaypoints) {
  const SocialForceModel model;
  std::vector<Walker> walkers{walker_at({0.0, 0.0}, {{3.0, 0.0}, {3.0, 3.0}, {0.0, 3.0}})};
  EXPECT_FALSE(reached_final_goal(walkers[0]));
  double farthest_x = 0.0;
  int k = 0;
  for (; k < 2000 && !reached_final_goal(walkers[0]); ++k) {
    ASSERT_TRUE(model.step(walkers, {}, nullptr, 0.01).ok());
    farthest_x = std::max(farthest_x, walkers[0].position.x_m);
  }
  EXPECT_TRUE(reached_final_goal(walkers[0]));
  EXPECT_GT(farthest_x, 2.6);  // it went by (3, 0) rather than straight to (0, 3)
  EXPECT_LT(geometry::distance(walkers[0].position, {0.0, 3.0}), 0.3);
  EXPECT_GT(k, 600);  // about 9 m at 1.3 m/s
  // Arrived, it brakes and stands.
  for (int s = 0; s < 300; ++s) ASSERT_TRUE(model.step(walkers, {}, nullptr, 0.01).ok());
  EXPECT_LT(msg::norm(walkers[0].velocity), 0.01);  // 1.3 exp(-3 / 0.5) = 0.003 m/s
  EXPECT_LT(geometry::distance(walkers[0].position, {0.0, 3.0}), 1.0);
}

TEST(CrowdSocialForce, SpeedIsCappedAtFactorTimesDesired) {
  const SocialForceModel model;
  // Shoved at 5 m/s towards its goal, a walker (v0 = 1.3 m/s) is capped at 1.3 * 1.3 = 1.69 m/s.
  std::vector<Walker> walkers{walker_at({0.0, 0.0}, {{10.0, 0.0}})};
  walkers[0].velocity = {5.0, 0.0};
  ASSERT_TRUE(model.step(walkers, {}, nullptr, 0.01).ok());
  EXPECT_NEAR(walkers[0].velocity.x_m, 1.69, 1e-12);
  EXPECT_NEAR(walkers[0].position.x_m, 0.0169, 1e-12);
}

TEST(CrowdSocialForce, RejectsWhatItCannotDo) {
  const SocialForceModel model;
  Walker w;
  const std::vector<Point2D> nine(kMaxGoals + 1);
  const Status too_long = set_route(w, nine);
  ASSERT_FALSE(too_long.ok());
  EXPECT_EQ(too_long.error().code(), Errc::capacity);
  EXPECT_EQ(w.goal_count, 0u);
  std::vector<Walker> many(kMaxWalkers + 1);
  const Status too_many = model.step(many, {}, nullptr, 0.01);
  ASSERT_FALSE(too_many.ok());
  EXPECT_EQ(too_many.error().code(), Errc::capacity);
  std::vector<Walker> one{walker_at({0.0, 0.0}, {{1.0, 0.0}})};
  EXPECT_FALSE(model.step(one, {}, nullptr, 0.0).ok());
  EXPECT_FALSE(model.step(one, {}, nullptr, std::nan("")).ok());
  EXPECT_EQ(one[0].position.x_m, 0.0);
}

// Six walkers crossing in a corridor with a robot: enough contact to exercise every term.
std::vector<Walker> crossing_crowd() {
  std::vector<Walker> w{
      walker_at({0.0, 0.3}, {{8.0, 0.4}}),   walker_at({8.0, 0.5}, {{0.0, 0.2}}),
      walker_at({0.5, -0.4}, {{8.0, -0.5}}), walker_at({7.5, -0.3}, {{0.0, 0.6}}),
      walker_at({4.0, -1.0}, {{4.2, 1.0}}),  walker_at({4.1, 1.0}, {{3.9, -1.0}, {0.0, 0.0}}),
  };
  w[3].sees_robot = false;
  w[4].radius_m = 0.3;
  w[5].desired_speed_m_s = 0.9;
  return w;
}
const std::vector<Wall> kCorridor{{{-1.0, -1.3}, {9.0, -1.3}}, {{-1.0, 1.3}, {9.0, 1.3}}};
const RobotDisc kRobot{{4.0, 0.0}, {0.2, 0.0}, 0.3};

TEST(CrowdSocialForce, StepIsDeterministicAndOrderIndependent) {
  const SocialForceModel model;
  std::vector<Walker> a = crossing_crowd();
  std::vector<Walker> b = crossing_crowd();
  std::vector<Walker> reversed = crossing_crowd();
  std::reverse(reversed.begin(), reversed.end());
  double closest = 1e9;
  for (int k = 0; k < 40; ++k) {
    ASSERT_TRUE(model.step(a, kCorridor, &kRobot, 0.05).ok());
    ASSERT_TRUE(model.step(b, kCorridor, &kRobot, 0.05).ok());
    ASSERT_TRUE(model.step(reversed, kCorridor, &kRobot, 0.05).ok());
    for (std::size_t i = 0; i < a.size(); ++i) {
      for (std::size_t j = i + 1; j < a.size(); ++j) closest = std::min(closest, geometry::distance(a[i].position, a[j].position));
    }
  }
  EXPECT_LT(closest, 1.0);  // they did interact
  for (std::size_t i = 0; i < a.size(); ++i) {
    EXPECT_EQ(std::memcmp(&a[i].position, &b[i].position, sizeof(Point2D)), 0);
    EXPECT_EQ(std::memcmp(&a[i].velocity, &b[i].velocity, sizeof(Point2D)), 0);
    EXPECT_EQ(a[i].next_goal, b[i].next_goal);
    const Walker& r = reversed[a.size() - 1 - i];
    EXPECT_NEAR(a[i].position.x_m, r.position.x_m, 1e-12);
    EXPECT_NEAR(a[i].position.y_m, r.position.y_m, 1e-12);
    EXPECT_NEAR(a[i].velocity.x_m, r.velocity.x_m, 1e-12);
    EXPECT_NEAR(a[i].velocity.y_m, r.velocity.y_m, 1e-12);
    EXPECT_EQ(a[i].next_goal, r.next_goal);
  }
}

TEST(CrowdSocialForce, StepAllocatesNothing) {
  const SocialForceModel model;
  std::vector<Walker> walkers = crossing_crowd();
  walkers.resize(kMaxWalkers);
  for (std::size_t i = 6; i < walkers.size(); ++i) {
    walkers[i].position = {0.5 * static_cast<double>(i % 16), 3.0 + 0.5 * static_cast<double>(i / 16)};
  }
  AllocationScope scope;
  for (int k = 0; k < 20; ++k) ASSERT_TRUE(model.step(walkers, kCorridor, &kRobot, 0.05).ok());
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(scope.malloc_calls(), 0u);
}

}  // namespace
}  // namespace sen3bot::crowd
