#include <gtest/gtest.h>

#include <algorithm>
#include <random>
#include <vector>

#include "sen3bot/tasks/histogram.hpp"

namespace sen3bot::tasks {
namespace {

TEST(LatencyHistogram, EmptyReportsZero) {
  LatencyHistogram h;
  EXPECT_EQ(h.count(), 0u);
  EXPECT_EQ(h.percentile_ns(0.99), 0);
  EXPECT_EQ(h.max_ns(), 0);
}

TEST(LatencyHistogram, SmallValuesAreExact) {
  LatencyHistogram h;
  for (int v = 0; v < 32; ++v) h.record(v);
  EXPECT_EQ(h.percentile_ns(0.5), 15);
  EXPECT_EQ(h.max_ns(), 31);
}

TEST(LatencyHistogram, PercentilesWithinThreePercentOfExact) {
  std::mt19937_64 rng(1);
  std::lognormal_distribution<double> dist(10.0, 1.5);  // ~22 us median, long tail
  std::vector<std::int64_t> values(100'000);
  LatencyHistogram h;
  for (auto& v : values) {
    v = static_cast<std::int64_t>(dist(rng));
    h.record(v);
  }
  std::sort(values.begin(), values.end());
  for (double p : {0.5, 0.9, 0.99, 0.999}) {
    const auto exact = static_cast<double>(values[static_cast<std::size_t>(p * static_cast<double>(values.size())) - 1]);
    const auto approx = static_cast<double>(h.percentile_ns(p));
    EXPECT_NEAR(approx, exact, exact * 0.032 + 1) << "p" << p;
  }
  EXPECT_EQ(h.max_ns(), values.back());
}

TEST(LatencyHistogram, BucketIndexIsMonotonicAndMidpointInsideBucket) {
  std::size_t previous = 0;
  for (std::uint64_t v = 0; v < (1u << 20); v += 7) {
    const std::size_t i = LatencyHistogram::index_of(v);
    ASSERT_GE(i, previous);
    previous = i;
    ASSERT_EQ(LatencyHistogram::index_of(LatencyHistogram::midpoint_of(i)), i) << v;
  }
  EXPECT_EQ(LatencyHistogram::index_of(UINT64_MAX), LatencyHistogram::kBucketCount - 1);
}

TEST(LatencyHistogram, NegativeValuesCountAsZero) {
  LatencyHistogram h;
  h.record(-5);
  EXPECT_EQ(h.count(), 1u);
  EXPECT_EQ(h.percentile_ns(1.0), 0);
}

}  // namespace
}  // namespace sen3bot::tasks
