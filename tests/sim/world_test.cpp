#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <utility>
#include <vector>

#include "sen3bot/world/world.hpp"

namespace sen3bot::world {
namespace {

// 4 x 4 m room at 0.05 m with one-cell walls on every side.
nav::OccupancyMap room() {
  nav::OccupancyMap m(80, 80, 0.05, 0.0, 0.0);
  for (int i = 0; i < 80; ++i) {
    m.set(i, 0, 100);
    m.set(i, 79, 100);
    m.set(0, i, 100);
    m.set(79, i, 100);
  }
  return m;
}

TEST(World, RaysHitWallsAtExactDistances) {
  const World w(room());
  EXPECT_NEAR(w.cast_ray(2.0, 2.0, 0.0, 10.0), 1.95, 1e-9);          // wall cell starts at 3.95
  EXPECT_NEAR(w.cast_ray(2.0, 2.0, M_PI, 10.0), 1.95, 1e-9);         // wall cell ends at 0.05
  EXPECT_NEAR(w.cast_ray(2.0, 2.0, M_PI / 2.0, 10.0), 1.95, 1e-9);
  EXPECT_NEAR(w.cast_ray(2.0, 2.0, M_PI / 4.0, 10.0), 1.95 * std::sqrt(2.0), 1e-9);
  EXPECT_DOUBLE_EQ(w.cast_ray(2.0, 2.0, 0.0, 1.0), 1.0);  // max range when nothing nearer
}

TEST(World, RotatedMapOriginIsHonoured) {
  nav::OccupancyMap m(40, 40, 0.05, 2.0, 0.0, M_PI / 2.0);  // grid +x is map +y
  for (int r = 0; r < 40; ++r) m.set(30, r, 100);              // a wall at map y in [1.5, 1.55)
  const World w(m);
  EXPECT_NEAR(w.cast_ray(1.0, 0.5, M_PI / 2.0, 5.0), 1.0, 1e-9);
}

TEST(World, MoversWalkPolylinesDeterministically) {
  World w(room());
  MoverScript person;
  person.path = {{1.0, 1.0}, {3.0, 1.0}};
  person.speed_m_s = 0.5;
  person.person = true;
  const auto id = w.add_mover(person);
  w.set_time(2.0);
  EXPECT_NEAR(w.mover_position(id).x_m, 2.0, 1e-12);
  w.set_time(5.0);  // 2.5 m walked: at the end and 0.5 m back
  EXPECT_NEAR(w.mover_position(id).x_m, 2.5, 1e-12);
  MoverScript loop = person;
  loop.path = {{1.0, 1.0}, {2.0, 1.0}, {2.0, 2.0}};
  loop.loop = true;
  loop.speed_m_s = 1.0;
  const auto id2 = w.add_mover(loop);
  w.set_time(2.0 + std::sqrt(2.0) + 0.25);  // once round plus 0.25 m
  EXPECT_NEAR(w.mover_position(id2).x_m, 1.25, 1e-9);
  EXPECT_NEAR(w.mover_position(id2).y_m, 1.0, 1e-9);
}

TEST(World, PhaseStartsAMoverPartWayRoundItsCycle) {
  World w(room());
  MoverScript box;
  box.path = {{1.0, 1.0}, {1.0, 3.0}};  // 2 m there, 2 m back: a 4 m ping-pong cycle
  box.speed_m_s = 0.5;
  box.shape = MoverShape::square;
  box.size_m = 0.2;
  box.start_time_s = 1.0;
  box.phase_m = 1.5;
  const auto there = w.add_mover(box);
  box.phase_m = 3.0;  // past the far end: on the way back
  const auto back = w.add_mover(box);
  box.phase_m = 4.0 + 0.5;  // a whole cycle and 0.5 m
  const auto wrapped = w.add_mover(box);
  w.set_time(0.0);  // before the start: waits at its phase's place
  EXPECT_NEAR(w.mover_position(there).y_m, 2.5, 1e-12);
  EXPECT_NEAR(w.mover_position(back).y_m, 2.0, 1e-12);
  EXPECT_NEAR(w.mover_position(wrapped).y_m, 1.5, 1e-12);
  w.set_time(2.0);  // 0.5 m walked since the start
  EXPECT_NEAR(w.mover_position(there).y_m, 3.0, 1e-12);
  EXPECT_NEAR(w.mover_position(back).y_m, 1.5, 1e-12);
  EXPECT_NEAR(w.mover_position(wrapped).y_m, 2.0, 1e-12);
  EXPECT_NEAR(w.mover_position(there).x_m, 1.0, 1e-12);
  w.set_time(3.0);  // 1 m walked: `there` turned at the far end and came 0.5 m back
  EXPECT_NEAR(w.mover_position(there).y_m, 2.5, 1e-12);

  MoverScript loop;  // a loop's cycle is once round: 1 + 1 + sqrt(2) m
  loop.path = {{1.0, 1.0}, {2.0, 1.0}, {2.0, 2.0}};
  loop.loop = true;
  loop.speed_m_s = 1.0;
  loop.phase_m = 1.25;
  const auto round = w.add_mover(loop);
  w.set_time(0.0);
  EXPECT_NEAR(w.mover_position(round).x_m, 2.0, 1e-9);
  EXPECT_NEAR(w.mover_position(round).y_m, 1.25, 1e-9);
  w.set_time(2.0 + std::sqrt(2.0));  // once round more: the same place
  EXPECT_NEAR(w.mover_position(round).x_m, 2.0, 1e-9);
  EXPECT_NEAR(w.mover_position(round).y_m, 1.25, 1e-9);
}

TEST(World, AWalkerSlowsToTurnBackAndSetsOffAgain) {
  World w(room());
  MoverScript person;
  person.path = {{1.0, 1.0}, {3.0, 1.0}};  // 2 m at 1 m/s, speeding up and slowing at 1 m/s^2
  person.speed_m_s = 1.0;
  person.accel_m_s2 = 1.0;
  person.person = true;
  const auto id = w.add_mover(person);
  // Each leg: 1 s up to speed (0.5 m), 1 s at speed, 1 s down (0.5 m): 3 s.
  const auto x_at = [&](double t) {
    w.set_time(t);
    return w.mover_position(id).x_m;
  };
  EXPECT_NEAR(x_at(0.5), 1.125, 1e-9);   // half a second in: 0.5 a t^2
  EXPECT_NEAR(x_at(1.5), 2.0, 1e-9);     // at full speed, mid-way
  EXPECT_NEAR(x_at(2.5), 2.875, 1e-9);   // slowing
  EXPECT_NEAR(x_at(3.0), 3.0, 1e-9);     // stopped at the end
  EXPECT_NEAR(x_at(3.5), 2.875, 1e-9);   // and back the same way
  EXPECT_NEAR(x_at(6.0), 1.0, 1e-9);
  // Too short a leg to reach full speed: up half way, down the other half.
  MoverScript short_walk = person;
  short_walk.path = {{1.0, 2.0}, {1.5, 2.0}};
  const auto id2 = w.add_mover(short_walk);
  w.set_time(std::sqrt(0.5));  // the middle, reached after sqrt(leg / a)
  EXPECT_NEAR(w.mover_position(id2).x_m, 1.25, 1e-9);
}

TEST(World, ScanSeesMoversOnlyOnceVisible) {
  World w(room());
  MoverScript box;
  box.path = {{3.0, 2.0}};
  box.size_m = 0.2;
  box.shape = MoverShape::square;
  box.appear_time_s = 1.0;
  w.add_mover(box);
  std::vector<float> ranges(181);
  const Pose2D sensor{2.0, 2.0, 0.0};
  w.scan(sensor, -M_PI / 2.0, M_PI / 180.0, 181, 8.0, ranges);
  EXPECT_NEAR(ranges[90], 1.95, 1e-6);
  w.set_time(1.0);
  w.scan(sensor, -M_PI / 2.0, M_PI / 180.0, 181, 8.0, ranges);
  EXPECT_NEAR(ranges[90], 0.9, 1e-6);
  EXPECT_NEAR(ranges[0], 1.95, 1e-6);
}

// Runs of consecutive beams that hit something nearer than `limit_m`: what a laser sees as
// separate objects. Each run's first and last beam.
std::vector<std::pair<std::size_t, std::size_t>> hit_runs(const std::vector<float>& ranges, double limit_m) {
  std::vector<std::pair<std::size_t, std::size_t>> runs;
  for (std::size_t i = 0; i < ranges.size(); ++i) {
    if (ranges[i] >= limit_m) continue;
    if (!runs.empty() && runs.back().second + 1 == i) runs.back().second = i;
    else runs.emplace_back(i, i);
  }
  return runs;
}

// A person walking across the laser's view at 1.3 m/s, 2 m ahead: the LMS200's 0.5 degree
// beams see two legs whose fore-aft spacing follows the gait (one step length apart at most,
// side by side twice per stride), never the body's 0.5 m disc.
TEST(World, APersonWithLegsIsTwoArcsThatSwingWithTheGait) {
  World w(room());
  MoverScript person;
  person.path = {{0.5, 3.0}, {3.5, 3.0}};
  person.speed_m_s = 1.3;
  person.size_m = 0.5;
  person.person = true;
  person.legs = true;
  const std::size_t i = w.add_mover(person);
  const Pose2D sensor{2.0, 1.0, M_PI / 2.0};  // looking along +y, the person crosses along x
  const double increment = 0.5 * M_PI / 180.0;
  std::vector<float> ranges(121);  // +-30 degrees: the person, and the far wall beyond 2.5 m
  double widest_m = 0.0, narrowest_m = 1e9;
  int two_runs = 0, frames = 0;
  for (double t = 0.8; t <= 1.5; t += 0.01) {  // about a stride, near the middle of the view
    w.set_time(t);
    const auto legs = w.mover_legs(i);
    const double spacing = std::abs(legs[0].x_m - legs[1].x_m);
    widest_m = std::max(widest_m, spacing);
    narrowest_m = std::min(narrowest_m, spacing);
    // The legs sit 0.1 m either side of the walking line, 2 m from the sensor.
    EXPECT_NEAR(std::abs(legs[0].y_m - legs[1].y_m), 2.0 * crowd::kLegSpreadM, 1e-9);
    w.scan(sensor, -M_PI / 6.0, increment, ranges.size(), 8.0, ranges);
    const auto runs = hit_runs(ranges, 2.5);
    ++frames;
    if (spacing > 0.3) {
      ASSERT_EQ(runs.size(), 2u) << "t " << t;
      ++two_runs;
      // Each arc is a 0.12 m leg at about 2 m (3.4 degrees: 7 beams), not the 0.5 m body (29).
      for (const auto& [a, b] : runs) EXPECT_LE(b - a + 1, 8u) << "t " << t;
    }
    for (const auto& [a, b] : runs) {
      // The nearer leg's edge is 1.84 m away at the closest; the body's would be 1.75 m.
      for (std::size_t k = a; k <= b; ++k) EXPECT_GT(ranges[k], 1.83f);
    }
  }
  // Step length at 1.3 m/s is 1.3^0.42 / 1.6 = 0.70 m: the legs' spacing swings from 0 to it.
  EXPECT_NEAR(widest_m, crowd::step_length_m(1.3), 0.02);
  EXPECT_LT(narrowest_m, 0.05);
  EXPECT_GT(two_runs, frames / 4);
}

TEST(World, ADrivenMoverStaysWherePlacedAndStandsWithItsFeetTogether) {
  World w(room());
  MoverScript person;
  person.path = {{1.0, 1.0}, {3.0, 1.0}};  // ignored: a model drives it
  person.speed_m_s = 1.0;
  person.size_m = 0.5;
  person.person = true;
  person.legs = true;
  person.driven = true;
  const std::size_t i = w.add_mover(person);
  w.place_mover(i, {2.0, 3.0}, {0.0, 1.0}, true);
  w.set_time(1.0);
  EXPECT_DOUBLE_EQ(w.mover_position(i).x_m, 2.0);
  EXPECT_DOUBLE_EQ(w.mover_position(i).y_m, 3.0);
  EXPECT_DOUBLE_EQ(w.mover_velocity(i).y_m, 1.0);
  EXPECT_TRUE(w.mover_visible(i));
  // Its body counts for contacts.
  EXPECT_TRUE(w.collides({2.0, 2.6, 0.0}, Footprint::circle(0.2)));
  w.place_mover(i, {2.0, 3.0}, {0.0, 0.0}, true);
  w.set_time(2.0);
  const auto legs = w.mover_legs(i);
  // Standing: side by side across its last heading (+y), 2 kLegSpreadM apart.
  EXPECT_NEAR(std::abs(legs[0].x_m - legs[1].x_m), 2.0 * crowd::kLegSpreadM, 1e-6);
  EXPECT_NEAR(legs[0].y_m, legs[1].y_m, 1e-6);
  w.place_mover(i, {2.0, 3.0}, {0.0, 0.0}, false);
  EXPECT_FALSE(w.collides({2.0, 2.6, 0.0}, Footprint::circle(0.2)));
  EXPECT_DOUBLE_EQ(w.cast_ray(2.0, 1.0, M_PI / 2.0, 8.0), 2.95);  // the wall behind, nothing else
}

TEST(World, NoisyScanIsSeeded) {
  WorldConfig cfg;
  cfg.range_noise_sigma_m = 0.01;
  cfg.seed = 7;
  World a(room(), cfg);
  World b(room(), cfg);
  std::vector<float> ra(50);
  std::vector<float> rb(50);
  a.noisy_scan({2.0, 2.0, 0.3}, -1.0, 0.04, 50, 8.0, ra);
  b.noisy_scan({2.0, 2.0, 0.3}, -1.0, 0.04, 50, 8.0, rb);
  EXPECT_EQ(ra, rb);
  const World clean(room());
  std::vector<float> rc(50);
  clean.scan({2.0, 2.0, 0.3}, -1.0, 0.04, 50, 8.0, rc);
  EXPECT_NE(ra, rc);
}

TEST(World, FootprintCollisions) {
  World w(room());
  const auto pioneer = nav::Footprint::pioneer();
  EXPECT_FALSE(w.collides({2.0, 2.0, 0.0}, pioneer));
  EXPECT_FALSE(w.collides({0.3, 2.0, 0.0}, pioneer));  // 0.2275 m half length, wall ends at 0.05
  EXPECT_TRUE(w.collides({0.25, 2.0, 0.0}, pioneer));
  EXPECT_FALSE(w.collides({0.25, 2.0, M_PI / 2.0}, pioneer));  // turned: half width 0.19 m
  EXPECT_TRUE(w.collides({0.2, 2.0, 0.0}, nav::Footprint::circle(0.26)));
  MoverScript person;
  person.path = {{2.6, 2.0}};
  person.size_m = 0.4;
  w.add_mover(person);
  EXPECT_TRUE(w.collides({2.2, 2.0, 0.0}, pioneer));
  EXPECT_FALSE(w.collides({1.8, 2.0, 0.0}, pioneer));
  EXPECT_NEAR(w.clearance_m({1.8, 2.0, 0.0}, pioneer, 2.0), 2.6 - 0.2 - (1.8 + 0.2275), 1e-9);
}

TEST(World, AContactIsTheRobotsWhenItsMotionClosesOnWhatItTouches) {
  World w(room());
  const auto pioneer = nav::Footprint::pioneer();
  MoverScript person;
  person.path = {{2.6, 2.0}};
  person.size_m = 0.4;
  w.add_mover(person);
  const Pose2D touching{2.2, 2.0, 0.0};  // the person ahead, overlapping the nose
  EXPECT_EQ(w.touching_mover(touching, pioneer), 0);
  EXPECT_FALSE(w.touches_map(touching, pioneer));
  EXPECT_TRUE(w.robot_closing(touching, pioneer, 0.3, 0.02));    // driving into them
  EXPECT_FALSE(w.robot_closing(touching, pioneer, 0.01, 0.02));  // standing
  EXPECT_FALSE(w.robot_closing(touching, pioneer, -0.1, 0.02));  // backing away
  // Facing away, driving on: they caught up with the robot's back.
  EXPECT_FALSE(w.robot_closing({3.0, 2.0, 0.0}, pioneer, 0.3, 0.02));
  // Beside the robot's flank: driving past at right angles closes on nothing; turned 0.5 rad
  // towards them it does, 0.5 rad away it does not.
  const Pose2D flank{2.25, 2.0, M_PI / 2.0};
  EXPECT_EQ(w.touching_mover(flank, pioneer), 0);
  EXPECT_FALSE(w.robot_closing(flank, pioneer, 0.3, 0.02));
  EXPECT_TRUE(w.robot_closing({2.25, 2.0, M_PI / 2.0 - 0.5}, pioneer, 0.3, 0.02));
  EXPECT_FALSE(w.robot_closing({2.25, 2.0, M_PI / 2.0 + 0.5}, pioneer, 0.3, 0.02));
  // The wall at any speed above the threshold, either way.
  EXPECT_TRUE(w.touches_map({0.25, 2.0, 0.0}, pioneer));
  EXPECT_TRUE(w.robot_closing({0.25, 2.0, 0.0}, pioneer, 0.05, 0.02));
  EXPECT_TRUE(w.robot_closing({0.25, 2.0, 0.0}, pioneer, -0.05, 0.02));
}

}  // namespace
}  // namespace sen3bot::world
