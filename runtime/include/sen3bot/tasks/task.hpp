#pragma once
// A periodic task: init() once before the scheduler starts (may allocate, from its budgeted
// arena only), step() every period (must not allocate, block or throw).
#include <cstdint>
#include <memory_resource>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/result.hpp"

namespace sen3bot::tasks {

struct StepContext {
  hal::Nanos release_ns;  // the deadline this run was released for
  hal::Nanos start_ns;    // when the step actually started
  std::uint64_t cycle;    // runs so far, counting this one from 0
};

class Task {
 public:
  virtual ~Task() = default;
  // `arena` is this task's budget: a monotonic resource whose upstream is the null
  // resource, so going over budget throws std::bad_alloc, which the caller turns into a
  // clear init error.
  virtual Status init(std::pmr::memory_resource& arena) = 0;
  virtual void step(const StepContext& context) = 0;
  // Called once after the scheduler stopped; may block (e.g. a clean device close).
  virtual void shutdown() {}
  // Its device failed for good (e.g. a camera that offers no codec we decode): the task keeps
  // its row but does nothing, and the rest of the firmware runs without it. Any thread.
  [[nodiscard]] virtual bool failed() const noexcept { return false; }
  // Its device is absent or went away (not opened, unplugged): the task keeps its row and
  // keeps trying to reopen it with backoff. Any thread.
  [[nodiscard]] virtual bool device_missing() const noexcept { return false; }
};

}  // namespace sen3bot::tasks
