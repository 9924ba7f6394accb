#pragma once
// Map building on the robot: the `mapping` row keeps the wheels' recent poses every period and,
// five times a second, takes the newest laser scan with the odometry pose of its stamp and hands it to the SLAM mapper (slam/mapper.hpp), and when the firmware
// stops writes the map in the map_server format (YAML + PGM) `navigation.map` reads, with the
// solved pose of every scan beside it. The robot is driven meanwhile by whatever drives it.
//
// Memory: the mapper's arena comes from the row's budget (tasks.mapping.arena_bytes; the init
// error says how much the configuration needs). Steps allocate nothing, except the pose graph's
// solve after a loop closure (Eigen, about 15 small blocks an iteration: pose_graph.cpp), which
// is why the row has a thread of its own; allocations() counts the solves.
#include <cstddef>
#include <cstdint>
#include <memory_resource>
#include <optional>
#include <span>
#include <string>

#include "sen3bot/msg/messages.hpp"
#include "sen3bot/nav/odometry_history.hpp"
#include "sen3bot/slam/mapper.hpp"
#include "sen3bot/tasks/task.hpp"
#include "sen3bot/tasks/topic.hpp"

namespace sen3bot::firmware {

// mapping: the section's keys.
struct MappingConfig {
  std::string out_path;                 // the map's YAML; the PGM and `<stem>.poses` go beside it
  std::size_t max_scans = 20'000;       // an hour at 5 scans a second
  std::size_t beams = 181;              // returns kept per scan (evenly thinned beyond)
  slam::MapperConfig mapper;            // resolution_m, scans_per_submap, max_range_m from the file
  std::size_t finished_submap_bytes = 64u << 20;
  double scan_interval_s = 0.15;        // scans closer in time than this are skipped
  // Where the robot stands when the mapping row starts (its first odometry), in the site's frame:
  // the map and the poses are written in that frame (origin and yaw of the map), so goals given
  // in site coordinates hold.
  nav::Pose2D start_pose;
};

struct MappingTopics {
  const tasks::Topic<msg::ScanMessage>& scan;
  const tasks::Topic<msg::Odometry>& odometry;
};

class MappingTask final : public tasks::Task {
 public:
  MappingTask(const MappingConfig& config, MappingTopics topics, msg::SensorMount laser_mount) noexcept;

  // The arena a configuration needs (what tasks.mapping.arena_bytes must hold).
  [[nodiscard]] static std::size_t arena_bytes_needed(const MappingConfig& config) noexcept;

  Status init(std::pmr::memory_resource& arena) override;
  void step(const tasks::StepContext& context) override;
  // Finishes the map and writes it (blocks: files).
  void shutdown() override;

  [[nodiscard]] const slam::Mapper& mapper() const noexcept { return mapper_; }
  [[nodiscard]] std::uint64_t scans_taken() const noexcept { return taken_; }
  [[nodiscard]] std::uint64_t scans_refused() const noexcept { return refused_; }  // mapper full or bad input
  // The first error the mapper or the writer met (empty: none).
  [[nodiscard]] const char* last_error() const noexcept { return error_.c_str(); }
  [[nodiscard]] bool written() const noexcept { return written_; }
  // The i-th scan's solved pose in the site's frame (start_pose), as the poses file has it.
  [[nodiscard]] nav::Pose2D site_pose(std::size_t i) const;
  // Where the mapper's frame lies in the site's frame (the map is written in the site's).
  [[nodiscard]] nav::Pose2D site_frame() const noexcept;
  // When the i-th scan the mapper took was measured (its stamp).
  [[nodiscard]] hal::Nanos scan_stamp(std::size_t i) const noexcept { return i < taken_ ? stamps_[i] : 0; }

 private:
  MappingConfig config_;
  MappingTopics topics_;
  msg::SensorMount mount_;
  slam::Mapper mapper_;
  slam::LaserRecord record_;
  // Where the wheels were when each scan was taken: a 361-beam LMS200 scan is 0.2-0.3 s old when
  // it is read, and the robot turns 10-20 degrees in that time (odometry_history.hpp).
  nav::OdometryHistory history_;
  hal::Nanos last_scan_stamp_ = 0;
  // The odometry when the row started and at the mapper's first scan: the robot may have moved
  // in between, and the mapper's frame is its pose at that scan.
  std::optional<nav::Pose2D> start_odometry_;
  nav::Pose2D first_scan_odometry_;
  std::span<hal::Nanos> stamps_;  // per scan taken, for the poses file
  std::uint64_t last_scan_sequence_ = 0;
  std::uint64_t taken_ = 0;
  std::uint64_t refused_ = 0;
  Error error_;
  bool written_ = false;
};

}  // namespace sen3bot::firmware
