#pragma once
// Fixed arrays taken once from a task's memory resource at init(). Over budget throws
// std::bad_alloc (the one exception the firmware uses); guarded() turns it into a Status.
#include <cstddef>
#include <memory_resource>
#include <new>
#include <span>
#include <type_traits>

#include "sen3bot/hal/result.hpp"

namespace sen3bot::nav {

template <typename T>
std::span<T> allocate_array(std::pmr::memory_resource& resource, std::size_t count) {
  static_assert(std::is_trivially_destructible_v<T>, "arena arrays are never destroyed");
  if (count == 0) return {};
  void* raw = resource.allocate(count * sizeof(T), alignof(T));
  T* items = static_cast<T*>(raw);
  for (std::size_t i = 0; i < count; ++i) ::new (static_cast<void*>(items + i)) T{};
  return {items, count};
}

// Runs an init body that may throw std::bad_alloc, reporting the failure as a Status.
template <typename Body>
Status guarded(const char* what, Body&& body) noexcept {
  try {
    return body();
  } catch (const std::bad_alloc&) {
    return Error::format(Errc::capacity, "%s: memory budget too small", what);
  }
}

}  // namespace sen3bot::nav
