// Simulated workers on the lab map: deterministic per seed, visiting their stations in order,
// recorded as the robot records, and the styles walking differently.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <memory>
#include <numeric>
#include <vector>

#include "sen3bot/sim/cobot/workers.hpp"
#include "sen3bot/geometry/point_math.hpp"

namespace sen3bot::cobot {
namespace {

class Workers : public ::testing::Test {
 protected:
  void SetUp() override {
    Result<OperationsConfig> c = load_operations(SEN3BOT_SOURCE_DIR "/config/cobot/operations.yaml");
    ASSERT_TRUE(c.ok()) << c.error().c_str();
    config_ = std::move(*c);
    Result<nav::OccupancyMap> m = nav::load_map(config_.map_path);
    ASSERT_TRUE(m.ok()) << m.error().c_str();
    map_ = std::make_unique<nav::OccupancyMap>(std::move(*m));
    Result<std::unique_ptr<WorkerSimulator>> w = WorkerSimulator::create(config_, *map_);
    ASSERT_TRUE(w.ok()) << w.error().c_str();
    workers_ = std::move(*w);
  }

  WorkerWalk walk(std::size_t op, const WorkerStyle& style, std::uint64_t seed, Observer observer = {}) {
    Result<WorkerWalk> w = workers_->walk(op, style, observer, seed);
    EXPECT_TRUE(w.ok()) << w.error().c_str();
    return w.ok() ? std::move(*w) : WorkerWalk{};
  }

  OperationsConfig config_;
  std::unique_ptr<nav::OccupancyMap> map_;
  std::unique_ptr<WorkerSimulator> workers_;
};


std::vector<WorkerStyle> all_styles() {
  std::vector<WorkerStyle> styles(training_styles().begin(), training_styles().end());
  styles.push_back(held_out_style());
  return styles;
}

TEST_F(Workers, SameSeedSameWalk) {
  const WorkerWalk a = walk(0, training_styles()[2], 42), b = walk(0, training_styles()[2], 42);
  ASSERT_GT(a.points(), 10u);
  EXPECT_EQ(a.xy, b.xy);
  EXPECT_EQ(a.duration_s, b.duration_s);
  const WorkerWalk c = walk(0, training_styles()[2], 43);
  EXPECT_NE(a.xy, c.xy);
}

TEST_F(Workers, VisitStationsInOrder) {
  for (const WorkerStyle& style : all_styles()) {
    for (std::size_t op = 0; op < config_.operations.size(); ++op) {
      const std::vector<std::size_t>& stations = config_.operations[op].stations;
      for (std::uint64_t seed = 1; seed <= 3; ++seed) {
        const WorkerWalk w = walk(op, style, seed);
        SCOPED_TRACE(style.name + " " + config_.operations[op].name + " seed " + std::to_string(seed));
        // The body reaches each station's radius, in the operation's order.
        ASSERT_EQ(w.arrivals.size(), stations.size());
        EXPECT_TRUE(std::is_sorted(w.arrivals.begin(), w.arrivals.end()));
        // So does the recorded path (its points are on the body's surface, up to 0.2 m off).
        std::size_t from = 0;
        for (const std::size_t s : stations) {
          const Workstation& st = config_.stations[s];
          std::size_t i = from;
          while (i < w.points() && geometry::distance({w.xy[2 * i], w.xy[2 * i + 1]}, st.position) > st.radius_m + 0.3) ++i;
          EXPECT_LT(i, w.points()) << "never near " << st.name;
          from = i;
        }
        // The recorder's spacing, points on the map, the body where a body fits.
        for (std::size_t i = 1; i < w.points(); ++i)
          EXPECT_GT(geometry::distance({w.xy[2 * i - 2], w.xy[2 * i - 1]}, {w.xy[2 * i], w.xy[2 * i + 1]}), 0.0499);
        for (std::size_t i = 0; i < w.points(); ++i) {
          EXPECT_TRUE(w.xy[2 * i] > 0.0f && w.xy[2 * i] < 8.0f && w.xy[2 * i + 1] > 0.0f && w.xy[2 * i + 1] < 9.5f);
        }
        for (const msg::Point2D& b : w.body) EXPECT_TRUE(workers_->standable(b));
        EXPECT_EQ(w.halvings, 0u);
      }
    }
  }
}

TEST_F(Workers, StylesWalkDifferently) {
  // Over the same operations and seeds: the hesitant worker takes longest, the rushed one (the
  // held-out style) walks fastest; the relaxed one sways most.
  auto mean_over = [&](const WorkerStyle& style, auto measure) {
    double total = 0;
    int n = 0;
    for (std::size_t op = 0; op < config_.operations.size(); ++op)
      for (std::uint64_t seed = 10; seed < 14; ++seed, ++n) total += measure(walk(op, style, seed));
    return total / n;
  };
  auto duration = [](const WorkerWalk& w) { return w.duration_s; };
  // Walking speed: the body's median speed over the scans where it walks (faster than
  // 0.75 m/s: not a worker shifting about at a station).
  auto speed = [](const WorkerWalk& w) {
    std::vector<double> steps;
    for (std::size_t i = 1; i < w.body.size(); ++i) {
      const double d = std::hypot(w.body[i].x_m - w.body[i - 1].x_m, w.body[i].y_m - w.body[i - 1].y_m);
      if (d > 0.15) steps.push_back(d * 5.0);  // 5 Hz scans
    }
    if (steps.empty()) return 0.0;
    std::nth_element(steps.begin(), steps.begin() + static_cast<std::ptrdiff_t>(steps.size() / 2), steps.end());
    return steps[steps.size() / 2];
  };
  const WorkerStyle& direct = *find_style("direct");
  const WorkerStyle& hesitant = *find_style("hesitant");
  const WorkerStyle& rushed = held_out_style();
  EXPECT_GT(mean_over(hesitant, duration), 1.5 * mean_over(direct, duration));
  EXPECT_GT(mean_over(rushed, speed), mean_over(direct, speed) + 0.1);
  EXPECT_GT(mean_over(direct, speed), mean_over(hesitant, speed) + 0.2);
  // Sway: the body's sideways wander from one scan to the next while walking.
  auto wobble = [](const WorkerWalk& w) {
    double turn = 0;
    for (std::size_t i = 2; i < w.body.size(); ++i) {
      const double ax = w.body[i - 1].x_m - w.body[i - 2].x_m, ay = w.body[i - 1].y_m - w.body[i - 2].y_m;
      const double bx = w.body[i].x_m - w.body[i - 1].x_m, by = w.body[i].y_m - w.body[i - 1].y_m;
      if (std::hypot(ax, ay) > 0.1 && std::hypot(bx, by) > 0.1) turn += std::fabs(std::atan2(ax * by - ay * bx, ax * bx + ay * by));
    }
    return turn;
  };
  EXPECT_GT(mean_over(*find_style("relaxed"), wobble), 1.5 * mean_over(direct, wobble));
  // The held-out style is none of the training ones.
  for (const WorkerStyle& s : training_styles()) EXPECT_NE(s.name, rushed.name);
  EXPECT_EQ(find_style("nobody"), nullptr);
}

TEST_F(Workers, WallsHideTheWorker) {
  // restock stays in the upper room: a robot standing in the lower room sees little of it.
  const std::size_t restock = static_cast<std::size_t>(config_.find_operation("restock"));
  Observer fixed;
  fixed.mode = ObserverMode::fixed;
  fixed.position = {6.0, 0.6};
  std::size_t seen_fixed = 0, seen_following = 0;
  for (std::uint64_t seed = 1; seed <= 4; ++seed) {
    seen_fixed += walk(restock, training_styles()[0], seed, fixed).points();
    seen_following += walk(restock, training_styles()[0], seed).points();
  }
  EXPECT_LT(seen_fixed * 4, seen_following);
}

TEST_F(Workers, ReferenceRoutes) {
  for (std::size_t op = 0; op < config_.operations.size(); ++op) {
    Result<std::vector<msg::Point2D>> route = workers_->reference_route(op);
    ASSERT_TRUE(route.ok()) << route.error().c_str();
    const Operation& o = config_.operations[op];
    EXPECT_LT(geometry::distance(route->front(), config_.stations[o.stations.front()].position), 1e-6);
    EXPECT_LT(geometry::distance(route->back(), config_.stations[o.stations.back()].position), 1e-6);
    for (std::size_t i = 1; i < route->size(); ++i) EXPECT_LE(geometry::distance((*route)[i - 1], (*route)[i]), 0.25 + 1e-6);
    for (const msg::Point2D& p : *route) EXPECT_TRUE(workers_->standable(p));
    // The shipped file carries these routes (tools/train_operations.sh writes them).
    ASSERT_EQ(o.reference.size(), route->size()) << o.name;
    for (std::size_t i = 0; i < route->size(); ++i) EXPECT_LT(geometry::distance(o.reference[i], (*route)[i]), 0.0075) << o.name;  // written to the cm
  }
}

TEST_F(Workers, DatasetsAreLabelledAndSeparate) {
  DatasetSpec spec;
  spec.styles = training_styles();
  spec.per_operation = 3;
  Result<std::vector<LabelledPath>> train = generate_paths(*workers_, spec);
  spec.purpose = kTestSeeds;
  Result<std::vector<LabelledPath>> test = generate_paths(*workers_, spec);
  ASSERT_TRUE(train.ok() && test.ok());
  ASSERT_EQ(train->size(), 3 * config_.operations.size());
  for (std::size_t i = 0; i < train->size(); ++i) {
    EXPECT_EQ((*train)[i].operation, i / 3);
    EXPECT_NE((*train)[i].xy, (*test)[i].xy);
  }
  EXPECT_NE(worker_seed(1, kTrainingSeeds, 0, 0), worker_seed(1, kTestSeeds, 0, 0));
  EXPECT_NE(worker_seed(1, kTrainingSeeds, 0, 1), worker_seed(1, kTrainingSeeds, 1, 0));
}

}  // namespace
}  // namespace sen3bot::cobot
