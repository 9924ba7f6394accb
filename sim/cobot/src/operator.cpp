#include "sen3bot/sim/cobot/operator.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

namespace sen3bot::sim::cobot {

using nav::normalize_angle;
using nav::Point2D;

void OperatorScript::add(double t_s, Point2D at, double facing_rad) {
  times_.push_back(t_s);
  points_.push_back(at);
  facing_.push_back(facing_rad);
}

void OperatorScript::start(double t_s, Point2D at, double facing_rad) {
  times_.clear();
  points_.clear();
  facing_.clear();
  add(t_s, at, facing_rad);
}

void OperatorScript::walk_to(Point2D to, double speed_m_s) {
  const Point2D from = end_at();
  const double d = std::hypot(to.x_m - from.x_m, to.y_m - from.y_m);
  if (d < 1e-6) return;
  const double heading = std::atan2(to.y_m - from.y_m, to.x_m - from.x_m);
  // Turning into the walk takes a moment; then straight on.
  constexpr double kTurnIntoWalkS = 0.3;
  add(end_s() + kTurnIntoWalkS, from, heading);
  add(end_s() + d / std::max(speed_m_s, 0.05), to, heading);
}

void OperatorScript::stand(double duration_s) { add(end_s() + duration_s, end_at(), end_facing()); }

void OperatorScript::turn_to(double facing_rad, double duration_s) {
  // Unwrapped, so interpolation turns the short way; a smaller turn takes less time.
  const double from = end_facing();
  const double angle = normalize_angle(facing_rad - from);
  add(end_s() + std::max(0.2, duration_s * std::fabs(angle) / std::numbers::pi), end_at(), from + angle);
}

Point2D OperatorScript::at(double t_s) const noexcept {
  if (times_.empty()) return {};
  if (t_s <= times_.front()) return points_.front();
  for (std::size_t i = 1; i < times_.size(); ++i) {
    if (t_s > times_[i]) continue;
    const double span = times_[i] - times_[i - 1];
    const double f = span > 0 ? (t_s - times_[i - 1]) / span : 1.0;
    return {points_[i - 1].x_m + f * (points_[i].x_m - points_[i - 1].x_m),
            points_[i - 1].y_m + f * (points_[i].y_m - points_[i - 1].y_m)};
  }
  return points_.back();
}

double OperatorScript::facing(double t_s) const noexcept {
  if (times_.empty()) return 0.0;
  if (t_s <= times_.front()) return normalize_angle(facing_.front());
  for (std::size_t i = 1; i < times_.size(); ++i) {
    if (t_s > times_[i]) continue;
    const double span = times_[i] - times_[i - 1];
    const double f = span > 0 ? (t_s - times_[i - 1]) / span : 1.0;
    const double from = facing_[i - 1];
    return normalize_angle(from + f * normalize_angle(facing_[i] - from));
  }
  return normalize_angle(facing_.back());
}

world::MoverScript OperatorScript::mover(double size_m) const {
  world::MoverScript m;
  m.timeline = points_;
  m.times_s = times_;
  m.path = {points_.empty() ? Point2D{} : points_.front()};
  m.size_m = size_m;
  m.person = true;
  return m;
}

std::string_view to_string(AttemptKind kind) noexcept {
  switch (kind) {
    case AttemptKind::valid: return "valid";
    case AttemptKind::too_far: return "too_far";
    case AttemptKind::too_short: return "too_short";
    case AttemptKind::wrong_order: return "wrong_order";
    case AttemptKind::unknown_operator: return "unknown_operator";
    case AttemptKind::person_in_the_way: return "person_in_the_way";
  }
  return "unknown";
}

namespace {

Point2D ahead(const nav::Pose2D& laser, double forward_m, double left_m) {
  const double c = std::cos(laser.theta_rad), s = std::sin(laser.theta_rad);
  return {laser.x_m + c * forward_m - s * left_m, laser.y_m + s * forward_m + c * left_m};
}

double uniform(std::mt19937_64& rng, double lo, double hi) { return std::uniform_real_distribution<double>(lo, hi)(rng); }

}  // namespace

AttemptPlan plan_attempt(OperatorScript& op, AttemptKind kind, std::uint32_t operator_id, const nav::Pose2D& laser,
                         double t0_s, const AttemptOptions& options, std::mt19937_64& rng) {
  AttemptPlan plan;
  plan.kind = kind;
  plan.operator_id = operator_id;
  // Inside the trained window with a margin for the robot's measurement of where they stand;
  // the failure kinds clearly outside theirs.
  // Centre distances: the robot measures to the body's near side, 0.2 m nearer.
  plan.stand_distance_m = kind == AttemptKind::too_far ? uniform(rng, 1.4, 1.6) : uniform(rng, 0.8, 1.1);
  // Standing still; the tag is also read during part of each turn (until it is turned about 70
  // degrees away), which the robot counts: 2.4-2.8 s shown in all.
  plan.front_s = kind == AttemptKind::too_short ? uniform(rng, 0.6, 1.2) : uniform(rng, 1.9, 2.2);
  plan.back_s = uniform(rng, 1.9, 2.2);
  const double side = std::bernoulli_distribution(0.5)(rng) ? 1.0 : -1.0;
  const double bearing = options.approach_bearing_rad;
  const Point2D from = ahead(laser, options.approach_m * std::cos(bearing), side * options.approach_m * std::sin(bearing));
  const Point2D to = ahead(laser, options.approach_m * std::cos(bearing), -side * options.approach_m * std::sin(bearing));
  const Point2D stand = ahead(laser, plan.stand_distance_m, uniform(rng, -0.1, 0.1));
  op.stand(std::max(0.0, t0_s - op.end_s()));
  op.walk_to(from, options.walk_speed_m_s);
  plan.start_s = op.end_s();
  op.walk_to(stand, options.walk_speed_m_s * 0.7);
  const double towards = std::atan2(laser.y_m - stand.y_m, laser.x_m - stand.x_m);
  const double face = towards + uniform(rng, -options.facing_error_rad, options.facing_error_rad);
  const double away = towards + std::numbers::pi + uniform(rng, -options.facing_error_rad, options.facing_error_rad);
  if (kind == AttemptKind::wrong_order) {
    op.turn_to(away, options.turn_s);
    op.stand(plan.back_s);
    op.turn_to(face, options.turn_s);
    op.stand(plan.front_s);
  } else {
    op.turn_to(face, options.turn_s);
    op.stand(plan.front_s);
    op.turn_to(away, options.turn_s);
    op.stand(plan.back_s);
    if (options.twice) {
      op.turn_to(face, options.turn_s);
      op.stand(uniform(rng, 1.9, 2.2));
      op.turn_to(away, options.turn_s);
      op.stand(uniform(rng, 1.9, 2.2));
    }
  }
  if (options.leave) op.walk_to(to, options.walk_speed_m_s);
  plan.end_s = op.end_s();
  if (kind == AttemptKind::person_in_the_way) {
    plan.bystander = true;
    // A step behind the operator and to the side, in the camera's view (it covers about 25
    // degrees either way) and not hidden behind the operator from the laser: someone else
    // within reach of the operator.
    plan.bystander_at = ahead(laser, plan.stand_distance_m + uniform(rng, 0.6, 0.8), side * uniform(rng, 0.45, 0.5));
  }
  return plan;
}

}  // namespace sen3bot::sim::cobot
