#include "sen3bot/nav/dynamic_obstacles.hpp"

#include <gtest/gtest.h>

#include <array>

#include <algorithm>
#include <cstdio>
#include <cstdlib>
#include <cmath>
#include <memory_resource>
#include <numeric>
#include <random>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/mem/budget_arena.hpp"
#include "sen3bot/world/world.hpp"

namespace sen3bot::nav {
namespace {

constexpr hal::Nanos kScanPeriodNs = 100'000'000;  // 10 Hz laser
constexpr hal::Nanos kCostmapTickNs = 50'000'000;         // 20 Hz costmap updates

// --- Running averages ---------------------------------------------------------------------

// The equation as written, in double, neighbours off the grid counted as the cell itself.
struct ReferenceAverages {
  int width = 0;
  int height = 0;
  std::vector<double> fast;
  std::vector<double> slow;

  void step(const std::vector<std::uint8_t>& image, const DolDetectorConfig& cfg) {
    if (fast.empty()) {  // fresh cells take the first image
      fast.assign(image.begin(), image.end());
      slow = fast;
      return;
    }
    run(fast, image, cfg.alpha_fast, cfg.beta);
    run(slow, image, cfg.alpha_slow, cfg.beta);
  }

  void run(std::vector<double>& p, const std::vector<std::uint8_t>& image, double alpha, double beta) const {
    std::vector<double> next(p.size());
    for (int r = 0; r < height; ++r) {
      for (int c = 0; c < width; ++c) {
        const std::size_t i = static_cast<std::size_t>(r * width + c);
        double sum = 0.0;
        for (int dr = -1; dr <= 1; ++dr) {
          for (int dc = -1; dc <= 1; ++dc) {
            if (dr == 0 && dc == 0) continue;
            const int nc = c + dc;
            const int nr = r + dr;
            const bool inside = nc >= 0 && nr >= 0 && nc < width && nr < height;
            sum += inside ? p[static_cast<std::size_t>(nr * width + nc)] : p[i];
          }
        }
        next[i] = beta * ((1.0 - alpha) * p[i] + alpha * image[i]) + (1.0 - beta) / 8.0 * sum;
      }
    }
    p = next;
  }
};

TEST(DynamicBackground, RunningAveragesMatchTheEquation) {
  std::mt19937 rng(11);
  for (const auto& [w, h] : {std::pair{17, 11}, std::pair{40, 33}, std::pair{3, 5}, std::pair{1, 7}, std::pair{120, 120}}) {
    mem::BudgetArena arena("test", 1 << 20);
    DolDetectorConfig cfg;
    cfg.alpha_fast = 0.8;  // not the defaults, so a swapped coefficient shows
    cfg.alpha_slow = 0.25;
    cfg.beta = 0.7;
    BackgroundSubtractor bg;
    ASSERT_TRUE(bg.init(w, h, cfg, arena));
    ReferenceAverages ref{w, h, {}, {}};
    const std::size_t n = static_cast<std::size_t>(w * h);
    std::vector<std::uint8_t> image(n);
    std::vector<std::uint8_t> dynamic(n);
    std::uniform_int_distribution<int> value(0, 255);
    std::bernoulli_distribution lit(0.3);
    for (int step = 0; step < 8; ++step) {
      for (auto& v : image) v = static_cast<std::uint8_t>(step % 2 == 0 ? value(rng) : (lit(rng) ? 255 : 0));
      bg.apply(image, dynamic);
      ref.step(image, cfg);
      for (std::size_t i = 0; i < n; ++i) {
        ASSERT_NEAR(bg.fast(i), ref.fast[i], 1e-3 * std::max(1.0, ref.fast[i])) << w << "x" << h << " step " << step << " cell " << i;
        ASSERT_NEAR(bg.slow(i), ref.slow[i], 1e-3 * std::max(1.0, ref.slow[i])) << w << "x" << h << " step " << step << " cell " << i;
        const double f = ref.fast[i];
        const double d = ref.fast[i] - ref.slow[i];
        if (std::abs(f - cfg.c1) < 0.01 || std::abs(d - cfg.c2) < 0.01) continue;  // too close to call
        ASSERT_EQ(dynamic[i], f > cfg.c1 && d > cfg.c2 ? 1 : 0) << "cell " << i;
      }
    }
  }
}

TEST(DynamicBackground, NewCellsStartAtTheImageAndTheMaskSilencesCells) {
  mem::BudgetArena arena("test", 1 << 20);
  DolDetectorConfig cfg;
  BackgroundSubtractor bg;
  const int w = 10;
  const int h = 8;
  ASSERT_TRUE(bg.init(w, h, cfg, arena));
  std::vector<std::uint8_t> image(80, 0);
  std::vector<std::uint8_t> dynamic(80);
  image[0] = 255;  // present from the start: background, not motion
  bg.apply(image, dynamic);
  EXPECT_EQ(bg.fast(0), 255.0f);
  EXPECT_EQ(bg.slow(0), 255.0f);
  EXPECT_EQ(std::accumulate(dynamic.begin(), dynamic.end(), 0), 0);
  // A cell that lights up later is dynamic at once, unless masked.
  image[3 * w + 4] = 255;
  image[5 * w + 7] = 255;
  std::vector<std::uint8_t> mask(80, 0);
  mask[5 * w + 7] = 1;
  bg.apply(image, dynamic, mask);
  EXPECT_EQ(dynamic[3 * w + 4], 1);
  EXPECT_EQ(dynamic[5 * w + 7], 0);
  EXPECT_EQ(dynamic[0], 0);
  // Shift: content moves by (-2, +1); the cells entering take the next image's value.
  std::vector<float> before(80);
  for (std::size_t i = 0; i < 80; ++i) before[i] = bg.fast(i);
  bg.shift(2, -1);
  for (int r = 0; r < h; ++r) {
    for (int c = 0; c < w; ++c) {
      const int sc = c + 2;
      const int sr = r - 1;
      if (sc >= w || sr < 0) continue;
      ASSERT_EQ(bg.fast(static_cast<std::size_t>(r * w + c)), before[static_cast<std::size_t>(sr * w + sc)]) << c << "," << r;
    }
  }
  std::fill(image.begin(), image.end(), std::uint8_t{0});
  image[0 * w + 9] = 255;  // an entering cell (column 8, 9 and row 0 entered)
  image[7 * w + 9] = 255;
  bg.apply(image, dynamic);
  EXPECT_EQ(bg.fast(9), 255.0f);
  EXPECT_EQ(bg.slow(static_cast<std::size_t>(7 * w + 9)), 255.0f);
  EXPECT_EQ(dynamic[9], 0);
  EXPECT_EQ(dynamic[static_cast<std::size_t>(7 * w + 9)], 0);
}

// --- Blobs ----------------------------------------------------------------------------------

TEST(DynamicBlob, EightConnectedComponentsWithSizeLimits) {
  mem::BudgetArena arena("test", 1 << 20);
  BlobFinder finder;
  const int w = 20;
  const int h = 10;
  ASSERT_TRUE(finder.init(w, h, 8, arena));
  std::vector<std::uint8_t> grid(200, 0);
  const auto on = [&](int c, int r) { grid[static_cast<std::size_t>(r * w + c)] = 1; };
  on(2, 2);  // a diagonal pair: one blob
  on(3, 3);
  for (int c = 10; c < 16; ++c) on(c, 5);  // a line of 6: too large for max 5
  on(18, 9);  // a single cell: too small for min 2
  on(0, 8);   // a 2x2 block in the corner
  on(1, 8);
  on(0, 9);
  on(1, 9);
  const GridGeometry geometry(w, h, 0.1, 1.0, 2.0);
  const auto blobs = finder.find(grid, geometry, 2, 5);
  ASSERT_EQ(blobs.size(), 2u);
  EXPECT_EQ(blobs[0].cells, 2);
  EXPECT_NEAR(blobs[0].x_m, 1.0 + 0.3, 1e-9);  // centres (2.5, 2.5) and (3.5, 3.5) cells
  EXPECT_NEAR(blobs[0].y_m, 2.0 + 0.3, 1e-9);
  EXPECT_NEAR(blobs[0].min_x_m, 1.25, 1e-9);
  EXPECT_NEAR(blobs[0].max_y_m, 2.35, 1e-9);
  EXPECT_NEAR(blobs[0].radius_m, 0.5 * std::hypot(0.1, 0.1) + 0.05, 1e-9);
  EXPECT_EQ(blobs[1].cells, 4);
  EXPECT_NEAR(blobs[1].x_m, 1.1, 1e-9);
  EXPECT_NEAR(blobs[1].y_m, 2.9, 1e-9);
  const auto all = finder.find(grid, geometry, 1, 400);
  EXPECT_EQ(all.size(), 4u);
  // Linked across one empty cell: the diagonal pair and the line stay apart (gap of 6 columns),
  // the corner block and the diagonal pair too; a piece one cell off the line joins it.
  on(17, 5);
  EXPECT_EQ(finder.find(grid, geometry, 1, 400).size(), 5u);
  const auto linked = finder.find(grid, geometry, 1, 400, 2);
  ASSERT_EQ(linked.size(), 4u);
  EXPECT_EQ(linked[1].cells, 7);
}

// --- Hungarian ------------------------------------------------------------------------------

double brute_force(const std::vector<double>& cost, std::size_t rows, std::size_t cols) {
  // Every injective map of the smaller side into the larger.
  const std::size_t n = std::max(rows, cols);
  std::vector<std::size_t> perm(n);
  std::iota(perm.begin(), perm.end(), 0);
  double best = 1e300;
  do {
    double total = 0.0;
    for (std::size_t r = 0; r < n; ++r) {
      const std::size_t c = perm[r];
      if (r < rows && c < cols) total += cost[r * cols + c];
    }
    best = std::min(best, total);
  } while (std::next_permutation(perm.begin(), perm.end()));
  return best;
}

void expect_valid(const std::vector<double>& cost, std::size_t rows, std::size_t cols, const std::vector<int>& row_to_col,
                  double total) {
  std::vector<int> seen(cols, 0);
  double sum = 0.0;
  std::size_t assigned = 0;
  for (std::size_t r = 0; r < rows; ++r) {
    const int c = row_to_col[r];
    if (c == Hungarian::kUnassigned) continue;
    ASSERT_GE(c, 0);
    ASSERT_LT(static_cast<std::size_t>(c), cols);
    ASSERT_EQ(seen[static_cast<std::size_t>(c)]++, 0) << "column used twice";
    sum += cost[r * cols + static_cast<std::size_t>(c)];
    ++assigned;
  }
  EXPECT_EQ(assigned, std::min(rows, cols));
  EXPECT_NEAR(sum, total, 1e-9);
}

TEST(Hungarian, MatchesBruteForceUpTo8x8) {
  mem::BudgetArena arena("test", 1 << 16);
  Hungarian h;
  ASSERT_TRUE(h.init(8, arena));
  std::mt19937 rng(5);
  std::uniform_real_distribution<double> value(0.0, 10.0);
  std::uniform_int_distribution<int> small(0, 3);  // many ties
  for (std::size_t rows = 1; rows <= 8; ++rows) {
    for (std::size_t cols = 1; cols <= 8; ++cols) {
      if (std::max(rows, cols) == 8 && rows != cols) continue;  // 8! per matrix is enough for the square case
      for (int trial = 0; trial < 3; ++trial) {
        std::vector<double> cost(rows * cols);
        for (auto& v : cost) v = trial == 2 ? small(rng) : value(rng);
        std::vector<int> row_to_col(rows);
        const double total = h.solve(cost, rows, cols, row_to_col);
        ASSERT_NEAR(total, brute_force(cost, rows, cols), 1e-9) << rows << "x" << cols << " trial " << trial;
        expect_valid(cost, rows, cols, row_to_col, total);
      }
    }
  }
}

TEST(Hungarian, RectangularBothWays) {
  mem::BudgetArena arena("test", 1 << 16);
  Hungarian h;
  ASSERT_TRUE(h.init(4, arena));
  // 2 rows, 3 columns: row 0 wants column 2, row 1 column 0.
  const std::vector<double> wide = {5, 9, 1, 2, 8, 3};
  std::vector<int> a(2);
  EXPECT_DOUBLE_EQ(h.solve(wide, 2, 3, a), 3.0);
  EXPECT_EQ(a[0], 2);
  EXPECT_EQ(a[1], 0);
  // 3 rows, 2 columns: one row stays unassigned.
  const std::vector<double> tall = {4, 1, 2, 7, 3, 6};
  std::vector<int> b(3);
  EXPECT_DOUBLE_EQ(h.solve(tall, 3, 2, b), 3.0);
  EXPECT_EQ(b[0], 1);
  EXPECT_EQ(b[1], 0);
  EXPECT_EQ(b[2], Hungarian::kUnassigned);
  // Larger than init()'s size: nothing assigned.
  std::vector<double> big(25, 1.0);
  std::vector<int> c(5, 3);
  EXPECT_EQ(h.solve(big, 5, 5, c), 0.0);
  EXPECT_EQ(c[0], Hungarian::kUnassigned);
}

// --- Tracker --------------------------------------------------------------------------------

Blob blob_at(double x, double y, double radius = 0.15) {
  Blob b;
  b.x_m = x;
  b.y_m = y;
  b.cells = 4;
  b.min_x_m = x - 0.05;
  b.max_x_m = x + 0.05;
  b.min_y_m = y - 0.05;
  b.max_y_m = y + 0.05;
  b.radius_m = radius;
  return b;
}

const DolTrack* find_track(const MoverTracker& tracker, std::uint32_t id) {
  for (const DolTrack& t : tracker.tracks())
    if (t.id == id) return &t;
  return nullptr;
}

TEST(MoverTracker, ConfirmsAfterHitsAndTwoPointVelocity) {
  mem::BudgetArena arena("test", 1 << 16);
  MoverTracker tracker;
  DolTrackerConfig cfg;
  cfg.confirm_hits = 3;
  cfg.max_coast_s = 0.6;
  ASSERT_TRUE(tracker.init(cfg, arena));
  const Blob first = blob_at(1.0, 2.0);
  tracker.update(std::span(&first, 1), 0);
  ASSERT_EQ(tracker.tracks().size(), 1u);
  EXPECT_FALSE(tracker.tracks()[0].confirmed);
  const Blob second = blob_at(1.08, 1.94);
  tracker.update(std::span(&second, 1), kScanPeriodNs);
  ASSERT_EQ(tracker.tracks().size(), 1u);
  EXPECT_NEAR(tracker.tracks()[0].kf.x[2], 0.8, 1e-9);  // the displacement over 0.1 s
  EXPECT_NEAR(tracker.tracks()[0].kf.x[3], -0.6, 1e-9);
  EXPECT_FALSE(tracker.tracks()[0].confirmed);
  const Blob third = blob_at(1.16, 1.88);
  tracker.update(std::span(&third, 1), 2 * kScanPeriodNs);
  EXPECT_TRUE(tracker.tracks()[0].confirmed);
  EXPECT_EQ(tracker.tracks()[0].id, 1u);
  const auto p = MoverTracker::predict_position(tracker.tracks()[0], 3 * kScanPeriodNs);
  EXPECT_NEAR(p.x_m, 1.24, 0.01);
  EXPECT_NEAR(p.y_m, 1.82, 0.01);
  // A tentative track that misses once is gone; ids are never reused.
  const Blob elsewhere = blob_at(-3.0, -3.0);
  tracker.update(std::span(&elsewhere, 1), 3 * kScanPeriodNs);
  tracker.update({}, 4 * kScanPeriodNs);
  ASSERT_EQ(tracker.tracks().size(), 1u);
  EXPECT_EQ(tracker.tracks()[0].id, 1u);
  tracker.update(std::span(&elsewhere, 1), 5 * kScanPeriodNs);
  ASSERT_EQ(tracker.tracks().size(), 2u);
  EXPECT_EQ(tracker.tracks()[1].id, 3u);
  // The confirmed one coasts for max_coast_s (last hit at 0.2 s), then dies.
  tracker.update({}, 6 * kScanPeriodNs);
  ASSERT_EQ(tracker.tracks().size(), 1u);
  EXPECT_EQ(tracker.tracks()[0].id, 1u);
  tracker.update({}, 9 * kScanPeriodNs);
  EXPECT_EQ(tracker.tracks().size(), 0u);
}

TEST(MoverTracker, TheCameraVouchesForAWalkerAtTheSecondScanNeverForAStillBox) {
  // A walker at 1 m/s coming into view beside a still box (0.45 m apart, jittering by 3 cm as
  // a box's faces do). The camera places a walking person where the walker is.
  mem::BudgetArena arena("test", 1 << 16);
  MoverTracker tracker;
  DolTrackerConfig cfg;
  cfg.camera_vouches = true;
  ASSERT_TRUE(tracker.init(cfg, arena));
  MoverTracker alone;  // the same scans, nobody vouching
  ASSERT_TRUE(alone.init(cfg, arena));
  int vouched_at = -1;
  for (int k = 0; k < 12; ++k) {
    const double t = static_cast<double>(k) * 0.1;
    const std::array<Blob, 2> blobs = {blob_at(1.0 + t, 2.0), blob_at(1.6 + (k % 2 == 0 ? 0.03 : -0.03), 2.45)};
    tracker.update(blobs, k * kScanPeriodNs);
    alone.update(blobs, k * kScanPeriodNs);
    // The person as fused: a few centimetres off the laser's blob, at their walking speed.
    const std::array<Vouch, 1> person = {Vouch{1.0 + t + 0.05, 2.02, 1.0, 0.0}};
    if (tracker.vouch(person) > 0 && vouched_at < 0) vouched_at = k;
    for (const DolTrack& track : tracker.tracks()) {
      if (track.kf.x[1] > 2.3) {
        EXPECT_FALSE(track.mover) << "the box became a mover at scan " << k;
      }
    }
    for (const DolTrack& track : alone.tracks()) {
      if (k < cfg.confirm_hits - 1) {
        EXPECT_FALSE(track.mover) << "without the camera, not before confirm_hits";
      }
    }
  }
  // Vouched for at its second scan (hits 2, the first with a velocity).
  EXPECT_EQ(vouched_at, 1);
  // A person walking the other way, or much slower, does not vouch; nor one too far off.
  MoverTracker other;
  ASSERT_TRUE(other.init(cfg, arena));
  for (int k = 0; k < 3; ++k) {
    const Blob b = blob_at(1.0 + 0.1 * k, 2.0);
    other.update(std::span(&b, 1), k * kScanPeriodNs);
    const double x = 1.0 + 0.1 * k;
    const std::array<Vouch, 3> no = {Vouch{x, 2.0, -1.0, 0.0}, Vouch{x, 2.0, 0.3, 0.0}, Vouch{x, 2.6, 1.0, 0.0}};
    EXPECT_EQ(other.vouch(no), 0u) << k;
  }
  // Switched off, nobody's word counts.
  cfg.camera_vouches = false;
  MoverTracker off;
  ASSERT_TRUE(off.init(cfg, arena));
  for (int k = 0; k < 3; ++k) {
    const Blob b = blob_at(1.0 + 0.1 * k, 2.0);
    off.update(std::span(&b, 1), k * kScanPeriodNs);
    const std::array<Vouch, 1> person = {Vouch{1.0 + 0.1 * k, 2.0, 1.0, 0.0}};
    EXPECT_EQ(off.vouch(person), 0u);
  }
}

TEST(MoverTracker, GateLeavesFarBlobsUnmatched) {
  mem::BudgetArena arena("test", 1 << 16);
  MoverTracker tracker;
  DolTrackerConfig cfg;  // gate 1 m
  cfg.confirm_hits = 3;
  ASSERT_TRUE(tracker.init(cfg, arena));
  hal::Nanos t = 0;
  for (int i = 0; i < 3; ++i, t += kScanPeriodNs) {
    const Blob b = blob_at(0.0, 0.0);
    tracker.update(std::span(&b, 1), t);
  }
  ASSERT_TRUE(tracker.tracks()[0].confirmed);
  // The only blob is 1.1 m away: not this track's; a new one starts there.
  const Blob far = blob_at(1.1, 0.0);
  tracker.update(std::span(&far, 1), t);
  ASSERT_EQ(tracker.tracks().size(), 2u);
  EXPECT_EQ(tracker.tracks()[0].hits, 3);
  EXPECT_NEAR(tracker.tracks()[0].kf.x[0], 0.0, 1e-6);
  EXPECT_EQ(tracker.tracks()[1].hits, 1);
  const std::uint32_t newcomer = tracker.tracks()[1].id;
  // Tracks at 0 and 1.1; blobs at 0.5 (0.5 and 0.6 away) and -2 (2 and 3.1 away). By plain
  // distance sums the 0.6 pair would win (2 + 0.6 < 0.5 + 3.1) and the first track would be
  // left with the out-of-gate blob; with out-of-gate pairs costing alike, the nearest pair wins.
  t += kScanPeriodNs;
  const Blob two[2] = {blob_at(0.5, 0.0), blob_at(-2.0, 0.0)};
  tracker.update(two, t);
  ASSERT_EQ(tracker.tracks().size(), 2u);
  EXPECT_EQ(tracker.tracks()[0].id, 1u);
  EXPECT_EQ(tracker.tracks()[0].hits, 4);
  EXPECT_GT(tracker.tracks()[0].kf.x[0], 0.2);
  EXPECT_EQ(find_track(tracker, newcomer), nullptr);  // tentative and missed: gone
  EXPECT_NEAR(tracker.tracks()[1].kf.x[0], -2.0, 1e-9);
  EXPECT_EQ(tracker.tracks()[1].hits, 1);
}

TEST(Kalman, VelocityConvergesOnAConstantVelocityTrack) {
  for (unsigned seed = 1; seed <= 5; ++seed) {
    mem::BudgetArena arena("test", 1 << 16);
    MoverTracker tracker;
    DolTrackerConfig cfg;
    // A target that truly keeps its velocity: little process noise (the default 1 m/s² is
    // for people who turn and stop, and trades this accuracy for a quick response).
    cfg.accel_sigma_m_s2 = 0.2;
    ASSERT_TRUE(tracker.init(cfg, arena));
    std::mt19937 rng(seed);
    std::normal_distribution<double> noise(0.0, 0.03);
    const double vx = 0.7;
    const double vy = -0.45;
    for (int k = 0; k <= 40; ++k) {  // 4 s at 10 Hz
      const double t = 0.1 * k;
      const Blob b = blob_at(1.0 + vx * t + noise(rng), 2.0 + vy * t + noise(rng));
      tracker.update(std::span(&b, 1), k * kScanPeriodNs);
    }
    ASSERT_EQ(tracker.tracks().size(), 1u);
    const DolTrack& track = tracker.tracks()[0];
    const double error = std::hypot(track.kf.x[2] - vx, track.kf.x[3] - vy);
    EXPECT_LT(error, 0.05 * std::hypot(vx, vy)) << "seed " << seed << " v " << track.kf.x[2] << "," << track.kf.x[3];
    if (std::getenv("DOL_TRACE") != nullptr) std::printf("seed %u: velocity error %.1f %%\n", seed, 100.0 * error / std::hypot(vx, vy));
  }
}

// Two scripted walkers; true when both keep the id they got (the track nearest each walker
// once confirmed) until the end.
void run_walkers(double ax, double ay, double avx, double avy, double bx, double by, double bvx, double bvy,
                 double seconds) {
  mem::BudgetArena arena("test", 1 << 16);
  MoverTracker tracker;
  DolTrackerConfig cfg;
  ASSERT_TRUE(tracker.init(cfg, arena));
  std::mt19937 rng(3);
  std::normal_distribution<double> noise(0.0, 0.03);
  std::uint32_t id_a = 0;
  std::uint32_t id_b = 0;
  const int steps = static_cast<int>(seconds * 10.0);
  for (int k = 0; k <= steps; ++k) {
    const double t = 0.1 * k;
    const double pa[2] = {ax + avx * t, ay + avy * t};
    const double pb[2] = {bx + bvx * t, by + bvy * t};
    const Blob blobs[2] = {blob_at(pa[0] + noise(rng), pa[1] + noise(rng)), blob_at(pb[0] + noise(rng), pb[1] + noise(rng))};
    // Alternate the order, so the blob index says nothing.
    if (k % 2 == 0) {
      tracker.update(blobs, k * kScanPeriodNs);
    } else {
      const Blob swapped[2] = {blobs[1], blobs[0]};
      tracker.update(swapped, k * kScanPeriodNs);
    }
    ASSERT_LE(tracker.tracks().size(), 2u) << "t=" << t;
    if (k == 3) {
      ASSERT_EQ(tracker.tracks().size(), 2u);
      for (const DolTrack& tr : tracker.tracks()) {
        ASSERT_TRUE(tr.confirmed);
        const double da = std::hypot(tr.kf.x[0] - pa[0], tr.kf.x[1] - pa[1]);
        const double db = std::hypot(tr.kf.x[0] - pb[0], tr.kf.x[1] - pb[1]);
        (da < db ? id_a : id_b) = tr.id;
      }
      ASSERT_NE(id_a, id_b);
    }
    if (k > 3) {
      const DolTrack* a = find_track(tracker, id_a);
      const DolTrack* b = find_track(tracker, id_b);
      ASSERT_NE(a, nullptr) << "t=" << t;
      ASSERT_NE(b, nullptr) << "t=" << t;
      EXPECT_LT(std::hypot(a->kf.x[0] - pa[0], a->kf.x[1] - pa[1]), 0.15) << "walker A swapped at t=" << t;
      EXPECT_LT(std::hypot(b->kf.x[0] - pb[0], b->kf.x[1] - pb[1]), 0.15) << "walker B swapped at t=" << t;
    }
  }
}

TEST(MoverTracker, CrossingWalkersKeepTheirIds) {
  // An X: both reach the origin at t = 2 s, at different speeds.
  run_walkers(-2.0, 0.0, 1.0, 0.0, 0.0, -1.4, 0.0, 0.7, 4.0);
  // Diagonal X at different speeds, meeting at (1, 1) at t = 1.5 s.
  run_walkers(-0.5, -0.5, 1.0, 1.0, 2.2, -0.2, -0.8, 0.8, 3.5);
  // Head-on, passing 0.4 m apart.
  run_walkers(-3.0, 0.2, 1.2, 0.0, 3.0, -0.2, -0.9, 0.0, 5.0);
}

TEST(MoverTracker, TrackSurvivesAnOcclusion) {
  mem::BudgetArena arena("test", 1 << 16);
  MoverTracker tracker;
  DolTrackerConfig cfg;
  ASSERT_TRUE(tracker.init(cfg, arena));
  std::mt19937 rng(9);
  std::normal_distribution<double> noise(0.0, 0.03);
  const auto at = [](double t) { return std::pair{0.5 + 0.8 * t, 1.0 - 0.3 * t}; };
  for (int k = 0; k <= 40; ++k) {
    const double t = 0.1 * k;
    const bool occluded = k >= 20 && k < 25;  // 0.5 s with no blob
    if (occluded) {
      tracker.update({}, k * kScanPeriodNs);
    } else {
      const auto [x, y] = at(t);
      const Blob b = blob_at(x + noise(rng), y + noise(rng));
      tracker.update(std::span(&b, 1), k * kScanPeriodNs);
    }
    ASSERT_EQ(tracker.tracks().size(), 1u) << "t=" << t;
    EXPECT_EQ(tracker.tracks()[0].id, 1u) << "t=" << t;
  }
  const auto [x, y] = at(4.0);
  EXPECT_NEAR(tracker.tracks()[0].kf.x[0], x, 0.1);
  EXPECT_NEAR(tracker.tracks()[0].kf.x[1], y, 0.1);
  EXPECT_TRUE(tracker.tracks()[0].confirmed);
}

// A box going up its lane at x = 2 at 0.8 m/s; for its last 0.5 s in view its centroid slides
// sideways and lags (the laser sees less and less of it at the edge of its field), then it is
// out of view for 1.5 s. Returns how far from its lane the coasting track is then.
double lane_error_after_coasting(const DolTrackerConfig& cfg) {
  mem::BudgetArena arena("test", 1 << 16);
  MoverTracker tracker;
  EXPECT_TRUE(tracker.init(cfg, arena));
  std::mt19937 rng(4);
  std::normal_distribution<double> noise(0.0, 0.02);
  LaserView blind;
  blind.half_angle_rad = 0.1;
  blind.heading_rad = -M_PI / 2.0;  // looking away: the track is out of view and coasts
  int k = 0;
  for (; k <= 30; ++k) {
    const double t = 0.1 * k;
    const double slide = k > 25 ? 0.04 * (k - 25) : 0.0;
    const Blob b = blob_at(2.0 + slide + noise(rng), 0.5 + 0.8 * t - 0.5 * slide + noise(rng));
    tracker.update(std::span(&b, 1), k * kScanPeriodNs);
  }
  if (tracker.tracks().size() != 1u) return 1e9;
  const double x0 = tracker.tracks()[0].kf.x[0];
  EXPECT_NEAR(x0, 2.2, 0.1);  // where the slide left it
  for (; k <= 45; ++k) tracker.update({}, k * kScanPeriodNs, blind);
  EXPECT_EQ(tracker.tracks().size(), 1u);
  if (tracker.tracks().empty()) return 1e9;
  const DolTrack& track = tracker.tracks()[0];
  if (cfg.axis_min_travel_m < 10.0) {
    // On its line, at the speed it kept while seen, not the lagging centroids' slower one.
    EXPECT_NEAR(track.kf.x[1], 0.5 + 0.8 * 4.5, 0.15);
    EXPECT_NEAR(track.kf.x[3], 0.8, 0.08);
  }
  return std::abs(track.kf.x[0] - 2.0);
}

TEST(MoverTracker, TheAxisKeepsACoastingTrackInItsLaneAtItsSpeed) {
  DolTrackerConfig cfg;
  const double held = lane_error_after_coasting(cfg);
  cfg.axis_min_travel_m = 1e9;  // no axis: the filter's velocity as it is
  const double drifting = lane_error_after_coasting(cfg);
  // Held: the fitted line's own small tilt from the slide; free: the slide and its speed.
  EXPECT_LT(held, 0.15);
  EXPECT_GT(drifting, 0.3);
}

TEST(MoverTracker, TheAxisFollowsAWalkerWhoTurns) {
  mem::BudgetArena arena("test", 1 << 16);
  MoverTracker tracker;
  DolTrackerConfig cfg;
  ASSERT_TRUE(tracker.init(cfg, arena));
  std::mt19937 rng(6);
  std::normal_distribution<double> noise(0.0, 0.02);
  // 3 s up at 0.8 m/s, then a right-angle turn and 3 s along +x.
  for (int k = 0; k <= 60; ++k) {
    const double t = 0.1 * k;
    const double x = t <= 3.0 ? 1.0 : 1.0 + 0.8 * (t - 3.0);
    const double y = t <= 3.0 ? 0.8 * t : 2.4;
    const Blob b = blob_at(x + noise(rng), y + noise(rng));
    tracker.update(std::span(&b, 1), k * kScanPeriodNs);
    if (k == 30) {  // held to the axis: straight up
      ASSERT_EQ(tracker.tracks().size(), 1u);
      const auto v = tracker.velocity(tracker.tracks()[0]);
      EXPECT_NEAR(std::atan2(v.y_m, v.x_m), M_PI / 2.0, 0.03);
    }
  }
  ASSERT_EQ(tracker.tracks().size(), 1u);
  const DolTrack& track = tracker.tracks()[0];
  EXPECT_EQ(track.id, 1u);
  const auto v = tracker.velocity(track);
  EXPECT_LT(std::abs(std::atan2(v.y_m, v.x_m)), 5.0 * M_PI / 180.0);
  EXPECT_NEAR(v.x_m, 0.8, 0.1);
}

TEST(MoverTracker, TurnBackReversesTheVelocityOnly) {
  mem::BudgetArena arena("test", 1 << 16);
  MoverTracker tracker;
  DolTrackerConfig cfg;
  ASSERT_TRUE(tracker.init(cfg, arena));
  for (int k = 0; k < 6; ++k) {
    const Blob b = blob_at(1.0, 0.06 * k);
    tracker.update(std::span(&b, 1), k * kScanPeriodNs);
  }
  ASSERT_EQ(tracker.tracks().size(), 1u);
  const DolTrack before = tracker.tracks()[0];
  tracker.turn_back(0);
  tracker.turn_back(7);  // no such track: nothing
  const DolTrack& after = tracker.tracks()[0];
  EXPECT_EQ(after.kf.x[0], before.kf.x[0]);
  EXPECT_EQ(after.kf.x[1], before.kf.x[1]);
  EXPECT_EQ(after.kf.x[2], -before.kf.x[2]);
  EXPECT_EQ(after.kf.x[3], -before.kf.x[3]);
  EXPECT_GT(before.kf.x[3], 0.4);
}

// --- Cost -----------------------------------------------------------------------------------

TEST(MoverGaussian, MatchesTheFormulaAtSamplePoints) {
  DolCostConfig cfg;
  cfg.cutoff = 1.0;
  const double cx = 2.0;
  const double cy = -1.0;
  const double vx = 0.6;
  const double vy = 0.8;  // speed 1, heading atan2(0.8, 0.6)
  const double speed = 1.0;
  const double r = speed / cfg.max_speed_m_s;  // 0.5
  const double plateau = cfg.front_horizon_s * speed;
  const double heading = std::atan2(vy, vx);
  struct Sample {
    double d;
    double angle;  // relative to the heading
  };
  for (const Sample s : {Sample{0.3, 0.2}, Sample{1.5, 0.0}, Sample{1.8, 0.4}, Sample{0.5, 2.5}, Sample{0.4, -1.7},
                         Sample{0.7, M_PI}, Sample{0.6, M_PI / 2 + 0.1}}) {
    const double along = s.d * std::cos(s.angle);
    const double across = s.d * std::sin(s.angle);
    double sx2 = 0.0;
    double sy2 = 0.0;
    double a = along;
    if (along > 0.0) {
      sx2 = (1.0 + r) * cfg.sigma2_front_x_m2;
      sy2 = (1.0 - r / 2.0) * cfg.sigma2_front_y_m2;
      a = std::max(0.0, along - plateau);
    } else {
      sx2 = (1.0 - r) * cfg.sigma2_back_x_m2;
      sy2 = (1.0 - r / 4.0) * cfg.sigma2_back_y_m2;
    }
    const double expected = 252.0 * std::exp(-a * a / (2.0 * sx2) - across * across / (2.0 * sy2));
    const double x = cx + s.d * std::cos(heading + s.angle);
    const double y = cy + s.d * std::sin(heading + s.angle);
    EXPECT_NEAR(mover_cost(cfg, cx, cy, vx, vy, x, y), expected, 1e-9 * expected + 1e-12) << s.d << " " << s.angle;
  }
  // Below the cutoff: 0.
  cfg.cutoff = 30.0;
  EXPECT_EQ(mover_cost(cfg, cx, cy, vx, vy, cx - 0.6 * 3.0, cy - 0.8 * 3.0), 0.0);
  // Amplitude capped at 252.
  cfg.amplitude = 400.0;
  EXPECT_NEAR(mover_cost(cfg, cx, cy, vx, vy, cx, cy), 252.0, 1e-9);
}

TEST(MoverGaussian, FrontFollowsTheVelocityInEveryQuadrant) {
  DolCostConfig cfg;
  cfg.front_horizon_s = 0.0;  // the source's shape: compare the Gaussians themselves
  for (const auto& [vx, vy] : {std::pair{0.8, 0.3}, std::pair{-0.5, 0.6}, std::pair{-0.7, -0.2}, std::pair{0.1, -0.9},
                              std::pair{0.0, 0.5}, std::pair{-0.6, 0.0}}) {
    const double speed = std::hypot(vx, vy);
    for (const double d : {0.3, 0.6, 1.0}) {
      const double ahead = mover_cost(cfg, 1.0, 1.0, vx, vy, 1.0 + vx / speed * d, 1.0 + vy / speed * d);
      const double behind = mover_cost(cfg, 1.0, 1.0, vx, vy, 1.0 - vx / speed * d, 1.0 - vy / speed * d);
      EXPECT_GT(ahead, behind) << vx << "," << vy << " at " << d;
    }
    // Symmetric about the heading.
    const double lx = -vy / speed * 0.4;
    const double ly = vx / speed * 0.4;
    EXPECT_NEAR(mover_cost(cfg, 0.0, 0.0, vx, vy, 0.3 * vx + lx, 0.3 * vy + ly),
                mover_cost(cfg, 0.0, 0.0, vx, vy, 0.3 * vx - lx, 0.3 * vy - ly), 1e-9);
  }
}

TEST(MoverGaussian, PlateauExtendsAheadBySpeedTimesHorizon) {
  DolCostConfig cfg;
  cfg.front_horizon_s = 1.5;
  const double vx = 0.0;
  const double vy = -0.8;  // heading -y: the plateau ends 1.2 m ahead
  for (const double d : {0.0, 0.3, 0.6, 0.9, 1.19}) EXPECT_NEAR(mover_cost(cfg, 0.0, 0.0, vx, vy, 0.0, -d), 252.0, 1e-9) << d;
  EXPECT_LT(mover_cost(cfg, 0.0, 0.0, vx, vy, 0.0, -1.6), 240.0);
  EXPECT_LT(mover_cost(cfg, 0.0, 0.0, vx, vy, 0.0, 0.3), 252.0);  // behind: no plateau
  cfg.front_horizon_s = 0.0;
  EXPECT_LT(mover_cost(cfg, 0.0, 0.0, vx, vy, 0.0, -0.6), 240.0);
}

TEST(MoverGaussian, PaintMatchesTheCostAndNeverLowersACell) {
  mem::BudgetArena arena("test", 1 << 20);
  DolCostConfig cfg;
  for (const double yaw : {0.0, 0.4}) {
    Costmap2D grid;
    ASSERT_TRUE(grid.init(120, 120, 0.05, arena, yaw));
    grid.set_origin(-3.0, -2.0);
    std::mt19937 rng(2);
    std::uniform_int_distribution<int> v(0, 255);
    for (auto& c : grid.cells()) c = static_cast<std::uint8_t>(v(rng) < 200 ? 0 : v(rng));
    const std::vector<std::uint8_t> before(grid.cells().begin(), grid.cells().end());
    const double cx = -0.4;
    const double cy = 1.3;
    const double vx = 0.5;
    const double vy = -0.35;
    paint_mover(cfg, cx, cy, vx, vy, grid);
    int raised = 0;
    for (int r = 0; r < 120; ++r) {
      for (int c = 0; c < 120; ++c) {
        const std::size_t i = grid.index(c, r);
        ASSERT_GE(grid.cells()[i], before[i]) << "lowered " << c << "," << r;
        double x = 0.0;
        double y = 0.0;
        grid.cell_to_world(c, r, x, y);
        const auto expected = static_cast<std::uint8_t>(mover_cost(cfg, cx, cy, vx, vy, x, y));
        ASSERT_NEAR(grid.cells()[i], std::max(before[i], expected), 1) << c << "," << r << " yaw " << yaw;
        if (grid.cells()[i] > before[i]) ++raised;
      }
    }
    EXPECT_GT(raised, 500);
    // Far off the grid (or nonsense): nothing painted, nothing out of bounds.
    const std::vector<std::uint8_t> painted(grid.cells().begin(), grid.cells().end());
    paint_mover(cfg, 1e12, -1e12, 0.5, 0.5, grid);
    paint_mover(cfg, 20.0, 1.0, 0.5, 0.0, grid);
    paint_mover(cfg, std::nan(""), 1.0, 0.5, 0.0, grid);
    EXPECT_TRUE(std::equal(painted.begin(), painted.end(), grid.cells().begin()));
  }
}

// --- The layer in a costmap -------------------------------------------------------------------

struct Rig {
  explicit Rig(const DynamicObstacleConfig& config, double noise_sigma_m = 0.01,
               const char* map_file = SEN3BOT_SOURCE_DIR "/config/maps/lab.yaml", bool as_in_the_firmware = false)
      : map(load(map_file)),
        truth(map, world_config(noise_sigma_m)),
        statics(map),
        dol(config, &map, as_in_the_firmware ? &obstacles : nullptr) {
    scan.count = 361;
    scan.angle_min_rad = static_cast<float>(-M_PI / 2.0);
    scan.increment_rad = static_cast<float>(M_PI / 360.0);
    scan.range_max_m = 8.0f;
  }
  static OccupancyMap load(const char* file) {
    auto m = load_map(file);
    EXPECT_TRUE(m.ok());
    return m.ok() ? std::move(*m) : OccupancyMap(10, 10, 0.05, 0.0, 0.0);
  }
  static world::WorldConfig world_config(double sigma) {
    world::WorldConfig wc;
    wc.range_noise_sigma_m = sigma;
    wc.seed = 5;
    return wc;
  }
  Status init(bool with_dol = true) {
    if (Status s = costmap.add_layer(statics); !s) return s;
    if (Status s = costmap.add_layer(obstacles); !s) return s;
    if (with_dol) {
      if (Status s = costmap.add_layer(dol); !s) return s;
    }
    if (Status s = costmap.add_layer(inflation); !s) return s;
    CostmapConfig cfg;
    cfg.rolling = true;
    cfg.lattice_x_m = map.origin_x_m();
    cfg.lattice_y_m = map.origin_y_m();
    return costmap.init(cfg, arena);
  }
  // One 20 Hz tick: a scan every other tick, taken at the true pose; the costmap is placed
  // at the believed pose.
  void tick(int k, const Pose2D& true_pose, const Pose2D& believed_pose) {
    const hal::Nanos now = k * kCostmapTickNs;
    truth.set_time(static_cast<double>(now) * 1e-9);
    const bool has_scan = k % 2 == 0;
    if (has_scan) {
      truth.noisy_scan(compose(true_pose, mount), scan.angle_min_rad, scan.increment_rad, scan.count, scan.range_max_m,
                       std::span<float>(scan.ranges_m.data(), scan.count));
      scan.stamp_ns = now;
      view.assign(scan.view(), mount);
    }
    costmap.update({believed_pose, believed_pose, has_scan ? &view : nullptr, now});
  }
  [[nodiscard]] int dynamic_count() const {
    const auto d = dol.dynamic_cells();
    return std::accumulate(d.begin(), d.end(), 0);
  }
  [[nodiscard]] int confirmed_count() const {
    int n = 0;
    for (const DolTrack& t : dol.tracks()) n += t.confirmed ? 1 : 0;
    return n;
  }

  OccupancyMap map;
  world::World truth;
  mem::BudgetArena arena{"test", 4 << 20};
  StaticLayer statics;
  ObstacleLayer obstacles;
  DynamicObstacleLayer dol;
  InflationLayer inflation;
  LayeredCostmap costmap;
  SensorMount mount{0.1, 0.0, 0.0};
  ScanMessage scan;
  ProjectedScan view;
};

const DolTrack* find_track_by_id(std::span<const DolTrack> tracks, std::uint32_t id) {
  for (const DolTrack& t : tracks)
    if (t.id == id) return &t;
  return nullptr;
}

const DolTrack* find_confirmed(std::span<const DolTrack> tracks) {
  for (const DolTrack& t : tracks)
    if (t.confirmed) return &t;
  return nullptr;
}

// Drives a circle of 1 m radius at 0.5 m/s in the open upper middle of the lab (x 3..5,
// y 6.2..8.2), between the blocks on either side and the middle wall below.
Pose2D circle_pose(double t) {
  const double w = 0.5;
  return {4.0 + std::sin(w * t), 7.2 - std::cos(w * t), normalize_angle(w * t)};
}

struct DriveOutcome {
  int max_dynamic_after_warmup = 0;
  int max_confirmed_after_warmup = 0;
  int max_dynamic_any = 0;
};

DriveOutcome drive(double mask_radius_m, const Pose2D& pose_error) {
  DynamicObstacleConfig cfg;
  cfg.detector.static_mask_radius_m = mask_radius_m;
  Rig rig(cfg);
  EXPECT_TRUE(rig.init());
  DriveOutcome out;
  const int warmup = 6;  // updates
  for (int k = 0; k < 20 * 14; ++k) {  // 14 s: most of a lap, turning all the time
    const Pose2D truth = circle_pose(k * 0.05);
    const double c = std::cos(truth.theta_rad);
    const double s = std::sin(truth.theta_rad);
    const Pose2D believed{truth.x_m + c * pose_error.x_m - s * pose_error.y_m, truth.y_m + s * pose_error.x_m + c * pose_error.y_m,
                          normalize_angle(truth.theta_rad + pose_error.theta_rad)};
    EXPECT_FALSE(rig.truth.collides(truth, Footprint::pioneer())) << "the route must be free, t=" << k * 0.05;
    rig.tick(k, truth, believed);
    out.max_dynamic_any = std::max(out.max_dynamic_any, rig.dynamic_count());
    if (k < warmup) continue;
    out.max_dynamic_after_warmup = std::max(out.max_dynamic_after_warmup, rig.dynamic_count());
    out.max_confirmed_after_warmup = std::max(out.max_confirmed_after_warmup, rig.confirmed_count());
  }
  if (std::getenv("DOL_TRACE") != nullptr) {
    std::printf("mask %.2f m: max dynamic cells %d (after warm-up %d), max confirmed tracks %d\n", mask_radius_m,
                out.max_dynamic_any, out.max_dynamic_after_warmup, out.max_confirmed_after_warmup);
  }
  return out;
}

TEST(DynamicObstacleLayer, StaticWallsAreNotMotionWhileDrivingAndTurning) {
  const DriveOutcome out = drive(0.15, {0.0, 0.0, 0.0});
  EXPECT_EQ(out.max_dynamic_after_warmup, 0);
  EXPECT_EQ(out.max_confirmed_after_warmup, 0);
}

TEST(DynamicObstacleLayer, LocalizationDriftNeedsTheStaticMask) {
  const Pose2D drift{0.025, -0.015, 0.005};  // about 3 cm and 0.3 degrees
  const DriveOutcome masked = drive(0.15, drift);
  EXPECT_EQ(masked.max_dynamic_after_warmup, 0);
  EXPECT_EQ(masked.max_confirmed_after_warmup, 0);
  // Without the mask the same drive sees the walls' laser marks flicker next to the map's walls.
  const DriveOutcome unmasked = drive(0.0, drift);
  EXPECT_GT(unmasked.max_dynamic_after_warmup, 0);
  EXPECT_GT(unmasked.max_confirmed_after_warmup, 0);
}

// A 20 cm box crossing the view of a robot at (3, 6.3) with the given heading, which sets off
// at the given speed when the box appears (at 2 s); the box goes from 0.3 m right of the
// robot's start to 2.3 m right of it at 0.6 m/s along +x. It stays on one side
// of the robot, so the laser sees the same two faces of it throughout (the blob's centroid is
// theirs, not the box's centre).
void track_crossing_box(double robot_heading_rad, double robot_speed_m_s) {
  DynamicObstacleConfig cfg;
  Rig rig(cfg);
  world::MoverScript box;
  box.path = {{3.3, 7.2}, {5.3, 7.2}};
  box.speed_m_s = 0.6;
  box.size_m = 0.2;
  box.shape = world::MoverShape::square;
  box.start_time_s = 2.0;
  box.appear_time_s = 2.0;
  rig.truth.add_mover(box);
  ASSERT_TRUE(rig.init());
  const bool trace = std::getenv("DOL_TRACE") != nullptr;
  int scans_visible = 0;
  int confirmed_after = -1;
  std::uint32_t id = 0;
  bool checked_cost = false;
  for (int k = 0; k <= 20 * 5; ++k) {  // the box appears at 2 s and is at x = 5.1 at 5 s
    const double t = k * 0.05;
    const double driven = robot_speed_m_s * std::max(0.0, t - 2.0);  // sets off with the box
    const Pose2D robot{3.0 + driven * std::cos(robot_heading_rad), 6.3 + driven * std::sin(robot_heading_rad),
                       robot_heading_rad};
    rig.tick(k, robot, robot);
    const world::Point2D p = rig.truth.mover_position(0);
    if (k % 2 != 0 || t < 2.0) continue;
    ++scans_visible;
    if (trace) {
      for (const DolTrack& tr : rig.dol.tracks()) {
        std::printf("t=%.2f box %.2f %.2f track %u%s hits %d at %.2f %.2f v %.2f %.2f\n", t, p.x_m, p.y_m, tr.id,
                    tr.confirmed ? " confirmed" : "", tr.hits, tr.kf.x[0], tr.kf.x[1], tr.kf.x[2], tr.kf.x[3]);
      }
    }
    if (confirmed_after < 0 && rig.confirmed_count() > 0) {
      confirmed_after = scans_visible;
      for (const DolTrack& tr : rig.dol.tracks())
        if (tr.confirmed) id = tr.id;
    }
    if (confirmed_after < 0) continue;
    // One confirmed track, the same one, on the box.
    ASSERT_EQ(rig.confirmed_count(), 1) << "t=" << t;
    const DolTrack* tr = find_confirmed(rig.dol.tracks());
    ASSERT_NE(tr, nullptr);
    EXPECT_EQ(tr->id, id) << "t=" << t;
    EXPECT_LT(std::hypot(tr->kf.x[0] - p.x_m, tr->kf.x[1] - p.y_m), 0.2) << "t=" << t;
    if (t >= 3.0) {  // from about 1 s after it appeared
      EXPECT_NEAR(std::hypot(tr->kf.x[2], tr->kf.x[3]), 0.6, 0.06) << "t=" << t;
      EXPECT_LT(std::abs(std::atan2(tr->kf.x[3], tr->kf.x[2])), 10.0 * M_PI / 180.0) << "t=" << t;
    }
    if (k == 80) {
      // The costmap shows the space ahead of the box as more expensive than behind it.
      int ca = 0;
      int ra = 0;
      int cb = 0;
      int rb = 0;
      const Costmap2D& g = rig.costmap.costmap();
      ASSERT_TRUE(g.world_to_cell(p.x_m + 0.5, p.y_m, ca, ra));
      ASSERT_TRUE(g.world_to_cell(p.x_m - 0.5, p.y_m, cb, rb));
      EXPECT_GT(g.at(ca, ra), g.at(cb, rb));
      EXPECT_GE(g.at(ca, ra), 200);
      checked_cost = true;
    }
  }
  ASSERT_GT(confirmed_after, 0);
  EXPECT_LE(confirmed_after, cfg.tracker.confirm_hits);  // measured: hits on consecutive scans
  EXPECT_TRUE(checked_cost);
  msg::MovingObstacles movers;
  rig.dol.movers(5'100'000'000LL, movers);
  ASSERT_EQ(movers.count, 1);
  EXPECT_EQ(movers.items[0].id, id);
  EXPECT_EQ(movers.stamp_ns, 5'100'000'000LL);
  EXPECT_NEAR(movers.items[0].vx_m_s, 0.6, 0.06);
  EXPECT_NEAR(movers.items[0].x_m, rig.truth.mover_position(0).x_m + 0.06, 0.2);
  EXPECT_GT(movers.items[0].position_var_m2, 0.0);
  EXPECT_GT(movers.items[0].velocity_var_m2_s2, 0.0);
  EXPECT_GE(movers.items[0].radius_m, cfg.tracker.min_radius_m);
  EXPECT_LE(movers.items[0].radius_m, cfg.tracker.max_radius_m);
  EXPECT_GT(rig.dol.detections(), 0u);
}

// The same box, robot standing: between its confirmation and its travel far enough from where
// it came into view, the box is published as a candidate after the movers, then as a mover.
TEST(DynamicObstacleLayer, AConfirmedBoxIsACandidateUntilItHasTravelled) {
  DynamicObstacleConfig cfg;
  Rig rig(cfg);
  world::MoverScript box;
  box.path = {{3.3, 7.2}, {5.3, 7.2}};
  box.speed_m_s = 0.6;
  box.size_m = 0.2;
  box.shape = world::MoverShape::square;
  box.start_time_s = 2.0;
  box.appear_time_s = 2.0;
  rig.truth.add_mover(box);
  ASSERT_TRUE(rig.init());
  const Pose2D robot{3.0, 6.3, M_PI / 2.0};
  int candidate_scans = 0;
  int mover_scans = 0;
  for (int k = 0; k <= 20 * 4; ++k) {
    rig.tick(k, robot, robot);
    if (k % 2 != 0) continue;
    msg::MovingObstacles movers;
    rig.dol.movers(k * kCostmapTickNs, movers);
    ASSERT_LE(movers.count + movers.candidate_count, 1) << "k=" << k;
    const bool confirmed = rig.confirmed_count() > 0;
    if (movers.candidate_count == 1) {
      // Confirmed, not yet a mover, and never after it became one.
      EXPECT_TRUE(confirmed);
      EXPECT_EQ(mover_scans, 0);
      EXPECT_NEAR(movers.items[0].vx_m_s, 0.6, 0.3);
      ++candidate_scans;
    }
    if (movers.count == 1) ++mover_scans;
    if (!confirmed) {
      EXPECT_EQ(movers.count + movers.candidate_count, 0) << "k=" << k;
    }
  }
  EXPECT_GE(candidate_scans, 1);
  EXPECT_GE(mover_scans, 5);
}

TEST(DynamicObstacleLayer, MovingBoxIsConfirmedAndItsVelocityTracked) {
  SCOPED_TRACE("robot standing, facing +y");
  track_crossing_box(M_PI / 2.0, 0.0);
}

TEST(DynamicObstacleLayer, MovingBoxIsTrackedWhileTheRobotDrives) {
  // The robot follows the box at 0.3 m/s (the window rolls under the averages); the box's
  // velocity is still 0.6 m/s in the map frame. Seen from behind, its trailing face and the
  // leading end of its near face are new in each scan: with blob_link_cells = 1 (plain
  // 8-connectivity) they are two blobs and two confirmed tracks.
  SCOPED_TRACE("robot driving +x at 0.3 m/s");
  track_crossing_box(0.0, 0.3);
}

// A box goes up its lane in the arena, out of the laser's marking range, turns at the wall
// and comes back; the robot stands. Returns whether the track that comes back is the one that
// left, and the largest gap between the box and that track's prediction while it was away.
struct WallReturn {
  bool same_id = false;
  double worst_gap_m = 0.0;
};

WallReturn box_returning_from_a_wall(bool walls) {
  DynamicObstacleConfig cfg;
  cfg.tracker.max_coast_unseen_s = 8.0;
  // Without the static mask the layer has no wall zone: the prediction goes on.
  if (!walls) cfg.detector.static_mask_radius_m = 0.0;
  // With the obstacle layer, as the controller has it: the laser's range bounds its view.
  Rig rig(cfg, 0.01, SEN3BOT_SOURCE_DIR "/config/maps/arena.yaml", true);
  world::MoverScript box;
  box.path = {{3.0, 0.25}, {3.0, 5.75}};
  box.speed_m_s = 0.8;
  box.size_m = 0.2;
  box.shape = world::MoverShape::square;
  box.phase_m = 1.25;  // at y = 1.5, going up
  rig.truth.add_mover(box);
  EXPECT_TRUE(rig.init());
  const Pose2D robot{2.0, 1.5, 0.0};
  WallReturn out;
  std::uint32_t id = 0;
  for (int k = 0; k <= 20 * 12; ++k) {  // up 4.25 m, back 4.25 m: 10.6 s
    rig.tick(k, robot, robot);
    const double t = k * 0.05;
    const world::Point2D p = rig.truth.mover_position(0);
    const DolTrack* track = find_confirmed(rig.dol.tracks());
    if (t < 2.0) {
      if (track != nullptr && track->mover) id = track->id;
      continue;
    }
    if (id == 0) break;
    const DolTrack* first = find_track_by_id(rig.dol.tracks(), id);
    if (first == nullptr) break;  // lost
    out.worst_gap_m = std::max(out.worst_gap_m, std::hypot(first->kf.x[0] - p.x_m, first->kf.x[1] - p.y_m));
    if (t > 10.0) {  // back in sight, going down
      out.same_id = k * kCostmapTickNs - first->last_hit_ns <= 2 * kCostmapTickNs && first->kf.x[3] < -0.5;
      break;
    }
  }
  EXPECT_NE(id, 0u) << "the box was never tracked as a mover";
  return out;
}

TEST(DynamicObstacleLayer, AMoverOutOfSightTurnsBackAtTheWall) {
  const WallReturn with_walls = box_returning_from_a_wall(true);
  EXPECT_TRUE(with_walls.same_id);  // matched again where the box came back
  EXPECT_LT(with_walls.worst_gap_m, 0.6);
  const WallReturn through = box_returning_from_a_wall(false);
  EXPECT_FALSE(through.same_id);
}

TEST(DynamicObstacleLayer, DisabledLayerDoesNothing) {
  DynamicObstacleConfig cfg;
  cfg.enabled = false;
  Rig rig(cfg);
  Rig without(cfg);  // the same costmap with no dynamic obstacle layer at all
  for (Rig* r : {&rig, &without}) {
    world::MoverScript box;
    box.path = {{3.3, 7.2}, {5.3, 7.2}};
    box.speed_m_s = 0.6;
    box.size_m = 0.2;
    box.shape = world::MoverShape::square;
    r->truth.add_mover(box);
  }
  ASSERT_TRUE(rig.init());
  ASSERT_TRUE(without.init(false));
  EXPECT_EQ(rig.arena.used_bytes(), without.arena.used_bytes());  // no memory taken
  const Pose2D robot{3.0, 6.3, M_PI / 2.0};
  for (int k = 0; k < 40; ++k) {
    rig.tick(k, robot, robot);
    without.tick(k, robot, robot);
  }
  const auto a = rig.costmap.costmap().cells();
  const auto b = without.costmap.costmap().cells();
  EXPECT_TRUE(std::equal(a.begin(), a.end(), b.begin()));
  EXPECT_TRUE(rig.dol.tracks().empty());
  EXPECT_TRUE(rig.dol.dynamic_cells().empty());
  msg::MovingObstacles movers;
  movers.count = 3;
  rig.dol.movers(0, movers);
  EXPECT_EQ(movers.count, 0);
  // Enabled, the same run does paint the box.
  DynamicObstacleConfig on;
  Rig enabled(on);
  world::MoverScript box;
  box.path = {{3.3, 7.2}, {5.3, 7.2}};
  box.speed_m_s = 0.6;
  box.size_m = 0.2;
  box.shape = world::MoverShape::square;
  enabled.truth.add_mover(box);
  ASSERT_TRUE(enabled.init());
  for (int k = 0; k < 40; ++k) enabled.tick(k, robot, robot);
  const auto c = enabled.costmap.costmap().cells();
  EXPECT_FALSE(std::equal(c.begin(), c.end(), b.begin()));
}

TEST(DynamicObstacleLayer, UpdatesAllocateNothing) {
  DynamicObstacleConfig cfg;
  Rig rig(cfg);
  for (int i = 0; i < 3; ++i) {
    world::MoverScript box;
    box.path = {{2.8, 7.0 + 0.5 * i}, {5.4, 7.0 + 0.5 * i}};
    box.speed_m_s = 0.4 + 0.2 * i;
    box.size_m = 0.2;
    box.shape = world::MoverShape::square;
    rig.truth.add_mover(box);
  }
  ASSERT_TRUE(rig.init());
  // The scans beforehand: the world's ray caster is not what is measured.
  std::vector<ProjectedScan> views(40);
  for (int k = 0; k < 40; ++k) {
    const Pose2D robot{4.0, 6.0 + 0.01 * k, M_PI / 2.0};
    rig.truth.set_time(k * 0.05);
    rig.truth.noisy_scan(compose(robot, rig.mount), rig.scan.angle_min_rad, rig.scan.increment_rad, rig.scan.count,
                         rig.scan.range_max_m, std::span<float>(rig.scan.ranges_m.data(), rig.scan.count));
    rig.scan.stamp_ns = k * kCostmapTickNs;
    views[static_cast<std::size_t>(k)].assign(rig.scan.view(), rig.mount);
  }
  msg::MovingObstacles movers;
  const auto run = [&](int from, int to) {
    for (int k = from; k < to; ++k) {
      const Pose2D robot{4.0, 6.0 + 0.01 * k, M_PI / 2.0};
      rig.costmap.update({robot, robot, k % 2 == 0 ? &views[static_cast<std::size_t>(k)] : nullptr, k * kCostmapTickNs});
      rig.dol.movers(k * kCostmapTickNs, movers);
    }
  };
  run(0, 20);
  mem::testing::AllocationScope scope;
  run(20, 40);
  EXPECT_EQ(scope.allocations(), 0u);
  if (mem::testing::counts_malloc()) {
    EXPECT_EQ(scope.malloc_calls(), 0u);
  }
  EXPECT_GT(rig.dol.detections(), 0u);
}

}  // namespace
}  // namespace sen3bot::nav
