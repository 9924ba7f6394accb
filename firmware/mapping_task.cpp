#include "mapping_task.hpp"

#include <algorithm>
#include <cstdio>
#include <filesystem>
#include <optional>

#include "sen3bot/nav/arena.hpp"
#include "sen3bot/nav/map.hpp"
#include "task_table.hpp"
#include "wiring.hpp"

namespace sen3bot::firmware {
namespace {

slam::MapperCapacity capacity_of(const MappingConfig& c) noexcept {
  slam::MapperCapacity cap;
  cap.scans = c.max_scans;
  cap.beams = c.beams;
  cap.finished_submap_bytes = c.finished_submap_bytes;
  return cap;
}

}  // namespace

MappingTask::MappingTask(const MappingConfig& config, MappingTopics topics, msg::SensorMount laser_mount) noexcept
    : config_(config), topics_(topics), mount_(laser_mount) {}

std::size_t MappingTask::arena_bytes_needed(const MappingConfig& config) noexcept {
  return slam::Mapper::bytes_for(config.mapper, capacity_of(config)) + config.max_scans * sizeof(hal::Nanos) + 4096;
}

Status MappingTask::init(std::pmr::memory_resource& arena) {
  if (Status s = mapper_.init(arena, config_.mapper, capacity_of(config_)); !s)
    return Error::format(s.error().code(), "%s (the mapping row needs %zu bytes for max_scans %zu)", s.error().c_str(),
                         arena_bytes_needed(config_), config_.max_scans);
  return nav::guarded("mapping", [&]() -> Status {
    stamps_ = nav::allocate_array<hal::Nanos>(arena, config_.max_scans);
    return {};
  });
}

void MappingTask::step(const tasks::StepContext&) {
  tasks::Sample<msg::Odometry> odometry;
  if (topics_.odometry.read(odometry) && odometry.value.valid) {
    history_.push(odometry.value);
    if (!start_odometry_) start_odometry_ = nav::Pose2D{odometry.value.x_m, odometry.value.y_m, odometry.value.theta_rad};
  }
  tasks::Sample<msg::ScanMessage> scan;
  if (!topics_.scan.read(scan) || scan.sequence == last_scan_sequence_) return;
  const msg::ScanMessage& s = scan.value;
  if (last_scan_stamp_ != 0 && static_cast<double>(s.stamp_ns - last_scan_stamp_) * 1e-9 < config_.scan_interval_s) return;
  nav::Pose2D at_scan;
  if (!history_.pose_at(s.stamp_ns, at_scan)) return;  // no odometry of its time yet
  last_scan_sequence_ = scan.sequence;
  last_scan_stamp_ = s.stamp_ns;
  record_.source_line = scan.sequence;
  record_.time_s = static_cast<double>(s.stamp_ns) * 1e-9;
  record_.odometry = at_scan;
  record_.laser_mount = {mount_.x_m, mount_.y_m, mount_.theta_rad};
  record_.start_angle_rad = s.angle_min_rad;
  record_.angle_increment_rad = s.increment_rad;
  record_.max_range_m = s.range_max_m;
  record_.count = std::min<std::uint32_t>(s.count, msg::ScanMessage::kMaxBeams);
  std::copy_n(s.ranges_m.begin(), record_.count, record_.ranges.begin());
  if (Status st = mapper_.add(record_); !st) {
    if (refused_++ == 0) error_ = st.error();
    return;
  }
  if (taken_ == 0) first_scan_odometry_ = at_scan;
  stamps_[taken_++] = s.stamp_ns;
}

// The mapper's frame is the robot's pose at its first scan; the robot may have moved since the row
// started (start_pose), by what the odometry says.
nav::Pose2D MappingTask::site_frame() const noexcept {
  return nav::apply_motion(config_.start_pose,
                           nav::relative_pose(start_odometry_.value_or(first_scan_odometry_), first_scan_odometry_));
}

nav::Pose2D MappingTask::site_pose(std::size_t i) const { return nav::apply_motion(site_frame(), mapper_.scan_pose(i)); }

void MappingTask::shutdown() {
  if (written_ || config_.out_path.empty()) return;
  if (mapper_.scan_count() == 0) {
    error_ = Error(Errc::not_found, "mapping: no scan was taken, no map written");
    return;
  }
  if (Status s = mapper_.finish(); !s) {
    error_ = s.error();
    return;
  }
  Result<nav::OccupancyMap> drawn = mapper_.render(config_.mapper.resolution_m);
  if (!drawn) {
    error_ = drawn.error();
    return;
  }
  const nav::Pose2D first = site_frame();
  const nav::Pose2D origin =
      nav::apply_motion(first, {drawn->origin_x_m(), drawn->origin_y_m(), drawn->origin_yaw_rad()});
  std::optional<nav::OccupancyMap> map;
  map.emplace(drawn->width(), drawn->height(), drawn->resolution_m(), origin.x_m, origin.y_m, origin.theta_rad);
  for (int r = 0; r < drawn->height(); ++r)
    for (int c = 0; c < drawn->width(); ++c) map->set(c, r, drawn->at(c, r));
  char comment[160];
  std::snprintf(comment, sizeof comment, "Sen3Bot map built on the robot from %zu scans", mapper_.scan_count());
  if (Status s = nav::save_map(*map, config_.out_path, comment); !s) {
    error_ = s.error();
    return;
  }
  const std::string poses = (std::filesystem::path(config_.out_path).replace_extension(".poses")).string();
  if (Status s = slam::write_poses(mapper_, poses, first); !s) error_ = s.error();
  written_ = true;
}

Status make_mapping(Wiring& w) {
  if (!w.config.mapping.enabled) return w.absent("needs a mapping section");
  if (!w.config.devices.has_laser || !w.config.devices.has_base) return w.absent("needs devices.laser and devices.base");
  w.sends("the map (map_server YAML + PGM) and each scan's pose, when the firmware stops");
  w.make<MappingTask>(w.config.mapping.task, MappingTopics{w.reads(&Topics::scan), w.reads(&Topics::odometry)},
                      w.shared.laser_mount);
  return Status::success();
}

}  // namespace sen3bot::firmware
