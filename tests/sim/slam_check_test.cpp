// `sen3bot-sim slam-check` (sim/app/slam_check.hpp): on a small synthetic CARMEN log of a box
// room driven round three times, the true trajectory agrees with itself and one with a 0.3 m error
// in its later scans disagrees by 0.3 m; the poses files, the pair choice, the map and the
// command's errors and report.
#include <gtest/gtest.h>

#include <unistd.h>

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <numbers>
#include <span>
#include <string>
#include <vector>

#include "../slam/synthetic_world.hpp"
#include "command_capture.hpp"
#include "sen3bot/json/json.hpp"
#include "sim_commands.hpp"
#include "slam_check.hpp"

namespace sen3bot::sim::slam_check {
namespace {

constexpr std::size_t kLapScans = 20;
constexpr std::size_t kSlamLogScans = 3 * kLapScans;
constexpr double kInjectedM = 0.3;
constexpr std::size_t kTestMinGap = 20;

// A 6 m x 4 m room with two round pillars, its walls off the cells' boundaries.
slam::test::World room() {
  slam::test::World w;
  w.box(-3.01, -2.03, 3.02, 2.04);
  w.posts.push_back({1.51, 0.77, 0.2});
  w.posts.push_back({-1.22, -0.93, 0.15});
  return w;
}

// Three laps round the middle, each 0.1 m wider and a little more turned than the one before, so
// a scan of one lap is near but not at one of the next.
std::vector<nav::Pose2D> truth_poses() {
  std::vector<nav::Pose2D> poses;
  for (std::size_t k = 0; k < kSlamLogScans; ++k) {
    const std::size_t lap = k / kLapScans;
    const double phi = 2.0 * std::numbers::pi * static_cast<double>(k % kLapScans) / kLapScans;
    const double r = 1.0 + 0.1 * static_cast<double>(lap);
    poses.push_back({r * std::cos(phi), r * std::sin(phi),
                     nav::normalize_angle(phi + std::numbers::pi / 2 + 0.05 * static_cast<double>(lap))});
  }
  return poses;
}

// The truth with kInjectedM along x added from the second lap on.
std::vector<nav::Pose2D> injected_poses() {
  std::vector<nav::Pose2D> poses = truth_poses();
  for (std::size_t k = kLapScans; k < poses.size(); ++k) poses[k].x_m += kInjectedM;
  return poses;
}

std::string pose_text(const nav::Pose2D& p) {
  char s[96];
  std::snprintf(s, sizeof s, "%.6f %.6f %.6f", p.x_m, p.y_m, p.theta_rad);
  return s;
}

// The CARMEN text of the drive: scans from the truth, the odometry the injected trajectory.
std::string carmen_text() {
  const slam::test::World w = room();
  const std::vector<nav::Pose2D> truth = truth_poses();
  const std::vector<nav::Pose2D> odometry = injected_poses();
  std::string text = "# synthetic box room, three laps\n";
  for (std::size_t k = 0; k < truth.size(); ++k) {
    const slam::LaserRecord r = w.scan(truth[k], odometry[k]);
    text += "ODOM " + pose_text(odometry[k]) + " 0 0 0 " + std::to_string(k) + " nohost " + std::to_string(k) + "\n";
    text += "FLASER " + std::to_string(r.count);
    for (std::uint32_t i = 0; i < r.count; ++i) {
      char range[32];
      std::snprintf(range, sizeof range, " %.4f", r.ranges[i]);
      text += range;
    }
    // The laser at the robot's origin: its pose is the odometry pose.
    text += " " + pose_text(odometry[k]) + " " + pose_text(odometry[k]) + " " + std::to_string(k) + " nohost " +
            std::to_string(k) + "\n";
  }
  return text;
}

std::string poses_text(const std::vector<nav::Pose2D>& poses) {
  std::string text;
  for (std::size_t k = 0; k < poses.size(); ++k) text += std::to_string(k) + " " + pose_text(poses[k]) + "\n";
  return text;
}

class SlamCheckFiles : public ::testing::Test {
 protected:
  void SetUp() override {
    char dir[] = "/tmp/sen3bot_slam_check_XXXXXX";
    ASSERT_NE(::mkdtemp(dir), nullptr);
    dir_ = dir;
  }
  void TearDown() override {
    std::error_code ec;
    std::filesystem::remove_all(dir_, ec);
  }
  std::string write(const std::string& name, const std::string& text) const {
    const std::string path = dir_ + "/" + name;
    std::ofstream(path, std::ios::binary) << text;
    return path;
  }
  std::string dir_;
};

std::vector<Scan> synthetic_scans() {
  std::vector<Scan> scans;
  const slam::test::World w = room();
  for (const nav::Pose2D& p : truth_poses()) {
    const slam::LaserRecord r = w.scan(p, p);
    scans.push_back({p, {}, robot_points(r)});
  }
  return scans;
}

PairOptions test_pairs() {
  PairOptions o;
  o.min_gap = kTestMinGap;
  return o;
}

TEST(SlamCheck, TheTrueTrajectoryAgreesWithItself) {
  const std::vector<Scan> scans = synthetic_scans();
  const std::vector<nav::Pose2D> truth = truth_poses();
  const std::vector<ScanPair> pairs = choose_pairs(truth, test_pairs());
  ASSERT_GE(pairs.size(), 3u);
  PairChecker checker;
  ASSERT_TRUE(checker.ready());
  std::vector<PairCheck> checks;
  for (const ScanPair& p : pairs) {
    checks.push_back(check_pair(checker, scans, truth, p));
    const PairCheck& c = checks.back();
    EXPECT_TRUE(c.matched_ok) << p.i << "-" << p.j << " score " << c.score;
    EXPECT_LT(c.translation_m, 0.03) << p.i << "-" << p.j;
    EXPECT_LT(c.rotation_deg, 0.5) << p.i << "-" << p.j;
  }
  const Summary s = summarise(checks);
  EXPECT_EQ(s.pairs, pairs.size());
  EXPECT_EQ(s.matched, pairs.size());
  EXPECT_LT(s.translation_m.mean, 0.02);
  EXPECT_LT(s.translation_m.p95, 0.03);
  EXPECT_LT(s.rotation_deg.median, 0.3);
}

TEST(SlamCheck, AnErrorInTheLaterScansShowsAsItsSize) {
  const std::vector<Scan> scans = synthetic_scans();
  const std::vector<nav::Pose2D> wrong = injected_poses();
  // The true trajectory's pairs (the common set), judged under the wrong one: a pair across the
  // injection disagrees by its size, one on either side of it not at all.
  const std::vector<ScanPair> pairs = choose_pairs(truth_poses(), test_pairs());
  PairChecker checker;
  std::size_t across = 0;
  for (const ScanPair& p : pairs) {
    const PairCheck c = check_pair(checker, scans, wrong, p);
    ASSERT_TRUE(c.matched_ok) << p.i << "-" << p.j << " score " << c.score;
    const bool crosses = p.i < kLapScans && p.j >= kLapScans;
    across += crosses ? 1 : 0;
    EXPECT_NEAR(c.translation_m, crosses ? kInjectedM : 0.0, 0.03) << p.i << "-" << p.j;
    EXPECT_LT(c.rotation_deg, 0.5) << p.i << "-" << p.j;
  }
  EXPECT_GE(across, 2u);
}

TEST(SlamCheck, AnErrorPastTheWindowIsALowerBoundAtItsEdge) {
  const std::vector<Scan> scans = synthetic_scans();
  std::vector<nav::Pose2D> poses = truth_poses();
  for (std::size_t k = kLapScans; k < poses.size(); ++k) poses[k].x_m += 0.6;
  PairChecker checker;
  for (const ScanPair& p : choose_pairs(truth_poses(), test_pairs())) {
    const PairCheck truth = check_pair(checker, scans, truth_poses(), p);
    EXPECT_FALSE(truth.at_window_edge) << p.i << "-" << p.j;
    if (p.i >= kLapScans || p.j < kLapScans) continue;
    const PairCheck c = check_pair(checker, scans, poses, p);
    EXPECT_TRUE(c.at_window_edge) << p.i << "-" << p.j;
    EXPECT_LT(c.translation_m, 0.6 * std::sqrt(0.5) + 0.05) << p.i << "-" << p.j;
  }
}

TEST(SlamCheck, AScanAgainstItselfScoresTheCeiling) {
  const std::vector<Scan> scans = synthetic_scans();
  PairChecker checker;
  const PairCheck c = checker.check(scans[3], scans[3], {});
  EXPECT_GT(c.score, score_ceiling() - 0.04);
  EXPECT_LE(c.score, score_ceiling() + 0.002);  // the bytes' rounding
  EXPECT_NEAR(score_ceiling(), 0.646, 0.001);   // three hits at 0.55
  EXPECT_LT(c.translation_m, 0.01);
  EXPECT_FALSE(c.at_window_edge);
}

TEST(SlamCheck, WildPosesAreNotMatchedAndNoMap) {
  const std::vector<Scan> scans = synthetic_scans();
  PairChecker checker;
  for (const nav::Pose2D& far : {nav::Pose2D{1e300, 0, 0}, nav::Pose2D{-30.0, 2.0, 0.1}, nav::Pose2D{0, 1e12, 3.0}}) {
    const PairCheck c = checker.check(scans[0], scans[1], far);
    EXPECT_FALSE(c.matched_ok);
    EXPECT_EQ(c.score, 0.0);
  }
  std::vector<nav::Pose2D> poses = truth_poses();
  poses[7].x_m = 1e200;
  Result<MapGrid> map = render_map(scans, poses);
  ASSERT_FALSE(map.ok());
  EXPECT_NE(std::string(map.error().c_str()).find("spread over more than"), std::string::npos) << map.error().c_str();
}

TEST(SlamCheck, PoseFilesParseAndRejectMalformedLinesByNumber) {
  Result<std::vector<nav::Pose2D>> ok = parse_poses("# index x y theta\n0 0 0 0\n\n1 1.5 -2 0.25\n2 3 4 -3.1\n", "p.txt");
  ASSERT_TRUE(ok.ok()) << ok.error().c_str();
  ASSERT_EQ(ok->size(), 3u);
  EXPECT_DOUBLE_EQ((*ok)[1].x_m, 1.5);
  EXPECT_DOUBLE_EQ((*ok)[1].y_m, -2.0);
  EXPECT_DOUBLE_EQ((*ok)[2].theta_rad, -3.1);
  EXPECT_TRUE(parse_poses("", "p.txt")->empty());
  struct Case {
    const char* text;
    const char* says;
  };
  const Case cases[] = {
      {"0 0 0 0\n1 0.1 0.2\n", "p.txt:2: expected 'index x y theta', got 3 fields"},
      {"0 0 0 0 0\n", "p.txt:1: expected 'index x y theta', got 5 fields"},
      {"0 0 0 0\n\n# gap\n1 x 0 0\n", "p.txt:4: x is not a finite number"},
      {"0 0 0 0\n1 0 nan 0\n", "p.txt:2: y is not a finite number"},
      {"0 0 0 1e999\n", "p.txt:1: theta is not a finite number"},
      {"0 0 0 0\n2 0 0 0\n", "p.txt:2: expected index 1"},
      {"-1 0 0 0\n", "p.txt:1: the index is not a whole number"},
      {"0 0 0 0\n1 0 0 0.5rad\n", "p.txt:2: theta"},
  };
  for (const Case& c : cases) {
    Result<std::vector<nav::Pose2D>> r = parse_poses(c.text, "p.txt");
    ASSERT_FALSE(r.ok()) << c.text;
    EXPECT_NE(std::string(r.error().c_str()).find(c.says), std::string::npos) << r.error().c_str();
  }
}

// Out along x and back over the same line: a pair for every block of i whose scans come back.
TEST(SlamCheck, PairsKeepTheGapTheDistanceAndOnePerBlock) {
  std::vector<nav::Pose2D> poses;
  for (int k = 0; k < 100; ++k) poses.push_back({0.1 * (k < 50 ? k : 99 - k), 0.02 * (k % 3), 0.01 * (k % 5)});
  for (const double max_distance : {1.0, 0.35, 0.05}) {
    for (const std::size_t gap : {std::size_t{20}, std::size_t{60}}) {
      PairOptions o;
      o.min_gap = gap;
      o.max_distance_m = max_distance;
      const std::vector<ScanPair> pairs = choose_pairs(poses, o);
      std::size_t last_block = 0;
      for (std::size_t n = 0; n < pairs.size(); ++n) {
        const ScanPair& p = pairs[n];
        EXPECT_GE(p.j - p.i, gap);
        EXPECT_LE(std::hypot(poses[p.j].x_m - poses[p.i].x_m, poses[p.j].y_m - poses[p.i].y_m), max_distance + 1e-12);
        EXPECT_LE(std::abs(poses[p.j].theta_rad - poses[p.i].theta_rad), kMaxAngleRad);
        if (n > 0) {
          EXPECT_GT(p.i / kPairStride, last_block) << "two pairs in one block of 10";
        }
        last_block = p.i / kPairStride;
      }
      // Every block with a qualifying pair has one, and it is the nearest there.
      for (std::size_t block = 0; block < poses.size(); block += kPairStride) {
        double nearest = 1e9;
        for (std::size_t i = block; i < block + kPairStride; ++i)
          for (std::size_t j = i + gap; j < poses.size(); ++j) {
            const double d = std::hypot(poses[j].x_m - poses[i].x_m, poses[j].y_m - poses[i].y_m);
            if (d <= max_distance) nearest = std::min(nearest, d);
          }
        const auto chosen = std::find_if(pairs.begin(), pairs.end(),
                                         [&](const ScanPair& p) { return p.i / kPairStride == block / kPairStride; });
        ASSERT_EQ(chosen != pairs.end(), nearest < 1e9) << "block " << block << " gap " << gap << " max " << max_distance;
        if (chosen != pairs.end()) {
          EXPECT_NEAR(std::hypot(poses[chosen->j].x_m - poses[chosen->i].x_m, poses[chosen->j].y_m - poses[chosen->i].y_m),
                      nearest, 1e-12);
        }
      }
    }
  }
  // The way back is out of reach for a gap past it, and nothing pairs across a half turn.
  PairOptions far;
  far.min_gap = 100;
  EXPECT_TRUE(choose_pairs(poses, far).empty());
  for (std::size_t k = 50; k < poses.size(); ++k) poses[k].theta_rad = std::numbers::pi;
  EXPECT_TRUE(choose_pairs(poses, PairOptions{20, 1.0, kMaxAngleRad, kPairStride}).empty());
}

TEST(SlamCheck, QuantilesInterpolate) {
  EXPECT_DOUBLE_EQ(quantile({3, 1, 2, 4}, 0.5), 2.5);
  EXPECT_DOUBLE_EQ(quantile({1, 2, 3, 4, 5}, 0.95), 4.8);
  EXPECT_DOUBLE_EQ(quantile({7}, 0.95), 7.0);
  EXPECT_TRUE(std::isnan(quantile({}, 0.5)));
}

TEST(SlamCheck, PairsNotMatchedStayOutOfTheStatistics) {
  std::vector<PairCheck> checks(4);
  checks[0].matched_ok = true;
  checks[0].translation_m = 0.1;
  checks[0].rotation_deg = 1.0;
  checks[1].matched_ok = true;
  checks[1].translation_m = 0.3;
  checks[1].rotation_deg = 3.0;
  checks[1].at_window_edge = true;
  checks[2].at_window_edge = true;  // not matched: not counted
  for (std::size_t k = 0; k < checks.size(); ++k) checks[k].score = 0.4 + 0.1 * static_cast<double>(k);
  checks[2].translation_m = 5.0;  // below the score: not matched
  checks[3].translation_m = 7.0;
  const Summary s = summarise(checks);
  EXPECT_EQ(s.pairs, 4u);
  EXPECT_EQ(s.matched, 2u);
  EXPECT_EQ(s.matched_at_window_edge, 1u);
  EXPECT_DOUBLE_EQ(s.score_median, 0.55);
  EXPECT_DOUBLE_EQ(s.translation_m.mean, 0.2);
  EXPECT_DOUBLE_EQ(s.translation_m.median, 0.2);
  EXPECT_DOUBLE_EQ(s.rotation_deg.p95, 2.9);
  const Summary none = summarise(std::span<const PairCheck>(checks).subspan(2));
  EXPECT_EQ(none.matched, 0u);
  EXPECT_TRUE(std::isnan(none.translation_m.mean));
}

TEST(SlamCheck, TheMapHasTheRoomsWallsWhereTheyAre) {
  const std::vector<Scan> scans = synthetic_scans();
  const std::vector<nav::Pose2D> truth = truth_poses();
  Result<MapGrid> map = render_map(scans, truth);
  ASSERT_TRUE(map.ok()) << map.error().c_str();
  EXPECT_DOUBLE_EQ(map->resolution_m, 0.05);
  const auto at = [&](double x, double y) {
    const int c = static_cast<int>(std::floor((x - map->origin_x_m) / map->resolution_m));
    const int r = static_cast<int>(std::floor((y - map->origin_y_m) / map->resolution_m));
    return map->cells[static_cast<std::size_t>(r) * static_cast<std::size_t>(map->width) + static_cast<std::size_t>(c)];
  };
  EXPECT_GE(at(3.02 + 0.01, 0.3), 50);   // the east wall's cell
  EXPECT_GE(at(-0.5, -2.03 - 0.01), 50);  // the south wall's
  EXPECT_GE(at(0.0, 0.0), 0);             // the middle: seen, free
  EXPECT_LT(at(0.0, 0.0), 50);
  EXPECT_EQ(at(1.51, 0.77), -1);          // inside a pillar: never seen
  // The room and its margin of 10 cells, not more.
  EXPECT_NEAR(map->width * map->resolution_m, 6.03 + 1.0, 0.15);
  EXPECT_NEAR(map->height * map->resolution_m, 4.07 + 1.0, 0.15);

  MapFigure f;
  f.title = "synthetic: trajectory truth";
  f.subtitle = "own pairs";
  f.map = &*map;
  f.trajectory = truth;
  const figure::Canvas canvas = draw_map_figure(f);
  EXPECT_GT(canvas.width(), 400);
  EXPECT_GT(canvas.height(), 300);
}

// The JSON report's statistics of one trajectory: "name" then "own" or "common".
double reported(const json::Document& doc, const std::string& name, const char* set, const char* quantity,
                const char* stat) {
  for (json::Value t : doc.root().find("trajectories").items()) {
    if (!t.find("name").string_equals(name)) continue;
    Result<double> v = t.find(set).find(quantity).find(stat).number();
    return v.ok() ? *v : -1.0;
  }
  return -2.0;
}

TEST_F(SlamCheckFiles, TheCommandReportsEachTrajectoryOnItsOwnAndTheCommonPairs) {
  const std::string log = write("box.log", carmen_text());
  const std::string truth = write("truth.txt", poses_text(truth_poses()));
  const std::string figures = dir_ + "/fig";
  const sen3bot::testing::CommandOutcome run = sen3bot::testing::run_command(
      slam_check_command,
      {"--carmen", log, "--poses", "truth=" + truth, "--odometry", "--figure", figures, "--min-gap", "20"});
  ASSERT_EQ(run.code, 0) << run.err;
  json::StaticDocument<2048> doc;
  ASSERT_TRUE(doc.parse(run.out).ok()) << run.out;
  EXPECT_EQ(*doc.root().find("scans").uint32(), kSlamLogScans);
  EXPECT_TRUE(doc.root().find("common_pairs").find("chosen_by").string_equals("truth"));
  EXPECT_LT(reported(doc, "truth", "own", "translation_m", "mean"), 0.03);
  EXPECT_LT(reported(doc, "truth", "common", "translation_m", "p95"), 0.03);
  // The log's odometry is the injected trajectory: its common pairs across the laps show 0.3 m.
  EXPECT_NEAR(reported(doc, "odometry", "common", "translation_m", "p95"), kInjectedM, 0.04);
  EXPECT_GT(reported(doc, "odometry", "common", "translation_m", "mean"), 0.1);
  EXPECT_GE(reported(doc, "odometry", "own", "translation_m", "median"), 0.0);
  for (const char* name : {"truth", "odometry"}) {
    const std::string png = figures + "/" + name + ".png";
    std::error_code ec;
    EXPECT_GT(std::filesystem::file_size(png, ec), 2000u) << png;
  }
  EXPECT_NE(run.err.find("pair matches"), std::string::npos) << run.err;
}

TEST_F(SlamCheckFiles, BadInputIsAClearErrorWithExitStatus2) {
  const std::string log = write("box.log", carmen_text());
  std::vector<nav::Pose2D> short_poses = truth_poses();
  short_poses.pop_back();
  const std::string short_file = write("short.txt", poses_text(short_poses));
  const std::string broken = write("broken.txt", "0 0 0 0\n1 0 0 0\n2 0 0\n");
  struct Case {
    std::vector<std::string> args;
    std::string says;
  };
  const std::vector<Case> cases = {
      {{}, "--carmen LOG is required"},
      {{"--carmen", log}, "nothing to check"},
      {{"--carmen", dir_ + "/none.log", "--odometry"}, "none.log"},
      {{"--carmen", log, "--poses", "a=" + dir_ + "/none.txt"}, "none.txt: cannot open"},
      {{"--carmen", log, "--poses", "a=" + dir_}, dir_ + ": is a directory"},
      {{"--carmen", log, "--poses", "a=" + broken}, "broken.txt:3: expected 'index x y theta', got 3 fields"},
      {{"--carmen", log, "--poses", "a=" + short_file}, "holds 59 poses, " + log + " holds 60 scans"},
      {{"--carmen", log, "--poses", "nofile"}, "--poses: expected NAME=FILE"},
      {{"--carmen", log, "--poses", "a=" + short_file, "--poses", "a=" + short_file}, "two trajectories named 'a'"},
      {{"--carmen", log, "--odometry", "--min-gap", "0"}, "--min-gap: expected"},
      {{"--carmen", log, "--odometry", "--max-distance", "-1"}, "--max-distance: expected"},
      {{"--carmen", log, "--odometry", "--fast"}, "unknown or incomplete option '--fast'"},
      {{"--carmen", log, "--odometry", "--figure", "/dev/null"}, "--figure"},
  };
  for (const Case& c : cases) {
    const sen3bot::testing::CommandOutcome run = sen3bot::testing::run_command(slam_check_command, c.args);
    std::string line;
    for (const std::string& a : c.args) line += a + " ";
    EXPECT_EQ(run.code, 2) << line;
    EXPECT_NE(run.err.find(c.says), std::string::npos) << line << "\n" << run.err;
    EXPECT_EQ(run.out, "") << line;
  }
}

TEST(SlamCheck, TheSimulatorsHelpListsIt) {
  std::vector<std::string> args{"sen3bot-sim", "--help"};
  const sen3bot::testing::CommandOutcome run = sen3bot::testing::run_command(sim_cli_main, args);
  EXPECT_EQ(run.code, 0);
  EXPECT_NE(run.out.find("slam-check --carmen LOG [--poses NAME=FILE ...] [--odometry] [--figure DIR]"), std::string::npos);
}

}  // namespace
}  // namespace sen3bot::sim::slam_check
