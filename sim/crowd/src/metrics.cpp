#include "sen3bot/crowd/metrics.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

namespace sen3bot::crowd {
namespace {

// The type 7 quantile of sorted values: between the order statistics around (n - 1) p.
double quantile(std::span<const double> sorted, double p) noexcept {
  const double h = static_cast<double>(sorted.size() - 1) * p;
  const auto lo = static_cast<std::size_t>(std::floor(h));
  const std::size_t hi = std::min(lo + 1, sorted.size() - 1);
  const double frac = h - static_cast<double>(lo);
  // Equal neighbours (infinities included) need no interpolation, which would give inf - inf.
  if (frac == 0.0 || sorted[lo] == sorted[hi]) return sorted[lo];
  return sorted[lo] + frac * (sorted[hi] - sorted[lo]);
}

Rate rate_of(std::size_t count, std::size_t n) noexcept {
  const Interval ci = wilson_interval(count, n);
  return {count, n, n > 0 ? static_cast<double>(count) / static_cast<double>(n) : 0.0, ci.lower, ci.upper};
}

}  // namespace

double body_distance(const nav::Footprint& footprint, const Pose2D& pose, Point2D centre, double radius_m) noexcept {
  const Point2D offset = centre - Point2D{pose.x_m, pose.y_m};
  if (footprint.vertex_count == 0) return norm(offset) - footprint.circle_radius_m - radius_m;
  // The person into the robot frame: one rotation instead of placing every corner.
  const double c = std::cos(pose.theta_rad);
  const double s = std::sin(pose.theta_rad);
  const Point2D local{c * offset.x_m + s * offset.y_m, -s * offset.x_m + c * offset.y_m};
  const std::size_t count = std::min(footprint.vertex_count, nav::Footprint::kMaxVertices);
  return msg::convex_polygon_distance({footprint.vertices.data(), count}, local) - radius_m;
}

void RunMeter::start(const RunSetup& setup) noexcept {
  *this = RunMeter{};
  setup_ = setup;
}

void RunMeter::observe(const RunStep& step) noexcept {
  RunMetrics& m = metrics_;
  ++m.steps;

  if (have_pose_) m.path_length_m += std::hypot(step.robot.x_m - last_pose_.x_m, step.robot.y_m - last_pose_.y_m);
  last_pose_ = step.robot;
  have_pose_ = true;
  if (setup_.free_path_length_m > 0.0) m.path_ratio = m.path_length_m / setup_.free_path_length_m;

  double nearest = std::numeric_limits<double>::infinity();
  for (const PersonTruth& p : step.people) {
    if (p.visible) nearest = std::min(nearest, body_distance(step.footprint, step.robot, p.position, p.radius_m));
  }
  if (nearest < m.min_distance_m) {
    m.min_distance_m = nearest;
    m.min_distance_time_s = step.time_s;
  }
  if (nearest < kIntimateZoneM) m.intimate_zone_s += setup_.dt_s;
  if (nearest < kPersonalZoneM) m.personal_zone_s += setup_.dt_s;
  if (nearest < kDangerDistanceM) ++danger_steps_;
  m.danger_frequency = static_cast<double>(danger_steps_) / static_cast<double>(m.steps);

  if (step.contact_started) {
    ++m.contacts_any;
    if (step.contact_by_robot) ++m.contacts_by_robot;
  }
  if (step.robot_in_cage && !was_in_cage_) ++m.cage_entries;
  was_in_cage_ = step.robot_in_cage;

  // Jerk needs three speeds: two accelerations.
  if (m.steps >= 2 && setup_.dt_s > 0.0) {
    const double a = (step.v_m_s - last_v_) / setup_.dt_s;
    const double alpha = (step.w_rad_s - last_w_) / setup_.dt_s;
    if (m.steps >= 3) {
      const double jerk = std::abs(a - last_a_) / setup_.dt_s;
      const double angular_jerk = std::abs(alpha - last_alpha_) / setup_.dt_s;
      ++jerk_count_;
      jerk_sum_ += jerk;
      angular_jerk_sum_ += angular_jerk;
      m.max_jerk_m_s3 = std::max(m.max_jerk_m_s3, jerk);
      m.max_angular_jerk_rad_s3 = std::max(m.max_angular_jerk_rad_s3, angular_jerk);
      m.mean_jerk_m_s3 = jerk_sum_ / static_cast<double>(jerk_count_);
      m.mean_angular_jerk_rad_s3 = angular_jerk_sum_ / static_cast<double>(jerk_count_);
    }
    last_a_ = a;
    last_alpha_ = alpha;
  }
  last_v_ = step.v_m_s;
  last_w_ = step.w_rad_s;
}

const RunMetrics& RunMeter::finish(bool reached_goal, double time_s) noexcept {
  RunMetrics& m = metrics_;
  const double elapsed = time_s - setup_.start_time_s;
  const bool in_time = reached_goal && elapsed <= setup_.time_limit_s;
  m.reached_goal = reached_goal;
  m.success = in_time && m.contacts_any == 0;
  // A run given up before the limit (not reached, still time left) is no timeout.
  m.timeout = !in_time && elapsed >= setup_.time_limit_s;
  m.time_to_goal_s = reached_goal ? elapsed : -1.0;
  m.time_ratio = reached_goal && setup_.free_path_time_s > 0.0 ? elapsed / setup_.free_path_time_s : -1.0;
  return m;
}

Interval wilson_interval(std::size_t successes, std::size_t n, double z) noexcept {
  if (n == 0) return {0.0, 1.0};
  const double nn = static_cast<double>(n);
  const double p = static_cast<double>(std::min(successes, n)) / nn;
  const double z2 = z * z;
  const double denominator = 1.0 + z2 / nn;
  const double centre = (p + z2 / (2.0 * nn)) / denominator;
  const double half = z * std::sqrt(p * (1.0 - p) / nn + z2 / (4.0 * nn * nn)) / denominator;
  // At 0 and n successes the bound is exactly 0 or 1; the subtraction leaves rounding.
  return {successes == 0 ? 0.0 : std::max(0.0, centre - half), successes >= n ? 1.0 : std::min(1.0, centre + half)};
}

Quartiles quartiles(std::span<double> values) noexcept {
  Quartiles q;
  q.n = values.size();
  if (values.empty()) return q;
  std::sort(values.begin(), values.end());
  q.q1 = quantile(values, 0.25);
  q.median = quantile(values, 0.5);
  q.q3 = quantile(values, 0.75);
  q.iqr = q.q1 == q.q3 ? 0.0 : q.q3 - q.q1;
  q.min = values.front();
  q.max = values.back();
  return q;
}

Aggregate aggregate(std::span<const RunMetrics> runs) {
  Aggregate out;
  out.n = runs.size();
  std::size_t successes = 0;
  std::size_t collisions = 0;
  std::size_t timeouts = 0;
  std::vector<double> scratch;
  scratch.reserve(runs.size());
  for (const RunMetrics& r : runs) {
    successes += r.success ? 1 : 0;
    collisions += r.contacts_by_robot > 0 ? 1 : 0;
    timeouts += r.timeout ? 1 : 0;
    if (r.success) scratch.push_back(r.time_to_goal_s);
    out.mean_intimate_zone_s += r.intimate_zone_s;
    out.mean_personal_zone_s += r.personal_zone_s;
    out.mean_danger_frequency += r.danger_frequency;
  }
  out.success = rate_of(successes, runs.size());
  out.collision = rate_of(collisions, runs.size());
  out.timeout = rate_of(timeouts, runs.size());
  out.time_to_goal_s = quartiles(scratch);
  scratch.clear();
  for (const RunMetrics& r : runs) scratch.push_back(r.min_distance_m);
  out.min_distance_m = quartiles(scratch);
  if (!runs.empty()) {
    const double n = static_cast<double>(runs.size());
    out.mean_intimate_zone_s /= n;
    out.mean_personal_zone_s /= n;
    out.mean_danger_frequency /= n;
  }
  return out;
}

}  // namespace sen3bot::crowd
