// The request trigger over its timing and distance boundaries, with the camera's frames at
// 5 Hz (some missed) read by a 10 Hz control cycle, as on the robot.
#include "sen3bot/cobot/trigger.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <functional>
#include <map>
#include <vector>

#include "alloc_counter.hpp"

namespace sen3bot::cobot {
namespace {

using msg::TagSide;

constexpr std::uint32_t kAnna = 7;
constexpr std::uint32_t kBruno = 9;
constexpr std::uint32_t kStranger = 1234;
constexpr hal::Nanos kStart = hal::seconds(100);
constexpr hal::Nanos kCycle = hal::millis(100);

hal::Nanos at(double s) { return kStart + static_cast<hal::Nanos>(std::llround(s * 1e9)); }

TriggerConfig config() {
  TriggerConfig c;
  EXPECT_TRUE(c.operators.push_back(kAnna));
  EXPECT_TRUE(c.operators.push_back(kBruno));
  return c;
}

struct View {
  bool present = true;
  double distance_m = 0.8;
  std::uint8_t others = 0;
  double speed_m_s = 0.0;
};

// Frames by capture time (seconds after kStart), each with the tags read in it.
class Script {
 public:
  // Sightings of one tag from from_s to to_s inclusive, every period_s.
  Script& show(std::uint32_t id, TagSide side, double from_s, double to_s, double period_s = 0.2) {
    const hal::Nanos to = at(to_s);
    const auto period = static_cast<hal::Nanos>(std::llround(period_s * 1e9));
    for (hal::Nanos t = at(from_s); t <= to; t += period) add(t, id, side);
    return *this;
  }
  Script& once(std::uint32_t id, TagSide side, double t_s) {
    add(at(t_s), id, side);
    return *this;
  }
  // The frame taken at t_s is missed (the reader found no tag in it).
  Script& miss(double t_s) {
    frames_.erase(at(t_s));
    return *this;
  }
  [[nodiscard]] const std::map<hal::Nanos, msg::TagFrame>& frames() const { return frames_; }

 private:
  void add(hal::Nanos t, std::uint32_t id, TagSide side) {
    msg::TagFrame& frame = frames_[t];
    frame.capture_ns = t;
    frame.tags[frame.count].operator_id = id;
    frame.tags[frame.count].side = side;
    ++frame.count;
  }
  std::map<hal::Nanos, msg::TagFrame> frames_;
};

// Runs 10 Hz cycles from kStart to end_s; each cycle gets the newest frame taken since the
// last one, and the person tracker's view at that moment.
std::vector<TriggerEvent> run(CollaborationTrigger& trigger, const Script& script, double end_s,
                              const std::function<View(double)>& view = [](double) { return View{}; },
                              const std::function<bool(double)>& armed = [](double) { return true; }) {
  std::vector<TriggerEvent> events;
  auto next = script.frames().begin();
  for (hal::Nanos now = kStart; now <= at(end_s); now += kCycle) {
    const msg::TagFrame* frame = nullptr;
    while (next != script.frames().end() && next->first <= now) frame = &(next++)->second;
    const double t_s = hal::to_seconds(now - kStart);
    const View v = view(t_s);
    TriggerInput input;
    input.now_ns = now;
    input.frame = frame;
    input.armed = armed(t_s);
    input.operator_present = v.present;
    input.operator_speed_m_s = v.speed_m_s;
    input.operator_distance_m = v.distance_m;
    input.others_in_way = v.others;
    const TriggerOutput out = trigger.update(input);
    events.insert(events.end(), out.events.begin(), out.events.end());
  }
  return events;
}

std::size_t requests(const std::vector<TriggerEvent>& events) {
  return static_cast<std::size_t>(std::count_if(events.begin(), events.end(), [](const TriggerEvent& e) {
    return e.kind == TriggerEventKind::request;
  }));
}

std::vector<TriggerRejection> rejections(const std::vector<TriggerEvent>& events) {
  std::vector<TriggerRejection> out;
  for (const TriggerEvent& e : events)
    if (e.kind == TriggerEventKind::rejection) out.push_back(e.reason);
  return out;
}

// The standard sequence by one operator: front from 0 s for front_s, back after turn_s for back_s.
Script sequence(std::uint32_t id, double front_s, double turn_s, double back_s, double start_s = 0.0) {
  Script s;
  s.show(id, TagSide::front, start_s, start_s + front_s);
  s.show(id, TagSide::back, start_s + front_s + turn_s, start_s + front_s + turn_s + back_s);
  return s;
}

class TriggerTest : public ::testing::Test {
 protected:
  void SetUp() override { ASSERT_TRUE(trigger.init(config())); }
  CollaborationTrigger trigger;
};

TEST_F(TriggerTest, FrontThenBackInPlaceIsARequestByThatOperator) {
  const auto events = run(trigger, sequence(kAnna, 2.4, 1.0, 2.4), 10.0);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, TriggerEventKind::request);
  EXPECT_EQ(events[0].operator_id, kAnna);
  // Decided once the back tag has been unseen for longer than the sighting gap.
  EXPECT_GT(events[0].stamp_ns, at(5.8 + 0.7));
  EXPECT_LE(events[0].stamp_ns, at(5.8 + 0.7 + 0.2 + 0.1));
  EXPECT_EQ(trigger.requests(), 1u);
  EXPECT_EQ(trigger.rejections_total(), 0u);
}

TEST_F(TriggerTest, FrontLastingExactlyTheShortestAndLongestTimesIsAccepted) {
  for (double front_s : {2.0, 3.0}) {
    ASSERT_TRUE(trigger.init(config()));
    const auto events = run(trigger, sequence(kAnna, front_s, 0.6, 2.4), 10.0);
    EXPECT_EQ(requests(events), 1u) << front_s;
    EXPECT_TRUE(rejections(events).empty()) << front_s;
  }
}

TEST_F(TriggerTest, FrontJustShortOfTheShortestTimeIsRefusedAtTheTurn) {
  Script s;
  s.show(kAnna, TagSide::front, 0.0, 1.8).once(kAnna, TagSide::front, 1.999);
  s.show(kAnna, TagSide::back, 2.6, 5.0);
  const auto events = run(trigger, s, 10.0);
  EXPECT_EQ(requests(events), 0u);
  EXPECT_EQ(rejections(events), std::vector{TriggerRejection::front_too_short});
  EXPECT_EQ(trigger.rejections(TriggerRejection::front_too_short), 1u);
}

TEST_F(TriggerTest, FrontJustPastTheLongestTimeIsRefusedOnceWhileItGoesOn) {
  Script s;
  s.show(kAnna, TagSide::front, 0.0, 3.0).once(kAnna, TagSide::front, 3.001).show(kAnna, TagSide::front, 3.2, 6.0);
  s.show(kAnna, TagSide::back, 7.0, 9.4);
  const auto events = run(trigger, s, 12.0);
  EXPECT_EQ(requests(events), 0u);
  EXPECT_EQ(rejections(events), std::vector{TriggerRejection::front_too_long});
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].stamp_ns, at(3.001));
}

TEST_F(TriggerTest, BackLastingExactlyTheShortestAndLongestTimesIsAccepted) {
  for (double back_s : {2.0, 3.0}) {
    ASSERT_TRUE(trigger.init(config()));
    const auto events = run(trigger, sequence(kAnna, 2.4, 0.6, back_s), 10.0);
    EXPECT_EQ(requests(events), 1u) << back_s;
    EXPECT_TRUE(rejections(events).empty()) << back_s;
  }
}

TEST_F(TriggerTest, BackJustShortOfTheShortestTimeIsRefused) {
  Script s;
  s.show(kAnna, TagSide::front, 0.0, 2.4);
  s.show(kAnna, TagSide::back, 3.0, 4.8).once(kAnna, TagSide::back, 4.999);
  const auto events = run(trigger, s, 10.0);
  EXPECT_EQ(requests(events), 0u);
  EXPECT_EQ(rejections(events), std::vector{TriggerRejection::back_too_short});
}

TEST_F(TriggerTest, BackJustPastTheLongestTimeIsRefusedOnceWhileItGoesOn) {
  Script s;
  s.show(kAnna, TagSide::front, 0.0, 2.4);
  s.show(kAnna, TagSide::back, 3.0, 6.0).once(kAnna, TagSide::back, 6.001).show(kAnna, TagSide::back, 6.2, 9.0);
  const auto events = run(trigger, s, 12.0);
  EXPECT_EQ(requests(events), 0u);
  EXPECT_EQ(rejections(events), std::vector{TriggerRejection::back_too_long});
  EXPECT_EQ(trigger.rejections_total(), 1u);
}

TEST_F(TriggerTest, DistanceAtTheWindowsEdgesIsAccepted) {
  for (double d : {0.5, 1.0}) {
    ASSERT_TRUE(trigger.init(config()));
    const auto events = run(trigger, sequence(kAnna, 2.4, 0.6, 2.4), 10.0, [d](double) { return View{true, d, 0}; });
    EXPECT_EQ(requests(events), 1u) << d;
    EXPECT_TRUE(rejections(events).empty()) << d;
  }
}

TEST_F(TriggerTest, DistanceJustOutsideTheWindowDuringEitherPhaseIsRefusedOnce) {
  struct Case {
    double distance_m;
    double from_s;  // the distance holds from then on
    TriggerRejection reason;
  };
  for (const Case& c : {Case{0.49, 1.0, TriggerRejection::too_near}, Case{1.01, 1.0, TriggerRejection::too_far},
                        Case{0.49, 4.0, TriggerRejection::too_near}, Case{1.01, 4.0, TriggerRejection::too_far}}) {
    ASSERT_TRUE(trigger.init(config()));
    const auto events = run(trigger, sequence(kAnna, 2.4, 0.6, 2.4), 10.0, [&c](double t) {
      return View{true, t >= c.from_s ? c.distance_m : 0.8, 0};
    });
    EXPECT_EQ(requests(events), 0u) << c.distance_m << " from " << c.from_s;
    EXPECT_EQ(rejections(events), std::vector{c.reason}) << c.distance_m << " from " << c.from_s;
  }
}

TEST_F(TriggerTest, StandingOutsideTheWindowShowingTheFrontIsRefusedOnceAfterTheFrontTime) {
  Script s;
  s.show(kAnna, TagSide::front, 0.0, 8.0);
  const auto events = run(trigger, s, 10.0, [](double) { return View{true, 1.3, 0}; });
  ASSERT_EQ(rejections(events), std::vector{TriggerRejection::too_far});
  EXPECT_EQ(events[0].stamp_ns, at(2.0));
}

TEST_F(TriggerTest, ApproachingWhileShowingTheFrontStartsTheAttemptOnceInTheWindow) {
  // Seen from 1.8 m, walking in, standing at 0.8 m from 1.0 s: the front phase counts from there.
  const auto view = [](double t) { return View{true, t < 1.0 ? 1.8 - t : 0.8, 0}; };
  Script s;
  s.show(kAnna, TagSide::front, 0.0, 3.0).show(kAnna, TagSide::back, 3.6, 6.0);
  auto events = run(trigger, s, 10.0, view);
  EXPECT_EQ(requests(events), 1u);
  EXPECT_TRUE(rejections(events).empty());

  // The same front shown in the window only 1.8 s of its 3 s: too short.
  ASSERT_TRUE(trigger.init(config()));
  events = run(trigger, s, 10.0, [](double t) { return View{true, t < 1.2 ? 1.4 : 0.8, 0}; });
  EXPECT_EQ(requests(events), 0u);
  EXPECT_EQ(rejections(events), std::vector{TriggerRejection::front_too_short});
}

TEST_F(TriggerTest, TurnOfExactlyTheLongestTimeIsAcceptedAndJustLongerRefused) {
  Script ok;
  ok.show(kAnna, TagSide::front, 0.0, 2.4).show(kAnna, TagSide::back, 4.9, 7.3);
  auto events = run(trigger, ok, 12.0);
  EXPECT_EQ(requests(events), 1u);
  EXPECT_TRUE(rejections(events).empty());

  ASSERT_TRUE(trigger.init(config()));
  Script late;
  late.show(kAnna, TagSide::front, 0.0, 2.4).once(kAnna, TagSide::back, 4.91).show(kAnna, TagSide::back, 5.1, 7.3);
  events = run(trigger, late, 12.0);
  EXPECT_EQ(requests(events), 0u);
  // Once: the back showing that follows is the refused attempt's, not a new one.
  EXPECT_EQ(rejections(events), std::vector{TriggerRejection::turn_too_long});
}

TEST_F(TriggerTest, SightingGapOfExactlyTheLongestKeepsTheShowingAndJustLongerBreaksIt) {
  Script ok;
  ok.show(kAnna, TagSide::front, 0.0, 1.0).show(kAnna, TagSide::front, 1.7, 2.3).show(kAnna, TagSide::back, 3.0, 5.4);
  auto events = run(trigger, ok, 10.0);
  EXPECT_EQ(requests(events), 1u);
  EXPECT_TRUE(rejections(events).empty());

  ASSERT_TRUE(trigger.init(config()));
  Script broken;
  broken.show(kAnna, TagSide::front, 0.0, 1.0).show(kAnna, TagSide::front, 1.71, 2.31);
  broken.show(kAnna, TagSide::back, 3.0, 5.4);
  events = run(trigger, broken, 10.0);
  EXPECT_EQ(requests(events), 0u);
  EXPECT_EQ(rejections(events), std::vector{TriggerRejection::front_too_short});
}

TEST_F(TriggerTest, MissedFramesWithinTheGapDoNotBreakThePhases) {
  Script s = sequence(kAnna, 2.4, 0.8, 2.4);
  // Two frames in a row, and single ones, lost in both phases.
  s.miss(0.6).miss(0.8).miss(1.6).miss(2.2).miss(3.6).miss(3.8).miss(4.6);
  const auto events = run(trigger, s, 10.0);
  EXPECT_EQ(requests(events), 1u);
  EXPECT_TRUE(rejections(events).empty());
}

TEST_F(TriggerTest, IrregularFramesAreTimedByTheirCaptureTimes) {
  // Frames every 0.13 to 0.31 s; the last front frame 2.0 s after the first.
  Script s;
  double t = 0.0;
  for (double step : {0.13, 0.31, 0.2, 0.27, 0.15, 0.3, 0.14, 0.22, 0.28}) {
    s.once(kAnna, TagSide::front, t);
    t += step;
  }
  s.once(kAnna, TagSide::front, 2.0);
  ASSERT_NEAR(t, 2.0, 1e-9);
  s.show(kAnna, TagSide::back, 2.5, 4.9, 0.3);
  const auto events = run(trigger, s, 10.0);
  EXPECT_EQ(requests(events), 1u);
  EXPECT_TRUE(rejections(events).empty());
}

TEST_F(TriggerTest, UnknownOperatorIsRefusedOnceAndNeverRequests) {
  const auto events = run(trigger, sequence(kStranger, 2.4, 0.6, 2.4), 10.0);
  EXPECT_EQ(requests(events), 0u);
  EXPECT_EQ(rejections(events), std::vector{TriggerRejection::unknown_operator});
  ASSERT_FALSE(events.empty());
  EXPECT_EQ(events[0].operator_id, kStranger);
}

TEST_F(TriggerTest, BackShownFirstIsTheWrongOrder) {
  Script s;
  s.show(kAnna, TagSide::back, 0.0, 2.4);
  const auto events = run(trigger, s, 5.0);
  EXPECT_EQ(rejections(events), std::vector{TriggerRejection::wrong_order});
  EXPECT_EQ(requests(events), 0u);
}

TEST_F(TriggerTest, OperatorWalkingAwayShowingTheBackIsNoAttempt) {
  Script s;
  s.show(kAnna, TagSide::back, 0.0, 4.0);
  const auto events = run(trigger, s, 6.0, [](double t) { return View{true, 0.9 + 0.6 * t, 0}; });
  EXPECT_TRUE(events.empty());
}

TEST_F(TriggerTest, FrontAgainBeforeTheBackTimeIsTheWrongOrder) {
  Script s;
  s.show(kAnna, TagSide::front, 0.0, 2.4).show(kAnna, TagSide::back, 3.0, 4.0).show(kAnna, TagSide::front, 4.2, 6.0);
  const auto events = run(trigger, s, 8.0);
  EXPECT_EQ(requests(events), 0u);
  EXPECT_EQ(rejections(events), std::vector{TriggerRejection::wrong_order});
}

TEST_F(TriggerTest, AnotherOperatorsBackTagIsOperatorChanged) {
  Script s;
  s.show(kAnna, TagSide::front, 0.0, 2.4).show(kBruno, TagSide::back, 3.0, 5.4);
  const auto events = run(trigger, s, 8.0);
  EXPECT_EQ(requests(events), 0u);
  EXPECT_EQ(rejections(events), std::vector{TriggerRejection::operator_changed});
  EXPECT_EQ(events[0].operator_id, kAnna);
}

TEST_F(TriggerTest, PersonInTheWayDuringAPhaseIsRefusedOnce) {
  const auto events = run(trigger, sequence(kAnna, 2.4, 0.6, 2.4), 10.0, [](double t) {
    return View{true, 0.8, static_cast<std::uint8_t>(t >= 1.0 && t < 1.5 ? 1 : 0)};
  });
  EXPECT_EQ(requests(events), 0u);
  EXPECT_EQ(rejections(events), std::vector{TriggerRejection::person_in_the_way});
}

TEST_F(TriggerTest, TagsWithNoPersonThereAreOperatorLost) {
  const auto events = run(trigger, sequence(kAnna, 2.4, 0.6, 2.4), 10.0,
                          [](double t) { return View{t < 4.0, 0.8, 0}; });
  EXPECT_EQ(requests(events), 0u);
  EXPECT_EQ(rejections(events), std::vector{TriggerRejection::operator_lost});
}

TEST_F(TriggerTest, NoRequestWithoutBothPhases) {
  Script front_only;
  front_only.show(kAnna, TagSide::front, 0.0, 2.4);
  auto events = run(trigger, front_only, 10.0);
  EXPECT_EQ(requests(events), 0u);
  EXPECT_EQ(rejections(events), std::vector{TriggerRejection::turn_too_long});

  ASSERT_TRUE(trigger.init(config()));
  Script back_only;
  back_only.show(kAnna, TagSide::back, 0.0, 2.4);
  events = run(trigger, back_only, 10.0);
  EXPECT_EQ(requests(events), 0u);
}

TEST_F(TriggerTest, TheFrontIsTimedFromWhenTheOperatorStands) {
  // Walking up in the window with the front towards the robot for 1.5 s, then 2.4 s standing:
  // 3.9 s of front, but 2.4 s of it standing, which is what counts.
  Script s;
  s.show(kAnna, TagSide::front, 0.0, 3.9).show(kAnna, TagSide::back, 4.5, 6.9);
  const auto walking_up = [](double t) { return View{true, t < 1.5 ? 1.0 - 0.1 * t : 0.8, 0, t < 1.5 ? 0.5 : 0.0}; };
  auto events = run(trigger, s, 10.0, walking_up);
  EXPECT_EQ(requests(events), 1u);
  EXPECT_TRUE(rejections(events).empty());
  // Standing all along, the same 3.9 s is too long.
  ASSERT_TRUE(trigger.init(config()));
  events = run(trigger, s, 10.0);
  EXPECT_EQ(requests(events), 0u);
  EXPECT_EQ(rejections(events), std::vector{TriggerRejection::front_too_long});
}

TEST_F(TriggerTest, WalkingOffWithTheBackShownAfterTheBackTimeIsTheRequest) {
  // 2.2 s of back standing in the window, then walking away with it still shown.
  Script s;
  s.show(kAnna, TagSide::front, 0.0, 2.4).show(kAnna, TagSide::back, 3.0, 7.0);
  auto events = run(trigger, s, 10.0, [](double t) { return View{true, t < 5.2 ? 0.8 : 0.8 + 0.5 * (t - 5.2), 0}; });
  ASSERT_EQ(requests(events), 1u);
  EXPECT_TRUE(rejections(events).empty());
  // The same, judged by their pace: setting off after 2.2 s of back, still in the window.
  ASSERT_TRUE(trigger.init(config()));
  events = run(trigger, s, 10.0, [](double t) { return View{true, 0.8, 0, t < 5.2 ? 0.0 : 0.5}; });
  ASSERT_EQ(requests(events), 1u);
  EXPECT_TRUE(rejections(events).empty());
  // Leaving before the back time is up: refused as too far.
  ASSERT_TRUE(trigger.init(config()));
  events = run(trigger, s, 10.0, [](double t) { return View{true, t < 4.2 ? 0.8 : 0.8 + 0.5 * (t - 4.2), 0}; });
  EXPECT_EQ(requests(events), 0u);
  EXPECT_EQ(rejections(events), std::vector{TriggerRejection::too_far});
}

TEST_F(TriggerTest, ASecondAttemptAfterARefusalWorks) {
  Script s;
  s.show(kAnna, TagSide::front, 0.0, 1.0).show(kAnna, TagSide::back, 1.6, 4.0);  // the front too short
  s.show(kAnna, TagSide::front, 7.0, 9.4).show(kAnna, TagSide::back, 10.0, 12.4);
  const auto events = run(trigger, s, 15.0);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].kind, TriggerEventKind::rejection);
  EXPECT_EQ(events[0].reason, TriggerRejection::front_too_short);
  EXPECT_EQ(events[1].kind, TriggerEventKind::request);
}

TEST_F(TriggerTest, AGlimpseOfTheFrontThatNoBackFollowsIsNoAttempt) {
  // Someone walking past with the band towards the robot: nothing to refuse.
  Script s;
  s.show(kAnna, TagSide::front, 0.0, 1.0);
  EXPECT_TRUE(run(trigger, s, 6.0).empty());
  // And a real request right after one.
  ASSERT_TRUE(trigger.init(config()));
  s.show(kAnna, TagSide::front, 4.0, 6.4).show(kAnna, TagSide::back, 7.0, 9.4);
  const auto events = run(trigger, s, 12.0);
  ASSERT_EQ(events.size(), 1u);
  EXPECT_EQ(events[0].kind, TriggerEventKind::request);
}

TEST_F(TriggerTest, AfterARefusedBackTheOperatorTurningToTheFrontStartsOver) {
  Script s;
  s.show(kAnna, TagSide::front, 0.0, 2.4).show(kAnna, TagSide::back, 3.0, 6.6);  // back too long
  s.show(kAnna, TagSide::front, 7.2, 9.6).show(kAnna, TagSide::back, 10.2, 12.6);
  const auto events = run(trigger, s, 15.0);
  ASSERT_EQ(events.size(), 2u);
  EXPECT_EQ(events[0].reason, TriggerRejection::back_too_long);
  EXPECT_EQ(events[1].kind, TriggerEventKind::request);
}

TEST_F(TriggerTest, TheSameSequenceAgainIsASecondRequest) {
  Script s = sequence(kAnna, 2.4, 0.6, 2.4);
  s.show(kAnna, TagSide::front, 6.0, 8.4).show(kAnna, TagSide::back, 9.0, 11.4);
  const auto events = run(trigger, s, 14.0);
  EXPECT_EQ(requests(events), 2u);
  EXPECT_TRUE(rejections(events).empty());
}

TEST_F(TriggerTest, NotArmedIgnoresEverythingAndCountsNothing) {
  auto events = run(trigger, sequence(kAnna, 2.4, 0.6, 2.4), 10.0, [](double) { return View{}; },
                    [](double) { return false; });
  EXPECT_TRUE(events.empty());
  EXPECT_EQ(trigger.requests(), 0u);
  EXPECT_EQ(trigger.rejections_total(), 0u);

  // Disarmed in the middle: the attempt is dropped without a refusal.
  ASSERT_TRUE(trigger.init(config()));
  events = run(trigger, sequence(kAnna, 2.4, 0.6, 2.4), 10.0, [](double) { return View{}; },
               [](double t) { return t < 1.0 || t > 7.0; });
  EXPECT_TRUE(events.empty());
  EXPECT_EQ(trigger.phase(), TriggerPhase::idle);
}

TEST_F(TriggerTest, ResetDropsTheAttemptUnderWay) {
  Script s;
  s.show(kAnna, TagSide::front, 0.0, 1.0);
  (void)run(trigger, s, 1.0);
  EXPECT_EQ(trigger.phase(), TriggerPhase::front);
  EXPECT_EQ(trigger.operator_id(), kAnna);
  trigger.reset();
  EXPECT_EQ(trigger.phase(), TriggerPhase::idle);
  EXPECT_EQ(trigger.operator_id(), 0u);
}

TEST_F(TriggerTest, ConfigurationIsChecked) {
  TriggerConfig c = config();
  c.operators.clear();
  EXPECT_FALSE(trigger.init(c));
  c = config();
  c.front_min_s = 3.5;
  EXPECT_FALSE(trigger.init(c));
  c = config();
  c.min_distance_m = 1.2;
  EXPECT_FALSE(trigger.init(c));
  c = config();
  EXPECT_TRUE(c.operators.push_back(0));
  EXPECT_FALSE(trigger.init(c));
}

TEST_F(TriggerTest, UpdatesAllocateNothing) {
  const Script s = sequence(kAnna, 2.4, 0.6, 2.4);
  std::vector<const msg::TagFrame*> frames(200, nullptr);
  for (const auto& [t, frame] : s.frames()) frames[static_cast<std::size_t>((t - kStart + kCycle - 1) / kCycle)] = &frame;
  std::size_t request_count = 0;
  mem::testing::AllocationScope scope;
  for (std::size_t k = 0; k < frames.size(); ++k) {
    TriggerInput input;
    input.now_ns = kStart + static_cast<hal::Nanos>(k) * kCycle;
    input.frame = frames[k];
    input.armed = true;
    input.operator_present = true;
    input.operator_distance_m = 0.8;
    const TriggerOutput out = trigger.update(input);
    for (const TriggerEvent& e : out.events) request_count += e.kind == TriggerEventKind::request ? 1 : 0;
  }
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(request_count, 1u);  // the loop did the work it was meant to
}

}  // namespace
}  // namespace sen3bot::cobot
