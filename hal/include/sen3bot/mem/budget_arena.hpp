#pragma once
// BudgetArena: a std::pmr::memory_resource over ONE block of memory fixed at start-up, the
// memory budget of one task, driver, costmap or planner. It bump-allocates (monotonic:
// deallocate does nothing) and never falls back to the heap: a request that does not fit is
// recorded as a clear error and reported by throwing std::bad_alloc, the one exception this
// firmware uses, because that is how std::pmr containers learn that an allocation failed.
// try_init() turns that exception back into a Status, so a task's init() fails cleanly with a
// message naming the arena, its budget and the request.
//
// We implement the bump pointer ourselves rather than wrapping
// std::pmr::monotonic_buffer_resource (over null_memory_resource) so that used/peak bytes
// include alignment padding exactly and the error can say how much was in use.
//
// Not thread-safe: an arena belongs to one component and is filled during its init().
#include <algorithm>
#include <cassert>
#include <cstddef>
#include <cstdint>
#include <cstring>
#include <functional>
#include <memory_resource>
#include <new>
#include <span>
#include <stdexcept>
#include <string_view>
#include <type_traits>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/mem/cache_line.hpp"

namespace sen3bot::mem {

class BudgetArena final : public std::pmr::memory_resource {
 public:
  static constexpr std::size_t kNameCapacity = 32;  // longer names are truncated, not allocated
  // The owned block is cache-line aligned, so the first line-aligned request needs no padding.
  static constexpr std::size_t kBlockAlignment = kCacheLineBytes;

  // Takes budget_bytes from upstream now (this is the only allocation the arena ever makes;
  // it may throw std::bad_alloc at start-up) and touches every page of it, so that page faults
  // happen here and not on the first use in a real-time loop.
  BudgetArena(std::string_view name, std::size_t budget_bytes,
              std::pmr::memory_resource* upstream = std::pmr::new_delete_resource())
      : upstream_(upstream), capacity_(budget_bytes) {
    set_name(name);
    if (capacity_ > 0) {
      block_ = static_cast<std::byte*>(upstream_->allocate(capacity_, kBlockAlignment));
      std::memset(block_, 0, capacity_);
    }
  }

  // Over caller-provided storage (a static buffer, or a slice of a parent arena). Never
  // allocates; the buffer must outlive the arena.
  BudgetArena(std::string_view name, std::span<std::byte> buffer) noexcept
      : block_(buffer.data()), capacity_(buffer.size()) {
    set_name(name);
  }

  BudgetArena(const BudgetArena&) = delete;  // handed out by address to containers
  BudgetArena& operator=(const BudgetArena&) = delete;

  ~BudgetArena() override {
    if (upstream_ != nullptr && block_ != nullptr) {
      upstream_->deallocate(block_, capacity_, kBlockAlignment);
    }
  }

  [[nodiscard]] std::string_view name() const noexcept { return {name_, name_length_}; }
  [[nodiscard]] std::size_t capacity_bytes() const noexcept { return capacity_; }
  // Bytes handed out since construction or reset(), alignment padding included.
  [[nodiscard]] std::size_t used_bytes() const noexcept { return used_; }
  [[nodiscard]] std::size_t available_bytes() const noexcept { return capacity_ - used_; }
  // High-water mark of used_bytes() since construction (reset() does not lower it): the number
  // to compare with the configured budget when sizing it.
  [[nodiscard]] std::size_t peak_bytes() const noexcept { return peak_; }
  [[nodiscard]] std::size_t allocation_count() const noexcept { return allocations_; }
  // Requests refused for lack of budget since construction, and the latest one's message.
  [[nodiscard]] std::size_t failure_count() const noexcept { return failures_; }
  [[nodiscard]] const Error& last_error() const noexcept { return last_error_; }

  // Forgets every allocation: all memory handed out before becomes invalid. For tests and for
  // components that rebuild everything (e.g. a re-init after a configuration change).
  void reset() noexcept { used_ = 0; }

  // True when p points into this arena's block.
  [[nodiscard]] bool owns(const void* p) const noexcept {
    const auto address = reinterpret_cast<std::uintptr_t>(p);
    const auto first = reinterpret_cast<std::uintptr_t>(block_);
    return block_ != nullptr && address >= first && address - first < capacity_;
  }

 private:
  void* do_allocate(std::size_t bytes, std::size_t alignment) override {
    assert(alignment != 0 && (alignment & (alignment - 1)) == 0);
    // Align the address, not the offset, so alignments larger than the block's own work too.
    const auto address = reinterpret_cast<std::uintptr_t>(block_) + used_;
    const std::size_t padding = static_cast<std::size_t>((alignment - address % alignment) % alignment);
    const std::size_t size = bytes == 0 ? 1 : bytes;  // distinct addresses for empty requests
    const std::size_t room = capacity_ - used_;
    if (padding > room || size > room - padding) {
      last_error_ = Error::format(Errc::capacity,
                                  "arena '%.*s': budget %zu B exceeded: request of %zu B (align %zu) "
                                  "with %zu B in use",
                                  static_cast<int>(name_length_), name_, capacity_, bytes, alignment,
                                  used_);
      ++failures_;
      throw std::bad_alloc();
    }
    std::byte* out = block_ + used_ + padding;
    used_ += padding + size;
    peak_ = std::max(peak_, used_);
    ++allocations_;
    return out;
  }

  // Monotonic: memory comes back only with reset() or the arena's destruction.
  void do_deallocate(void* /*p*/, std::size_t /*bytes*/, std::size_t /*alignment*/) noexcept override {}

  [[nodiscard]] bool do_is_equal(const std::pmr::memory_resource& other) const noexcept override {
    return this == &other;
  }

  void set_name(std::string_view name) noexcept {
    name_length_ = std::min(name.size(), kNameCapacity - 1);
    std::memcpy(name_, name.data(), name_length_);
    name_[name_length_] = '\0';
  }

  std::pmr::memory_resource* upstream_ = nullptr;  // owner of block_, or nullptr for caller storage
  std::byte* block_ = nullptr;
  std::size_t capacity_ = 0;
  std::size_t used_ = 0;
  std::size_t peak_ = 0;
  std::size_t allocations_ = 0;
  std::size_t failures_ = 0;
  Error last_error_;
  char name_[kNameCapacity] = {};
  std::size_t name_length_ = 0;
};

// Runs init (a callable returning Status or void) that allocates from arena, and turns the
// arena's std::bad_alloc into its recorded error, so an over-budget init() is an ordinary
// failed Status. std::length_error (a pmr container asked for more than it can ever hold) is
// converted too. Any other exception is a bug and terminates (this function is noexcept).
template <typename Init>
Status try_init(BudgetArena& arena, Init&& init) noexcept {
  const std::size_t failures_before = arena.failure_count();
  const std::string_view name = arena.name();
  try {
    if constexpr (std::is_void_v<std::invoke_result_t<Init>>) {
      std::invoke(std::forward<Init>(init));
      return Status::success();
    } else {
      static_assert(std::is_convertible_v<std::invoke_result_t<Init>, Status>,
                    "init must return Status or void");
      return std::invoke(std::forward<Init>(init));
    }
  } catch (const std::bad_alloc&) {
    if (arena.failure_count() != failures_before) return arena.last_error();
    return Error::format(Errc::capacity,
                         "arena '%.*s': init failed: out of memory outside the arena",
                         static_cast<int>(name.size()), name.data());
  } catch (const std::length_error& e) {
    return Error::format(Errc::capacity, "arena '%.*s': init failed: %s",
                         static_cast<int>(name.size()), name.data(), e.what());
  }
}

}  // namespace sen3bot::mem
