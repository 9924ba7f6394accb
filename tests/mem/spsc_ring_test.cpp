#include "sen3bot/mem/spsc_ring.hpp"

#include <gtest/gtest.h>

#include <cstdint>
#include <thread>

#include "tracked.hpp"

namespace sen3bot::mem {
namespace {

using testing::Tracked;

static_assert(alignof(SpscRing<int, 8>) >= kCacheLineBytes);
// Producer line, consumer line, then the slots on lines of their own.
static_assert(sizeof(SpscRing<char, 8>) >= 3 * kCacheLineBytes);

class SpscRingTest : public testing::TrackedTest {};

TEST_F(SpscRingTest, FillsToCapacityThenRejects) {
  SpscRing<int, 4> ring;
  EXPECT_EQ(ring.capacity(), 4u);
  EXPECT_TRUE(ring.empty_approx());
  EXPECT_EQ(ring.try_pop(), std::nullopt);
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(ring.try_push(i));
  EXPECT_FALSE(ring.try_push(4));
  EXPECT_EQ(ring.size_approx(), 4u);
  for (int i = 0; i < 4; ++i) EXPECT_EQ(ring.try_pop(), i);
  EXPECT_EQ(ring.try_pop(), std::nullopt);
}

TEST_F(SpscRingTest, WrapsAroundManyTimes) {
  SpscRing<int, 8> ring;
  int next_in = 0;
  int next_out = 0;
  for (int round = 0; round < 1000; ++round) {
    const int burst = 1 + round % 8;
    for (int i = 0; i < burst; ++i) ASSERT_TRUE(ring.try_push(next_in++));
    for (int i = 0; i < burst; ++i) {
      int out = -1;
      ASSERT_TRUE(ring.try_pop(out));
      ASSERT_EQ(out, next_out++);
    }
  }
  int untouched = 77;
  EXPECT_FALSE(ring.try_pop(untouched));
  EXPECT_EQ(untouched, 77);
}

TEST_F(SpscRingTest, ElementLifetimes) {
  {
    SpscRing<Tracked, 4> ring;
    for (int i = 0; i < 4; ++i) ASSERT_TRUE(ring.try_emplace(i));
    const int before = Tracked::constructed;
    EXPECT_FALSE(ring.try_emplace(9));
    EXPECT_EQ(Tracked::constructed, before);
    auto first = ring.try_pop();
    ASSERT_TRUE(first.has_value());
    EXPECT_EQ(first->value, 0);
    Tracked second;
    ASSERT_TRUE(ring.try_pop(second));
    EXPECT_EQ(second.value, 1);
    EXPECT_EQ(Tracked::live(), 4);  // two left in the ring + first + second
  }
  EXPECT_EQ(Tracked::live(), 0);  // the destructor destroyed the two left in the ring
}

// A payload larger than one word, so a torn (half-published) element would be noticed.
struct Sequenced {
  std::uint64_t sequence;
  std::uint64_t check;  // ~sequence
};

template <std::size_t N>
void run_two_threads(std::uint64_t count) {
  SpscRing<Sequenced, N> ring;
  std::thread producer([&] {
    for (std::uint64_t i = 0; i < count; ++i) {
      while (!ring.try_push(Sequenced{i, ~i})) std::this_thread::yield();
    }
  });
  std::uint64_t expected = 0;
  std::uint64_t out_of_order = 0;
  std::uint64_t torn = 0;
  while (expected < count) {
    if (auto item = ring.try_pop()) {
      if (item->sequence != expected) ++out_of_order;
      if (item->check != ~item->sequence) ++torn;
      ++expected;
    } else {
      std::this_thread::yield();
    }
  }
  producer.join();
  EXPECT_EQ(out_of_order, 0u);
  EXPECT_EQ(torn, 0u);
  EXPECT_EQ(expected, count);
  EXPECT_EQ(ring.try_pop(), std::nullopt) << "more items came out than went in";
}

TEST_F(SpscRingTest, TwoThreadsPassAMillionItemsInOrderWithoutLoss) {
  run_two_threads<1024>(1'000'000);
}

TEST_F(SpscRingTest, TwoThreadsThroughATinyRing) {
  // Capacity 2 keeps the queue full or empty nearly all the time: maximum contention on the
  // indices and on the full/empty edges.
  run_two_threads<2>(200'000);
}

}  // namespace
}  // namespace sen3bot::mem
