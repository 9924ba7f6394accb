#pragma once
// The social force model of pedestrians (Helbing & Molnár 1995) for the simulator's walkers.
// Each walker is a disc of mass m driven by Newton's law:
//
//   m dv/dt = m (v0 e - v) / tau                    driving: relax to the desired velocity
//           + sum_j f_ij + sum_walls f_iW + f_iR     other walkers, walls, the robot if seen
//
//   f_ij = A exp((r_ij - d_ij) / B) w(phi_ij) n_ij  social repulsion (anisotropic)
//        + k g(r_ij - d_ij) n_ij                    body compression
//        + kappa g(r_ij - d_ij) ((v_j - v_i) . t_ij) t_ij   sliding friction
//   f_iW = A exp((r_i - d_iW) / B) n_iW + k g(r_i - d_iW) n_iW - kappa g(r_i - d_iW) (v_i . t_iW) t_iW
//
// with d the distance between centres (or to the nearest wall point), r_ij = r_i + r_j,
// n pointing from the other body to the walker, t = n rotated by +90 degrees and g(x) = max(x, 0).
// Magnitudes and the contact terms are Helbing, Farkas & Vicsek 2000 ("Simulating dynamical
// features of escape panic", Nature 407): m = 80 kg, tau = 0.5 s, A = 2000 N, B = 0.08 m,
// k = 1.2e5 kg/s^2, kappa = 2.4e5 kg/(m s). That paper's interaction is isotropic; the weight
//
//   w(phi) = lambda + (1 - lambda) (1 + cos phi) / 2,   cos phi = -n_ij . e_i
//
// (what lies ahead, along the desired direction e_i, counts fully, what lies behind counts
// lambda) is the circular specification of Helbing & Johansson (Johansson, Helbing & Shukla
// 2007). lambda = 0.5 is our choice; it weights only the social term, never the physical
// contact terms, and walls stay isotropic as in Helbing 2000.
//
// A walker that sees the robot treats it as one more body with the same law (robot radius and
// velocity in place of a person's): with B = 0.08 m the repulsion only matters some 0.3 m
// before contact, so people give way late, as they do. A blind walker (sees_robot = false) feels
// nothing from the robot and walks through its place; the world registers that contact.
//
// Companions (walkers with the same non-zero group) also feel the attraction of Moussaïd et al.
// 2010 ("The walking behaviour of pedestrian social groups", PLoS ONE 5): towards the group's
// centre of mass, m q beta U, with q = 1 once farther from it than (N - 1) / 2 m (N members
// present) and 0 nearer; beta = 1 m/s^2 is our choice. Their gaze term is left out: it turns
// heads, not paths.
//
// Known property of the model: two bodies in exact head-on symmetry (no lateral offset at all)
// only push each other back and stop. Scripted crowds give walkers a few centimetres of offset.
//
// Everything is deterministic and allocation-free; step() updates all walkers from the forces of
// the same instant, so the result does not depend on the walkers' order (up to the rounding of
// the force sums).
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/msg/geometry.hpp"
#include "sen3bot/msg/point_math.hpp"

namespace sen3bot::crowd {

using msg::Point2D;

inline constexpr std::size_t kMaxGoals = 8;      // waypoints per walker
inline constexpr std::size_t kMaxWalkers = 256;  // per step() call (force scratch on the stack)

struct Walker {
  Point2D position;
  Point2D velocity;
  double radius_m = 0.25;          // Helbing 2000: shoulder width 2r of 0.5 to 0.7 m
  double mass_kg = 80.0;           // Helbing 2000
  // About the free walking speed measured by Moussaïd et al. 2009. Also the speed cap's scale:
  // at 0 the walker is a pillar nobody can push; to have someone wait, route them to where they are.
  double desired_speed_m_s = 1.3;
  // Route: goals[next_goal] is where the walker heads; it moves on when within the model's
  // goal_reach_m. With next_goal == goal_count the walker has arrived and stands.
  std::array<Point2D, kMaxGoals> goals{};
  std::size_t goal_count = 0;
  std::size_t next_goal = 0;
  bool active = true;      // false: not in the scene (neither moves nor is an obstacle)
  bool sees_robot = true;  // false: the invisible-robot setting; still avoids walls and people
  std::uint32_t group = 0; // > 0: walks with the others of this group (the attraction above)
};

struct Wall {
  Point2D a;
  Point2D b;  // a == b is a pillar of zero radius
};

struct RobotDisc {
  Point2D centre;
  Point2D velocity;
  double radius_m = 0.3;
};

// Replaces the walker's route by `goals` and starts at the first; capacity error when there are
// more than kMaxGoals (the walker is left unchanged).
Status set_route(Walker& walker, std::span<const Point2D> goals) noexcept;
// True once the walker has passed its last goal (also for a walker that never had one).
[[nodiscard]] bool reached_final_goal(const Walker& walker) noexcept;
// Unit vector towards the current goal; zero when arrived or standing on it.
[[nodiscard]] Point2D desired_direction(const Walker& walker) noexcept;

class SocialForceModel {
 public:
  struct Params {
    double relaxation_s = 0.5;                   // tau, Helbing 2000
    double social_strength_N = 2000.0;           // A, Helbing 2000
    double social_range_m = 0.08;                // B, Helbing 2000
    double body_stiffness_N_per_m = 1.2e5;       // k, Helbing 2000
    double body_friction_kg_per_m_s = 2.4e5;     // kappa, Helbing 2000
    double anisotropy = 0.5;                     // lambda: weight of what is behind (see above)
    double wall_strength_N = 2000.0;             // Helbing 2000 uses A, B for walls too
    double wall_range_m = 0.08;
    double robot_strength_N = 2000.0;            // the robot as another body: the people's A, B
    double robot_range_m = 0.08;
    double max_speed_factor = 1.3;               // speed cap = factor * desired speed
    double goal_reach_m = 0.3;                   // a goal is passed within this distance
    double group_attraction_m_s2 = 1.0;          // beta, companions' pull to their centre
    // Bodies whose surfaces are farther apart than this are skipped: A exp(-3 / 0.08) ~ 1e-13 N.
    double cutoff_gap_m = 3.0;
    // step() splits dt into sub-steps no longer than this: the contact stiffness k/m makes the
    // explicit update oscillate above about 0.03 s; 0.01 s keeps contacts well damped.
    double max_substep_s = 0.01;
  };

  SocialForceModel() = default;
  explicit SocialForceModel(const Params& params) noexcept : params_(params) {}
  [[nodiscard]] const Params& params() const noexcept { return params_; }

  // The single terms of the total force, in newtons.
  [[nodiscard]] Point2D driving_force(const Walker& walker) const noexcept;
  [[nodiscard]] Point2D walker_force(const Walker& on, const Walker& from) const noexcept;
  [[nodiscard]] Point2D wall_force(const Walker& on, const Wall& wall) const noexcept;
  // Towards walkers[i]'s companions (zero alone, or near enough to their centre).
  [[nodiscard]] Point2D group_force(std::size_t i, std::span<const Walker> walkers) const noexcept;
  // Zero for a walker that does not see the robot.
  [[nodiscard]] Point2D robot_force(const Walker& on, const RobotDisc& robot) const noexcept;
  // Total force on walkers[i]; zero for an inactive walker. robot may be null (no robot).
  [[nodiscard]] Point2D force_on(std::size_t i, std::span<const Walker> walkers, std::span<const Wall> walls,
                                 const RobotDisc* robot) const noexcept;

  // Advances every active walker by dt_s (semi-implicit Euler in sub-steps: all forces of a
  // sub-step first, then v += F/m h, speed cap, x += v h, route advance). The robot stands where
  // it is given for the whole step. Fails, changing nothing, for more than kMaxWalkers walkers
  // or a dt_s that is not positive and finite.
  Status step(std::span<Walker> walkers, std::span<const Wall> walls, const RobotDisc* robot,
              double dt_s) const noexcept;

 private:
  // Social, body and friction force on `on` from a disc at `centre`.
  [[nodiscard]] Point2D disc_force(const Walker& on, Point2D centre, Point2D velocity, double radius_m,
                                   double strength_N, double range_m) const noexcept;

  Params params_;
};

}  // namespace sen3bot::crowd
