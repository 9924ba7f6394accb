#include "sen3bot/crowd/social_force.hpp"

#include <algorithm>
#include <cmath>

namespace sen3bot::crowd {
namespace {

using msg::dot;
using msg::norm;
using msg::perpendicular;
using msg::unit_or;

// Where the walker looks, for the anisotropy: towards its goal, or where it moves once arrived.
Point2D heading(const Walker& w) noexcept {
  const Point2D e = desired_direction(w);
  return (e.x_m != 0.0 || e.y_m != 0.0) ? e : unit_or(w.velocity, {});
}

Point2D nearest_on_segment(Point2D q, const Wall& wall) noexcept {
  const Point2D ab = wall.b - wall.a;
  const double len2 = msg::norm_squared(ab);
  const double t = len2 > 0.0 ? std::clamp(dot(q - wall.a, ab) / len2, 0.0, 1.0) : 0.0;
  return wall.a + t * ab;
}

void advance_route(Walker& w, double reach_m) noexcept {
  while (w.next_goal < w.goal_count && norm(w.goals[w.next_goal] - w.position) < reach_m) ++w.next_goal;
}

}  // namespace

Status set_route(Walker& walker, std::span<const Point2D> goals) noexcept {
  if (goals.size() > kMaxGoals) {
    return Error::format(Errc::capacity, "route of %zu goals, at most %zu", goals.size(), kMaxGoals);
  }
  std::copy(goals.begin(), goals.end(), walker.goals.begin());
  walker.goal_count = goals.size();
  walker.next_goal = 0;
  return Status::success();
}

bool reached_final_goal(const Walker& walker) noexcept { return walker.next_goal >= walker.goal_count; }

Point2D desired_direction(const Walker& walker) noexcept {
  if (reached_final_goal(walker)) return {};
  return unit_or(walker.goals[walker.next_goal] - walker.position, {});
}

Point2D SocialForceModel::driving_force(const Walker& walker) const noexcept {
  const Point2D desired = walker.desired_speed_m_s * desired_direction(walker);
  return (walker.mass_kg / params_.relaxation_s) * (desired - walker.velocity);
}

Point2D SocialForceModel::disc_force(const Walker& on, Point2D centre, Point2D velocity, double radius_m,
                                     double strength_N, double range_m) const noexcept {
  const Point2D e = heading(on);
  const Point2D diff = on.position - centre;
  const double d = norm(diff);
  const double overlap = on.radius_m + radius_m - d;  // r_ij - d_ij
  if (-overlap > params_.cutoff_gap_m) return {};
  // Coincident centres have no direction; backing off against the heading separates them.
  const Point2D n = unit_or(diff, -e);
  const double lambda = params_.anisotropy;
  const double weight = lambda + (1.0 - lambda) * 0.5 * (1.0 - dot(n, e));
  Point2D f = (strength_N * std::exp(overlap / range_m) * weight) * n;
  if (overlap > 0.0) {
    const Point2D t = perpendicular(n);
    f += (params_.body_stiffness_N_per_m * overlap) * n;
    f += (params_.body_friction_kg_per_m_s * overlap * dot(velocity - on.velocity, t)) * t;
  }
  return f;
}

Point2D SocialForceModel::walker_force(const Walker& on, const Walker& from) const noexcept {
  return disc_force(on, from.position, from.velocity, from.radius_m, params_.social_strength_N,
                    params_.social_range_m);
}

Point2D SocialForceModel::robot_force(const Walker& on, const RobotDisc& robot) const noexcept {
  if (!on.sees_robot) return {};
  return disc_force(on, robot.centre, robot.velocity, robot.radius_m, params_.robot_strength_N,
                    params_.robot_range_m);
}

Point2D SocialForceModel::wall_force(const Walker& on, const Wall& wall) const noexcept {
  const Point2D diff = on.position - nearest_on_segment(on.position, wall);
  const double d = norm(diff);
  const double overlap = on.radius_m - d;
  if (-overlap > params_.cutoff_gap_m) return {};
  const Point2D n = unit_or(diff, -heading(on));
  Point2D f = (params_.wall_strength_N * std::exp(overlap / params_.wall_range_m)) * n;
  if (overlap > 0.0) {
    const Point2D t = perpendicular(n);
    f += (params_.body_stiffness_N_per_m * overlap) * n;
    f -= (params_.body_friction_kg_per_m_s * overlap * dot(on.velocity, t)) * t;
  }
  return f;
}

Point2D SocialForceModel::group_force(std::size_t i, std::span<const Walker> walkers) const noexcept {
  const Walker& me = walkers[i];
  if (me.group == 0 || !me.active) return {};
  Point2D sum;
  std::size_t n = 0;
  for (const Walker& w : walkers) {
    if (w.group != me.group || !w.active) continue;
    sum += w.position;
    ++n;
  }
  if (n < 2) return {};
  const Point2D to_centre = (1.0 / static_cast<double>(n)) * sum - me.position;
  const double d = norm(to_centre);
  if (d <= 0.5 * static_cast<double>(n - 1)) return {};
  return (me.mass_kg * params_.group_attraction_m_s2 / d) * to_centre;
}

Point2D SocialForceModel::force_on(std::size_t i, std::span<const Walker> walkers, std::span<const Wall> walls,
                                   const RobotDisc* robot) const noexcept {
  const Walker& me = walkers[i];
  if (!me.active) return {};
  Point2D f = driving_force(me);
  for (std::size_t j = 0; j < walkers.size(); ++j) {
    if (j != i && walkers[j].active) f += walker_force(me, walkers[j]);
  }
  for (const Wall& wall : walls) f += wall_force(me, wall);
  if (robot != nullptr) f += robot_force(me, *robot);
  f += group_force(i, walkers);
  return f;
}

Status SocialForceModel::step(std::span<Walker> walkers, std::span<const Wall> walls, const RobotDisc* robot,
                              double dt_s) const noexcept {
  if (walkers.size() > kMaxWalkers) {
    return Error::format(Errc::capacity, "%zu walkers, at most %zu", walkers.size(), kMaxWalkers);
  }
  const double substeps = std::ceil(dt_s / params_.max_substep_s);
  if (!(dt_s > 0.0) || !(substeps <= 1e6)) {
    return Error::format(Errc::invalid_argument, "dt %g s in sub-steps of %g s", dt_s, params_.max_substep_s);
  }
  const int count = substeps < 1.0 ? 1 : static_cast<int>(substeps);
  const double h = dt_s / count;
  std::array<Point2D, kMaxWalkers> forces;
  for (int s = 0; s < count; ++s) {
    // All forces from the same instant first, so no walker sees another's new state.
    for (std::size_t i = 0; i < walkers.size(); ++i) forces[i] = force_on(i, walkers, walls, robot);
    for (std::size_t i = 0; i < walkers.size(); ++i) {
      Walker& w = walkers[i];
      if (!w.active) continue;
      w.velocity += (h / w.mass_kg) * forces[i];
      const double cap = params_.max_speed_factor * w.desired_speed_m_s;
      const double speed = norm(w.velocity);
      if (speed > cap) w.velocity = (speed > 0.0 ? cap / speed : 0.0) * w.velocity;
      w.position += h * w.velocity;
      advance_route(w, params_.goal_reach_m);
    }
  }
  return Status::success();
}

}  // namespace sen3bot::crowd
