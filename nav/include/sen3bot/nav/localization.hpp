#pragma once
// Monte Carlo localization (AMCL's design): odometry motion model, likelihood-field laser
// model, KLD-sampling between min and max particles. All buffers come from init(); update()
// allocates nothing.
//
// Laser model, per beam: pz = z_hit * exp(-d^2 / (2 sigma_hit^2)) + z_rand / range_max, with
// d the distance from the beam's end point to the nearest occupied map cell (capped at
// likelihood_max_dist_m), looked up in a field precomputed at init(). Per particle the beams
// combine as a tempered product, (prod pz)^product_exponent (the likelihood-field model of
// Probabilistic Robotics; the exponent < 1 allows for correlated beams), or, as AMCL does,
// as 1 + sum pz^3 (beam_model cubed_sum), which discriminates far less per scan: in our
// simulations it tracked to about 0.3 m where the product holds a few centimetres.
//
// KLD bound (Fox 2003): n = (k - 1) / (2 err) * (1 - 2/(9(k-1)) + sqrt(2/(9(k-1))) * z)^3
// with k the occupied histogram bins (bin_xy_m x bin_xy_m x bin_theta_rad) and z the upper
// standard-normal quantile of the configured confidence p: z = Phi^-1(p) (p = 0.99 gives
// z = 2.326). Note AMCL passes its "pf_z" 0.99 as z itself (about 84 % confidence); we
// convert a real probability.
//
// Updates fire when the odometry moved update_min_d_m or turned update_min_a_rad since the
// last one, or update_max_interval_s passed (0: never by time), on every scan while the
// estimate is lost or the last update fit far worse than usual, and when a scan checked every
// recovery_update_interval_s (standing still) fits that badly. Between updates pose() adds the odometry moved since the last update to the
// filter's estimate.
//
// Recovery (Augmented MCL, as AMCL): w_slow and w_fast follow the mean measurement likelihood
// (the mean pz of every particle's beams) with rates recovery_alpha_slow and
// recovery_alpha_fast (the plain mean while fewer than 1/alpha updates were seen); each resampled particle is replaced, with probability
// max(0, 1 - w_fast / w_slow), by one drawn uniformly over the map's free cells (listed at
// init()). A sudden drop in likelihood (a kidnapped robot, a filter settled on a look-alike
// place) thus spreads fresh hypotheses over the map until the likelihood recovers.
#include <algorithm>
#include <array>
#include <cstdint>
#include <memory_resource>
#include <random>
#include <span>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/msg/navigation.hpp"
#include "sen3bot/nav/geometry.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/nav/projected_scan.hpp"
#include "sen3bot/nav/scan.hpp"

namespace sen3bot::nav {

enum class MclBeamModel : std::uint8_t { product, cubed_sum };

struct MclConfig {
  std::size_t min_particles = 500;
  std::size_t max_particles = 2000;
  double kld_err = 0.05;
  double kld_confidence = 0.99;
  double bin_xy_m = 0.5;
  double bin_theta_rad = 10.0 * 3.14159265358979323846 / 180.0;
  std::size_t max_beams = 60;
  double sigma_hit_m = 0.2;
  double z_hit = 0.5;
  double z_rand = 0.5;
  double likelihood_max_dist_m = 2.0;
  MclBeamModel beam_model = MclBeamModel::product;
  double product_exponent = 0.5;
  int occupied_threshold = 65;  // map occupancy (0..100) counted as an obstacle
  // Beam skipping (AMCL's do_beamskip): a beam that ends farther than beam_skip_distance_m
  // from every mapped obstacle for all but a beam_skip_threshold share of the particles sees
  // something the map does not have (a box, a person) and is left out for every particle.
  // When more than beam_skip_error_threshold of the beams would go, none is skipped (then the
  // filter, not the world, is probably wrong).
  bool beam_skip = true;
  double beam_skip_distance_m = 0.5;
  double beam_skip_threshold = 0.3;
  double beam_skip_error_threshold = 0.9;
  // Odometry noise (AMCL's alpha1..alpha4): rotation from rotation, rotation from
  // translation, translation from translation, translation from rotation.
  double alpha1 = 0.2;
  double alpha2 = 0.2;
  double alpha3 = 0.2;
  double alpha4 = 0.2;
  double update_min_d_m = 0.25;
  double update_min_a_rad = 0.2;
  double update_max_interval_s = 0.0;
  // Standing still, every this often the scan is checked against the particles; a likelihood
  // well below w_slow starts an update, so a robot that stopped (or was carried off standing)
  // still notices and relocalises (0: no check).
  double recovery_update_interval_s = 0.5;
  int resample_interval = 1;
  Pose2D initial_pose;                 // map frame
  double initial_std_xy_m = 0.25;
  double initial_std_theta_rad = 0.2;
  double lost_std_xy_m = 1.0;          // estimate reported lost above this position spread
  // Random-particle injection; 0 for either rate turns it off. Needs 0 < slow < fast <= 1.
  // Off by default, as in AMCL: on a loaded computer in real time it has perturbed a good
  // estimate (docs/navigation.md); 0.001 / 0.1 are the usual rates when a site needs it.
  double recovery_alpha_slow = 0.0;
  double recovery_alpha_fast = 0.0;
  // An injected particle takes, of this many evenly spaced headings, the one the last scan
  // fits best (1: a uniformly random heading, as AMCL).
  std::size_t injection_headings = 36;
  // Also reported lost while w_fast < lost_likelihood_ratio * w_slow (0: never by likelihood).
  double lost_likelihood_ratio = 0.5;
  SensorMount laser_mount;            // LocalizationTask projects scans with it
  std::uint64_t seed = 1;
};

using msg::PoseEstimate;

// The standard-normal quantile: Phi^-1(p) for 0 < p < 1 (Acklam's rational approximation,
// relative error below 1.2e-9).
double normal_quantile(double p) noexcept;
// The KLD-sampling particle count for k occupied bins.
std::size_t kld_particle_count(std::size_t k, double err, double z, std::size_t min_count, std::size_t max_count) noexcept;

class MonteCarloLocalization {
 public:
  // The map is read at init() (likelihood field); it need not outlive the filter.
  Status init(const MclConfig& config, const OccupancyMap& map, std::pmr::memory_resource& resource);
  static std::size_t storage_bytes(const MclConfig& config, const OccupancyMap& map) noexcept;

  // Particles around a pose (Gaussian with the given spreads).
  void set_pose(const Pose2D& pose, double std_xy_m, double std_theta_rad) noexcept;
  // Global initialisation: max_particles spread uniformly over free cells.
  void global_initialize() noexcept;

  // Feeds odometry and (optionally) a scan. Returns true when a filter update ran.
  bool update(const Odometry& odom, const ProjectedScan* scan) noexcept;
  // The same for a scan taken when odometry read odom_at_scan (an older pose than odom's, from
  // an OdometryHistory): the update happens at the scan's pose, and estimate() carries the
  // result forward to odom.
  bool update(const Odometry& odom, const ProjectedScan* scan, const Pose2D& odom_at_scan) noexcept;
  // The filter pose carried to an odometry pose (estimate() does this for the newest one).
  [[nodiscard]] Pose2D pose_at_odometry(const Pose2D& odom_pose) const noexcept;

  [[nodiscard]] PoseEstimate estimate() const noexcept;
  [[nodiscard]] std::size_t particle_count() const noexcept { return count_; }
  [[nodiscard]] double z_quantile() const noexcept { return z_; }
  // The laser model's pz for a beam ending at (x, y) in the map frame.
  [[nodiscard]] float likelihood_at(double x_m, double y_m) const noexcept { return likelihood(x_m, y_m); }
  [[nodiscard]] bool recovery_enabled() const noexcept {
    return config_.recovery_alpha_slow > 0.0 && config_.recovery_alpha_fast > 0.0;
  }
  // Random particles injected at the last resampling.
  [[nodiscard]] std::size_t injected() const noexcept { return injected_; }
  [[nodiscard]] std::size_t free_cell_count() const noexcept { return free_count_; }

 private:
  struct Particle {
    double x_m;
    double y_m;
    double theta_rad;
    double weight;
  };
  void motion_update(const Pose2D& from, const Pose2D& to) noexcept;
  void sensor_update(const ProjectedScan& scan) noexcept;
  void resample() noexcept;
  void compute_estimate() noexcept;
  void reset_likelihood_averages() noexcept;
  [[nodiscard]] Particle random_free_particle(bool fit_heading) noexcept;
  [[nodiscard]] float likelihood(double x_m, double y_m) const noexcept;
  [[nodiscard]] float log_field(double x_m, double y_m) const noexcept;
  [[nodiscard]] bool solid(double x_m, double y_m) const noexcept;  // occupied or off the map
  // The mean pz of a scan's beams over the particles, without updating anything.
  [[nodiscard]] double mean_likelihood(const ProjectedScan& scan) const noexcept;
  static constexpr std::size_t kMaxBeamEnds = 512;
  // The end points of up to max_beams valid beams spread over the scan, in the robot frame.
  std::size_t beam_ends(const ProjectedScan& scan, double (&bx)[kMaxBeamEnds], double (&by)[kMaxBeamEnds]) const noexcept;
  // The particles that were resampled, not just injected (those sit at the end, unweighed).
  [[nodiscard]] std::size_t believed_count() const noexcept { return count_ - std::min(injected_, count_ - 1); }

  MclConfig config_;
  double z_ = 2.326;
  // Likelihood field over the map grid.
  GridGeometry grid_;
  float pz_far_ = 0.0f;
  float pz_skip_ = 0.0f;  // likelihood at beam_skip_distance_m
  float log_pz_far_ = 0.0f;
  std::span<float> field_;
  std::span<float> log_field_;
  std::span<std::uint32_t> free_cells_;
  std::span<std::uint8_t> solid_;  // occupied cells: no robot stands there
  std::size_t free_count_ = 0;
  // Particles.
  std::span<Particle> particles_;
  std::span<Particle> next_;
  std::span<double> cumulative_;
  std::span<std::uint64_t> bins_;  // open-addressing set of occupied histogram bins
  std::size_t count_ = 0;
  std::mt19937_64 rng_;
  // Odometry bookkeeping.
  bool have_odom_ = false;
  Pose2D odom_at_update_;
  Pose2D odom_latest_;
  hal::Nanos last_update_ns_ = 0;
  hal::Nanos last_check_ns_ = 0;
  int updates_since_resample_ = 0;
  // Recovery: running averages of the mean measurement likelihood.
  double w_slow_ = 0.0;
  double w_fast_ = 0.0;
  std::uint64_t average_count_ = 0;
  static constexpr std::size_t kProbeBeams = 16;
  std::array<double, kProbeBeams> probe_x_{};  // robot frame, from the last scan
  std::array<double, kProbeBeams> probe_y_{};
  std::size_t probe_count_ = 0;
  std::size_t injected_ = 0;
  PoseEstimate estimate_;
};

}  // namespace sen3bot::nav
