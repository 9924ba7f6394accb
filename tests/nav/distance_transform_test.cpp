#include <gtest/gtest.h>

#include <limits>
#include <random>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/mem/budget_arena.hpp"
#include "sen3bot/nav/distance_transform.hpp"

namespace sen3bot::nav {
namespace {

constexpr float kInf = std::numeric_limits<float>::infinity();

// Squared distance in cells from every cell to the nearest site, by trying every site.
std::vector<float> brute_force(const std::vector<float>& sites, int width, int height) {
  std::vector<float> out(sites.size(), kInf);
  for (int r = 0; r < height; ++r) {
    for (int c = 0; c < width; ++c) {
      for (int sr = 0; sr < height; ++sr) {
        for (int sc = 0; sc < width; ++sc) {
          if (sites[static_cast<std::size_t>(sr * width + sc)] != 0.0f) continue;
          const auto d2 = static_cast<float>((c - sc) * (c - sc) + (r - sr) * (r - sr));
          float& best = out[static_cast<std::size_t>(r * width + c)];
          if (d2 < best) best = d2;
        }
      }
    }
  }
  return out;
}

std::vector<float> random_sites(int width, int height, double density, unsigned seed) {
  std::mt19937 rng(seed);
  std::bernoulli_distribution site(density);
  std::vector<float> grid(static_cast<std::size_t>(width * height));
  for (float& cell : grid) cell = site(rng) ? 0.0f : kInf;
  return grid;
}

TEST(DistanceTransform, MatchesBruteForceOnRandomGrids) {
  mem::BudgetArena arena("test", 1 << 16);
  DistanceTransform transform;
  ASSERT_TRUE(transform.init(40, arena));
  const int sizes[][2] = {{23, 17}, {17, 23}, {40, 1}, {1, 40}, {31, 31}};
  unsigned seed = 1;
  for (const auto& size : sizes) {
    for (const double density : {0.01, 0.05, 0.3}) {
      const int w = size[0];
      const int h = size[1];
      std::vector<float> grid = random_sites(w, h, density, seed++);
      const std::vector<float> expected = brute_force(grid, w, h);
      ASSERT_TRUE(transform.transform(grid, w, h));
      // Squared distances are small integers: the float result is exact.
      EXPECT_EQ(grid, expected) << w << " x " << h << " density " << density;
    }
  }
}

TEST(DistanceTransform, NoSiteLeavesEveryCellInfinite) {
  mem::BudgetArena arena("test", 1 << 12);
  DistanceTransform transform;
  ASSERT_TRUE(transform.init(8, arena));
  std::vector<float> grid(8 * 5, kInf);
  ASSERT_TRUE(transform.transform(grid, 8, 5));
  for (const float d2 : grid) EXPECT_EQ(d2, kInf);
}

TEST(DistanceTransform, OneSiteInACorner) {
  mem::BudgetArena arena("test", 1 << 12);
  DistanceTransform transform;
  ASSERT_TRUE(transform.init(6, arena));
  std::vector<float> grid(6 * 4, kInf);
  grid[0] = 0.0f;
  ASSERT_TRUE(transform.transform(grid, 6, 4));
  EXPECT_EQ(grid[0], 0.0f);
  EXPECT_EQ(grid[5], 25.0f);            // (5, 0)
  EXPECT_EQ(grid[3 * 6 + 5], 34.0f);    // (5, 3)
  EXPECT_EQ(grid[2 * 6 + 1], 5.0f);     // (1, 2)
}

TEST(DistanceTransform, RefusesGridsLargerThanSized) {
  mem::BudgetArena arena("test", 1 << 12);
  DistanceTransform transform;
  ASSERT_TRUE(transform.init(10, arena));
  std::vector<float> grid(11 * 2, 0.0f);
  grid[1] = kInf;
  EXPECT_FALSE(transform.transform(grid, 11, 2));
  EXPECT_EQ(grid[1], kInf);  // untouched
}

TEST(DistanceTransform, TransformAllocatesNothing) {
  mem::BudgetArena arena("test", 1 << 16);
  DistanceTransform transform;
  ASSERT_TRUE(transform.init(64, arena));
  std::vector<float> grid = random_sites(64, 48, 0.05, 7);
  const std::vector<float> sites = grid;
  mem::testing::AllocationScope scope;
  for (int i = 0; i < 20; ++i) {
    grid = sites;  // same size: the vector keeps its buffer
    ASSERT_TRUE(transform.transform(grid, 64, 48));
  }
  EXPECT_EQ(scope.allocations(), 0u);
}

}  // namespace
}  // namespace sen3bot::nav
