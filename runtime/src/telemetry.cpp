#include "sen3bot/tasks/telemetry.hpp"

#include <cinttypes>

namespace sen3bot::tasks {

namespace {
const char* severity_name(Severity s) {
  switch (s) {
    case Severity::info: return "info";
    case Severity::warning: return "warning";
    case Severity::error: return "error";
  }
  return "?";
}
}  // namespace

Status TelemetryTask::init(std::pmr::memory_resource& arena) {
  if (out_ == nullptr) return Error(Errc::invalid_argument, "telemetry: no output stream");
  if (config_.line_buffer_bytes < 128) return Error(Errc::config, "telemetry: line_buffer_bytes must be >= 128");
  if (config_.status_period_ms < 0) return Error(Errc::config, "telemetry: status_period_ms must be >= 0");
  auto* storage = static_cast<char*>(arena.allocate(config_.line_buffer_bytes, alignof(char)));
  line_ = std::span<char>(storage, config_.line_buffer_bytes);
  next_status_ns_ = 0;
  return Status::success();
}

double TelemetryTask::seconds_since_start(hal::Nanos t) const {
  return hal::to_seconds(t - scheduler_.start_time_ns());
}

void TelemetryTask::drain_events() {
  Event e;
  while (bus_.events.pop(e)) {
    std::fprintf(out_, "[%9.3f s] %-7s %s: %s\n", seconds_since_start(e.stamp_ns), severity_name(e.severity), e.source,
                 e.text);
    ++events_written_;
  }
}

void TelemetryTask::write_status(hal::Nanos now) {
  Sample<HealthReport> health;
  const bool have_health = bus_.health.read(health);
  std::uint64_t runs = 0;
  for (std::size_t i = 0; i < scheduler_.task_count(); ++i)
    runs += scheduler_.counters(i).runs.load(std::memory_order_relaxed);
  int n = std::snprintf(line_.data(), line_.size(), "[%9.3f s] status  %zu tasks, %" PRIu64 " runs", seconds_since_start(now),
                        scheduler_.task_count(), runs);
  if (have_health && n > 0 && static_cast<std::size_t>(n) < line_.size()) {
    const HealthReport& h = health.value;
    std::snprintf(line_.data() + n, line_.size() - static_cast<std::size_t>(n),
                  ", health %s (%u stalled, %u failed, %u missing), overruns %" PRIu64 ", slips %" PRIu64 ", skips %" PRIu64
                  ", events dropped %" PRIu64,
                  h.ok ? "ok" : "DEGRADED", h.stalled_count, h.failed_count, h.missing_count, h.overruns_total, h.slips_total, h.skips_total,
                  bus_.events.dropped());
  }
  std::fprintf(out_, "%s\n", line_.data());
  ++status_lines_;
}

void TelemetryTask::step(const StepContext& context) {
  drain_events();
  const hal::Nanos now = context.start_ns;
  if (config_.status_period_ms > 0 && now >= next_status_ns_) {
    if (next_status_ns_ != 0) write_status(now);
    next_status_ns_ = (next_status_ns_ == 0 ? now : next_status_ns_) + hal::millis(config_.status_period_ms);
  }
  std::fflush(out_);
}

void TelemetryTask::shutdown() {
  drain_events();
  std::fflush(out_);
}

}  // namespace sen3bot::tasks
