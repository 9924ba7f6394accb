#include <gtest/gtest.h>

#include <array>

#include "sen3bot/tasks/utilization.hpp"

namespace sen3bot::tasks {
namespace {

// control: 1000/10000 + 5000/50000 = 0.2; io: 2000/5000 = 0.4.
constexpr std::array kLight = {
    TaskSpec{"a", 10'000, 1'000, 50, "control"},
    TaskSpec{"b", 5'000, 2'000, 40, "io"},
    TaskSpec{"c", 50'000, 5'000, 30, "control"},
};
static_assert(threads_fit(kLight));

// io alone is fine (0.3), control is over the limit: 0.5 + 0.3 = 0.8.
constexpr std::array kOverloaded = {
    TaskSpec{"a", 10'000, 5'000, 50, "control"},
    TaskSpec{"b", 10'000, 3'000, 40, "io"},
    TaskSpec{"c", 100'000, 30'000, 30, "control"},
};
static_assert(!threads_fit(kOverloaded));

TEST(Utilization, SumsBudgetOverPeriodOfTheNamedThreadOnly) {
  EXPECT_DOUBLE_EQ(thread_utilization(kLight, "control"), 0.2);
  EXPECT_DOUBLE_EQ(thread_utilization(kLight, "io"), 0.4);
  EXPECT_DOUBLE_EQ(thread_utilization(kLight, "background"), 0.0);
  EXPECT_DOUBLE_EQ(max_thread_utilization(kLight), 0.4);
}

TEST(Utilization, ATableWithAnOverloadedThreadDoesNotFit) {
  // A runtime copy, so the same constexpr functions are exercised at run time too.
  std::array table = kOverloaded;
  EXPECT_DOUBLE_EQ(thread_utilization(table, "control"), 0.8);
  EXPECT_DOUBLE_EQ(thread_utilization(table, "io"), 0.3);
  EXPECT_DOUBLE_EQ(max_thread_utilization(table), 0.8);
  EXPECT_FALSE(threads_fit(table));
  EXPECT_TRUE(threads_fit(table, 0.9));
  // Lightening the control thread's biggest row brings it under the limit.
  table[0].budget_us = 3'000;
  EXPECT_TRUE(threads_fit(table));
}

TEST(Utilization, TheLimitIsExclusive) {
  std::array table = {TaskSpec{"a", 10'000, 5'000, 50, "control"}};
  EXPECT_FALSE(threads_fit(table, 0.5));
  EXPECT_TRUE(threads_fit(table, 0.51));
}

TEST(Utilization, ARowWithoutAPeriodNeverFits) {
  std::array table = {TaskSpec{"a", 10'000, 1'000, 50, "control"}, TaskSpec{"b", 0, 1'000, 50, "io"}};
  EXPECT_FALSE(threads_fit(table));
  EXPECT_DOUBLE_EQ(thread_utilization(table, "control"), 0.1);
}

TEST(Utilization, AnEmptyTableFits) {
  constexpr std::array<TaskSpec, 0> empty{};
  static_assert(threads_fit(empty));
  EXPECT_DOUBLE_EQ(max_thread_utilization(empty), 0.0);
}

}  // namespace
}  // namespace sen3bot::tasks
