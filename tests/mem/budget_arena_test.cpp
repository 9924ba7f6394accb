#include "sen3bot/mem/budget_arena.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cstddef>
#include <cstdint>
#include <limits>
#include <algorithm>
#include <memory_resource>
#include <new>
#include <set>
#include <string>
#include <vector>

#include "alloc_counter.hpp"

namespace sen3bot::mem {
namespace {

using testing::AllocationScope;

// Hides a constant from the optimiser, which otherwise warns about impossible sizes at compile
// time: here they are the point of the test.
std::size_t opaque(std::size_t value) {
  volatile std::size_t hidden = value;
  return hidden;
}

bool aligned_to(const void* p, std::size_t alignment) {
  return reinterpret_cast<std::uintptr_t>(p) % alignment == 0;
}

// Counts what the arena asks of its upstream.
class CountingResource final : public std::pmr::memory_resource {
 public:
  int allocations = 0;
  int deallocations = 0;
  std::size_t last_alignment = 0;

 private:
  void* do_allocate(std::size_t bytes, std::size_t alignment) override {
    ++allocations;
    last_alignment = alignment;
    return std::pmr::new_delete_resource()->allocate(bytes, alignment);
  }
  void do_deallocate(void* p, std::size_t bytes, std::size_t alignment) override {
    ++deallocations;
    std::pmr::new_delete_resource()->deallocate(p, bytes, alignment);
  }
  bool do_is_equal(const std::pmr::memory_resource& other) const noexcept override {
    return this == &other;
  }
};

TEST(BudgetArenaTest, ReportsNameAndBudget) {
  BudgetArena arena("laser", 65536);
  EXPECT_EQ(arena.name(), "laser");
  EXPECT_EQ(arena.capacity_bytes(), 65536u);
  EXPECT_EQ(arena.used_bytes(), 0u);
  EXPECT_EQ(arena.available_bytes(), 65536u);
  EXPECT_EQ(arena.peak_bytes(), 0u);
  EXPECT_EQ(arena.failure_count(), 0u);
}

TEST(BudgetArenaTest, HonoursEveryAlignment) {
  BudgetArena arena("align", 64 * 1024);
  for (std::size_t alignment : {1, 2, 4, 8, 16, 32, 64, 128, 256, 1024, 4096}) {
    for (std::size_t bytes : {1, 3, 7, 24}) {
      void* odd = arena.allocate(1, 1);  // knock the bump pointer off any alignment
      void* p = arena.allocate(bytes, alignment);
      EXPECT_TRUE(aligned_to(p, alignment)) << "alignment " << alignment << ", size " << bytes;
      EXPECT_TRUE(arena.owns(p));
      EXPECT_NE(p, odd);
    }
  }
}

TEST(BudgetArenaTest, HonoursAlignmentOverAMisalignedCallerBuffer) {
  alignas(64) static std::array<std::byte, 4096 + 1> storage;
  BudgetArena arena("caller", std::span<std::byte>(storage).subspan(1));  // odd start address
  for (std::size_t alignment : {1, 2, 4, 8, 16, 32, 64, 128}) {
    void* p = arena.allocate(5, alignment);
    EXPECT_TRUE(aligned_to(p, alignment)) << alignment;
    EXPECT_TRUE(arena.owns(p));
  }
}

TEST(BudgetArenaTest, AllocationsDoNotOverlap) {
  BudgetArena arena("overlap", 4096);
  std::vector<std::pair<std::uintptr_t, std::uintptr_t>> ranges;
  for (std::size_t i = 1; i <= 40; ++i) {
    const std::size_t bytes = i * 3;
    auto* p = static_cast<std::byte*>(arena.allocate(bytes, std::size_t{1} << (i % 5)));
    std::fill(p, p + bytes, std::byte{0xAB});
    const auto first = reinterpret_cast<std::uintptr_t>(p);
    for (const auto& [a, b] : ranges) ASSERT_TRUE(first >= b || first + bytes <= a);
    ranges.emplace_back(first, first + bytes);
  }
}

TEST(BudgetArenaTest, UsedCountsPaddingAndPeakSurvivesReset) {
  alignas(64) static std::array<std::byte, 1024> storage;
  BudgetArena arena("acct", storage);
  (void)arena.allocate(1, 1);
  EXPECT_EQ(arena.used_bytes(), 1u);
  (void)arena.allocate(8, 8);  // 7 bytes of padding, then 8
  EXPECT_EQ(arena.used_bytes(), 16u);
  (void)arena.allocate(0, 1);  // zero bytes still gets a distinct address
  EXPECT_EQ(arena.used_bytes(), 17u);
  EXPECT_EQ(arena.allocation_count(), 3u);
  void* p = arena.allocate(100, 4);
  arena.deallocate(p, 100, 4);  // monotonic: a no-op
  EXPECT_EQ(arena.used_bytes(), 120u);
  EXPECT_EQ(arena.peak_bytes(), 120u);
  arena.reset();
  EXPECT_EQ(arena.used_bytes(), 0u);
  EXPECT_EQ(arena.peak_bytes(), 120u);
  EXPECT_EQ(arena.allocate(1, 1), storage.data()) << "reset starts again at the beginning";
}

TEST(BudgetArenaTest, ZeroByteRequestsGetDistinctAddresses) {
  BudgetArena arena("zero", 64);
  std::set<void*> seen;
  for (int i = 0; i < 10; ++i) seen.insert(arena.allocate(0, 1));
  EXPECT_EQ(seen.size(), 10u);
}

TEST(BudgetArenaTest, OverBudgetThrowsBadAllocWithAClearMessage) {
  BudgetArena arena("laser", 65536);
  (void)arena.allocate(63000, 1);
  EXPECT_THROW((void)arena.allocate(4096, 8), std::bad_alloc);
  EXPECT_EQ(arena.failure_count(), 1u);
  EXPECT_EQ(arena.last_error().code(), Errc::capacity);
  EXPECT_EQ(arena.last_error().message(),
            "arena 'laser': budget 65536 B exceeded: request of 4096 B (align 8) with 63000 B in use");
  EXPECT_EQ(arena.used_bytes(), 63000u) << "a refused request changes nothing";
  void* fits = arena.allocate(2536, 8);
  EXPECT_TRUE(arena.owns(fits)) << "the exact remainder still fits";
  EXPECT_EQ(arena.available_bytes(), 0u);
}

TEST(BudgetArenaTest, PaddingCanBeWhatExceedsTheBudget) {
  alignas(64) static std::array<std::byte, 64> storage;
  BudgetArena arena("pad", storage);
  (void)arena.allocate(1, 1);
  EXPECT_THROW((void)arena.allocate(60, 8), std::bad_alloc) << "60 B fit, but not after 7 B of padding";
  (void)arena.allocate(63, 1);
  EXPECT_EQ(arena.used_bytes(), 64u);
}

TEST(BudgetArenaTest, HugeRequestsDoNotWrapAround) {
  BudgetArena arena("huge", 1024);
  (void)arena.allocate(10, 1);
  EXPECT_THROW((void)arena.allocate(opaque(std::numeric_limits<std::size_t>::max()), 1), std::bad_alloc);
  EXPECT_THROW((void)arena.allocate(opaque(std::numeric_limits<std::size_t>::max() - 5), 16), std::bad_alloc);
  EXPECT_EQ(arena.used_bytes(), 10u);
}

TEST(BudgetArenaTest, ZeroBudgetRefusesEverything) {
  BudgetArena arena("none", 0);
  EXPECT_THROW((void)arena.allocate(1, 1), std::bad_alloc);
  EXPECT_EQ(arena.last_error().message(),
            "arena 'none': budget 0 B exceeded: request of 1 B (align 1) with 0 B in use");
}

TEST(BudgetArenaTest, LongNamesAreTruncatedNotAllocated) {
  AllocationScope scope;
  BudgetArena arena("a-very-long-arena-name-that-goes-on-and-on", std::span<std::byte>{});
  EXPECT_EQ(arena.name(), "a-very-long-arena-name-that-goe");
  EXPECT_EQ(arena.name().size(), BudgetArena::kNameCapacity - 1);
  EXPECT_EQ(scope.allocations(), 0u);
}

TEST(BudgetArenaTest, TakesOneBlockFromUpstreamAndNothingElse) {
  CountingResource upstream;
  {
    BudgetArena arena("up", 4096, &upstream);
    EXPECT_EQ(upstream.allocations, 1);
    EXPECT_EQ(upstream.last_alignment, BudgetArena::kBlockAlignment);
    for (int i = 0; i < 100; ++i) (void)arena.allocate(16, 8);
    try {
      (void)arena.allocate(8192, 8);
    } catch (const std::bad_alloc&) {
    }
    EXPECT_EQ(upstream.allocations, 1) << "never falls back to upstream";
    EXPECT_EQ(upstream.deallocations, 0);
  }
  EXPECT_EQ(upstream.deallocations, 1);
}

TEST(BudgetArenaTest, OverBudgetNeverTouchesTheHeap) {
  BudgetArena arena("laser", 1024);
  AllocationScope scope;
  for (int i = 0; i < 100; ++i) {
    try {
      (void)arena.allocate(2048, 8);
    } catch (const std::bad_alloc&) {
    }
  }
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(arena.failure_count(), 100u);
}

TEST(BudgetArenaTest, CallerBufferArenaNeverAllocates) {
  AllocationScope scope;
  alignas(64) static std::array<std::byte, 2048> storage;
  {
    BudgetArena arena("static", storage);
    std::pmr::vector<int> v(&arena);
    v.reserve(100);
    for (int i = 0; i < 100; ++i) v.push_back(i);
  }
  EXPECT_EQ(scope.allocations(), 0u);
}

TEST(BudgetArenaTest, IsEqualOnlyToItself) {
  BudgetArena a("a", 16);
  BudgetArena b("b", 16);
  EXPECT_TRUE(a.is_equal(a));
  EXPECT_FALSE(a.is_equal(b));
  EXPECT_FALSE(a.is_equal(*std::pmr::new_delete_resource()));
}

TEST(BudgetArenaTest, PmrVectorGrowsUntilTheBudgetTrips) {
  BudgetArena arena("costmap", 4096);
  std::pmr::vector<std::uint32_t> cells(&arena);
  std::size_t pushed = 0;
  bool tripped = false;
  try {
    for (;;) {
      cells.push_back(static_cast<std::uint32_t>(pushed));
      ++pushed;
    }
  } catch (const std::bad_alloc&) {
    tripped = true;
  }
  ASSERT_TRUE(tripped);
  // Geometric growth: the last successful buffer is at most half of the budget plus the
  // abandoned ones (monotonic arenas do not reuse them).
  EXPECT_GT(pushed, 128u);
  EXPECT_LT(pushed, 1024u);
  EXPECT_EQ(cells.size(), pushed) << "the vector is intact after the failed growth";
  EXPECT_EQ(cells.back(), pushed - 1);
  EXPECT_LE(arena.peak_bytes(), arena.capacity_bytes());
  EXPECT_EQ(arena.failure_count(), 1u);
  EXPECT_EQ(arena.last_error().message().substr(0, 39), "arena 'costmap': budget 4096 B exceeded");
}

TEST(BudgetArenaTest, TryInitTurnsTheBudgetFailureIntoAStatus) {
  BudgetArena arena("costmap", 4096);
  std::pmr::vector<float> layer(&arena);
  const Status status = try_init(arena, [&] { layer.resize(2000); });  // 8000 B
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.error().code(), Errc::capacity);
  EXPECT_EQ(status.error().message(),
            "arena 'costmap': budget 4096 B exceeded: request of 8000 B (align 4) with 0 B in use");
}

TEST(BudgetArenaTest, TryInitPassesSuccessAndReturnedStatusThrough) {
  BudgetArena arena("task", 4096);
  std::pmr::vector<float> layer(&arena);
  EXPECT_TRUE(try_init(arena, [&] { layer.resize(100); }).ok());
  EXPECT_EQ(layer.size(), 100u);
  const Status returned = try_init(arena, [&]() -> Status { return Error(Errc::config, "bad resolution"); });
  ASSERT_FALSE(returned.ok());
  EXPECT_EQ(returned.error().code(), Errc::config);
  EXPECT_EQ(returned.error().message(), "bad resolution");
}

TEST(BudgetArenaTest, TryInitDoesNotBlameTheArenaForAnOlderFailure) {
  BudgetArena arena("task", 64);
  EXPECT_THROW((void)arena.allocate(128, 8), std::bad_alloc);  // an earlier, handled failure
  const Status status = try_init(arena, [] { throw std::bad_alloc(); });
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.error().message(), "arena 'task': init failed: out of memory outside the arena");
}

TEST(BudgetArenaTest, TryInitConvertsLengthError) {
  BudgetArena arena("task", 64);
  std::pmr::vector<double> v(&arena);
  const Status status = try_init(arena, [&] { v.reserve(opaque(v.max_size() + 1)); });
  ASSERT_FALSE(status.ok());
  EXPECT_EQ(status.error().code(), Errc::capacity);
  EXPECT_TRUE(status.error().message().starts_with("arena 'task': init failed: "))
      << status.error().message();
}

TEST(BudgetArenaTest, NestedContainersStayInTheArena) {
  BudgetArena arena("nested", 16 * 1024);
  AllocationScope scope;
  std::pmr::vector<std::pmr::string> names(&arena);  // uses_allocator: strings use the arena too
  for (int i = 0; i < 20; ++i) names.emplace_back(64, 'x');
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_GT(arena.used_bytes(), 20u * 64u);
}

}  // namespace
}  // namespace sen3bot::mem
