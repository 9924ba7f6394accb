#pragma once
// The firmware's configuration, loaded from YAML. Every error names the file, the key and the
// problem (and the line, when the YAML has one), so a robot that will not start says why.
#include <cstddef>
#include <cstdint>
#include <map>
#include <span>
#include <string>
#include <string_view>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/camera/camera.hpp"
#include "sen3bot/lms200/device.hpp"
#include "sen3bot/nav/crossings.hpp"
#include "sen3bot/nav/dynamic_obstacles.hpp"
#include "sen3bot/nav/geometry.hpp"
#include "sen3bot/nav/local_planner.hpp"
#include "sen3bot/nav/localization.hpp"
#include "sen3bot/detector/hog.hpp"
#include "sen3bot/nav/osgp.hpp"
#include "sen3bot/nav/people.hpp"
#include "sen3bot/nav/safety.hpp"
#include "sen3bot/nav/sgp.hpp"
#include "sen3bot/p2os/driver.hpp"
#include "can_io_task.hpp"
#include "view_config.hpp"
#include "cobot_task.hpp"
#include "fleet_task.hpp"
#include "mapping_task.hpp"
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

// Each device's port is handed to the board as it is: a device path or tcp://host:port on the
// robot, or a name the simulated board answers ("sim").
struct DevicesConfig {
  bool has_base = false;    // devices.base present
  bool has_laser = false;   // devices.laser present
  bool has_camera = false;  // devices.camera present
  bool has_io_node = false; // devices.io_node present
  p2os::P2osConfig base;
  lms200::Lms200Config laser;
  camera::CameraConfig camera;
  CanIoConfig io_node;  // the CANopen safety I/O node (can_io_task.hpp)
};

// Localization, planners and safety over one map, and the mission's goals. The algorithms'
// own configurations are held here, so their defaults are the only defaults; the
// configuration file overrides a few of their keys and composition fills in the rest (laser
// mount, scan timing, braking).
struct NavigationSection {
  bool enabled = false;        // a `navigation` section is present
  std::string map_path;        // ROS map_server YAML
  std::string waypoints_path;  // optional: "x y" per line, map frame (a fixed supervisory path)
  // Optional, instead of waypoints: the site's safe curve (safe_curve.hpp); the supervisory
  // planner then computes each goal's waypoints from where the robot is.
  std::string safe_curve_path;
  nav::SgpConfig sgp;
  // People (docs/people.md): boxes from a person detector on `people_detector` ("sim", or
  // "udp://ADDRESS:PORT"), fused with the laser, tracked, and caged on both costmaps.
  bool people_enabled = false;
  // With people on, the safety filter cages a mover at walking speed as a person until the
  // camera sees it (people.keep_out.movers).
  bool cage_movers = true;
  std::string people_detector;
  nav::FusionConfig fusion;
  nav::PersonTrackerConfig person_tracker;
  nav::PeopleLayerConfig cages;
  double detection_max_age_s = 0.5;
  // detector: onboard: OpenCV's HOG on the camera's frames (vision_task.hpp).
  detector::HogConfig onboard_hog;
  double onboard_rate_hz = 2.0;
  bool osgp_enabled = true;  // with the safe curve and people: the online SGP (osgp.hpp)
  nav::OsgpConfig osgp;
  nav::MclConfig mcl;          // initial_pose, initial_std_xy_m, min/max_particles from the file
  nav::DwaConfig dwa;          // max_v_m_s, max_w_rad_s, goal_tolerance_m
  nav::SafetyConfig safety;    // stop_distance_m
  nav::DynamicObstacleConfig dynamic_obstacles;  // the local costmap's moving-obstacle layer
  nav::CrossingConfig crossings;  // walkers' crossings of the path, planned in time
  nav::LaneConfig lanes;          // where walkers went in the last minutes
  nav::MakeWayConfig make_way;    // moving out of a walker's way
  // The local costmap: its square window and how far its obstacle layer marks and clears.
  double local_costmap_size_m = 6.0;
  nav::ObstacleLayerConfig local_obstacles;
  MissionConfig mission;
};

// The robot computer's discrete I/O, as Linux GPIO lines "/dev/gpiochipN:LINE" (empty: none).
struct BoardIo {
  std::string estop_input;   // the e-stop chain, active when pressed or open
  std::string light_output;  // the warning light
};

// The collaborative mode (Sen3CoBot; cobot_task.hpp, docs/cobot.md): the site's areas, the
// trained operators, the QR tags, follow-me, the worker's path and operation recognition.
struct CobotSection {
  bool enabled = false;           // a `cobot` section is present
  std::string site_path;          // the site file's areas (ssc site format)
  CobotTaskConfig task;           // the areas are filled in from site_path when the firmware starts
  double operator_safety_radius_m = 0.25;  // the followed operator's cage, instead of the tracker's
  double qr_rate_hz = 5.0;        // frames searched for tags a second, at most
  double qr_reach_m = 2.0;        // only near people within this of the laser
  double tag_side_m = 0.10;
  bool qr_whole_frame = false;
  // Operation recognition (off without `recognition`).
  bool recognition = false;
  std::string operations_path;
  std::string model_path;
  double recognition_rate_hz = 1.0;
};

// view: the live view's server (docs/view.md); off without the section.
struct ViewSection {
  bool enabled = false;
  ViewTaskConfig task;
};

// mapping: the robot builds a map while it is driven (mapping_task.hpp); off without the section.
struct MappingSection {
  bool enabled = false;
  MappingConfig task;
};

struct FirmwareConfig {
  std::string source_path;  // the file it came from, for messages
  std::string robot_name;
  nav::Pose2D laser_mount{0.16, 0.0, 0.0};  // scanner pose in the robot frame (robot.laser_mount)
  ClockMode clock = ClockMode::lockstep;
  double duration_s = 0.0;  // 0: until SIGINT/SIGTERM
  bool lock_memory = true;
  // PM QoS: the deepest CPU idle state's exit latency while running in real time; -1 leaves
  // the platform's choice.
  int max_cpu_wakeup_latency_us = 0;
  std::size_t prefault_stack_bytes = 64 * 1024;
  // The stack of every thread started after the memory is locked (rows, devices, libraries'
  // own threads that take the default): mlockall keeps all of it resident. 0: glibc's default,
  // RLIMIT_STACK (8 MiB).
  std::size_t thread_stack_bytes = 1024 * 1024;
  std::map<std::string, ThreadConfig, std::less<>> threads;
  std::map<std::string, TaskConfig, std::less<>> tasks;
  int health_stall_periods = 3;
  std::int64_t telemetry_status_period_ms = 10'000;
  BoardIo board;
  DevicesConfig devices;
  NavigationSection navigation;
  bool has_fleet = false;  // a `fleet` section: the goals come from VDA 5050 orders
  FleetConfig fleet;
  CobotSection cobot;
  ViewSection view;
  MappingSection mapping;
};

// `board_sections` are top-level sections that belong to the board the firmware runs on (the
// simulator's `sim`): accepted and left to the board to read. Any other unknown key is an error.
Result<FirmwareConfig> load_config(const std::string& path, std::span<const std::string_view> board_sections = {});
Result<FirmwareConfig> parse_config(std::string_view yaml_text, const std::string& source_name,
                                    std::span<const std::string_view> board_sections = {});

}  // namespace sen3bot::firmware
