#pragma once
// The per-run metrics of a crowd-navigation run, from the referee's ground truth, and their
// aggregation over many runs. A RunMeter is fed one RunStep per world step (a fixed step dt) and
// keeps running sums only: fixed memory, no allocation per step.
//
// Distances are body to body: from the robot's footprint placed at its true pose to the edge of
// a person's body circle (negative when they overlap). The zones are Hall's proxemics (intimate
// up to 0.45 m, personal up to 1.2 m); the danger share is CrowdNav's (Chen et al. 2019), which
// counts the steps closer than its discomfort distance of 0.2 m, here as the share of the run's
// time (steps at a fixed dt). Contacts and cage intrusions are the world's to judge: the meter
// only counts them.
#include <cstddef>
#include <cstdint>
#include <limits>
#include <span>

#include "sen3bot/msg/geometry.hpp"
#include "sen3bot/msg/point_math.hpp"
#include "sen3bot/nav/geometry.hpp"

namespace sen3bot::crowd {

using msg::Point2D;
using msg::Pose2D;

inline constexpr double kIntimateZoneM = 0.45;
inline constexpr double kPersonalZoneM = 1.2;
inline constexpr double kDangerDistanceM = 0.2;  // CrowdNav's discomfort_dist

// One person as the world has them at a step.
struct PersonTruth {
  Point2D position;
  Point2D velocity;
  double radius_m = 0.25;  // the body, shoulders included
  bool visible = true;     // not yet in or already out of the scene: ignored
};

// What the world knows at one step.
struct RunStep {
  double time_s = 0.0;
  Pose2D robot;          // true pose
  double v_m_s = 0.0;    // true forward speed
  double w_rad_s = 0.0;  // true yaw rate
  nav::Footprint footprint = nav::Footprint::pioneer();
  std::span<const PersonTruth> people;
  bool contact_started = false;   // a contact with anyone began at this step
  bool contact_by_robot = false;  // read with contact_started: the robot was moving towards them
  bool robot_in_cage = false;     // the robot is inside some person's virtual cage
};

struct RunSetup {
  double dt_s = 0.05;               // the fixed step between RunSteps
  double start_time_s = 0.0;        // when the robot set off (RunStep::time_s clock)
  double time_limit_s = 60.0;       // from the start
  double free_path_time_s = 0.0;    // the caller's reference time, e.g. straight length / max speed
  double free_path_length_m = 0.0;  // the caller's reference length, e.g. the straight line
};

struct RunMetrics {
  bool reached_goal = false;
  bool success = false;  // reached within the time limit without any contact
  bool timeout = false;  // the time limit passed before the goal (a late arrival too)
  std::uint32_t contacts_any = 0;
  std::uint32_t contacts_by_robot = 0;
  std::uint32_t cage_entries = 0;  // steps the robot went from outside every cage to inside one
  double time_to_goal_s = -1.0;    // from the start; -1 unless the goal was reached
  double time_ratio = -1.0;        // time_to_goal_s / free_path_time_s; -1 unless both known
  double path_length_m = 0.0;      // the true path
  double path_ratio = -1.0;        // path_length_m / free_path_length_m; -1 without a reference
  // Closest body-to-body distance to any visible person, and when; infinity with nobody seen.
  double min_distance_m = std::numeric_limits<double>::infinity();
  double min_distance_time_s = -1.0;
  // Time with someone nearer than the zone's bound (nested: the personal time includes the
  // intimate time).
  double intimate_zone_s = 0.0;
  double personal_zone_s = 0.0;
  double danger_frequency = 0.0;  // share of steps (of time) nearer than kDangerDistanceM
  // |d^2 v / dt^2| and |d^2 w / dt^2| by finite differences over consecutive steps.
  double mean_jerk_m_s3 = 0.0;
  double max_jerk_m_s3 = 0.0;
  double mean_angular_jerk_rad_s3 = 0.0;
  double max_angular_jerk_rad_s3 = 0.0;
  std::uint64_t steps = 0;
};

// Body-to-body distance from the footprint at `pose` to a circle of radius_m around `centre`:
// negative when they overlap (down to -radius_m with the centre inside the footprint).
[[nodiscard]] double body_distance(const nav::Footprint& footprint, const Pose2D& pose, Point2D centre,
                                   double radius_m) noexcept;

class RunMeter {
 public:
  // Forgets the previous run.
  void start(const RunSetup& setup) noexcept;
  // Every world step; never allocates.
  void observe(const RunStep& step) noexcept;
  // The end of the run at time_s (RunStep::time_s clock): settles success, timeout and times.
  const RunMetrics& finish(bool reached_goal, double time_s) noexcept;

  // So far, or the finished run.
  [[nodiscard]] const RunMetrics& metrics() const noexcept { return metrics_; }

 private:
  RunSetup setup_;
  RunMetrics metrics_;
  bool have_pose_ = false;
  Pose2D last_pose_;
  bool was_in_cage_ = false;
  std::uint64_t danger_steps_ = 0;
  // Finite differences: the last speeds and accelerations, and how many of each exist.
  double last_v_ = 0.0;
  double last_w_ = 0.0;
  double last_a_ = 0.0;
  double last_alpha_ = 0.0;
  std::uint64_t jerk_count_ = 0;
  double jerk_sum_ = 0.0;
  double angular_jerk_sum_ = 0.0;
};

// A binomial proportion with its 95 % (for z = 1.96) Wilson score interval.
struct Rate {
  std::size_t count = 0;
  std::size_t n = 0;
  double rate = 0.0;  // count / n; 0 when n == 0
  double lower = 0.0;
  double upper = 1.0;
};

struct Interval {
  double lower = 0.0;
  double upper = 1.0;
};

// The Wilson score interval for `successes` out of n (Wilson 1927): unlike the normal
// approximation it stays inside [0, 1] and is not empty at 0 or n successes. [0, 1] for n == 0.
[[nodiscard]] Interval wilson_interval(std::size_t successes, std::size_t n, double z = 1.96) noexcept;

// Quartiles by linear interpolation between order statistics (Hyndman & Fan type 7, the
// default of R and numpy); NaN without values.
struct Quartiles {
  std::size_t n = 0;
  double q1 = std::numeric_limits<double>::quiet_NaN();
  double median = std::numeric_limits<double>::quiet_NaN();
  double q3 = std::numeric_limits<double>::quiet_NaN();
  double iqr = std::numeric_limits<double>::quiet_NaN();
  double min = std::numeric_limits<double>::quiet_NaN();
  double max = std::numeric_limits<double>::quiet_NaN();
};
// Sorts `values` in place.
[[nodiscard]] Quartiles quartiles(std::span<double> values) noexcept;

struct Aggregate {
  std::size_t n = 0;
  Rate success;
  Rate collision;  // runs with contacts_by_robot > 0
  Rate timeout;
  Quartiles time_to_goal_s;  // successful runs only
  Quartiles min_distance_m;  // every run
  // Means over every run; 0 without runs.
  double mean_intimate_zone_s = 0.0;
  double mean_personal_zone_s = 0.0;
  double mean_danger_frequency = 0.0;
};

// Over finished runs. Allocates a scratch copy for the quartiles: call after the runs.
[[nodiscard]] Aggregate aggregate(std::span<const RunMetrics> runs);

}  // namespace sen3bot::crowd
