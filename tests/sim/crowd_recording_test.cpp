// Recorded pedestrians: the parser turns `frame person x y` lines into walks (a gap makes two)
// and refuses bad files with the line that is wrong; the replay passes through every
// annotation, walks straight lines at their speed, never speeds up more than 1.5 times the
// adjacent annotated speeds, stops where a person stops and allocates nothing when queried.
// The four shipped scenes reproduce their README's table.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/crowd/recording.hpp"
#include "sen3bot/crowd/replay.hpp"
#include "sen3bot/msg/point_math.hpp"

namespace sen3bot::crowd {
namespace {

constexpr double kExact_m = 1e-9;  // the target is 0.01 m; the curve gives the annotation itself
constexpr double kStep_s = 0.4;    // one annotation step of 10 frames

Recording parse_ok(std::string_view text) {
  Result<Recording> recording = parse_recording(text, "test.txt");
  EXPECT_TRUE(recording.ok()) << recording.error().message();
  return recording.ok() ? std::move(recording).value() : Recording{};
}

// A file of one person walking through `points`, one annotation step apart from frame 0.
std::string walk(const std::vector<Point2D>& points, int person = 1) {
  std::string text;
  for (std::size_t i = 0; i < points.size(); ++i) {
    text += std::to_string(10 * i) + "\t" + std::to_string(person) + "\t" + std::to_string(points[i].x_m) + "\t" +
            std::to_string(points[i].y_m) + "\n";
  }
  return text;
}

TEST(CrowdRecording, ParsesWalksInTimeOrderSkippingCommentsAndBlankLines) {
  const Recording recording = parse_ok(
      "# frame person x y\n"
      "\n"
      "100\t2\t1.5\t-2.0\r\n"
      "100 5 0.0 0.0\n"
      "110.0\t2.0\t1.75\t-2.25\n"
      "   # indented comment\n"
      "110 5 0.5 0.0\n"
      "120 5 1.0 0.0\n"
      "  130   7   3   4  \n");
  EXPECT_EQ(recording.name, "test.txt");
  EXPECT_EQ(recording.first_frame, 100);
  EXPECT_EQ(recording.frame_step, 10);
  ASSERT_EQ(recording.tracks.size(), 3u);
  // Ordered by start time, then id: 2 and 5 both start at frame 100.
  EXPECT_EQ(recording.tracks[0].person_id, 2);
  EXPECT_EQ(recording.tracks[1].person_id, 5);
  EXPECT_EQ(recording.tracks[2].person_id, 7);
  const std::vector<Sample>& two = recording.tracks[0].samples;
  ASSERT_EQ(two.size(), 2u);
  EXPECT_DOUBLE_EQ(two[0].time_s, 0.0);  // the file's first frame is time 0
  EXPECT_DOUBLE_EQ(two[1].time_s, kStep_s);
  EXPECT_DOUBLE_EQ(two[1].position.x_m, 1.75);
  EXPECT_DOUBLE_EQ(two[1].position.y_m, -2.25);
  EXPECT_EQ(recording.tracks[1].samples.size(), 3u);
  EXPECT_DOUBLE_EQ(recording.tracks[1].samples[2].time_s, 2 * kStep_s);
  EXPECT_DOUBLE_EQ(recording.tracks[2].samples[0].time_s, 3 * kStep_s);
}

TEST(CrowdRecording, APersonMissingForMoreThanOneStepBecomesTwoWalks) {
  // Person 1 is annotated at frames 0..20 and 60..70; person 2 fills every frame, so the step is
  // 10 and 30..50 is a gap.
  std::string text;
  for (int frame = 0; frame <= 70; frame += 10) {
    if (frame <= 20 || frame >= 60) text += std::to_string(frame) + " 1 " + std::to_string(0.4 * frame / 10) + " 0\n";
    text += std::to_string(frame) + " 2 5 " + std::to_string(0.4 * frame / 10) + "\n";
  }
  const Recording recording = parse_ok(text);
  ASSERT_EQ(recording.tracks.size(), 3u);
  std::vector<const Track*> ones;
  for (const Track& track : recording.tracks) {
    if (track.person_id == 1) ones.push_back(&track);
  }
  ASSERT_EQ(ones.size(), 2u);
  EXPECT_EQ(ones[0]->samples.size(), 3u);
  EXPECT_DOUBLE_EQ(ones[0]->samples.back().time_s, 2 * kStep_s);
  EXPECT_EQ(ones[1]->samples.size(), 2u);
  EXPECT_DOUBLE_EQ(ones[1]->samples.front().time_s, 6 * kStep_s);

  const Summary summary = summarize(recording);
  EXPECT_EQ(summary.people, 2u);
  EXPECT_EQ(summary.tracks, 3u);
}

TEST(CrowdRecording, TheStepIsInferredNotAssumed) {
  // Annotated every 20 frames: 0, 20, 40 is one walk, not three, and 20 frames are 0.8 s.
  const Recording recording = parse_ok("0 1 0 0\n20 1 1 0\n40 1 2 0\n");
  EXPECT_EQ(recording.frame_step, 20);
  ASSERT_EQ(recording.tracks.size(), 1u);
  EXPECT_DOUBLE_EQ(recording.tracks[0].samples[2].time_s, 4 * kStep_s);
}

struct BadFile {
  const char* what;
  std::string text;
  std::vector<std::string> expected;  // all in the message
};

TEST(CrowdRecording, BadFilesAreRefusedNamingTheFileAndLine) {
  const std::vector<BadFile> cases = {
      {"three columns", "0 1 0 0\n10 1 0.4\n", {"test.txt:2:", "4 columns", "found 3"}},
      {"five columns", "# c\n0 1 0 0 9\n", {"test.txt:2:", "found 5"}},
      {"not a number", "0 1 0 0\n\n10 1 abc 0\n", {"test.txt:3:", "x 'abc'", "not a finite number"}},
      {"trailing junk", "0 1 0 0m\n", {"test.txt:1:", "y '0m'"}},
      {"nan", "0 1 nan 0\n", {"test.txt:1:", "not a finite number"}},
      {"infinity", "0 1 0 inf\n", {"test.txt:1:", "y 'inf'"}},
      {"overflow", "0 1 1e999 0\n", {"test.txt:1:", "x '1e999'"}},
      {"fractional frame", "0 1 0 0\n10.5 1 0 0\n", {"test.txt:2:", "frame id '10.5'", "not an integer"}},
      {"fractional id", "0 1.5 0 0\n", {"test.txt:1:", "person id '1.5'", "not an integer"}},
      {"huge frame", "1e12 1 0 0\n", {"test.txt:1:", "frame id '1e12'"}},
      {"jump", "0 7 0 0\n0 8 1 1\n10 7 12 0\n", {"test.txt:3:", "person 7", "12.00 m", "0.40 s"}},
      {"just over 5 m/s", "0 7 0 0\n10 7 2.01 0\n", {"test.txt:2:", "person 7", "2.01 m"}},
      {"backwards", "0 3 0 0\n20 3 0.5 0\n10 3 0.2 0\n", {"test.txt:3:", "person 3", "backwards"}},
      {"twice in a frame", "0 4 0 0\n0 5 1 0\n0 4 0.1 0\n", {"test.txt:3:", "person 4", "twice", "frame 0"}},
      {"empty", "", {"test.txt", "no samples"}},
      {"only comments", "# a\n\n   \n# b\n", {"test.txt", "no samples"}},
  };
  for (const BadFile& bad : cases) {
    SCOPED_TRACE(bad.what);
    const Result<Recording> recording = parse_recording(bad.text, "test.txt");
    ASSERT_FALSE(recording.ok());
    EXPECT_EQ(recording.error().code(), Errc::protocol);
    for (const std::string& part : bad.expected) {
      EXPECT_NE(recording.error().message().find(part), std::string_view::npos)
          << "'" << part << "' not in: " << recording.error().message();
    }
  }
}

TEST(CrowdRecording, TheJumpLimitIsTheImpliedSpeed) {
  EXPECT_TRUE(parse_recording("0 1 0 0\n10 1 1.99 0\n", "t").ok());         // 4.98 m/s
  EXPECT_TRUE(parse_recording("0 1 0 0\n30 1 5.9 0\n", "t").ok());          // over a gap: 4.9 m/s
  EXPECT_FALSE(parse_recording("0 1 0 0\n10 1 1.99 0\n", "t", {.max_speed_m_s = 4.0}).ok());
  const Result<Recording> bad_options = parse_recording("0 1 0 0\n", "t", {.seconds_per_frame = 0.0});
  ASSERT_FALSE(bad_options.ok());
  EXPECT_EQ(bad_options.error().code(), Errc::invalid_argument);
}

TEST(CrowdRecording, ALongPathKeepsItsFileNameAndTheLine) {
  const std::string path = "/very" + std::string(300, 'x') + "/deep/scene.txt";
  const Result<Recording> recording = parse_recording("0 1 0 0\n10 1 9 9\n", path);
  ASSERT_FALSE(recording.ok());
  EXPECT_NE(recording.error().message().find("scene.txt:2: person 1"), std::string_view::npos)
      << recording.error().message();
}

TEST(CrowdRecording, LoadingAMissingFileSaysWhich) {
  const Result<Recording> recording = load_recording("/nonexistent/crowd.txt");
  ASSERT_FALSE(recording.ok());
  EXPECT_EQ(recording.error().code(), Errc::not_found);
  EXPECT_NE(recording.error().message().find("/nonexistent/crowd.txt"), std::string_view::npos);
}

TEST(CrowdRecording, SummaryCountsPeopleSpanExtentAndMedianSpeed) {
  // Person 1 walks at 1, 2 then 3 m/s; person 2 at 0.5 m/s; person 3 stands once, at frame 40.
  const Recording recording = parse_ok(
      "0 1 0 0\n0 2 -1 5\n"
      "10 1 0.4 0\n10 2 -1 5.2\n"
      "20 1 1.2 0\n"
      "30 1 2.4 0\n"
      "40 3 6 -3\n");
  const Summary summary = summarize(recording);
  EXPECT_EQ(summary.people, 3u);
  EXPECT_EQ(summary.tracks, 3u);
  EXPECT_EQ(summary.samples, 7u);
  EXPECT_DOUBLE_EQ(summary.start_s, 0.0);
  EXPECT_DOUBLE_EQ(summary.end_s, 4 * kStep_s);
  EXPECT_DOUBLE_EQ(summary.extent.min.x_m, -1.0);
  EXPECT_DOUBLE_EQ(summary.extent.min.y_m, -3.0);
  EXPECT_DOUBLE_EQ(summary.extent.max.x_m, 6.0);
  EXPECT_DOUBLE_EQ(summary.extent.max.y_m, 5.2);
  EXPECT_EQ(summary.most_at_once, 2u);
  EXPECT_NEAR(summary.median_speed_m_s, 1.5, 1e-12);  // of 0.5, 1, 2, 3

  const std::vector<FrameCount> frames = people_per_frame(recording);
  ASSERT_EQ(frames.size(), 5u);
  const std::size_t expected[] = {2, 2, 1, 1, 1};
  for (std::size_t i = 0; i < frames.size(); ++i) {
    EXPECT_DOUBLE_EQ(frames[i].time_s, static_cast<double>(i) * kStep_s);
    EXPECT_EQ(frames[i].people, expected[i]);
  }

  // An odd number of speeds: the middle one.
  EXPECT_NEAR(summarize(parse_ok("0 1 0 0\n10 1 0.4 0\n20 1 1.2 0\n30 1 2.4 0\n")).median_speed_m_s, 2.0, 1e-12);
}

TEST(CrowdRecording, BusiestPointIsTheCentreOfTheFullestCell) {
  // Three samples in the 1 m cell [2, 3) x [3, 4), two near the origin, one far away.
  const Recording recording = parse_ok(
      "0 1 0.1 0.1\n10 1 0.2 0.15\n"
      "0 2 2.1 3.9\n10 2 2.5 3.5\n20 2 2.9 3.1\n"
      "0 3 -7.5 -7.5\n");
  const Result<Point2D> busiest = busiest_point(recording);
  ASSERT_TRUE(busiest.ok()) << busiest.error().message();
  EXPECT_DOUBLE_EQ(busiest->x_m, 2.5);
  EXPECT_DOUBLE_EQ(busiest->y_m, 3.5);
  // On a 0.25 m grid the origin's two share a cell while person 2's three do not.
  const Result<Point2D> fine = busiest_point(recording, 0.25);
  ASSERT_TRUE(fine.ok());
  EXPECT_DOUBLE_EQ(fine->x_m, 0.125);
  EXPECT_DOUBLE_EQ(fine->y_m, 0.125);
  EXPECT_EQ(busiest_point(recording, 0.0).error().code(), Errc::invalid_argument);
  EXPECT_FALSE(busiest_point(Recording{}).ok());
}

// The fastest the replay goes between annotations i and i + 1 of a track, over the fastest of
// the annotated (secant) speeds of the segments before, at and after it; the worst over all.
double worst_speed_ratio(Replay& replay) {
  double worst = 0.0;
  for (std::size_t t = 0; t < replay.track_count(); ++t) {
    const std::vector<Sample>& s = replay.recording().tracks[t].samples;
    auto secant = [&](std::size_t i) {
      return geometry::distance(s[i + 1].position, s[i].position) / (s[i + 1].time_s - s[i].time_s);
    };
    for (std::size_t i = 0; i + 1 < s.size(); ++i) {
      double adjacent = secant(i);
      if (i > 0) adjacent = std::max(adjacent, secant(i - 1));
      if (i + 2 < s.size()) adjacent = std::max(adjacent, secant(i + 1));
      for (int k = 0; k <= 20; ++k) {
        const double time_s = s[i].time_s + (s[i + 1].time_s - s[i].time_s) * k / 20.0;
        const double speed = msg::norm(replay.state_at(t, time_s).velocity_m_s);
        if (adjacent > 1e-9) worst = std::max(worst, speed / adjacent);
      }
    }
  }
  return worst;
}

TEST(CrowdReplay, PassesThroughEveryAnnotationWithAContinuousVelocity) {
  const Recording recording =
      parse_ok(walk({{0, 0}, {0.5, 0.1}, {0.9, 0.5}, {1.0, 1.1}, {0.8, 1.5}, {0.3, 1.6}, {0.3, 1.6}, {0.1, 1.2}}));
  Replay replay(recording);
  const std::vector<Sample>& samples = recording.tracks[0].samples;
  for (std::size_t i = 0; i < samples.size(); ++i) {
    SCOPED_TRACE(i);
    const WalkerState at = replay.state_at(0, samples[i].time_s);
    ASSERT_TRUE(at.visible);
    EXPECT_LT(geometry::distance(at.position, samples[i].position), kExact_m);
    if (i == 0 || i + 1 == samples.size()) continue;
    // C1: the velocity just before and just after an annotation agree.
    constexpr double kEpsilon_s = 1e-7;
    const Point2D before = replay.state_at(0, samples[i].time_s - kEpsilon_s).velocity_m_s;
    const Point2D after = replay.state_at(0, samples[i].time_s + kEpsilon_s).velocity_m_s;
    EXPECT_LT(geometry::distance(before, after), 1e-4);
    EXPECT_LT(geometry::distance(before, at.velocity_m_s), 1e-4);
  }
}

TEST(CrowdReplay, AStraightWalkAtConstantSpeedIsInterpolatedLinearly) {
  // 1.25 m/s along (3, 4) / 5.
  std::vector<Point2D> points;
  for (int i = 0; i < 5; ++i) points.push_back({0.3 * i, 0.4 * i});
  Replay replay(parse_ok(walk(points)));
  const Point2D expected_velocity{0.75, 1.0};
  for (int i = 0; i + 1 < 5; ++i) {
    for (const double fraction : {0.25, 0.5, 0.75}) {
      SCOPED_TRACE(i + fraction);
      const WalkerState state = replay.state_at(0, (i + fraction) * kStep_s);
      ASSERT_TRUE(state.visible);
      EXPECT_LT(geometry::distance(state.position, points[i] + fraction * (points[i + 1] - points[i])), kExact_m);
      EXPECT_LT(geometry::distance(state.velocity_m_s, expected_velocity), 1e-9);
    }
  }
}

TEST(CrowdReplay, SpeedStaysWithinOneAndAHalfTimesTheAdjacentAnnotatedSpeeds) {
  // A circle at 1.2 m/s, a sharp corner, a turn back and a zig-zag.
  std::vector<Point2D> circle;
  for (int i = 0; i < 30; ++i) circle.push_back({2.0 * std::cos(0.24 * i), 2.0 * std::sin(0.24 * i)});
  const std::vector<Point2D> corner = {{0, 0}, {0.5, 0}, {1.0, 0}, {1.0, 0.5}, {1.0, 1.0}};
  const std::vector<Point2D> back = {{0, 0}, {0.5, 0}, {1.0, 0}, {0.5, 0}, {0, 0}};
  const std::vector<Point2D> zigzag = {{0, 0}, {0.3, 0.5}, {0.6, 0}, {0.9, 0.5}, {1.2, 0}, {1.5, 0.5}};
  for (const auto& points : {circle, corner, back, zigzag}) {
    Replay replay(parse_ok(walk(points)));
    EXPECT_LE(worst_speed_ratio(replay), 1.5 + 1e-9);
  }
  // Random walks of varied speed and heading.
  std::mt19937_64 rng(7);
  std::uniform_real_distribution<double> step_m(-0.9, 0.9);
  std::string text;
  for (int person = 1; person <= 200; ++person) {
    Point2D at{};
    for (int i = 0; i < 8; ++i) {
      text += std::to_string(10 * i) + " " + std::to_string(person) + " " + std::to_string(at.x_m) + " " +
              std::to_string(at.y_m) + "\n";
      at += Point2D{step_m(rng), step_m(rng)};
    }
  }
  Replay random(parse_ok(text));
  const double worst = worst_speed_ratio(random);
  EXPECT_LE(worst, 1.5 + 1e-9);
  EXPECT_GT(worst, 1.0);  // the check sees curves that do speed up between annotations
}

TEST(CrowdReplay, APersonWhoStopsDoesNotOvershoot) {
  // Walks along x at 1.2 m/s and stands at 1.44 m: the curve must not go past it and come back.
  Replay replay(parse_ok(walk({{0, 0}, {0.48, 0}, {0.96, 0}, {1.44, 0}, {1.44, 0}, {1.44, 0}})));
  for (int k = 0; k <= 500; ++k) {
    const double time_s = 5 * kStep_s * k / 500.0;
    const WalkerState state = replay.state_at(0, time_s);
    ASSERT_TRUE(state.visible);
    EXPECT_LE(state.position.x_m, 1.44 + kExact_m) << "at " << time_s << " s";
    EXPECT_GE(state.velocity_m_s.x_m, -1e-12) << "at " << time_s << " s";
  }
  EXPECT_LT(msg::norm(replay.state_at(0, 3.5 * kStep_s).velocity_m_s), 1e-12);  // standing
}

TEST(CrowdReplay, WalkersAreVisibleOnlyDuringTheirWalks) {
  // Person 1 walks over frames 0..20 and 60..80; person 2 keeps the step at 10.
  std::string text;
  for (int frame = 0; frame <= 80; frame += 10) {
    if (frame <= 20 || frame >= 60) text += std::to_string(frame) + " 1 " + std::to_string(0.1 * frame) + " 1\n";
    text += std::to_string(frame) + " 2 0 " + std::to_string(0.1 * frame) + "\n";
  }
  Replay replay(parse_ok(text));
  ASSERT_EQ(replay.track_count(), 3u);
  std::vector<std::size_t> ones;
  for (std::size_t t = 0; t < replay.track_count(); ++t) {
    if (replay.recording().tracks[t].person_id == 1) ones.push_back(t);
  }
  ASSERT_EQ(ones.size(), 2u);
  auto person_one_visible = [&](double time_s) {
    return replay.state_at(ones[0], time_s).visible || replay.state_at(ones[1], time_s).visible;
  };
  EXPECT_TRUE(person_one_visible(0.0));
  EXPECT_TRUE(person_one_visible(2 * kStep_s));  // the last annotation before the gap
  EXPECT_FALSE(person_one_visible(2 * kStep_s + 1e-6));
  EXPECT_FALSE(person_one_visible(4 * kStep_s));
  EXPECT_FALSE(person_one_visible(6 * kStep_s - 1e-6));
  EXPECT_TRUE(person_one_visible(6 * kStep_s));
  EXPECT_TRUE(person_one_visible(8 * kStep_s));
  EXPECT_FALSE(person_one_visible(8 * kStep_s + 1e-6));
  EXPECT_FALSE(person_one_visible(-1e-6));
  EXPECT_LT(geometry::distance(replay.state_at(ones[1], 6 * kStep_s).position, {6.0, 1.0}), kExact_m);

  const WalkerState absent = replay.state_at(ones[0], 4 * kStep_s);
  EXPECT_LT(msg::norm(absent.position) + msg::norm(absent.velocity_m_s), 1e-12);
  EXPECT_FALSE(replay.state_at(replay.track_count(), 0.0).visible);
  EXPECT_FALSE(replay.state_at(0, std::nan("")).visible);
}

TEST(CrowdReplay, QueriesInAnyOrderAgreeWithQueriesInOrder) {
  std::vector<Point2D> points;
  for (int i = 0; i < 40; ++i) points.push_back({0.5 * i, std::sin(0.3 * i)});
  const Recording recording = parse_ok(walk(points));
  Replay in_order(recording);
  Replay shuffled(recording);
  const double end_s = recording.tracks[0].samples.back().time_s;
  std::vector<double> times_s;
  for (int k = 0; k <= 400; ++k) times_s.push_back(end_s * k / 400.0);
  std::vector<WalkerState> expected;
  for (const double t : times_s) expected.push_back(in_order.state_at(0, t));
  std::vector<std::size_t> order(times_s.size());
  for (std::size_t i = 0; i < order.size(); ++i) order[i] = i;
  std::shuffle(order.begin(), order.end(), std::mt19937_64(3));
  for (const std::size_t i : order) {
    const WalkerState state = shuffled.state_at(0, times_s[i]);
    ASSERT_TRUE(state.visible);
    EXPECT_EQ(state.position.x_m, expected[i].position.x_m) << times_s[i];
    EXPECT_EQ(state.position.y_m, expected[i].position.y_m) << times_s[i];
    EXPECT_EQ(state.velocity_m_s.x_m, expected[i].velocity_m_s.x_m) << times_s[i];
  }
}

TEST(CrowdReplay, QueriesDoNotAllocate) {
  std::vector<Point2D> points;
  for (int i = 0; i < 50; ++i) points.push_back({0.4 * i, 0.1 * (i % 3)});
  std::string text = walk(points, 1) + walk(points, 2);
  Replay replay(parse_ok(text));
  std::vector<WalkerState> states(replay.track_count());
  int visible = 0;
  const mem::testing::AllocationScope scope;
  for (int k = 0; k < 10'000; ++k) {
    const double time_s = (k % 1000) * 0.0195;  // forward sweeps over the walk, and back to its start
    replay.states_at(time_s, states);
    visible += states[0].visible ? 1 : 0;
    visible += replay.state_at(1, 19.6 - time_s).visible ? 1 : 0;  // backwards
  }
  EXPECT_EQ(scope.allocations(), 0u);
  if (mem::testing::counts_malloc()) {
    EXPECT_EQ(scope.malloc_calls(), 0u);
  }
  EXPECT_EQ(visible, 20'000);
}

// The README's table of the shipped scenes.
struct RecordedScene {
  const char* file;
  std::size_t people;
  double duration_s;
  std::size_t most_at_once;
  double median_speed_m_s;
};

constexpr RecordedScene kScenes[] = {
    {"biwi_hotel.txt", 389, 722, 18, 1.27},
    {"crowds_zara01.txt", 148, 360, 20, 1.15},
    {"students001.txt", 415, 177, 75, 0.52},
    {"uni_examples.txt", 118, 296, 9, 1.46},
};

std::string dataset(const char* file) {
  return std::string(SEN3BOT_SOURCE_DIR) + "/data/pedestrians/" + file;
}

TEST(CrowdScenes, TheShippedFilesReproduceTheirTable) {
  for (const RecordedScene& scene : kScenes) {
    SCOPED_TRACE(scene.file);
    const Result<Recording> recording = load_recording(dataset(scene.file));
    ASSERT_TRUE(recording.ok()) << recording.error().message();
    EXPECT_EQ(recording->frame_step, 10);
    const Summary summary = summarize(*recording);
    EXPECT_EQ(summary.people, scene.people);
    EXPECT_EQ(summary.tracks, scene.people);  // nobody leaves and comes back in these files
    EXPECT_NEAR(summary.end_s - summary.start_s, scene.duration_s, 0.5);
    EXPECT_EQ(summary.most_at_once, scene.most_at_once);
    EXPECT_NEAR(summary.median_speed_m_s, scene.median_speed_m_s, 0.005);
    const Result<Point2D> busiest = busiest_point(*recording);
    ASSERT_TRUE(busiest.ok());
    EXPECT_GE(busiest->x_m, summary.extent.min.x_m - 0.5);
    EXPECT_LE(busiest->x_m, summary.extent.max.x_m + 0.5);
    EXPECT_GE(busiest->y_m, summary.extent.min.y_m - 0.5);
    EXPECT_LE(busiest->y_m, summary.extent.max.y_m + 0.5);
    std::printf("%-18s %3zu people, %5.1f s, %2zu at once, median %.3f m/s, x [%.1f, %.1f] y [%.1f, %.1f] m, "
                "busiest (%.1f, %.1f) m\n",
                scene.file, summary.people, summary.end_s - summary.start_s, summary.most_at_once,
                summary.median_speed_m_s, summary.extent.min.x_m, summary.extent.max.x_m, summary.extent.min.y_m,
                summary.extent.max.y_m, busiest->x_m, busiest->y_m);
  }
}

TEST(CrowdScenes, ReplayingEachFileAtItsFramesGivesBackItsAnnotations) {
  for (const RecordedScene& scene : kScenes) {
    SCOPED_TRACE(scene.file);
    Result<Recording> loaded = load_recording(dataset(scene.file));
    ASSERT_TRUE(loaded.ok()) << loaded.error().message();
    const std::vector<FrameCount> frames = people_per_frame(*loaded);
    Replay replay(std::move(loaded).value());
    const Recording& recording = replay.recording();

    // Every walker at every annotated time, as the world would ask: the people in view are
    // the people annotated, each where the file puts them.
    std::vector<WalkerState> states(replay.track_count());
    std::vector<std::size_t> next(replay.track_count(), 0);  // each track's next annotation
    std::size_t checked = 0;
    for (const FrameCount& frame : frames) {
      replay.states_at(frame.time_s, states);
      std::size_t visible = 0;
      for (std::size_t t = 0; t < states.size(); ++t) {
        if (!states[t].visible) continue;
        ++visible;
        const std::vector<Sample>& samples = recording.tracks[t].samples;
        ASSERT_LT(next[t], samples.size());
        ASSERT_EQ(samples[next[t]].time_s, frame.time_s);
        EXPECT_LT(geometry::distance(states[t].position, samples[next[t]].position), kExact_m);
        ++next[t];
        ++checked;
      }
      EXPECT_EQ(visible, frame.people) << "at " << frame.time_s << " s";
    }
    EXPECT_EQ(checked, summarize(recording).samples);
    // Real walks, too, never speed up by more than half between annotations.
    EXPECT_LE(worst_speed_ratio(replay), 1.5 + 1e-9);
  }
}

}  // namespace
}  // namespace sen3bot::crowd
