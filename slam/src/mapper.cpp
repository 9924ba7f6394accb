#include "sen3bot/slam/mapper.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <vector>

#include "sen3bot/nav/arena.hpp"

namespace sen3bot::slam {
namespace {

using Clock = std::chrono::steady_clock;

double seconds_since(Clock::time_point t0) noexcept {
  return std::chrono::duration<double>(Clock::now() - t0).count();
}

nav::Pose2D inverse(const nav::Pose2D& p) noexcept { return nav::relative_pose(p, {}); }

std::size_t submaps_for(const MapperConfig& c, const MapperCapacity& cap) noexcept {
  if (cap.submaps != 0) return cap.submaps;
  return cap.scans / static_cast<std::size_t>(std::max(c.scans_per_submap, 1)) + 3;
}

// What the loop search needs a side of: the largest finished submap (cropped from a build grid).
int loop_side(const MapperConfig& c) noexcept { return c.submap_side_cells; }

// Two edges a scan to the submaps it went into, and room for a loop closure a scan.
std::size_t graph_edges(std::size_t scans) noexcept { return 3 * scans + 16; }

}  // namespace

std::size_t Mapper::bytes_for(const MapperConfig& config, const MapperCapacity& capacity) noexcept {
  const std::size_t submaps = submaps_for(config, capacity);
  const auto pad = static_cast<std::size_t>((1 << std::clamp(config.loop.depth, 1, 10)) - 1);
  const auto side = static_cast<std::size_t>(loop_side(config)) + pad;
  const std::size_t loop_bytes = side * side * static_cast<std::size_t>(config.loop.depth + 1) +
                                 capacity.beams * 721 * 2 * sizeof(int) + 721 * 64 * 16 + 4096;
  return 2 * BuildGrid::bytes_for(config.submap_side_cells) + loop_bytes +
         capacity.scans * (sizeof(Node) + capacity.beams * sizeof(PointF)) + capacity.beams * sizeof(PointF) +
         submaps * sizeof(Submap) + capacity.beams * 2 * sizeof(int) + 129 * 129 * sizeof(float) +
         capacity.finished_submap_bytes + 4096;
}

Status Mapper::init(std::pmr::memory_resource& arena, const MapperConfig& config, const MapperCapacity& capacity) {
  if (capacity.scans == 0 || capacity.beams == 0 || capacity.beams > kMaxBeams)
    return Error(Errc::invalid_argument, "mapper: room for at least one scan of 1 to 1081 returns");
  if (config.scans_per_submap < 2 || !(config.min_range_m >= 0.0) || !(config.max_range_m > config.min_range_m) ||
      config.loop_every_n_scans < 1 || !(config.loop_min_score > 0.0 && config.loop_min_score < 1.0))
    return Error(Errc::invalid_argument,
                 "mapper: at least 2 scans a submap, 0 <= min range < max range, a loop score in (0, 1)");
  config_ = config;
  capacity_ = capacity;
  arena_ = &arena;
  for (BuildGrid& g : grids_)
    if (Status s = g.init(arena, config.submap_side_cells, config.resolution_m, config.insertion); !s) return s;
  if (Status s = matcher_.init(arena, capacity.beams, config.local); !s) return s;
  if (Status s = loops_.init(arena, loop_side(config), capacity.beams, config.resolution_m, config.loop); !s) return s;
  const std::size_t submaps = submaps_for(config, capacity);
  if (Status s = nav::guarded("mapper", [&]() -> Status {
        nodes_ = nav::allocate_array<Node>(arena, capacity.scans);
        points_ = nav::allocate_array<PointF>(arena, capacity.scans * capacity.beams);
        scratch_ = nav::allocate_array<PointF>(arena, capacity.beams);
        submaps_ = nav::allocate_array<Submap>(arena, submaps);
        return {};
      });
      !s)
    return s;
  graph_.emplace(capacity.scans + submaps, graph_edges(capacity.scans));
  return {};
}

nav::Pose2D Mapper::global_estimate(const nav::Pose2D& local) const noexcept {
  return nav::apply_motion(correction_, local);
}

nav::Point2D Mapper::submap_middle(const Submap& s) const noexcept {
  const double n = std::max<double>(s.scans, 1.0);
  const nav::Pose2D middle_local{s.sum_x / n, s.sum_y / n, 0.0};
  // The middle moves with the submap's solved pose.
  const nav::Pose2D g = nav::apply_motion(graph_pose(s.graph), nav::relative_pose(s.local, middle_local));
  return {g.x_m, g.y_m};
}

Status Mapper::start_submap(const nav::Pose2D& at) {
  if (submap_count_ == submaps_.size())
    return Error::format(Errc::capacity, "mapper: more than %zu submaps", submaps_.size());
  const int grid = grid_used_[0] ? 1 : 0;
  grid_used_[grid] = true;
  grids_[grid].reset();
  Submap& s = submaps_[submap_count_];
  s = Submap{};
  s.local = {at.x_m, at.y_m, 0.0};
  s.grid = grid;
  s.first_node = static_cast<std::uint32_t>(node_count_);
  Result<std::uint32_t> id = graph_->add_node(global_estimate(s.local));
  if (!id) return id.error();
  s.graph = *id;
  active_[active_count_++] = submap_count_++;
  ++stats_.submaps;
  return {};
}

Status Mapper::finish_oldest() {
  const std::size_t index = active_[0];
  Submap& s = submaps_[index];
  Result<ProbabilityView> frozen = freeze(grids_[s.grid], *arena_);
  if (!frozen) return Error::format(Errc::capacity, "mapper: the finished submaps fill their %zu bytes",
                                    capacity_.finished_submap_bytes);
  s.finished = *frozen;
  grid_used_[s.grid] = false;
  s.grid = -1;
  active_[0] = active_[1];
  --active_count_;
  return search_loops(index, searched_up_to_);
}

Status Mapper::add(const LaserRecord& scan) {
  if (node_count_ == nodes_.size()) return Error::format(Errc::capacity, "mapper: more than %zu scans", nodes_.size());
  if (scan.count > kMaxBeams || !std::isfinite(scan.odometry.x_m) || !std::isfinite(scan.odometry.y_m) ||
      !std::isfinite(scan.odometry.theta_rad))
    return Error::format(Errc::invalid_argument, "mapper: scan %zu has no finite odometry or too many beams", node_count_);
  const auto t0 = Clock::now();
  // The returns, in the robot frame.
  const double far = std::min(config_.max_range_m, scan.max_range_m > 0.0 ? scan.max_range_m : config_.max_range_m);
  Node& node = nodes_[node_count_];
  node = Node{};
  node.mount = scan.laser_mount;
  node.first_point = static_cast<std::uint32_t>(point_count_);
  const double mc = std::cos(scan.laser_mount.theta_rad);
  const double ms = std::sin(scan.laser_mount.theta_rad);
  // A scan of more beams than a node keeps is thinned evenly, never cut at one side.
  const std::uint32_t stride =
      std::max<std::uint32_t>(1, static_cast<std::uint32_t>((scan.count + capacity_.beams - 1) / capacity_.beams));
  for (std::uint32_t i = 0; i < scan.count && node.point_count < capacity_.beams; i += stride) {
    const double r = scan.ranges[i];
    if (!(r > config_.min_range_m && r < far)) continue;
    const double a = scan.start_angle_rad + i * scan.angle_increment_rad;
    const double lx = r * std::cos(a);
    const double ly = r * std::sin(a);
    points_[point_count_ + node.point_count++] = {static_cast<float>(scan.laser_mount.x_m + mc * lx - ms * ly),
                                                  static_cast<float>(scan.laser_mount.y_m + ms * lx + mc * ly)};
  }
  point_count_ += node.point_count;
  const std::span<const PointF> points = points_of(node);

  // The front end: odometry's motion, then the scan matched into the oldest open submap.
  nav::Pose2D local;
  if (node_count_ > 0) {
    local = nav::apply_motion(nodes_[node_count_ - 1].local, nav::relative_pose(last_odometry_, scan.odometry));
    if (active_count_ > 0 && submaps_[active_[0]].scans >= 2 && !points.empty()) {
      const Submap& s = submaps_[active_[0]];
      // Returns near the far end of the range are left out of the match: the scans before saw up
      // to the same range from a step behind, so such a return may fall past what the submap
      // knows, where cells score low, and moving the scan back would put it on known wall. (With
      // the old 0.55 / 0.49 odds this took a 30 m corridor drive from 6.7 to 5.7 % short; the
      // odds did the rest: grid.hpp.)
      const double reach_sq = std::pow(config_.match_range_fraction * far, 2);
      std::size_t n = 0;
      for (const PointF& q : points)
        if (static_cast<double>(q.x) * q.x + static_cast<double>(q.y) * q.y < reach_sq) scratch_[n++] = q;
      const Match m = matcher_.match(grids_[s.grid].view(), nav::relative_pose(s.local, local),
                                     std::span<const PointF>(scratch_.data(), n));
      local = nav::apply_motion(s.local, m.pose);
    }
  }
  last_odometry_ = scan.odometry;
  node.local = local;
  if (active_count_ == 0)
    if (Status s = start_submap(local); !s) return s;
  Result<std::uint32_t> id = graph_->add_node(global_estimate(local));
  if (!id) return id.error();
  node.graph = *id;
  ++node_count_;
  ++stats_.scans;

  // Into every open submap, and tied to each in the graph.
  const nav::Pose2D sensor_robot = scan.laser_mount;
  for (std::size_t k = 0; k < active_count_; ++k) {
    Submap& s = submaps_[active_[k]];
    const nav::Pose2D in_submap = nav::relative_pose(s.local, local);
    const nav::Pose2D sensor = nav::apply_motion(in_submap, sensor_robot);
    const double c = std::cos(in_submap.theta_rad);
    const double sn = std::sin(in_submap.theta_rad);
    for (std::size_t i = 0; i < points.size(); ++i)
      scratch_[i] = {static_cast<float>(in_submap.x_m + c * points[i].x - sn * points[i].y),
                     static_cast<float>(in_submap.y_m + sn * points[i].x + c * points[i].y)};
    grids_[s.grid].insert({static_cast<float>(sensor.x_m), static_cast<float>(sensor.y_m)},
                          std::span<const PointF>(scratch_.data(), points.size()));
    ++s.scans;
    s.sum_x += local.x_m;
    s.sum_y += local.y_m;
    const double wxy = 1.0 / (config_.local_sigma_xy_m * config_.local_sigma_xy_m);
    const double wth = 1.0 / (config_.local_sigma_theta_rad * config_.local_sigma_theta_rad);
    if (Status st = graph_->add_edge({s.graph, node.graph, in_submap, wxy, wth, 0.0}); !st) return st;
  }
  stats_.matching_s += seconds_since(t0);

  // A new submap every scans_per_submap scans; the oldest is finished when it has twice as many.
  const auto per = static_cast<std::uint32_t>(config_.scans_per_submap);
  if (submaps_[active_[active_count_ - 1]].scans >= per) {
    if (active_count_ == 2)
      if (Status s = finish_oldest(); !s) return s;
    if (Status s = start_submap(local); !s) return s;
  }
  return {};
}

Status Mapper::try_loop(std::size_t submap, std::size_t node_index) {
  const Submap& s = submaps_[submap];
  const Node& n = nodes_[node_index];
  const std::span<const PointF> points = points_of(n);
  if (points.size() < 10) return {};
  const nav::Pose2D guess = nav::relative_pose(graph_pose(s.graph), graph_pose(n.graph));
  ++stats_.loop_searches;
  const std::optional<Match> best = loops_.search(guess, points, config_.loop_min_score);
  if (!best) return {};
  const Match refined = refine_match(s.finished, best->pose, points, config_.local.refine_translation_weight,
                                     config_.local.refine_rotation_weight, config_.local.refine_iterations);
  if (refined.score < config_.loop_min_score) return {};
  // A corridor or a row of racks fits in several places: a distinct second fit nearly as good
  // means the scan does not say where it is.
  const Exclusion away{best->pose, config_.loop_exclusion_m, config_.loop_exclusion_rad};
  if (loops_.search(guess, points, config_.loop_ambiguity * best->score, &away)) {
    ++stats_.loops_rejected_ambiguous;
    return {};
  }
  const double wxy = 1.0 / (config_.loop_sigma_xy_m * config_.loop_sigma_xy_m);
  const double wth = 1.0 / (config_.loop_sigma_theta_rad * config_.loop_sigma_theta_rad);
  if (graph_->edge_count() == graph_edges(capacity_.scans)) return {};  // full: later ones add nothing new
  if (Status st = graph_->add_edge({s.graph, n.graph, refined.pose, wxy, wth, config_.loop_huber_scale}); !st) return st;
  ++stats_.loops_accepted;
  return {};
}

// The new nodes against every older finished submap near them, and the newly finished submap
// against the older nodes near it.
Status Mapper::search_loops(std::size_t finished, std::size_t first_new_node) {
  const auto t0 = Clock::now();
  const std::size_t before = stats_.loops_accepted;
  const auto every = static_cast<std::size_t>(config_.loop_every_n_scans);
  const auto cap = static_cast<std::size_t>(std::max(config_.loops_per_submap, 1));
  const auto near = [&](const Submap& s, std::size_t node) {
    const nav::Point2D m = submap_middle(s);
    const nav::Pose2D g = graph_pose(nodes_[node].graph);
    return std::hypot(g.x_m - m.x_m, g.y_m - m.y_m) < config_.loop_max_distance_m;
  };
  // A scan is tied to the submaps next to its own in time through the scans they share; a
  // closure with them says nothing the front end did not.
  const auto span = static_cast<std::size_t>(config_.scans_per_submap) * 3;
  const auto neighbours_in_time = [&](const Submap& s, std::size_t node) {
    return node + span >= s.first_node && node < s.first_node + s.scans + span;
  };
  for (std::size_t k = 0; k < finished; ++k) {
    const Submap& s = submaps_[k];
    if (s.grid >= 0 || s.finished.cells == nullptr) continue;
    bool prepared = false;
    const std::size_t taken = stats_.loops_accepted;
    for (std::size_t node = first_new_node; node < node_count_ && stats_.loops_accepted - taken < cap; ++node) {
      if (node % every != 0 || neighbours_in_time(s, node) || !near(s, node)) continue;
      if (!prepared) {
        if (Status st = loops_.prepare(s.finished); !st) return st;
        prepared = true;
      }
      if (Status st = try_loop(k, node); !st) return st;
    }
  }
  const Submap& f = submaps_[finished];
  if (f.finished.cells != nullptr) {
    bool prepared = false;
    std::size_t skip_until = 0;  // one closure per submap's worth of older scans
    for (std::size_t node = 0; node < first_new_node; ++node) {
      if (node < skip_until || node % every != 0 || neighbours_in_time(f, node) || !near(f, node)) continue;
      if (!prepared) {
        if (Status st = loops_.prepare(f.finished); !st) return st;
        prepared = true;
      }
      const std::size_t accepted = stats_.loops_accepted;
      if (Status st = try_loop(finished, node); !st) return st;
      if (stats_.loops_accepted > accepted) skip_until = node + static_cast<std::size_t>(config_.scans_per_submap);
    }
  }
  searched_up_to_ = node_count_;
  stats_.loop_search_s += seconds_since(t0);
  if (stats_.loops_accepted > before) return optimise(10);
  return {};
}

Status Mapper::optimise(int iterations) {
  Result<SolveSummary> r = graph_->optimize({iterations, 1e-6});
  if (!r) return r.error();
  ++stats_.optimisations;
  stats_.optimisation_s += r->seconds;
  // The front end goes on in its own frame; new nodes enter the map through the newest submap.
  const Submap& s = submaps_[submap_count_ - 1];
  correction_ = nav::apply_motion(graph_pose(s.graph), inverse(s.local));
  return {};
}

Status Mapper::finish() {
  while (active_count_ > 0)
    if (Status s = finish_oldest(); !s) return s;
  return optimise(50);
}

// A cell hit more often than crossed is a wall, one crossed at least twice more often than hit
// is free (a single miss, as from a passing person's gap, leaves it unknown).
std::int8_t occupancy_of(std::uint8_t byte) noexcept {
  if (byte == 0) return nav::kUnknownOccupancy;
  const double p = probability_table()[byte];
  if (p >= 0.65) return nav::kOccupiedOccupancy;
  if (p <= 0.35) return 0;
  return nav::kUnknownOccupancy;
}

nav::Pose2D Mapper::scan_pose(std::size_t scan) const { return graph_pose(nodes_[scan].graph); }

Result<nav::OccupancyMap> Mapper::render(double resolution_m) const {
  if (!(resolution_m > 0.0) || node_count_ == 0) return Error(Errc::invalid_argument, "render: no scans or no resolution");
  double min_x = 1e300, min_y = 1e300, max_x = -1e300, max_y = -1e300;
  for (std::size_t i = 0; i < node_count_; ++i) {
    const nav::Pose2D p = scan_pose(i);
    const double c = std::cos(p.theta_rad);
    const double s = std::sin(p.theta_rad);
    for (const PointF& q : points_of(nodes_[i])) {
      const double x = p.x_m + c * q.x - s * q.y;
      const double y = p.y_m + s * q.x + c * q.y;
      min_x = std::min(min_x, x);
      max_x = std::max(max_x, x);
      min_y = std::min(min_y, y);
      max_y = std::max(max_y, y);
    }
    min_x = std::min(min_x, p.x_m);
    max_x = std::max(max_x, p.x_m);
    min_y = std::min(min_y, p.y_m);
    max_y = std::max(max_y, p.y_m);
  }
  const double margin = 10 * resolution_m;
  const double cx = 0.5 * (min_x + max_x);
  const double cy = 0.5 * (min_y + max_y);
  const int side = static_cast<int>(std::ceil((std::max(max_x - min_x, max_y - min_y) + 2 * margin) / resolution_m));
  if (side > 8192) return Error::format(Errc::capacity, "render: a map of %d cells a side is too large", side);
  std::vector<std::byte> memory(BuildGrid::bytes_for(std::max(side, 16)) + 256);
  std::pmr::monotonic_buffer_resource arena(memory.data(), memory.size(), std::pmr::null_memory_resource());
  BuildGrid grid;
  if (Status s = grid.init(arena, std::max(side, 16), resolution_m, config_.insertion); !s) return s.error();
  std::vector<PointF> hits(capacity_.beams);
  for (std::size_t i = 0; i < node_count_; ++i) {
    const nav::Pose2D p = scan_pose(i);
    const nav::Pose2D sensor = nav::apply_motion(p, nodes_[i].mount);
    const double c = std::cos(p.theta_rad);
    const double s = std::sin(p.theta_rad);
    const std::span<const PointF> pts = points_of(nodes_[i]);
    for (std::size_t k = 0; k < pts.size(); ++k)
      hits[k] = {static_cast<float>(p.x_m + c * pts[k].x - s * pts[k].y - cx),
                 static_cast<float>(p.y_m + s * pts[k].x + c * pts[k].y - cy)};
    grid.insert({static_cast<float>(sensor.x_m - cx), static_cast<float>(sensor.y_m - cy)},
                std::span<const PointF>(hits.data(), pts.size()));
  }
  const ProbabilityView v = grid.view();
  nav::OccupancyMap map(v.width, v.height, resolution_m, v.origin_x_m + cx, v.origin_y_m + cy);
  for (int r = 0; r < v.height; ++r)
    for (int c = 0; c < v.width; ++c) {
      const std::uint8_t b = v.byte(c, r);
      map.set(c, r, occupancy_of(b));
    }
  return map;
}

Status write_poses(const Mapper& mapper, const std::string& path, const nav::Pose2D& frame) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return Error::format(Errc::io, "%s: cannot create", path.c_str());
  for (std::size_t i = 0; i < mapper.scan_count(); ++i) {
    const nav::Pose2D p = nav::apply_motion(frame, mapper.scan_pose(i));
    std::fprintf(f, "%zu %.4f %.4f %.5f\n", i, p.x_m, p.y_m, p.theta_rad);
  }
  if (std::fclose(f) != 0) return Error::format(Errc::io, "%s: write failed", path.c_str());
  return {};
}

}  // namespace sen3bot::slam
