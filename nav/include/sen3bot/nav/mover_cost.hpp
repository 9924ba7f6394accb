#pragma once
// The dynamic obstacle layer's cost (dynamic_obstacles.hpp): the space a mover is about to
// occupy, painted into a costmap.
#include "sen3bot/nav/costmap.hpp"

namespace sen3bot::nav {

// The asymmetric Gaussian: with d the distance from the centroid and θ_c the velocity direction,
//   Φ(q) = A exp(-[d cos(θ-θ_c)]² / (2 σx²) - [d sin(θ-θ_c)]² / (2 σy²))
// front half-plane: σx² = (1 + r) sigma2_front_x, σy² = (1 - r/2) sigma2_front_y
// back half-plane:  σx² = (1 - r) sigma2_back_x,  σy² = (1 - r/4) sigma2_back_y
// r = min(1, speed / max_speed_m_s). Ahead, the Gaussian starts front_horizon_s * speed in
// front of the centroid (flat before it): the space the mover reaches in that time.
// A is min(amplitude, 252). "Front" is the half-plane where d cos(θ-θc) > 0; at zero velocity
// θc = 0 and r = 0 (the layer paints only tracks of at least min_speed_m_s). Each σ² is kept
// at least 1e-4 m² so that r = 1 behind the mover stays finite.
struct DolCostConfig {
  double amplitude = 252.0;        // kMaxNonObstacleCost: painted cells are never lethal...
  double cutoff = 30.0;            // ...and cells below this are left alone
  double sigma2_front_x_m2 = 1.0;  // the source's 2.0, 0.7, 0.5, 0.9 m² with its exponent
  double sigma2_front_y_m2 = 0.35; // factor csf * 0.2 = 2 folded in
  double sigma2_back_x_m2 = 0.25;
  double sigma2_back_y_m2 = 0.45;
  double max_speed_m_s = 2.0;
  double front_horizon_s = 1.0;    // 0: the source's shape
  double lethal_radius_m = 0.1;    // ...except this core around the predicted centre: 254
  double min_speed_m_s = 0.1;      // slower tracks are painted as a core only
};

// The Gaussian's value at (x_m, y_m) for a mover at (cx, cy) moving with (vx, vy); 0 below cutoff.
[[nodiscard]] double mover_cost(const DolCostConfig& config, double cx, double cy, double vx, double vy, double x_m,
                                double y_m) noexcept;
// Max-merges mover_cost over the grid cells around the mover into grid (never lowers a cell).
// Visits only the cells whose centre lies in the box around the mover outside which the
// Gaussian is below cutoff.
void paint_mover(const DolCostConfig& config, double cx, double cy, double vx, double vy, Costmap2D& grid) noexcept;
// Marks the cells whose centre lies within radius_m of (x, y), and the cell holding it, lethal.
void paint_core(double x_m, double y_m, double radius_m, Costmap2D& grid) noexcept;

}  // namespace sen3bot::nav
