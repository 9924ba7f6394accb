#pragma once
// Counts calls to the global operator new/delete and (outside sanitizer builds, whose runtime
// owns malloc) to malloc, calloc, realloc, aligned_alloc, memalign and posix_memalign, to prove
// that code allocates nothing in steady state. Link the sen3bot_alloc_counter object library
// into a test executable: it replaces those functions with counting ones.
//
//   AllocationScope scope;
//   for (int i = 0; i < 10'000; ++i) task.step();
//   EXPECT_EQ(scope.allocations(), 0u);
//
// Counts are process-wide (all threads). std::pmr resources that forward to operator new
// (new_delete_resource) are counted; a BudgetArena's allocations are not (that is the point).
#include <cstdint>

namespace sen3bot::mem::testing {

struct AllocationStats {
  std::uint64_t allocations = 0;    // calls to any operator new / new[]
  std::uint64_t deallocations = 0;  // calls to any operator delete / delete[] with a non-null pointer
  std::uint64_t bytes = 0;          // bytes requested from operator new
  std::uint64_t malloc_calls = 0;   // C allocation calls, including those behind operator new
};

// False in sanitizer builds: there only operator new is counted.
bool counts_malloc() noexcept;

// Totals since the process started.
AllocationStats allocation_stats() noexcept;

// The difference between now and when the scope was created.
class AllocationScope {
 public:
  AllocationScope() noexcept : start_(allocation_stats()) {}
  [[nodiscard]] std::uint64_t allocations() const noexcept {
    return allocation_stats().allocations - start_.allocations;
  }
  [[nodiscard]] std::uint64_t deallocations() const noexcept {
    return allocation_stats().deallocations - start_.deallocations;
  }
  [[nodiscard]] std::uint64_t bytes() const noexcept { return allocation_stats().bytes - start_.bytes; }
  [[nodiscard]] std::uint64_t malloc_calls() const noexcept {
    return allocation_stats().malloc_calls - start_.malloc_calls;
  }

 private:
  AllocationStats start_;
};

}  // namespace sen3bot::mem::testing
