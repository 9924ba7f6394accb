#include "allocation_counter.hpp"

#include <atomic>
#include <cstdlib>
#include <new>

namespace {
std::atomic<bool> g_armed{false};
std::atomic<std::uint64_t> g_count{0};

inline void note() noexcept {
  if (g_armed.load(std::memory_order_relaxed)) g_count.fetch_add(1, std::memory_order_relaxed);
}

void* checked(void* p) {
  if (p == nullptr) throw std::bad_alloc();
  return p;
}
}  // namespace

namespace sen3bot::testing {
void AllocationCounter::arm() noexcept {
  g_count.store(0);
  g_armed.store(true);
}
void AllocationCounter::disarm() noexcept { g_armed.store(false); }
std::uint64_t AllocationCounter::count() noexcept { return g_count.load(); }
bool AllocationCounter::counts_malloc() noexcept {
#ifdef SEN3BOT_SANITIZED
  return false;
#else
  return true;
#endif
}
}  // namespace sen3bot::testing

// operator new forwards to malloc; in a sanitizer build that is the sanitizer's malloc, and
// only these operators are counted.
void* operator new(std::size_t n) { note(); return checked(std::malloc(n ? n : 1)); }
void* operator new[](std::size_t n) { note(); return checked(std::malloc(n ? n : 1)); }
void* operator new(std::size_t n, const std::nothrow_t&) noexcept { note(); return std::malloc(n ? n : 1); }
void* operator new[](std::size_t n, const std::nothrow_t&) noexcept { note(); return std::malloc(n ? n : 1); }
void* operator new(std::size_t n, std::align_val_t a) {
  note();
  return checked(std::aligned_alloc(static_cast<std::size_t>(a), (n + static_cast<std::size_t>(a) - 1) & ~(static_cast<std::size_t>(a) - 1)));
}
void* operator new[](std::size_t n, std::align_val_t a) { return operator new(n, a); }
void operator delete(void* p) noexcept { std::free(p); }
void operator delete[](void* p) noexcept { std::free(p); }
void operator delete(void* p, std::size_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t) noexcept { std::free(p); }
void operator delete(void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::align_val_t) noexcept { std::free(p); }
void operator delete(void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }
void operator delete[](void* p, std::size_t, std::align_val_t) noexcept { std::free(p); }

#ifndef SEN3BOT_SANITIZED
// glibc exports its allocator under these names; ours count and forward. (The counted
// operator new calls std::malloc, so one new counts twice; zero is zero either way.)
extern "C" {
void* __libc_malloc(std::size_t);
void* __libc_calloc(std::size_t, std::size_t);
void* __libc_realloc(void*, std::size_t);
void* __libc_memalign(std::size_t, std::size_t);
void __libc_free(void*);

void* malloc(std::size_t n) { note(); return __libc_malloc(n); }
void* calloc(std::size_t n, std::size_t size) { note(); return __libc_calloc(n, size); }
void* realloc(void* p, std::size_t n) { note(); return __libc_realloc(p, n); }
void free(void* p) { __libc_free(p); }
void* memalign(std::size_t alignment, std::size_t n) { note(); return __libc_memalign(alignment, n); }
void* aligned_alloc(std::size_t alignment, std::size_t n) { note(); return __libc_memalign(alignment, n); }
int posix_memalign(void** out, std::size_t alignment, std::size_t n) {
  note();
  void* p = __libc_memalign(alignment, n);
  if (p == nullptr) return 12;  // ENOMEM
  *out = p;
  return 0;
}
}
#endif
