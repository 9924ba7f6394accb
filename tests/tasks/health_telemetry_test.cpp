#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cstdio>
#include <functional>
#include <string>

#include "sen3bot/tasks/health.hpp"
#include "sen3bot/tasks/telemetry.hpp"

namespace sen3bot::tasks {
namespace {

using hal::millis;
using hal::seconds;

class HealthScriptedTask final : public Task {
 public:
  explicit HealthScriptedTask(std::function<void(const StepContext&)> body) : body_(std::move(body)) {}
  Status init(std::pmr::memory_resource&) override { return Status::success(); }
  void step(const StepContext& c) override { body_(c); }

 private:
  std::function<void(const StepContext&)> body_;
};

std::string read_all(std::FILE* f) {
  std::fflush(f);
  std::rewind(f);
  std::string text;
  std::array<char, 4096> buf;
  while (std::size_t n = std::fread(buf.data(), 1, buf.size(), f)) text.append(buf.data(), n);
  return text;
}

struct Rig {
  hal::SimClock clock;
  Scheduler scheduler{clock};
  Bus bus;
  std::array<std::byte, 4096> arena_storage{};
  std::pmr::monotonic_buffer_resource arena{arena_storage.data(), arena_storage.size(), std::pmr::null_memory_resource()};
};

TEST(HealthTask, ReportsAStalledTaskAndItsRecovery) {
  Rig rig;
  // The worker blocks for 400 ms once, at 1 s: with a 50 ms period that is a stall.
  HealthScriptedTask worker([&](const StepContext& c) {
    if (c.release_ns == seconds(1)) rig.clock.advance_by(millis(400));
  });
  HealthTask health(rig.scheduler, rig.bus, rig.clock, HealthConfig{3});
  ASSERT_TRUE(rig.scheduler.add({"worker", 50'000, 10'000, 50, "io"}, worker));
  ASSERT_TRUE(rig.scheduler.add({"health", 100'000, 1'000, 60, "control"}, health));

  // Sample the report at every health run.
  std::uint64_t degraded_reports = 0, healthy_reports = 0;
  HealthScriptedTask observer([&](const StepContext&) {
    Sample<HealthReport> s;
    if (!rig.bus.health.read(s)) return;
    (s.value.ok ? healthy_reports : degraded_reports)++;
  });
  ASSERT_TRUE(rig.scheduler.add({"observer", 100'000, 1'000, 1, "background"}, observer));
  ASSERT_TRUE(health.init(rig.arena));
  ASSERT_TRUE(rig.scheduler.run_lockstep(rig.clock, seconds(3)));

  Sample<HealthReport> last;
  ASSERT_TRUE(rig.bus.health.read(last));
  EXPECT_TRUE(last.value.ok);
  EXPECT_EQ(last.value.task_count, 3u);
  EXPECT_EQ(last.value.overruns_total, 1u);
  EXPECT_GE(last.value.skips_total, 7u);
  EXPECT_GT(degraded_reports, 0u);
  EXPECT_GT(healthy_reports, 20u);

  // The event log says what happened, in order.
  std::string events;
  Event e;
  while (rig.bus.events.pop(e)) events += std::string(e.text) + "\n";
  EXPECT_NE(events.find("worker: 1 overruns"), std::string::npos) << events;
  EXPECT_NE(events.find("slips"), std::string::npos) << events;
}

TEST(HealthTask, DetectsATaskThatNeverRuns) {
  Rig rig;
  HealthScriptedTask hog([&](const StepContext& c) {
    if (c.cycle == 0) rig.clock.advance_by(millis(500));
  });
  HealthScriptedTask starved([](const StepContext&) {});
  HealthTask health(rig.scheduler, rig.bus, rig.clock, HealthConfig{3});
  ASSERT_TRUE(rig.scheduler.add({"hog", 1'000'000, 900'000, 90, "control"}, hog));
  ASSERT_TRUE(rig.scheduler.add({"health", 100'000, 1'000, 80, "control"}, health));
  ASSERT_TRUE(rig.scheduler.add({"starved", 100'000, 1'000, 10, "control"}, starved));
  ASSERT_TRUE(health.init(rig.arena));
  // At 500 ms health runs before the starved task has ever run (released at 0, never started).
  ASSERT_TRUE(rig.scheduler.run_lockstep(rig.clock, millis(510)));
  Sample<HealthReport> s;
  ASSERT_TRUE(rig.bus.health.read(s));
  EXPECT_FALSE(s.value.ok);
  EXPECT_EQ(s.value.stalled_mask, 0b100u);
  EXPECT_EQ(s.value.stalled_count, 1u);
}

// A task whose device failed for good keeps running (it is not stalled) but the report and
// the event log say it failed, and the status line shows it.
class DeviceTask final : public Task {
 public:
  Status init(std::pmr::memory_resource&) override { return Status::success(); }
  void step(const StepContext& c) override {
    if (c.release_ns >= seconds(1)) failed_.store(true);
  }
  [[nodiscard]] bool failed() const noexcept override { return failed_.load(); }

 private:
  std::atomic<bool> failed_{false};
};

TEST(HealthTask, ReportsATaskWhoseDeviceFailed) {
  Rig rig;
  std::FILE* out = std::tmpfile();
  ASSERT_NE(out, nullptr);
  DeviceTask device;
  HealthTask health(rig.scheduler, rig.bus, rig.clock, HealthConfig{3});
  TelemetryTask telemetry(rig.scheduler, rig.bus, out, TelemetryConfig{1'000, 256});
  ASSERT_TRUE(rig.scheduler.add({"device", 50'000, 10'000, 50, "io"}, device));
  ASSERT_TRUE(rig.scheduler.add({"health", 100'000, 1'000, 60, "control"}, health));
  ASSERT_TRUE(rig.scheduler.add({"telemetry", 200'000, 5'000, 0, "background"}, telemetry));
  ASSERT_TRUE(health.init(rig.arena));
  ASSERT_TRUE(telemetry.init(rig.arena));
  ASSERT_TRUE(rig.scheduler.run_lockstep(rig.clock, millis(900)));
  Sample<HealthReport> before;
  ASSERT_TRUE(rig.bus.health.read(before));
  EXPECT_TRUE(before.value.ok);
  EXPECT_EQ(before.value.failed_count, 0u);

  ASSERT_TRUE(rig.scheduler.run_lockstep(rig.clock, millis(2100)));
  telemetry.shutdown();
  const std::string text = read_all(out);
  std::fclose(out);
  Sample<HealthReport> after;
  ASSERT_TRUE(rig.bus.health.read(after));
  EXPECT_FALSE(after.value.ok);
  EXPECT_EQ(after.value.failed_count, 1u);
  EXPECT_EQ(after.value.failed_mask, 0b1u);
  EXPECT_EQ(after.value.stalled_count, 0u);
  EXPECT_NE(text.find("error   health: task device failed: running without its device"), std::string::npos) << text;
  EXPECT_NE(text.find("health DEGRADED (0 stalled, 1 failed, 0 missing)"), std::string::npos) << text;
}

// A device that is missing from 1 s to 2 s: the report says so while it is, and the log
// tells when it went and came back.
class MissingDeviceTask final : public Task {
 public:
  Status init(std::pmr::memory_resource&) override { return Status::success(); }
  void step(const StepContext& c) override { missing_.store(c.release_ns >= seconds(1) && c.release_ns < seconds(2)); }
  [[nodiscard]] bool device_missing() const noexcept override { return missing_.load(); }

 private:
  std::atomic<bool> missing_{false};
};

TEST(HealthTask, ReportsAMissingDeviceAndItsReturn) {
  Rig rig;
  std::FILE* out = std::tmpfile();
  ASSERT_NE(out, nullptr);
  MissingDeviceTask device;
  HealthTask health(rig.scheduler, rig.bus, rig.clock, HealthConfig{3});
  TelemetryTask telemetry(rig.scheduler, rig.bus, out, TelemetryConfig{1'000, 256});
  ASSERT_TRUE(rig.scheduler.add({"laser", 50'000, 10'000, 50, "io"}, device));
  ASSERT_TRUE(rig.scheduler.add({"health", 100'000, 1'000, 60, "control"}, health));
  ASSERT_TRUE(rig.scheduler.add({"telemetry", 200'000, 5'000, 0, "background"}, telemetry));
  ASSERT_TRUE(health.init(rig.arena));
  ASSERT_TRUE(telemetry.init(rig.arena));
  ASSERT_TRUE(rig.scheduler.run_lockstep(rig.clock, millis(1500)));
  Sample<HealthReport> during;
  ASSERT_TRUE(rig.bus.health.read(during));
  EXPECT_FALSE(during.value.ok);
  EXPECT_EQ(during.value.missing_count, 1u);
  EXPECT_EQ(during.value.missing_mask, 0b1u);
  EXPECT_EQ(during.value.stalled_count, 0u);
  ASSERT_TRUE(rig.scheduler.run_lockstep(rig.clock, millis(1000)));
  telemetry.shutdown();
  const std::string text = read_all(out);
  std::fclose(out);
  Sample<HealthReport> after;
  ASSERT_TRUE(rig.bus.health.read(after));
  EXPECT_TRUE(after.value.ok);
  EXPECT_EQ(after.value.missing_count, 0u);
  EXPECT_NE(text.find("error   health: task laser has no device: retrying"), std::string::npos) << text;
  EXPECT_NE(text.find("info    health: task laser has its device"), std::string::npos) << text;
  EXPECT_NE(text.find("health DEGRADED (0 stalled, 0 failed, 1 missing)"), std::string::npos) << text;
}

TEST(HealthTask, InitFailsCleanlyWhenItsArenaIsTooSmall) {
  hal::SimClock clock;
  Scheduler scheduler(clock);
  Bus bus;
  HealthTask health(scheduler, bus, clock, HealthConfig{3});
  HealthScriptedTask t([](const StepContext&) {});
  for (int i = 0; i < 8; ++i) {
    static const char* names[] = {"a", "b", "c", "d", "e", "f", "g", "h"};
    ASSERT_TRUE(scheduler.add({names[i], 1'000, 100, 1, "control"}, t));
  }
  std::array<std::byte, 16> tiny{};
  std::pmr::monotonic_buffer_resource arena{tiny.data(), tiny.size(), std::pmr::null_memory_resource()};
  EXPECT_THROW((void)health.init(arena), std::bad_alloc);
}

TEST(TelemetryTask, WritesEventsAndPeriodicStatusLines) {
  Rig rig;
  std::FILE* out = std::tmpfile();
  ASSERT_NE(out, nullptr);
  HealthScriptedTask chatty([&](const StepContext& c) {
    if (c.cycle % 10 == 0) rig.bus.events.post(c.start_ns, Severity::warning, "chatty", "cycle %llu", static_cast<unsigned long long>(c.cycle));
  });
  HealthTask health(rig.scheduler, rig.bus, rig.clock, HealthConfig{3});
  TelemetryTask telemetry(rig.scheduler, rig.bus, out, TelemetryConfig{1'000, 256});
  ASSERT_TRUE(rig.scheduler.add({"chatty", 100'000, 1'000, 50, "io"}, chatty));
  ASSERT_TRUE(rig.scheduler.add({"health", 100'000, 1'000, 60, "control"}, health));
  ASSERT_TRUE(rig.scheduler.add({"telemetry", 200'000, 5'000, 0, "background"}, telemetry));
  ASSERT_TRUE(health.init(rig.arena));
  ASSERT_TRUE(telemetry.init(rig.arena));
  ASSERT_TRUE(rig.scheduler.run_lockstep(rig.clock, seconds(5)));
  telemetry.shutdown();
  const std::string text = read_all(out);
  std::fclose(out);
  EXPECT_EQ(telemetry.events_written(), 5u);  // cycles 0, 10, 20, 30, 40
  EXPECT_NE(text.find("warning chatty: cycle 40"), std::string::npos) << text;
  // Status lines at 1, 2, 3, 4 s (the first period starts at the first run).
  EXPECT_EQ(telemetry.status_lines_written(), 4u);
  EXPECT_NE(text.find("status  3 tasks"), std::string::npos) << text;
  EXPECT_NE(text.find("health ok"), std::string::npos) << text;
}

}  // namespace
}  // namespace sen3bot::tasks
