#pragma once
// The firmware's configuration, loaded from YAML. Every error names the file, the key and the
// problem (and the line, when the YAML has one), so a robot that will not start says why.
#include <cstddef>
#include <cstdint>
#include <map>
#include <string>
#include <string_view>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/lms200/device.hpp"
#include "sen3bot/nav/geometry.hpp"
#include "sen3bot/p2os/driver.hpp"
#include "sen3bot/sim/simulation.hpp"
#include "mission.hpp"

namespace sen3bot::firmware {

enum class ClockMode { lockstep, realtime };

struct ThreadConfig {
  int cpu = -1;           // -1: no affinity
  bool realtime = true;   // ask for SCHED_FIFO at the priority of the thread's highest task
};

struct TaskConfig {
  std::size_t arena_bytes = 0;  // the task's whole memory budget for init()
};

// A device's `port: sim` connects its driver to the simulated robot of the `sim` section.
struct DevicesConfig {
  bool has_base = false;   // devices.base present
  bool has_laser = false;  // devices.laser present
  p2os::P2osConfig base;
  bool base_simulated = false;
  lms200::Lms200Config laser;
  bool laser_simulated = false;
};

struct SimSection {
  bool enabled = false;     // a `sim` section is present
  sim::SimulationConfig world;
};

// Localization, planners and safety over one map, and the mission's goals.
struct NavigationSection {
  bool enabled = false;        // a `navigation` section is present
  std::string map_path;        // ROS map_server YAML
  std::string waypoints_path;  // optional: "x y" per line, map frame (the supervisory path)
  nav::Pose2D initial_pose;    // localization's starting estimate
  double initial_std_xy_m = 0.25;
  std::size_t min_particles = 500;
  std::size_t max_particles = 2000;
  double max_v_m_s = 0.5;
  double max_w_rad_s = 1.2;
  double goal_tolerance_m = 0.15;
  double stop_distance_m = 0.25;
  MissionConfig mission;
};

struct FirmwareConfig {
  std::string source_path;  // the file it came from, for messages
  std::string robot_name;
  nav::Pose2D laser_mount{0.16, 0.0, 0.0};  // scanner pose in the robot frame (robot.laser_mount)
  ClockMode clock = ClockMode::lockstep;
  double duration_s = 0.0;  // 0: until SIGINT/SIGTERM
  bool lock_memory = true;
  std::size_t prefault_stack_bytes = 64 * 1024;
  std::map<std::string, ThreadConfig, std::less<>> threads;
  std::map<std::string, TaskConfig, std::less<>> tasks;
  int health_stall_periods = 3;
  std::int64_t telemetry_status_period_ms = 10'000;
  DevicesConfig devices;
  SimSection sim;
  NavigationSection navigation;
};

Result<FirmwareConfig> load_config(const std::string& path);
Result<FirmwareConfig> parse_config(std::string_view yaml_text, const std::string& source_name);

}  // namespace sen3bot::firmware
