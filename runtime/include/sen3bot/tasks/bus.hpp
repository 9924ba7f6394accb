#pragma once
// The firmware's message bus: one Topic per message, each a fixed-size struct, plus the event
// log. It is owned by the firmware composition and handed to tasks by reference. Later
// messages (odometry, laser scans, costmaps, detections, velocity commands) are added here.
#include <cstdint>

#include "sen3bot/tasks/event_log.hpp"
#include "sen3bot/tasks/topic.hpp"

namespace sen3bot::tasks {

// Published by the health task: whether every task keeps its rate.
struct HealthReport {
  std::uint32_t task_count = 0;
  std::uint32_t stalled_count = 0;
  std::uint64_t stalled_mask = 0;      // bit i: task i has not started for stall_periods periods
  std::uint32_t failed_count = 0;
  std::uint64_t failed_mask = 0;       // bit i: task i's device failed for good (Task::failed())
  std::uint32_t missing_count = 0;
  std::uint64_t missing_mask = 0;      // bit i: task i's device is missing, retried (Task::device_missing())
  std::uint64_t overruns_total = 0;
  std::uint64_t slips_total = 0;
  std::uint64_t skips_total = 0;
  std::uint64_t overruns_since_last = 0;  // since the previous report
  std::uint64_t slips_since_last = 0;
  bool ok = false;                     // nothing stalled, failed or missing, no slip since the previous report
};

using FirmwareEventLog = EventLog<256>;

struct Bus {
  Topic<HealthReport> health;
  FirmwareEventLog events;
};

}  // namespace sen3bot::tasks
