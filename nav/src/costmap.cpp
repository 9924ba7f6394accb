#include "sen3bot/nav/costmap.hpp"

#include <algorithm>
#include <cmath>
#include <cstring>
#include <limits>
#include <utility>

#include "sen3bot/nav/arena.hpp"

namespace sen3bot::nav {

Status Costmap2D::init(int width, int height, double resolution_m, std::pmr::memory_resource& resource, double yaw_rad) {
  if (width <= 0 || height <= 0 || !(resolution_m > 0.0)) {
    return Error::format(Errc::config, "costmap: bad size %d x %d at %g m", width, height, resolution_m);
  }
  if (static_cast<std::size_t>(width) * static_cast<std::size_t>(height) > kMaxMapCells) {
    return Error::format(Errc::config, "costmap: %d x %d cells is too large", width, height);
  }
  return guarded("costmap", [&]() -> Status {
    cells_ = allocate_array<std::uint8_t>(resource, static_cast<std::size_t>(width) * static_cast<std::size_t>(height));
    geometry_ = GridGeometry(width, height, resolution_m, 0.0, 0.0, yaw_rad);
    return Status::success();
  });
}

void Costmap2D::fill(std::uint8_t cost) noexcept { std::fill(cells_.begin(), cells_.end(), cost); }

// --- LayeredCostmap -----------------------------------------------------------------------

Status LayeredCostmap::add_layer(CostmapLayer& layer) {
  if (!layers_.push_back(&layer)) {
    return Error::format(Errc::capacity, "costmap: more than %zu layers", kMaxLayers);
  }
  return Status::success();
}

Status LayeredCostmap::init(const CostmapConfig& config, std::pmr::memory_resource& resource) {
  config_ = config;
  if (!(config.resolution_m > 0.0) || !(config.width_m > 0.0) || !(config.height_m > 0.0)) {
    return Error::format(Errc::config, "costmap: width_m, height_m and resolution_m must be > 0");
  }
  const int width = static_cast<int>(std::lround(config.width_m / config.resolution_m));
  const int height = static_cast<int>(std::lround(config.height_m / config.resolution_m));
  if (Status s = master_.init(width, height, config.resolution_m, resource, config.yaw_rad); !s) return s;
  master_.set_origin(config.origin_x_m, config.origin_y_m);
  window_placed_ = false;
  return init_layers(resource);
}

Status LayeredCostmap::init_over_map(const OccupancyMap& map, std::pmr::memory_resource& resource) {
  config_ = CostmapConfig{};
  config_.rolling = false;
  config_.resolution_m = map.resolution_m();
  config_.width_m = map.width() * map.resolution_m();
  config_.height_m = map.height() * map.resolution_m();
  config_.origin_x_m = map.origin_x_m();
  config_.origin_y_m = map.origin_y_m();
  config_.yaw_rad = map.origin_yaw_rad();
  if (Status s = master_.init(map.width(), map.height(), map.resolution_m(), resource, map.origin_yaw_rad()); !s) return s;
  master_.set_origin(map.origin_x_m(), map.origin_y_m());
  return init_layers(resource);
}

Status LayeredCostmap::init_layers(std::pmr::memory_resource& resource) {
  for (CostmapLayer* layer : layers_) {
    if (Status s = layer->init(master_, resource); !s) return s;
  }
  return Status::success();
}

void LayeredCostmap::move_window(double robot_x_m, double robot_y_m) noexcept {
  // In the lattice's own (possibly rotated) grid frame, in cells.
  const GridGeometry lattice(1, 1, master_.resolution_m(), config_.lattice_x_m, config_.lattice_y_m, config_.yaw_rad);
  double gx = 0.0;
  double gy = 0.0;
  lattice.world_to_grid(robot_x_m, robot_y_m, gx, gy);
  const double cells_x = std::floor(gx - master_.width() / 2.0);
  const double cells_y = std::floor(gy - master_.height() / 2.0);
  if (window_placed_) {
    double ox = 0.0;
    double oy = 0.0;
    lattice.world_to_grid(master_.origin_x_m(), master_.origin_y_m(), ox, oy);
    const int shift_c = static_cast<int>(std::lround(cells_x - ox));
    const int shift_r = static_cast<int>(std::lround(cells_y - oy));
    if (shift_c == 0 && shift_r == 0) return;
    for (CostmapLayer* layer : layers_) layer->on_window_moved(shift_c, shift_r);
  }
  double new_x = 0.0;
  double new_y = 0.0;
  lattice.grid_to_world(cells_x, cells_y, new_x, new_y);
  master_.set_origin(new_x, new_y);
  window_placed_ = true;
}

void LayeredCostmap::update(const CostmapInputs& inputs) noexcept {
  if (config_.rolling) move_window(inputs.robot_pose.x_m, inputs.robot_pose.y_m);
  master_.fill(kFreeCost);
  for (CostmapLayer* layer : layers_) layer->update(master_, inputs);
}

// --- StaticLayer --------------------------------------------------------------------------

Status StaticLayer::init(const Costmap2D& master, std::pmr::memory_resource& resource) {
  if (std::abs(master.resolution_m() - map_.resolution_m()) > 1e-9) {
    return Error::format(Errc::config, "static layer: costmap resolution %g m differs from the map's %g m",
                         master.resolution_m(), map_.resolution_m());
  }
  if (std::abs(normalize_angle(master.yaw_rad() - map_.origin_yaw_rad())) > 1e-9) {
    return Error::format(Errc::config, "static layer: costmap yaw %g rad differs from the map's origin yaw %g rad",
                         master.yaw_rad(), map_.origin_yaw_rad());
  }
  return guarded("static layer", [&]() -> Status {
    costs_ = allocate_array<std::uint8_t>(resource, map_.cell_count());
    const auto& cells = map_.cells();
    for (std::size_t i = 0; i < cells.size(); ++i) {
      const int v = cells[i];
      std::uint8_t cost = kFreeCost;
      if (v < 0) {
        cost = config_.track_unknown ? kNoInformationCost : kFreeCost;
      } else if (v >= config_.lethal_threshold) {
        cost = kLethalCost;
      }
      costs_[i] = cost;
    }
    return Status::success();
  });
}

void StaticLayer::update(Costmap2D& master, const CostmapInputs& /*inputs*/) noexcept {
  // The master's origin in the map's grid: both grids share the yaw and the cell lattice.
  double gx = 0.0;
  double gy = 0.0;
  map_.world_to_grid(master.origin_x_m(), master.origin_y_m(), gx, gy);
  const int off_c = static_cast<int>(std::lround(gx));
  const int off_r = static_cast<int>(std::lround(gy));
  const std::uint8_t outside = config_.track_unknown ? kNoInformationCost : kFreeCost;
  for (int r = 0; r < master.height(); ++r) {
    const int mr = r + off_r;
    for (int c = 0; c < master.width(); ++c) {
      const int mc = c + off_c;
      master.set(c, r, map_.in_bounds(mc, mr) ? costs_[static_cast<std::size_t>(mr) * map_.width() + mc] : outside);
    }
  }
}

// --- ObstacleLayer ------------------------------------------------------------------------

Status ObstacleLayer::init(const Costmap2D& master, std::pmr::memory_resource& resource) {
  if (Status s = grid_.init(master.width(), master.height(), master.resolution_m(), resource, master.yaw_rad()); !s) return s;
  grid_.set_origin(master.origin_x_m(), master.origin_y_m());
  return guarded("obstacle layer", [&]() -> Status {
    scratch_ = allocate_array<std::uint8_t>(resource, master.size());
    seen_free_ = allocate_array<std::uint8_t>(resource, master.size());
    return Status::success();
  });
}

void ObstacleLayer::clear() noexcept {
  grid_.fill(kFreeCost);
  std::fill(seen_free_.begin(), seen_free_.end(), std::uint8_t{0});
}

void ObstacleLayer::on_window_moved(int shift_cols, int shift_rows) noexcept {
  shift_grid(grid_.cells(), shift_cols, shift_rows);
  shift_grid(seen_free_, shift_cols, shift_rows);
}

void ObstacleLayer::shift_grid(std::span<std::uint8_t> cells, int shift_cols, int shift_rows) noexcept {
  const int w = grid_.width();
  const int h = grid_.height();
  std::fill(scratch_.begin(), scratch_.end(), std::uint8_t{0});
  for (int r = 0; r < h; ++r) {
    const int src_r = r + shift_rows;
    if (src_r < 0 || src_r >= h) continue;
    for (int c = 0; c < w; ++c) {
      const int src_c = c + shift_cols;
      if (src_c < 0 || src_c >= w) continue;
      scratch_[grid_.index(c, r)] = cells[grid_.index(src_c, src_r)];
    }
  }
  std::memcpy(cells.data(), scratch_.data(), scratch_.size());
}

void ObstacleLayer::raytrace(int c0, int r0, int c1, int r1, int max_cells) noexcept {
  // From the sensor cell towards the endpoint cell, the endpoint itself excluded.
  walk_line(c0, r0, c1, r1, [&](int c, int r, int step) noexcept {
    if (step >= max_cells) return false;
    if (grid_.in_bounds(c, r)) {
      grid_.set(c, r, kFreeCost);
      seen_free_[grid_.index(c, r)] = 1;
      return true;
    }
    return step == 0;  // left the window: nothing further can be inside again on a straight line
  });
}

void ObstacleLayer::clear_sonar_cones(const CostmapInputs& inputs) noexcept {
  const msg::Sonar& sonar = *inputs.sonar;
  const double res = grid_.resolution_m();
  const Pose2D& robot = inputs.robot_pose;
  const double tan_half = std::tan(config_.sonar_half_angle_rad);
  for (std::size_t d = 0; d < std::min<std::size_t>(sonar.count, msg::Sonar::kMax); ++d) {
    const hal::Nanos stamp = sonar.stamp_ns[d];
    const double range = sonar.range_m[d];
    if (stamp <= 0 || static_cast<double>(inputs.now_ns - stamp) > config_.sonar_max_age_s * 1e9) continue;
    if (!(range < sonar.max_range_m)) continue;  // no echo: may be a miss
    const double clear_m = std::min(range - config_.sonar_margin_m, config_.raytrace_max_range_m);
    if (!(clear_m > 0.0)) continue;
    const Pose2D disc = apply_motion(robot, sonar.mount[d]);
    const double c = std::cos(disc.theta_rad);
    const double s = std::sin(disc.theta_rad);
    // The cone's bounding box in cells (the grid may be rotated), then each cell in it tested.
    int c0 = std::numeric_limits<int>::max(), r0 = c0, c1 = std::numeric_limits<int>::min(), r1 = c1;
    const double half_width = clear_m * tan_half;
    for (const auto& [ahead, side] : {std::pair{0.0, 0.0}, std::pair{clear_m, -half_width}, std::pair{clear_m, half_width}}) {
      int col = 0;
      int row = 0;
      (void)grid_.world_to_cell(disc.x_m + c * ahead - s * side, disc.y_m + s * ahead + c * side, col, row);
      c0 = std::min(c0, col);
      c1 = std::max(c1, col);
      r0 = std::min(r0, row);
      r1 = std::max(r1, row);
    }
    c0 = std::max(c0, 0);
    r0 = std::max(r0, 0);
    c1 = std::min(c1, grid_.width() - 1);
    r1 = std::min(r1, grid_.height() - 1);
    for (int row = r0; row <= r1; ++row) {
      for (int col = c0; col <= c1; ++col) {
        if (grid_.at(col, row) != kLethalCost) continue;
        double x = 0.0;
        double y = 0.0;
        grid_.cell_to_world(col, row, x, y);
        const double along = c * (x - disc.x_m) + s * (y - disc.y_m);
        const double across = -s * (x - disc.x_m) + c * (y - disc.y_m);
        // The whole cell nearer than the echo's clearing distance, its centre inside the cone.
        if (along <= 0.0 || along + res > clear_m || std::abs(across) > along * tan_half) continue;
        grid_.set(col, row, kFreeCost);
      }
    }
  }
}

void ObstacleLayer::update(Costmap2D& master, const CostmapInputs& inputs) noexcept {
  grid_.set_origin(master.origin_x_m(), master.origin_y_m());
  const double res = grid_.resolution_m();
  // Before the scan: a mark the laser makes now is never taken back by a sonar cone.
  if (config_.sonar_clearing && inputs.sonar != nullptr) clear_sonar_cones(inputs);
  if (inputs.scan != nullptr) {
    const ProjectedScan& scan = *inputs.scan;
    // Beams are in the robot frame; the robot stood at scan_pose when the scan was taken.
    const Pose2D& p = inputs.scan_pose;
    const double pc = std::cos(p.theta_rad);
    const double ps = std::sin(p.theta_rad);
    const GridGeometry& geometry = grid_.geometry();
    const auto to_grid = [&](double x_m, double y_m, double& gx, double& gy) {
      geometry.world_to_grid(p.x_m + pc * x_m - ps * y_m, p.y_m + ps * x_m + pc * y_m, gx, gy);
    };
    const SensorMount& mount = scan.mount();
    double sx = 0.0;
    double sy = 0.0;
    to_grid(mount.x_m, mount.y_m, sx, sy);
    const int c0 = static_cast<int>(std::floor(sx));
    const int r0 = static_cast<int>(std::floor(sy));
    // Clearing first, then marking, so a ray never erases another beam's endpoint.
    for (std::size_t i = 0; i < scan.size(); ++i) {
      const bool no_return = scan.no_return(i);
      if (!scan.valid(i) && !(no_return && config_.clear_no_return)) continue;
      const double range = scan.range_m(i);
      const double clear_range = std::min(no_return ? config_.raytrace_max_range_m : range, config_.raytrace_max_range_m);
      if (clear_range <= config_.raytrace_min_range_m) continue;
      const Point2D& u = scan.direction(i);
      double ex = 0.0;
      double ey = 0.0;
      to_grid(mount.x_m + u.x_m * clear_range, mount.y_m + u.y_m * clear_range, ex, ey);
      const int max_cells = static_cast<int>(std::ceil(2.0 * clear_range / res)) + 2;
      const int c1 = static_cast<int>(std::floor(ex));
      const int r1 = static_cast<int>(std::floor(ey));
      raytrace(c0, r0, c1, r1, max_cells);
      // A ray cut short by the range limit clears its last cell too.
      if (clear_range < range && grid_.in_bounds(c1, r1)) {
        grid_.set(c1, r1, kFreeCost);
        seen_free_[grid_.index(c1, r1)] = 1;
      }
    }
    for (std::size_t i = 0; i < scan.size(); ++i) {
      if (!scan.valid(i)) continue;
      const double range = scan.range_m(i);
      if (range > config_.obstacle_max_range_m || range < config_.obstacle_min_range_m) continue;
      const Point2D& e = scan.end(i);
      int c = 0;
      int r = 0;
      if (grid_.world_to_cell(p.x_m + pc * e.x_m - ps * e.y_m, p.y_m + ps * e.x_m + pc * e.y_m, c, r)) {
        grid_.set(c, r, kLethalCost);
      }
    }
  }
  if (config_.footprint_clearing) {
    const int reach = static_cast<int>(std::ceil(config_.footprint_clearing_radius_m / res));
    int rc = 0;
    int rr = 0;
    grid_.world_to_cell(inputs.robot_pose.x_m, inputs.robot_pose.y_m, rc, rr);
    const double limit2 = std::pow(config_.footprint_clearing_radius_m / res, 2);
    for (int r = rr - reach; r <= rr + reach; ++r) {
      for (int c = rc - reach; c <= rc + reach; ++c) {
        if (grid_.in_bounds(c, r) && double((c - rc) * (c - rc) + (r - rr) * (r - rr)) <= limit2) grid_.set(c, r, kFreeCost);
      }
    }
  }
  // Max-combine into the master (Nav2's combination_method 1).
  const auto marks = grid_.cells();
  auto out = master.cells();
  for (std::size_t i = 0; i < out.size(); ++i) {
    if (marks[i] > out[i] || out[i] == kNoInformationCost) {
      if (marks[i] != kFreeCost) out[i] = marks[i];
    }
  }
}

// --- InflationLayer -----------------------------------------------------------------------

std::uint8_t InflationLayer::cost_at(double distance_m, const InflationLayerConfig& config) noexcept {
  if (distance_m <= 0.0) return kLethalCost;
  if (distance_m <= config.inscribed_radius_m) return kInscribedCost;
  if (distance_m > config.inflation_radius_m) return kFreeCost;
  const double factor = std::exp(-config.cost_scaling_factor * (distance_m - config.inscribed_radius_m));
  return static_cast<std::uint8_t>((kInscribedCost - 1) * factor);
}

Status InflationLayer::init(const Costmap2D& master, std::pmr::memory_resource& resource) {
  if (config_.inflation_radius_m < config_.inscribed_radius_m || config_.cost_scaling_factor < 0.0) {
    return Error::format(Errc::config, "inflation: inflation_radius_m %g must be >= inscribed_radius_m %g, csf >= 0",
                         config_.inflation_radius_m, config_.inscribed_radius_m);
  }
  const double res = master.resolution_m();
  radius_cells_ = static_cast<int>(std::ceil(config_.inflation_radius_m / res));
  return guarded("inflation layer", [&]() -> Status {
    const auto line = static_cast<std::size_t>(std::max(master.width(), master.height()));
    if (Status s = transform_.init(line, resource); !s) return s;
    distance2_ = allocate_array<float>(resource, master.size());
    const std::size_t lut_size = static_cast<std::size_t>(radius_cells_) * radius_cells_ + 1;
    lut_ = allocate_array<std::uint8_t>(resource, lut_size);
    for (std::size_t k = 0; k < lut_size; ++k) lut_[k] = cost_at(std::sqrt(static_cast<double>(k)) * res, config_);
    return Status::success();
  });
}

void InflationLayer::inflate(Costmap2D& grid) noexcept {
  constexpr float kInf = std::numeric_limits<float>::infinity();
  const auto cells = grid.cells();
  if (cells.size() > distance2_.size()) return;  // not the grid init() was sized for
  for (std::size_t i = 0; i < cells.size(); ++i) distance2_[i] = cells[i] == kLethalCost ? 0.0f : kInf;
  // Sized at init() for this grid's master, so it cannot refuse the grid.
  (void)transform_.transform(distance2_, grid.width(), grid.height());
  const float limit = static_cast<float>(lut_.size() - 1);
  for (std::size_t i = 0; i < cells.size(); ++i) {
    const float d2 = distance2_[i];
    if (!(d2 <= limit)) continue;
    const std::uint8_t cost = lut_[static_cast<std::size_t>(d2 + 0.5f)];
    std::uint8_t& cell = cells[i];
    if (cell == kNoInformationCost) {
      if (cost >= kInscribedCost) cell = cost;
    } else if (cost > cell) {
      cell = cost;
    }
  }
}

void InflationLayer::update(Costmap2D& master, const CostmapInputs& /*inputs*/) noexcept { inflate(master); }

}  // namespace sen3bot::nav
