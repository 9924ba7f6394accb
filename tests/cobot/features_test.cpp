// The path features: the drawn path (occupancy) cannot tell a path from its reverse, the order
// channel can; bilinear splatting; edge cases; no allocation.
#include <gtest/gtest.h>

#include <cmath>
#include <limits>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/cobot/operations.hpp"

namespace sen3bot::cobot {
namespace {

const GridSpec kGrid{0.0, 0.0, 0.5, 16, 19};

// A walk east along y = 1.25 m then north along x = 6.25 m, a point every 5 cm.
std::vector<float> l_path() {
  std::vector<float> xy;
  for (double x = 1.0; x < 6.25; x += 0.05) xy.insert(xy.end(), {static_cast<float>(x), 1.25f});
  for (double y = 1.25; y <= 6.0; y += 0.05) xy.insert(xy.end(), {6.25f, static_cast<float>(y)});
  return xy;
}

std::vector<float> reversed(const std::vector<float>& xy) {
  std::vector<float> r;
  for (std::size_t i = xy.size(); i >= 2; i -= 2) r.insert(r.end(), {xy[i - 2], xy[i - 1]});
  return r;
}

std::vector<float> features(const std::vector<float>& xy, FeatureEncoding e = FeatureEncoding::occupancy_order) {
  std::vector<float> out(feature_count(kGrid, e), -1.0f);
  path_features(xy, kGrid, out, e);
  return out;
}

std::size_t cell(int c, int r) { return static_cast<std::size_t>(r * kGrid.cols + c); }

TEST(PathFeatures, Sizes) {
  EXPECT_EQ(feature_count(kGrid, FeatureEncoding::occupancy), 304u);
  EXPECT_EQ(feature_count(kGrid, FeatureEncoding::occupancy_order), 608u);
}

TEST(PathFeatures, OrderTellsAPathFromItsReverse) {
  const std::vector<float> path = l_path();
  const std::vector<float> forward = features(path), backward = features(reversed(path));
  const std::size_t cells = kGrid.cells();
  // The thesis' input, the drawn path, is the same both ways...
  for (std::size_t k = 0; k < cells; ++k) EXPECT_NEAR(forward[k], backward[k], 1e-6f) << k;
  EXPECT_EQ(features(path, FeatureEncoding::occupancy), features(reversed(path), FeatureEncoding::occupancy));
  // ...the order is mirrored: where the forward path starts the reverse one ends.
  const std::size_t start = cells + cell(2, 2), end = cells + cell(12, 11);
  EXPECT_LT(forward[start], 0.1f);
  EXPECT_GT(backward[start], 0.9f);
  EXPECT_GT(forward[end], 0.9f);
  EXPECT_LT(backward[end], 0.1f);
  std::size_t visited = 0;
  for (std::size_t k = 0; k < cells; ++k) {
    if (forward[k] <= 0.0f) {
      EXPECT_EQ(forward[cells + k], 0.0f);  // never touched: no order either
      continue;
    }
    ++visited;
    EXPECT_NEAR(forward[cells + k] + backward[cells + k], 1.0f, 1e-4f) << k;
  }
  EXPECT_GT(visited, 20u);
}

TEST(PathFeatures, BilinearSplat) {
  // A point on a cell's centre is all in that cell; one on a corner of four is shared equally.
  std::vector<float> at_centre{1.25f, 0.75f};
  std::vector<float> f = features(at_centre);
  EXPECT_FLOAT_EQ(f[cell(2, 1)], 1.0f);
  float others = 0;
  for (std::size_t k = 0; k < kGrid.cells(); ++k) others += k == cell(2, 1) ? 0.0f : f[k];
  EXPECT_FLOAT_EQ(others, 0.0f);
  std::vector<float> on_corner{1.5f, 1.0f};
  f = features(on_corner);
  for (const std::size_t k : {cell(2, 1), cell(3, 1), cell(2, 2), cell(3, 2)}) EXPECT_NEAR(f[k], 0.25f, 1e-6f);
  // One point: its fraction is 0 (the path's start).
  EXPECT_EQ(f[kGrid.cells() + cell(2, 1)], 0.0f);
}

TEST(PathFeatures, EdgeCases) {
  // Nothing: zeros (the output is cleared first).
  std::vector<float> none;
  for (const float v : features(none)) EXPECT_EQ(v, 0.0f);
  // Off the grid: the nearest border cells.
  std::vector<float> far{-50.0f, 100.0f};
  std::vector<float> f = features(far);
  EXPECT_FLOAT_EQ(f[cell(0, kGrid.rows - 1)], 1.0f);
  // Non-finite points are skipped; the others still count.
  const float nan = std::numeric_limits<float>::quiet_NaN();
  std::vector<float> mixed{1.25f, 0.75f, nan, 2.0f, 3.25f, std::numeric_limits<float>::infinity()};
  f = features(mixed);
  EXPECT_FLOAT_EQ(f[cell(2, 1)], 1.0f);
  for (const float v : f) EXPECT_TRUE(std::isfinite(v));
  // An output too short for the grid gets zeros, not a partial write past its end.
  std::vector<float> short_out(10, -1.0f);
  path_features(l_path(), kGrid, short_out);
  for (const float v : short_out) EXPECT_EQ(v, 0.0f);
}

TEST(PathFeatures, AllocatesNothing) {
  const std::vector<float> path = l_path();
  std::vector<float> out(feature_count(kGrid, FeatureEncoding::occupancy_order));
  const mem::testing::AllocationScope scope;
  for (int i = 0; i < 1000; ++i) path_features(path, kGrid, out);
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_GT(out[kGrid.cells() + cell(12, 11)], 0.9f);  // it did run
}

}  // namespace
}  // namespace sen3bot::cobot
