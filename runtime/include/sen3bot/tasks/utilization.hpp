#pragma once
// Compile-time sizing of a task table: the share of one thread's CPU that its rows' budgets
// claim, and whether every thread stays under a limit. Used by a static_assert next to the
// firmware's table, so a row that overloads its thread does not build.
#include <array>
#include <cstddef>
#include <limits>
#include <string_view>

#include "sen3bot/tasks/scheduler.hpp"

namespace sen3bot::tasks {

// The most a thread's budgets may claim of its CPU. Liu and Layland's bound for fixed-priority
// periodic tasks falls towards ln 2 (about 0.69) as tasks are added: below it, rate-ordered
// tasks meet every deadline however their releases line up. The rest is headroom for what the
// budgets leave out (kernel, interrupts, the other threads sharing a core on the Pi 3).
inline constexpr double kMaxThreadUtilization = 0.7;

// Sum of budget/period over the rows that run on `thread`. A row with a non-positive period
// claims the whole CPU, so such a table never fits.
template <std::size_t N>
constexpr double thread_utilization(const std::array<TaskSpec, N>& table, std::string_view thread) {
  double total = 0.0;
  for (const TaskSpec& row : table) {
    if (row.thread != thread) continue;
    if (row.period_us <= 0) return std::numeric_limits<double>::infinity();
    total += static_cast<double>(row.budget_us) / static_cast<double>(row.period_us);
  }
  return total;
}

// The utilization of the most loaded thread of the table (0 for an empty table).
template <std::size_t N>
constexpr double max_thread_utilization(const std::array<TaskSpec, N>& table) {
  double worst = 0.0;
  for (const TaskSpec& row : table) {
    const double u = thread_utilization(table, row.thread);
    if (u > worst) worst = u;
  }
  return worst;
}

// True when every thread of the table stays below `limit`.
template <std::size_t N>
constexpr bool threads_fit(const std::array<TaskSpec, N>& table, double limit = kMaxThreadUtilization) {
  return max_thread_utilization(table) < limit;
}

}  // namespace sen3bot::tasks
