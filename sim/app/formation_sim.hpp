#pragma once
// The formation examples in lockstep (sen3bot-sim formation, docs/formation/examples.md): N
// whole firmwares, each over its own simulated board (its Pioneer emulator driven by the real
// P2OS driver, its laser in the formation workspace), and the centre's formation service, all
// on one in-process broker. The robots report their pose in VDA 5050 visualization messages;
// the centre steps the centralised controller and sends each robot its velocity. The rig also
// keeps what the report needs, from the ground truth.
//
// The examples are the thesis' (figures 1.20-1.22) scaled by 2.5 in position so that Pioneer-
// sized robots fit: a body circle of 0.3 m about the axle covers the Pioneer's 0.455 x 0.381 m.
#include <cstdint>
#include <cstdio>
#include <memory>
#include <random>
#include <span>
#include <string>
#include <vector>

#include "config.hpp"
#include "firmware.hpp"
#include "sen3bot/formation/controller.hpp"
#include "sen3bot/formation/examples.hpp"
#include "sen3bot/formation/service.hpp"
#include "sen3bot/hal/pubsub.hpp"
#include "sen3bot/sim/sim_board.hpp"
#include "sen3bot/sim/sim_config.hpp"

namespace sen3bot::sim {

inline constexpr double kFormationRadiusM = 0.3;   // the body circle about the axle
inline constexpr double kFormationOffsetM = 0.1;   // L: the axle to the driven point P
inline constexpr double kFormationErrorBoundM = 0.05;
inline constexpr double kFormationTargetToleranceM = 0.05;
inline constexpr hal::Nanos kFormationSliceNs = hal::millis(10);
// Each robot's teammates in its world: round bodies the Pioneer's length across, moved to
// where the teammates truly are this often (the world moves them straight in between).
inline constexpr double kTeammateDiameterM = 0.45;
inline constexpr hal::Nanos kTeammateStepNs = hal::millis(50);
inline constexpr double kFormationSampleS = 0.1;
inline constexpr const char* kFormationCentreId = "formation-centre";

// The workspace inside the walls of config/maps/formation.yaml.
[[nodiscard]] formation::Workspace formation_workspace() noexcept;

struct FormationExample {
  int number = 0;
  const char* name = "";
  const char* description = "";
  formation::ControllerConfig config;      // formation::example(number)'s; the speed limits are the robot's at run time
  std::vector<formation::Pose> starts;     // axle poses, one per robot
  std::vector<formation::Vec2> targets;    // targets: where each robot's P goes (else empty)
  double duration_s = 0;                   // the default run length
};

// Examples 1 (targets, 4 robots), 2 (patrol, 3) and 3 (leader, 3), in that order.
[[nodiscard]] const std::vector<FormationExample>& formation_examples();
// The example numbered `number`, or nullptr.
[[nodiscard]] const FormationExample* formation_example(int number);
// The example's controller configuration with the robots' speed limits.
[[nodiscard]] formation::ControllerConfig formation_controller_config(const FormationExample& example, double v_max_m_s,
                                                                      double w_max_rad_s);
// The serial numbers: f1, f2, ...
[[nodiscard]] std::string formation_serial(std::size_t robot);

// Starts may be driven from: every pair of axles at least 0.8 m apart, every body circle at
// least 0.1 m inside the walls.
[[nodiscard]] bool formation_starts_admissible(std::span<const formation::Pose> starts) noexcept;
// The nominal starts moved by uniform +-0.15 m in x and y and +-0.3 rad, drawn again until
// admissible.
[[nodiscard]] std::vector<formation::Pose> perturbed_starts(const FormationExample& example, std::mt19937_64& rng);

struct FormationRunOptions {
  std::string config_path;   // the robot's base configuration (default config/sim.yaml)
  std::string map_path;      // default config/maps/formation.yaml
  std::uint64_t seed = 1;    // the simulation's noise
  double visualization_period_s = 0.1;
};

// Every kFormationSampleS: the true poses and the centre's last step.
struct FormationSample {
  double t_s = 0;
  std::vector<nav::Pose2D> truth;  // axle poses
  double formation_error_m = 0;    // the controller's, on the true P points
  double centre_error_m = -1;      // the centre's own, on the poses it stepped on (-1: not stepping)
  double scale = 0;                // F of the centre's last step (0 while it stops the team)
  bool switched = false;           // the hybrid rule jumped since the last sample
};

struct FormationMetrics {
  double min_robot_distance_m = 1e9;   // axle to axle, over time and pairs
  std::uint64_t obstacle_contacts = 0;
  std::size_t targets_reached = 0;     // example 1: P within 0.05 m of its target at the end
  double formation_error_m = -1;       // max after convergence (never converged: over the last 10 s)
  double final_formation_error_m = -1;
  double converge_s = -1;              // from then on the error stays <= 0.05 m; -1: never
  double centre_converge_s = -1;       // the same for the centre's own error (its estimates, not the truth)
  std::vector<double> switches_s;
  double min_scale = 1;                // the least F the controller used
  std::uint64_t commands_sent = 0;
  std::uint64_t stale_steps = 0;
  std::uint64_t rejected = 0;
  std::uint64_t safety_stops = 0;      // safety-filter steps that cut a robot's request to zero
  bool passed = false;
  std::vector<std::string> failures;
};

class FormationRig {
 public:
  // Loads the base configuration, builds one board and firmware per start and the centre.
  // Allocates; errors name what failed.
  static Result<std::unique_ptr<FormationRig>> create(const FormationExample& example, std::span<const formation::Pose> starts,
                                                      const FormationRunOptions& options);
  ~FormationRig();
  FormationRig(const FormationRig&) = delete;
  FormationRig& operator=(const FormationRig&) = delete;

  // One kFormationSliceNs: every firmware, then the centre (while it steps), then the records.
  Status advance();
  Status run_for(double seconds);
  // A centre that stops stepping goes silent (its link stays up).
  void set_centre_stepping(bool on) noexcept { centre_stepping_ = on; }
  // Stops the firmwares (their links close cleanly).
  void shutdown();

  [[nodiscard]] double t_s() const noexcept { return hal::to_seconds(now_); }
  [[nodiscard]] hal::Nanos now() const noexcept { return now_; }
  [[nodiscard]] std::size_t robots() const noexcept { return robots_.size(); }
  [[nodiscard]] hal::MemoryBroker& broker() noexcept { return broker_; }
  [[nodiscard]] formation::FormationService& service() noexcept { return *service_; }
  [[nodiscard]] SimBoard& board(std::size_t robot) noexcept { return *robots_[robot].board; }
  [[nodiscard]] firmware::Firmware& firmware(std::size_t robot) noexcept { return *robots_[robot].fw; }
  [[nodiscard]] const nav::Pose2D& truth(std::size_t robot) noexcept;
  [[nodiscard]] const FormationExample& example() const noexcept { return example_; }
  [[nodiscard]] const std::vector<FormationSample>& samples() const noexcept { return samples_; }
  [[nodiscard]] const std::vector<double>& switches_s() const noexcept { return switches_s_; }
  [[nodiscard]] double min_robot_distance_m() const noexcept { return min_distance_m_; }
  // When the centre last sent commands (any kind), s; -1 before.
  [[nodiscard]] double last_command_s() const noexcept { return last_command_s_; }
  [[nodiscard]] const nav::OccupancyMap& map() const noexcept { return robots_.front().fw->map(); }
  // The metrics of the run so far, judged against the example's bounds.
  [[nodiscard]] FormationMetrics metrics() const;

 private:
  struct RobotRun {
    std::string serial;
    firmware::FirmwareConfig config;
    std::unique_ptr<SimBoard> board;
    std::unique_ptr<firmware::Firmware> fw;
  };
  explicit FormationRig(const FormationExample& example);
  void record();

  FormationExample example_;
  hal::MemoryBroker broker_;
  std::FILE* quiet_ = nullptr;
  std::vector<RobotRun> robots_;
  std::unique_ptr<formation::FormationService> service_;
  bool centre_stepping_ = true;
  bool shut_down_ = false;
  hal::Nanos now_ = 0;
  hal::Nanos next_sample_ns_ = 0;
  hal::Nanos next_teammates_ns_ = 0;
  double min_distance_m_ = 1e9;
  double min_scale_ = 1.0;
  double last_scale_ = 0.0;
  bool switched_since_sample_ = false;
  double last_command_s_ = -1;
  std::vector<double> switches_s_;
  std::vector<FormationSample> samples_;
  std::vector<formation::Vec2> p_;  // scratch: the true P points
};

}  // namespace sen3bot::sim
