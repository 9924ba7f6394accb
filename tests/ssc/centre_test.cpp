#include <gtest/gtest.h>

#include <algorithm>
#include <initializer_list>
#include <memory>
#include <string>
#include <vector>

#include "fixtures.hpp"
#include "sen3bot/ssc/centre.hpp"

namespace sen3bot::ssc {
namespace {

using testing::area;
using testing::home;
using testing::rect;

constexpr Nanos kSecond = hal::seconds(1);

// A centre with its site, and shorthand for feeding it and reading its decisions.
class Harness {
 public:
  explicit Harness(const Site& site, const CentreConfig& config = {}) {
    auto created = Centre::create(site, config);
    EXPECT_TRUE(created) << (created ? "" : created.error().c_str());
    centre = std::move(*created);
  }

  void robot(RobotId id, Pose pose, double battery = 90, bool charging = false) {
    RobotReport r;
    r.robot = id;
    r.stamp = now;
    r.pose = pose;
    r.battery = battery;
    r.charging = charging;
    ASSERT_TRUE(centre->update_robot(r));
  }
  void online(RobotId id, Pose pose, double battery = 90) {
    robot(id, pose, battery);
    ASSERT_TRUE(centre->set_online(id, true, now));
  }
  void agv(AgvId id, Pose pose, std::initializer_list<Point> route) {
    AgvReport a;
    a.agv = id;
    a.name.format("agv-%u", id);
    a.pose = pose;
    for (const Point& p : route) (void)a.route.push_back(p);
    ASSERT_TRUE(centre->update_agv(a));
  }
  // People seen by one robot, all with the same velocity (m/s).
  void person(RobotId by, std::initializer_list<Point> people, double vx = 0, double vy = 0) {
    PeopleReport r;
    r.robot = by;
    r.stamp = now;
    std::uint32_t local = 1;
    for (const Point& p : people) (void)r.people.push_back({p.x_m, p.y_m, vx, vy, local++});
    centre->add_people(r);
  }
  const Decisions& step(Nanos dt = kSecond) {
    now += dt;
    const Decisions& d = centre->step(now);
    for (const Event& e : d.events) {
      EXPECT_FALSE(e.reason.empty()) << to_string(e.type);
      EXPECT_LE(e.time, now);  // events of input calls keep the time they were given
      log.push_back(std::string(to_string(e.type)) + ": " + std::string(e.reason.view()));
    }
    for (const RobotCommand& c : d.commands) EXPECT_FALSE(c.reason.empty());
    EXPECT_EQ(d.dropped, 0u);
    return d;
  }

  std::unique_ptr<Centre> centre;
  Nanos now = 0;
  std::vector<std::string> log;  // every event so far, printed when a test fails
};

const RobotCommand* find(const Decisions& d, CommandKind kind, RobotId robot) {
  for (const RobotCommand& c : d.commands)
    if (c.kind == kind && c.robot == robot) return &c;
  return nullptr;
}
std::size_t count(const Decisions& d, EventType type) {
  return static_cast<std::size_t>(std::count_if(d.events.begin(), d.events.end(), [&](const Event& e) { return e.type == type; }));
}
bool monitors(const Harness& h, RobotId robot, AreaId area) {
  const RobotTasks* t = h.centre->tasks(robot);
  return t->is(TaskKind::monitor) && t->current()->area == area;
}
std::vector<RobotId> members(const Harness& h, AreaId area) {
  const Coalition* c = h.centre->coalition_at(area);
  return c ? std::vector<RobotId>(c->members.begin(), c->members.end()) : std::vector<RobotId>{};
}
std::string dump(const Harness& h) {
  std::string s;
  for (const std::string& line : h.log) s += line + "\n";
  return s;
}

// A straight AGV corridor along y = 0 with a 1.1 blind intersection at x 20..24, a 1.2
// transition at 30..34 and a type 2 station at 40..44.
Site corridor() {
  Site site;
  (void)site.areas.push_back(area(1, "cross", AreaType::blind_intersection, rect(20, -2, 24, 2), {{19, 3, 0}, {25, -3, 0}}));
  (void)site.areas.push_back(area(2, "bay", AreaType::transition, rect(30, -2, 34, 2), {{31, 3, 0}, {33, -3, 0}}));
  (void)site.areas.push_back(area(3, "station", AreaType::workstation, rect(40, -2, 44, 2), {{42, 3, 0}, {42, -3, 0}}));
  (void)site.robots.push_back(home(0, "r0", {18, 6, 0}, 1));
  (void)site.robots.push_back(home(1, "r1", {28, 6, 0}));
  (void)site.robots.push_back(home(2, "r2", {48, 6, 0}));
  (void)site.robots.push_back(home(3, "r3", {70, 6, 0}));
  return site;
}

TEST(SscCentre, RejectsABadSiteOrConfig) {
  Site bad = corridor();
  bad.areas[1].id = 1;
  EXPECT_FALSE(Centre::create(bad));
  CentreConfig config;
  config.stop_distance = 20;  // beyond the slow distance
  EXPECT_FALSE(Centre::create(corridor(), config));
  Harness h(corridor());
  RobotReport stranger;
  stranger.robot = 9;
  EXPECT_FALSE(h.centre->update_robot(stranger));
  EXPECT_FALSE(h.centre->submit_amr_task({.request = 1, .priority = 0, .goal = {}}, 0));
}

TEST(SscCentre, IdleRobotsGoHomeAtLowPriority) {
  Harness h(corridor());
  h.online(0, {5, 5, 0});
  h.online(1, {28, 6, 0});
  const Decisions& d = h.step();
  for (const RobotId r : {RobotId{0}, RobotId{1}}) {
    const RobotCommand* c = find(d, CommandKind::send, r);
    ASSERT_NE(c, nullptr);
    EXPECT_EQ(c->task.kind, TaskKind::home);
    EXPECT_EQ(c->task.priority, 2);
  }
  EXPECT_EQ(find(d, CommandKind::send, 0)->task.goal, (Pose{18, 6, 0}));
  EXPECT_EQ(count(d, EventType::home), 2u);
  EXPECT_EQ(count(d, EventType::connection), 2u);
  EXPECT_TRUE(h.step().commands.empty());  // they stay on their home task: nothing new
}

TEST(SscCentre, CoalitionFollowsTheFirstAreaOnTheRoute) {
  Harness h(corridor());
  for (RobotId r = 0; r < 4; ++r) h.online(r, h.centre->site().robot(r)->pose);
  h.step();
  // The route crosses 1.1, 1.2 and 2: the 1.1 intersection comes first, two robots.
  h.agv(7, {0, 0, 0}, {{10, 0}, {30, 0}, {50, 0}});
  const Decisions& d = h.step();
  ASSERT_EQ(h.centre->coalitions().size(), 1u) << dump(h);
  EXPECT_EQ(members(h, 1), (std::vector<RobotId>{0, 1}));
  const RobotCommand* r0 = find(d, CommandKind::send, 0);
  ASSERT_NE(r0, nullptr);
  EXPECT_EQ(r0->task.kind, TaskKind::monitor);
  EXPECT_EQ(r0->task.priority, 0);                  // 1.1 monitoring
  EXPECT_EQ(r0->task.goal, (Pose{18, 6, 0}));       // its home overlooks the intersection
  EXPECT_EQ(find(d, CommandKind::send, 1)->task.goal, (Pose{19, 3, 0}));
  EXPECT_EQ(count(d, EventType::coalition), 1u);
  EXPECT_EQ(count(d, EventType::allocation), 2u);

  // Still approaching: nothing changes.
  h.agv(7, {15, 0, 0}, {{30, 0}, {50, 0}});
  EXPECT_TRUE(h.step().commands.empty());
  // Inside the intersection, past its last node inside: still monitored.
  h.agv(7, {23, 0, 0}, {{30, 0}, {50, 0}});
  EXPECT_TRUE(h.step().commands.empty());

  // Past it: released; the 1.2 bay is now first, with two robots of p = 1.
  for (const RobotId r : {RobotId{0}, RobotId{1}}) h.robot(r, h.centre->site().area(1)->sentries[0]);
  h.agv(7, {26, 0, 0}, {{30, 0}, {50, 0}});
  const Decisions& next = h.step();
  EXPECT_EQ(h.centre->coalition_at(1), nullptr);
  ASSERT_NE(h.centre->coalition_at(2), nullptr);
  EXPECT_EQ(members(h, 2).size(), 2u);
  EXPECT_GE(count(next, EventType::release), 2u) << dump(h);
  for (const RobotId r : members(h, 2)) EXPECT_EQ(h.centre->tasks(r)->priority(), 1);

  // The AGV leaves the plant's coordination: everything released, everyone home.
  h.centre->remove_agv(7);
  h.step();
  EXPECT_TRUE(h.centre->coalitions().empty());
  for (RobotId r = 0; r < 4; ++r) EXPECT_TRUE(h.centre->tasks(r)->is(TaskKind::home));
}

TEST(SscCentre, TwoAgvsHeadingForOneAreaShareItsCoalition) {
  Harness h(corridor());
  for (RobotId r = 0; r < 4; ++r) h.online(r, h.centre->site().robot(r)->pose);
  h.agv(1, {0, 0, 0}, {{60, 0}});
  h.agv(2, {22, -20, 0}, {{22, 20}});  // crosses the intersection from the side
  h.step();
  ASSERT_EQ(h.centre->coalitions().size(), 1u);
  EXPECT_EQ(h.centre->coalitions()[0].agvs.size(), 2u);
  EXPECT_EQ(members(h, 1).size(), 2u);
  // One AGV passes: the other still needs it.
  h.agv(1, {26, 0, 0}, {{60, 0}});
  h.step();
  EXPECT_EQ(members(h, 1).size(), 2u);
}

// Table 2.1 through the centre: the final size each area type settles on with its people.
TEST(SscCentre, FinalSizeFollowsThePeopleInTheArea) {
  const struct {
    AreaType type;
    int people;  // 0 none, 1 static, 2 dynamic
    std::size_t initial;
    std::size_t final_size;
  } cases[] = {
      {AreaType::blind_intersection, 0, 2, 2}, {AreaType::blind_intersection, 1, 2, 2}, {AreaType::blind_intersection, 2, 2, 2},
      {AreaType::transition, 0, 2, 2},         {AreaType::transition, 1, 2, 1},         {AreaType::transition, 2, 2, 2},
      {AreaType::workstation, 0, 1, 1},        {AreaType::workstation, 1, 1, 1},        {AreaType::workstation, 2, 1, 2},
      {AreaType::not_monitored, 0, 0, 0},      {AreaType::not_monitored, 1, 0, 0},      {AreaType::not_monitored, 2, 0, 0},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(::testing::Message() << to_string(c.type) << " people " << c.people);
    Site site;
    (void)site.areas.push_back(area(1, "a", c.type, rect(20, -2, 24, 2), {{21, 3, 0}, {23, -3, 0}}));
    for (RobotId r = 0; r < 3; ++r) (void)site.robots.push_back(home(r, "r", {10.0 + 10 * r, 8, 0}));
    Harness h(site);
    for (RobotId r = 0; r < 3; ++r) h.online(r, site.robots[r].pose);
    h.agv(1, {0, 0, 0}, {{60, 0}});
    h.step();
    EXPECT_EQ(members(h, 1).size(), c.initial);
    // Two seconds of people reports: a walker crosses more than 1 m, a standing person not.
    for (int i = 0; i <= 4; ++i) {
      if (c.people == 1) h.person(0, {{22, 0.5}});
      if (c.people == 2) h.person(0, {{21 + 0.5 * i, 0.5}}, 1.0);
      h.step(kSecond / 2);
    }
    EXPECT_EQ(members(h, 1).size(), c.final_size);
  }
}

// Thesis scenario 1: one AGV and one robot. The robot sees a person the AGV cannot yet see
// and the AGV is slowed well before its own sensors would have found the person.
TEST(SscCentre, Net1TheAgvLearnsOfAPersonBeyondItsSensors) {
  Site site;
  (void)site.areas.push_back(area(1, "station", AreaType::workstation, rect(20, -2, 24, 2), {{22, 3, 0}}));
  (void)site.robots.push_back(home(0, "sen3bot", {30, 6, 0}));
  Harness h(site);
  h.online(0, {30, 6, 0});
  h.agv(1, {0, 0, 0}, {{10, 0}, {20, 0}, {30, 0}, {40, 0}});
  const Decisions& start = h.step();
  ASSERT_EQ(start.advisories.size(), 1u);
  EXPECT_EQ(start.advisories[0].advice, Advice::clear);  // nobody known yet
  const RobotCommand* go = find(start, CommandKind::send, 0);
  ASSERT_NE(go, nullptr);
  EXPECT_EQ(go->task.goal, (Pose{22, 3, 0}));
  EXPECT_EQ(go->task.priority, 1);

  // At its sentry pose the robot sees a person standing in the station; the AGV is 10 m away.
  h.robot(0, {22, 3, 0});
  h.agv(1, {10, 0, 0}, {{20, 0}, {30, 0}, {40, 0}});
  h.person(0, {{22, 0.5}});
  const Decisions& seen = h.step();
  ASSERT_EQ(seen.advisories.size(), 1u) << dump(h);
  const Advisory& slow = seen.advisories[0];
  EXPECT_EQ(slow.advice, Advice::slow);
  EXPECT_EQ(slow.area, 1);
  EXPECT_EQ(slow.people, 1);
  EXPECT_DOUBLE_EQ(slow.speed_factor, 0.3);
  EXPECT_GE(slow.distance, 5.0);  // beyond the AGV's own sensors
  EXPECT_EQ(count(seen, EventType::advisory), 1u);
  // Unchanged advice is not repeated.
  h.person(0, {{22, 0.5}});
  EXPECT_TRUE(h.step().advisories.empty());

  // The person starts walking about the station as the AGV comes within the stop distance.
  h.agv(1, {18, 0, 0}, {{20, 0}, {30, 0}, {40, 0}});
  for (int i = 1; i <= 3; ++i) {
    h.person(0, {{22 - 0.5 * i, 0.5}}, -1.0);
    h.step(kSecond / 2);
  }
  ASSERT_TRUE(h.centre->advice(1));
  EXPECT_EQ(h.centre->advice(1)->advice, Advice::stop) << dump(h);
  EXPECT_DOUBLE_EQ(h.centre->advice(1)->speed_factor, 0);

  // The person leaves the area (and is seen outside it): clear once the track inside is dropped.
  for (int i = 0; i < 5; ++i) {
    h.person(0, {{21, 4.5}});
    h.step(kSecond / 2);
  }
  EXPECT_EQ(h.centre->advice(1)->advice, Advice::clear) << dump(h);
  EXPECT_NE(h.centre->advice(1)->reason.view().find("empty"), std::string_view::npos);

  // Past the station: released and home.
  h.agv(1, {26, 0, 0}, {{30, 0}, {40, 0}});
  const Decisions& passed = h.step();
  EXPECT_EQ(h.centre->coalition_at(1), nullptr);
  ASSERT_NE(find(passed, CommandKind::send, 0), nullptr);
  EXPECT_EQ(find(passed, CommandKind::send, 0)->task.kind, TaskKind::home);
}

// Thesis scenario 2: a 1.1 intersection with a dynamic person; two robots go and both stay.
TEST(SscCentre, Net2BlindIntersectionWithAWalkerKeepsBothRobots) {
  Harness h(corridor());
  for (RobotId r = 0; r < 4; ++r) h.online(r, h.centre->site().robot(r)->pose);
  h.step();
  h.agv(1, {0, 0, 0}, {{10, 0}, {22, 0}, {27, 0}});  // ends before the bay
  const Decisions& start = h.step();
  EXPECT_EQ(count(start, EventType::allocation), 2u);
  ASSERT_EQ(members(h, 1), (std::vector<RobotId>{0, 1}));

  h.robot(1, {19, 3, 0});
  double x = 0;
  for (int i = 0; i < 12; ++i) {
    // Both robots see the walker crossing the intersection (a little apart: localisation).
    const double px = 20.5 + 0.25 * i;
    h.person(0, {{px, -1}}, 0.5);
    h.person(1, {{px + 0.15, -0.9}}, 0.5);
    x = std::min(19.0, 2.0 * i);
    h.agv(1, {x, 0, 0}, {{22, 0}, {27, 0}});
    const Decisions& d = h.step(kSecond / 2);
    EXPECT_EQ(count(d, EventType::release), 0u) << dump(h);
    EXPECT_EQ(h.centre->people().tracks().size(), 1u);
  }
  EXPECT_EQ(members(h, 1), (std::vector<RobotId>{0, 1}));
  EXPECT_EQ(h.centre->coalition_at(1)->people, PeopleState::dynamic_people);
  EXPECT_TRUE(monitors(h, 0, 1));
  EXPECT_TRUE(monitors(h, 1, 1));
  EXPECT_EQ(h.centre->tasks(0)->priority(), 0);
  ASSERT_TRUE(h.centre->advice(1));
  EXPECT_EQ(h.centre->advice(1)->advice, Advice::stop);  // a walker, the AGV 1 m from the area

  h.agv(1, {26, 0, 0}, {{27, 0}});
  const Decisions& passed = h.step();
  EXPECT_EQ(h.centre->coalition_at(1), nullptr);
  EXPECT_EQ(count(passed, EventType::home), 2u);
  EXPECT_EQ(h.centre->advice(1)->advice, Advice::clear);
  EXPECT_NE(h.centre->advice(1)->reason.view().find("passed"), std::string_view::npos);
}

// Thesis scenario 3: a workstation behind racks, treated as 1.2, with static people. Two
// robots go; one is released to p = 2 and then taken for a monitoring request nearby.
TEST(SscCentre, Net3StaticPeopleReleaseOneRobotWhichServesANearbyArea) {
  Site site;
  (void)site.areas.push_back(area(1, "racks station", AreaType::transition, rect(20, -2, 24, 2), {{21, 2.5, 0}, {23, -3.5, 0}}));
  (void)site.areas.push_back(area(2, "nearby", AreaType::workstation, rect(26, -8, 30, -4), {{28, -3, 0}}));
  (void)site.robots.push_back(home(0, "robot 1", {15, -6, 0}));
  (void)site.robots.push_back(home(1, "robot 2", {26, 6, 0}));
  (void)site.robots.push_back(home(2, "robot 3", {60, 6, 0}));
  Harness h(site);
  for (RobotId r = 0; r < 3; ++r) h.online(r, site.robots[r].pose);
  h.step();
  h.agv(1, {0, 0, 0}, {{22, 0}, {50, 0}});
  const Decisions& start = h.step();
  ASSERT_EQ(members(h, 1), (std::vector<RobotId>{1, 0})) << dump(h);
  EXPECT_EQ(find(start, CommandKind::send, 1)->task.goal, (Pose{21, 2.5, 0}));
  EXPECT_EQ(find(start, CommandKind::send, 0)->task.goal, (Pose{23, -3.5, 0}));

  // Both arrive and see two people working at the station, standing still.
  h.robot(1, {21, 2.5, 0});
  h.robot(0, {23, -3.5, 0});
  h.agv(1, {12, 0, 0}, {{22, 0}, {50, 0}});
  h.person(1, {{21.5, 0}, {22.5, 0.5}});
  h.person(0, {{21.6, 0.1}, {22.5, 0.4}});
  const Decisions& settled = h.step();
  EXPECT_EQ(h.centre->people().tracks().size(), 2u);
  ASSERT_EQ(members(h, 1), (std::vector<RobotId>{1})) << dump(h);
  const RobotCommand* freed = find(settled, CommandKind::send, 0);  // the one farther from the area
  ASSERT_NE(freed, nullptr);
  EXPECT_EQ(freed->task.kind, TaskKind::home);
  EXPECT_EQ(h.centre->tasks(0)->priority(), 2);
  EXPECT_EQ(count(settled, EventType::release), 1u);
  ASSERT_TRUE(h.centre->advice(1));
  EXPECT_EQ(h.centre->advice(1)->advice, Advice::slow);
  EXPECT_EQ(h.centre->advice(1)->people, 2);

  // A second AGV's route crosses the nearby station: the freed robot is nearest and p = 2.
  h.agv(2, {28, -20, 0}, {{28, 0}});
  h.person(1, {{21.5, 0}, {22.5, 0.5}});
  const Decisions& nearby = h.step();
  ASSERT_EQ(members(h, 2), (std::vector<RobotId>{0})) << dump(h);
  const RobotCommand* sent = find(nearby, CommandKind::send, 0);
  ASSERT_NE(sent, nullptr);
  EXPECT_EQ(sent->task.kind, TaskKind::monitor);
  EXPECT_EQ(sent->task.goal, (Pose{28, -3, 0}));
  EXPECT_EQ(members(h, 1), (std::vector<RobotId>{1}));
}

TEST(SscCentre, AmrWorkIsSuspendedForMonitoringAndResumedAfter) {
  Harness h(corridor());
  h.online(1, {28, 6, 0});
  h.online(2, {48, 6, 0});
  h.step();
  auto task = h.centre->submit_amr_task({.request = 55, .priority = 2, .goal = {27, 8, 0}}, h.now);
  ASSERT_TRUE(task);
  const Decisions& given = h.step();
  const RobotCommand* work = find(given, CommandKind::send, 1);
  ASSERT_NE(work, nullptr);
  EXPECT_EQ(work->task.kind, TaskKind::amr);
  EXPECT_EQ(work->task.id, *task);
  EXPECT_EQ(work->task.request, 55u);
  EXPECT_EQ(count(given, EventType::task), 2u);  // queued, taken

  // An AGV's route crosses the bay (1.2, two robots): r1 is taken from its p = 2 work.
  h.robot(1, {30, 0, 0});
  h.agv(2, {20, -10, 0}, {{31, 0}, {31, 10}});
  const Decisions& d = h.step();
  EXPECT_EQ(members(h, 2).size(), 2u);
  ASSERT_NE(find(d, CommandKind::suspend, 1), nullptr) << dump(h);
  EXPECT_EQ(find(d, CommandKind::suspend, 1)->task.id, *task);
  EXPECT_EQ(count(d, EventType::suspension), 1u);
  EXPECT_TRUE(monitors(h, 1, 2));
  ASSERT_EQ(h.centre->tasks(1)->suspended().size(), 1u);

  h.centre->remove_agv(2);
  const Decisions& back = h.step();
  const RobotCommand* resumed = find(back, CommandKind::resume, 1);
  ASSERT_NE(resumed, nullptr) << dump(h);
  EXPECT_EQ(resumed->task.id, *task);
  EXPECT_EQ(count(back, EventType::resumption), 1u);

  // The work is done: home.
  RobotReport done{.robot = 1, .stamp = h.now, .pose = {27, 8, 0}, .battery = 80, .charging = false,
                   .driving = false, .order_task = *task, .order_finished = true};
  ASSERT_TRUE(h.centre->update_robot(done));
  const Decisions& finished = h.step();
  ASSERT_NE(find(finished, CommandKind::send, 1), nullptr);
  EXPECT_EQ(find(finished, CommandKind::send, 1)->task.kind, TaskKind::home);
}

TEST(SscCentre, ANearerP1RobotIsPassedOverForAFartherIdleOne) {
  Harness h(corridor());
  h.online(1, {28, 6, 0});
  h.online(2, {48, 6, 0});
  h.step();
  ASSERT_TRUE(h.centre->submit_amr_task({.request = 9, .priority = 1, .goal = {29, 6, 0}}, h.now));
  h.step();
  ASSERT_TRUE(h.centre->tasks(1)->is(TaskKind::amr));
  h.agv(1, {36, 0, 0}, {{39, 0}, {50, 0}});  // the station: one robot, r1 nearer but busy at p = 1
  h.robot(1, {36, 6, 0});
  const Decisions& d = h.step();
  EXPECT_EQ(members(h, 3), (std::vector<RobotId>{2})) << dump(h);
  EXPECT_EQ(count(d, EventType::swap), 1u);
  EXPECT_EQ(find(d, CommandKind::suspend, 1), nullptr);
  EXPECT_TRUE(h.centre->tasks(1)->is(TaskKind::amr));
}

TEST(SscCentre, P0RobotsAreNeverTakenAndAShortCoalitionIsLogged) {
  Harness h(corridor());
  h.online(0, {18, 6, 0});
  h.online(1, {28, 6, 0});
  h.step();
  h.agv(1, {0, 0, 0}, {{60, 0}});  // the 1.1 intersection: both robots at p = 0
  h.step();
  ASSERT_EQ(members(h, 1).size(), 2u);
  h.agv(2, {32, -20, 0}, {{32, 20}});  // the bay: nobody may be taken from p = 0
  const Decisions& d = h.step();
  ASSERT_NE(h.centre->coalition_at(2), nullptr);
  EXPECT_TRUE(members(h, 2).empty());
  EXPECT_EQ(h.centre->coalition_at(2)->shortfall, 2);
  EXPECT_EQ(count(d, EventType::coalition), 2u);  // started, short
  EXPECT_EQ(count(h.step(), EventType::coalition), 0u);  // logged once
}

TEST(SscCentre, LowBatteryChargesAtTopPriorityAndIsReplaced) {
  Harness h(corridor());
  for (RobotId r = 0; r < 3; ++r) h.online(r, h.centre->site().robot(r)->pose);
  h.step();
  h.agv(1, {0, 0, 0}, {{60, 0}});
  h.step();
  ASSERT_EQ(members(h, 1), (std::vector<RobotId>{0, 1}));
  h.robot(1, {19, 3, 0}, 15);
  const Decisions& d = h.step();
  const RobotCommand* charge = find(d, CommandKind::send, 1);
  ASSERT_NE(charge, nullptr) << dump(h);
  EXPECT_EQ(charge->task.kind, TaskKind::charge);
  EXPECT_EQ(charge->task.priority, 0);
  EXPECT_EQ(charge->task.goal, (Pose{28, 6, 0}));
  EXPECT_EQ(count(d, EventType::charge), 1u);
  EXPECT_EQ(members(h, 1), (std::vector<RobotId>{0, 2}));  // r2 replaces it
  // Charging: never taken, no new commands until charged.
  h.robot(1, {28, 6, 0}, 50, true);
  EXPECT_EQ(find(h.step(), CommandKind::send, 1), nullptr);
  h.robot(1, {28, 6, 0}, 85, true);
  const Decisions& charged = h.step();
  EXPECT_EQ(count(charged, EventType::home), 1u);
  EXPECT_TRUE(h.centre->tasks(1)->is(TaskKind::home));
  EXPECT_EQ(h.centre->tasks(1)->priority(), 2);

  // Already charging when low: a p = 0 charge task, but no order.
  Harness g(corridor());
  g.online(3, {70, 6, 0}, 10);
  g.robot(3, {70, 6, 0}, 10, true);
  const Decisions& already = g.step();
  EXPECT_EQ(find(already, CommandKind::send, 3), nullptr);
  EXPECT_TRUE(g.centre->tasks(3)->is(TaskKind::charge));
  EXPECT_EQ(count(already, EventType::charge), 1u);
}

TEST(SscCentre, OfflineRobotsAreSkippedAndReplaced) {
  Harness h(corridor());
  h.robot(0, {18, 6, 0});  // reports, but the connection topic says offline
  h.online(1, {28, 6, 0});
  h.online(2, {48, 6, 0});
  h.online(3, {70, 6, 0});
  h.step();
  h.agv(1, {0, 0, 0}, {{60, 0}});
  h.step();
  EXPECT_EQ(members(h, 1), (std::vector<RobotId>{1, 2}));  // r0 is nearest but offline

  ASSERT_TRUE(h.centre->set_online(2, false, h.now));
  const Decisions& d = h.step();
  EXPECT_EQ(members(h, 1), (std::vector<RobotId>{1, 3})) << dump(h);
  EXPECT_EQ(count(d, EventType::connection), 1u);
  EXPECT_EQ(count(d, EventType::release), 1u);
  EXPECT_EQ(count(d, EventType::allocation), 1u);
  EXPECT_EQ(find(d, CommandKind::send, 2), nullptr);  // nothing is sent to an offline robot
  EXPECT_NE(find(d, CommandKind::send, 3), nullptr);
}

TEST(SscCentre, AmrRequestWaitsForAFreeRobot) {
  Harness h(corridor());
  h.online(0, {18, 6, 0});
  h.step();
  h.agv(1, {0, 0, 0}, {{60, 0}});
  h.step();  // r0 monitors at p = 0
  ASSERT_TRUE(h.centre->submit_amr_task({.request = 3, .priority = 1, .goal = {5, 5, 0}}, h.now));
  h.step();
  EXPECT_EQ(h.centre->pending_requests(), 1u);
  h.centre->remove_agv(1);
  const Decisions& d = h.step();
  EXPECT_EQ(h.centre->pending_requests(), 0u);
  const RobotCommand* c = find(d, CommandKind::send, 0);
  ASSERT_NE(c, nullptr) << dump(h);
  EXPECT_EQ(c->task.kind, TaskKind::amr);
  EXPECT_EQ(c->task.priority, 1);
}

}  // namespace
}  // namespace sen3bot::ssc
