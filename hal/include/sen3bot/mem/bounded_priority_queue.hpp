#pragma once
// BoundedPriorityQueue<T, N, Compare>: std::priority_queue semantics (top() is the greatest
// element under Compare, so std::less gives a max-queue) over inline storage for N elements.
// push() returns false when full. Never allocates; T's copy/move and Compare must not throw
// (the operations are noexcept).
//
// For a min-queue over integer keys with decrease-key (an A* open list), use BoundedIndexHeap.
#include <algorithm>
#include <cassert>
#include <cstddef>
#include <functional>
#include <optional>
#include <utility>

#include "sen3bot/mem/static_vector.hpp"

namespace sen3bot::mem {

template <typename T, std::size_t N, typename Compare = std::less<T>>
class BoundedPriorityQueue {
 public:
  using value_type = T;
  using size_type = std::size_t;
  using value_compare = Compare;

  BoundedPriorityQueue() noexcept = default;
  explicit BoundedPriorityQueue(const Compare& compare) noexcept : compare_(compare) {}

  [[nodiscard]] static constexpr size_type capacity() noexcept { return N; }
  [[nodiscard]] size_type size() const noexcept { return heap_.size(); }
  [[nodiscard]] bool empty() const noexcept { return heap_.empty(); }
  [[nodiscard]] bool full() const noexcept { return heap_.full(); }

  [[nodiscard]] bool push(const T& value) noexcept { return emplace(value); }
  [[nodiscard]] bool push(T&& value) noexcept { return emplace(std::move(value)); }
  template <typename... Args>
  [[nodiscard]] bool emplace(Args&&... args) noexcept {
    if (!heap_.emplace_back(std::forward<Args>(args)...)) return false;
    std::push_heap(heap_.begin(), heap_.end(), compare_);
    return true;
  }

  // Precondition: !empty() (asserted).
  [[nodiscard]] const T& top() const noexcept { return heap_.front(); }

  // The top element, moved out, or nullopt when empty.
  std::optional<T> pop() noexcept {
    if (heap_.empty()) return std::nullopt;
    std::pop_heap(heap_.begin(), heap_.end(), compare_);
    std::optional<T> out(std::move(heap_.back()));
    heap_.pop_back();
    return out;
  }

  void clear() noexcept { heap_.clear(); }

  // The elements in heap order (not sorted), e.g. for inspection in tests.
  [[nodiscard]] std::span<const T> unordered() const noexcept { return heap_.as_span(); }

 private:
  StaticVector<T, N> heap_;
  [[no_unique_address]] Compare compare_{};
};

}  // namespace sen3bot::mem
