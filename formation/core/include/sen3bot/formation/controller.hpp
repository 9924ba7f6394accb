#pragma once
// The centralised formation controller (thesis §1.2.2; docs/formation.md has the construction
// and what is proved or tested of it). Pure: no I/O, no clock (time is handed in), every buffer
// inside the object; step() allocates nothing.
//
// Each robot i is driven through its point P_i, L ahead of its axle (unicycle.hpp), so the team
// is the single-integrator system x' = f(x, k) with x = (P_1, ..., P_N). f is a task field (go
// to targets; patrol a closed curve in formation; a leader patrols, followers keep offsets from
// it) plus barrier terms that keep the robots apart and inside the workspace. k is one of a
// finite set of gain vectors; V is the task's Lyapunov function and rho = eta * (-<grad V,
// f_task(x)>) the decrease asked for. The hybrid rule: flow while <grad V, f(x, k)> <= -mu rho;
// when that fails, jump to the k in the set with the steepest decrease (which meets -rho when
// the set allows it), at most once per min_dwell_s. The field is then turned into (v, w) per
// robot and scaled by the common factor F.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>

#include "sen3bot/formation/unicycle.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/nav/sgp.hpp"

namespace sen3bot::formation {

inline constexpr std::size_t kMaxRobots = 10;
inline constexpr std::size_t kMaxObstacles = 16;
inline constexpr std::size_t kMaxGainSets = 8;
inline constexpr std::size_t kCurveSamples = 1024;

enum class TaskKind : std::uint8_t {
  targets,  // robot i to targets[i]
  patrol,   // every robot on the curve, evenly spaced along it, moving along it
  leader,   // robot 0 patrols the curve; robot i > 0 keeps P_i = P_0 + offsets[i]
};

// The workspace's inside (walls at its edges) and round obstacles in it, map frame.
struct Workspace {
  double x0_m = -1e9;
  double y0_m = -1e9;
  double x1_m = 1e9;
  double y1_m = 1e9;
};
struct Obstacle {
  Vec2 centre;
  double radius_m = 0.0;
};

// One element of the parameter set A: the gains k the hybrid rule chooses among.
struct Gains {
  double attract = 0.6;      // 1/s: targets, follower offsets, distance to the curve
  double spacing = 0.6;      // 1/s: along-curve spacing error to speed
  double repel = 0.02;       // m^2/s: barrier strength (robots and obstacles)
  double swirl_rad = 0.0;    // the robot-robot and round-obstacle repulsion turned by this angle
};

struct ControllerConfig {
  TaskKind task = TaskKind::targets;
  std::size_t robots = 0;
  double offset_m = 0.1;        // L, the axle to P
  double radius_m = 0.3;        // a robot's body circle about its axle
  double margin_m = 0.05;       // the barriers' zero lies this far outside contact
  double influence_m = 0.25;    // a barrier acts within this of its zero; the task's set lies beyond
  Workspace workspace;
  std::array<Obstacle, kMaxObstacles> obstacles{};
  std::size_t obstacle_count = 0;
  std::array<Vec2, kMaxRobots> targets{};   // TaskKind::targets
  nav::SafeCurve curve;                     // patrol, leader: a closed curve p(x) = 0
  Vec2 curve_start;                         // a point on or near the curve, where tracing starts
  double along_speed_m_s = 0.12;            // patrol, leader: speed along the curve (sign: direction)
  std::array<Vec2, kMaxRobots> offsets{};   // leader: P_i - P_0 for i > 0
  double target_saturation_m = 1.0;         // the attraction stops growing beyond this error
  std::array<Gains, kMaxGainSets> gain_sets{};
  std::size_t gain_set_count = 0;           // 0: the defaults (default_gain_sets())
  double eta = 0.3;                         // rho = eta * the task field's own decrease
  double mu = 0.5;                          // the flow condition's slack (0 < mu < 1)
  double min_dwell_s = 0.5;
  double settled_v = 1e-4;                  // below this V the decrease is not checked (m^2)
  double v_max_m_s = 0.5;                   // v-bar
  double w_max_rad_s = 1.5;                 // w-bar
};

// The set A used when a configuration gives none: the nominal gains, and the same with the
// avoidance turned by +-60 degrees (breaks the symmetric stand-offs where repulsion cancels
// attraction), with stronger and weaker attraction.
[[nodiscard]] std::span<const Gains> default_gain_sets() noexcept;

// What one step decided, for logs and reports.
struct StepInfo {
  double t_s = 0.0;
  double lyapunov = 0.0;       // V(x)
  double decrease = 0.0;       // <grad V, f(x, k)> for the k in force after the step
  double rho = 0.0;
  double scale = 1.0;          // F
  std::size_t gain_set = 0;    // index into A
  bool switched = false;       // the hybrid rule jumped this step
  bool unresolved = false;     // no k in A met -rho here (Assumption 2 fails at this x)
  double formation_error_m = 0.0;
  double min_barrier_m = 0.0;  // smallest barrier argument (distance to a barrier's zero)
};

class Controller {
 public:
  // Checks the configuration and, for a curve task, traces the curve into kCurveSamples points
  // (its arc length is the along-curve coordinate). An Error names the field at fault.
  Status configure(const ControllerConfig& config);

  // Starts a run from these poses (one per robot): for patrol, each robot's slot on the curve
  // keeps the robots' order along it. Resets the hybrid state to gain set 0.
  void reset(std::span<const Pose> poses, double t_s) noexcept;

  // One control step: fills commands[i] (v, w) for robot i, scaled by F. poses and commands
  // hold config.robots entries. Never allocates.
  const StepInfo& step(double t_s, std::span<const Pose> poses, std::span<Unicycle> commands) noexcept;

  // The pieces, on P points (config.robots of them), for tests and reports. They share the
  // step's scratch: not to be called from another thread while step() runs.
  void field(std::span<const Vec2> p, std::size_t gain_set, std::span<Vec2> u) const noexcept;
  [[nodiscard]] double lyapunov(std::span<const Vec2> p) const noexcept;
  [[nodiscard]] double decrease(std::span<const Vec2> p, std::size_t gain_set) const noexcept;
  [[nodiscard]] double rho(std::span<const Vec2> p) const noexcept;
  // The largest distance from a robot's P to where the task wants it (metres): its target, its
  // slot on the curve, or its offset from the leader (the leader: its distance to the curve).
  [[nodiscard]] double formation_error(std::span<const Vec2> p) const noexcept;
  // Where robot i's P should be now (its target, slot, or offset point).
  [[nodiscard]] Vec2 desired(std::span<const Vec2> p, std::size_t robot) const noexcept;

  [[nodiscard]] const ControllerConfig& config() const noexcept { return config_; }
  [[nodiscard]] std::span<const Gains> gain_sets() const noexcept { return {gains_.data(), gain_count_}; }
  [[nodiscard]] std::size_t gain_set() const noexcept { return active_; }
  [[nodiscard]] std::uint64_t switches() const noexcept { return switches_; }
  [[nodiscard]] const StepInfo& last() const noexcept { return info_; }
  // The traced curve (empty for targets), and its length.
  [[nodiscard]] std::span<const Vec2> curve_points() const noexcept { return {curve_.data(), curve_count_}; }
  [[nodiscard]] double curve_length_m() const noexcept { return curve_length_; }

 private:
  struct Along {
    double s = 0.0;        // arc length of the nearest point
    Vec2 tangent;          // unit, along increasing s
  };
  // Per robot on the curve, for the P points of the latest prepare().
  struct State {
    double s = 0.0;         // along-curve coordinate
    double distance = 0.0;  // signed, to first order (p / |grad p|)
    double spacing = 0.0;   // patrol: arc length ahead of its slot
    Vec2 normal;            // grad p, unit
    Vec2 tangent;           // J normal
  };
  Status trace_curve();
  [[nodiscard]] Along locate(Vec2 p) const noexcept;
  [[nodiscard]] Vec2 curve_at(double s) const noexcept;
  // The per-robot curve quantities the field, V and rho share: computed once per step.
  void prepare(std::span<const Vec2> p) const noexcept;
  void task_field(std::span<const Vec2> p, const Gains& k, std::span<Vec2> u) const noexcept;
  void barrier_field(std::span<const Vec2> p, const Gains& k, std::span<Vec2> u, double* min_h) const noexcept;
  void field_prepared(std::span<const Vec2> p, std::size_t gain_set, std::span<Vec2> u, double* min_h) const noexcept;
  [[nodiscard]] double decrease_prepared(std::span<const Vec2> p, std::span<const Vec2> u) const noexcept;
  [[nodiscard]] double lyapunov_prepared(std::span<const Vec2> p) const noexcept;
  [[nodiscard]] double rho_prepared(std::span<const Vec2> p) const noexcept;
  [[nodiscard]] Vec2 desired_prepared(std::span<const Vec2> p, std::size_t robot) const noexcept;

  ControllerConfig config_;
  std::array<Gains, kMaxGainSets> gains_{};
  std::size_t gain_count_ = 0;
  std::array<Vec2, kCurveSamples> curve_{};
  std::array<double, kCurveSamples> curve_s_{};
  std::size_t curve_count_ = 0;
  double curve_length_ = 0.0;
  std::array<double, kMaxRobots> slot_s_{};   // patrol: each robot's slot offset along the curve
  mutable std::array<State, kMaxRobots> state_{};
  mutable double mean_s_ = 0.0;               // patrol: the team's phase along the curve
  std::size_t active_ = 0;
  double last_switch_s_ = -1e9;
  std::uint64_t switches_ = 0;
  std::array<Vec2, kMaxRobots> p_{};
  std::array<Vec2, kMaxRobots> u_{};
  std::array<Vec2, kMaxRobots> scratch_{};
  StepInfo info_;
  bool configured_ = false;
};

}  // namespace sen3bot::formation
