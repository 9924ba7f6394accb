// Maps whose origin has a yaw (ROS map YAML `origin: [x, y, yaw]`): the lab map, loaded once as
// shipped and once as a copy whose grid is rotated by kYaw about a moved origin, must give the
// same global plans, the same local costmaps (static, obstacle and inflation layers) and the
// same localization, once every map-frame point is carried by that rigid transform.
#include <gtest/gtest.h>

#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "sen3bot/mem/budget_arena.hpp"
#include "sen3bot/nav/costmap.hpp"
#include "sen3bot/nav/global_planner.hpp"
#include "sen3bot/nav/localization.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/world/world.hpp"

namespace sen3bot::nav {
namespace {

constexpr double kYaw = 0.6;  // rad
constexpr double kOriginX = 3.0;
constexpr double kOriginY = -1.5;

// The shipped map's frame to the rotated copy's (the shipped origin is (0, 0, 0)).
Point2D carry(Point2D p) {
  return {kOriginX + std::cos(kYaw) * p.x_m - std::sin(kYaw) * p.y_m, kOriginY + std::sin(kYaw) * p.x_m + std::cos(kYaw) * p.y_m};
}
Pose2D carry(const Pose2D& p) {
  const Point2D q = carry(Point2D{p.x_m, p.y_m});
  return {q.x_m, q.y_m, normalize_angle(p.theta_rad + kYaw)};
}

struct Maps {
  OccupancyMap lab;
  OccupancyMap rotated;
};

// The rotated copy: a YAML of its own next to nothing but naming the shipped PGM.
Maps load_maps() {
  Result<OccupancyMap> lab = load_map(SEN3BOT_SOURCE_DIR "/config/maps/lab.yaml");
  EXPECT_TRUE(lab.ok());
  char dir[] = "/tmp/sen3bot-rotated-XXXXXX";
  EXPECT_NE(::mkdtemp(dir), nullptr);
  const std::string yaml = std::string(dir) + "/lab_rotated.yaml";
  {
    std::ofstream out(yaml);
    out << "image: " SEN3BOT_SOURCE_DIR "/config/maps/lab.pgm\nresolution: 0.05\norigin: [" << kOriginX << ", " << kOriginY
        << ", " << kYaw << "]\nnegate: 0\noccupied_thresh: 0.65\nfree_thresh: 0.196\nmode: trinary\n";
  }
  Result<OccupancyMap> rotated = load_map(yaml);
  EXPECT_TRUE(rotated.ok()) << (rotated.ok() ? "" : rotated.error().c_str());
  return {std::move(*lab), std::move(*rotated)};
}

TEST(RotatedMap, GlobalPlansAreTheSameCells) {
  const Maps maps = load_maps();
  // Cell centres: a point on a cell edge may land either side once rotated by rounding.
  const std::vector<std::pair<Point2D, Point2D>> queries = {{{4.025, 7.025}, {2.525, 2.025}},
                                                            {{2.525, 2.025}, {4.025, 7.025}},
                                                            {{5.025, 3.525}, {4.525, 8.825}},
                                                            {{6.525, 1.025}, {1.025, 5.325}}};
  for (const auto& [start, goal] : queries) {
    std::vector<GridCell> paths[2];
    PlanResult results[2];
    int k = 0;
    for (const OccupancyMap* map : {&maps.lab, &maps.rotated}) {
      mem::BudgetArena arena("plan", 4 << 20);
      StaticLayer static_layer(*map);
      InflationLayer inflation;
      LayeredCostmap costmap;
      ASSERT_TRUE(costmap.add_layer(static_layer));
      ASSERT_TRUE(costmap.add_layer(inflation));
      ASSERT_TRUE(costmap.init_over_map(*map, arena));
      costmap.update({});
      GlobalPlanner planner;
      GlobalPlannerConfig cfg;
      ASSERT_TRUE(planner.init(cfg, arena));
      paths[k].resize(costmap.costmap().size());
      const bool rotated = map == &maps.rotated;
      results[k] = planner.plan_world(costmap.costmap(), rotated ? carry(start) : start, rotated ? carry(goal) : goal, {}, paths[k]);
      paths[k].resize(results[k].cells);
      // The path's cell centres, carried back, are where the shipped map's are.
      if (rotated) {
        for (std::size_t i = 0; i < paths[k].size() && i < paths[0].size(); ++i) {
          double x0 = 0, y0 = 0, x1 = 0, y1 = 0;
          maps.lab.geometry().cell_to_world(paths[0][i].col, paths[0][i].row, x0, y0);
          costmap.costmap().cell_to_world(paths[1][i].col, paths[1][i].row, x1, y1);
          const Point2D expected = carry(Point2D{x0, y0});
          ASSERT_NEAR(x1, expected.x_m, 1e-9);
          ASSERT_NEAR(y1, expected.y_m, 1e-9);
        }
      }
      ++k;
    }
    ASSERT_TRUE(results[0].ok()) << to_string(results[0].status) << " from (" << start.x_m << ", " << start.y_m << ")";
    ASSERT_TRUE(results[1].ok());
    EXPECT_EQ(paths[0], paths[1]);
    EXPECT_DOUBLE_EQ(results[0].length_m, results[1].length_m);
    EXPECT_EQ(results[0].expansions, results[1].expansions);
  }
}

TEST(RotatedMap, RollingCostmapWithAScanIsTheSameCells) {
  const Maps maps = load_maps();
  // A scan from the shipped world at a pose, with a box the map lacks.
  world::World truth(maps.lab, world::WorldConfig{});
  world::MoverScript box;
  box.path = {{3.3, 5.8}};
  box.size_m = 0.4;
  box.shape = world::MoverShape::square;
  truth.add_mover(box);
  truth.set_time(0.0);
  const SensorMount mount{0.16, 0.0, 0.0};
  ScanMessage msg;
  msg.count = 361;
  msg.angle_min_rad = static_cast<float>(-M_PI / 2.0);
  msg.increment_rad = static_cast<float>(M_PI / 360.0);
  msg.range_max_m = 8.0f;
  std::vector<std::uint8_t> cells[2];
  // Poses along the way, so the window moves (and shifts its marks) between updates.
  const std::vector<Pose2D> poses = {{3.0, 4.2, 1.4}, {3.1, 4.6, 1.3}, {3.2, 5.1, 1.5}, {3.6, 4.9, 0.7}};
  int k = 0;
  for (const OccupancyMap* map : {&maps.lab, &maps.rotated}) {
    const bool rotated = map == &maps.rotated;
    mem::BudgetArena arena("local", 2 << 20);
    StaticLayer static_layer(*map);
    ObstacleLayer obstacles;
    InflationLayer inflation;
    LayeredCostmap costmap;
    ASSERT_TRUE(costmap.add_layer(static_layer));
    ASSERT_TRUE(costmap.add_layer(obstacles));
    ASSERT_TRUE(costmap.add_layer(inflation));
    CostmapConfig cfg;
    cfg.rolling = true;
    cfg.lattice_x_m = map->origin_x_m();
    cfg.lattice_y_m = map->origin_y_m();
    cfg.yaw_rad = map->origin_yaw_rad();
    ASSERT_TRUE(costmap.init(cfg, arena));
    for (const Pose2D& pose : poses) {
      truth.scan(compose(pose, mount), msg.angle_min_rad, msg.increment_rad, msg.count, msg.range_max_m,
                 std::span<float>(msg.ranges_m.data(), msg.count));
      ProjectedScan scan;
      scan.assign(msg.view(), mount);
      const Pose2D at = rotated ? carry(pose) : pose;
      costmap.update({at, at, &scan});
    }
    const auto view = costmap.costmap().cells();
    cells[k++].assign(view.begin(), view.end());
  }
  std::size_t lethal = 0;
  for (const std::uint8_t c : cells[0]) lethal += c == kLethalCost ? 1 : 0;
  EXPECT_GT(lethal, 100u);
  EXPECT_EQ(cells[0], cells[1]);
}

// Tracks a short drive with scans ray-cast in each map's own world: the rotated run's errors
// equal the shipped run's.
TEST(RotatedMap, LocalizesTheSame) {
  const Maps maps = load_maps();
  double rms[2] = {0, 0};
  int k = 0;
  for (const OccupancyMap* map : {&maps.lab, &maps.rotated}) {
    const bool rotated = map == &maps.rotated;
    world::WorldConfig wc;
    wc.range_noise_sigma_m = 0.01;
    wc.seed = 5;
    world::World truth(*map, wc);
    MclConfig cfg;
    cfg.initial_pose = rotated ? carry(Pose2D{2.5, 1.0, M_PI / 2}) : Pose2D{2.5, 1.0, M_PI / 2};
    cfg.initial_std_xy_m = 0.1;
    cfg.initial_std_theta_rad = 0.05;
    cfg.update_min_d_m = 0.1;
    cfg.update_min_a_rad = 0.1;
    mem::BudgetArena arena("mcl", MonteCarloLocalization::storage_bytes(cfg, *map));
    MonteCarloLocalization mcl;
    ASSERT_TRUE(mcl.init(cfg, *map, arena));
    ScanMessage msg;
    msg.count = 361;
    msg.angle_min_rad = static_cast<float>(-M_PI / 2.0);
    msg.increment_rad = static_cast<float>(M_PI / 360.0);
    msg.range_max_m = 8.0f;
    double sum = 0;
    int n = 0;
    // Up the lower work area, odometry exact and in its own frame (starts at zero).
    for (int step = 0; step <= 60; ++step) {
      const Pose2D lab_pose{2.5, 1.0 + 0.05 * step, M_PI / 2};
      const Pose2D pose = rotated ? carry(lab_pose) : lab_pose;
      truth.noisy_scan(pose, msg.angle_min_rad, msg.increment_rad, msg.count, msg.range_max_m,
                       std::span<float>(msg.ranges_m.data(), msg.count));
      ProjectedScan scan;
      scan.assign(msg.view(), SensorMount{});
      const Odometry odom{0.05 * step, 0.0, 0.0, 0.5, 0.0, step * 100'000'000LL, true};
      if (mcl.update(odom, &scan) && step > 10) {
        const PoseEstimate e = mcl.estimate();
        const double err = std::hypot(e.pose.x_m - pose.x_m, e.pose.y_m - pose.y_m);
        sum += err * err;
        ++n;
      }
    }
    ASSERT_GT(n, 10);
    rms[k++] = std::sqrt(sum / n);
  }
  std::printf("localization RMS: shipped map %.4f m, rotated copy %.4f m\n", rms[0], rms[1]);
  EXPECT_LT(rms[0], 0.05);
  EXPECT_LT(rms[1], 0.05);
  EXPECT_NEAR(rms[0], rms[1], 0.01);
}

}  // namespace
}  // namespace sen3bot::nav
