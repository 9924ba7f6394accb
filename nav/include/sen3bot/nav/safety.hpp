#pragma once
// The safety filter: the last stage before the base. It takes the requested velocity and can
// only lower it (same sign, never larger in magnitude), to zero when:
//  * the newest laser scan is older than stale_scan_periods scan periods (or none arrived),
//  * odometry is older than odom_timeout_s (or none arrived),
//  * the e-stop is pressed or the motors are reported off,
//  * the safety I/O holds a stop (the e-stop chain, a bumper, the I/O node lost; SafetyLatch),
//  * localization is lost,
//  * a laser point lies inside the stop zone along the direction of motion: the front half of
//    the body (its width plus lateral_margin_m a side) swept forward along the commanded arc
//    would reach it within the stop distance. That distance grows with the speed v:
//      stop_distance_m + v * (reaction_s + scan_age_s) + v^2 / (2 decel_m_s2)
//    The base cannot stop at once (the braking term), a command takes reaction_s to reach the
//    wheels, and the robot has already moved for scan_age_s (now - the scan's stamp, at least
//    0) towards what the scan shows: a scan may be up to stale_scan_periods periods old.
//    A tracked mover ahead (in the swept corridor widened by its radius) coming towards the
//    robot at closing speed u shortens the gap as well: while the command reaches the wheels
//    and while the robot brakes (v / decel_m_s2), so the distance grows by
//      u * (reaction_s + scan_age_s + v / decel_m_s2)
//    Up to slow_distance_m beyond it the command is scaled down (v and w alike, so the arc
//    stays the one checked). Turning on the spot is refused when a point is inside the
//    circumscribed circle plus lateral_margin_m.
//  * Crossing movers: beyond stop_distance_m (the fixed part), a point that belongs to a
//    tracked mover going across the corridor (not towards the robot faster than
//    min_crossing_speed_m_s) counts neither for stopping nor for slowing when the mover will
//    have left the corridor, by crossing_margin_m, before the robot at its speed reaches the
//    point. Braking for a box that is gone when the robot gets there would stop the robot
//    short, in the way of whatever comes next.
//  * Approaching movers: a tracked mover coming from the side never enters the corridor ahead
//    before it meets the body. The command is held for approach_horizon_s (the robot on its
//    arc, each mover at its velocity); when that brings the body within approach_margin_m of
//    a mover and braking now would keep the two farther apart, the robot stops. Moving away
//    from a mover that walks up to the robot stays allowed. With approach_candidates, the
//    layer's candidates (confirmed, moving, not yet movers) count as well.
//  * Virtual cages: a command is refused when the robot could no longer stop outside a
//    tracked person's cage radius plus cage_margin_m (the margin is for the error of the
//    person's placement): held for reaction_s and then braked along its arc, the body comes
//    within that distance of the person held where they are, closer than braking now would
//    bring it. A walker (at approach_min_speed_m_s or more) on their velocity is checked as
//    the approach check does, over cage_horizon_s. Backing away stays allowed; a person who
//    walks up to a standing robot is theirs to avoid. With people tracked, a mover at walking
//    speed is caged the same way, its radius plus mover_cage_m: the camera sees 52 degrees
//    of the laser's 180, and a walker coming from the side is on the laser long before the
//    camera can tell what it is.
//  * Speed and separation (ISO/TS 15066's speed and separation monitoring): near a tracked
//    person (and, with people tracked, a mover or candidate at walking speed) the robot's
//    speed towards them is limited so that it can still stop outside their cage plus
//    cage_margin_m while they keep coming: with T = reaction_s + scan_age_s, the robot's
//    speed towards them v_r, theirs towards the robot v_h and the gap S from the body to the
//    cage's edge,
//      v_h (T + v_r / decel) + v_r T + v_r^2 / (2 decel) <= S
//    v_h is the measured approach speed, plus separation_spread_m_s for a walker (at
//    approach_min_speed_m_s or more: their velocity is a prediction; a standing person's step
//    is what their cage's safety radius holds). The command is scaled down (v and w alike) to
//    the largest v_r that holds, for the most constraining person; moving away is never
//    limited. The cap and its terms go out with the decision (kSafetySeparation when it bit).
// The LMS200 looks forward only. Behind, the base's sonar ring (when it reports) checks
// reversing: a fresh echo (at most sonar_max_age_s old) of a disc facing backwards inside the
// corridor the body sweeps backwards within sonar_stop_m plus the reaction and braking
// distance stops it (kSafetySonar); and any fresh echo inside the turn circle refuses turning on
// the spot, as a laser point does. Sonar misses what glances off it, so reverse speed stays
// capped at max_reverse_m_s (the back-off recovery's speed), or sonar_reverse_m_s while every
// disc facing backwards has a fresh reading (making way for a walker backs off at it).
#include <array>
#include <cstdint>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/msg/io.hpp"
#include "sen3bot/msg/navigation.hpp"
#include "sen3bot/msg/people.hpp"
#include "sen3bot/nav/geometry.hpp"
#include "sen3bot/nav/projected_scan.hpp"

namespace sen3bot::nav {

using msg::SafetyOutput;
using msg::SafetyReason;
using msg::VelocityCommand;
using enum msg::SafetyReason;

struct SafetyConfig {
  double scan_period_s = 0.2;      // LMS200 at 38.4 kbaud: about 5 scans/s
  double stale_scan_periods = 3.0;
  double odom_timeout_s = 0.3;
  double stop_distance_m = 0.25;
  double slow_distance_m = 0.35;    // the slow zone's depth beyond the stop distance
  // Command to wheels. The composition sets it from the measured sense-to-act budget; the
  // default is one control period.
  double reaction_s = 0.1;
  double decel_m_s2 = 0.6;          // the base's braking deceleration
  double lateral_margin_m = 0.05;
  double max_reverse_m_s = 0.1;
  // Crossing movers: a laser point within the mover's radius plus mover_point_slack_m of
  // where the mover was at the scan's time is the mover's.
  double mover_point_slack_m = 0.1;
  double min_crossing_speed_m_s = 0.1;
  double crossing_margin_m = 0.1;
  double approach_horizon_s = 1.0;  // 0: no approach check
  double approach_margin_m = 0.1;
  // Slower tracks are left to the corridor: a still box whose faces come into view one after
  // another is tracked at up to about 0.1 m/s; people walk at 0.5-1.5 m/s.
  double approach_min_speed_m_s = 0.3;
  // Also check the layer's candidates (MovingObstacles::candidate_count): a walker coming out
  // from behind a door jamb is tracked for about half a second before it has travelled far
  // enough to be a mover, and the robot needs that time to stop.
  bool approach_candidates = true;
  double cage_margin_m = 0.1;   // < 0: no cage check
  double cage_horizon_s = 1.0;
  double mover_cage_m = -1.0;   // < 0: movers are not caged (people tracking sets it)
  // The approach speed counted beyond the measured one (< 0: no separation limit): the p90 of
  // the constant-velocity prediction's speed error on the recorded pedestrians (docs/crowd.md).
  double separation_spread_m_s = 0.3;
  double sonar_max_age_s = 1.0;  // a disc fires every 0.32 s on a P3-DX
  double sonar_stop_m = 0.25;     // as stop_distance_m in front
  double sonar_reverse_m_s = 0.25;
  Footprint footprint = Footprint::pioneer();
  SensorMount laser_mount;          // SafetyTask projects scans with it
};

struct SafetyInputs {
  VelocityCommand requested;
  const ProjectedScan* scan = nullptr;  // the newest scan, or null if none ever arrived
  hal::Nanos odom_stamp_ns = -1;        // -1: never
  bool estop = false;
  bool motors_enabled = true;
  bool localization_lost = false;
  double measured_v_m_s = 0.0;     // odometry speed, for the braking distance
  hal::Nanos now_ns = 0;
  // Tracked movers (map frame, predicted to movers->stamp_ns) and the robot's pose; null: none.
  const msg::MovingObstacles* movers = nullptr;
  // Tracked people (map frame, predicted to people->stamp_ns) with their cages; null: none.
  const msg::People* people = nullptr;
  Pose2D pose;
  // The sonar ring's newest readings (body frame mounts); null: none.
  const msg::Sonar* sonar = nullptr;
  // Stops from the safety I/O, as SafetyLatch holds them (kSafetyEstopChain, kSafetyBumper,
  // kSafetyIoLost, kSafetyResetNeeded): any of them stops the robot.
  std::uint32_t io_stops = 0;
};

// The e-stop chain's rule (as machinery standards ask of an emergency stop): a stop from the
// safety I/O holds the robot until its cause is gone AND a reset was requested after that.
// A reset pressed while the chain is still open does not count, nor does releasing the chain
// alone. Before the I/O has ever been healthy, its absence stops the robot without latching
// (unless reset_at_start), so a robot that powers up with the chain closed needs no reset.
class SafetyLatch {
 public:
  explicit SafetyLatch(bool reset_at_start = false) noexcept : reset_at_start_(reset_at_start) {}
  // io: the newest SafetyIo, or null when it is missing or stale. Returns the stop reasons.
  [[nodiscard]] std::uint32_t update(const msg::SafetyIo* io) noexcept;
  [[nodiscard]] bool held() const noexcept { return held_; }
  [[nodiscard]] std::uint64_t trips() const noexcept { return trips_; }  // times it began to hold

 private:
  bool reset_at_start_;
  bool held_ = false;
  bool ever_healthy_ = false;  // a stale message after that is a loss like any other
  bool counted_since_clear_ = false;  // resets_seen_ taken since the cause went away
  std::uint32_t resets_seen_ = 0;
  std::uint64_t trips_ = 0;
};

class SafetyFilter {
 public:
  explicit SafetyFilter(const SafetyConfig& config = {}) noexcept;
  [[nodiscard]] SafetyOutput filter(const SafetyInputs& in) const noexcept;
  [[nodiscard]] const SafetyConfig& config() const noexcept { return config_; }
  // The speed at which the nearest mover ahead, inside the corridor the body sweeps, comes
  // towards the robot (0 when none does).
  [[nodiscard]] double closing_speed(const SafetyInputs& in) const noexcept;
  // Whether holding (v, w) brings the body within approach_margin_m of a tracked mover in the
  // horizon, closer than braking now would.
  [[nodiscard]] bool approach_refused(const SafetyInputs& in, double v, double w) const noexcept;
  // Whether (v, w) would leave the robot unable to stop outside a tracked person's cage plus
  // cage_margin_m, or take it into a walker's, when braking now would keep it farther out.
  [[nodiscard]] bool cage_refused(const SafetyInputs& in, double v, double w) const noexcept;
  // The largest speed along (v, w)'s direction that keeps the separation from every tracked
  // person (+inf when none limits it); fills the output's separation terms.
  [[nodiscard]] double separation_cap(const SafetyInputs& in, double v, double scan_age_s, SafetyOutput& out) const noexcept;
  // ISO/TS 15066's separation solved for the robot's speed towards the person: the largest v_r
  // with v_h (T + v_r / a) + v_r T + v_r^2 / (2 a) <= gap (0 when even standing does not hold).
  [[nodiscard]] static double separation_speed(double gap_m, double approach_m_s, double latency_s,
                                               double decel_m_s2) noexcept;

 private:
  static constexpr double kSweepStepM = 0.02;
  static constexpr double kApproachStepS = 0.05;
  static constexpr double kApproachSlackM = 0.02;  // "closer than braking" by at least this
  static constexpr double kCageSlackM = 1e-4;  // rounding only: creeping in by millimetres is creeping in

  // The least gap, over horizon_s, between a disc moving from (x, y) at (vx, vy) (body frame
  // of now) and the body holding (v, w) (then_stop: held for reaction_s and then braked, the
  // horizon that long), and the body braking now from its measured speed.
  struct Gaps {
    double moving_m = 0.0;
    double braking_m = 0.0;
  };
  [[nodiscard]] Gaps gaps(const SafetyInputs& in, double v, double w, double x, double y, double vx, double vy,
                          double radius, double horizon_s, bool then_stop = false) const noexcept;

  struct Crosser {
    double x_m = 0.0, y_m = 0.0;  // body frame, at the scan's time (where its points are)
    double radius_m = 0.0;
    double leaves_s = 0.0;  // when it is out of the corridor
  };
  struct Crossers {
    std::array<Crosser, msg::MovingObstacles::kMax> items{};
    std::size_t count = 0;
    // Whether q (body frame) is a crossing mover's point and the mover leaves before arrival_s.
    [[nodiscard]] bool gone_before(const Point2D& q, double arrival_s) const noexcept;
  };
  [[nodiscard]] Crossers crossing_movers(const SafetyInputs& in, double half_width_m, double scan_age_s) const noexcept;

  SafetyConfig config_;
  // Whether a fresh sonar echo lies in the corridor the body sweeps reversing at v (< 0), or,
  // with turning, inside the turn circle.
  [[nodiscard]] bool sonar_blocks_reverse(const SafetyInputs& in, double v) const noexcept;
  [[nodiscard]] bool sonar_in_turn_circle(const SafetyInputs& in) const noexcept;
  // Whether every disc facing backwards has a reading no older than sonar_max_age_s.
  [[nodiscard]] bool sonar_watches_behind(const SafetyInputs& in) const noexcept;
  double front_m_ = 0.0;
  double rear_m_ = 0.0;
  double half_width_m_ = 0.0;
  double turn_radius_m_ = 0.0;
};

}  // namespace sen3bot::nav
