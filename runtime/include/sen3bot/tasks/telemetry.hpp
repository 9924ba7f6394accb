#pragma once
// The background voice of the firmware: writes out the event log and, every status period,
// one status line. It runs on a non-real-time thread because writing may block.
#include <cstdio>
#include <memory_resource>
#include <span>

#include "sen3bot/tasks/bus.hpp"
#include "sen3bot/tasks/scheduler.hpp"
#include "sen3bot/tasks/task.hpp"

namespace sen3bot::tasks {

struct TelemetryConfig {
  std::int64_t status_period_ms = 10'000;  // 0: no status lines, events only
  std::size_t line_buffer_bytes = 512;
};

class TelemetryTask final : public Task {
 public:
  TelemetryTask(const Scheduler& scheduler, Bus& bus, std::FILE* out, TelemetryConfig config)
      : scheduler_(scheduler), bus_(bus), out_(out), config_(config) {}

  Status init(std::pmr::memory_resource& arena) override;
  void step(const StepContext& context) override;
  void shutdown() override;

  [[nodiscard]] std::uint64_t events_written() const noexcept { return events_written_; }
  [[nodiscard]] std::uint64_t status_lines_written() const noexcept { return status_lines_; }

 private:
  void drain_events();
  void write_status(hal::Nanos now);
  [[nodiscard]] double seconds_since_start(hal::Nanos t) const;

  const Scheduler& scheduler_;
  Bus& bus_;
  std::FILE* out_;
  TelemetryConfig config_;
  std::span<char> line_;
  hal::Nanos next_status_ns_ = 0;
  std::uint64_t events_written_ = 0;
  std::uint64_t status_lines_ = 0;
};

}  // namespace sen3bot::tasks
