#pragma once
// StaticVector<T, N>: a vector with inline storage for at most N elements. It never allocates
// and never throws on its own: a full vector is reported by push_back/emplace_back returning
// false. For a trivially copyable T the whole vector is trivially copyable, so it can sit in a
// message that crosses the real-time boundary.
#include <algorithm>
#include <cassert>
#include <cstddef>
#include <memory>
#include <span>
#include <type_traits>
#include <utility>

namespace sen3bot::mem {

template <typename T, std::size_t N>
class StaticVector {
  static_assert(N > 0, "a StaticVector needs room for at least one element");
  static_assert(std::is_nothrow_destructible_v<T>, "elements are destroyed on real-time paths");

  static constexpr bool kTriviallyCopyAssignable =
      std::is_trivially_copy_assignable_v<T> && std::is_trivially_copy_constructible_v<T> &&
      std::is_trivially_destructible_v<T>;
  static constexpr bool kTriviallyMoveAssignable =
      std::is_trivially_move_assignable_v<T> && std::is_trivially_move_constructible_v<T> &&
      std::is_trivially_destructible_v<T>;

 public:
  using value_type = T;
  using size_type = std::size_t;
  using difference_type = std::ptrdiff_t;
  using reference = T&;
  using const_reference = const T&;
  using pointer = T*;
  using const_pointer = const T*;
  using iterator = T*;
  using const_iterator = const T*;

  StaticVector() noexcept {}  // NOLINT: the union member is deliberately left unconstructed

  // Copy and move follow T: trivial when T's are, so a vector of PODs stays trivially copyable.
  // A moved-from vector keeps its size and holds moved-from elements (as std::array does).
  StaticVector(const StaticVector&) requires std::is_trivially_copy_constructible_v<T> = default;
  StaticVector(const StaticVector& other) noexcept(std::is_nothrow_copy_constructible_v<T>)
    requires(std::is_copy_constructible_v<T> && !std::is_trivially_copy_constructible_v<T>)
      : StaticVector() {  // delegating: if a copy throws, the destructor cleans up
    for (const T& item : other) unchecked_emplace_back(item);
  }

  StaticVector(StaticVector&&) requires std::is_trivially_move_constructible_v<T> = default;
  StaticVector(StaticVector&& other) noexcept(std::is_nothrow_move_constructible_v<T>)
    requires(std::is_move_constructible_v<T> && !std::is_trivially_move_constructible_v<T>)
      : StaticVector() {
    for (T& item : other) unchecked_emplace_back(std::move(item));
  }

  StaticVector& operator=(const StaticVector&) requires kTriviallyCopyAssignable = default;
  StaticVector& operator=(const StaticVector& other) noexcept(
      std::is_nothrow_copy_constructible_v<T> && std::is_nothrow_copy_assignable_v<T>)
    requires(std::is_copy_constructible_v<T> && std::is_copy_assignable_v<T> &&
             !kTriviallyCopyAssignable)
  {
    if (this != &other) assign_from(other);
    return *this;
  }

  StaticVector& operator=(StaticVector&&) requires kTriviallyMoveAssignable = default;
  StaticVector& operator=(StaticVector&& other) noexcept(
      std::is_nothrow_move_constructible_v<T> && std::is_nothrow_move_assignable_v<T>)
    requires(std::is_move_constructible_v<T> && std::is_move_assignable_v<T> &&
             !kTriviallyMoveAssignable)
  {
    if (this != &other) assign_from(std::move(other));
    return *this;
  }

  ~StaticVector() requires std::is_trivially_destructible_v<T> = default;
  ~StaticVector() { clear(); }

  // --- capacity -------------------------------------------------------------------------------
  [[nodiscard]] static constexpr size_type capacity() noexcept { return N; }
  [[nodiscard]] static constexpr size_type max_size() noexcept { return N; }
  [[nodiscard]] size_type size() const noexcept { return size_; }
  [[nodiscard]] bool empty() const noexcept { return size_ == 0; }
  [[nodiscard]] bool full() const noexcept { return size_ == N; }

  // --- adding: false (and no change) when full --------------------------------------------------
  [[nodiscard]] bool push_back(const T& value) noexcept(std::is_nothrow_copy_constructible_v<T>) {
    return emplace_back(value);
  }
  [[nodiscard]] bool push_back(T&& value) noexcept(std::is_nothrow_move_constructible_v<T>) {
    return emplace_back(std::move(value));
  }
  template <typename... Args>
  [[nodiscard]] bool emplace_back(Args&&... args) noexcept(
      std::is_nothrow_constructible_v<T, Args...>) {
    if (full()) return false;
    unchecked_emplace_back(std::forward<Args>(args)...);
    return true;
  }

  // --- removing ---------------------------------------------------------------------------------
  // Returns false (and does nothing) on an empty vector, so an unchecked call is never UB.
  bool pop_back() noexcept {
    if (empty()) return false;
    --size_;
    std::destroy_at(items_ + size_);
    return true;
  }

  // Order-preserving: shifts the tail down by one. pos must be in [begin(), end()).
  iterator erase(const_iterator pos) noexcept(std::is_nothrow_move_assignable_v<T>) {
    return erase(pos, pos + 1);
  }
  // Order-preserving range erase of [first, last).
  iterator erase(const_iterator first, const_iterator last) noexcept(
      std::is_nothrow_move_assignable_v<T>) {
    assert(cbegin() <= first && first <= last && last <= cend());
    iterator out = begin() + (first - cbegin());
    const iterator in = begin() + (last - cbegin());
    if (first != last) truncate(static_cast<size_type>(std::move(in, end(), out) - begin()));
    return out;
  }
  // O(1), not order-preserving: the last element moves into the hole. pos must be in
  // [begin(), end()). Returns pos, which now holds the former last element (or end()).
  iterator swap_remove(const_iterator pos) noexcept(std::is_nothrow_move_assignable_v<T>) {
    assert(cbegin() <= pos && pos < cend());
    iterator hole = begin() + (pos - cbegin());
    if (hole != end() - 1) *hole = std::move(back());
    pop_back();
    return hole;
  }
  // Order-preserving removal of every element matching pred; returns how many went.
  template <typename Pred>
  size_type remove_if(Pred pred) noexcept(std::is_nothrow_move_assignable_v<T>) {
    const size_type before = size_;
    truncate(static_cast<size_type>(std::remove_if(begin(), end(), pred) - begin()));
    return before - size_;
  }

  void clear() noexcept { truncate(0); }

  // --- access (preconditions as for std::vector; checked by assert) ------------------------------
  [[nodiscard]] T& operator[](size_type i) noexcept {
    assert(i < size_);
    return items_[i];
  }
  [[nodiscard]] const T& operator[](size_type i) const noexcept {
    assert(i < size_);
    return items_[i];
  }
  [[nodiscard]] T& front() noexcept { return (*this)[0]; }
  [[nodiscard]] const T& front() const noexcept { return (*this)[0]; }
  [[nodiscard]] T& back() noexcept { return (*this)[size_ - 1]; }
  [[nodiscard]] const T& back() const noexcept { return (*this)[size_ - 1]; }
  [[nodiscard]] T* data() noexcept { return items_; }
  [[nodiscard]] const T* data() const noexcept { return items_; }

  [[nodiscard]] iterator begin() noexcept { return items_; }
  [[nodiscard]] iterator end() noexcept { return items_ + size_; }
  [[nodiscard]] const_iterator begin() const noexcept { return items_; }
  [[nodiscard]] const_iterator end() const noexcept { return items_ + size_; }
  [[nodiscard]] const_iterator cbegin() const noexcept { return items_; }
  [[nodiscard]] const_iterator cend() const noexcept { return items_ + size_; }

  // A StaticVector is a contiguous sized range, so it also converts implicitly to
  // std::span<T> (from an lvalue) and std::span<const T> through span's range constructor.
  [[nodiscard]] std::span<T> as_span() noexcept { return {items_, size_}; }
  [[nodiscard]] std::span<const T> as_span() const noexcept { return {items_, size_}; }

  friend bool operator==(const StaticVector& a, const StaticVector& b) noexcept
    requires std::equality_comparable<T>
  {
    return std::equal(a.begin(), a.end(), b.begin(), b.end());
  }

 private:
  template <typename... Args>
  void unchecked_emplace_back(Args&&... args) noexcept(std::is_nothrow_constructible_v<T, Args...>) {
    std::construct_at(items_ + size_, std::forward<Args>(args)...);
    ++size_;
  }

  // Destroys the elements at [new_size, size()).
  void truncate(size_type new_size) noexcept {
    while (size_ > new_size) {
      --size_;
      std::destroy_at(items_ + size_);
    }
  }

  void assign_from(const StaticVector& other) {
    const size_type common = std::min(size_, other.size_);
    for (size_type i = 0; i < common; ++i) items_[i] = other.items_[i];
    truncate(other.size_);
    for (size_type i = size_; i < other.size_; ++i) unchecked_emplace_back(other.items_[i]);
  }
  void assign_from(StaticVector&& other) {
    const size_type common = std::min(size_, other.size_);
    for (size_type i = 0; i < common; ++i) items_[i] = std::move(other.items_[i]);
    truncate(other.size_);
    for (size_type i = size_; i < other.size_; ++i) unchecked_emplace_back(std::move(other.items_[i]));
  }

  // A union leaves the elements unconstructed until they are pushed; they are a real T[N], so
  // pointer arithmetic over them is plain array arithmetic.
  union {
    T items_[N];
  };
  size_type size_ = 0;
};

}  // namespace sen3bot::mem
