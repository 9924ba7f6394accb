#include "sen3bot/nav/nav_tasks.hpp"

#include <algorithm>
#include <chrono>
#include <cmath>
#include <limits>

#include "sen3bot/nav/arena.hpp"

namespace sen3bot::nav {
namespace {

// Where the robot was when the scan was taken: the pose localization found for that very scan
// when it has one, else the newest pose.
Pose2D robot_pose_at(const PoseEstimate& pose, const ProjectedScan& scan) noexcept {
  const bool same_scan = pose.scan_stamp_ns != 0 && pose.scan_stamp_ns == scan.stamp_ns();
  return same_scan ? pose.scan_pose : pose.pose;
}

}  // namespace

// --- LocalizationTask --------------------------------------------------------------------------

Status LocalizationTask::init(std::pmr::memory_resource& arena) {
  return guarded("localization task", [&]() -> Status { return mcl_.init(config_.mcl, map_, arena); });
}

void LocalizationTask::step(const tasks::StepContext& context) {
  if (global_request_.exchange(false, std::memory_order_relaxed)) mcl_.global_initialize();
  tasks::Sample<Odometry> odom;
  if (!odom_.read(odom) || !odom.value.valid) return;
  history_.push(odom.value);
  const ProjectedScan* scan = nullptr;
  if (scan_.read(scan_sample_) && scan_sample_.sequence != scan_seq_) {
    scan_seq_ = scan_sample_.sequence;
    projected_.assign(scan_sample_.value.view(), config_.mcl.laser_mount);
    scan = &projected_;
  }
  // A scan is weighed at the odometry pose of its stamp (when odometry reaches back that far).
  Pose2D at_scan{odom.value.x_m, odom.value.y_m, odom.value.theta_rad};
  if (scan != nullptr) (void)history_.pose_at(scan->stamp_ns(), at_scan);
  (void)mcl_.update(odom.value, scan, at_scan);
  if (scan != nullptr && mcl_.estimate().valid) {
    scan_pose_ = mcl_.pose_at_odometry(at_scan);
    scan_stamp_ns_ = scan->stamp_ns();
  }
  PoseEstimate e = mcl_.estimate();
  e.stamp_ns = context.start_ns;
  e.scan_pose = scan_pose_;
  e.scan_stamp_ns = scan_stamp_ns_;
  estimate_.publish(e, context.start_ns);
}

// --- PlannerTask ----------------------------------------------------------------------------------

Status PlannerTask::init(std::pmr::memory_resource& arena) {
  return guarded("planner task", [&]() -> Status {
    if (Status s = costmap_.add_layer(static_layer_); !s) return s;
    if (config_.use_scan) {
      if (Status s = costmap_.add_layer(obstacle_layer_); !s) return s;
    }
    if (config_.use_people && people_ != nullptr) {
      if (Status s = costmap_.add_layer(people_layer_); !s) return s;
    }
    if (Status s = costmap_.add_layer(inflation_layer_); !s) return s;
    if (Status s = costmap_.init_over_map(map_, arena); !s) return s;
    GlobalPlannerConfig planner = config_.planner;
    if (config_.plan_clearance_m > 0.0) {
      const std::uint8_t bar = InflationLayer::cost_at(config_.plan_clearance_m, config_.inflation);
      if (bar == kFreeCost) {
        return Error::format(Errc::config, "planner task: plan_clearance_m %g must lie inside the inflation radius %g",
                             config_.plan_clearance_m, config_.inflation.inflation_radius_m);
      }
      planner.blocked_cost = std::min(planner.blocked_cost, bar);
    }
    planner.max_cells = std::max(planner.max_cells, costmap_.costmap().size());
    std::size_t capacity = waypoints_in_.size();
    if (config_.use_sgp) {
      MapEllipsesConfig fit = config_.ellipses;
      // Sized for this map: it is fitted once, here.
      fit.max_map_cells = map_.cells().size();
      fit.max_map_rows = map_.height();
      fit.max_obstacle_cells = std::min(fit.max_obstacle_cells, map_.cells().size());
      if (Status s = ellipses_.init(fit, arena); !s) return s;
      if (Status s = ellipses_.fit(map_); !s)
        return Error::format(s.error().code(), "planner task: map ellipses: %s", s.error().c_str());
      SgpConfig sgp = config_.sgp;
      sgp.max_ellipses = std::max<std::size_t>(ellipses_.ellipses().size(), 1);
      if (Status s = sgp_.init(sgp, arena); !s) return s;
      if (Status s = sgp_.set_site(config_.curve, config_.curve_bounds, ellipses_.ellipses()); !s)
        return Error::format(s.error().code(), "planner task: safe curve: %s", s.error().c_str());
      capacity = sgp.max_waypoints;
    }
    planner.max_waypoints = std::max(planner.max_waypoints, capacity);
    if (Status s = planner_.init(planner, arena); !s) return s;
    waypoints_ = allocate_array<Point2D>(arena, capacity);
    open_waypoints_ = allocate_array<Point2D>(arena, capacity);
    if (!config_.use_sgp) {
      std::copy(waypoints_in_.begin(), waypoints_in_.end(), waypoints_.begin());
      waypoint_count_ = waypoints_in_.size();
    }
    cells_ = allocate_array<GridCell>(arena, costmap_.costmap().size());
    kept_cells_ = allocate_array<GridCell>(arena, 4 * PathMessage::kMaxPoints);
    costmap_.update({});
    return Status::success();
  });
}

double PlannerTask::remaining_cost(const Pose2D& pose) noexcept {
  constexpr double kNone = std::numeric_limits<double>::infinity();
  if (!have_plan_ || message_.count == 0) return kNone;
  std::size_t nearest = 0;
  double best = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < message_.count; ++i) {
    const double d = std::hypot(message_.points[i].x_m - pose.x_m, message_.points[i].y_m - pose.y_m);
    if (d < best) {
      best = d;
      nearest = i;
    }
  }
  if (best > config_.keep_off_plan_m) return kNone;
  // The rest of the plan as an 8-connected cell path (thinned points are joined cell by cell).
  const Costmap2D& grid = costmap_.costmap();
  std::size_t n = 0;
  for (std::size_t i = nearest; i < message_.count; ++i) {
    GridCell target;
    if (!grid.world_to_cell(message_.points[i].x_m, message_.points[i].y_m, target.col, target.row)) return kNone;
    if (n == 0) {
      kept_cells_[n++] = target;
      continue;
    }
    GridCell at = kept_cells_[n - 1];
    while (!(at == target)) {
      at.col += (target.col > at.col) - (target.col < at.col);
      at.row += (target.row > at.row) - (target.row < at.row);
      if (n >= kept_cells_.size()) return kNone;
      kept_cells_[n++] = at;
    }
  }
  const double along = planner_.path_cost(grid, kept_cells_.first(n));
  return along + best / grid.resolution_m();
}

void PlannerTask::plan_safe_path(const NavGoal& goal, const Pose2D& pose) noexcept {
  const auto begin = std::chrono::steady_clock::now();
  sgp_result_ = sgp_.plan({pose.x_m, pose.y_m}, {goal.x_m, goal.y_m});
  sgp_time_ms_ = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
  ++sgp_runs_;
  // A path that reached V is followed as far as it goes. One that stopped before (at a sink
  // of the field in a corner, from inside an ellipse, outside the bounds) would lead the robot
  // away from the goal, or nowhere: then A* plans alone.
  const std::span<const Point2D> path = sgp_.waypoints();
  waypoint_count_ = sgp_result_.on_curve ? std::min(path.size(), waypoints_.size()) : 0;
  std::copy_n(path.begin(), waypoint_count_, waypoints_.begin());
}

void PlannerTask::plan(const NavGoal& goal, const Pose2D& pose, hal::Nanos now_ns, bool new_goal) noexcept {
  // Waypoints behind the robot are dropped so a re-plan from mid-route is not pulled back.
  const std::span<const Point2D> waypoints = safe_path();
  std::size_t nearest = waypoints.size();
  double best = config_.waypoint_pass_m;
  for (std::size_t i = next_waypoint_; i < waypoints.size(); ++i) {
    const double d = std::hypot(waypoints[i].x_m - pose.x_m, waypoints[i].y_m - pose.y_m);
    if (d <= best) {
      best = d;
      nearest = i;
    }
  }
  if (nearest < waypoints.size()) next_waypoint_ = nearest;
  // Waypoints a person's cage (or any obstacle) now covers are left out: the safe path is
  // the map's, and steering through them would take the robot into the cage's edge.
  std::size_t open = 0;
  const Costmap2D& grid = costmap_.costmap();
  for (const Point2D& w : waypoints.subspan(goal.direct ? waypoints.size() : next_waypoint_)) {
    int col = 0;
    int row = 0;
    if (grid.world_to_cell(w.x_m, w.y_m, col, row) && grid.at(col, row) >= kInscribedCost) continue;
    open_waypoints_[open++] = w;
  }
  const auto begin = std::chrono::steady_clock::now();
  const PlanResult r = planner_.plan_world(grid, {pose.x_m, pose.y_m}, {goal.x_m, goal.y_m},
                                           open_waypoints_.first(open), cells_);
  const auto end = std::chrono::steady_clock::now();
  last_plan_ns_ = now_ns;
  if (!new_goal) {
    // Hysteresis: keep following the current plan unless it is blocked, left behind, or
    // clearly dearer than the new one. A failed re-plan never replaces a usable plan.
    const double kept = remaining_cost(pose);
    if (std::isfinite(kept) && (!r.ok() || r.cost >= config_.keep_cost_ratio * kept)) {
      ++kept_;
      return;
    }
  }
  have_plan_ = r.ok();
  message_.plan_id = ++plan_id_;
  message_.goal_id = goal.id;
  message_.status = r.status;
  message_.expansions = static_cast<std::uint32_t>(r.expansions);
  message_.waypoints_passed = r.waypoints_passed;
  message_.length_m = r.length_m;
  message_.plan_time_ms = std::chrono::duration<double, std::milli>(end - begin).count();
  message_.count = 0;
  if (r.ok()) {
    // Long paths are thinned evenly to fit the message; the last cell is always kept.
    const std::size_t stride = (r.cells + PathMessage::kMaxPoints - 1) / PathMessage::kMaxPoints;
    for (std::size_t i = 0; i < r.cells; i += stride) {
      double x = 0.0;
      double y = 0.0;
      grid.cell_to_world(cells_[i].col, cells_[i].row, x, y);
      message_.points[message_.count++] = {static_cast<float>(x), static_cast<float>(y)};
    }
    if ((r.cells - 1) % stride != 0 && message_.count < PathMessage::kMaxPoints) {
      double x = 0.0;
      double y = 0.0;
      grid.cell_to_world(cells_[r.cells - 1].col, cells_[r.cells - 1].row, x, y);
      message_.points[message_.count++] = {static_cast<float>(x), static_cast<float>(y)};
    }
    // The exact goal as the last point, so the controller's tolerance is measured to it.
    message_.points[message_.count - 1] = {static_cast<float>(goal.x_m), static_cast<float>(goal.y_m)};
  }
  path_.publish(message_, now_ns);
}

void PlannerTask::step(const tasks::StepContext& context) {
  tasks::Sample<PoseEstimate> pose;
  const bool have_pose = pose_.read(pose) && pose.value.valid;
  const ProjectedScan* scan = nullptr;
  if (config_.use_scan && scan_.read(scan_sample_) && scan_sample_.sequence != scan_seq_) {
    scan_seq_ = scan_sample_.sequence;
    projected_.assign(scan_sample_.value.view(), config_.laser_mount);
    scan = &projected_;
  }
  if (people_ != nullptr) {
    tasks::Sample<msg::People> people;
    if (people_->read(people)) people_copy_ = people.value;
  }
  if (have_pose && scan != nullptr)
    costmap_.update({pose.value.pose, robot_pose_at(pose.value, *scan), scan, context.start_ns});
  tasks::Sample<NavGoal> goal;
  if (!goal_.read(goal)) return;
  if (!goal.value.active) {
    if (goal_active_) {
      message_ = PathMessage{};
      have_plan_ = false;
      message_.plan_id = ++plan_id_;
      message_.goal_id = goal.value.id;
      path_.publish(message_, context.start_ns);
    }
    goal_active_ = false;
    return;
  }
  if (!have_pose) return;
  const bool new_goal = !goal_active_ || goal.value.id != goal_id_;
  const bool due = config_.replan_period_s > 0.0 &&
                   static_cast<double>(context.start_ns - last_plan_ns_) >= config_.replan_period_s * 1e9;
  // Between periodic re-plans, a plan that a new scan shows blocked is replaced at once.
  const bool blocked = !new_goal && !due && scan != nullptr && have_plan_ && !std::isfinite(remaining_cost(pose.value.pose));
  if (new_goal) {
    next_waypoint_ = 0;
    if (config_.use_sgp && !goal.value.direct) plan_safe_path(goal.value, pose.value.pose);
    osgp_.reset();
  }
  // Online SGP: a person pushed the robot off its safe path; the new one starts where it is.
  const bool replan_safe_path = !new_goal && osgp() != nullptr &&
                                osgp_.update(pose.value.pose, safe_path(), {goal.value.x_m, goal.value.y_m}, people_copy_,
                                             context.start_ns) ==
                                    OsgpOutcome::triggered;
  if (replan_safe_path) {
    next_waypoint_ = 0;
    plan_safe_path(goal.value, pose.value.pose);
  }
  if (new_goal || due || blocked || replan_safe_path) {
    goal_active_ = true;
    goal_id_ = goal.value.id;
    plan(goal.value, pose.value.pose, context.start_ns, new_goal || replan_safe_path);
  }
}

// --- ControllerTask -------------------------------------------------------------------------------

Status ControllerTask::init(std::pmr::memory_resource& arena) {
  return guarded("controller task", [&]() -> Status {
    if (Status s = costmap_.add_layer(static_layer_); !s) return s;
    if (Status s = costmap_.add_layer(obstacle_layer_); !s) return s;
    if (config_.dynamic_obstacles.enabled) {
      if (config_.use_people && people_ != nullptr) dynamic_layer_.vouch_with(&people_copy_);
      if (Status s = costmap_.add_layer(dynamic_layer_); !s) return s;
    }
    if (config_.use_people && people_ != nullptr) {
      if (Status s = costmap_.add_layer(people_layer_); !s) return s;
    }
    if (Status s = costmap_.add_layer(inflation_layer_); !s) return s;
    CostmapConfig cfg = config_.local_costmap;
    cfg.lattice_x_m = map_.origin_x_m();
    cfg.lattice_y_m = map_.origin_y_m();
    cfg.yaw_rad = map_.origin_yaw_rad();
    if (Status s = costmap_.init(cfg, arena); !s) return s;
    DwaConfig dwa = config_.dwa;
    dwa.max_costmap_cells = std::max(dwa.max_costmap_cells, costmap_.costmap().size());
    dwa.max_path_points = std::max(dwa.max_path_points, PathMessage::kMaxPoints);
    if (Status s = dwa_.init(dwa, arena); !s) return s;
    if (!crossings_on()) return Status::success();
    // The lanes cover the map (its corners in the map frame, for a rotated map).
    const double w = map_.width() * map_.resolution_m(), h = map_.height() * map_.resolution_m();
    const double cy = std::cos(map_.origin_yaw_rad()), sy = std::sin(map_.origin_yaw_rad());
    double x0 = map_.origin_x_m(), x1 = x0, y0 = map_.origin_y_m(), y1 = y0;
    for (const auto& [u, v] : {std::pair{w, 0.0}, std::pair{0.0, h}, std::pair{w, h}}) {
      x0 = std::min(x0, map_.origin_x_m() + cy * u - sy * v);
      x1 = std::max(x1, map_.origin_x_m() + cy * u - sy * v);
      y0 = std::min(y0, map_.origin_y_m() + sy * u + cy * v);
      y1 = std::max(y1, map_.origin_y_m() + sy * u + cy * v);
    }
    if (Status s = lanes_.init(config_.lanes, x0, y0, x1 - x0, y1 - y0, arena); !s) return s;
    // The body as a disc: it crosses lanes at any angle.
    return gate_.init(config_.crossings, config_.dwa.footprint.circumscribed_radius_m(), config_.dwa.max_v_m_s,
                      config_.dwa.acc_v_m_s2);
  });
}

bool ControllerTask::walkers_tracked() const noexcept {
  return config_.dynamic_obstacles.enabled || (config_.use_people && people_ != nullptr);
}

// The gate is for people: its prediction's spread is measured on recorded walkers, and it
// counts on them not turning back; boxes and trolleys on lanes that reverse are the DWA's
// (which does count on that).
bool ControllerTask::crossings_on() const noexcept {
  return config_.crossings.enabled && config_.use_people && people_ != nullptr;
}

std::size_t ControllerTask::collect_tracks(hal::Nanos now) noexcept {
  std::size_t n = 0;
  // The candidates too (walkers that have not yet travelled far enough to be movers): a worker
  // coming out from behind a rack is one for the first half second.
  const std::size_t movers =
      std::min<std::size_t>(movers_message_.count + movers_message_.candidate_count, msg::MovingObstacles::kMax);
  for (std::size_t i = 0; i < movers; ++i) {
    const msg::MovingObstacle& m = movers_message_.items[i];
    tracks_[n++] = {m.id, m.x_m, m.y_m, m.vx_m_s, m.vy_m_s, m.radius_m + config_.mover_keep_out_m, m.radius_m};
  }
  if (config_.use_people && people_ != nullptr) {
    const double age_s = std::max(0.0, static_cast<double>(now - people_copy_.stamp_ns) * 1e-9);
    for (std::size_t i = 0; i < std::min<std::size_t>(people_copy_.count, msg::People::kMax); ++i) {
      const msg::TrackedPerson& p = people_copy_.items[i];
      // Ids of their own, apart from the movers'.
      tracks_[n++] = {p.id | 0x8000'0000u, p.x_m + p.vx_m_s * age_s, p.y_m + p.vy_m_s * age_s, p.vx_m_s, p.vy_m_s,
                      p.cage_radius_m, p.width_m / 2.0};
    }
  }
  return n;
}

void ControllerTask::gate(const Pose2D& pose, double v_m_s, hal::Nanos now, std::size_t n, VelocityCommand& command,
                          ControllerStatus& status) noexcept {
  const double now_s = static_cast<double>(now) * 1e-9;
  for (std::size_t i = 0; i < n; ++i) {
    const CrossingTrack& t = tracks_[i];
    if (std::hypot(t.vx_m_s, t.vy_m_s) >= lanes_.config().min_speed_m_s) lanes_.walk(t.x_m, t.y_m, t.body_m, now_s);
  }
  const std::span<const PathPoint> path = dwa_.path();
  const std::size_t from = std::min(dwa_.window_begin(), path.size());
  const CrossingDecision d =
      gate_.decide({pose, v_m_s, path.subspan(from), std::span<const CrossingTrack>(tracks_.data(), n), &lanes_, now_s});
  status.crossing = d.action;
  status.crossing_cap_m_s = d.v_cap_m_s;
  if (d.action == Crossing::wait && command.v_m_s > d.v_cap_m_s) {
    const double scale = command.v_m_s > 0.0 ? d.v_cap_m_s / command.v_m_s : 0.0;
    command.v_m_s = d.v_cap_m_s;
    command.w_rad_s *= scale;  // the same arc, slower
    status.status = DwaStatus::yielding;
    ++crossing_waits_;
  }
}

void ControllerTask::make_way(const Pose2D& pose, double v_m_s, std::size_t n, VelocityCommand& command,
                              ControllerStatus& status) noexcept {
  const MakeWayDecision d = nav::make_way(config_.make_way, pose, v_m_s, config_.dwa.footprint.circumscribed_radius_m(),
                                          std::span<const CrossingTrack>(tracks_.data(), n));
  status.making_way = d.move;
  // A command already taking it out that way, briskly, stands; one that would hold it in
  // their way (standing, creeping, or going the other way) is replaced.
  const bool out_ahead = d.move == MakeWayMove::forward && command.v_m_s < 0.5 * d.v_m_s;
  const bool out_behind = d.move == MakeWayMove::backward && command.v_m_s > 0.5 * d.v_m_s;
  if (!out_ahead && !out_behind) return;
  command.v_m_s = d.v_m_s;
  command.w_rad_s = 0.0;  // straight out along its axis
  status.status = DwaStatus::yielding;
  ++ways_made_;
}

bool ControllerTask::formation_fresh(hal::Nanos now) const noexcept {
  return formation_ != nullptr && formation_sample_.sequence != 0 &&
         static_cast<double>(now - formation_sample_.value.received_ns) <= formation_sample_.value.hold_s * 1e9;
}

void ControllerTask::step(const tasks::StepContext& context) {
  if (formation_ != nullptr) (void)formation_->read(formation_sample_);
  VelocityCommand command{0.0, 0.0, context.start_ns};
  movers_message_.count = 0;
  movers_message_.stamp_ns = context.start_ns;
  ControllerStatus status;
  if (path_.read(path_sample_) && path_sample_.value.plan_id != plan_id_) {
    plan_id_ = path_sample_.value.plan_id;
    if (path_sample_.value.status == PlanStatus::ok && path_sample_.value.count > 0) {
      dwa_.set_path(std::span<const PathPoint>(path_sample_.value.points.data(), path_sample_.value.count));
    } else {
      dwa_.clear_path();
    }
  }
  tasks::Sample<PoseEstimate> pose;
  tasks::Sample<Odometry> odom;
  const bool fresh_pose = pose_.read(pose) && pose.value.valid &&
                          static_cast<double>(context.start_ns - pose.stamp_ns) <= config_.pose_timeout_s * 1e9;
  // Lost (spread, or relocalising after a drop in likelihood): stand still and let
  // localization catch up rather than follow a pose that may be in another room.
  if (fresh_pose && pose.value.lost) {
    status.status = DwaStatus::localizing;
  } else if (fresh_pose && odom_.read(odom)) {
    const ProjectedScan* scan = nullptr;
    if (scan_.read(scan_sample_) && scan_sample_.sequence != scan_seq_) {
      scan_seq_ = scan_sample_.sequence;
      projected_.assign(scan_sample_.value.view(), config_.laser_mount);
      scan = &projected_;
    }
    const Pose2D at_scan = scan != nullptr ? robot_pose_at(pose.value, *scan) : pose.value.pose;
    if (people_ != nullptr) {
      tasks::Sample<msg::People> people;
      if (people_->read(people)) people_copy_ = people.value;
    }
    CostmapInputs inputs{pose.value.pose, at_scan, scan, context.start_ns};
    if (sonar_ != nullptr && sonar_->read(sonar_sample_)) inputs.sonar = &sonar_sample_.value;
    costmap_.update(inputs);
    if (config_.dynamic_obstacles.enabled) dynamic_layer_.movers(context.start_ns, movers_message_);
    // Under a formation command the DWA rests: its recoveries would count the robot not
    // following a path it is not asked to follow.
    if (!formation_fresh(context.start_ns)) {
      const DwaCommand c =
          dwa_.compute(pose.value.pose, odom.value.v_m_s, odom.value.w_rad_s, costmap_.costmap(),
                       std::span<const msg::MovingObstacle>(movers_message_.items.data(), movers_message_.count));
      command.v_m_s = c.v_m_s;
      command.w_rad_s = c.w_rad_s;
      status.status = c.status;
      status.distance_to_goal_m = c.distance_to_goal_m;
      status.admissible = c.admissible;
      if ((crossings_on() || (config_.make_way.enabled && walkers_tracked())) && c.status != DwaStatus::reached &&
          c.status != DwaStatus::idle) {
        const std::size_t tracks = collect_tracks(context.start_ns);
        if (crossings_on()) gate(pose.value.pose, odom.value.v_m_s, context.start_ns, tracks, command, status);
        if (config_.make_way.enabled) make_way(pose.value.pose, odom.value.v_m_s, tracks, command, status);
      }
    }
  }
  // The centre's velocity replaces whatever the DWA or localization would ask for; the safety
  // filter after this row still stops for obstacles, cages, a lost pose and stale sensors.
  if (formation_fresh(context.start_ns)) {
    command.v_m_s = formation_sample_.value.v_m_s;
    command.w_rad_s = formation_sample_.value.w_rad_s;
    status.status = DwaStatus::idle;
    status.formation = true;
  }
  status.recoveries = dwa_.recoveries();
  status.plan_id = plan_id_;
  status.crossing_waits = crossing_waits_;
  status.ways_made = ways_made_;
  command_.publish(command, context.start_ns);
  status_.publish(status, context.start_ns);
  movers_.publish(movers_message_, context.start_ns);
  if (snapshot_topic_ != nullptr && ++snapshot_count_ >= snapshot_every_) {
    snapshot_count_ = 0;
    snapshot_costmap(costmap_.costmap(), snapshot_);
    snapshot_topic_->publish(snapshot_, context.start_ns);
  }
}

void snapshot_costmap(const Costmap2D& costmap, msg::CostmapSnapshot& out) noexcept {
  const int width = costmap.width(), height = costmap.height();
  int factor = 1;
  while (static_cast<std::size_t>((width + factor - 1) / factor) * static_cast<std::size_t>((height + factor - 1) / factor) >
         msg::CostmapSnapshot::kMaxCells)
    ++factor;
  const int columns = (width + factor - 1) / factor, rows = (height + factor - 1) / factor;
  out.columns = static_cast<std::uint16_t>(columns);
  out.rows = static_cast<std::uint16_t>(rows);
  out.resolution_m = costmap.resolution_m() * factor;
  out.origin_x_m = costmap.origin_x_m();
  out.origin_y_m = costmap.origin_y_m();
  const std::span<const std::uint8_t> cells = costmap.cells();
  if (factor == 1) {
    std::copy(cells.begin(), cells.begin() + static_cast<std::ptrdiff_t>(columns * rows), out.cells.begin());
    return;
  }
  for (int r = 0; r < rows; ++r)
    for (int c = 0; c < columns; ++c) {
      std::uint8_t worst = 0;
      for (int y = r * factor; y < std::min(height, (r + 1) * factor); ++y)
        for (int x = c * factor; x < std::min(width, (c + 1) * factor); ++x)
          worst = std::max(worst, cells[costmap.index(x, y)]);
      out.cells[static_cast<std::size_t>(r * columns + c)] = worst;
    }
}

// --- SafetyTask ---------------------------------------------------------------------------------

Status SafetyTask::init(std::pmr::memory_resource& /*arena*/) { return Status::success(); }

void SafetyTask::step(const tasks::StepContext& context) {
  SafetyInputs in;
  in.now_ns = context.start_ns;
  tasks::Sample<VelocityCommand> requested;
  if (requested_.read(requested) &&
      static_cast<double>(context.start_ns - requested.stamp_ns) <= config_.command_timeout_s * 1e9) {
    in.requested = requested.value;
  }
  // The scan is copied and projected once, when a new one arrives; this row runs several times
  // per scan.
  if (scan_.published() != scan_seq_ && scan_.read(scan_sample_)) {
    scan_seq_ = scan_sample_.sequence;
    projected_.assign(scan_sample_.value.view(), config_.safety.laser_mount);
  }
  if (scan_seq_ != 0) in.scan = &projected_;
  tasks::Sample<Odometry> odom;
  if (odom_.read(odom) && odom.value.valid) {
    in.odom_stamp_ns = odom.value.stamp_ns;
    in.measured_v_m_s = odom.value.v_m_s;
  }
  tasks::Sample<BaseFlags> base;
  if (base_.read(base)) {
    in.estop = base.value.estop;
    in.motors_enabled = base.value.motors_enabled;
  } else {
    in.motors_enabled = !config_.require_base_flags;
  }
  tasks::Sample<PoseEstimate> pose;
  in.localization_lost = !pose_.read(pose) || !pose.value.valid || pose.value.lost;
  in.pose = pose.value.pose;
  if (movers_.read(movers_sample_) &&
      static_cast<double>(context.start_ns - movers_sample_.stamp_ns) <= config_.movers_timeout_s * 1e9) {
    in.movers = &movers_sample_.value;
  }
  if (sonar_ != nullptr && sonar_->read(sonar_sample_)) in.sonar = &sonar_sample_.value;
  if (people_ != nullptr && people_->read(people_sample_) &&
      static_cast<double>(context.start_ns - people_sample_.stamp_ns) <= config_.people_timeout_s * 1e9) {
    in.people = &people_sample_.value;
  }
  if (io_ != nullptr) {
    tasks::Sample<msg::SafetyIo> io;
    const bool fresh = io_->read(io) && static_cast<double>(context.start_ns - io.stamp_ns) <= config_.io_timeout_s * 1e9;
    in.io_stops = latch_.update(fresh ? &io.value : nullptr);
  }
  const SafetyOutput out = filter_.filter(in);
  if ((in.requested.v_m_s != 0.0 || in.requested.w_rad_s != 0.0) && out.command.v_m_s == 0.0 &&
      out.command.w_rad_s == 0.0) {
    ++stops_;
  }
  VelocityCommand command = out.command;
  command.stamp_ns = context.start_ns;
  command_.publish(command, context.start_ns);
  status_.publish(out, context.start_ns);
}


// --- PeopleTask ------------------------------------------------------------------------------------

Status PeopleTask::init(std::pmr::memory_resource& arena) {
  if (!(config_.frame_wait_s >= 0.0)) return Error(Errc::config, "people task: frame_wait_s must be at least 0");
  if (Status s = fusion_.init(config_.fusion, config_.camera, &map_, ScanMessage::kMaxBeams, arena); !s) return s;
  if (Status s = tracker_.init(config_.tracker, arena); !s) return s;
  return guarded("people task", [&]() -> Status {
    scans_ = allocate_array<PosedScan>(arena, kScans);
    frames_ = allocate_array<msg::PersonDetections>(arena, kFrames);
    return Status::success();
  });
}

void PeopleTask::fuse(const msg::PersonDetections& frame, const PosedScan& scan) noexcept {
  const Pose2D laser = msg::compose(scan.pose, config_.laser_mount);
  const std::size_t n = fusion_.fuse(scan.scan.view(), laser, frame, fixes_);
  // The positions are the laser's: they hold at the scan's time, not the frame's.
  tracker_.update(std::span(fixes_).first(n), scan.scan.stamp_ns);
  ++frames_fused_;
}

void PeopleTask::follow(PosedScan& scan) noexcept {
  scan.followed = true;
  const std::size_t n = tracker_.followable(scan.scan.stamp_ns, predicted_, followed_tracks_);
  if (n == 0) return;
  const Pose2D laser = msg::compose(scan.pose, config_.laser_mount);
  fusion_.follow(scan.scan.view(), laser, std::span(predicted_).first(n), config_.tracker.follow_gate_m, follow_fixes_);
  for (std::size_t i = 0; i < n; ++i) {
    if (follow_fixes_[i].points == 0) continue;
    tracker_.follow(followed_tracks_[i], follow_fixes_[i], scan.scan.stamp_ns);
    ++laser_fixes_;
  }
}

void PeopleTask::step(const tasks::StepContext& context) {
  // A new scan joins the ring; the localization's pose for a scan comes with its estimate.
  if (scan_.read(scan_sample_) && scan_sample_.sequence != scan_seq_) {
    scan_seq_ = scan_sample_.sequence;
    PosedScan& slot = scans_[scan_next_++ % kScans];
    slot.scan = scan_sample_.value;
    slot.posed = false;
    slot.followed = false;
  }
  tasks::Sample<PoseEstimate> pose;
  if (pose_.read(pose) && pose.value.valid && pose.value.scan_stamp_ns != 0) {
    for (PosedScan& s : scans_)
      if (!s.posed && s.scan.count > 0 && s.scan.stamp_ns == pose.value.scan_stamp_ns) {
        s.pose = pose.value.scan_pose;
        s.posed = true;
      }
  }
  if (detections_.read(frame_sample_) && frame_sample_.sequence != frame_seq_) {
    frame_seq_ = frame_sample_.sequence;
    if (frame_count_ == kFrames) {
      // The oldest waiting frame gives way (it would be out of its window by now).
      std::move(frames_.begin() + 1, frames_.end(), frames_.begin());
      --frame_count_;
    }
    frames_[frame_count_++] = frame_sample_.value;
  }
  // Each waiting frame: fused with a posed scan inside the match window, or after frame_wait_s
  // with the nearest posed scan (the fusion then counts it out of the window).
  std::size_t kept = 0;
  for (std::size_t f = 0; f < frame_count_; ++f) {
    const msg::PersonDetections& frame = frames_[f];
    const PosedScan* nearest = nullptr;
    double best = std::numeric_limits<double>::infinity();
    for (const PosedScan& s : scans_) {
      if (!s.posed) continue;
      const double dt = std::abs(static_cast<double>(s.scan.stamp_ns - frame.capture_ns)) * 1e-9;
      if (dt < best) {
        best = dt;
        nearest = &s;
      }
    }
    const bool waited = static_cast<double>(context.start_ns - frame.capture_ns) * 1e-9 > config_.frame_wait_s;
    if (nearest != nullptr && (best <= config_.fusion.match_window_s || waited)) {
      fuse(frame, *nearest);
      continue;
    }
    if (waited) continue;  // no posed scan at all: dropped
    frames_[kept++] = frame;
  }
  frame_count_ = kept;
  // Then the laser alone, through each posed scan once, oldest first.
  for (std::size_t k = 0; k < kScans; ++k) {
    PosedScan& s = scans_[(scan_next_ + k) % kScans];
    if (s.posed && !s.followed) follow(s);
  }
  // Which unseen people are hidden: the newest posed scan and the sonar ring tell.
  SensorCoverage coverage;
  const PosedScan* newest = nullptr;
  for (const PosedScan& s : scans_)
    if (s.posed && (newest == nullptr || s.scan.stamp_ns > newest->scan.stamp_ns)) newest = &s;
  msg::ScanView newest_view;
  if (newest != nullptr) {
    newest_view = newest->scan.view();
    coverage.scan = &newest_view;
    coverage.laser_pose = msg::compose(newest->pose, config_.laser_mount);
  }
  if (sonar_ != nullptr && sonar_->read(sonar_sample_) && pose.value.valid && !pose.value.lost) {
    coverage.sonar = &sonar_sample_.value;
    coverage.robot_pose = pose.value.pose;
  }
  tracker_.expire(context.start_ns, coverage);
  tracker_.publish(context.start_ns, message_);
  tasks::Sample<msg::CobotState> cobot;
  if (cobot_ != nullptr && config_.operator_safety_radius_m >= 0.0 && cobot_->read(cobot) &&
      cobot.value.mode == msg::CobotMode::collaborative && cobot.value.operator_track != 0) {
    for (std::size_t i = 0; i < message_.count; ++i) {
      msg::TrackedPerson& p = message_.items[i];
      if (p.id != cobot.value.operator_track) continue;
      p.cage_radius_m =
          cage_radius(config_.tracker, p.width_m, config_.operator_safety_radius_m, p.hidden, p.position_sigma_m);
    }
  }
  people_.publish(message_, context.start_ns);
}

// --- PeopleRelayTask -------------------------------------------------------------------------------

Status PeopleRelayTask::init(std::pmr::memory_resource& arena) {
  (void)arena;
  if (!(tracker_.expire_s > 0.0) || !(tracker_.safety_radius_m >= 0.0) || !(tracker_.min_width_m >= 0.0))
    return Error::format(Errc::config, "people relay: expire_s must be positive, safety_radius_m and min_width_m at least 0");
  return {};
}

void PeopleRelayTask::step(const tasks::StepContext& context) {
  message_.count = 0;
  message_.stamp_ns = context.start_ns;
  if (source_.read(sample_) &&
      static_cast<double>(context.start_ns - sample_.value.stamp_ns) <= tracker_.expire_s * 1e9) {
    const std::size_t n = std::min<std::size_t>(sample_.value.count, msg::People::kMax);
    for (std::size_t i = 0; i < n; ++i) {
      msg::TrackedPerson p = sample_.value.items[i];
      p.cage_radius_m = cage_radius(tracker_, p.width_m, tracker_.safety_radius_m, p.hidden, p.position_sigma_m);
      message_.items[message_.count++] = p;
    }
  }
  people_.publish(message_, context.start_ns);
}

}  // namespace sen3bot::nav
