#include "sen3bot/mem/ring_buffer.hpp"

#include <gtest/gtest.h>

#include <deque>
#include <iterator>
#include <random>
#include <type_traits>
#include <vector>

#include "tracked.hpp"

namespace sen3bot::mem {
namespace {

using testing::Tracked;

template <std::size_t N, WhenFull P>
std::vector<int> ring_values(const RingBuffer<int, N, P>& ring) {
  return {ring.begin(), ring.end()};
}
template <std::size_t N, WhenFull P>
std::vector<int> ring_values(const RingBuffer<Tracked, N, P>& ring) {
  std::vector<int> out;
  for (const Tracked& t : ring) out.push_back(t.value);
  return out;
}

static_assert(std::is_trivially_copyable_v<RingBuffer<int, 8>>);
static_assert(!std::is_trivially_copyable_v<RingBuffer<Tracked, 8>>);
static_assert(std::forward_iterator<RingBuffer<int, 8>::iterator>);
static_assert(std::forward_iterator<RingBuffer<int, 8>::const_iterator>);
static_assert(std::is_convertible_v<RingBuffer<int, 8>::iterator, RingBuffer<int, 8>::const_iterator>);

class RingBufferTest : public testing::TrackedTest {};

TEST_F(RingBufferTest, FifoOrder) {
  RingBuffer<int, 4> ring;
  EXPECT_TRUE(ring.empty());
  EXPECT_EQ(ring.pop(), std::nullopt);
  EXPECT_FALSE(ring.drop_front());
  EXPECT_TRUE(ring.push(1));
  EXPECT_TRUE(ring.push(2));
  EXPECT_TRUE(ring.push(3));
  EXPECT_EQ(ring.front(), 1);
  EXPECT_EQ(ring.back(), 3);
  EXPECT_EQ(ring.pop(), 1);
  EXPECT_EQ(ring.pop(), 2);
  EXPECT_EQ(ring.pop(), 3);
  EXPECT_EQ(ring.pop(), std::nullopt);
  EXPECT_EQ(ring.dropped(), 0u);
}

TEST_F(RingBufferTest, RejectWhenFullLeavesContentsAndCountsTheDrop) {
  RingBuffer<int, 3, WhenFull::reject> ring;
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(ring.push(i));
  EXPECT_TRUE(ring.full());
  EXPECT_FALSE(ring.push(99));
  EXPECT_FALSE(ring.emplace(98));
  EXPECT_EQ(ring_values(ring), (std::vector<int>{0, 1, 2}));
  EXPECT_EQ(ring.dropped(), 2u);
}

TEST_F(RingBufferTest, OverwriteOldestKeepsTheNewest) {
  RingBuffer<int, 3, WhenFull::overwrite_oldest> ring;
  for (int i = 0; i < 3; ++i) EXPECT_TRUE(ring.push(i));
  EXPECT_FALSE(ring.push(3));  // stored, but 0 was lost
  EXPECT_FALSE(ring.push(4));
  EXPECT_EQ(ring.size(), 3u);
  EXPECT_EQ(ring_values(ring), (std::vector<int>{2, 3, 4}));
  EXPECT_EQ(ring.front(), 2);
  EXPECT_EQ(ring.back(), 4);
  EXPECT_EQ(ring.dropped(), 2u);
  EXPECT_EQ(ring.pop(), 2);
  EXPECT_TRUE(ring.push(5));  // room again: nothing lost
  EXPECT_EQ(ring_values(ring), (std::vector<int>{3, 4, 5}));
}

TEST_F(RingBufferTest, OverwriteWithTheOldestElementAsArgument) {
  RingBuffer<Tracked, 2, WhenFull::overwrite_oldest> ring;
  ring.emplace(1);
  ring.emplace(2);
  ring.push(ring.front());  // the argument is the element about to be overwritten
  EXPECT_EQ(ring_values(ring), (std::vector<int>{2, 1}));
}

TEST_F(RingBufferTest, AtCountsFromTheOldestAcrossTheWrap) {
  RingBuffer<int, 4> ring;
  for (int i = 0; i < 4; ++i) ring.push(i);
  ring.pop();
  ring.pop();
  ring.push(4);
  ring.push(5);  // physically: [4 5 2 3], head at slot 2
  ASSERT_EQ(ring.size(), 4u);
  for (std::size_t i = 0; i < 4; ++i) EXPECT_EQ(ring.at(i), static_cast<int>(i) + 2);
  EXPECT_EQ(ring[3], 5);
  ring.at(1) = 30;
  EXPECT_EQ(ring_values(ring), (std::vector<int>{2, 30, 4, 5}));
}

// Random pushes and pops against std::deque, for both policies, with enough operations to
// wrap the indices many times.
template <WhenFull Policy>
void check_against_deque() {
  constexpr std::size_t kCapacity = 7;  // not a power of two on purpose
  RingBuffer<int, kCapacity, Policy> ring;
  std::deque<int> model;
  std::uint64_t model_dropped = 0;
  std::mt19937_64 rng(1);
  int next = 0;
  for (int step = 0; step < 20'000; ++step) {
    if (rng() % 5 < 3) {  // push-heavy so the full edge is hit often
      const bool stored_without_loss = ring.push(next);
      if (model.size() < kCapacity) {
        model.push_back(next);
        EXPECT_TRUE(stored_without_loss);
      } else {
        ++model_dropped;
        EXPECT_FALSE(stored_without_loss);
        if (Policy == WhenFull::overwrite_oldest) {
          model.pop_front();
          model.push_back(next);
        }
      }
      ++next;
    } else {
      const auto popped = ring.pop();
      if (model.empty()) {
        EXPECT_EQ(popped, std::nullopt);
      } else {
        ASSERT_TRUE(popped.has_value());
        EXPECT_EQ(*popped, model.front());
        model.pop_front();
      }
    }
    ASSERT_EQ(ring.size(), model.size());
    ASSERT_EQ(ring.full(), model.size() == kCapacity);
    ASSERT_EQ(ring.dropped(), model_dropped);
    ASSERT_TRUE(std::equal(ring.begin(), ring.end(), model.begin(), model.end())) << "step " << step;
  }
}

TEST_F(RingBufferTest, RejectPolicyMatchesDequeOverRandomOperations) {
  check_against_deque<WhenFull::reject>();
}

TEST_F(RingBufferTest, OverwritePolicyMatchesDequeOverRandomOperations) {
  check_against_deque<WhenFull::overwrite_oldest>();
}

TEST_F(RingBufferTest, LifetimesWithRejectPolicy) {
  {
    RingBuffer<Tracked, 3> ring;
    for (int i = 0; i < 3; ++i) ring.emplace(i);
    const int before = Tracked::constructed;
    EXPECT_FALSE(ring.emplace(3));
    EXPECT_EQ(Tracked::constructed, before) << "a rejected element must not be constructed";
    auto popped = ring.pop();
    ASSERT_TRUE(popped.has_value());
    EXPECT_EQ(popped->value, 0);
    EXPECT_EQ(Tracked::live(), 3);  // two in the ring and the popped one
    for (int i = 10; i < 20; ++i) {  // wrap a few times
      ring.emplace(i);
      ring.drop_front();
    }
    EXPECT_EQ(Tracked::live(), 3);
  }
  EXPECT_EQ(Tracked::live(), 0);
}

TEST_F(RingBufferTest, LifetimesWithOverwritePolicy) {
  {
    RingBuffer<Tracked, 3, WhenFull::overwrite_oldest> ring;
    for (int i = 0; i < 10; ++i) ring.emplace(i);
    EXPECT_EQ(Tracked::live(), 3);
    EXPECT_EQ(ring_values(ring), (std::vector<int>{7, 8, 9}));
  }
  EXPECT_EQ(Tracked::live(), 0);
}

TEST_F(RingBufferTest, ClearDestroysAndResets) {
  RingBuffer<Tracked, 4> ring;
  for (int i = 0; i < 3; ++i) ring.emplace(i);
  ring.pop();
  ring.clear();
  EXPECT_TRUE(ring.empty());
  EXPECT_EQ(Tracked::live(), 0);
  for (int i = 0; i < 4; ++i) EXPECT_TRUE(ring.emplace(i));
  EXPECT_EQ(ring_values(ring), (std::vector<int>{0, 1, 2, 3}));
}

TEST_F(RingBufferTest, CopyAndMoveKeepOrderAcrossTheWrap) {
  RingBuffer<Tracked, 4> a;
  for (int i = 0; i < 4; ++i) a.emplace(i);
  a.pop();
  a.pop();
  a.emplace(4);  // wrapped: oldest..newest = 2 3 4
  RingBuffer<Tracked, 4> b(a);
  EXPECT_EQ(ring_values(b), (std::vector<int>{2, 3, 4}));
  RingBuffer<Tracked, 4> c;
  c.emplace(100);
  c = a;
  EXPECT_EQ(ring_values(c), (std::vector<int>{2, 3, 4}));
  RingBuffer<Tracked, 4> d(std::move(b));
  EXPECT_EQ(ring_values(d), (std::vector<int>{2, 3, 4}));
  c = std::move(d);
  EXPECT_EQ(ring_values(c), (std::vector<int>{2, 3, 4}));
  EXPECT_EQ(c.pop()->value, 2);
}

TEST_F(RingBufferTest, TrivialRingCopies) {
  RingBuffer<int, 3, WhenFull::overwrite_oldest> a;
  for (int i = 0; i < 5; ++i) a.push(i);
  const auto b = a;
  EXPECT_EQ(ring_values(b), (std::vector<int>{2, 3, 4}));
  EXPECT_EQ(b.dropped(), 2u);
}

TEST_F(RingBufferTest, CapacityOne) {
  RingBuffer<int, 1, WhenFull::overwrite_oldest> latest;
  EXPECT_TRUE(latest.push(1));
  EXPECT_FALSE(latest.push(2));
  EXPECT_EQ(latest.front(), 2);
  RingBuffer<int, 1> one;
  EXPECT_TRUE(one.push(1));
  EXPECT_FALSE(one.push(2));
  EXPECT_EQ(one.pop(), 1);
  EXPECT_TRUE(one.push(3));
  EXPECT_EQ(one.front(), 3);
}

TEST_F(RingBufferTest, IteratorsWalkOldestToNewest) {
  RingBuffer<int, 5, WhenFull::overwrite_oldest> ring;
  for (int i = 0; i < 8; ++i) ring.push(i);
  std::vector<int> seen;
  for (int& x : ring) seen.push_back(x);
  EXPECT_EQ(seen, (std::vector<int>{3, 4, 5, 6, 7}));
  for (int& x : ring) x *= 10;
  const auto& cring = ring;
  EXPECT_EQ(std::distance(cring.begin(), cring.end()), 5);
  EXPECT_EQ(*cring.begin(), 30);
  RingBuffer<int, 5, WhenFull::overwrite_oldest>::const_iterator it = ring.begin();
  EXPECT_EQ(*it++, 30);
  EXPECT_EQ(*it, 40);
}

}  // namespace
}  // namespace sen3bot::mem
