#include "sen3bot/mem/object_pool.hpp"

#include <gtest/gtest.h>

#include <algorithm>
#include <cstdint>
#include <random>
#include <set>
#include <vector>

#include "tracked.hpp"

namespace sen3bot::mem {
namespace {

using testing::Tracked;

class ObjectPoolTest : public testing::TrackedTest {};

TEST_F(ObjectPoolTest, AcquiresUntilExhaustedThenReturnsNull) {
  ObjectPool<Tracked, 3> pool;
  EXPECT_EQ(pool.capacity(), 3u);
  EXPECT_EQ(pool.available(), 3u);
  Tracked* a = pool.acquire(1);
  Tracked* b = pool.acquire(2);
  Tracked* c = pool.acquire(3);
  ASSERT_NE(a, nullptr);
  ASSERT_NE(b, nullptr);
  ASSERT_NE(c, nullptr);
  EXPECT_EQ(a->value, 1);
  EXPECT_EQ(c->value, 3);
  EXPECT_TRUE(pool.exhausted());
  EXPECT_EQ(pool.in_use(), 3u);
  const int before = Tracked::constructed;
  EXPECT_EQ(pool.acquire(4), nullptr);
  EXPECT_EQ(Tracked::constructed, before) << "an exhausted pool must construct nothing";
  EXPECT_EQ(std::set<Tracked*>({a, b, c}).size(), 3u);
}

TEST_F(ObjectPoolTest, ReleaseDestroysAndTheSlotIsReusedFirst) {
  ObjectPool<Tracked, 4> pool;
  Tracked* a = pool.acquire(1);
  Tracked* b = pool.acquire(2);
  ASSERT_TRUE(pool.release(a));
  EXPECT_EQ(Tracked::live(), 1);
  EXPECT_EQ(pool.in_use(), 1u);
  Tracked* again = pool.acquire(3);
  EXPECT_EQ(again, a) << "the most recently released slot is handed out next";
  EXPECT_EQ(again->value, 3);
  EXPECT_TRUE(pool.release(b));
  EXPECT_TRUE(pool.release(again));
  EXPECT_EQ(pool.in_use(), 0u);
  EXPECT_EQ(Tracked::live(), 0);
}

TEST_F(ObjectPoolTest, RejectsNullForeignMisalignedAndDoubleRelease) {
  ObjectPool<Tracked, 4> pool;
  Tracked* a = pool.acquire(1);
  Tracked outside(5);
  EXPECT_FALSE(pool.release(nullptr));
  EXPECT_FALSE(pool.release(&outside));
  auto* inside_a_slot = reinterpret_cast<Tracked*>(reinterpret_cast<char*>(a) + 1);
  EXPECT_FALSE(pool.release(inside_a_slot));
  auto* past_the_pool = reinterpret_cast<Tracked*>(reinterpret_cast<std::uintptr_t>(a) + 100 * sizeof(Tracked));
  EXPECT_FALSE(pool.release(past_the_pool));
  EXPECT_FALSE(pool.release(a + 1)) << "a free slot is not a live object";
  EXPECT_EQ(pool.in_use(), 1u);
  EXPECT_TRUE(pool.release(a));
  EXPECT_FALSE(pool.release(a)) << "double release";
  EXPECT_EQ(pool.in_use(), 0u);
  EXPECT_EQ(pool.available(), 4u);
  // The free list survived: every slot can still be acquired exactly once.
  std::set<Tracked*> slots;
  while (Tracked* p = pool.acquire(0)) slots.insert(p);
  EXPECT_EQ(slots.size(), 4u);
  for (Tracked* p : slots) EXPECT_TRUE(pool.release(p));
}

TEST_F(ObjectPoolTest, DestructorDestroysObjectsStillInUse) {
  {
    ObjectPool<Tracked, 8> pool;
    for (int i = 0; i < 5; ++i) ASSERT_NE(pool.acquire(i), nullptr);
    ASSERT_TRUE(pool.release(pool.at_index(2)));
  }
  EXPECT_EQ(Tracked::constructed, 5);
  EXPECT_EQ(Tracked::destroyed, 5);
}

TEST_F(ObjectPoolTest, HandlesReleaseAutomatically) {
  ObjectPool<Tracked, 2> pool;
  {
    auto a = pool.acquire_handle(1);
    auto b = pool.acquire_handle(2);
    auto c = pool.acquire_handle(3);
    ASSERT_TRUE(a);
    ASSERT_TRUE(b);
    EXPECT_FALSE(c) << "exhausted pool gives an empty handle";
    EXPECT_EQ(pool.in_use(), 2u);
    a.reset();
    EXPECT_EQ(pool.in_use(), 1u);
    auto moved = std::move(b);
    EXPECT_EQ(moved->value, 2);
  }
  EXPECT_EQ(pool.in_use(), 0u);
  EXPECT_EQ(Tracked::live(), 0);
}

TEST_F(ObjectPoolTest, IndexOwnsAndAtIndex) {
  ObjectPool<int, 4> pool;
  int* a = pool.acquire(10);
  int* b = pool.acquire(20);
  EXPECT_EQ(pool.index_of(a), 0u);
  EXPECT_EQ(pool.index_of(b), 1u);
  EXPECT_EQ(pool.at_index(1), b);
  EXPECT_EQ(pool.at_index(2), nullptr) << "free slot";
  EXPECT_EQ(pool.at_index(99), nullptr) << "out of range";
  int outside = 0;
  EXPECT_EQ(pool.index_of(&outside), (ObjectPool<int, 4>::npos));
  EXPECT_TRUE(pool.owns(a));
  EXPECT_FALSE(pool.owns(&outside));
  ASSERT_TRUE(pool.release(a));
  EXPECT_FALSE(pool.owns(a));
}

TEST_F(ObjectPoolTest, ForEachVisitsLiveObjectsInSlotOrder) {
  ObjectPool<Tracked, 6> pool;
  std::vector<Tracked*> all;
  for (int i = 0; i < 6; ++i) all.push_back(pool.acquire(i));
  ASSERT_TRUE(pool.release(all[1]));
  ASSERT_TRUE(pool.release(all[4]));
  std::vector<int> seen;
  pool.for_each([&](Tracked& t) { seen.push_back(t.value); });
  EXPECT_EQ(seen, (std::vector<int>{0, 2, 3, 5}));
}

TEST_F(ObjectPoolTest, RandomAcquireReleaseKeepsSlotsDistinct) {
  constexpr std::size_t kCapacity = 32;
  ObjectPool<Tracked, kCapacity> pool;
  std::vector<Tracked*> live;
  std::mt19937_64 rng(1);
  int next = 0;
  for (int step = 0; step < 50'000; ++step) {
    if (rng() % 2 == 0) {
      Tracked* p = pool.acquire(next);
      if (live.size() == kCapacity) {
        ASSERT_EQ(p, nullptr);
      } else {
        ASSERT_NE(p, nullptr);
        ASSERT_EQ(std::find(live.begin(), live.end(), p), live.end()) << "slot handed out twice";
        live.push_back(p);
        ++next;
      }
    } else if (!live.empty()) {
      const std::size_t i = rng() % live.size();
      ASSERT_TRUE(pool.release(live[i]));
      live[i] = live.back();
      live.pop_back();
    }
    ASSERT_EQ(pool.in_use(), live.size());
    ASSERT_EQ(Tracked::live(), static_cast<int>(live.size()));
  }
  for (Tracked* p : live) ASSERT_TRUE(pool.release(p));
}

}  // namespace
}  // namespace sen3bot::mem
