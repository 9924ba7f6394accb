// A crowd in the simulated world: its people are the world's movers, placed by the model at
// every simulation step, seen by the laser as legs, counted by the ground truth, and judged for
// contacts like any mover. The robot stands (no firmware drives it).
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <memory>
#include <optional>
#include <span>

#include "sen3bot/crowd/crowd.hpp"
#include "sen3bot/detector/protocol.hpp"
#include "sim_rig.hpp"

namespace sen3bot::sim {
namespace {

// The arena (config/dol_arena.yaml): an empty 10 x 6 m room, the robot at (1, 3) m facing +x.
// One person walks from `from` to `to`; by default from (4, 3.05) m to (0.4, 3.05) m, straight
// through the robot's place. `camera`: the simulated detector on, missing nothing, inventing
// nothing.
testing::SimRig arena_with_walker(crowd::Behaviour behaviour, msg::Point2D from = {4.0, 3.05},
                                  msg::Point2D to = {0.4, 3.05}, bool camera = false) {
  testing::SimRig rig = testing::load_sim_rig(SEN3BOT_SOURCE_DIR "/config/dol_arena.yaml");
  if (camera) {
    rig.world.detector.enabled = true;
    rig.world.detector.miss_rate = 0.0;
    rig.world.detector.false_positive_rate = 0.0;
  }
  auto config = std::make_shared<crowd::CrowdConfig>();
  config->behaviour = behaviour;
  crowd::Person walker;
  walker.start = from;
  walker.goals[0] = to;
  walker.goal_count = 1;
  config->people.push_back(walker);
  rig.world.crowd = config;
  rig.make_board();
  return rig;
}

struct Watched {
  std::uint64_t contacts = 0, moving_contacts = 0;
  double nearest_person_m = 1e9;
  double start_x_m = 0, end_x_m = 0;
  bool seen_by_truth = false;
  bool legs_seen = false;
};

Watched walk(testing::SimRig& rig, double seconds) {
  Simulation& sim = rig.board->simulation();
  const std::size_t person = sim.first_crowd_mover();
  Watched w;
  w.start_x_m = sim.world().mover_position(person).x_m;
  for (hal::Nanos t = 0; t <= hal::millis(static_cast<std::int64_t>(seconds * 1000)); t += hal::millis(5)) {
    sim.step(t);
    const GroundTruth& truth = sim.truth();
    w.nearest_person_m = std::min(w.nearest_person_m, truth.nearest_person_m);
    w.seen_by_truth = w.seen_by_truth || truth.people_count == 1;
    // Beams fanned over the person (+-10 degrees at 0.5) stop at the nearer leg's surface: the
    // laser sees legs (a stride puts the front one ahead of the body's 0.25 m edge), not a disc.
    const nav::Point2D p = sim.world().mover_position(person);
    const double dx = p.x_m - truth.pose.x_m, dy = p.y_m - truth.pose.y_m;
    const double d = std::hypot(dx, dy);
    if (d > 1.0 && sim.world().mover_visible(person)) {
      std::array<float, 41> ranges{};
      const double step = 0.5 * M_PI / 180.0;
      sim.world().scan({truth.pose.x_m, truth.pose.y_m, std::atan2(dy, dx)}, -20 * step, step, ranges.size(), 10.0,
                       ranges);
      const double nearest = *std::min_element(ranges.begin(), ranges.end());
      double leg_m = 1e9;
      for (const nav::Point2D& leg : sim.world().mover_legs(person))
        leg_m = std::min(leg_m, std::hypot(leg.x_m - truth.pose.x_m, leg.y_m - truth.pose.y_m) - crowd::kLegRadiusM);
      EXPECT_NEAR(nearest, leg_m, 0.01);
      w.legs_seen = w.legs_seen || std::abs(nearest - leg_m) < 0.01;
    }
  }
  w.contacts = sim.truth().contacts;
  w.moving_contacts = sim.truth().moving_contacts;
  w.end_x_m = sim.world().mover_position(person).x_m;
  return w;
}

TEST(CrowdSimulation, ASocialWalkerGivesWayToTheStandingRobot) {
  testing::SimRig rig = arena_with_walker(crowd::Behaviour::social);
  const Watched w = walk(rig, 8.0);
  EXPECT_EQ(w.contacts, 0u);
  EXPECT_TRUE(w.seen_by_truth);
  EXPECT_TRUE(w.legs_seen);
  EXPECT_NEAR(w.start_x_m, 4.0, 1e-9);
  EXPECT_LT(w.end_x_m, 0.8) << "the walker went round the robot to its goal";
  EXPECT_GT(w.nearest_person_m, 0.3) << "centre to centre";
}

TEST(CrowdSimulation, ABlindWalkerWalksIntoTheRobotAndTheContactIsNotTheRobots) {
  testing::SimRig rig = arena_with_walker(crowd::Behaviour::blind);
  const Watched w = walk(rig, 8.0);
  EXPECT_GE(w.contacts, 1u);
  EXPECT_EQ(w.moving_contacts, 0u);  // the robot stood still
  EXPECT_LT(w.nearest_person_m, 0.2);
}

TEST(CrowdSimulation, TheCameraSeesTheCrowdsWalkersAsPeople) {
  // Ahead of the robot, walking away from it.
  testing::SimRig rig = arena_with_walker(crowd::Behaviour::blind, {3.0, 3.2}, {8.0, 3.2}, true);
  ASSERT_TRUE(rig.board->start());
  rig.clock().advance_to(hal::millis(1000));
  std::size_t frames = 0, boxes = 0;
  std::array<std::uint8_t, detector::kMaxDatagramBytes> bytes{};
  for (;;) {
    Result<std::optional<std::size_t>> got = rig.board->detector().receive(bytes);
    ASSERT_TRUE(got);
    if (!got->has_value()) break;
    detector::Datagram d;
    detector::Reject why{};
    ASSERT_TRUE(detector::decode(std::span<const std::uint8_t>(bytes.data(), **got), d, why));
    ++frames;
    boxes += d.count;
  }
  rig.board->stop();
  EXPECT_GE(frames, 8u);  // 10 Hz, 0.1 s latency
  EXPECT_EQ(boxes, frames) << "one box per frame: the walker";
}

TEST(CrowdSimulation, TheTruePeopleAreTheNearestWalkersWithTheirVelocities) {
  testing::SimRig rig = testing::load_sim_rig(SEN3BOT_SOURCE_DIR "/config/dol_arena.yaml");
  auto config = std::make_shared<crowd::CrowdConfig>();
  config->behaviour = crowd::Behaviour::blind;
  // 20 people standing in a row away from the robot at (1, 3) m, the nearest first; one walking.
  for (int i = 0; i < 20; ++i) {
    crowd::Person p;
    p.start = {1.6 + 0.4 * i, i % 2 == 0 ? 1.0 : 5.0};
    p.goals[0] = p.start;
    p.goal_count = 1;
    config->people.push_back(p);
  }
  config->people[0].start = {1.6, 2.0};
  config->people[0].goals[0] = {9.0, 2.0};
  rig.world.crowd = config;
  rig.make_board();
  rig.board->publish_true_people();
  ASSERT_TRUE(rig.board->start());
  rig.clock().advance_to(hal::millis(1000));
  tasks::Sample<msg::People> people;
  ASSERT_TRUE(rig.board->true_people().read(people));
  rig.board->stop();
  ASSERT_EQ(people.value.count, msg::People::kMax);
  const std::size_t first = rig.board->simulation().first_crowd_mover();
  double last_d = 0.0;
  for (std::size_t k = 0; k < people.value.count; ++k) {
    const msg::TrackedPerson& p = people.value.items[k];
    const std::size_t mover = p.id - 1;
    ASSERT_GE(mover, first);
    EXPECT_LT(mover - first, msg::People::kMax) << "the 16 nearest of 20";
    const double d = std::hypot(p.x_m - 1.0, p.y_m - 3.0);
    EXPECT_GE(d, last_d) << "nearest first";
    last_d = d;
    EXPECT_NEAR(p.width_m, 2 * config->people[mover - first].radius_m, 1e-9);
    EXPECT_EQ(p.last_seen_ns, people.stamp_ns);
    if (mover == first) {
      EXPECT_GT(p.vx_m_s, 0.3) << "walking away, +x";
      EXPECT_EQ(p.state, msg::PersonState::dynamic_person);
    } else {
      EXPECT_EQ(p.state, msg::PersonState::static_person);
    }
  }
}

TEST(CrowdSimulation, ABadCrowdIsAClearErrorOfTheSimulation) {
  testing::SimRig rig = testing::load_sim_rig(SEN3BOT_SOURCE_DIR "/config/dol_arena.yaml");
  auto config = std::make_shared<crowd::CrowdConfig>();
  crowd::Person walker;
  walker.desired_speed_m_s = -1.0;
  config->people.push_back(walker);
  rig.world.crowd = config;
  Result<std::unique_ptr<SimBoard>> created = SimBoard::create(rig.world, true);
  ASSERT_FALSE(created);
  EXPECT_NE(std::string(created.error().c_str()).find("crowd"), std::string::npos) << created.error().c_str();
  EXPECT_NE(std::string(created.error().c_str()).find("person 0"), std::string::npos) << created.error().c_str();
}

}  // namespace
}  // namespace sen3bot::sim
