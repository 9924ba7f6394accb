#include "sen3bot/mem/static_vector.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstring>
#include <memory>
#include <span>
#include <string>
#include <type_traits>
#include <vector>

#include "tracked.hpp"

namespace sen3bot::mem {
namespace {

using testing::Tracked;

struct Point {
  float x_m;
  float y_m;
};

// A StaticVector of PODs is itself a POD-like value: trivially copyable and destructible, so
// it can be a member of a message copied across threads by memcpy.
static_assert(std::is_trivially_copyable_v<StaticVector<Point, 8>>);
static_assert(std::is_trivially_destructible_v<StaticVector<int, 8>>);
static_assert(!std::is_trivially_copyable_v<StaticVector<Tracked, 8>>);
static_assert(!std::is_trivially_destructible_v<StaticVector<Tracked, 8>>);
static_assert(std::is_nothrow_move_constructible_v<StaticVector<Tracked, 8>>);
static_assert(!std::is_copy_constructible_v<StaticVector<std::unique_ptr<int>, 2>>);
static_assert(std::is_move_constructible_v<StaticVector<std::unique_ptr<int>, 2>>);
static_assert(std::contiguous_iterator<StaticVector<int, 4>::iterator>);
static_assert(noexcept(std::declval<StaticVector<int, 4>&>().push_back(1)));
static_assert(noexcept(std::declval<StaticVector<int, 4>&>().pop_back()));

template <std::size_t N>
std::vector<int> values(const StaticVector<Tracked, N>& v) {
  std::vector<int> out;
  for (const Tracked& t : v) out.push_back(t.value);
  return out;
}

class StaticVectorTest : public testing::TrackedTest {};

TEST_F(StaticVectorTest, StartsEmpty) {
  StaticVector<int, 4> v;
  EXPECT_TRUE(v.empty());
  EXPECT_FALSE(v.full());
  EXPECT_EQ(v.size(), 0u);
  EXPECT_EQ(v.capacity(), 4u);
  EXPECT_EQ(v.begin(), v.end());
  EXPECT_TRUE(v.as_span().empty());
}

TEST_F(StaticVectorTest, PushUntilFullThenRejectsWithoutChange) {
  StaticVector<int, 3> v;
  EXPECT_TRUE(v.push_back(1));
  EXPECT_TRUE(v.push_back(2));
  EXPECT_TRUE(v.emplace_back(3));
  EXPECT_TRUE(v.full());
  EXPECT_FALSE(v.push_back(4));
  EXPECT_FALSE(v.emplace_back(5));
  ASSERT_EQ(v.size(), 3u);
  EXPECT_EQ(v[0], 1);
  EXPECT_EQ(v[1], 2);
  EXPECT_EQ(v[2], 3);
  EXPECT_EQ(v.front(), 1);
  EXPECT_EQ(v.back(), 3);
}

TEST_F(StaticVectorTest, RejectedPushConstructsNothing) {
  StaticVector<Tracked, 1> v;
  ASSERT_TRUE(v.emplace_back(1));
  const int before = Tracked::constructed;
  EXPECT_FALSE(v.emplace_back(2));
  EXPECT_EQ(Tracked::constructed, before);
}

TEST_F(StaticVectorTest, EmplaceBackConstructsInPlace) {
  StaticVector<Tracked, 4> v;
  ASSERT_TRUE(v.emplace_back(7));
  EXPECT_EQ(Tracked::constructed, 1);
  EXPECT_EQ(Tracked::copies, 0);
  EXPECT_EQ(Tracked::moves, 0);
  EXPECT_EQ(v[0].value, 7);
}

TEST_F(StaticVectorTest, PushBackCopiesOrMoves) {
  StaticVector<Tracked, 4> v;
  Tracked a(1);
  ASSERT_TRUE(v.push_back(a));
  EXPECT_EQ(Tracked::copies, 1);
  ASSERT_TRUE(v.push_back(std::move(a)));
  EXPECT_EQ(Tracked::moves, 1);
  EXPECT_EQ(values(v), (std::vector<int>{1, 1}));
}

TEST_F(StaticVectorTest, PushBackOfOwnElementIsSafe) {
  StaticVector<std::string, 4> v;
  ASSERT_TRUE(v.push_back(std::string(40, 'x')));  // long enough to live on the heap
  ASSERT_TRUE(v.push_back(v[0]));
  EXPECT_EQ(v[1], std::string(40, 'x'));
}

TEST_F(StaticVectorTest, PopBackDestroysLastAndIsANoOpWhenEmpty) {
  StaticVector<Tracked, 4> v;
  ASSERT_TRUE(v.emplace_back(1));
  ASSERT_TRUE(v.emplace_back(2));
  EXPECT_TRUE(v.pop_back());
  EXPECT_EQ(Tracked::live(), 1);
  EXPECT_EQ(values(v), (std::vector<int>{1}));
  EXPECT_TRUE(v.pop_back());
  EXPECT_FALSE(v.pop_back());
  EXPECT_TRUE(v.empty());
  EXPECT_EQ(Tracked::live(), 0);
}

TEST_F(StaticVectorTest, EraseKeepsOrder) {
  StaticVector<Tracked, 8> v;
  for (int i = 0; i < 6; ++i) ASSERT_TRUE(v.emplace_back(i));
  auto next = v.erase(v.begin() + 2);
  EXPECT_EQ(next->value, 3);
  EXPECT_EQ(values(v), (std::vector<int>{0, 1, 3, 4, 5}));
  next = v.erase(v.begin());
  EXPECT_EQ(next->value, 1);
  next = v.erase(v.end() - 1);
  EXPECT_EQ(next, v.end());
  EXPECT_EQ(values(v), (std::vector<int>{1, 3, 4}));
  EXPECT_EQ(Tracked::live(), 3);
}

TEST_F(StaticVectorTest, RangeEraseKeepsOrder) {
  StaticVector<Tracked, 8> v;
  for (int i = 0; i < 8; ++i) ASSERT_TRUE(v.emplace_back(i));
  auto next = v.erase(v.begin() + 1, v.begin() + 4);
  EXPECT_EQ(next->value, 4);
  EXPECT_EQ(values(v), (std::vector<int>{0, 4, 5, 6, 7}));
  EXPECT_EQ(Tracked::live(), 5);
  next = v.erase(v.begin() + 2, v.begin() + 2);  // empty range: nothing happens
  EXPECT_EQ(next->value, 5);
  EXPECT_EQ(v.size(), 5u);
  v.erase(v.begin(), v.end());
  EXPECT_TRUE(v.empty());
  EXPECT_EQ(Tracked::live(), 0);
}

TEST_F(StaticVectorTest, SwapRemoveMovesLastIntoTheHole) {
  StaticVector<Tracked, 8> v;
  for (int i = 0; i < 5; ++i) ASSERT_TRUE(v.emplace_back(i));
  auto at = v.swap_remove(v.begin() + 1);
  EXPECT_EQ(at->value, 4);
  EXPECT_EQ(values(v), (std::vector<int>{0, 4, 2, 3}));
  at = v.swap_remove(v.end() - 1);  // removing the last element moves nothing
  EXPECT_EQ(at, v.end());
  EXPECT_EQ(values(v), (std::vector<int>{0, 4, 2}));
  EXPECT_EQ(Tracked::live(), 3);
}

TEST_F(StaticVectorTest, RemoveIfKeepsOrderAndCounts) {
  StaticVector<Tracked, 8> v;
  for (int i = 0; i < 8; ++i) ASSERT_TRUE(v.emplace_back(i));
  EXPECT_EQ(v.remove_if([](const Tracked& t) { return t.value % 3 == 0; }), 3u);
  EXPECT_EQ(values(v), (std::vector<int>{1, 2, 4, 5, 7}));
  EXPECT_EQ(Tracked::live(), 5);
}

TEST_F(StaticVectorTest, ClearDestroysEveryElementAndAllowsReuse) {
  StaticVector<Tracked, 4> v;
  for (int i = 0; i < 4; ++i) ASSERT_TRUE(v.emplace_back(i));
  v.clear();
  EXPECT_TRUE(v.empty());
  EXPECT_EQ(Tracked::live(), 0);
  for (int i = 0; i < 4; ++i) ASSERT_TRUE(v.emplace_back(10 + i));
  EXPECT_EQ(values(v), (std::vector<int>{10, 11, 12, 13}));
}

TEST_F(StaticVectorTest, DestructorDestroysOnlyLiveElements) {
  {
    StaticVector<Tracked, 16> v;
    for (int i = 0; i < 5; ++i) ASSERT_TRUE(v.emplace_back(i));
  }
  EXPECT_EQ(Tracked::constructed, 5);
  EXPECT_EQ(Tracked::destroyed, 5);
}

TEST_F(StaticVectorTest, CopyConstructionIsDeep) {
  StaticVector<Tracked, 8> a;
  for (int i = 0; i < 3; ++i) ASSERT_TRUE(a.emplace_back(i));
  StaticVector<Tracked, 8> b(a);
  EXPECT_EQ(values(b), values(a));
  b[0].value = 100;
  EXPECT_EQ(a[0].value, 0);
  EXPECT_EQ(Tracked::live(), 6);
}

TEST_F(StaticVectorTest, CopyAssignmentGrowsAndShrinks) {
  StaticVector<Tracked, 8> big;
  StaticVector<Tracked, 8> small;
  for (int i = 0; i < 6; ++i) ASSERT_TRUE(big.emplace_back(i));
  for (int i = 0; i < 2; ++i) ASSERT_TRUE(small.emplace_back(50 + i));

  StaticVector<Tracked, 8> target(small);
  target = big;  // grows: assigns 2, constructs 4
  EXPECT_EQ(values(target), values(big));
  target = small;  // shrinks: assigns 2, destroys 4
  EXPECT_EQ(values(target), values(small));
  EXPECT_EQ(Tracked::live(), 6 + 2 + 2);

  const auto& same = target;
  target = same;  // self-assignment leaves it unchanged
  EXPECT_EQ(values(target), values(small));
}

TEST_F(StaticVectorTest, MoveLeavesSourceWithMovedFromElements) {
  StaticVector<Tracked, 8> a;
  for (int i = 1; i <= 3; ++i) ASSERT_TRUE(a.emplace_back(i));
  StaticVector<Tracked, 8> b(std::move(a));
  EXPECT_EQ(values(b), (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(Tracked::copies, 0);
  EXPECT_EQ(a.size(), 3u);  // NOLINT(bugprone-use-after-move): documented moved-from state
  EXPECT_EQ(a[0].value, -1);

  StaticVector<Tracked, 8> c;
  ASSERT_TRUE(c.emplace_back(9));
  c = std::move(b);
  EXPECT_EQ(values(c), (std::vector<int>{1, 2, 3}));
  EXPECT_EQ(Tracked::copies, 0);
}

TEST_F(StaticVectorTest, HoldsMoveOnlyTypes) {
  StaticVector<std::unique_ptr<int>, 3> v;
  ASSERT_TRUE(v.push_back(std::make_unique<int>(1)));
  ASSERT_TRUE(v.emplace_back(new int(2)));
  StaticVector<std::unique_ptr<int>, 3> w(std::move(v));
  ASSERT_EQ(w.size(), 2u);
  EXPECT_EQ(*w[0], 1);
  EXPECT_EQ(*w[1], 2);
  w.swap_remove(w.begin());
  EXPECT_EQ(*w[0], 2);
}

TEST_F(StaticVectorTest, ConvertsToSpans) {
  StaticVector<int, 8> v;
  for (int i = 0; i < 4; ++i) ASSERT_TRUE(v.push_back(i));
  std::span<int> writable = v;
  writable[1] = 42;
  EXPECT_EQ(v[1], 42);
  const auto& cv = v;
  std::span<const int> readable = cv;
  EXPECT_EQ(readable.size(), 4u);
  EXPECT_EQ(readable.data(), v.data());
  EXPECT_EQ(v.as_span().size(), 4u);
  EXPECT_EQ(cv.as_span()[1], 42);
}

TEST_F(StaticVectorTest, WorksWithStandardAlgorithms) {
  StaticVector<int, 8> v;
  for (int x : {5, 3, 7, 1}) ASSERT_TRUE(v.push_back(x));
  std::sort(v.begin(), v.end());
  EXPECT_TRUE(std::is_sorted(v.begin(), v.end()));
  EXPECT_EQ(v.front(), 1);
  EXPECT_EQ(std::distance(v.cbegin(), v.cend()), 4);
}

TEST_F(StaticVectorTest, EqualityComparesContents) {
  StaticVector<int, 4> a;
  StaticVector<int, 4> b;
  EXPECT_EQ(a, b);
  ASSERT_TRUE(a.push_back(1));
  EXPECT_NE(a, b);
  ASSERT_TRUE(b.push_back(1));
  EXPECT_EQ(a, b);
}

TEST_F(StaticVectorTest, TrivialVectorCopiesByMemcpy) {
  StaticVector<Point, 4> a;
  ASSERT_TRUE(a.push_back({1.0F, 2.0F}));
  ASSERT_TRUE(a.push_back({3.0F, 4.0F}));
  StaticVector<Point, 4> b;
  std::memcpy(static_cast<void*>(&b), &a, sizeof a);
  ASSERT_EQ(b.size(), 2u);
  EXPECT_EQ(b[1].y_m, 4.0F);
  StaticVector<Point, 4> c = a;
  EXPECT_EQ(c[0].x_m, 1.0F);
}

TEST_F(StaticVectorTest, CapacityOneEdge) {
  StaticVector<Tracked, 1> v;
  ASSERT_TRUE(v.emplace_back(1));
  EXPECT_TRUE(v.full());
  EXPECT_FALSE(v.emplace_back(2));
  v.swap_remove(v.begin());
  EXPECT_TRUE(v.empty());
  ASSERT_TRUE(v.emplace_back(3));
  EXPECT_EQ(v.back().value, 3);
}

}  // namespace
}  // namespace sen3bot::mem
