#pragma once
// Local planner (LP): dynamic window approach over the Pioneer's limits. Each control period
// it samples (v, w) reachable within one period under the acceleration limits, rolls each
// out for sim_time_s, discards rollouts whose footprint touches a lethal cell anywhere along
// the way, and scores the rest (thesis eq. A.6 plus path and goal distance):
//
//   G = heading_weight   * (1 - |bearing of the target from the rollout's end pose| / pi)
//     + clearance_weight * (1 - max centre cost along the rollout / 253)
//     + velocity_weight  * v / max_v
//     - path_weight      * distance from the rollout's end to the pruned path / prune_distance
//     - goal_weight      * distance from the rollout's end to the target / prune_distance
//
// The two distances are breadth-first (4-connected) through cells below the inscribed cost,
// as DWB's map-grid critics do, so an obstacle between a rollout and the target counts.
//
// The target is the farthest point of the global path within prune_distance_m (along the
// path) of the point nearest the robot: the LP sees only that window of the path, so it
// tracks the plan closely and returns to it after avoiding something. Path points inside a
// lethal or inscribed cell (an obstacle the plan did not know) are skipped: the target moves
// past them so the rollouts bend around the obstacle, and while any window point is blocked
// the path-distance term is off (the robot has to leave the path to pass).
// With tracked movers around and no admissible rollout while moving, it brakes (status
// `braking`) if stopping along the current arc stays clear, and samples again from the lower
// speed. Otherwise, or with no
// admissible moving rollout at a standstill, it recovers: wait, then rotate in place towards the
// target, then back off, in a cycle, counting each. Every period samples again first, so a
// recovery ends as soon as a way forward opens; after max_recovery_cycles it reports failure.
//
// Tracked movers (the dynamic obstacle layer's, predicted to now) are checked in time, not
// only as painted cost. Each rollout is followed to mover_horizon_s in two ways along its arc:
// driving on at its (v, w), and braking (at mover_brake_decel_m_s2, from one control period
// plus mover_brake_delay_s on). The
// first step at which the padded footprint comes within a mover's radius plus mover_margin_m
// of that mover's constant-velocity prediction is a time to contact. A rollout that meets a
// mover even when braking leads into an unavoidable contact and is not taken; one that meets
// it only when driving on costs
//   mover_weight * (1 - t_contact / mover_horizon_s)
// so the robot slows down for a crossing mover, stops short of its way and lets it pass, or
// crosses ahead of it when there is time. The costmap check of a rollout leaves out the cells
// where a tracked mover stands now (its laser marks and painted core): they hold its present,
// and the time check above decides about its future, so the robot may pass behind it.
// When every admissible rollout is refused, each is looked at once more without the margin
// (would it really touch?), driving on, braking, or speeding up to max_v_m_s at acc_v_m_s2 as
// later windows allow (how a robot standing in a mover's way gets out of it). Among those where
// holding or braking touches nothing, the usual score picks (not the margin's penalty, which
// favours arcs that turn away and leads the robot in loops among lanes); else,
// among those where speeding up touches nothing, the fastest; else the one whose touch comes
// latest, then whose margin contact comes latest (among equals the fastest when speeding up
// puts it off, else the slowest). When movers make it stop it reports `yielding`, not a
// recovery, for up to max_yield_s.
#include <cstdint>
#include <limits>
#include <memory_resource>
#include <span>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/msg/navigation.hpp"
#include "sen3bot/nav/costmap.hpp"
#include "sen3bot/nav/geometry.hpp"

namespace sen3bot::nav {

using msg::DwaStatus;
using msg::PathPoint;
using msg::RecoveryCounts;
using msg::to_string;

struct DwaConfig {
  // Pioneer 3-DX limits (navigation.md): 1.2 m/s and 300 deg/s; indoors we stay lower.
  double max_v_m_s = 0.5;
  double max_w_rad_s = 1.2;
  double acc_v_m_s2 = 0.6;
  double acc_w_rad_s2 = 2.0;
  double control_period_s = 0.1;   // the task's period: sizes the dynamic window
  int v_samples = 20;
  int w_samples = 21;              // 20 x 21 = 420 rollouts
  double sim_time_s = 1.5;
  double sim_step_s = 0.1;
  Footprint footprint = Footprint::pioneer();
  double footprint_padding_m = 0.05;  // one cell of margin around the footprint
  // Forward arcs are checked at least this far even when slow (match the safety filter's
  // stop zone, so the planner does not choose what the filter would stop).
  double min_clear_distance_m = 0.35;
  // Footprint cells are checked only where the centre cell's cost is at least this (the
  // inflation radius must reach the circumscribed radius for that to be safe).
  std::uint8_t footprint_check_min_cost = 1;
  double heading_weight = 0.5;
  double clearance_weight = 0.4;
  double velocity_weight = 0.6;
  double path_weight = 1.5;
  double goal_weight = 1.0;
  double prune_distance_m = 1.0;
  double blocked_lookahead_m = 2.0;  // how far past the window a blocked path may move the target
  double min_progress_v_m_s = 0.02;  // slower than this counts as not moving...
  double align_angle_rad = 0.6;      // ...unless turning towards a target farther off than this
  double goal_tolerance_m = 0.15;
  double slow_down_radius_m = 0.6;  // v is capped proportionally inside this radius of the goal
  std::size_t max_path_points = 2048;
  std::size_t max_costmap_cells = 120 * 120;  // the local costmap (6 x 6 m at 0.05 m)
  // Tracked movers (the dynamic obstacle layer's): each rollout is checked against their
  // predicted positions at its own time steps (the time-aware critic).
  bool mover_prediction = true;
  double mover_horizon_s = 4.0;  // long enough that standing in a mover's way counts
  // The braking the check counts on: it starts this long after the next period (the command
  // still has to reach the wheels), at this deceleration (below the base's, for margin).
  double mover_brake_delay_s = 0.2;
  double mover_brake_decel_m_s2 = 0.45;
  // Braking or standing counts a mover coming back along its way too (forklifts, trolleys
  // and workers go back and forth), and looks mover_stay_horizon_s ahead: the robot does not
  // stop where it would stand in a mover's way.
  bool mover_may_return = true;
  double mover_stay_horizon_s = 10.0;
  double mover_margin_m = 0.1;
  double mover_weight = 1.5;
  double mover_min_speed_m_s = 0.1;  // slower tracks are left to the costmap
  // Skip, per mover, the times at which it cannot be within reach (the answer is the same;
  // off only to check that).
  bool mover_broad_phase = true;
  double max_yield_s = 6.0;
  // Recoveries.
  double wait_s = 1.0;
  double rotate_s = 1.5;
  double rotate_w_rad_s = 0.6;
  double backoff_s = 1.0;
  double backoff_v_m_s = -0.1;
  int max_recovery_cycles = 3;
};

struct DwaCommand {
  double v_m_s = 0.0;
  double w_rad_s = 0.0;
  DwaStatus status = DwaStatus::idle;
  std::uint32_t admissible = 0;  // rollouts that passed the collision check
  std::uint32_t evaluated = 0;
  std::uint32_t mover_rejected = 0;  // admissible rollouts refused: a contact even when braking
  double distance_to_goal_m = 0.0;
};

class DwaPlanner {
 public:
  Status init(const DwaConfig& config, std::pmr::memory_resource& resource);

  // Copies the global path (map frame, start first); resets progress and recoveries.
  void set_path(std::span<const PathPoint> path) noexcept;
  void clear_path() noexcept;
  [[nodiscard]] std::size_t path_size() const noexcept { return path_count_; }
  [[nodiscard]] std::span<const PathPoint> path() const noexcept { return {path_.data(), path_count_}; }

  // One control period: pose in the map frame, current body velocities, the local costmap.
  // movers: tracked moving obstacles predicted to now (map frame); used when mover_prediction.
  DwaCommand compute(const Pose2D& pose, double v_m_s, double w_rad_s, const Costmap2D& costmap,
                     std::span<const msg::MovingObstacle> movers = {}) noexcept;
  // The first time (s) at which the robot driving (v, w) from pose comes within a mover's
  // reach, or infinity within mover_horizon_s, holding (v, w), braking or speeding up.
  // margin: the padded footprint within mover_margin_m of the mover's radius; touching:
  // within the radius itself (how bad a contact is, when every way has one).
  enum class MoverMotion : std::uint8_t { hold, brake, speed_up };
  enum class MoverReach : std::uint8_t { margin, touching };
  [[nodiscard]] double time_to_contact(const Pose2D& pose, double v, double w, std::span<const msg::MovingObstacle> movers,
                                       MoverMotion motion = MoverMotion::hold,
                                       MoverReach reach = MoverReach::margin) const noexcept;

  // True when the padded footprint at pose touches a lethal or unknown cell (or leaves the
  // costmap). When the robot already stands that close, a cycle checks the bare footprint
  // instead, so it can move away (escaping()).
  [[nodiscard]] bool footprint_collides(const Pose2D& pose, const Costmap2D& costmap) const noexcept;

  [[nodiscard]] const RecoveryCounts& recoveries() const noexcept { return recoveries_; }
  [[nodiscard]] bool escaping() const noexcept { return escaping_; }
  [[nodiscard]] const DwaConfig& config() const noexcept { return config_; }
  // The pruned window of the last compute(): path indices [begin, end].
  [[nodiscard]] std::size_t window_begin() const noexcept { return window_begin_; }
  [[nodiscard]] std::size_t window_end() const noexcept { return window_end_; }

 private:
  struct Rollout {
    bool admissible = false;
    std::uint8_t max_cost = 0;
    Pose2D end;
  };
  Rollout roll_out(const Pose2D& pose, double v, double w, const Costmap2D& costmap) const noexcept;
  [[nodiscard]] double score_rollout(const Rollout& r, double v, const PathPoint& target,
                                     const Costmap2D& costmap) const noexcept;
  // When every rollout meets a mover: a way of going on that touches nothing (free_class 2:
  // holding or braking does, best by score; 1: only speeding up does, the fastest), else the
  // one whose contact comes latest.
  struct MoverFallback {
    double escape_ttc = -1.0;
    double escape_hit = -1.0;  // the same, touching: without the margin
    double escape_score = -std::numeric_limits<double>::infinity();
    double escape_preference = -std::numeric_limits<double>::infinity();
    double escape_v = 0.0;
    double escape_w = 0.0;
    int free_class = 0;
    double free_key = -std::numeric_limits<double>::infinity();
    double free_v = 0.0;
    double free_w = 0.0;
  };
  // A rollout that meets a mover even braking, offered to the fallback (movers_: this cycle's).
  void offer_refused(const Pose2D& pose, double v, double w, double score, double ttc, double ttc_braking,
                     MoverFallback& fallback) const noexcept;
  [[nodiscard]] double distance_to_window(double x_m, double y_m) const noexcept;
  // time_to_contact over at most MovingObstacles::kMax movers, looking only before before_s.
  [[nodiscard]] double contact_in_batch(const Pose2D& pose, double v, double w, std::span<const msg::MovingObstacle> movers,
                                        MoverMotion motion, MoverReach reach_of, double before_s) const noexcept;
  [[nodiscard]] bool braking_is_clear(const Pose2D& pose, double v, double w, const Costmap2D& costmap) const noexcept;
  // Whether (v, w) held meets one of this compute()'s movers (time_to_contact finite).
  [[nodiscard]] bool meets_mover(const Pose2D& pose, double v, double w) const noexcept;
  void update_window(const Pose2D& pose) noexcept;
  void wavefront(const Costmap2D& costmap, std::span<std::uint16_t> distance, bool from_path) noexcept;
  [[nodiscard]] double grid_distance_m(std::span<const std::uint16_t> distance, const Costmap2D& costmap, double x_m,
                                       double y_m) const noexcept;
  void skip_blocked_part(const Costmap2D& costmap) noexcept;
  DwaCommand recover(const Pose2D& pose, const Costmap2D& costmap, DwaCommand out) noexcept;

  DwaConfig config_;
  std::span<PathPoint> path_;
  std::span<std::uint8_t> path_blocked_;  // per window point: inside an obstacle
  std::span<std::uint16_t> goal_distance_;  // cells from the target, through free space
  std::span<std::uint16_t> path_distance_;  // cells from the pruned path window
  std::span<std::uint32_t> queue_;
  // movers_move_on: lethal cells where a tracked mover stands now do not count (rollouts,
  // which the time-aware check covers); otherwise they do (braking, recoveries, escaping).
  [[nodiscard]] bool outline_hits(const Pose2D& pose, const Costmap2D& costmap, std::span<const Point2D> outline,
                                  bool movers_move_on = false) const noexcept;
  [[nodiscard]] bool near_mover(double x_m, double y_m, double reach_m) const noexcept;

  std::span<Point2D> padded_;        // footprint outline + padding, every half cell (robot frame)
  std::span<Point2D> bare_;          // the footprint outline itself
  std::span<const Point2D> check_;   // the outline this cycle checks (bare while escaping)
  bool escaping_ = false;
  std::size_t path_count_ = 0;
  std::size_t window_begin_ = 0;
  std::size_t window_end_ = 0;
  std::size_t target_index_ = 0;
  bool window_blocked_ = false;
  RecoveryCounts recoveries_;
  DwaStatus recovery_state_ = DwaStatus::tracking;
  int recovery_ticks_ = 0;
  int recovery_cycles_ = 0;
  int yield_ticks_ = 0;
  std::span<const msg::MovingObstacle> movers_;  // the current compute()'s; read only within it
  bool held_by_movers_ = false;  // this recovery cycle stood instead of turning or backing off
  // The padded footprint's bounding box in the robot frame (the mover check).
  double body_min_x_ = 0.0, body_max_x_ = 0.0, body_min_y_ = 0.0, body_max_y_ = 0.0;
  double inscribed_m_ = 0.0;
};

}  // namespace sen3bot::nav
