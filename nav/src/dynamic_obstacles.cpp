#include "sen3bot/nav/dynamic_obstacles.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>

#include "grid_shift.hpp"
#include "sen3bot/nav/arena.hpp"

namespace sen3bot::nav {

namespace {

using geometry::Point2D;

}  // namespace

Status DynamicObstacleLayer::init(const Costmap2D& master, std::pmr::memory_resource& resource) {
  active_ = false;
  if (!config_.enabled) return Status::success();
  if (static_map_ != nullptr) {
    if (std::abs(master.resolution_m() - static_map_->resolution_m()) > 1e-9 ||
        std::abs(normalize_angle(master.yaw_rad() - static_map_->origin_yaw_rad())) > 1e-9) {
      return Error::format(Errc::config, "dynamic obstacles: the costmap and the static map differ in resolution or yaw");
    }
  }
  const int w = master.width();
  const int h = master.height();
  if (Status s = detector_.init(w, h, config_.detector, resource); !s) return s;
  if (Status s = blob_finder_.init(w, h, config_.tracker.max_blobs, resource); !s) return s;
  if (Status s = tracker_.init(config_.tracker, resource); !s) return s;
  const Status s = guarded("dynamic obstacles", [&]() -> Status {
    image_ = allocate_array<std::uint8_t>(resource, master.size());
    dynamic_ = allocate_array<std::uint8_t>(resource, master.size());
    mask_ = allocate_array<std::uint8_t>(resource, master.size());
    if (static_map_ != nullptr && config_.detector.static_mask_radius_m > 0.0) {
      map_near_ = allocate_array<std::uint8_t>(resource, static_map_->cell_count());
      // Every cell whose centre lies within the radius of an occupied cell's centre.
      const OccupancyMap& map = *static_map_;
      const double reach = config_.detector.static_mask_radius_m / map.resolution_m();
      const int k = static_cast<int>(std::floor(reach));
      const double reach2 = reach * reach + 1e-9;
      for (int r = 0; r < map.height(); ++r) {
        for (int c = 0; c < map.width(); ++c) {
          if (map.at(c, r) < kOccupiedOccupancy) continue;
          for (int dr = -k; dr <= k; ++dr) {
            for (int dc = -k; dc <= k; ++dc) {
              if (double(dc * dc + dr * dr) > reach2 || !map.in_bounds(c + dc, r + dr)) continue;
              map_near_[map.geometry().index(c + dc, r + dr)] = 1;
            }
          }
        }
      }
    }
    return Status::success();
  });
  if (!s) return s;
  blobs_ = {};
  detections_ = 0;
  active_ = true;
  return Status::success();
}

void DynamicObstacleLayer::on_window_moved(int shift_cols, int shift_rows) noexcept {
  if (!active_) return;
  detector_.shift(shift_cols, shift_rows);
  const int w = detector_.width();
  const int h = detector_.height();
  if (std::abs(shift_cols) >= w || std::abs(shift_rows) >= h) {
    std::fill(dynamic_.begin(), dynamic_.end(), std::uint8_t{0});
  } else {
    shift_grid(dynamic_, w, h, shift_cols, shift_rows, std::uint8_t{0});
  }
}

bool DynamicObstacleLayer::near_wall(double x_m, double y_m) const noexcept {
  int col = 0;
  int row = 0;
  if (!static_map_->world_to_cell(x_m, y_m, col, row)) return true;  // off the map: walled in
  return map_near_[static_map_->geometry().index(col, row)] != 0;
}

void DynamicObstacleLayer::turn_back_at_walls(hal::Nanos stamp_ns) noexcept {
  if (map_near_.empty()) return;
  const auto tracks = tracker_.tracks();
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    const DolTrack& track = tracks[i];
    if (!track.mover || track.last_hit_ns == stamp_ns) continue;  // seen: the filter follows it
    const double speed = std::hypot(track.kf.x[2], track.kf.x[3]);
    if (speed < config_.tracker.moving_min_speed_m_s) continue;
    const double ux = track.kf.x[2] / speed * kWallLookahead_m;
    const double uy = track.kf.x[3] / speed * kWallLookahead_m;
    if (near_wall(track.kf.x[0] + ux, track.kf.x[1] + uy) && !near_wall(track.kf.x[0] - ux, track.kf.x[1] - uy))
      tracker_.turn_back(i);
  }
}

void DynamicObstacleLayer::update(Costmap2D& master, const CostmapInputs& inputs) noexcept {
  if (!active_ || master.size() != image_.size()) return;
  if (inputs.scan != nullptr) {
    const auto cells = master.cells();
    for (std::size_t i = 0; i < cells.size(); ++i) image_[i] = cells[i] == kLethalCost ? 255 : 0;
    std::span<const std::uint8_t> mask;
    const std::span<const std::uint8_t> seen =
        observations_ != nullptr && observations_->seen_free().size() == mask_.size() ? observations_->seen_free()
                                                                                      : std::span<const std::uint8_t>{};
    if (!map_near_.empty() || !seen.empty()) {
      // Never dynamic: next to the static map, or where the laser never saw free floor (a face
      // that just came into view, not something that moved in). The window and the map share
      // the lattice and the yaw: a fixed cell offset.
      int off_c = 0;
      int off_r = 0;
      if (!map_near_.empty()) {
        double gx = 0.0;
        double gy = 0.0;
        static_map_->world_to_grid(master.origin_x_m(), master.origin_y_m(), gx, gy);
        off_c = static_cast<int>(std::lround(gx));
        off_r = static_cast<int>(std::lround(gy));
      }
      for (int r = 0; r < master.height(); ++r) {
        const int mr = r + off_r;
        const std::size_t row = master.index(0, r);
        for (int c = 0; c < master.width(); ++c) {
          const int mc = c + off_c;
          const std::size_t i = row + static_cast<std::size_t>(c);
          const bool near_map = !map_near_.empty() && static_map_->in_bounds(mc, mr) &&
                                map_near_[static_map_->geometry().index(mc, mr)] != 0;
          mask_[i] = near_map || (!seen.empty() && seen[i] == 0) ? 1 : 0;
        }
      }
      mask = mask_;
    }
    detector_.apply(image_, dynamic_, mask);
    blobs_ = blob_finder_.find(dynamic_, master.geometry(), config_.detector.min_blob_cells,
                               config_.detector.max_blob_cells, config_.detector.blob_link_cells);
    detections_ += blobs_.size();
    // Where the laser looked: from the sensor at the scan's pose, over the beams' sector, as
    // far as the obstacle layer marks (what lies beyond is not detected).
    const ProjectedScan& scan = *inputs.scan;
    LaserView view;
    const Pose2D& at = inputs.scan_pose;
    const double c = std::cos(at.theta_rad);
    const double s = std::sin(at.theta_rad);
    view.x_m = at.x_m + c * scan.mount().x_m - s * scan.mount().y_m;
    view.y_m = at.y_m + s * scan.mount().x_m + c * scan.mount().y_m;
    view.heading_rad = at.theta_rad + scan.mount().theta_rad;
    if (scan.size() > 1) {
      const Point2D first = scan.direction(0);
      const Point2D last = scan.direction(scan.size() - 1);
      view.half_angle_rad =
          0.5 * std::abs(normalize_angle(std::atan2(last.y_m, last.x_m) - std::atan2(first.y_m, first.x_m)));
    }
    if (observations_ != nullptr) view.range_m = observations_->config().obstacle_max_range_m;
    tracker_.update(blobs_, scan.stamp_ns(), view);
    tracker_.classify(image_, master.geometry());
    if (people_ != nullptr) {
      // Walking people the sensors see now, predicted to the scan: their word for a track.
      std::array<Vouch, msg::People::kMax> vouches{};
      std::size_t n = 0;
      const double walking = 2.0 * config_.tracker.moving_min_speed_m_s;
      for (std::size_t i = 0; i < std::min<std::size_t>(people_->count, msg::People::kMax); ++i) {
        const msg::TrackedPerson& p = people_->items[i];
        if (p.hidden || std::hypot(p.vx_m_s, p.vy_m_s) < walking) continue;
        const double dt = static_cast<double>(scan.stamp_ns() - people_->stamp_ns) * 1e-9;
        vouches[n++] = {p.x_m + p.vx_m_s * dt, p.y_m + p.vy_m_s * dt, p.vx_m_s, p.vy_m_s};
      }
      vouched_ += tracker_.vouch(std::span<const Vouch>(vouches.data(), n));
    }
    turn_back_at_walls(scan.stamp_ns());
  }
  for (const DolTrack& track : tracker_.tracks()) {
    if (!tracker_.moving(track) || !track.kf.finite()) continue;
    const Point2D p = MoverTracker::predict_position(track, inputs.now_ns);
    const Point2D v = tracker_.velocity(track);
    if (std::sqrt(v.x_m * v.x_m + v.y_m * v.y_m) >= config_.cost.min_speed_m_s) {
      paint_mover(config_.cost, p.x_m, p.y_m, v.x_m, v.y_m, master);
    }
    paint_core(p.x_m, p.y_m, config_.cost.lethal_radius_m, master);
  }
}

void DynamicObstacleLayer::movers(hal::Nanos stamp_ns, msg::MovingObstacles& out) const noexcept {
  out.count = 0;
  out.candidate_count = 0;
  out.stamp_ns = stamp_ns;
  if (!active_) return;
  for (const DolTrack& track : tracker_.tracks()) {
    if (!tracker_.moving(track) || !track.kf.finite()) continue;
    if (out.count >= msg::MovingObstacles::kMax) break;
    put(track, stamp_ns, out.items[out.count++]);
  }
  for (const DolTrack& track : tracker_.tracks()) {
    if (!tracker_.candidate(track) || !track.kf.finite()) continue;
    if (out.count + out.candidate_count >= msg::MovingObstacles::kMax) break;
    put(track, stamp_ns, out.items[out.count + out.candidate_count++]);
  }
}

void DynamicObstacleLayer::put(const DolTrack& track, hal::Nanos stamp_ns, msg::MovingObstacle& m) const noexcept {
  const DolTrack at = tracker_.predicted(track, stamp_ns);
  m.id = track.id;
  m.x_m = at.kf.x[0];
  m.y_m = at.kf.x[1];
  const Point2D v = tracker_.velocity(at);
  m.vx_m_s = v.x_m;
  m.vy_m_s = v.y_m;
  m.radius_m = track.radius_m;
  m.position_var_m2 = (at.kf.cov(0, 0) + at.kf.cov(1, 1)) / 2.0;
  m.velocity_var_m2_s2 = (at.kf.cov(2, 2) + at.kf.cov(3, 3)) / 2.0;
}

}  // namespace sen3bot::nav
