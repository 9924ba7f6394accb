#pragma once
// Counts every heap allocation made by the process while armed: all forms of global operator
// new, and (outside sanitizer builds, whose runtime owns malloc) malloc, calloc, realloc,
// aligned_alloc, posix_memalign and memalign.
#include <cstdint>

namespace sen3bot::testing {

struct AllocationCounter {
  static void arm() noexcept;
  static void disarm() noexcept;
  [[nodiscard]] static std::uint64_t count() noexcept;
  [[nodiscard]] static bool counts_malloc() noexcept;
};

}  // namespace sen3bot::testing
