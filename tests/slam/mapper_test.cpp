// The SLAM core on synthetic worlds: a submap's cells, scan matching, the loop-closure search
// (and its refusal on a corridor), and the whole mapper round a loop with drifting odometry.
#include <gtest/gtest.h>

#include <cmath>
#include <filesystem>
#include <memory_resource>
#include <numbers>
#include <random>
#include <vector>

#include "sen3bot/nav/map.hpp"
#include "sen3bot/slam/branch_bound.hpp"
#include "sen3bot/slam/grid.hpp"
#include "sen3bot/slam/mapper.hpp"
#include "sen3bot/slam/scan_matcher.hpp"
#include "synthetic_world.hpp"

namespace sen3bot::slam {
namespace {

using test::World;

constexpr double kOneDegree = std::numbers::pi / 180.0;

// A room with a few things in it that make every pose look different.
World furnished_room() {
  World w;
  w.box(-4.0, -3.0, 6.0, 4.0);
  w.walls.push_back({1.0, 4.0, 1.0, 2.5});  // a partition
  w.walls.push_back({-4.0, 1.0, -2.5, 1.0});
  w.box(3.0, -1.5, 3.8, -0.7);  // a cabinet
  w.posts.push_back({-1.5, -2.0, 0.2});
  return w.shifted(0.013, 0.021);
}

struct GridRig {
  std::vector<std::byte> memory = std::vector<std::byte>(BuildGrid::bytes_for(400) + 4096);
  std::pmr::monotonic_buffer_resource arena{memory.data(), memory.size(), std::pmr::null_memory_resource()};
  BuildGrid grid;
  GridRig() { EXPECT_TRUE(grid.init(arena, 400, 0.05, {})); }

  void insert(const World& w, const nav::Pose2D& at, int times = 1) {
    const LaserRecord r = w.scan(at, at);
    std::vector<PointF> hits;
    for (const PointF& p : test::returns(r)) {
      const double c = std::cos(at.theta_rad);
      const double s = std::sin(at.theta_rad);
      hits.push_back({static_cast<float>(at.x_m + c * p.x - s * p.y), static_cast<float>(at.y_m + s * p.x + c * p.y)});
    }
    for (int i = 0; i < times; ++i)
      grid.insert({static_cast<float>(at.x_m), static_cast<float>(at.y_m)}, hits);
  }
};

TEST(SubmapGrid, AHitRaisesItsCellAndTheRayBeforeItIsLowered) {
  GridRig rig;
  const std::vector<PointF> hit = {{1.02F, 0.02F}};
  rig.grid.insert({0.02F, 0.02F}, hit);
  const ProbabilityView v = rig.grid.view();
  const InsertionConfig odds;
  // The grid is centred on the frame's origin: cell 200 starts at x = 0.
  EXPECT_EQ(v.byte(220, 200), probability_byte(odds.hit_probability));  // the hit, at x in [1.00, 1.05)
  for (int c = 200; c < 220; ++c) EXPECT_EQ(v.byte(c, 200), probability_byte(odds.miss_probability)) << c;
  EXPECT_EQ(v.byte(221, 200), 0) << "behind the hit is unknown";
  EXPECT_EQ(v.byte(210, 201), 0) << "beside the ray is unknown";
  // Once per scan: a second hit in the same cell does not count twice.
  const std::vector<PointF> twice = {{1.02F, 0.02F}, {1.03F, 0.03F}};
  rig.grid.insert({0.02F, 0.02F}, twice);
  const double p2 = 1.0 / (1.0 + std::exp(-2.0 * std::log(odds.hit_probability / (1.0 - odds.hit_probability))));
  EXPECT_EQ(v.byte(220, 200), probability_byte(p2));
  const BuildGrid::Bounds b = rig.grid.known_bounds();
  EXPECT_EQ(b.min_col, 200);
  EXPECT_EQ(b.max_col, 220);
  EXPECT_EQ(b.min_row, 200);
  EXPECT_EQ(b.max_row, 200);
  // A wall cell just before a later hit keeps its evidence (a grazing ray does not thin it);
  // farther back along the ray it is lowered like any other.
  const std::vector<PointF> beyond = {{1.17F, 0.02F}};
  rig.grid.insert({0.02F, 0.02F}, beyond);
  EXPECT_EQ(v.byte(220, 200), probability_byte(p2));
  rig.grid.insert({0.02F, 0.02F}, std::vector<PointF>{{1.52F, 0.02F}});
  EXPECT_LT(v.byte(220, 200), probability_byte(p2));
}

TEST(SubmapGrid, AFrozenSubmapKeepsOnlyItsKnownCells) {
  GridRig rig;
  rig.insert(furnished_room(), {0.0, 0.0, 0.0}, 3);
  std::vector<std::byte> memory(1 << 20);
  std::pmr::monotonic_buffer_resource arena(memory.data(), memory.size(), std::pmr::null_memory_resource());
  const Result<ProbabilityView> frozen = freeze(rig.grid, arena);
  ASSERT_TRUE(frozen);
  EXPECT_LT(frozen->width, 230);  // the room is 10 m x 7 m
  EXPECT_LT(frozen->height, 160);
  const ProbabilityView full = rig.grid.view();
  // The same bytes at the same places of the submap frame.
  for (double x = -3.8873; x < 5.9; x += 0.3711)
    for (double y = -2.8817; y < 3.9; y += 0.4123)
      EXPECT_EQ(full.byte(static_cast<int>(std::floor(full.grid_x(x))), static_cast<int>(std::floor(full.grid_y(y)))),
                frozen->byte(static_cast<int>(std::floor(frozen->grid_x(x))),
                             static_cast<int>(std::floor(frozen->grid_y(y)))));
}

struct MatchCase {
  nav::Pose2D offset;
  bool people;
};

class ScanMatching : public ::testing::TestWithParam<MatchCase> {};

TEST_P(ScanMatching, RecoversAKnownOffset) {
  const World room = furnished_room();
  GridRig rig;
  for (const nav::Pose2D& at : {nav::Pose2D{0.0, 0.0, 0.0}, nav::Pose2D{0.5, 0.3, 0.3}, nav::Pose2D{-0.5, -0.4, -0.4}})
    rig.insert(room, at, 2);
  World seen = room;
  if (GetParam().people) {  // three people who were not there when the submap was built
    seen.posts.push_back({1.5, 0.5, 0.25});
    seen.posts.push_back({-2.0, 2.0, 0.25});
    seen.posts.push_back({2.2, -2.0, 0.25});
  }
  const nav::Pose2D truth{0.2, 0.1, 0.1};
  const nav::Pose2D prior{truth.x_m - GetParam().offset.x_m, truth.y_m - GetParam().offset.y_m,
                          truth.theta_rad - GetParam().offset.theta_rad};
  const std::vector<PointF> points = test::returns(seen.scan(truth, truth));
  std::vector<std::byte> memory(1 << 20);
  std::pmr::monotonic_buffer_resource arena(memory.data(), memory.size(), std::pmr::null_memory_resource());
  ScanMatcher matcher;
  ASSERT_TRUE(matcher.init(arena, 400, {}));
  const Match m = matcher.match(rig.grid.view(), prior, points);
  // Within less than half a cell of 5 cm, wherever the search started.
  EXPECT_NEAR(m.pose.x_m, truth.x_m, 0.02);
  EXPECT_NEAR(m.pose.y_m, truth.y_m, 0.02);
  EXPECT_NEAR(m.pose.theta_rad, truth.theta_rad, 0.5 * kOneDegree);
  EXPECT_GT(m.score, 0.5);
}

INSTANTIATE_TEST_SUITE_P(Offsets, ScanMatching,
                         ::testing::Values(MatchCase{{0.0, 0.0, 0.0}, false}, MatchCase{{0.1, -0.07, 3 * kOneDegree}, false},
                                           MatchCase{{-0.12, 0.1, -7 * kOneDegree}, false},
                                           MatchCase{{0.1, -0.07, 3 * kOneDegree}, true},
                                           MatchCase{{-0.08, 0.12, 6 * kOneDegree}, true}));

struct LoopRig {
  std::vector<std::byte> memory = std::vector<std::byte>(64u << 20);
  std::pmr::monotonic_buffer_resource arena{memory.data(), memory.size(), std::pmr::null_memory_resource()};
  BranchBound search;
  ProbabilityView submap;

  explicit LoopRig(const World& w, const std::vector<nav::Pose2D>& built_from) {
    GridRig rig;
    for (const nav::Pose2D& at : built_from) rig.insert(w, at, 8);
    const Result<ProbabilityView> frozen = freeze(rig.grid, arena);
    EXPECT_TRUE(frozen);
    submap = *frozen;
    EXPECT_TRUE(search.init(arena, 400, 400, 0.05, {}));
    EXPECT_TRUE(search.prepare(submap));
  }
};

TEST(LoopSearch, EachLevelHoldsTheBestCellOfItsSquare) {
  std::vector<std::uint8_t> cells(37 * 23);
  std::mt19937 rng(4);
  for (std::uint8_t& c : cells) c = static_cast<std::uint8_t>(rng() % 3 == 0 ? 0 : rng() % 256);
  const ProbabilityView grid{cells.data(), 37, 23, 0.05, 0.0, 0.0};
  std::vector<std::byte> memory(4u << 20);
  std::pmr::monotonic_buffer_resource arena(memory.data(), memory.size(), std::pmr::null_memory_resource());
  BranchBound search;
  LoopSearchConfig config;
  config.depth = 4;
  ASSERT_TRUE(search.init(arena, 64, 16, 0.05, config));
  ASSERT_TRUE(search.prepare(grid));
  for (int level = 0; level <= 4; ++level)
    for (int row = -16; row < 23; ++row)
      for (int col = -16; col < 37; ++col) {
        std::uint8_t best = 1;  // unknown reads as the least probable
        for (int r = row; r < row + (1 << level); ++r)
          for (int c = col; c < col + (1 << level); ++c) best = std::max(best, std::max(grid.byte(c, r), std::uint8_t{1}));
        ASSERT_EQ(search.level_byte(level, col, row), best) << level << " " << col << " " << row;
      }
}

TEST(LoopSearch, FindsAScanMetresAndDegreesFromItsGuess) {
  const World room = furnished_room();
  LoopRig rig(room, {{0.0, 0.0, 0.0}, {2.0, 1.0, 1.0}, {-2.0, -1.0, -1.0}});
  const nav::Pose2D truth{1.0, -0.5, 0.6};
  const std::vector<PointF> points = test::returns(room.scan(truth, truth));
  const nav::Pose2D guess{truth.x_m - 2.3, truth.y_m + 1.4, truth.theta_rad - 15 * kOneDegree};
  const std::optional<Match> m = rig.search.search(guess, points, 0.6);
  ASSERT_TRUE(m);
  EXPECT_NEAR(m->pose.x_m, truth.x_m, 0.06);
  EXPECT_NEAR(m->pose.y_m, truth.y_m, 0.06);
  EXPECT_NEAR(m->pose.theta_rad, truth.theta_rad, 1.0 * kOneDegree);
  // Nothing fits that well from a place the scan was not taken at.
  const Exclusion away{m->pose, 0.5, 0.2};
  EXPECT_FALSE(rig.search.search(guess, points, 0.93 * m->score, &away));
  // The branch and bound scored far fewer poses than the window holds.
  EXPECT_LT(rig.search.last_scored(), 200'000u);
}

TEST(LoopSearch, ACorridorWithoutFeaturesFitsInMoreThanOnePlace) {
  World corridor;
  corridor.walls.push_back({-30.0, -1.0, 30.0, -1.0});
  corridor.walls.push_back({-30.0, 1.0, 30.0, 1.0});
  LoopRig rig(corridor, {{-3.0, 0.0, 0.0}, {0.0, 0.0, 0.0}, {3.0, 0.0, 0.0}});
  const nav::Pose2D truth{0.5, 0.0, 0.0};
  const std::vector<PointF> points = test::returns(corridor.scan(truth, truth, 8.0));
  const std::optional<Match> m = rig.search.search({1.5, 0.1, 0.05}, points, 0.6);
  ASSERT_TRUE(m);
  EXPECT_NEAR(m->pose.y_m, 0.0, 0.06);  // across the corridor it is sure
  const Exclusion away{m->pose, 0.5, 0.2};
  EXPECT_TRUE(rig.search.search({1.5, 0.1, 0.05}, points, 0.93 * m->score, &away))
      << "along the corridor another place fits as well";
}

// An office floor: a ring corridor round a block of rooms, with pillars and doorways so that
// places differ. The robot drives the ring twice; its odometry turns 2 degrees a metre too much.
World office() {
  World w;
  w.box(0.0, 0.0, 20.0, 12.0);
  w.box(4.0, 4.0, 16.0, 8.0);
  w.walls.push_back({9.0, 4.0, 9.0, 8.0});
  w.posts.push_back({2.0, 6.0, 0.3});
  w.posts.push_back({18.0, 3.0, 0.2});
  w.posts.push_back({12.0, 10.5, 0.25});
  w.box(6.0, 0.0, 7.0, 0.8);
  w.box(14.0, 11.2, 15.5, 12.0);
  w.walls.push_back({0.0, 9.0, 1.0, 9.0});
  return w;
}

std::vector<nav::Pose2D> ring_drive(int laps) {
  // Off the cell grid by a fraction of a cell: the submaps' cells are laid from the first pose, and
  // walls exactly on cell boundaries would split between two rows of cells.
  const std::vector<std::pair<double, double>> corners = {{2.013, 2.021}, {18.013, 2.021}, {18.013, 10.021}, {2.013, 10.021}};
  std::vector<nav::Pose2D> path;
  for (int lap = 0; lap < laps; ++lap)
    for (std::size_t k = 0; k < corners.size(); ++k) {
      const auto [x0, y0] = corners[k];
      const auto [x1, y1] = corners[(k + 1) % corners.size()];
      const double heading = std::atan2(y1 - y0, x1 - x0);
      const double length = std::hypot(x1 - x0, y1 - y0);
      for (double d = 0.0; d < length - 1e-9; d += 0.25) path.push_back({x0 + d * std::cos(heading), y0 + d * std::sin(heading), heading});
    }
  return path;
}

struct MapperRun {
  std::vector<nav::Pose2D> truth;
  std::vector<nav::Pose2D> solved;
  MapperStats stats;
  std::optional<nav::OccupancyMap> map;
};

MapperRun run_mapper(const World& world, const std::vector<nav::Pose2D>& truth, std::uint64_t seed) {
  const MapperConfig config;
  const double drift = 1.0;
  std::mt19937_64 rng(seed);
  std::normal_distribution<double> noise(0.0, 1.0);
  MapperCapacity capacity;
  capacity.scans = truth.size();
  capacity.finished_submap_bytes = 16u << 20;
  std::vector<std::byte> memory(Mapper::bytes_for(config, capacity));
  std::pmr::monotonic_buffer_resource arena(memory.data(), memory.size(), std::pmr::null_memory_resource());
  Mapper mapper;
  EXPECT_TRUE(mapper.init(arena, config, capacity));
  nav::Pose2D odometry = truth.front();
  for (std::size_t i = 0; i < truth.size(); ++i) {
    if (i > 0) {
      nav::Pose2D step = nav::relative_pose(truth[i - 1], truth[i]);
      const double d = std::hypot(step.x_m, step.y_m);
      step.x_m *= 1.0 + drift * 0.02 * noise(rng);
      step.theta_rad += drift * (2.0 * kOneDegree * d + 0.3 * kOneDegree * noise(rng) + (std::abs(step.theta_rad) > 0.1 ? 0.05 * step.theta_rad : 0.0));
      odometry = nav::apply_motion(odometry, step);
    }
    EXPECT_TRUE(mapper.add(world.scan(truth[i], odometry)));
  }
  EXPECT_TRUE(mapper.finish());
  MapperRun run;
  run.truth = truth;
  for (std::size_t i = 0; i < mapper.scan_count(); ++i) run.solved.push_back(mapper.scan_pose(i));
  run.stats = mapper.stats();
  Result<nav::OccupancyMap> map = mapper.render(0.05);
  if (map) run.map = std::move(*map);
  return run;
}

// RMS of the solved poses against the truth, both taken relative to the first pose.
double trajectory_rms(const MapperRun& run) {
  double sum = 0.0;
  for (std::size_t i = 0; i < run.truth.size(); ++i) {
    const nav::Pose2D t = nav::relative_pose(run.truth.front(), run.truth[i]);
    sum += std::pow(t.x_m - run.solved[i].x_m, 2) + std::pow(t.y_m - run.solved[i].y_m, 2);
  }
  return std::sqrt(sum / static_cast<double>(run.truth.size()));
}

TEST(Mapper, ClosesTheLoopOfARingCorridorAndKeepsTheTrajectory) {
  const MapperRun run = run_mapper(office(), ring_drive(2), 7);
  EXPECT_GT(run.stats.loops_accepted, 5u);
  EXPECT_GT(run.stats.submaps, 4u);
  const double rms = trajectory_rms(run);
  std::printf("ring: %zu scans, %zu submaps, %zu loop closures (%zu searched), RMS %.3f m\n", run.stats.scans,
              run.stats.submaps, run.stats.loops_accepted, run.stats.loop_searches, rms);
  EXPECT_LT(rms, 0.05);
}

TEST(Mapper, TheSameDriveGivesTheSamePoses) {
  const std::vector<nav::Pose2D> drive = ring_drive(1);
  const MapperRun a = run_mapper(office(), drive, 3);
  const MapperRun b = run_mapper(office(), drive, 3);
  ASSERT_EQ(a.solved.size(), b.solved.size());
  for (std::size_t i = 0; i < a.solved.size(); ++i) EXPECT_EQ(a.solved[i], b.solved[i]) << i;
}

TEST(Mapper, TheMapItWritesReadsBackThroughTheMapLoader) {
  const MapperRun run = run_mapper(office(), ring_drive(1), 5);
  ASSERT_TRUE(run.map);
  const std::filesystem::path dir = std::filesystem::temp_directory_path() / "sen3bot_mapper_test";
  std::filesystem::create_directories(dir);
  const std::string yaml = (dir / "office.yaml").string();
  ASSERT_TRUE(nav::save_map(*run.map, yaml, "a test map"));
  const Result<nav::OccupancyMap> back = nav::load_map(yaml);
  ASSERT_TRUE(back) << back.error().c_str();
  EXPECT_EQ(back->width(), run.map->width());
  EXPECT_EQ(back->height(), run.map->height());
  EXPECT_NEAR(back->origin_x_m(), run.map->origin_x_m(), 1e-9);
  EXPECT_NEAR(back->origin_y_m(), run.map->origin_y_m(), 1e-9);
  std::size_t walls = 0;
  for (int r = 0; r < back->height(); ++r)
    for (int c = 0; c < back->width(); ++c) {
      const std::int8_t v = run.map->at(c, r);
      const std::int8_t w = back->at(c, r);
      if (v >= 65) {
        EXPECT_EQ(w, nav::kOccupiedOccupancy);
        ++walls;
      } else if (v >= 0 && v <= 19) {
        EXPECT_EQ(w, 0);
      } else {
        EXPECT_EQ(w, nav::kUnknownOccupancy);
      }
    }
  EXPECT_GT(walls, 500u);
  std::filesystem::remove_all(dir);
}

}  // namespace
}  // namespace sen3bot::slam
