#include "sen3bot/mem/bounded_priority_queue.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <cstdlib>
#include <functional>
#include <queue>
#include <random>
#include <vector>

#include "tracked.hpp"

namespace sen3bot::mem {
namespace {

using testing::Tracked;

class BoundedPriorityQueueTest : public testing::TrackedTest {};

TEST_F(BoundedPriorityQueueTest, EmptyAndFullEdges) {
  BoundedPriorityQueue<int, 3> queue;
  EXPECT_TRUE(queue.empty());
  EXPECT_EQ(queue.pop(), std::nullopt);
  EXPECT_TRUE(queue.push(2));
  EXPECT_TRUE(queue.push(9));
  EXPECT_TRUE(queue.push(4));
  EXPECT_TRUE(queue.full());
  EXPECT_FALSE(queue.push(100)) << "full: rejected, even though it would be the new top";
  EXPECT_EQ(queue.top(), 9);
  EXPECT_EQ(queue.pop(), 9);
  EXPECT_EQ(queue.pop(), 4);
  EXPECT_EQ(queue.pop(), 2);
  EXPECT_EQ(queue.pop(), std::nullopt);
}

// Interleaved random pushes and pops, with many equal values, against std::priority_queue.
template <typename Compare>
void check_against_std(std::uint64_t seed) {
  constexpr std::size_t kCapacity = 256;
  BoundedPriorityQueue<int, kCapacity, Compare> queue;
  std::priority_queue<int, std::vector<int>, Compare> model;
  std::mt19937_64 rng(seed);
  std::uniform_int_distribution<int> value(-50, 50);
  for (int step = 0; step < 100'000; ++step) {
    if (rng() % 3 != 0) {
      const int v = value(rng);
      const bool pushed = queue.push(v);
      ASSERT_EQ(pushed, model.size() < kCapacity);
      if (pushed) model.push(v);
    } else {
      const auto popped = queue.pop();
      if (model.empty()) {
        ASSERT_EQ(popped, std::nullopt);
      } else {
        ASSERT_EQ(popped, model.top());
        model.pop();
      }
    }
    ASSERT_EQ(queue.size(), model.size());
    if (!model.empty()) {
      ASSERT_EQ(queue.top(), model.top());
    }
  }
  while (!model.empty()) {
    ASSERT_EQ(queue.pop(), model.top());
    model.pop();
  }
  EXPECT_TRUE(queue.empty());
}

TEST_F(BoundedPriorityQueueTest, MaxQueueMatchesStdPriorityQueue) { check_against_std<std::less<int>>(1); }

TEST_F(BoundedPriorityQueueTest, MinQueueMatchesStdPriorityQueue) {
  check_against_std<std::greater<int>>(1);
}

TEST_F(BoundedPriorityQueueTest, StatefulComparator) {
  // Orders by distance from a reference that is only known at run time.
  struct CloserTo {
    int reference;
    bool operator()(int a, int b) const { return std::abs(a - reference) > std::abs(b - reference); }
  };
  BoundedPriorityQueue<int, 8, CloserTo> queue(CloserTo{10});
  for (int v : {0, 25, 9, 14, 10}) ASSERT_TRUE(queue.push(v));
  EXPECT_EQ(queue.pop(), 10);
  EXPECT_EQ(queue.pop(), 9);
  EXPECT_EQ(queue.pop(), 14);
  EXPECT_EQ(queue.pop(), 0);
  EXPECT_EQ(queue.pop(), 25);
}

TEST_F(BoundedPriorityQueueTest, ElementLifetimes) {
  {
    BoundedPriorityQueue<Tracked, 8> queue;
    for (int v : {5, 1, 7, 3}) ASSERT_TRUE(queue.emplace(v));
    EXPECT_EQ(queue.pop()->value, 7);
    EXPECT_EQ(Tracked::live(), 3);
    queue.clear();
    EXPECT_EQ(Tracked::live(), 0);
    for (int v : {2, 4}) ASSERT_TRUE(queue.emplace(v));
  }
  EXPECT_EQ(Tracked::live(), 0);
}

TEST_F(BoundedPriorityQueueTest, UnorderedViewHoldsEveryElement) {
  BoundedPriorityQueue<int, 4> queue;
  for (int v : {3, 1, 2}) ASSERT_TRUE(queue.push(v));
  std::vector<int> held(queue.unordered().begin(), queue.unordered().end());
  std::sort(held.begin(), held.end());
  EXPECT_EQ(held, (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(queue.unordered().front(), 3) << "heap order puts the top first";
}

}  // namespace
}  // namespace sen3bot::mem
