#pragma once
// BoundedIndexHeap<Priority, Compare>: an indexed binary min-heap over the integer keys
// 0..capacity()-1, each present at most once, with decrease-key. It is an A* open list over
// grid cells: key = cell index, priority = f cost. The capacity comes from configuration at
// init(); the storage is either given by the caller or taken once from a memory resource
// (a BudgetArena), so a search allocates nothing.
//
// Memory: capacity * (sizeof(Node) + sizeof(Key)) bytes; storage_bytes() computes it. With a
// float priority that is 12 B per key (8 B node + 4 B position).
//
// Ordering is deterministic: the smallest priority under Compare comes first and, on equal
// priorities, the LOWER KEY comes first. The pop order therefore depends only on the set of
// (key, priority) pairs, never on the order of pushes or updates, so a planner's result is
// reproducible. Priorities must be totally ordered under Compare (no NaN). Compare must not throw.
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <functional>
#include <limits>
#include <memory>
#include <memory_resource>
#include <new>
#include <optional>
#include <span>
#include <type_traits>
#include <utility>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/mem/budget_arena.hpp"

namespace sen3bot::mem {

template <typename Priority, typename Compare = std::less<Priority>>
class BoundedIndexHeap {
  static_assert(std::is_trivially_copyable_v<Priority>,
                "nodes live in raw storage and move by copy: use a number or a small POD");

 public:
  using Key = std::uint32_t;
  struct Node {
    Priority priority;
    Key key;
  };
  static constexpr Key kNotQueued = std::numeric_limits<Key>::max();  // position of an absent key
  static constexpr std::size_t kMaxCapacity = kNotQueued;

  BoundedIndexHeap() noexcept = default;
  explicit BoundedIndexHeap(const Compare& compare) noexcept : compare_(compare) {}
  BoundedIndexHeap(const BoundedIndexHeap&) = delete;
  BoundedIndexHeap& operator=(const BoundedIndexHeap&) = delete;
  BoundedIndexHeap(BoundedIndexHeap&& other) noexcept { take(other); }
  BoundedIndexHeap& operator=(BoundedIndexHeap&& other) noexcept {
    if (this != &other) {
      release_storage();
      take(other);
    }
    return *this;
  }
  ~BoundedIndexHeap() { release_storage(); }

  // Bytes of storage init() needs for a capacity, for sizing the arena it comes from.
  [[nodiscard]] static constexpr std::size_t storage_bytes(std::size_t capacity) noexcept {
    return capacity * (sizeof(Node) + sizeof(Key));
  }

  // Uses caller storage, which must outlive the heap (or the next init()). The capacity is
  // positions.size(); nodes must have at least as many elements.
  Status init(std::span<Node> nodes, std::span<Key> positions) noexcept {
    release_storage();
    if (positions.size() > kMaxCapacity) {
      return Error::format(Errc::invalid_argument, "index heap: capacity %zu exceeds the maximum %zu",
                           positions.size(), kMaxCapacity);
    }
    if (nodes.size() < positions.size()) {
      return Error::format(Errc::invalid_argument,
                           "index heap: %zu node slots for a capacity of %zu keys", nodes.size(),
                           positions.size());
    }
    adopt(nodes.data(), positions.data(), positions.size());
    return Status::success();
  }

  // Takes storage for capacity keys from resource, once; it is returned to resource by the
  // destructor or the next init(), so resource must outlive the heap (declare it first). Over budget is a failed Status (the arena's message when
  // resource is a BudgetArena), not an exception.
  Status init(std::size_t capacity, std::pmr::memory_resource* resource) noexcept {
    release_storage();
    if (capacity > kMaxCapacity) {
      return Error::format(Errc::invalid_argument, "index heap: capacity %zu exceeds the maximum %zu",
                           capacity, kMaxCapacity);
    }
    if (capacity == 0) return Status::success();
    auto* arena = dynamic_cast<BudgetArena*>(resource);
    const std::size_t failures_before = arena != nullptr ? arena->failure_count() : 0;
    void* nodes = nullptr;
    try {
      nodes = resource->allocate(capacity * sizeof(Node), alignof(Node));
      void* positions = resource->allocate(capacity * sizeof(Key), alignof(Key));
      adopt(static_cast<Node*>(nodes), static_cast<Key*>(positions), capacity);
      resource_ = resource;
      return Status::success();
    } catch (const std::bad_alloc&) {
      if (nodes != nullptr) resource->deallocate(nodes, capacity * sizeof(Node), alignof(Node));
      if (arena != nullptr && arena->failure_count() != failures_before) return arena->last_error();
      return Error::format(Errc::capacity, "index heap: cannot allocate %zu B for %zu keys",
                           storage_bytes(capacity), capacity);
    }
  }

  [[nodiscard]] std::size_t capacity() const noexcept { return capacity_; }
  [[nodiscard]] std::size_t size() const noexcept { return size_; }
  [[nodiscard]] bool empty() const noexcept { return size_ == 0; }

  [[nodiscard]] bool contains(Key key) const noexcept {
    return key < capacity_ && positions_[key] != kNotQueued;
  }
  // Precondition: contains(key) (asserted).
  [[nodiscard]] const Priority& priority(Key key) const noexcept {
    assert(contains(key));
    return nodes_[positions_[key]].priority;
  }

  // Inserts key. False (no change) when key >= capacity() or key is already queued.
  [[nodiscard]] bool push(Key key, const Priority& priority) noexcept {
    if (key >= capacity_ || positions_[key] != kNotQueued) return false;
    const std::size_t hole = size_++;
    std::construct_at(nodes_ + hole, Node{priority, key});
    positions_[key] = static_cast<Key>(hole);
    sift_up(hole);
    return true;
  }

  // Sets the priority of a queued key, up or down. False when key is not queued.
  bool update(Key key, const Priority& priority) noexcept {
    if (!contains(key)) return false;
    const std::size_t at = positions_[key];
    const bool earlier = compare_(priority, nodes_[at].priority);
    nodes_[at].priority = priority;
    if (earlier) {
      sift_up(at);
    } else {
      sift_down(at);
    }
    return true;
  }

  // Lowers the priority of a queued key. False when key is not queued or priority is not
  // strictly earlier than its current one.
  bool decrease(Key key, const Priority& priority) noexcept {
    if (!contains(key) || !compare_(priority, nodes_[positions_[key]].priority)) return false;
    return update(key, priority);
  }

  // The A* "relax" step: queue key if absent, lower its priority if queued with a later one.
  // True when the heap changed.
  bool push_or_decrease(Key key, const Priority& priority) noexcept {
    return contains(key) ? decrease(key, priority) : push(key, priority);
  }

  // Removes a queued key. False when key is not queued.
  bool erase(Key key) noexcept {
    if (!contains(key)) return false;
    const std::size_t at = positions_[key];
    positions_[key] = kNotQueued;
    --size_;
    if (at != size_) {
      // Fill the hole with the last node, which may belong above or below it.
      nodes_[at] = nodes_[size_];
      positions_[nodes_[at].key] = static_cast<Key>(at);
      sift_up(at);
      sift_down(positions_[nodes_[at].key]);
    }
    return true;
  }

  // Precondition: !empty() (asserted).
  [[nodiscard]] const Node& top() const noexcept {
    assert(!empty());
    return nodes_[0];
  }

  // The first node, removed, or nullopt when empty.
  std::optional<Node> pop() noexcept {
    if (empty()) return std::nullopt;
    const Node first = nodes_[0];
    erase(first.key);
    return first;
  }

  // O(size()): only queued keys have positions to forget.
  void clear() noexcept {
    for (std::size_t i = 0; i < size_; ++i) positions_[nodes_[i].key] = kNotQueued;
    size_ = 0;
  }

 private:
  // The heap order: priority first, then the lower key (see the header comment).
  bool before(const Node& a, const Node& b) const noexcept {
    if (compare_(a.priority, b.priority)) return true;
    if (compare_(b.priority, a.priority)) return false;
    return a.key < b.key;
  }

  void sift_up(std::size_t at) noexcept {
    const Node moving = nodes_[at];
    while (at > 0) {
      const std::size_t parent = (at - 1) / 2;
      if (!before(moving, nodes_[parent])) break;
      place(at, nodes_[parent]);
      at = parent;
    }
    place(at, moving);
  }

  void sift_down(std::size_t at) noexcept {
    const Node moving = nodes_[at];
    for (;;) {
      std::size_t child = 2 * at + 1;
      if (child >= size_) break;
      if (child + 1 < size_ && before(nodes_[child + 1], nodes_[child])) ++child;
      if (!before(nodes_[child], moving)) break;
      place(at, nodes_[child]);
      at = child;
    }
    place(at, moving);
  }

  void place(std::size_t at, const Node& node) noexcept {
    nodes_[at] = node;
    positions_[node.key] = static_cast<Key>(at);
  }

  void adopt(Node* nodes, Key* positions, std::size_t capacity) noexcept {
    nodes_ = nodes;
    positions_ = positions;
    capacity_ = capacity;
    size_ = 0;
    std::uninitialized_fill_n(positions_, capacity, kNotQueued);
  }

  void take(BoundedIndexHeap& other) noexcept {
    nodes_ = std::exchange(other.nodes_, nullptr);
    positions_ = std::exchange(other.positions_, nullptr);
    capacity_ = std::exchange(other.capacity_, 0);
    size_ = std::exchange(other.size_, 0);
    resource_ = std::exchange(other.resource_, nullptr);
    compare_ = other.compare_;
  }

  void release_storage() noexcept {
    if (resource_ != nullptr) {
      resource_->deallocate(positions_, capacity_ * sizeof(Key), alignof(Key));
      resource_->deallocate(nodes_, capacity_ * sizeof(Node), alignof(Node));
    }
    nodes_ = nullptr;
    positions_ = nullptr;
    capacity_ = 0;
    size_ = 0;
    resource_ = nullptr;
  }

  Node* nodes_ = nullptr;
  Key* positions_ = nullptr;  // positions_[key]: index of key's node in nodes_, or kNotQueued
  std::size_t capacity_ = 0;
  std::size_t size_ = 0;
  std::pmr::memory_resource* resource_ = nullptr;  // owner of the storage, or nullptr
  [[no_unique_address]] Compare compare_{};
};

}  // namespace sen3bot::mem
