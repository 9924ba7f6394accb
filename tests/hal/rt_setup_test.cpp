// Real-time set-up may or may not be permitted on the test machine: each call must return
// either success or a message that says what failed, never abort.
#include <gtest/gtest.h>

#include <pthread.h>

#include <thread>

#include "hal_test_util.hpp"
#include "sen3bot/hal/rt_setup.hpp"

namespace sen3bot::hal {
namespace {

void expect_ok_or_explained(const Status& status) {
  if (!status.ok()) {
    EXPECT_FALSE(status.error().message().empty());
  }
}

// Scheduling and affinity change the calling thread: do it on a throwaway thread.
template <typename F>
Status on_own_thread(F&& f) {
  Status result;
  std::thread([&] { result = f(); }).join();
  return result;
}

TEST(HalRtSetup, LockMemoryAnswers) {
  Status locked = lock_memory();
  expect_ok_or_explained(locked);
  if (!locked.ok()) {
    EXPECT_TRUE(testing::contains(locked.error().message(), "mlockall")) << locked.error().c_str();
  }
  expect_ok_or_explained(unlock_memory());
}

TEST(HalRtSetup, PrefaultStack) {
  EXPECT_TRUE(prefault_stack(0).ok());
  Status small = prefault_stack(64 * 1024);
  EXPECT_TRUE(small.ok()) << small.error().c_str();
  Status huge = prefault_stack(std::size_t{1} << 40);  // 1 TiB: never fits
  ASSERT_FALSE(huge.ok());
  EXPECT_EQ(huge.error().code(), Errc::invalid_argument);
  EXPECT_TRUE(testing::contains(huge.error().message(), "stack")) << huge.error().c_str();
}

TEST(HalRtSetup, DefaultThreadStack) {
  pthread_attr_t saved;
  ASSERT_EQ(::pthread_getattr_default_np(&saved), 0);
  std::size_t saved_bytes = 0;
  ::pthread_attr_getstacksize(&saved, &saved_bytes);
  ::pthread_attr_destroy(&saved);
  ASSERT_TRUE(set_default_thread_stack(512 * 1024));
  std::size_t seen = 0;
  std::thread([&] {
    pthread_attr_t attr;
    ASSERT_EQ(::pthread_getattr_np(::pthread_self(), &attr), 0);
    ::pthread_attr_getstacksize(&attr, &seen);
    ::pthread_attr_destroy(&attr);
  }).join();
  EXPECT_EQ(seen, 512u * 1024);
  EXPECT_EQ(set_default_thread_stack(16).error().code(), Errc::invalid_argument);
  if (saved_bytes != 0) {
    EXPECT_TRUE(set_default_thread_stack(saved_bytes));
  }
}

TEST(HalRtSetup, FifoPriorityAnswers) {
  Status fifo = on_own_thread([] { return set_current_thread_fifo(80); });
  expect_ok_or_explained(fifo);
  if (!fifo.ok() && fifo.error().code() == Errc::permission) {
    EXPECT_TRUE(testing::contains(fifo.error().message(), "SCHED_FIFO priority 80 not permitted")) << fifo.error().c_str();
    EXPECT_TRUE(testing::contains(fifo.error().message(), "CAP_SYS_NICE")) << fifo.error().c_str();
  }
  for (const int bad : {0, 100, -5}) {
    Status out_of_range = on_own_thread([bad] { return set_current_thread_fifo(bad); });
    ASSERT_FALSE(out_of_range.ok()) << bad;
    EXPECT_EQ(out_of_range.error().code(), Errc::invalid_argument);
  }
}

TEST(HalRtSetup, AffinityAnswers) {
  expect_ok_or_explained(on_own_thread([] { return set_current_thread_affinity(0); }));
  Status negative = on_own_thread([] { return set_current_thread_affinity(-1); });
  ASSERT_FALSE(negative.ok());
  EXPECT_EQ(negative.error().code(), Errc::invalid_argument);
  Status absent = on_own_thread([] { return set_current_thread_affinity(1000); });
  ASSERT_FALSE(absent.ok());
  EXPECT_TRUE(testing::contains(absent.error().message(), "CPU 1000")) << absent.error().c_str();
}

TEST(HalRtSetup, ReportDescribesEveryStep) {
  RtSetupOptions options;
  options.lock_memory = false;  // keep the test process unlocked
  options.prefault_stack_bytes = 32 * 1024;
  options.fifo_priority = 10;
  options.cpu = 0;
  RtSetupReport report;
  std::thread([&] { report = apply_rt_setup(options); }).join();
  const std::string text = describe(report);
  EXPECT_TRUE(testing::contains(text, "lock memory: skipped")) << text;
  EXPECT_TRUE(testing::contains(text, "prefault stack: ok")) << text;
  EXPECT_TRUE(testing::contains(text, "SCHED_FIFO: ")) << text;
  EXPECT_TRUE(testing::contains(text, "CPU affinity: ")) << text;
  bool every_attempt_ok = true;
  for (const RtStepResult& step : report.steps) {
    if (step.attempted && !step.status.ok()) {
      every_attempt_ok = false;
      EXPECT_TRUE(testing::contains(text, step.status.error().message())) << text;
      EXPECT_TRUE(testing::contains(text, "FAILED")) << text;
    }
  }
  EXPECT_EQ(report.all_ok(), every_attempt_ok);
}

TEST(HalRtSetup, NothingRequestedIsAllOk) {
  RtSetupOptions options;
  options.lock_memory = false;
  options.prefault_stack_bytes = 0;
  const RtSetupReport report = apply_rt_setup(options);
  EXPECT_TRUE(report.all_ok());
  EXPECT_EQ(describe(report).find("FAILED"), std::string::npos);
}

}  // namespace
}  // namespace sen3bot::hal
