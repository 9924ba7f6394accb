#include "sen3bot/nav/localization.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <numbers>

#include "sen3bot/nav/arena.hpp"
#include "sen3bot/nav/distance_transform.hpp"

namespace sen3bot::nav {

namespace {
// A scan whose mean pz is this far below w_slow fits far worse than usual (tracking, it varies
// by about 10 % from scan to scan): it starts updates without waiting for motion.
constexpr double kLowLikelihood = 0.8;
}  // namespace

double normal_quantile(double p) noexcept {
  // Acklam's algorithm: rational approximations in a central and two tail regions.
  static constexpr double a[] = {-3.969683028665376e+01, 2.209460984245205e+02, -2.759285104469687e+02,
                                 1.383577518672690e+02, -3.066479806614716e+01, 2.506628277459239e+00};
  static constexpr double b[] = {-5.447609879822406e+01, 1.615858368580409e+02, -1.556989798598866e+02,
                                 6.680131188771972e+01, -1.328068155288572e+01};
  static constexpr double c[] = {-7.784894002430293e-03, -3.223964580411365e-01, -2.400758277161838e+00,
                                 -2.549732539343734e+00, 4.374664141464968e+00, 2.938163982698783e+00};
  static constexpr double d[] = {7.784695709041462e-03, 3.224671290700398e-01, 2.445134137142996e+00,
                                 3.754408661907416e+00};
  constexpr double low = 0.02425;
  if (!(p > 0.0 && p < 1.0)) return p <= 0.0 ? -std::numeric_limits<double>::infinity() : std::numeric_limits<double>::infinity();
  if (p < low) {
    const double q = std::sqrt(-2.0 * std::log(p));
    return (((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
           ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
  }
  if (p > 1.0 - low) {
    const double q = std::sqrt(-2.0 * std::log(1.0 - p));
    return -(((((c[0] * q + c[1]) * q + c[2]) * q + c[3]) * q + c[4]) * q + c[5]) /
           ((((d[0] * q + d[1]) * q + d[2]) * q + d[3]) * q + 1.0);
  }
  const double q = p - 0.5;
  const double r = q * q;
  return (((((a[0] * r + a[1]) * r + a[2]) * r + a[3]) * r + a[4]) * r + a[5]) * q /
         (((((b[0] * r + b[1]) * r + b[2]) * r + b[3]) * r + b[4]) * r + 1.0);
}

std::size_t kld_particle_count(std::size_t k, double err, double z, std::size_t min_count, std::size_t max_count) noexcept {
  if (k <= 1) return min_count;
  const double km1 = static_cast<double>(k - 1);
  const double b = 2.0 / (9.0 * km1);
  const double x = 1.0 - b + std::sqrt(b) * z;
  const double n = std::ceil(km1 / (2.0 * err) * x * x * x);
  return std::clamp(static_cast<std::size_t>(n), min_count, max_count);
}

std::size_t MonteCarloLocalization::storage_bytes(const MclConfig& c, const OccupancyMap& map) noexcept {
  const std::size_t cells = map.cell_count();
  const auto line = static_cast<std::size_t>(std::max(map.width(), map.height()));
  return cells * (sizeof(float) * 3 + sizeof(std::uint32_t) + sizeof(std::uint8_t)) + DistanceTransform::storage_bytes(line) +
         c.max_particles * (2 * sizeof(Particle) + sizeof(double) + 2 * sizeof(std::uint64_t)) + 1024;
}

Status MonteCarloLocalization::init(const MclConfig& config, const OccupancyMap& map, std::pmr::memory_resource& resource) {
  if (config.min_particles == 0 || config.max_particles < config.min_particles || !(config.kld_err > 0.0) ||
      !(config.kld_confidence > 0.0 && config.kld_confidence < 1.0) || config.max_beams == 0 ||
      !(config.sigma_hit_m > 0.0) || map.cell_count() == 0) {
    return Error::format(Errc::config,
                         "mcl: need 0 < min_particles <= max_particles, kld_err > 0, 0 < kld_confidence < 1, "
                         "max_beams > 0, sigma_hit_m > 0 and a map");
  }
  const bool alphas_ok = config.recovery_alpha_slow >= 0.0 && config.recovery_alpha_fast >= 0.0 &&
                         config.recovery_alpha_slow <= 1.0 && config.recovery_alpha_fast <= 1.0;
  const bool recovery = config.recovery_alpha_slow > 0.0 && config.recovery_alpha_fast > 0.0;
  if (!alphas_ok || (recovery && !(config.recovery_alpha_slow < config.recovery_alpha_fast))) {
    return Error::format(Errc::config,
                         "mcl: recovery_alpha_slow %g and recovery_alpha_fast %g must lie in [0, 1] with slow < fast "
                         "(0 for either turns recovery off)",
                         config.recovery_alpha_slow, config.recovery_alpha_fast);
  }
  if (config.injection_headings == 0 || config.injection_headings > 360) {
    return Error::format(Errc::config, "mcl: injection_headings %zu must lie in 1..360", config.injection_headings);
  }
  if (!(config.lost_likelihood_ratio >= 0.0 && config.lost_likelihood_ratio < 1.0)) {
    return Error::format(Errc::config, "mcl: lost_likelihood_ratio %g must lie in [0, 1)", config.lost_likelihood_ratio);
  }
  config_ = config;
  z_ = normal_quantile(config.kld_confidence);
  grid_ = map.geometry();
  const int width = grid_.width();
  const int height = grid_.height();
  rng_.seed(config.seed);
  return guarded("mcl", [&]() -> Status {
    const std::size_t cells = map.cell_count();
    field_ = allocate_array<float>(resource, cells);
    log_field_ = allocate_array<float>(resource, cells);
    auto squared = allocate_array<float>(resource, cells);
    free_cells_ = allocate_array<std::uint32_t>(resource, cells);
    solid_ = allocate_array<std::uint8_t>(resource, cells);
    DistanceTransform transform;
    if (Status s = transform.init(static_cast<std::size_t>(std::max(width, height)), resource); !s) return s;
    particles_ = allocate_array<Particle>(resource, config.max_particles);
    next_ = allocate_array<Particle>(resource, config.max_particles);
    cumulative_ = allocate_array<double>(resource, config.max_particles);
    bins_ = allocate_array<std::uint64_t>(resource, 2 * config.max_particles);

    constexpr float kInf = std::numeric_limits<float>::infinity();
    free_count_ = 0;
    for (std::size_t i = 0; i < cells; ++i) squared[i] = map.cells()[i] >= config.occupied_threshold ? 0.0f : kInf;
    transform.transform(squared, width, height);
    const double two_sigma2 = 2.0 * config.sigma_hit_m * config.sigma_hit_m;
    const double range_max = 10.0;  // LMS200 default range: only scales the z_rand floor
    const double max_d = config.likelihood_max_dist_m;
    pz_far_ = static_cast<float>(config.z_hit * std::exp(-max_d * max_d / two_sigma2) + config.z_rand / range_max);
    log_pz_far_ = std::log(pz_far_);
    const double skip_d = std::min(max_d, config.beam_skip_distance_m);
    pz_skip_ = static_cast<float>(config.z_hit * std::exp(-skip_d * skip_d / two_sigma2) + config.z_rand / range_max);
    const double resolution_m = grid_.resolution_m();
    for (int r = 0; r < height; ++r) {
      const std::size_t row = static_cast<std::size_t>(r) * static_cast<std::size_t>(width);
      for (int c = 0; c < width; ++c) {
        const double dist = std::min(max_d, std::sqrt(static_cast<double>(squared[row + c])) * resolution_m);
        field_[row + c] = static_cast<float>(config.z_hit * std::exp(-dist * dist / two_sigma2) + config.z_rand / range_max);
        // Distance from the obstacle cell's edge rather than its centre, for the interpolation.
        const double edge = std::max(0.0, dist - 0.5 * resolution_m);
        log_field_[row + c] = static_cast<float>(std::log(config.z_hit * std::exp(-edge * edge / two_sigma2) + config.z_rand / range_max));
        const int occ = map.at(c, r);
        solid_[row + c] = occ >= config.occupied_threshold ? 1 : 0;
        if (occ >= 0 && occ < config.occupied_threshold / 2) free_cells_[free_count_++] = static_cast<std::uint32_t>(row + c);
      }
    }
    set_pose(config.initial_pose, config.initial_std_xy_m, config.initial_std_theta_rad);
    return Status::success();
  });
}

float MonteCarloLocalization::log_field(double x_m, double y_m) const noexcept {
  // Bilinear between cell centres: a wall face then scores as well as the wall cell, so the
  // estimate does not snap half a cell into walls.
  double gx = 0.0;
  double gy = 0.0;
  grid_.world_to_grid(x_m, y_m, gx, gy);
  gx -= 0.5;
  gy -= 0.5;
  const int width = grid_.width();
  if (!(gx >= 0.0 && gy >= 0.0 && gx < width - 1 && gy < grid_.height() - 1)) return log_pz_far_;
  const auto c = static_cast<std::size_t>(gx);
  const auto r = static_cast<std::size_t>(gy);
  const auto fx = static_cast<float>(gx - static_cast<double>(c));
  const auto fy = static_cast<float>(gy - static_cast<double>(r));
  const auto w = static_cast<std::size_t>(width);
  const std::size_t i = r * w + c;
  const float top = log_field_[i] + fx * (log_field_[i + 1] - log_field_[i]);
  const float bottom = log_field_[i + w] + fx * (log_field_[i + w + 1] - log_field_[i + w]);
  return top + fy * (bottom - top);
}

bool MonteCarloLocalization::solid(double x_m, double y_m) const noexcept {
  int col = 0;
  int row = 0;
  if (!grid_.world_to_cell(x_m, y_m, col, row)) return true;
  return solid_[grid_.index(col, row)] != 0;
}

float MonteCarloLocalization::likelihood(double x_m, double y_m) const noexcept {
  double gx = 0.0;
  double gy = 0.0;
  grid_.world_to_grid(x_m, y_m, gx, gy);
  if (!(gx >= 0.0 && gy >= 0.0 && gx < grid_.width() && gy < grid_.height())) return pz_far_;
  return field_[static_cast<std::size_t>(gy) * static_cast<std::size_t>(grid_.width()) + static_cast<std::size_t>(gx)];
}

void MonteCarloLocalization::set_pose(const Pose2D& pose, double std_xy_m, double std_theta_rad) noexcept {
  std::normal_distribution<double> n01(0.0, 1.0);
  count_ = config_.max_particles;
  // A confident start needs no more than the minimum; a vague one gets all the particles.
  if (std_xy_m <= config_.bin_xy_m) count_ = config_.min_particles;
  const double w = 1.0 / static_cast<double>(count_);
  for (std::size_t i = 0; i < count_; ++i) {
    particles_[i] = {pose.x_m + std_xy_m * n01(rng_), pose.y_m + std_xy_m * n01(rng_),
                     normalize_angle(pose.theta_rad + std_theta_rad * n01(rng_)), w};
  }
  updates_since_resample_ = 0;
  reset_likelihood_averages();
  compute_estimate();
  estimate_.valid = true;
}

MonteCarloLocalization::Particle MonteCarloLocalization::random_free_particle(bool fit_heading) noexcept {
  std::uniform_int_distribution<std::size_t> pick(0, free_count_ - 1);
  std::uniform_real_distribution<double> unit(0.0, 1.0);
  const std::uint32_t cell = free_cells_[pick(rng_)];
  const auto width = static_cast<std::uint32_t>(grid_.width());
  double x = 0.0;
  double y = 0.0;
  grid_.grid_to_world(static_cast<double>(cell % width) + unit(rng_), static_cast<double>(cell / width) + unit(rng_), x, y);
  double theta = (2.0 * unit(rng_) - 1.0) * std::numbers::pi;
  if (fit_heading && probe_count_ > 0 && config_.injection_headings > 1) {
    // Of injection_headings evenly spaced headings, the one the last scan fits best: a random
    // pose then needs only its position near the truth, not its heading too.
    const double step = 2.0 * std::numbers::pi / static_cast<double>(config_.injection_headings);
    double best = -1.0;
    double best_theta = theta;
    for (std::size_t h = 0; h < config_.injection_headings; ++h) {
      const double t = theta + step * static_cast<double>(h);
      const double c = std::cos(t);
      const double s = std::sin(t);
      double sum = 0.0;
      for (std::size_t k = 0; k < probe_count_; ++k)
        sum += likelihood(x + c * probe_x_[k] - s * probe_y_[k], y + s * probe_x_[k] + c * probe_y_[k]);
      if (sum > best) {
        best = sum;
        best_theta = t;
      }
    }
    theta = normalize_angle(best_theta);
  }
  return {x, y, theta, 0.0};
}

void MonteCarloLocalization::reset_likelihood_averages() noexcept {
  w_slow_ = 0.0;
  w_fast_ = 0.0;
  average_count_ = 0;
  probe_count_ = 0;
  injected_ = 0;
  estimate_.relocalizing = false;
  estimate_.likelihood_slow = 0.0f;
  estimate_.likelihood_fast = 0.0f;
  estimate_.injection = 0.0f;
}

void MonteCarloLocalization::global_initialize() noexcept {
  if (free_count_ == 0) return;
  count_ = config_.max_particles;
  const double w = 1.0 / static_cast<double>(count_);
  for (std::size_t i = 0; i < count_; ++i) {
    particles_[i] = random_free_particle(false);
    particles_[i].weight = w;
  }
  updates_since_resample_ = 0;
  reset_likelihood_averages();
  compute_estimate();
  estimate_.valid = true;
}

void MonteCarloLocalization::motion_update(const Pose2D& from, const Pose2D& to) noexcept {
  // Probabilistic Robotics' sample_motion_model_odometry, as AMCL's differential model.
  const double dx = to.x_m - from.x_m;
  const double dy = to.y_m - from.y_m;
  const double trans = std::hypot(dx, dy);
  const double rot1 = trans < 0.01 ? 0.0 : normalize_angle(std::atan2(dy, dx) - from.theta_rad);
  const double rot2 = normalize_angle(to.theta_rad - from.theta_rad - rot1);
  // Driving backwards: measure the first rotation from the reversed heading.
  const double rot1_noise = std::min(std::abs(rot1), std::abs(normalize_angle(rot1 - std::numbers::pi)));
  const double rot2_noise = std::min(std::abs(rot2), std::abs(normalize_angle(rot2 - std::numbers::pi)));
  const double sd_rot1 = std::sqrt(config_.alpha1 * rot1_noise * rot1_noise + config_.alpha2 * trans * trans);
  const double sd_trans = std::sqrt(config_.alpha3 * trans * trans + config_.alpha4 * (rot1_noise * rot1_noise + rot2_noise * rot2_noise));
  const double sd_rot2 = std::sqrt(config_.alpha1 * rot2_noise * rot2_noise + config_.alpha2 * trans * trans);
  std::normal_distribution<double> n01(0.0, 1.0);
  for (std::size_t i = 0; i < count_; ++i) {
    Particle& p = particles_[i];
    const double r1 = rot1 - sd_rot1 * n01(rng_);
    const double t = trans - sd_trans * n01(rng_);
    const double r2 = rot2 - sd_rot2 * n01(rng_);
    p.x_m += t * std::cos(p.theta_rad + r1);
    p.y_m += t * std::sin(p.theta_rad + r1);
    p.theta_rad = normalize_angle(p.theta_rad + r1 + r2);
  }
}

std::size_t MonteCarloLocalization::beam_ends(const ProjectedScan& scan, double (&bx)[kMaxBeamEnds],
                                              double (&by)[kMaxBeamEnds]) const noexcept {
  const std::size_t beams = scan.size();
  if (beams == 0) return 0;
  const std::size_t used = std::min(beams, config_.max_beams);
  const double step = used > 1 ? static_cast<double>(beams - 1) / static_cast<double>(used - 1) : 1.0;
  std::size_t n = 0;
  for (std::size_t k = 0; k < used && n < kMaxBeamEnds; ++k) {
    const auto i = static_cast<std::size_t>(std::lround(static_cast<double>(k) * step));
    if (!scan.valid(i)) continue;
    bx[n] = scan.end(i).x_m;
    by[n] = scan.end(i).y_m;
    ++n;
  }
  return n;
}

double MonteCarloLocalization::mean_likelihood(const ProjectedScan& scan) const noexcept {
  double bx[kMaxBeamEnds];
  double by[kMaxBeamEnds];
  const std::size_t n = beam_ends(scan, bx, by);
  if (n == 0 || count_ == 0) return 0.0;
  const std::size_t believed = believed_count();
  double sum = 0.0;
  for (std::size_t i = 0; i < believed; ++i) {
    const Particle& p = particles_[i];
    const double c = std::cos(p.theta_rad);
    const double s = std::sin(p.theta_rad);
    for (std::size_t k = 0; k < n; ++k) sum += likelihood(p.x_m + c * bx[k] - s * by[k], p.y_m + s * bx[k] + c * by[k]);
  }
  return sum / (static_cast<double>(n) * static_cast<double>(believed));
}

void MonteCarloLocalization::sensor_update(const ProjectedScan& scan) noexcept {
  // Beam end points in the robot frame, computed once per scan.
  double bx[kMaxBeamEnds];
  double by[kMaxBeamEnds];
  std::size_t n = beam_ends(scan, bx, by);
  if (n == 0) return;
  // A few beams spread over the scan, for the headings of injected particles.
  probe_count_ = std::min(n, kProbeBeams);
  for (std::size_t k = 0; k < probe_count_; ++k) {
    const std::size_t i = probe_count_ > 1 ? k * (n - 1) / (probe_count_ - 1) : 0;
    probe_x_[k] = bx[i];
    probe_y_[k] = by[i];
  }
  const bool recovery = recovery_enabled();
  std::uint32_t near[kMaxBeamEnds] = {};
  double beam_pz[kMaxBeamEnds] = {};  // per beam, summed over the believed particles
  std::size_t believed = count_;
  if ((config_.beam_skip || recovery) && count_ > 0) {
    // Per beam, how many particles put its end point near a mapped obstacle, and its pz summed
    // over the particles. The particles injected last time sit at the end; they only probe the
    // map and are left out of the sums, which would otherwise sink with every injection.
    believed = believed_count();
    for (std::size_t i = 0; i < count_; ++i) {
      const Particle& p = particles_[i];
      const double c = std::cos(p.theta_rad);
      const double s = std::sin(p.theta_rad);
      for (std::size_t k = 0; k < n; ++k) {
        const float pz = likelihood(p.x_m + c * bx[k] - s * by[k], p.y_m + s * bx[k] + c * by[k]);
        if (pz >= pz_skip_) ++near[k];
        if (i < believed) beam_pz[k] += pz;
      }
    }
  }
  const std::size_t all_beams = n;
  if (config_.beam_skip && count_ > 0) {
    const double needed = config_.beam_skip_threshold * static_cast<double>(count_);
    std::size_t kept = 0;
    for (std::size_t k = 0; k < n; ++k) kept += static_cast<double>(near[k]) >= needed ? 1 : 0;
    if (static_cast<double>(n - kept) <= config_.beam_skip_error_threshold * static_cast<double>(n) && kept > 0) {
      std::size_t m = 0;
      for (std::size_t k = 0; k < n; ++k) {
        if (static_cast<double>(near[k]) < needed) continue;
        bx[m] = bx[k];
        by[m] = by[k];
        ++m;
      }
      n = m;
    }
  }
  if ((config_.beam_skip || recovery) && count_ > 0) {
    // The mean pz over every beam, skipped ones too: beam skipping would hide most of a
    // kidnapping (the beams that miss are skipped as unmapped obstacles).
    double pz_sum = 0.0;
    for (std::size_t k = 0; k < all_beams; ++k) pz_sum += beam_pz[k];
    const double mean_pz = pz_sum / (static_cast<double>(believed) * static_cast<double>(all_beams));
    estimate_.likelihood = static_cast<float>(mean_pz);
    if (recovery) {
      // Until 1/alpha updates have been seen an average is the plain mean so far, so the first
      // update (often from a vague initial cloud) does not set the reference for a thousand more.
      ++average_count_;
      const double first = 1.0 / static_cast<double>(average_count_);
      w_slow_ += std::max(config_.recovery_alpha_slow, first) * (mean_pz - w_slow_);
      w_fast_ += std::max(config_.recovery_alpha_fast, first) * (mean_pz - w_fast_);
      estimate_.likelihood_slow = static_cast<float>(w_slow_);
      estimate_.likelihood_fast = static_cast<float>(w_fast_);
      estimate_.relocalizing = config_.lost_likelihood_ratio > 0.0 && w_fast_ < config_.lost_likelihood_ratio * w_slow_;
    }
  }
  // Log-likelihood per particle first, then weights relative to the best one, so the
  // product over beams cannot underflow.
  double best = -std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < count_; ++i) {
    Particle& p = particles_[i];
    const double c = std::cos(p.theta_rad);
    const double s = std::sin(p.theta_rad);
    double score = 0.0;
    if (config_.beam_model == MclBeamModel::cubed_sum) {
      double sum = 1.0;
      for (std::size_t k = 0; k < n; ++k) {
        const double pz = likelihood(p.x_m + c * bx[k] - s * by[k], p.y_m + s * bx[k] + c * by[k]);
        sum += pz * pz * pz;
      }
      score = std::log(sum);
    } else {
      for (std::size_t k = 0; k < n; ++k) {
        score += log_field(p.x_m + c * bx[k] - s * by[k], p.y_m + s * bx[k] + c * by[k]);
      }
      score *= config_.product_exponent;
    }
    // A robot whose centre or laser sits inside a wall is impossible, however well its beams
    // (ending inside that wall's solid interior) score.
    const double lx = config_.laser_mount.x_m;
    const double ly = config_.laser_mount.y_m;
    if (solid(p.x_m, p.y_m) || solid(p.x_m + c * lx - s * ly, p.y_m + s * lx + c * ly))
      score = -std::numeric_limits<double>::infinity();
    cumulative_[i] = score;  // scratch until resampling
    best = std::max(best, score);
  }
  if (!(best > -std::numeric_limits<double>::infinity())) {
    for (std::size_t i = 0; i < count_; ++i) particles_[i].weight = 1.0 / static_cast<double>(count_);
    return;
  }
  double total = 0.0;
  for (std::size_t i = 0; i < count_; ++i) {
    Particle& p = particles_[i];
    p.weight *= std::exp(cumulative_[i] - best);
    total += p.weight;
  }
  if (!(total > 0.0)) {
    for (std::size_t i = 0; i < count_; ++i) particles_[i].weight = 1.0 / static_cast<double>(count_);
    return;
  }
  for (std::size_t i = 0; i < count_; ++i) particles_[i].weight /= total;
}

void MonteCarloLocalization::resample() noexcept {
  double acc = 0.0;
  for (std::size_t i = 0; i < count_; ++i) {
    acc += particles_[i].weight;
    cumulative_[i] = acc;
  }
  std::fill(bins_.begin(), bins_.end(), std::uint64_t{0});
  const std::size_t table = bins_.size();
  std::size_t occupied = 0;
  std::size_t target = config_.min_particles;
  std::uniform_real_distribution<double> unit(0.0, acc);
  std::uniform_real_distribution<double> coin(0.0, 1.0);
  // The share of random particles; random ones count in the KLD bins, as in AMCL, so a
  // dropping likelihood also raises the particle count.
  const double inject = recovery_enabled() && w_slow_ > 0.0 && free_count_ > 0 ? std::max(0.0, 1.0 - w_fast_ / w_slow_) : 0.0;
  injected_ = 0;
  std::size_t drawn = 0;
  while (drawn < config_.max_particles && (drawn < target || drawn < config_.min_particles)) {
    // Resampled particles fill next_ from the front, random ones from the back.
    Particle* slot_for = nullptr;
    if (inject > 0.0 && coin(rng_) < inject) {
      slot_for = &next_[next_.size() - 1 - injected_];
      *slot_for = random_free_particle(true);
      ++injected_;
    } else {
      const double u = unit(rng_);
      const auto it = std::lower_bound(cumulative_.begin(), cumulative_.begin() + static_cast<std::ptrdiff_t>(count_), u);
      const std::size_t pick = std::min<std::size_t>(static_cast<std::size_t>(it - cumulative_.begin()), count_ - 1);
      slot_for = &next_[drawn - injected_];
      *slot_for = particles_[pick];
    }
    ++drawn;
    // The histogram bin of the drawn particle; a new bin raises the KLD target.
    const auto bx = static_cast<std::int64_t>(std::floor(slot_for->x_m / config_.bin_xy_m));
    const auto by = static_cast<std::int64_t>(std::floor(slot_for->y_m / config_.bin_xy_m));
    const auto bt = static_cast<std::int64_t>(std::floor(slot_for->theta_rad / config_.bin_theta_rad));
    const std::uint64_t key = ((static_cast<std::uint64_t>(bx) & 0xFFFFFu) << 40) |
                              ((static_cast<std::uint64_t>(by) & 0xFFFFFu) << 20) |
                              (static_cast<std::uint64_t>(bt) & 0xFFFFFu) | (std::uint64_t{1} << 63);
    std::size_t slot = static_cast<std::size_t>((key * 0x9E3779B97F4A7C15ull) >> 33) % table;
    while (bins_[slot] != 0 && bins_[slot] != key) slot = (slot + 1) % table;
    if (bins_[slot] == 0) {
      bins_[slot] = key;
      ++occupied;
      target = kld_particle_count(occupied, config_.kld_err, z_, config_.min_particles, config_.max_particles);
    }
  }
  count_ = drawn;
  const double w = 1.0 / static_cast<double>(count_);
  const std::size_t resampled = count_ - injected_;
  for (std::size_t i = 0; i < count_; ++i) {
    particles_[i] = i < resampled ? next_[i] : next_[next_.size() - 1 - (i - resampled)];
    particles_[i].weight = w;
  }
  estimate_.particles = static_cast<std::uint32_t>(count_);
  estimate_.injection = static_cast<float>(static_cast<double>(injected_) / static_cast<double>(count_));
}

void MonteCarloLocalization::compute_estimate() noexcept {
  // The particles just injected have not been weighed yet: the estimate leaves them out.
  const std::size_t count = believed_count();
  double wsum = 0.0;
  double mx = 0.0;
  double my = 0.0;
  double mc = 0.0;
  double ms = 0.0;
  for (std::size_t i = 0; i < count; ++i) {
    const Particle& p = particles_[i];
    wsum += p.weight;
    mx += p.weight * p.x_m;
    my += p.weight * p.y_m;
    mc += p.weight * std::cos(p.theta_rad);
    ms += p.weight * std::sin(p.theta_rad);
  }
  if (!(wsum > 0.0)) return;
  mx /= wsum;
  my /= wsum;
  const double mean_theta = std::atan2(ms, mc);
  double xx = 0.0;
  double xy = 0.0;
  double yy = 0.0;
  double tt = 0.0;
  for (std::size_t i = 0; i < count; ++i) {
    const Particle& p = particles_[i];
    const double dx = p.x_m - mx;
    const double dy = p.y_m - my;
    const double dt = normalize_angle(p.theta_rad - mean_theta);
    xx += p.weight * dx * dx;
    xy += p.weight * dx * dy;
    yy += p.weight * dy * dy;
    tt += p.weight * dt * dt;
  }
  estimate_.pose = {mx, my, mean_theta};
  estimate_.cov_xx = xx / wsum;
  estimate_.cov_xy = xy / wsum;
  estimate_.cov_yy = yy / wsum;
  estimate_.cov_tt = tt / wsum;
  estimate_.particles = static_cast<std::uint32_t>(count_);
  estimate_.lost = std::sqrt(std::max(estimate_.cov_xx, estimate_.cov_yy)) > config_.lost_std_xy_m || estimate_.relocalizing;
}

bool MonteCarloLocalization::update(const Odometry& odom, const ProjectedScan* scan) noexcept {
  return update(odom, scan, Pose2D{odom.x_m, odom.y_m, odom.theta_rad});
}

bool MonteCarloLocalization::update(const Odometry& odom, const ProjectedScan* scan, const Pose2D& odom_at_scan) noexcept {
  const Pose2D now{odom.x_m, odom.y_m, odom.theta_rad};
  odom_latest_ = now;
  if (!have_odom_) {
    have_odom_ = true;
    odom_at_update_ = now;
    last_update_ns_ = odom.stamp_ns;
    return false;
  }
  if (scan == nullptr) return false;
  // The filter moves to where odometry was when the scan was taken and weighs the scan there.
  const Pose2D at = odom_at_scan;
  const double moved = std::hypot(at.x_m - odom_at_update_.x_m, at.y_m - odom_at_update_.y_m);
  const double turned = std::abs(normalize_angle(at.theta_rad - odom_at_update_.theta_rad));
  const bool by_time = config_.update_max_interval_s > 0.0 &&
                       static_cast<double>(odom.stamp_ns - last_update_ns_) * 1e-9 >= config_.update_max_interval_s;
  const bool first = estimate_.updates == 0;
  // Lost, every scan counts: a robot that stopped because of it must still relocalise.
  bool due = first || moved >= config_.update_min_d_m || turned >= config_.update_min_a_rad || by_time || estimate_.lost;
  // After an update that fit far worse than usual, every scan updates until one fits: the
  // filter relocalises while the robot still moves and shows it new views. A robot standing
  // still triggers nothing by motion, so every recovery_update_interval_s its scan is checked
  // against the particles, and a bad fit starts an update.
  if (!due && recovery_enabled() && w_slow_ > 0.0) {
    const double interval = config_.recovery_update_interval_s;
    if (static_cast<double>(estimate_.likelihood) < kLowLikelihood * w_slow_) {
      due = true;
    } else if (interval > 0.0 && static_cast<double>(odom.stamp_ns - last_check_ns_) * 1e-9 >= interval) {
      last_check_ns_ = odom.stamp_ns;
      due = mean_likelihood(*scan) < kLowLikelihood * w_slow_;
    }
  }
  if (!due) return false;
  motion_update(odom_at_update_, at);
  sensor_update(*scan);
  if (++updates_since_resample_ >= config_.resample_interval) {
    resample();
    updates_since_resample_ = 0;
  }
  compute_estimate();
  odom_at_update_ = at;
  last_update_ns_ = odom.stamp_ns;
  ++estimate_.updates;
  estimate_.stamp_ns = odom.stamp_ns;
  return true;
}

Pose2D MonteCarloLocalization::pose_at_odometry(const Pose2D& odom_pose) const noexcept {
  // The filter pose carried by the odometry moved since the last update.
  return apply_motion(estimate_.pose, relative_pose(odom_at_update_, odom_pose));
}

PoseEstimate MonteCarloLocalization::estimate() const noexcept {
  PoseEstimate e = estimate_;
  if (!have_odom_) return e;
  e.pose = pose_at_odometry(odom_latest_);
  return e;
}

}  // namespace sen3bot::nav
