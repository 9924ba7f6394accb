// The firmware rule: memory is taken at start-up, steady state allocates nothing. These tests
// run each container's steady-state operations many times under a counting global operator new
// (tests/support/alloc_counter.cpp) and require zero calls. A positive control proves the counter sees
// allocations at all.
#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <memory_resource>
#include <new>
#include <string>
#include <type_traits>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/mem/bounded_index_heap.hpp"
#include "sen3bot/mem/bounded_priority_queue.hpp"
#include "sen3bot/mem/budget_arena.hpp"
#include "sen3bot/mem/object_pool.hpp"
#include "sen3bot/mem/ring_buffer.hpp"
#include "sen3bot/mem/spsc_ring.hpp"
#include "sen3bot/mem/static_vector.hpp"

namespace sen3bot::mem {
namespace {

using testing::AllocationScope;

// --- compile-time evidence: inline storage, no allocator anywhere -------------------------------

template <typename C>
concept HasAllocator = requires { typename C::allocator_type; };

static_assert(!HasAllocator<StaticVector<int, 4>>);
static_assert(!HasAllocator<RingBuffer<int, 4>>);
static_assert(!HasAllocator<SpscRing<int, 4>>);
static_assert(!HasAllocator<ObjectPool<int, 4>>);
static_assert(!HasAllocator<BoundedPriorityQueue<int, 4>>);

// The elements live inside the object.
static_assert(sizeof(StaticVector<int, 64>) >= 64 * sizeof(int));
static_assert(sizeof(RingBuffer<int, 64>) >= 64 * sizeof(int));
static_assert(sizeof(SpscRing<int, 64>) >= 64 * sizeof(int));
static_assert(sizeof(ObjectPool<int, 64>) >= 64 * sizeof(int));
static_assert(sizeof(BoundedPriorityQueue<int, 64>) >= 64 * sizeof(int));

// Trivially copyable containers of PODs hold no pointer to anything they own.
struct Sample {
  double range_m;
  float bearing_rad;
};
static_assert(std::is_trivially_copyable_v<StaticVector<Sample, 361>>);
static_assert(std::is_trivially_copyable_v<RingBuffer<Sample, 16, WhenFull::overwrite_oldest>>);

// Steady-state operations are noexcept for nothrow element types.
static_assert(noexcept(std::declval<StaticVector<Sample, 4>&>().push_back(Sample{})));
static_assert(noexcept(std::declval<RingBuffer<Sample, 4>&>().push(Sample{})));
static_assert(noexcept(std::declval<RingBuffer<Sample, 4>&>().pop()));
static_assert(noexcept(std::declval<SpscRing<Sample, 4>&>().try_push(Sample{})));
static_assert(noexcept(std::declval<SpscRing<Sample, 4>&>().try_pop()));
static_assert(noexcept(std::declval<ObjectPool<Sample, 4>&>().acquire()));
static_assert(noexcept(std::declval<ObjectPool<Sample, 4>&>().release(nullptr)));
static_assert(noexcept(std::declval<BoundedPriorityQueue<int, 4>&>().push(1)));
static_assert(noexcept(std::declval<BoundedIndexHeap<float>&>().push_or_decrease(0, 1.0F)));
static_assert(noexcept(std::declval<BoundedIndexHeap<float>&>().pop()));

constexpr int kTicks = 10'000;

// --- the counter works -------------------------------------------------------------------------

TEST(NoAllocationTest, CounterSeesEveryKindOfOperatorNew) {
  AllocationScope scope;
  std::vector<int> grows;
  for (int i = 0; i < 100; ++i) grows.push_back(i);
  EXPECT_GT(scope.allocations(), 0u);

  // Direct calls, because the compiler may elide a new-expression paired with its delete.
  AllocationScope forms;
  ::operator delete(::operator new(8));
  ::operator delete[](::operator new[](8));
  ::operator delete(::operator new(8, std::nothrow), std::nothrow);
  ::operator delete(::operator new(128, std::align_val_t{128}), std::align_val_t{128});
  ::operator delete[](::operator new[](256, std::align_val_t{64}), std::align_val_t{64});
  auto* pmr = std::pmr::new_delete_resource();
  pmr->deallocate(pmr->allocate(16, 8), 16, 8);
  const auto allocations = forms.allocations();  // read both before any assertion output
  const auto deallocations = forms.deallocations();
  EXPECT_EQ(allocations, 6u);
  EXPECT_EQ(deallocations, 6u);
}

// --- each container in steady state ------------------------------------------------------------

TEST(NoAllocationTest, StaticVector) {
  StaticVector<std::string, 16> names;  // short strings fit std::string's inline buffer
  AllocationScope scope;
  for (int tick = 0; tick < kTicks; ++tick) {
    while (names.emplace_back("cell")) {
    }
    names.erase(names.begin() + 3);
    names.swap_remove(names.begin());
    names.remove_if([](const std::string& s) { return s.empty(); });
    StaticVector<std::string, 16> copy = names;
    names = std::move(copy);
    names.clear();
  }
  EXPECT_EQ(scope.allocations(), 0u);
}

TEST(NoAllocationTest, RingBuffers) {
  RingBuffer<Sample, 32> commands;
  RingBuffer<Sample, 32, WhenFull::overwrite_oldest> history;
  AllocationScope scope;
  for (int tick = 0; tick < kTicks; ++tick) {
    for (int i = 0; i < 40; ++i) {
      commands.push(Sample{1.0, 0.5F});
      history.push(Sample{2.0, 0.25F});
    }
    double sum_m = 0;
    for (const Sample& s : history) sum_m += s.range_m;
    EXPECT_GT(sum_m, 0.0);
    while (commands.pop()) {
    }
  }
  EXPECT_EQ(scope.allocations(), 0u);
}

TEST(NoAllocationTest, SpscRing) {
  SpscRing<Sample, 64> queue;
  AllocationScope scope;
  for (int tick = 0; tick < kTicks; ++tick) {
    while (queue.try_push(Sample{1.0, 0.0F})) {
    }
    Sample out{};
    while (queue.try_pop(out)) {
    }
  }
  EXPECT_EQ(scope.allocations(), 0u);
}

TEST(NoAllocationTest, ObjectPool) {
  ObjectPool<Sample, 32> pool;
  std::array<Sample*, 32> taken{};
  AllocationScope scope;
  for (int tick = 0; tick < kTicks; ++tick) {
    for (auto& p : taken) p = pool.acquire(Sample{3.0, 1.0F});
    EXPECT_EQ(pool.acquire(), nullptr);
    for (Sample* p : taken) pool.release(p);
    auto handle = pool.acquire_handle();
    EXPECT_TRUE(handle);
  }
  EXPECT_EQ(scope.allocations(), 0u);
}

TEST(NoAllocationTest, BoundedPriorityQueue) {
  BoundedPriorityQueue<std::uint32_t, 128> queue;
  std::uint32_t x = 1;
  AllocationScope scope;
  for (int tick = 0; tick < kTicks; ++tick) {
    while (queue.push(x = x * 1664525U + 1013904223U)) {
    }
    while (queue.pop()) {
    }
  }
  EXPECT_EQ(scope.allocations(), 0u);
}

// A whole A*-style search per tick over a 100x100 grid with the heap as the open list and every
// other buffer from the same arena, all sized at "start-up".
TEST(NoAllocationTest, GridSearchWithIndexHeapFromAnArena) {
  constexpr std::uint32_t kWidth = 100;
  constexpr std::uint32_t kCells = kWidth * kWidth;
  using Heap = BoundedIndexHeap<std::uint32_t>;
  BudgetArena arena("planner", Heap::storage_bytes(kCells) + kCells * sizeof(std::uint32_t) + 256);
  Heap open;
  std::pmr::vector<std::uint32_t> g_cost(&arena);
  const Status init = try_init(arena, [&]() -> Status {
    g_cost.resize(kCells);
    return open.init(kCells, &arena);
  });
  ASSERT_TRUE(init.ok()) << init.error().message();

  AllocationScope scope;
  std::uint64_t expanded = 0;
  std::uint64_t decreases = 0;
  for (int tick = 0; tick < 20; ++tick) {
    std::fill(g_cost.begin(), g_cost.end(), UINT32_MAX);
    open.clear();
    g_cost[0] = 0;
    (void)open.push(0, 0);
    while (auto node = open.pop()) {
      ++expanded;
      const std::uint32_t x = node->key % kWidth;
      const std::uint32_t y = node->key / kWidth;
      const auto relax = [&](std::uint32_t next) {
        // A hashed cost per directed edge, so cells are often improved after being queued.
        std::uint32_t h = node->key * 0x9E3779B1U ^ (next + 0x7F4A7C15U) * 0x85EBCA77U;
        h ^= h >> 15;
        const std::uint32_t g = g_cost[node->key] + 1 + h % 9;
        if (g < g_cost[next]) {
          g_cost[next] = g;
          if (open.contains(next)) ++decreases;
          open.push_or_decrease(next, g);
        }
      };
      if (x > 0) relax(node->key - 1);
      if (x + 1 < kWidth) relax(node->key + 1);
      if (y > 0) relax(node->key - kWidth);
      if (y + 1 < kWidth) relax(node->key + kWidth);
    }
  }
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(expanded, 20u * kCells);
  EXPECT_GT(decreases, 0u) << "the search should exercise decrease-key";
}

TEST(NoAllocationTest, PmrContainersInAnArenaAfterInit) {
  BudgetArena arena("scan", 64 * 1024);
  std::pmr::vector<float> ranges_m(&arena);
  ASSERT_TRUE(try_init(arena, [&] { ranges_m.reserve(361); }).ok());
  AllocationScope scope;
  for (int tick = 0; tick < kTicks; ++tick) {
    ranges_m.clear();
    for (int i = 0; i < 361; ++i) ranges_m.push_back(static_cast<float>(i));
  }
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(arena.allocation_count(), 1u) << "reserved once, never regrown";
}

}  // namespace
}  // namespace sen3bot::mem
