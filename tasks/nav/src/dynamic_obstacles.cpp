#include "sen3bot/nav/dynamic_obstacles.hpp"

#include <Eigen/LU>
#include <algorithm>
#include <array>
#include <cmath>
#include <cstring>
#include <limits>

#include "sen3bot/nav/arena.hpp"

namespace sen3bot::nav {

namespace {

using Vector2 = Eigen::Matrix<double, 2, 1>;
using Vector4 = Eigen::Matrix<double, 4, 1>;
using Matrix2 = Eigen::Matrix<double, 2, 2>;
using Matrix4 = Eigen::Matrix<double, 4, 4>;
using Matrix24 = Eigen::Matrix<double, 2, 4>;
using Matrix42 = Eigen::Matrix<double, 4, 2>;

constexpr double kNanosPerSecond = 1e9;

double seconds_between(hal::Nanos from, hal::Nanos to) noexcept {
  return static_cast<double>(to - from) / kNanosPerSecond;
}

// Moves a row-major grid's content by (-cols, -rows) in place; cells whose source lies outside
// take `entering`. Reads always run ahead of writes in the chosen direction, so no copy is needed.
template <typename T>
void shift_grid(std::span<T> grid, int width, int height, int cols, int rows, T entering) noexcept {
  if (cols == 0 && rows == 0) return;
  const long offset = static_cast<long>(rows) * width + cols;
  const auto move_cell = [&](int c, int r) {
    const int sc = c + cols;
    const int sr = r + rows;
    const std::size_t i = static_cast<std::size_t>(r) * static_cast<std::size_t>(width) + static_cast<std::size_t>(c);
    if (sc < 0 || sr < 0 || sc >= width || sr >= height) {
      grid[i] = entering;
    } else {
      grid[i] = grid[static_cast<std::size_t>(sr) * static_cast<std::size_t>(width) + static_cast<std::size_t>(sc)];
    }
  };
  if (offset > 0) {
    for (int r = 0; r < height; ++r)
      for (int c = 0; c < width; ++c) move_cell(c, r);
  } else {
    for (int r = height - 1; r >= 0; --r)
      for (int c = width - 1; c >= 0; --c) move_cell(c, r);
  }
}

// The 8-neighbour sum of cell (c, r), neighbours off the grid counted as the cell itself.
float border_neighbour_sum(std::span<const float> prev, int width, int height, int c, int r) noexcept {
  const float own = prev[static_cast<std::size_t>(r) * static_cast<std::size_t>(width) + static_cast<std::size_t>(c)];
  float sum = 0.0f;
  for (int dr = -1; dr <= 1; ++dr) {
    for (int dc = -1; dc <= 1; ++dc) {
      if (dc == 0 && dr == 0) continue;
      const int nc = c + dc;
      const int nr = r + dr;
      const bool inside = nc >= 0 && nr >= 0 && nc < width && nr < height;
      sum += inside ? prev[static_cast<std::size_t>(nr) * static_cast<std::size_t>(width) + static_cast<std::size_t>(nc)]
                    : own;
    }
  }
  return sum;
}

// One step of a running average: out = β[(1-α)prev + α C] + (1-β)/8 Σ neighbours(prev).
void blend(std::span<const float> prev, std::span<const std::uint8_t> image, float alpha, float beta, int width,
           int height, std::span<float> out) noexcept {
  const float keep = beta * (1.0f - alpha);
  const float take = beta * alpha;
  const float spread = (1.0f - beta) / 8.0f;
  const auto w = static_cast<std::size_t>(width);
  const auto cell = [&](std::size_t i, float neighbours) {
    out[i] = keep * prev[i] + take * static_cast<float>(image[i]) + spread * neighbours;
  };
  for (int r = 0; r < height; ++r) {
    const bool border_row = r == 0 || r == height - 1;
    const std::size_t row = static_cast<std::size_t>(r) * w;
    if (border_row || width < 3) {
      for (int c = 0; c < width; ++c) cell(row + static_cast<std::size_t>(c), border_neighbour_sum(prev, width, height, c, r));
      continue;
    }
    cell(row, border_neighbour_sum(prev, width, height, 0, r));
    // Interior: plain pointer arithmetic the compiler can vectorise.
    const float* up = prev.data() + row - w;
    const float* mid = prev.data() + row;
    const float* down = prev.data() + row + w;
    for (std::size_t c = 1; c + 1 < w; ++c) {
      const float n = up[c - 1] + up[c] + up[c + 1] + mid[c - 1] + mid[c + 1] + down[c - 1] + down[c] + down[c + 1];
      out[row + c] = keep * mid[c] + take * static_cast<float>(image[row + c]) + spread * n;
    }
    cell(row + w - 1, border_neighbour_sum(prev, width, height, width - 1, r));
  }
}

}  // namespace

// --- BackgroundSubtractor -----------------------------------------------------------------

Status BackgroundSubtractor::init(int width, int height, const DolDetectorConfig& config,
                                  std::pmr::memory_resource& resource) {
  if (width <= 0 || height <= 0) return Error::format(Errc::config, "dynamic obstacles: bad grid %d x %d", width, height);
  config_ = config;
  width_ = width;
  height_ = height;
  return guarded("dynamic obstacles: detector", [&]() -> Status {
    const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    fast_ = allocate_array<float>(resource, n);
    slow_ = allocate_array<float>(resource, n);
    scratch_ = allocate_array<float>(resource, n);
    fresh_ = allocate_array<std::uint8_t>(resource, n);
    reset();
    return Status::success();
  });
}

void BackgroundSubtractor::reset() noexcept {
  std::fill(fresh_.begin(), fresh_.end(), std::uint8_t{1});
  any_fresh_ = true;
}

void BackgroundSubtractor::shift(int cols, int rows) noexcept {
  if (cols == 0 && rows == 0) return;
  if (std::abs(cols) >= width_ || std::abs(rows) >= height_) {
    reset();  // nothing of the old window remains
    return;
  }
  shift_grid(fast_, width_, height_, cols, rows, 0.0f);
  shift_grid(slow_, width_, height_, cols, rows, 0.0f);
  shift_grid(fresh_, width_, height_, cols, rows, std::uint8_t{1});
  any_fresh_ = true;
}

void BackgroundSubtractor::apply(std::span<const std::uint8_t> image, std::span<std::uint8_t> dynamic,
                                 std::span<const std::uint8_t> mask) noexcept {
  const std::size_t n = fast_.size();
  if (n == 0 || image.size() < n || dynamic.size() < n) return;
  const bool masked = mask.size() >= n;
  const auto beta = static_cast<float>(config_.beta);
  // The neighbours must be the previous step's values: blend from a copy.
  std::memcpy(scratch_.data(), fast_.data(), n * sizeof(float));
  blend(scratch_, image, static_cast<float>(config_.alpha_fast), beta, width_, height_, fast_);
  std::memcpy(scratch_.data(), slow_.data(), n * sizeof(float));
  blend(scratch_, image, static_cast<float>(config_.alpha_slow), beta, width_, height_, slow_);
  if (any_fresh_) {
    // New cells start at what they show now, so a wall entering the window is not motion.
    for (std::size_t i = 0; i < n; ++i) {
      if (fresh_[i] == 0) continue;
      fast_[i] = slow_[i] = static_cast<float>(image[i]);
      fresh_[i] = 0;
    }
    any_fresh_ = false;
  }
  const auto c1 = static_cast<float>(config_.c1);
  const auto c2 = static_cast<float>(config_.c2);
  for (std::size_t i = 0; i < n; ++i) {
    const bool moving = fast_[i] > c1 && fast_[i] - slow_[i] > c2;
    dynamic[i] = moving && !(masked && mask[i] != 0) ? 1 : 0;
  }
}

// --- BlobFinder ---------------------------------------------------------------------------

Status BlobFinder::init(int width, int height, std::size_t max_blobs, std::pmr::memory_resource& resource) {
  if (width <= 0 || height <= 0) return Error::format(Errc::config, "dynamic obstacles: bad grid %d x %d", width, height);
  width_ = width;
  height_ = height;
  return guarded("dynamic obstacles: blob finder", [&]() -> Status {
    const std::size_t n = static_cast<std::size_t>(width) * static_cast<std::size_t>(height);
    labels_ = allocate_array<std::int32_t>(resource, n);
    stack_ = allocate_array<std::uint32_t>(resource, n);
    blobs_ = allocate_array<Blob>(resource, max_blobs);
    return Status::success();
  });
}

std::span<const Blob> BlobFinder::find(std::span<const std::uint8_t> dynamic, const GridGeometry& geometry,
                                       int min_cells, int max_cells, int link_cells) noexcept {
  count_ = 0;
  const std::size_t n = labels_.size();
  if (dynamic.size() < n || geometry.width() != width_ || geometry.height() != height_) return {};
  std::fill(labels_.begin(), labels_.end(), 0);
  const auto w = static_cast<std::uint32_t>(width_);
  const int link = std::max(1, link_cells);
  std::int32_t label = 0;
  for (std::size_t seed = 0; seed < n && count_ < blobs_.size(); ++seed) {
    if (dynamic[seed] == 0 || labels_[seed] != 0) continue;
    ++label;
    // Depth-first flood fill; every cell is pushed once (labelled when pushed).
    std::size_t top = 0;
    stack_[top++] = static_cast<std::uint32_t>(seed);
    labels_[seed] = label;
    Blob blob;
    blob.min_x_m = blob.min_y_m = std::numeric_limits<double>::infinity();
    blob.max_x_m = blob.max_y_m = -std::numeric_limits<double>::infinity();
    double sum_x = 0.0;
    double sum_y = 0.0;
    while (top > 0) {
      const std::uint32_t i = stack_[--top];
      const int c = static_cast<int>(i % w);
      const int r = static_cast<int>(i / w);
      double x = 0.0;
      double y = 0.0;
      geometry.cell_to_world(c, r, x, y);
      sum_x += x;
      sum_y += y;
      blob.min_x_m = std::min(blob.min_x_m, x);
      blob.max_x_m = std::max(blob.max_x_m, x);
      blob.min_y_m = std::min(blob.min_y_m, y);
      blob.max_y_m = std::max(blob.max_y_m, y);
      ++blob.cells;
      for (int dr = -link; dr <= link; ++dr) {
        for (int dc = -link; dc <= link; ++dc) {
          const int nc = c + dc;
          const int nr = r + dr;
          if (!geometry.in_bounds(nc, nr)) continue;
          const std::size_t j = geometry.index(nc, nr);
          if (dynamic[j] == 0 || labels_[j] != 0) continue;
          labels_[j] = label;
          stack_[top++] = static_cast<std::uint32_t>(j);
        }
      }
    }
    if (blob.cells < min_cells || blob.cells > max_cells) continue;
    blob.x_m = sum_x / blob.cells;
    blob.y_m = sum_y / blob.cells;
    blob.radius_m = 0.5 * std::hypot(blob.max_x_m - blob.min_x_m, blob.max_y_m - blob.min_y_m) +
                    0.5 * geometry.resolution_m();
    blobs_[count_++] = blob;
  }
  return {blobs_.data(), count_};
}

// --- Hungarian ----------------------------------------------------------------------------

Status Hungarian::init(std::size_t max_n, std::pmr::memory_resource& resource) {
  max_n_ = max_n;
  return guarded("dynamic obstacles: assignment", [&]() -> Status {
    // Index 0 is the algorithm's virtual row and column; the real ones are 1..n.
    u_ = allocate_array<double>(resource, max_n + 1);
    v_ = allocate_array<double>(resource, max_n + 1);
    min_v_ = allocate_array<double>(resource, max_n + 1);
    match_ = allocate_array<int>(resource, max_n + 1);
    way_ = allocate_array<int>(resource, max_n + 1);
    used_ = allocate_array<std::uint8_t>(resource, max_n + 1);
    return Status::success();
  });
}

double Hungarian::solve(std::span<const double> cost, std::size_t rows, std::size_t cols,
                        std::span<int> row_to_col) noexcept {
  const std::size_t out = std::min(rows, row_to_col.size());
  std::fill(row_to_col.begin(), row_to_col.begin() + static_cast<std::ptrdiff_t>(out), kUnassigned);
  if (rows == 0 || cols == 0 || rows > max_n_ || cols > max_n_ || cost.size() < rows * cols || row_to_col.size() < rows) {
    return 0.0;
  }
  // The algorithm assigns every one of n "workers" to one of m >= n "jobs"; with more rows
  // than columns the columns are the workers (the matrix read transposed).
  const bool transposed = rows > cols;
  const std::size_t n = transposed ? cols : rows;
  const std::size_t m = transposed ? rows : cols;
  const auto a = [&](std::size_t worker, std::size_t job) {  // 1-based
    return transposed ? cost[(job - 1) * cols + (worker - 1)] : cost[(worker - 1) * cols + (job - 1)];
  };
  constexpr double kInf = std::numeric_limits<double>::infinity();
  std::fill(u_.begin(), u_.begin() + static_cast<std::ptrdiff_t>(n + 1), 0.0);
  std::fill(v_.begin(), v_.begin() + static_cast<std::ptrdiff_t>(m + 1), 0.0);
  std::fill(match_.begin(), match_.begin() + static_cast<std::ptrdiff_t>(m + 1), 0);  // job -> worker, 0: free
  for (std::size_t worker = 1; worker <= n; ++worker) {
    // Grow a tree of tight edges from the new worker (parked on virtual job 0) until it
    // reaches a free job: a shortest augmenting path under the reduced costs.
    match_[0] = static_cast<int>(worker);
    std::size_t job = 0;
    std::fill(min_v_.begin(), min_v_.begin() + static_cast<std::ptrdiff_t>(m + 1), kInf);
    std::fill(used_.begin(), used_.begin() + static_cast<std::ptrdiff_t>(m + 1), std::uint8_t{0});
    do {
      used_[job] = 1;
      const auto from = static_cast<std::size_t>(match_[job]);
      double delta = kInf;
      std::size_t next = 0;
      for (std::size_t j = 1; j <= m; ++j) {
        if (used_[j] != 0) continue;
        const double reduced = a(from, j) - u_[from] - v_[j];
        if (reduced < min_v_[j]) {
          min_v_[j] = reduced;
          way_[j] = static_cast<int>(job);
        }
        if (min_v_[j] < delta) {
          delta = min_v_[j];
          next = j;
        }
      }
      // Move the potentials so that the cheapest edge out of the tree becomes tight.
      for (std::size_t j = 0; j <= m; ++j) {
        if (used_[j] != 0) {
          u_[static_cast<std::size_t>(match_[j])] += delta;
          v_[j] -= delta;
        } else {
          min_v_[j] -= delta;
        }
      }
      job = next;
    } while (match_[job] != 0);
    // Flip the path back to the root.
    do {
      const auto previous = static_cast<std::size_t>(way_[job]);
      match_[job] = match_[previous];
      job = previous;
    } while (job != 0);
  }
  double total = 0.0;
  for (std::size_t j = 1; j <= m; ++j) {
    if (match_[j] == 0) continue;
    const auto worker = static_cast<std::size_t>(match_[j]);
    total += a(worker, j);
    if (transposed) {
      row_to_col[j - 1] = static_cast<int>(worker - 1);
    } else {
      row_to_col[worker - 1] = static_cast<int>(j - 1);
    }
  }
  return total;
}

// --- MoverTracker -------------------------------------------------------------------------

namespace {

// Constant-velocity transition and white-noise-acceleration process noise for dt.
void predict_state(DolTrack& track, double dt, double accel_sigma) noexcept {
  if (!(dt > 0.0)) return;
  Matrix4 f = Matrix4::Identity();
  f(0, 2) = dt;
  f(1, 3) = dt;
  const double q = accel_sigma * accel_sigma;
  const double dt2 = dt * dt;
  const double pp = q * dt2 * dt2 / 4.0;
  const double pv = q * dt2 * dt / 2.0;
  const double vv = q * dt2;
  Matrix4 noise = Matrix4::Zero();
  noise(0, 0) = noise(1, 1) = pp;
  noise(0, 2) = noise(2, 0) = noise(1, 3) = noise(3, 1) = pv;
  noise(2, 2) = noise(3, 3) = vv;
  track.x = f * track.x;
  track.P = f * track.P * f.transpose() + noise;
}

// Standard Kalman correction with a position measurement (Joseph form keeps P symmetric).
void correct(DolTrack& track, const Vector2& z, double measurement_sigma) noexcept {
  Matrix24 h = Matrix24::Zero();
  h(0, 0) = 1.0;
  h(1, 1) = 1.0;
  const Matrix2 r = Matrix2::Identity() * (measurement_sigma * measurement_sigma);
  const Matrix2 s = h * track.P * h.transpose() + r;
  const Matrix42 k = track.P * h.transpose() * s.inverse();
  track.x += k * (z - h * track.x);
  const Matrix4 i_kh = Matrix4::Identity() - k * h;
  track.P = i_kh * track.P * i_kh.transpose() + k * r * k.transpose();
}

}  // namespace

Status MoverTracker::init(const DolTrackerConfig& config, std::pmr::memory_resource& resource) {
  if (config.max_tracks == 0 || config.confirm_hits < 1 || !(config.gate_m > 0.0) ||
      !(config.measurement_sigma_m > 0.0) || config.min_radius_m > config.max_radius_m) {
    return Error::format(Errc::config,
                         "dynamic obstacles: max_tracks >= 1, confirm_hits >= 1, gate_m > 0, measurement_sigma_m > 0 "
                         "and min_radius_m <= max_radius_m needed");
  }
  config_ = config;
  count_ = 0;
  next_id_ = 1;
  return guarded("dynamic obstacles: tracker", [&]() -> Status {
    const std::size_t n = std::max(config.max_tracks, config.max_blobs);
    if (Status s = hungarian_.init(n, resource); !s) return s;
    tracks_ = allocate_array<DolTrack>(resource, config.max_tracks);
    cost_ = allocate_array<double>(resource, config.max_tracks * std::max<std::size_t>(config.max_blobs, 1));
    assignment_ = allocate_array<int>(resource, config.max_tracks);
    blob_used_ = allocate_array<std::uint8_t>(resource, std::max<std::size_t>(config.max_blobs, 1));
    return Status::success();
  });
}

Eigen::Matrix<double, 2, 1> MoverTracker::predict_position(const DolTrack& track, hal::Nanos stamp_ns) noexcept {
  const double dt = std::max(0.0, seconds_between(track.stamp_ns, stamp_ns));
  return {track.x(0) + track.x(2) * dt, track.x(1) + track.x(3) * dt};
}

DolTrack MoverTracker::predicted(const DolTrack& track, hal::Nanos stamp_ns) const noexcept {
  DolTrack out = track;
  predict_state(out, seconds_between(track.stamp_ns, stamp_ns), config_.accel_sigma_m_s2);
  if (stamp_ns > out.stamp_ns) out.stamp_ns = stamp_ns;
  return out;
}

void MoverTracker::follow_axis(DolTrack& track, const Eigen::Matrix<double, 2, 1>& z) const noexcept {
  const double forget = std::exp(-(z - track.seen).norm() / std::max(config_.axis_memory_m, 1e-6));
  const Vector2 r = z - track.birth;
  track.axis_weight = forget * track.axis_weight + 1.0;
  track.axis_sum = forget * track.axis_sum + r;
  track.axis_squares = forget * track.axis_squares + r * r.transpose();
}

bool MoverTracker::axis(const DolTrack& track, Axis& out) const noexcept {
  constexpr double kMinWeight = 3.0;   // a line needs a few centroids
  constexpr double kMinElongation = 16.0;  // variance ratio: 4 times as long as wide
  if (track.axis_weight < kMinWeight) return false;
  const Vector2 mean = track.axis_sum / track.axis_weight;
  const Eigen::Matrix<double, 2, 2> c = track.axis_squares / track.axis_weight - mean * mean.transpose();
  const SymmetricEigen spread = symmetric_eigen(c(0, 0), c(0, 1), c(1, 1));
  const double major = spread.larger;
  const double minor = std::max(0.0, spread.smaller);
  // A uniform spread over a segment of length L has variance L^2 / 12.
  if (!(12.0 * major >= config_.axis_min_travel_m * config_.axis_min_travel_m) || minor * kMinElongation > major) return false;
  out.centre = track.birth + mean;
  out.direction = Vector2(std::cos(spread.larger_angle_rad), std::sin(spread.larger_angle_rad));
  return true;
}

bool MoverTracker::along_axis(const DolTrack& track, Axis& a) const noexcept {
  if (!axis(track, a)) return false;
  const Vector2 v(track.x(2), track.x(3));
  const double along = v.dot(a.direction);
  const double across = std::abs(a.direction(0) * v(1) - a.direction(1) * v(0));
  return std::atan2(across, std::abs(along)) <= config_.axis_max_angle_rad;  // else turning: the filter's
}

Eigen::Matrix<double, 2, 1> MoverTracker::velocity(const DolTrack& track) const noexcept {
  const Vector2 v(track.x(2), track.x(3));
  Axis a;
  return along_axis(track, a) ? Vector2(a.direction * v.dot(a.direction)) : v;
}

void MoverTracker::hold_to_axis(DolTrack& track, Hold hold) const noexcept {
  Axis a;
  if (!along_axis(track, a)) return;
  const Vector2& u = a.direction;
  double along = Vector2(track.x(2), track.x(3)).dot(u);
  if (hold == Hold::measured) {
    // Averaged over some 20 scans: the last, half-seen ones do not rule it.
    constexpr double kSpeedGain = 0.05;
    track.axis_speed_m_s = track.axis_speed_m_s > 0.0 ? track.axis_speed_m_s + kSpeedGain * (std::abs(along) - track.axis_speed_m_s)
                                                      : std::abs(along);
  } else if (hold == Hold::unseen) {
    // Out of sight: on the line, at the speed it kept while seen.
    const Vector2 p(track.x(0), track.x(1));
    const Vector2 on_line = a.centre + u * (p - a.centre).dot(u);
    track.x(0) = on_line(0);
    track.x(1) = on_line(1);
    if (std::abs(along) < track.axis_speed_m_s) along = std::copysign(track.axis_speed_m_s, along);
  }
  track.x(2) = along * u(0);
  track.x(3) = along * u(1);
}

void MoverTracker::update(std::span<const Blob> blobs, hal::Nanos stamp_ns, const LaserView& view) noexcept {
  const std::size_t blob_count = std::min(blobs.size(), config_.max_blobs);
  last_update_ns_ = std::max(last_update_ns_, stamp_ns);
  for (std::size_t t = 0; t < count_; ++t) {
    DolTrack& track = tracks_[t];
    predict_state(track, seconds_between(track.stamp_ns, stamp_ns), config_.accel_sigma_m_s2);
    track.stamp_ns = std::max(track.stamp_ns, stamp_ns);
  }
  std::fill(blob_used_.begin(), blob_used_.end(), std::uint8_t{0});
  std::fill(assignment_.begin(), assignment_.end(), Hungarian::kUnassigned);
  if (count_ > 0 && blob_count > 0) {
    // Out-of-gate pairs share one cost above the gate: they never win over an in-gate pair.
    const double far = 2.0 * config_.gate_m;
    for (std::size_t t = 0; t < count_; ++t) {
      for (std::size_t b = 0; b < blob_count; ++b) {
        const double d = std::hypot(blobs[b].x_m - tracks_[t].x(0), blobs[b].y_m - tracks_[t].x(1));
        cost_[t * blob_count + b] = std::min(d, far);
      }
    }
    hungarian_.solve(cost_.first(count_ * blob_count), count_, blob_count, assignment_.first(count_));
    for (std::size_t t = 0; t < count_; ++t) {
      const int b = assignment_[t];
      if (b == Hungarian::kUnassigned) continue;
      if (cost_[t * blob_count + static_cast<std::size_t>(b)] > config_.gate_m) {
        assignment_[t] = Hungarian::kUnassigned;
        continue;
      }
      blob_used_[static_cast<std::size_t>(b)] = 1;
    }
  }
  // Corrections, then deaths (compacting in place, order kept).
  std::size_t kept = 0;
  for (std::size_t t = 0; t < count_; ++t) {
    DolTrack& track = tracks_[t];
    const int b = assignment_[t];
    if (b != Hungarian::kUnassigned) {
      const Blob& blob = blobs[static_cast<std::size_t>(b)];
      const Vector2 z(blob.x_m, blob.y_m);
      const double dt = seconds_between(track.last_hit_ns, stamp_ns);
      if (track.hits == 1 && dt > 0.0) {
        // Two-point initialisation: the velocity from the two positions, with its covariance.
        const double s2 = config_.measurement_sigma_m * config_.measurement_sigma_m;
        const Vector2 previous(track.x(0), track.x(1));
        track.x << z, (z - previous) / dt;
        track.P = Matrix4::Zero();
        track.P(0, 0) = track.P(1, 1) = s2;
        track.P(0, 2) = track.P(2, 0) = track.P(1, 3) = track.P(3, 1) = s2 / dt;
        track.P(2, 2) = track.P(3, 3) = 2.0 * s2 / (dt * dt);
      } else {
        correct(track, z, config_.measurement_sigma_m);
      }
      ++track.hits;
      track.last_hit_ns = stamp_ns;
      track.in_view = true;
      follow_axis(track, z);
      track.seen = z;
      hold_to_axis(track, Hold::measured);
      if (track.hits >= config_.confirm_hits) track.confirmed = true;
      constexpr double kRadiusGain = 0.3;  // blobs flicker with the scan; the size does not
      const double radius = std::clamp(blob.radius_m, config_.min_radius_m, config_.max_radius_m);
      track.radius_m += kRadiusGain * (radius - track.radius_m);
    } else {
      const double dx = track.x(0) - view.x_m;
      const double dy = track.x(1) - view.y_m;
      const double bearing = std::abs(normalize_angle(std::atan2(dy, dx) - view.heading_rad));
      track.in_view = bearing <= view.half_angle_rad && std::hypot(dx, dy) <= view.range_m;
      const double limit = track.in_view ? config_.max_coast_s : config_.max_coast_unseen_s;
      const bool lost = !track.confirmed || seconds_between(track.last_hit_ns, stamp_ns) > limit;
      if (lost) continue;
      // Coasting on along the axis, not off it with a sideways slide.
      hold_to_axis(track, track.in_view ? Hold::coasting : Hold::unseen);
    }
    if (kept != t) tracks_[kept] = track;
    ++kept;
  }
  count_ = kept;
  // Births from the blobs nobody took, while there is room.
  const double s2 = config_.measurement_sigma_m * config_.measurement_sigma_m;
  const double v2 = config_.initial_velocity_sigma_m_s * config_.initial_velocity_sigma_m_s;
  for (std::size_t b = 0; b < blob_count && count_ < tracks_.size(); ++b) {
    if (blob_used_[b] != 0) continue;
    DolTrack& track = tracks_[count_++];
    track = DolTrack{};
    track.id = next_id_++;
    track.hits = 1;
    track.confirmed = config_.confirm_hits <= 1;
    track.stamp_ns = stamp_ns;
    track.last_hit_ns = stamp_ns;
    track.x << blobs[b].x_m, blobs[b].y_m, 0.0, 0.0;
    track.birth << blobs[b].x_m, blobs[b].y_m;
    track.seen = track.birth;
    track.P = Vector4(s2, s2, v2, v2).asDiagonal();
    track.radius_m = std::clamp(blobs[b].radius_m, config_.min_radius_m, config_.max_radius_m);
  }
}

void MoverTracker::classify(std::span<const std::uint8_t> image, const GridGeometry& geometry) noexcept {
  const auto vacated = [&](const DolTrack& track) {
    const double reach = config_.vacated_radius_m / geometry.resolution_m();
    const int k = static_cast<int>(std::ceil(reach));
    int col = 0;
    int row = 0;
    if (!geometry.world_to_cell(track.birth(0), track.birth(1), col, row)) return false;  // not in view: unknown
    for (int dr = -k; dr <= k; ++dr) {
      for (int dc = -k; dc <= k; ++dc) {
        if (dc * dc + dr * dr > reach * reach + 1e-9 || !geometry.in_bounds(col + dc, row + dr)) continue;
        if (image[geometry.index(col + dc, row + dr)] != 0) return false;
      }
    }
    return true;
  };
  for (std::size_t t = 0; t < count_; ++t) {
    DolTrack& track = tracks_[t];
    if (!track.confirmed || track.mover || track.last_hit_ns != last_update_ns_) continue;
    if (std::hypot(track.x(2), track.x(3)) < config_.moving_min_speed_m_s) continue;
    // Measured, not filtered: a filter's overshoot is no evidence of travel.
    const double travel = std::hypot(track.seen(0) - track.birth(0), track.seen(1) - track.birth(1));
    track.mover = travel >= config_.moving_far_travel_m || (travel >= config_.moving_min_travel_m && vacated(track));
  }
}

void MoverTracker::turn_back(std::size_t index) noexcept {
  if (index >= count_) return;
  tracks_[index].x(2) = -tracks_[index].x(2);
  tracks_[index].x(3) = -tracks_[index].x(3);
}

std::size_t MoverTracker::vouch(std::span<const Vouch> people) noexcept {
  if (!config_.camera_vouches || people.empty()) return 0;
  const double cos_max = std::cos(config_.vouch_max_angle_rad);
  std::size_t made = 0;
  for (std::size_t t = 0; t < count_; ++t) {
    DolTrack& track = tracks_[t];
    if (track.mover || track.hits < config_.vouch_min_hits || track.last_hit_ns != last_update_ns_ ||
        !track.x.allFinite())
      continue;
    const double speed = std::hypot(track.x(2), track.x(3));
    if (speed < config_.moving_min_speed_m_s) continue;
    for (const Vouch& p : people) {
      const double person_speed = std::hypot(p.vx_m_s, p.vy_m_s);
      if (std::hypot(track.x(0) - p.x_m, track.x(1) - p.y_m) > config_.vouch_reach_m) continue;
      // Their way: the same direction, and a like speed (a box beside a walker has neither).
      if ((track.x(2) * p.vx_m_s + track.x(3) * p.vy_m_s) < cos_max * speed * person_speed) continue;
      if (speed > config_.vouch_speed_ratio * person_speed || person_speed > config_.vouch_speed_ratio * speed) continue;
      track.confirmed = true;
      track.mover = true;
      ++made;
      break;
    }
  }
  return made;
}

bool MoverTracker::moving(const DolTrack& track) const noexcept {
  return track.mover &&
         (!track.in_view || seconds_between(track.last_hit_ns, last_update_ns_) <= config_.publish_max_coast_s);
}

bool MoverTracker::candidate(const DolTrack& track) const noexcept {
  return track.confirmed && !track.mover && track.last_hit_ns == last_update_ns_ &&
         std::hypot(track.x(2), track.x(3)) >= config_.moving_min_speed_m_s;
}

// --- Cost ---------------------------------------------------------------------------------

namespace {

// The Gaussian around one mover, prepared once for many cells.
struct MoverShape {
  double cos_h = 1.0;  // velocity direction
  double sin_h = 0.0;
  double plateau_m = 0.0;  // flat stretch ahead
  double inv_front_x = 0.0;  // 1 / (2 σ²)
  double inv_front_y = 0.0;
  double inv_back_x = 0.0;
  double inv_back_y = 0.0;
  double amplitude = 0.0;
  double cutoff = 0.0;
  double limit = -1.0;  // exponents above this give less than cutoff
  double reach_front_m = 0.0;
  double reach_back_m = 0.0;
  double reach_side_m = 0.0;
};

MoverShape make_shape(const DolCostConfig& config, double vx, double vy) noexcept {
  constexpr double kMinSigma2 = 1e-4;
  MoverShape shape;
  const double speed = std::hypot(vx, vy);
  const double heading = std::atan2(vy, vx);  // 0 at rest
  shape.cos_h = std::cos(heading);
  shape.sin_h = std::sin(heading);
  const double r = config.max_speed_m_s > 0.0 ? std::min(1.0, speed / config.max_speed_m_s) : 1.0;
  shape.plateau_m = std::max(0.0, config.front_horizon_s) * speed;
  const double front_x = std::max(kMinSigma2, (1.0 + r) * config.sigma2_front_x_m2);
  const double front_y = std::max(kMinSigma2, (1.0 - r / 2.0) * config.sigma2_front_y_m2);
  const double back_x = std::max(kMinSigma2, (1.0 - r) * config.sigma2_back_x_m2);
  const double back_y = std::max(kMinSigma2, (1.0 - r / 4.0) * config.sigma2_back_y_m2);
  shape.inv_front_x = 1.0 / (2.0 * front_x);
  shape.inv_front_y = 1.0 / (2.0 * front_y);
  shape.inv_back_x = 1.0 / (2.0 * back_x);
  shape.inv_back_y = 1.0 / (2.0 * back_y);
  shape.amplitude = std::min(config.amplitude, static_cast<double>(kMaxNonObstacleCost));
  shape.cutoff = config.cutoff;
  if (shape.amplitude > 0.0 && shape.amplitude >= config.cutoff) {
    shape.limit = config.cutoff > 0.0 ? std::log(shape.amplitude / config.cutoff) : 50.0;
    // exponent = along² / (2σ²) <= limit  <=>  |along| <= σ sqrt(2 limit)
    const double k = std::sqrt(2.0 * shape.limit);
    shape.reach_front_m = shape.plateau_m + k * std::sqrt(front_x);
    shape.reach_back_m = k * std::sqrt(back_x);
    shape.reach_side_m = k * std::sqrt(std::max(front_y, back_y));
  }
  return shape;
}

// The three pieces of the shape along the velocity: behind, the flat stretch, ahead of it.
enum Piece : int { kBack = 0, kPlateau = 1, kFront = 2 };

Piece piece_of(const MoverShape& shape, double along) noexcept {
  if (along <= 0.0) return kBack;
  return along <= shape.plateau_m ? kPlateau : kFront;
}

// The exponent with one piece's formula (each a quadratic in along and across).
double piece_exponent(const MoverShape& shape, Piece piece, double along, double across) noexcept {
  switch (piece) {
    case kBack:
      return along * along * shape.inv_back_x + across * across * shape.inv_back_y;
    case kPlateau:
      return across * across * shape.inv_front_y;
    case kFront:
      break;
  }
  const double ahead = along - shape.plateau_m;
  return ahead * ahead * shape.inv_front_x + across * across * shape.inv_front_y;
}

// The value at offset (dx, dy) from the mover's centre; 0 below the cutoff.
double shape_value(const MoverShape& shape, double dx, double dy) noexcept {
  const double along = dx * shape.cos_h + dy * shape.sin_h;
  const double across = -dx * shape.sin_h + dy * shape.cos_h;
  const double exponent = piece_exponent(shape, piece_of(shape, along), along, across);
  if (exponent > shape.limit) return 0.0;
  const double value = shape.amplitude * std::exp(-exponent);
  return value < shape.cutoff ? 0.0 : value;
}

// floor() or ceil() of a cell coordinate as an int, clamped to [-1, limit] first so that a
// point far off the grid cannot overflow the cast.
int clamped_cell(double v, int limit) noexcept {
  return static_cast<int>(std::clamp(std::isnan(v) ? -1.0 : v, -1.0, static_cast<double>(limit)));
}

// The dx with a * dx in [lo, hi], intersected into [dx_min, dx_max].
void restrict_interval(double a, double lo, double hi, double& dx_min, double& dx_max) noexcept {
  if (std::abs(a) < 1e-12) {
    if (lo > 0.0 || hi < 0.0) dx_max = dx_min - 1.0;  // empty
    return;
  }
  const double x0 = lo / a;
  const double x1 = hi / a;
  dx_min = std::max(dx_min, std::min(x0, x1));
  dx_max = std::min(dx_max, std::max(x0, x1));
}

// Marks the cells whose centre lies within radius_m of (x, y), and the cell holding it, lethal.
void paint_core(double x_m, double y_m, double radius_m, Costmap2D& grid) noexcept {
  const GridGeometry& g = grid.geometry();
  double gx = 0.0;
  double gy = 0.0;
  g.world_to_grid(x_m, y_m, gx, gy);
  int col = 0;
  int row = 0;
  if (grid.world_to_cell(x_m, y_m, col, row)) grid.set(col, row, kLethalCost);
  const double reach = std::max(0.0, radius_m) / g.resolution_m();
  const int r0 = std::max(0, clamped_cell(std::floor(gy - 0.5 - reach), g.height()));
  const int r1 = std::min(g.height() - 1, clamped_cell(std::ceil(gy - 0.5 + reach), g.height()));
  const int c0 = std::max(0, clamped_cell(std::floor(gx - 0.5 - reach), g.width()));
  const int c1 = std::min(g.width() - 1, clamped_cell(std::ceil(gx - 0.5 + reach), g.width()));
  const double reach2 = reach * reach;
  for (int r = r0; r <= r1; ++r) {
    const double dy = r + 0.5 - gy;
    for (int c = c0; c <= c1; ++c) {
      const double dx = c + 0.5 - gx;
      if (dx * dx + dy * dy <= reach2) grid.set(c, r, kLethalCost);
    }
  }
}

}  // namespace

double mover_cost(const DolCostConfig& config, double cx, double cy, double vx, double vy, double x_m,
                  double y_m) noexcept {
  return shape_value(make_shape(config, vx, vy), x_m - cx, y_m - cy);
}

void paint_mover(const DolCostConfig& config, double cx, double cy, double vx, double vy, Costmap2D& grid) noexcept {
  MoverShape shape = make_shape(config, vx, vy);
  if (shape.limit < 0.0) return;
  // Work in the grid's frame: distances and relative angles are the same as in the map frame.
  const GridGeometry& g = grid.geometry();
  const double res = g.resolution_m();
  const double yaw_c = std::cos(g.origin_yaw_rad());
  const double yaw_s = std::sin(g.origin_yaw_rad());
  const double cos_h = shape.cos_h * yaw_c + shape.sin_h * yaw_s;  // heading - yaw
  const double sin_h = shape.sin_h * yaw_c - shape.cos_h * yaw_s;
  shape.cos_h = cos_h;
  shape.sin_h = sin_h;
  double gx = 0.0;
  double gy = 0.0;
  g.world_to_grid(cx, cy, gx, gy);
  const double reach = std::max({shape.reach_front_m, shape.reach_back_m, shape.reach_side_m}) / res;
  const int r0 = std::max(0, clamped_cell(std::floor(gy - 0.5 - reach), g.height()));
  const int r1 = std::min(g.height() - 1, clamped_cell(std::ceil(gy - 0.5 + reach), g.height()));
  constexpr double kSlack = 1e-9;
  const auto cells = grid.cells();
  // Per piece, exp(-2 a res²) with a the exponent's x² coefficient along a row.
  const double res2 = res * res;
  const double step_ratio[3] = {
      std::exp(-2.0 * res2 * (shape.inv_back_x * cos_h * cos_h + shape.inv_back_y * sin_h * sin_h)),
      std::exp(-2.0 * res2 * (shape.inv_front_y * sin_h * sin_h)),
      std::exp(-2.0 * res2 * (shape.inv_front_x * cos_h * cos_h + shape.inv_front_y * sin_h * sin_h))};
  for (int r = r0; r <= r1; ++r) {
    const double dy = (r + 0.5 - gy) * res;
    // The cells of this row inside the box along ∈ [-back, front], across ∈ [-side, side].
    double dx_min = -std::numeric_limits<double>::infinity();
    double dx_max = std::numeric_limits<double>::infinity();
    restrict_interval(cos_h, -shape.reach_back_m - dy * sin_h - kSlack, shape.reach_front_m - dy * sin_h + kSlack,
                      dx_min, dx_max);
    restrict_interval(-sin_h, -shape.reach_side_m - dy * cos_h - kSlack, shape.reach_side_m - dy * cos_h + kSlack,
                      dx_min, dx_max);
    if (!(dx_min <= dx_max)) continue;
    const int c0 = std::max(0, clamped_cell(std::ceil(gx - 0.5 + dx_min / res), g.width()));
    const int c1 = std::min(g.width() - 1, clamped_cell(std::floor(gx - 0.5 + dx_max / res), g.width()));
    // Along a row each piece's exponent is a quadratic in the column, so exp(-exponent) follows
    // from cell to cell by two multiplications: g(k+1) = g(k) ratio(k), ratio(k+1) = ratio(k) m,
    // with m = exp(-2 a res²) for the quadratic's leading coefficient a. exp() is called only
    // where a row enters a piece.
    const std::size_t row = g.index(0, r);
    const double x0 = (c0 + 0.5 - gx) * res;
    const double along0 = x0 * cos_h + dy * sin_h;
    const double across0 = -x0 * sin_h + dy * cos_h;
    const double step_along = res * cos_h;
    const double step_across = -res * sin_h;
    const double floor_g = shape.cutoff / shape.amplitude;
    int piece = -1;
    double g_value = 0.0;
    double ratio = 0.0;
    for (int c = c0; c <= c1; ++c) {
      const double k = c - c0;
      const double along = along0 + k * step_along;
      const Piece here = piece_of(shape, along);
      if (here != piece) {
        piece = here;
        const double across = across0 + k * step_across;
        const double e = piece_exponent(shape, here, along, across);
        const double e_next = piece_exponent(shape, here, along + step_along, across + step_across);
        g_value = std::exp(-e);
        ratio = std::exp(e - e_next);
      } else {
        g_value *= ratio;
        ratio *= step_ratio[piece];
      }
      if (g_value < floor_g) continue;
      const auto cost = static_cast<std::uint8_t>(std::min(shape.amplitude, shape.amplitude * g_value));
      std::uint8_t& cell = cells[row + static_cast<std::size_t>(c)];
      if (cost > cell) cell = cost;
    }
  }
}

// --- DynamicObstacleLayer -----------------------------------------------------------------

Status DynamicObstacleLayer::init(const Costmap2D& master, std::pmr::memory_resource& resource) {
  active_ = false;
  if (!config_.enabled) return Status::success();
  if (static_map_ != nullptr) {
    if (std::abs(master.resolution_m() - static_map_->resolution_m()) > 1e-9 ||
        std::abs(normalize_angle(master.yaw_rad() - static_map_->origin_yaw_rad())) > 1e-9) {
      return Error::format(Errc::config, "dynamic obstacles: the costmap and the static map differ in resolution or yaw");
    }
  }
  const int w = master.width();
  const int h = master.height();
  if (Status s = detector_.init(w, h, config_.detector, resource); !s) return s;
  if (Status s = blob_finder_.init(w, h, config_.tracker.max_blobs, resource); !s) return s;
  if (Status s = tracker_.init(config_.tracker, resource); !s) return s;
  const Status s = guarded("dynamic obstacles", [&]() -> Status {
    image_ = allocate_array<std::uint8_t>(resource, master.size());
    dynamic_ = allocate_array<std::uint8_t>(resource, master.size());
    mask_ = allocate_array<std::uint8_t>(resource, master.size());
    if (static_map_ != nullptr && config_.detector.static_mask_radius_m > 0.0) {
      map_near_ = allocate_array<std::uint8_t>(resource, static_map_->cell_count());
      // Every cell whose centre lies within the radius of an occupied cell's centre.
      const OccupancyMap& map = *static_map_;
      const double reach = config_.detector.static_mask_radius_m / map.resolution_m();
      const int k = static_cast<int>(std::floor(reach));
      const double reach2 = reach * reach + 1e-9;
      for (int r = 0; r < map.height(); ++r) {
        for (int c = 0; c < map.width(); ++c) {
          if (map.at(c, r) < kOccupiedOccupancy) continue;
          for (int dr = -k; dr <= k; ++dr) {
            for (int dc = -k; dc <= k; ++dc) {
              if (double(dc * dc + dr * dr) > reach2 || !map.in_bounds(c + dc, r + dr)) continue;
              map_near_[map.geometry().index(c + dc, r + dr)] = 1;
            }
          }
        }
      }
    }
    return Status::success();
  });
  if (!s) return s;
  blobs_ = {};
  detections_ = 0;
  active_ = true;
  return Status::success();
}

void DynamicObstacleLayer::on_window_moved(int shift_cols, int shift_rows) noexcept {
  if (!active_) return;
  detector_.shift(shift_cols, shift_rows);
  const int w = detector_.width();
  const int h = detector_.height();
  if (std::abs(shift_cols) >= w || std::abs(shift_rows) >= h) {
    std::fill(dynamic_.begin(), dynamic_.end(), std::uint8_t{0});
  } else {
    shift_grid(dynamic_, w, h, shift_cols, shift_rows, std::uint8_t{0});
  }
}

bool DynamicObstacleLayer::near_wall(double x_m, double y_m) const noexcept {
  int col = 0;
  int row = 0;
  if (!static_map_->world_to_cell(x_m, y_m, col, row)) return true;  // off the map: walled in
  return map_near_[static_map_->geometry().index(col, row)] != 0;
}

void DynamicObstacleLayer::turn_back_at_walls(hal::Nanos stamp_ns) noexcept {
  if (map_near_.empty()) return;
  const auto tracks = tracker_.tracks();
  for (std::size_t i = 0; i < tracks.size(); ++i) {
    const DolTrack& track = tracks[i];
    if (!track.mover || track.last_hit_ns == stamp_ns) continue;  // seen: the filter follows it
    const double speed = std::hypot(track.x(2), track.x(3));
    if (speed < config_.tracker.moving_min_speed_m_s) continue;
    const double ux = track.x(2) / speed * kWallLookahead_m;
    const double uy = track.x(3) / speed * kWallLookahead_m;
    if (near_wall(track.x(0) + ux, track.x(1) + uy) && !near_wall(track.x(0) - ux, track.x(1) - uy))
      tracker_.turn_back(i);
  }
}

void DynamicObstacleLayer::update(Costmap2D& master, const CostmapInputs& inputs) noexcept {
  if (!active_ || master.size() != image_.size()) return;
  if (inputs.scan != nullptr) {
    const auto cells = master.cells();
    for (std::size_t i = 0; i < cells.size(); ++i) image_[i] = cells[i] == kLethalCost ? 255 : 0;
    std::span<const std::uint8_t> mask;
    const std::span<const std::uint8_t> seen =
        observations_ != nullptr && observations_->seen_free().size() == mask_.size() ? observations_->seen_free()
                                                                                      : std::span<const std::uint8_t>{};
    if (!map_near_.empty() || !seen.empty()) {
      // Never dynamic: next to the static map, or where the laser never saw free floor (a face
      // that just came into view, not something that moved in). The window and the map share
      // the lattice and the yaw: a fixed cell offset.
      int off_c = 0;
      int off_r = 0;
      if (!map_near_.empty()) {
        double gx = 0.0;
        double gy = 0.0;
        static_map_->world_to_grid(master.origin_x_m(), master.origin_y_m(), gx, gy);
        off_c = static_cast<int>(std::lround(gx));
        off_r = static_cast<int>(std::lround(gy));
      }
      for (int r = 0; r < master.height(); ++r) {
        const int mr = r + off_r;
        const std::size_t row = master.index(0, r);
        for (int c = 0; c < master.width(); ++c) {
          const int mc = c + off_c;
          const std::size_t i = row + static_cast<std::size_t>(c);
          const bool near_map = !map_near_.empty() && static_map_->in_bounds(mc, mr) &&
                                map_near_[static_map_->geometry().index(mc, mr)] != 0;
          mask_[i] = near_map || (!seen.empty() && seen[i] == 0) ? 1 : 0;
        }
      }
      mask = mask_;
    }
    detector_.apply(image_, dynamic_, mask);
    blobs_ = blob_finder_.find(dynamic_, master.geometry(), config_.detector.min_blob_cells,
                               config_.detector.max_blob_cells, config_.detector.blob_link_cells);
    detections_ += blobs_.size();
    // Where the laser looked: from the sensor at the scan's pose, over the beams' sector, as
    // far as the obstacle layer marks (what lies beyond is not detected).
    const ProjectedScan& scan = *inputs.scan;
    LaserView view;
    const Pose2D& at = inputs.scan_pose;
    const double c = std::cos(at.theta_rad);
    const double s = std::sin(at.theta_rad);
    view.x_m = at.x_m + c * scan.mount().x_m - s * scan.mount().y_m;
    view.y_m = at.y_m + s * scan.mount().x_m + c * scan.mount().y_m;
    view.heading_rad = at.theta_rad + scan.mount().theta_rad;
    if (scan.size() > 1) {
      const Point2D first = scan.direction(0);
      const Point2D last = scan.direction(scan.size() - 1);
      view.half_angle_rad =
          0.5 * std::abs(normalize_angle(std::atan2(last.y_m, last.x_m) - std::atan2(first.y_m, first.x_m)));
    }
    if (observations_ != nullptr) view.range_m = observations_->config().obstacle_max_range_m;
    tracker_.update(blobs_, scan.stamp_ns(), view);
    tracker_.classify(image_, master.geometry());
    if (people_ != nullptr) {
      // Walking people the sensors see now, predicted to the scan: their word for a track.
      std::array<Vouch, msg::People::kMax> vouches{};
      std::size_t n = 0;
      const double walking = 2.0 * config_.tracker.moving_min_speed_m_s;
      for (std::size_t i = 0; i < std::min<std::size_t>(people_->count, msg::People::kMax); ++i) {
        const msg::TrackedPerson& p = people_->items[i];
        if (p.hidden || std::hypot(p.vx_m_s, p.vy_m_s) < walking) continue;
        const double dt = static_cast<double>(scan.stamp_ns() - people_->stamp_ns) * 1e-9;
        vouches[n++] = {p.x_m + p.vx_m_s * dt, p.y_m + p.vy_m_s * dt, p.vx_m_s, p.vy_m_s};
      }
      vouched_ += tracker_.vouch(std::span<const Vouch>(vouches.data(), n));
    }
    turn_back_at_walls(scan.stamp_ns());
  }
  for (const DolTrack& track : tracker_.tracks()) {
    if (!tracker_.moving(track) || !track.x.allFinite()) continue;
    const Vector2 p = MoverTracker::predict_position(track, inputs.now_ns);
    const Vector2 v = tracker_.velocity(track);
    if (v.norm() >= config_.cost.min_speed_m_s) {
      paint_mover(config_.cost, p(0), p(1), v(0), v(1), master);
    }
    paint_core(p(0), p(1), config_.cost.lethal_radius_m, master);
  }
}

void DynamicObstacleLayer::movers(hal::Nanos stamp_ns, msg::MovingObstacles& out) const noexcept {
  out.count = 0;
  out.candidate_count = 0;
  out.stamp_ns = stamp_ns;
  if (!active_) return;
  for (const DolTrack& track : tracker_.tracks()) {
    if (!tracker_.moving(track) || !track.x.allFinite()) continue;
    if (out.count >= msg::MovingObstacles::kMax) break;
    put(track, stamp_ns, out.items[out.count++]);
  }
  for (const DolTrack& track : tracker_.tracks()) {
    if (!tracker_.candidate(track) || !track.x.allFinite()) continue;
    if (out.count + out.candidate_count >= msg::MovingObstacles::kMax) break;
    put(track, stamp_ns, out.items[out.count + out.candidate_count++]);
  }
}

void DynamicObstacleLayer::put(const DolTrack& track, hal::Nanos stamp_ns, msg::MovingObstacle& m) const noexcept {
  const DolTrack at = tracker_.predicted(track, stamp_ns);
  m.id = track.id;
  m.x_m = at.x(0);
  m.y_m = at.x(1);
  const Vector2 v = tracker_.velocity(at);
  m.vx_m_s = v(0);
  m.vy_m_s = v(1);
  m.radius_m = track.radius_m;
  m.position_var_m2 = (at.P(0, 0) + at.P(1, 1)) / 2.0;
  m.velocity_var_m2_s2 = (at.P(2, 2) + at.P(3, 3)) / 2.0;
}

}  // namespace sen3bot::nav
