// The crowd the simulator runs: configs refused with what is wrong; social walkers crossing a
// square without touching; a walker giving way to a robot it sees and walking through the place
// of one it does not; CrowdNav's ORCA circle crossing without contact, people standing on or
// leaving at their goals; people appearing on time without disturbing anyone before; recorded
// people exactly on their annotations; no allocation per step; the same result however the
// world's calls split the time.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <initializer_list>
#include <limits>
#include <memory>
#include <numbers>
#include <string>
#include <utility>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/crowd/crowd.hpp"

namespace sen3bot::crowd {
namespace {

using mem::testing::AllocationScope;

constexpr double kNan = std::numeric_limits<double>::quiet_NaN();
constexpr double kInf = std::numeric_limits<double>::infinity();

Person person(Point2D start, std::initializer_list<Point2D> goals) {
  Person p;
  p.start = start;
  for (const Point2D g : goals) p.goals[p.goal_count++] = g;
  return p;
}

std::unique_ptr<Crowd> make(const CrowdConfig& config) {
  Result<std::unique_ptr<Crowd>> crowd = Crowd::create(config);
  EXPECT_TRUE(crowd.ok()) << crowd.error().message();
  return crowd.ok() ? std::move(crowd).value() : nullptr;
}

Point2D final_goal(const Person& p) { return p.goals[p.goal_count - 1]; }

std::shared_ptr<const Recording> recording(std::string_view text) {
  Result<Recording> parsed = parse_recording(text, "test.txt");
  EXPECT_TRUE(parsed.ok()) << parsed.error().message();
  return std::make_shared<const Recording>(parsed.ok() ? std::move(parsed).value() : Recording{});
}

TEST(Crowd, BehavioursHaveNames) {
  for (const Behaviour b : {Behaviour::recorded, Behaviour::social, Behaviour::blind, Behaviour::orca}) {
    EXPECT_EQ(parse_behaviour(to_string(b)), b);
  }
  EXPECT_STREQ(to_string(Behaviour::orca), "orca");
  EXPECT_FALSE(parse_behaviour("ORCA").has_value());
  EXPECT_FALSE(parse_behaviour("").has_value());
}

TEST(Crowd, CreateRefusesBadConfigsSayingWhatIsWrong) {
  CrowdConfig good;
  good.people = {person({0, 0}, {{5, 0}}), person({0, 1}, {{5, 1}, {5, 3}}), person({0, 2}, {})};
  good.walls = {Wall{{-1, -1}, {6, -1}}, Wall{{-1, 4}, {6, 4}}};
  for (const Behaviour b : {Behaviour::social, Behaviour::blind, Behaviour::orca}) {
    CrowdConfig c = good;
    c.behaviour = b;
    EXPECT_TRUE(Crowd::create(c).ok()) << to_string(b);
  }

  struct Bad {
    void (*spoil)(CrowdConfig&);
    const char* says;
    Errc code;
  };
  const Bad bad[] = {
      {[](CrowdConfig& c) { c.step_s = 0.0; }, "step 0 s is not positive", Errc::invalid_argument},
      {[](CrowdConfig& c) { c.step_s = kNan; }, "step nan s is not positive", Errc::invalid_argument},
      {[](CrowdConfig& c) { c.people.resize(kMaxWalkers + 1, c.people[0]); }, "257 walkers, at most 256",
       Errc::capacity},
      {[](CrowdConfig& c) {
         c.behaviour = Behaviour::orca;
         c.people.resize(kMaxOrcaAgents + 1, c.people[0]);
       },
       "65 ORCA people, at most 64", Errc::capacity},
      {[](CrowdConfig& c) { c.people[2].desired_speed_m_s = 0.0; }, "person 2: desired speed 0 m/s",
       Errc::invalid_argument},
      {[](CrowdConfig& c) { c.people[1].radius_m = -0.1; }, "person 1: radius -0.1 m", Errc::invalid_argument},
      {[](CrowdConfig& c) { c.people[1].goals[1].y_m = kInf; }, "person 1: goal 1 is not finite",
       Errc::invalid_argument},
      {[](CrowdConfig& c) { c.people[0].start.x_m = kNan; }, "person 0: start is not finite", Errc::invalid_argument},
      {[](CrowdConfig& c) { c.people[1].goal_count = kMaxGoals + 1; }, "person 1: 9 goals, at most 8", Errc::capacity},
      {[](CrowdConfig& c) { c.people[2].appear_s = kNan; }, "person 2: appear time", Errc::invalid_argument},
      {[](CrowdConfig& c) { c.people[2].leave_at_goal = true; }, "person 2: leaves at its goal but has no goal",
       Errc::invalid_argument},
      {[](CrowdConfig& c) {
         c.people[0].leave_at_goal = true;
         c.people[0].loop = true;
       },
       "person 0: a looping route never ends", Errc::invalid_argument},
      {[](CrowdConfig& c) { c.walls[1].b.x_m = kInf; }, "wall 1: an end is not finite", Errc::invalid_argument},
      {[](CrowdConfig& c) { c.social.max_substep_s = 0.0; }, "in social sub-steps of 0 s", Errc::invalid_argument},
      {[](CrowdConfig& c) {
         c.behaviour = Behaviour::orca;
         c.orca.time_horizon_s = 0.0;
       },
       "ORCA time horizon 0 s", Errc::invalid_argument},
      {[](CrowdConfig& c) {
         c.behaviour = Behaviour::orca;
         c.people[1].desired_speed_m_s = kInf;
       },
       "person 1: desired speed inf m/s", Errc::invalid_argument},
      {[](CrowdConfig& c) { c.behaviour = static_cast<Behaviour>(9); }, "unknown behaviour 9", Errc::invalid_argument},
      {[](CrowdConfig& c) { c.behaviour = Behaviour::recorded; }, "a recorded crowd needs a recording",
       Errc::invalid_argument},
  };
  for (const Bad& b : bad) {
    CrowdConfig c = good;
    b.spoil(c);
    const Result<std::unique_ptr<Crowd>> crowd = Crowd::create(c);
    ASSERT_FALSE(crowd.ok()) << b.says;
    EXPECT_NE(crowd.error().message().find(b.says), std::string_view::npos)
        << "got: " << crowd.error().message() << "\nwant: " << b.says;
    EXPECT_EQ(crowd.error().code(), b.code) << b.says;
  }

  // Recorded crowds.
  CrowdConfig rec;
  rec.behaviour = Behaviour::recorded;
  rec.recording = recording("0 1 0 0\n10 1 0.4 0\n");
  EXPECT_TRUE(Crowd::create(rec).ok());
  auto refused = [](const CrowdConfig& c, std::string_view says) {
    const Result<std::unique_ptr<Crowd>> crowd = Crowd::create(c);
    ASSERT_FALSE(crowd.ok()) << says;
    EXPECT_NE(crowd.error().message().find(says), std::string_view::npos) << crowd.error().message();
  };
  CrowdConfig c = rec;
  c.radius_m = 0.0;
  refused(c, "radius 0 m of recorded people");
  c = rec;
  c.recording_offset.x_m = kInf;
  refused(c, "recording offset is not finite");
  c = rec;
  c.recording_start_s = kNan;
  refused(c, "recording start nan s");
  c = rec;
  c.recording_offset.x_m = 1.7e308;  // finite, but not with the annotations added
  auto far = std::make_shared<Recording>(*rec.recording);
  far->tracks[0].samples[1].position.x_m = 1.7e308;
  c.recording = far;
  refused(c, "recording track 0 (person 1): sample 1's position is not finite once offset");
  auto hand = std::make_shared<Recording>(*rec.recording);
  hand->tracks.push_back(Track{7, {}});
  c = rec;
  c.recording = hand;
  refused(c, "recording track 1 (person 7) is empty");
  hand->tracks[1].samples = {Sample{1.0, {}}, Sample{1.0, {1.0, 0.0}}};
  refused(c, "recording track 1 (person 7): sample 1's time is not finite and increasing");

  // What another behaviour uses is not looked at: ORCA ignores walls, recorded people people.
  CrowdConfig ignored = good;
  ignored.behaviour = Behaviour::orca;
  ignored.walls[0].a.x_m = kNan;
  EXPECT_TRUE(Crowd::create(ignored).ok());
  ignored = rec;
  ignored.people = {person({0, 0}, {})};
  ignored.people[0].radius_m = -1.0;
  ignored.step_s = 0.0;  // recorded people are replayed, not stepped
  EXPECT_TRUE(Crowd::create(ignored).ok());
}

// Eight walkers cross a free 8 m square: four between the midpoints of opposite sides, four
// between opposite corners, all meeting in the middle. Each is a few centimetres off the exact
// lines (the social force model stalls in exact head-on symmetry).
TEST(Crowd, SocialWalkersCrossASquareWithoutTouchingAndArrive) {
  CrowdConfig c;
  c.behaviour = Behaviour::social;
  c.people = {
      person({-4.0, 0.05}, {{4.0, 0.05}}),  person({4.0, -0.05}, {{-4.0, -0.05}}),
      person({0.05, -4.0}, {{0.05, 4.0}}),  person({-0.05, 4.0}, {{-0.05, -4.0}}),
      person({-4.0, -3.95}, {{4.0, 4.05}}), person({4.0, 3.95}, {{-4.0, -4.05}}),
      person({3.95, -4.0}, {{-4.05, 4.0}}), person({-3.95, 4.0}, {{4.05, -4.0}}),
  };
  c.people[2].desired_speed_m_s = 1.1;  // not all at one speed
  c.people[5].radius_m = 0.3;
  std::unique_ptr<Crowd> crowd = make(c);
  ASSERT_NE(crowd, nullptr);
  ASSERT_EQ(crowd->size(), c.people.size());
  std::vector<double> nearest_goal(c.people.size(), 1e9);
  double closest_gap = 1e9;  // centre distance less the radii
  for (int k = 1; k <= 600; ++k) {
    crowd->advance(k * c.step_s, nullptr);
    for (std::size_t i = 0; i < crowd->size(); ++i) {
      const PersonState a = crowd->state(i);
      ASSERT_TRUE(a.visible);
      nearest_goal[i] = std::min(nearest_goal[i], geometry::distance(a.position, final_goal(c.people[i])));
      for (std::size_t j = i + 1; j < crowd->size(); ++j) {
        const PersonState b = crowd->state(j);
        closest_gap = std::min(closest_gap, geometry::distance(a.position, b.position) - a.radius_m - b.radius_m);
      }
    }
  }
  EXPECT_DOUBLE_EQ(crowd->time_s(), 30.0);
  EXPECT_GT(closest_gap, 0.0);
  for (std::size_t i = 0; i < nearest_goal.size(); ++i) {
    EXPECT_LT(nearest_goal[i], c.social.goal_reach_m) << "person " << i;
  }
}

// One walker from (0, 0) to (10, 0) past a robot standing at (5, 0.05); the closest approach of
// the centres, sampled every step, and of the walker to its goal.
std::pair<double, double> walk_past_robot(Behaviour behaviour) {
  CrowdConfig c;
  c.behaviour = behaviour;
  c.people = {person({0.0, 0.0}, {{10.0, 0.0}})};
  std::unique_ptr<Crowd> crowd = make(c);
  if (!crowd) return {0.0, 1e9};
  const RobotDisc robot{{5.0, 0.05}, {0.0, 0.0}, 0.3};
  double closest = 1e9;
  double to_goal = 1e9;
  for (int k = 1; k <= 400; ++k) {
    crowd->advance(k * c.step_s, &robot);
    closest = std::min(closest, geometry::distance(crowd->state(0).position, robot.centre));
    to_goal = std::min(to_goal, geometry::distance(crowd->state(0).position, {10.0, 0.0}));
  }
  return {closest, to_goal};
}

TEST(Crowd, ASocialWalkerKeepsClearOfTheRobotABlindOneWalksThroughItsPlace) {
  const auto [social_closest, social_to_goal] = walk_past_robot(Behaviour::social);
  EXPECT_GT(social_closest, 0.25 + 0.3);
  EXPECT_LT(social_to_goal, 0.3);
  const auto [blind_closest, blind_to_goal] = walk_past_robot(Behaviour::blind);
  EXPECT_LT(blind_closest, 0.1);  // straight on: a step of 0.065 m and the 0.05 m offset apart
  EXPECT_LT(blind_to_goal, 0.3);
  // ORCA humans ignore the robot too.
  const auto [orca_closest, orca_to_goal] = walk_past_robot(Behaviour::orca);
  EXPECT_LT(orca_closest, 0.1);
  EXPECT_LT(orca_to_goal, 1e-9);
}

// CrowdNav's circle crossing: 5 humans of radius 0.3 m at 1 m/s on a circle of radius 4 m, each
// walking to the opposite point. Angles spread unevenly so they do not all meet at once.
CrowdConfig circle_crossing(double step_s, bool leave_at_goal) {
  CrowdConfig c;
  c.behaviour = Behaviour::orca;
  c.step_s = step_s;
  for (int i = 0; i < 5; ++i) {
    const double angle = 2.0 * std::numbers::pi * i / 5.0 + 0.3 * std::sin(1.7 * i);
    const Point2D start{4.0 * std::cos(angle), 4.0 * std::sin(angle)};
    Person p = person(start, {-start});
    p.desired_speed_m_s = 1.0;
    p.radius_m = 0.3;
    p.leave_at_goal = leave_at_goal;
    c.people.push_back(p);
  }
  return c;
}

TEST(Crowd, OrcaCircleCrossingWithoutContactStandingOnOrLeavingAtTheGoals) {
  for (const double step_s : {0.25, 0.05}) {
    for (const bool leave : {false, true}) {
      SCOPED_TRACE(testing::Message() << "step " << step_s << " s, leave " << leave);
      const CrowdConfig c = circle_crossing(step_s, leave);
      std::unique_ptr<Crowd> crowd = make(c);
      ASSERT_NE(crowd, nullptr);
      const std::size_t n = crowd->size();
      std::vector<PersonState> before(n);
      for (std::size_t i = 0; i < n; ++i) before[i] = crowd->state(i);
      std::vector<int> last_visible_step(n, 0);
      std::vector<int> vanished(n, 0);  // times a person went from visible to invisible
      double closest = 1e9;
      const int steps = static_cast<int>(std::lround(25.0 / step_s));
      for (int k = 1; k <= steps; ++k) {
        crowd->advance(k * step_s, nullptr);
        std::vector<PersonState> now(n);
        for (std::size_t i = 0; i < n; ++i) {
          now[i] = crowd->state(i);
          if (now[i].visible) {
            last_visible_step[i] = k;
            ASSERT_TRUE(before[i].visible) << "person " << i << " came back";
            EXPECT_LE(msg::norm(now[i].velocity), 1.0 + 1e-9);
          } else if (before[i].visible) {
            ++vanished[i];
            // It leaves from within the goal reach, i.e. it really got there.
            EXPECT_LT(geometry::distance(before[i].position, final_goal(c.people[i])), c.social.goal_reach_m + step_s);
          }
        }
        for (std::size_t i = 0; i < n; ++i) {
          for (std::size_t j = i + 1; j < n; ++j) {
            if (!(before[i].visible && before[j].visible && now[i].visible && now[j].visible)) continue;
            // Closest approach of the straight-line motion within the step.
            const Point2D a = before[j].position - before[i].position;
            const Point2D e = (now[j].position - now[i].position) - a;
            const double e2 = msg::norm_squared(e);
            const double t = e2 > 0.0 ? std::clamp(-msg::dot(a, e) / e2, 0.0, 1.0) : 0.0;
            closest = std::min(closest, msg::norm(a + t * e));
          }
        }
        before = now;
      }
      EXPECT_GT(closest, 0.6);
      for (std::size_t i = 0; i < n; ++i) {
        if (leave) {
          EXPECT_EQ(vanished[i], 1) << "person " << i;
          EXPECT_GT(last_visible_step[i] * step_s, 7.0) << "person " << i;  // 8 m at 1 m/s, less the reach
          EXPECT_FALSE(crowd->state(i).visible);
        } else {
          EXPECT_EQ(vanished[i], 0) << "person " << i;
          EXPECT_LT(geometry::distance(crowd->state(i).position, final_goal(c.people[i])), 1e-9) << "person " << i;
          EXPECT_LT(msg::norm(crowd->state(i).velocity), 1e-9) << "person " << i;
        }
      }
    }
  }
}

// B appears at 2 s right in A's way. Until then A walks exactly as if alone; B enters at its
// start, standing; afterwards A has to deal with it.
TEST(Crowd, PeopleAppearOnTimeAndAreNothingBefore) {
  for (const Behaviour behaviour : {Behaviour::social, Behaviour::orca}) {
    SCOPED_TRACE(to_string(behaviour));
    CrowdConfig alone;
    alone.behaviour = behaviour;
    alone.people = {person({0.0, 0.0}, {{10.0, 0.0}})};
    CrowdConfig pair = alone;
    Person b = person({3.0, 0.05}, {{-5.0, 0.05}});
    b.appear_s = 2.0;
    pair.people.push_back(b);
    std::unique_ptr<Crowd> one = make(alone);
    std::unique_ptr<Crowd> two = make(pair);
    ASSERT_NE(one, nullptr);
    ASSERT_NE(two, nullptr);
    EXPECT_TRUE(two->state(0).visible);
    EXPECT_FALSE(two->state(1).visible);
    bool differed = false;
    for (int k = 1; k <= 100; ++k) {
      const double t = k * alone.step_s;
      one->advance(t, nullptr);
      two->advance(t, nullptr);
      const PersonState a1 = one->state(0);
      const PersonState a2 = two->state(0);
      const PersonState b2 = two->state(1);
      if (t < 2.0 - 1e-9) {
        ASSERT_FALSE(b2.visible) << "t " << t;
        ASSERT_EQ(a1.position.x_m, a2.position.x_m) << "t " << t;
        ASSERT_EQ(a1.position.y_m, a2.position.y_m) << "t " << t;
        ASSERT_EQ(a1.velocity.x_m, a2.velocity.x_m) << "t " << t;
      } else {
        ASSERT_TRUE(b2.visible) << "t " << t;
        if (k == 40) {  // 2 s: there, not yet moved
          EXPECT_EQ(b2.position.x_m, 3.0);
          EXPECT_EQ(b2.position.y_m, 0.05);
          EXPECT_EQ(b2.velocity.x_m, 0.0);
        }
        differed = differed || a1.position.y_m != a2.position.y_m;
      }
    }
    EXPECT_TRUE(differed);  // B was an obstacle once there
  }
}

TEST(Crowd, ASocialWalkerWhoLeavesAtItsGoalVanishesThere) {
  CrowdConfig c;
  c.people = {person({0.0, 0.0}, {{3.0, 0.0}, {3.0, 3.0}}), person({0.0, -2.0}, {{3.0, -2.0}})};
  c.people[0].leave_at_goal = true;
  std::unique_ptr<Crowd> crowd = make(c);
  ASSERT_NE(crowd, nullptr);
  Point2D last;
  int k = 1;
  for (; k <= 400 && crowd->state(0).visible; ++k) {
    last = crowd->state(0).position;
    crowd->advance(k * c.step_s, nullptr);
  }
  EXPECT_FALSE(crowd->state(0).visible);
  EXPECT_LT(geometry::distance(last, {3.0, 3.0}), 0.3 + 0.1);
  EXPECT_GT(k * c.step_s, 4.0);  // it walked both legs, 6 m at up to 1.69 m/s
  for (; k <= 400; ++k) {
    crowd->advance(k * c.step_s, nullptr);
    ASSERT_FALSE(crowd->state(0).visible);
  }
  EXPECT_TRUE(crowd->state(1).visible);  // the other stays, standing near its goal
  EXPECT_LT(geometry::distance(crowd->state(1).position, {3.0, -2.0}), 1.0);
}

// Social and ORCA people on a looping route walk it again and again: back and forth between two
// goals 4 m apart for 40 s, each passes both ends several times.
TEST(Crowd, ALoopingRouteIsWalkedAgainAndAgain) {
  for (const Behaviour b : {Behaviour::social, Behaviour::orca}) {
    CrowdConfig c;
    c.behaviour = b;
    c.people = {person({0.0, 0.0}, {{4.0, 0.0}, {0.0, 0.0}})};
    c.people[0].loop = true;
    c.people[0].desired_speed_m_s = 1.0;
    std::unique_ptr<Crowd> crowd = make(c);
    ASSERT_NE(crowd, nullptr);
    int at_far = 0, at_near = 0;
    bool near_far = false, near_start = true;
    for (int k = 1; k <= 800; ++k) {
      crowd->advance(k * c.step_s, nullptr);
      const Point2D p = crowd->state(0).position;
      const bool far = geometry::distance(p, {4.0, 0.0}) < 0.5, start = geometry::distance(p, {0.0, 0.0}) < 0.5;
      at_far += far && !near_far ? 1 : 0;
      at_near += start && !near_start ? 1 : 0;
      near_far = far;
      near_start = start;
    }
    EXPECT_GE(at_far, 3) << to_string(b);
    EXPECT_GE(at_near, 3) << to_string(b);
  }
}

// Two tracks of a recording, replayed with an offset: exactly the annotations at their times,
// invisible outside the tracks.
TEST(Crowd, RecordedPeopleAreTheirAnnotationsOffsetAndInvisibleOutsideTheirTracks) {
  const std::shared_ptr<const Recording> rec = recording(
      "0 1 1.0 2.0\n10 1 1.5 2.1\n20 1 2.1 2.1\n30 1 2.5 2.6\n40 1 3.0 2.9\n"
      "20 2 -1.0 0.0\n30 2 -1.2 0.4\n40 2 -1.5 0.9\n50 2 -1.6 1.3\n60 2 -1.9 1.8\n");
  ASSERT_EQ(rec->tracks.size(), 2u);
  CrowdConfig c;
  c.behaviour = Behaviour::recorded;
  c.recording = rec;
  c.recording_offset = {100.0, -50.0};
  c.radius_m = 0.22;
  c.people = {person({0.0, 0.0}, {})};  // ignored: every track is a person
  std::unique_ptr<Crowd> crowd = make(c);
  ASSERT_NE(crowd, nullptr);
  ASSERT_EQ(crowd->size(), 2u);

  // A fine grid and every annotation time, in order.
  std::vector<double> times;
  for (int k = 0; k <= 300; ++k) times.push_back(k * 0.01 - 0.2);
  for (const Track& track : rec->tracks) {
    for (const Sample& s : track.samples) times.push_back(s.time_s);
  }
  std::sort(times.begin(), times.end());
  times.erase(std::unique(times.begin(), times.end()), times.end());
  const RobotDisc robot{{100.0, -50.0}, {}, 0.3};  // right in the way: ignored
  int checked = 0;
  for (const double t : times) {
    crowd->advance(t, &robot);
    ASSERT_EQ(crowd->time_s(), t < 0.0 ? 0.0 : t);  // crowd time starts at 0
    if (t < 0.0) continue;
    for (std::size_t i = 0; i < 2; ++i) {
      const std::vector<Sample>& samples = rec->tracks[i].samples;
      const PersonState s = crowd->state(i);
      EXPECT_EQ(s.visible, t >= samples.front().time_s && t <= samples.back().time_s) << "track " << i << " t " << t;
      EXPECT_EQ(s.radius_m, 0.22);
      for (const Sample& a : samples) {
        if (a.time_s != t) continue;
        EXPECT_NEAR(s.position.x_m, a.position.x_m + 100.0, 1e-9);
        EXPECT_NEAR(s.position.y_m, a.position.y_m - 50.0, 1e-9);
        ++checked;
      }
    }
  }
  EXPECT_EQ(checked, 10);

  // Going back changes nothing.
  std::unique_ptr<Crowd> back = make(c);
  ASSERT_NE(back, nullptr);
  back->advance(1.3, &robot);
  const PersonState there = back->state(1);
  EXPECT_TRUE(there.visible);
  back->advance(0.5, &robot);
  EXPECT_EQ(back->time_s(), 1.3);
  EXPECT_TRUE(back->state(1).visible);
  EXPECT_EQ(back->state(1).position.x_m, there.position.x_m);
  EXPECT_EQ(back->state(1).position.y_m, there.position.y_m);

  // With the recording started 0.8 s in, crowd time t shows the recording at t + 0.8.
  c.recording_start_s = 0.8;
  std::unique_ptr<Crowd> later = make(c);
  ASSERT_NE(later, nullptr);
  const Sample& a = rec->tracks[0].samples[0];  // recording time 0: before the crowd's start
  EXPECT_EQ(a.time_s, 0.0);
  const Sample& b = rec->tracks[1].samples[2];  // 1.6 s
  later->advance(b.time_s - 0.8, nullptr);
  EXPECT_TRUE(later->state(1).visible);
  EXPECT_NEAR(later->state(1).position.x_m, b.position.x_m + 100.0, 1e-9);
  EXPECT_NEAR(later->state(1).position.y_m, b.position.y_m - 50.0, 1e-9);
  later->advance(1.7, nullptr);  // recording 2.5 s: track 0 ended at 1.6 s
  EXPECT_FALSE(later->state(0).visible);
  EXPECT_EQ(later->state(0).position.x_m, 0.0);
}

// A crowd of each behaviour with everything in play: walls, a robot, late and leaving people.
CrowdConfig busy(Behaviour behaviour) {
  CrowdConfig c;
  c.behaviour = behaviour;
  c.walls = {Wall{{-5.0, -3.0}, {5.0, -3.0}}, Wall{{-5.0, 3.0}, {5.0, 3.0}}, Wall{{0.0, 2.0}, {0.0, 2.0}}};
  for (int i = 0; i < 12; ++i) {
    const double y = -2.5 + 0.43 * i;
    Person p = i % 2 == 0 ? person({-4.0, y}, {{0.0, -y}, {4.0, y + 0.02}}) : person({4.0, y}, {{-4.0, y - 0.03}});
    p.appear_s = 0.37 * (i % 5);
    p.leave_at_goal = i % 3 == 0;
    p.desired_speed_m_s = 1.0 + 0.05 * i;
    c.people.push_back(p);
  }
  if (behaviour == Behaviour::recorded) {
    std::string text;
    for (int f = 0; f <= 300; f += 10) {
      for (int id = 1; id <= 6; ++id) {
        text += std::to_string(f) + " " + std::to_string(id) + " " + std::to_string(0.04 * f * (id % 2 ? 1 : -1)) +
                " " + std::to_string(0.3 * id) + "\n";
      }
    }
    c.recording = recording(text);
  }
  return c;
}

constexpr Behaviour kAll[] = {Behaviour::recorded, Behaviour::social, Behaviour::blind, Behaviour::orca};

TEST(Crowd, AdvanceAllocatesNothing) {
  for (const Behaviour behaviour : kAll) {
    SCOPED_TRACE(to_string(behaviour));
    std::unique_ptr<Crowd> crowd = make(busy(behaviour));
    ASSERT_NE(crowd, nullptr);
    RobotDisc robot{{-3.0, 0.0}, {0.5, 0.0}, 0.35};
    int visible = 0;
    const AllocationScope scope;
    for (int k = 1; k <= 400; ++k) {
      robot.centre.x_m = -3.0 + 0.5 * 0.03 * k;
      crowd->advance(k * 0.03, &robot);
      for (std::size_t i = 0; i < crowd->size(); ++i) visible += crowd->state(i).visible ? 1 : 0;
    }
    crowd->advance(1.0, &robot);  // backwards
    EXPECT_EQ(scope.allocations(), 0u);
    if (mem::testing::counts_malloc()) {
      EXPECT_EQ(scope.malloc_calls(), 0u);
    }
    EXPECT_GT(visible, 0);
  }
}

TEST(Crowd, OneCallOrManySmallOnesGiveTheSameSteps) {
  for (const Behaviour behaviour : kAll) {
    SCOPED_TRACE(to_string(behaviour));
    const CrowdConfig c = busy(behaviour);
    std::unique_ptr<Crowd> once = make(c);
    std::unique_ptr<Crowd> often = make(c);
    ASSERT_NE(once, nullptr);
    ASSERT_NE(often, nullptr);
    const RobotDisc robot{{0.5, 0.1}, {0.0, 0.0}, 0.35};
    once->advance(10.0, &robot);
    for (int k = 1; k <= 1000; ++k) often->advance(k * 0.01, &robot);
    EXPECT_EQ(once->time_s(), often->time_s());
    EXPECT_DOUBLE_EQ(once->time_s(), 10.0);
    int visible = 0;
    for (std::size_t i = 0; i < once->size(); ++i) {
      const PersonState a = once->state(i);
      const PersonState b = often->state(i);
      EXPECT_EQ(a.visible, b.visible) << "person " << i;
      EXPECT_EQ(a.position.x_m, b.position.x_m) << "person " << i;
      EXPECT_EQ(a.position.y_m, b.position.y_m) << "person " << i;
      EXPECT_EQ(a.velocity.x_m, b.velocity.x_m) << "person " << i;
      EXPECT_EQ(a.velocity.y_m, b.velocity.y_m) << "person " << i;
      visible += a.visible ? 1 : 0;
    }
    // Not a vacuous comparison: someone is still there and someone has left (not recorded).
    EXPECT_GT(visible, 0);
    if (behaviour != Behaviour::recorded) {
      EXPECT_LT(visible, static_cast<int>(once->size()));
    }
  }
}

TEST(Crowd, NoTimeBeforeTheNextStepMovesAnyone) {
  CrowdConfig c;
  c.people = {person({0.0, 0.0}, {{10.0, 0.0}})};
  std::unique_ptr<Crowd> crowd = make(c);
  ASSERT_NE(crowd, nullptr);
  crowd->advance(0.049, nullptr);
  EXPECT_EQ(crowd->time_s(), 0.0);
  EXPECT_EQ(crowd->state(0).position.x_m, 0.0);
  crowd->advance(0.12, nullptr);  // two whole steps
  EXPECT_DOUBLE_EQ(crowd->time_s(), 0.1);
  const double x = crowd->state(0).position.x_m;
  EXPECT_GT(x, 0.0);
  crowd->advance(0.05, nullptr);  // backwards
  crowd->advance(kNan, nullptr);
  EXPECT_DOUBLE_EQ(crowd->time_s(), 0.1);
  EXPECT_EQ(crowd->state(0).position.x_m, x);
  EXPECT_FALSE(crowd->state(1).visible);  // no such person
}

}  // namespace
}  // namespace sen3bot::crowd
