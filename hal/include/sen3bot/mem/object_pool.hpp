#pragma once
// ObjectPool<T, N>: N inline slots for objects of one type, handed out and taken back in O(1)
// with a free list of slot indices. For things created and destroyed at run time (tracks,
// detections, pending requests) whose maximum count is known. Never allocates, never throws on
// its own; an exhausted pool returns nullptr.
#include <cstddef>
#include <cstdint>
#include <limits>
#include <memory>
#include <type_traits>
#include <utility>

namespace sen3bot::mem {

template <typename T, std::size_t N>
class ObjectPool {
  using Index = std::uint32_t;
  static constexpr Index kEnd = std::numeric_limits<Index>::max();    // end of the free list
  static constexpr Index kInUse = kEnd - 1;                           // marks a live slot
  static_assert(N > 0 && N < kInUse, "pool capacity must fit the 32-bit slot index");
  static_assert(std::is_nothrow_destructible_v<T>, "objects are destroyed on real-time paths");

 public:
  using value_type = T;
  using size_type = std::size_t;

  // Returns an object to its pool when a Handle goes out of scope; no allocation involved.
  class Releaser {
   public:
    Releaser() noexcept = default;
    explicit Releaser(ObjectPool* pool) noexcept : pool_(pool) {}
    void operator()(T* object) const noexcept {
      if (pool_ != nullptr) pool_->release(object);
    }

   private:
    ObjectPool* pool_ = nullptr;
  };
  using Handle = std::unique_ptr<T, Releaser>;

  ObjectPool() noexcept {  // NOLINT: the union member is deliberately left unconstructed
    // Free list 0 -> 1 -> ... -> N-1, so slots are handed out in address order at first.
    for (Index i = 0; i < static_cast<Index>(N); ++i) next_[i] = i + 1;
    next_[N - 1] = kEnd;
  }
  ObjectPool(const ObjectPool&) = delete;  // objects are referred to by address
  ObjectPool& operator=(const ObjectPool&) = delete;
  ~ObjectPool() {
    for (Index i = 0; i < static_cast<Index>(N); ++i) {
      if (next_[i] == kInUse) std::destroy_at(items_ + i);
    }
  }

  [[nodiscard]] static constexpr size_type capacity() noexcept { return N; }
  [[nodiscard]] size_type in_use() const noexcept { return in_use_; }
  [[nodiscard]] size_type available() const noexcept { return N - in_use_; }
  [[nodiscard]] bool exhausted() const noexcept { return in_use_ == N; }

  // Constructs a T in a free slot. nullptr when every slot is in use.
  template <typename... Args>
  [[nodiscard]] T* acquire(Args&&... args) noexcept(std::is_nothrow_constructible_v<T, Args...>) {
    if (free_head_ == kEnd) return nullptr;
    const Index slot = free_head_;
    // Construct before unlinking, so a throwing constructor leaves the pool unchanged.
    T* object = std::construct_at(items_ + slot, std::forward<Args>(args)...);
    free_head_ = next_[slot];
    next_[slot] = kInUse;
    ++in_use_;
    return object;
  }
  // Same, but the object goes back to the pool when the handle is destroyed. An empty handle
  // when the pool is exhausted.
  template <typename... Args>
  [[nodiscard]] Handle acquire_handle(Args&&... args) noexcept(
      std::is_nothrow_constructible_v<T, Args...>) {
    return Handle(acquire(std::forward<Args>(args)...), Releaser(this));
  }

  // Destroys the object and frees its slot. Returns false, doing nothing, for nullptr, for a
  // pointer that is not a slot of this pool, or for a slot that is already free (so a double
  // release cannot corrupt the free list).
  bool release(T* object) noexcept {
    const Index slot = slot_of(object);
    if (slot == kEnd || next_[slot] != kInUse) return false;
    std::destroy_at(items_ + slot);
    next_[slot] = free_head_;  // LIFO: the most recently used (cache-warm) slot goes out next
    free_head_ = slot;
    --in_use_;
    return true;
  }

  // True when object is a live object of this pool.
  [[nodiscard]] bool owns(const T* object) const noexcept {
    const Index slot = slot_of(object);
    return slot != kEnd && next_[slot] == kInUse;
  }
  // The slot number of a pointer into this pool, for compact references (e.g. in messages);
  // npos for a pointer that is not a slot of this pool.
  static constexpr std::size_t npos = std::numeric_limits<std::size_t>::max();
  [[nodiscard]] std::size_t index_of(const T* object) const noexcept {
    const Index slot = slot_of(object);
    return slot == kEnd ? npos : slot;
  }
  // The live object in a slot, or nullptr.
  [[nodiscard]] T* at_index(std::size_t slot) noexcept {
    return slot < N && next_[slot] == kInUse ? items_ + slot : nullptr;
  }

  // Calls f(T&) for every live object, in slot order.
  template <typename F>
  void for_each(F&& f) {
    for (Index i = 0; i < static_cast<Index>(N); ++i) {
      if (next_[i] == kInUse) f(items_[i]);
    }
  }

 private:
  // kEnd for anything that is not exactly the address of one of our slots. Compared as
  // integers because relational comparison of unrelated pointers is unspecified.
  Index slot_of(const T* object) const noexcept {
    const auto address = reinterpret_cast<std::uintptr_t>(object);
    const auto first = reinterpret_cast<std::uintptr_t>(items_);
    if (object == nullptr || address < first) return kEnd;
    const std::uintptr_t offset = address - first;
    if (offset % sizeof(T) != 0 || offset / sizeof(T) >= N) return kEnd;
    return static_cast<Index>(offset / sizeof(T));
  }

  union {
    T items_[N];
  };
  Index next_[N];  // free slot: next free slot (or kEnd); live slot: kInUse
  Index free_head_ = 0;
  size_type in_use_ = 0;
};

}  // namespace sen3bot::mem
