#pragma once
// The point-offset unicycle (thesis §1.2.2, eq. 1.9-1.11) and the common velocity scaling.
//
// A unicycle at (X, Y, theta) driven by (v, w) moves its point P = (X + L cos theta,
// Y + L sin theta) with
//   P' = [cos theta, -L sin theta; sin theta, L cos theta] [v; w],
// a matrix of determinant L: for L != 0 it is inverted exactly, so any planar velocity u asked
// of P is given by
//   v = cos theta u_x + sin theta u_y,   w = (-sin theta u_x + cos theta u_y) / L,
// and P then behaves as a single integrator P' = u.
#include <span>

#include "sen3bot/geometry/geometry.hpp"

namespace sen3bot::formation {

using Vec2 = geometry::Point2D;
// The wheel axle's centre and heading, map frame.
using Pose = geometry::Pose2D;

struct Unicycle {
  double v = 0.0;  // m/s
  double w = 0.0;  // rad/s
};

[[nodiscard]] Vec2 point_p(const Pose& pose, double offset_m) noexcept;
// The (v, w) that gives P the velocity u (eq. 1.9). offset_m != 0.
[[nodiscard]] Unicycle to_unicycle(const Pose& pose, Vec2 u, double offset_m) noexcept;
// P's velocity for a given (v, w): the forward map, the closed form the inverse is checked with.
[[nodiscard]] Vec2 point_velocity(const Pose& pose, Unicycle command, double offset_m) noexcept;

// F = min{1, v_max / (2 max|v_i|), w_max / (2 max|w_i|)} (§1.2.2): one positive factor for the
// whole team, so every robot keeps within half its limits and the team's trajectories are the
// unscaled field's, only slower. Non-finite commands give 0 (stop everyone).
[[nodiscard]] double common_scale(std::span<const Unicycle> commands, double v_max, double w_max) noexcept;

}  // namespace sen3bot::formation
