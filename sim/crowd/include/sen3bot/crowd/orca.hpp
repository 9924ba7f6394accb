#pragma once
// Optimal Reciprocal Collision Avoidance for simulated people (van den Berg, Guy, Lin & Manocha,
// "Reciprocal n-body collision avoidance", ISRR 2011), written from the paper.
//
// For agent A and neighbour B (relative position p = p_B - p_A, combined radius r, relative
// velocity v = v_A - v_B) the velocity obstacle for the time horizon tau is the cone of
// relative velocities that touch the disc D(p, r) within tau: the cone from the origin tangent
// to D(p/tau, r/tau), cut off by that small disc. u is the smallest change of v that takes it
// to the cone's boundary and n the boundary's outward normal there; A may use the half-plane
//
//   ORCA = { v : (v - (v_A + rho u)) . n >= 0 }
//
// with rho = 1/2 when B does the other half (another agent) and rho = 1 when B does not react
// (the robot, a scripted walker). Agents already overlapping use the disc D(p/dt, r/dt)
// instead, so that they separate within one step dt. The paper's optimisation velocity is the
// current velocity, as here. The new velocity is the one closest to the preferred velocity in
// all half-planes and within the speed limit (a 2D linear program solved incrementally: a
// constraint the current answer breaks puts the answer on its line); when the half-planes leave
// no room, the velocity that breaks the worst of them least (a 3D linear program in (v, d)),
// which the paper uses for dense crowds. Line-segment obstacles (walls) are not modelled: the
// open scenes this serves (CrowdNav's circle crossing) have none.
//
// Ties: a relative velocity exactly on the cone's axis (a perfectly head-on pair) is sent to the
// right leg, so both people keep right. Everything is deterministic and allocation-free.
#include <cstddef>
#include <span>

#include "sen3bot/msg/geometry.hpp"
#include "sen3bot/msg/point_math.hpp"

namespace sen3bot::crowd {

using msg::Point2D;

inline constexpr std::size_t kMaxOrcaAgents = 64;     // per orca_step() (new velocities on the stack)
inline constexpr std::size_t kMaxOrcaNeighbors = 16;  // half-planes per agent; more are ignored

struct OrcaAgent {
  Point2D position;
  Point2D velocity;
  Point2D preferred_velocity;
  double radius_m = 0.3;
  double max_speed_m_s = 1.0;
  bool active = true;  // false: not in the scene (neither moves nor is seen)
};

// Something agents avoid but which does not avoid them: it takes no share (rho = 1). The robot
// when people see it; leave it out for CrowdNav's invisible-robot setting.
struct OrcaDisc {
  Point2D position;
  Point2D velocity;
  double radius_m = 0.3;
};

// CrowdNav's ORCA humans: tau 5 s, neighbours within 10 m, at most 10 of them, and every radius
// 1 cm larger than the body. ORCA's answer lies on a half-plane's edge, i.e. a pair passes at
// exactly the sum of radii; without the margin rounding turns a third of CrowdNav's circle
// crossings into contacts of 1e-15 m.
struct OrcaParams {
  double time_horizon_s = 5.0;
  double neighbor_distance_m = 10.0;  // centre distance
  std::size_t max_neighbors = 10;     // capped at kMaxOrcaNeighbors
  double radius_padding_m = 0.01;     // added to every disc's radius (agents and others)
};

// A neighbour as one agent sees it; responsibility is rho (0.5 reciprocal, 1 for a disc that
// does not react).
struct OrcaNeighbor {
  Point2D position;
  Point2D velocity;
  double radius_m = 0.3;
  double responsibility = 0.5;
};

// Permitted velocities v: (v - point) . normal >= 0. u is the change of relative velocity that
// leaves the velocity obstacle (point = v_A + rho u), kept for reports and tests.
struct OrcaHalfPlane {
  Point2D point;
  Point2D normal;  // unit
  Point2D u;
};

// The ORCA half-plane of `self` for one neighbour, radii as given (no padding). time_horizon_s
// and dt must be > 0.
[[nodiscard]] OrcaHalfPlane orca_half_plane(const OrcaAgent& self, const OrcaNeighbor& other, double time_horizon_s,
                                            double dt) noexcept;

// The velocity within max_speed_m_s nearest `preferred` in every half-plane, or, when there is
// none, the one whose largest violation is least. Uses the first kMaxOrcaNeighbors planes.
[[nodiscard]] Point2D solve_velocity(std::span<const OrcaHalfPlane> planes, Point2D preferred,
                                     double max_speed_m_s) noexcept;

// One agent's new velocity among `neighbors`: the nearest max_neighbors within
// neighbor_distance_m (equal distances in span order) each give a half-plane.
[[nodiscard]] Point2D new_velocity(const OrcaAgent& self, std::span<const OrcaNeighbor> neighbors,
                                   const OrcaParams& params, double dt) noexcept;

// Every active agent's new velocity from the same instant (the result does not depend on the
// agents' order), then each moves velocity * dt. Neighbours are the other active agents
// (reciprocal) and `others` (not reacting), nearest first, equal distances by index (agents
// before others). Returns false and changes nothing when agents.size() > kMaxOrcaAgents.
bool orca_step(std::span<OrcaAgent> agents, std::span<const OrcaDisc> others, const OrcaParams& params,
               double dt) noexcept;

}  // namespace sen3bot::crowd
