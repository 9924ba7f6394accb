#pragma once
// RingBuffer<T, N>: a single-threaded FIFO with inline storage for N elements. What happens
// when it is full is part of the type: a command queue rejects new items, a history/log ring
// overwrites the oldest. Never allocates; never throws on its own. For a thread hand-off use
// SpscRing (spsc_ring.hpp).
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <iterator>
#include <memory>
#include <optional>
#include <type_traits>
#include <utility>

namespace sen3bot::mem {

enum class WhenFull : unsigned char {
  reject,            // push() leaves the buffer unchanged and returns false
  overwrite_oldest,  // push() destroys the oldest element to make room and returns false
};

template <typename T, std::size_t N, WhenFull Policy = WhenFull::reject>
class RingBuffer {
  static_assert(N > 0, "a RingBuffer needs room for at least one element");
  static_assert(std::is_nothrow_destructible_v<T>, "elements are destroyed on real-time paths");

  static constexpr bool kTriviallyCopyAssignable =
      std::is_trivially_copy_assignable_v<T> && std::is_trivially_copy_constructible_v<T> &&
      std::is_trivially_destructible_v<T>;
  static constexpr bool kTriviallyMoveAssignable =
      std::is_trivially_move_assignable_v<T> && std::is_trivially_move_constructible_v<T> &&
      std::is_trivially_destructible_v<T>;

  template <bool Const>
  class Iterator;

 public:
  using value_type = T;
  using size_type = std::size_t;
  using difference_type = std::ptrdiff_t;
  using reference = T&;
  using const_reference = const T&;
  using iterator = Iterator<false>;
  using const_iterator = Iterator<true>;

  static constexpr WhenFull kWhenFull = Policy;

  RingBuffer() noexcept {}  // NOLINT: the union member is deliberately left unconstructed

  // Copy and move follow T (trivial for trivially copyable T). A moved-from ring keeps its
  // size and holds moved-from elements.
  RingBuffer(const RingBuffer&) requires std::is_trivially_copy_constructible_v<T> = default;
  RingBuffer(const RingBuffer& other) noexcept(std::is_nothrow_copy_constructible_v<T>)
    requires(std::is_copy_constructible_v<T> && !std::is_trivially_copy_constructible_v<T>)
      : RingBuffer() {  // delegating: if a copy throws, the destructor cleans up
    for (const T& item : other) unchecked_emplace(item);
    dropped_ = other.dropped_;
  }
  RingBuffer(RingBuffer&&) requires std::is_trivially_move_constructible_v<T> = default;
  RingBuffer(RingBuffer&& other) noexcept(std::is_nothrow_move_constructible_v<T>)
    requires(std::is_move_constructible_v<T> && !std::is_trivially_move_constructible_v<T>)
      : RingBuffer() {
    for (T& item : other) unchecked_emplace(std::move(item));
    dropped_ = other.dropped_;
  }

  RingBuffer& operator=(const RingBuffer&) requires kTriviallyCopyAssignable = default;
  RingBuffer& operator=(const RingBuffer& other) noexcept(std::is_nothrow_copy_constructible_v<T>)
    requires(std::is_copy_constructible_v<T> && !kTriviallyCopyAssignable)
  {
    if (this != &other) {
      clear();
      for (const T& item : other) unchecked_emplace(item);
      dropped_ = other.dropped_;
    }
    return *this;
  }
  RingBuffer& operator=(RingBuffer&&) requires kTriviallyMoveAssignable = default;
  RingBuffer& operator=(RingBuffer&& other) noexcept(std::is_nothrow_move_constructible_v<T>)
    requires(std::is_move_constructible_v<T> && !kTriviallyMoveAssignable)
  {
    if (this != &other) {
      clear();
      for (T& item : other) unchecked_emplace(std::move(item));
      dropped_ = other.dropped_;
    }
    return *this;
  }

  ~RingBuffer() requires std::is_trivially_destructible_v<T> = default;
  ~RingBuffer() { clear(); }

  // --- capacity -------------------------------------------------------------------------------
  [[nodiscard]] static constexpr size_type capacity() noexcept { return N; }
  [[nodiscard]] size_type size() const noexcept { return size_; }
  [[nodiscard]] bool empty() const noexcept { return size_ == 0; }
  [[nodiscard]] bool full() const noexcept { return size_ == N; }
  // Elements lost because the ring was full (rejected or overwritten) since construction.
  [[nodiscard]] std::uint64_t dropped() const noexcept { return dropped_; }

  // --- adding -----------------------------------------------------------------------------------
  // Returns true when nothing was lost. When full: with WhenFull::reject the new element is
  // not stored; with WhenFull::overwrite_oldest the oldest element is destroyed and the new one
  // stored. Either way the loss is counted in dropped().
  bool push(const T& value) noexcept(std::is_nothrow_copy_constructible_v<T>) { return emplace(value); }
  bool push(T&& value) noexcept(std::is_nothrow_move_constructible_v<T>) {
    return emplace(std::move(value));
  }
  template <typename... Args>
  bool emplace(Args&&... args) noexcept(std::is_nothrow_constructible_v<T, Args...>) {
    if (!full()) {
      unchecked_emplace(std::forward<Args>(args)...);
      return true;
    }
    ++dropped_;
    if constexpr (Policy == WhenFull::overwrite_oldest) {
      // The new element goes where the oldest was; construct it first so that the args may
      // still refer to the oldest element.
      T replacement(std::forward<Args>(args)...);
      std::destroy_at(items_ + head_);
      std::construct_at(items_ + head_, std::move(replacement));
      head_ = wrap(head_ + 1);
    }
    return false;
  }

  // --- removing (oldest first) ------------------------------------------------------------------
  // The oldest element, moved out, or nullopt when empty.
  std::optional<T> pop() noexcept(std::is_nothrow_move_constructible_v<T>) {
    if (empty()) return std::nullopt;
    std::optional<T> out(std::move(items_[head_]));
    drop_front();
    return out;
  }
  // Destroys the oldest element; false when empty.
  bool drop_front() noexcept {
    if (empty()) return false;
    std::destroy_at(items_ + head_);
    head_ = wrap(head_ + 1);
    --size_;
    return true;
  }
  void clear() noexcept {
    while (drop_front()) {
    }
    head_ = 0;
  }

  // --- access: i counts from the oldest (0) to the newest (size() - 1); preconditions asserted --
  [[nodiscard]] T& at(size_type i) noexcept {
    assert(i < size_);
    return items_[wrap(head_ + i)];
  }
  [[nodiscard]] const T& at(size_type i) const noexcept {
    assert(i < size_);
    return items_[wrap(head_ + i)];
  }
  [[nodiscard]] T& operator[](size_type i) noexcept { return at(i); }
  [[nodiscard]] const T& operator[](size_type i) const noexcept { return at(i); }
  [[nodiscard]] T& front() noexcept { return at(0); }
  [[nodiscard]] const T& front() const noexcept { return at(0); }
  [[nodiscard]] T& back() noexcept { return at(size_ - 1); }
  [[nodiscard]] const T& back() const noexcept { return at(size_ - 1); }

  // Oldest to newest.
  [[nodiscard]] iterator begin() noexcept { return {this, 0}; }
  [[nodiscard]] iterator end() noexcept { return {this, size_}; }
  [[nodiscard]] const_iterator begin() const noexcept { return {this, 0}; }
  [[nodiscard]] const_iterator end() const noexcept { return {this, size_}; }
  [[nodiscard]] const_iterator cbegin() const noexcept { return begin(); }
  [[nodiscard]] const_iterator cend() const noexcept { return end(); }

 private:
  template <bool Const>
  class Iterator {
    using Ring = std::conditional_t<Const, const RingBuffer, RingBuffer>;

   public:
    using iterator_category = std::forward_iterator_tag;
    using value_type = T;
    using difference_type = std::ptrdiff_t;
    using reference = std::conditional_t<Const, const T&, T&>;
    using pointer = std::conditional_t<Const, const T*, T*>;

    Iterator() noexcept = default;
    Iterator(Ring* ring, size_type index) noexcept : ring_(ring), index_(index) {}
    // iterator -> const_iterator (a template, so it is never mistaken for the copy constructor)
    template <bool OtherConst>
      requires(Const && !OtherConst)
    Iterator(const Iterator<OtherConst>& other) noexcept  // NOLINT(implicit)
        : ring_(other.ring_), index_(other.index_) {}

    reference operator*() const noexcept { return ring_->at(index_); }
    pointer operator->() const noexcept { return &ring_->at(index_); }
    Iterator& operator++() noexcept {
      ++index_;
      return *this;
    }
    Iterator operator++(int) noexcept {
      Iterator before = *this;
      ++index_;
      return before;
    }
    friend bool operator==(const Iterator& a, const Iterator& b) noexcept {
      return a.ring_ == b.ring_ && a.index_ == b.index_;
    }

   private:
    friend class Iterator<!Const>;
    Ring* ring_ = nullptr;
    size_type index_ = 0;
  };

  // head_ < N and i < N, so one conditional subtraction replaces a division.
  static size_type wrap(size_type i) noexcept { return i >= N ? i - N : i; }

  template <typename... Args>
  void unchecked_emplace(Args&&... args) noexcept(std::is_nothrow_constructible_v<T, Args...>) {
    std::construct_at(items_ + wrap(head_ + size_), std::forward<Args>(args)...);
    ++size_;
  }

  union {
    T items_[N];
  };
  size_type head_ = 0;  // slot of the oldest element
  size_type size_ = 0;
  std::uint64_t dropped_ = 0;
};

}  // namespace sen3bot::mem
