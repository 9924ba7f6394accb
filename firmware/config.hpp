#pragma once
// The firmware's configuration, loaded from YAML. Every error names the file, the key and the
// problem (and the line, when the YAML has one), so a robot that will not start says why.
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>

#include "sen3bot/hal/result.hpp"

namespace sen3bot::firmware {

enum class ClockMode { lockstep, realtime };

struct ThreadConfig {
  int cpu = -1;           // -1: no affinity
  bool realtime = true;   // ask for SCHED_FIFO at the priority of the thread's highest task
};

struct TaskConfig {
  std::size_t arena_bytes = 0;  // the task's whole memory budget for init()
};

struct FirmwareConfig {
  std::string source_path;  // the file it came from, for messages
  std::string robot_name;
  ClockMode clock = ClockMode::lockstep;
  double duration_s = 0.0;  // 0: until SIGINT/SIGTERM
  bool lock_memory = true;
  std::size_t prefault_stack_bytes = 64 * 1024;
  std::map<std::string, ThreadConfig, std::less<>> threads;
  std::map<std::string, TaskConfig, std::less<>> tasks;
  int health_stall_periods = 3;
  std::int64_t telemetry_status_period_ms = 10'000;
};

Result<FirmwareConfig> load_config(const std::string& path);
Result<FirmwareConfig> parse_config(std::string_view yaml_text, const std::string& source_name);

}  // namespace sen3bot::firmware
