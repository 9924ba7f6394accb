#include "sen3bot/slam/branch_bound.hpp"

#include <algorithm>
#include <cmath>

#include "sen3bot/nav/arena.hpp"

namespace sen3bot::slam {
namespace {

constexpr int kMaxAngles = 721;

}  // namespace

Status BranchBound::init(std::pmr::memory_resource& arena, int max_cells_side, std::size_t max_points,
                         double resolution_m, const LoopSearchConfig& config) {
  if (config.depth < 1 || config.depth > 10 || !(config.linear_window_m >= 0.0) ||
      !(config.angular_window_rad >= 0.0) || max_cells_side < 1 || !(resolution_m > 0.0))
    return Error(Errc::invalid_argument, "loop search: depth 1..10, windows not negative, a grid of at least a cell");
  config_ = config;
  resolution_m_ = resolution_m;
  max_side_ = max_cells_side;
  pad_ = (1 << config.depth) - 1;
  max_points_ = max_points;
  max_angles_ = kMaxAngles;
  window_cells_ = static_cast<int>(std::ceil(config.linear_window_m / resolution_m));
  const int step = 1 << config.depth;
  const auto per_axis = static_cast<std::size_t>((2 * window_cells_) / step + 1);
  const auto side = static_cast<std::size_t>(max_cells_side + pad_);
  return nav::guarded("loop search", [&]() -> Status {
    levels_ = nav::allocate_array<std::uint8_t>(arena, side * side * static_cast<std::size_t>(config.depth + 1));
    cols_ = nav::allocate_array<int>(arena, max_points * kMaxAngles);
    rows_ = nav::allocate_array<int>(arena, max_points * kMaxAngles);
    top_ = nav::allocate_array<Candidate>(arena, per_axis * per_axis * kMaxAngles);
    return {};
  });
}

Status BranchBound::prepare(const ProbabilityView& submap) noexcept {
  if (submap.width > max_side_ || submap.height > max_side_)
    return Error::format(Errc::capacity, "loop search: a submap of %d x %d cells is larger than %d a side", submap.width,
                         submap.height, max_side_);
  submap_ = submap;
  width_ = submap.width;
  height_ = submap.height;
  stride_ = width_ + pad_;
  level_size_ = static_cast<std::size_t>(stride_) * static_cast<std::size_t>(height_ + pad_);
  std::uint8_t* base = levels_.data();
  std::fill(base, base + level_size_, std::uint8_t{1});
  for (int r = 0; r < height_; ++r)
    for (int c = 0; c < width_; ++c)
      base[static_cast<std::size_t>(r + pad_) * static_cast<std::size_t>(stride_) + static_cast<std::size_t>(c + pad_)] =
          std::max(submap.byte(c, r), std::uint8_t{1});
  // Level k holds, at (c, r), the best byte of the 2^k-cell square whose lower-left cell is (c, r):
  // the best of two level k-1 squares side by side, then of two such pairs one above the other.
  // Cells past the grid's far edges hold unknown (1).
  const auto rows = static_cast<std::size_t>(height_ + pad_);
  const auto cols = static_cast<std::size_t>(stride_);
  for (int k = 1; k <= config_.depth; ++k) {
    const std::uint8_t* below = base + static_cast<std::size_t>(k - 1) * level_size_;
    std::uint8_t* level = base + static_cast<std::size_t>(k) * level_size_;
    const auto h = static_cast<std::size_t>(1) << (k - 1);
    for (std::size_t r = 0; r < rows; ++r) {
      const std::uint8_t* in = below + r * cols;
      std::uint8_t* out = level + r * cols;
      const std::size_t split = cols > h ? cols - h : 0;
      for (std::size_t c = 0; c < split; ++c) out[c] = std::max(in[c], in[c + h]);
      for (std::size_t c = split; c < cols; ++c) out[c] = std::max(in[c], std::uint8_t{1});
    }
    for (std::size_t r = 0; r < rows; ++r) {
      std::uint8_t* out = level + r * cols;
      if (r + h < rows) {
        const std::uint8_t* up = level + (r + h) * cols;
        for (std::size_t c = 0; c < cols; ++c) out[c] = std::max(out[c], up[c]);
      }
    }
  }
  return {};
}

std::uint8_t BranchBound::level_byte(int level, int col, int row) const noexcept {
  const int c = col + pad_;
  const int r = row + pad_;
  if (level < 0 || level > config_.depth || c < 0 || r < 0 || c >= stride_ || r >= height_ + pad_) return 1;
  return levels_[static_cast<std::size_t>(level) * level_size_ + static_cast<std::size_t>(r) * static_cast<std::size_t>(stride_) +
                 static_cast<std::size_t>(c)];
}

// Bytes are probabilities on a line (byte 1 = kMinProbability, 255 = kMaxProbability; the levels
// hold unknown cells as 1), so a mean of bytes is a mean of probabilities, summed as integers.
float BranchBound::bound(int level, const Candidate& c) const noexcept {
  const std::uint8_t* cells = levels_.data() + static_cast<std::size_t>(level) * level_size_;
  const int* cols = cols_.data() + static_cast<std::size_t>(c.angle) * max_points_;
  const int* rows = rows_.data() + static_cast<std::size_t>(c.angle) * max_points_;
  const int rows_total = height_ + pad_;
  std::uint32_t sum = 0;
  for (std::size_t i = 0; i < points_; ++i) {
    const int col = cols[i] + c.dx + pad_;
    const int row = rows[i] + c.dy + pad_;
    const bool inside = static_cast<unsigned>(col) < static_cast<unsigned>(stride_) &&
                        static_cast<unsigned>(row) < static_cast<unsigned>(rows_total);
    sum += inside ? cells[static_cast<std::size_t>(row) * static_cast<std::size_t>(stride_) + static_cast<std::size_t>(col)]
                  : 1u;
  }
  const double mean_byte = static_cast<double>(sum) / static_cast<double>(points_);
  return static_cast<float>(kMinProbability + (kMaxProbability - kMinProbability) * (mean_byte - 1.0) / 254.0);
}

nav::Pose2D BranchBound::pose_of(const Candidate& c, const nav::Pose2D& guess) const noexcept {
  return {guess.x_m + c.dx * resolution_m_, guess.y_m + c.dy * resolution_m_,
          nav::normalize_angle(guess.theta_rad + (c.angle - angle_count_ / 2) * angle_step_)};
}

void BranchBound::descend(int level, const Candidate& c, double min_score, Candidate& best, const Exclusion* exclusion,
                          const nav::Pose2D& guess) noexcept {
  if (level == 0) {
    if (exclusion != nullptr) {
      const nav::Pose2D p = pose_of(c, guess);
      if (std::hypot(p.x_m - exclusion->centre.x_m, p.y_m - exclusion->centre.y_m) < exclusion->radius_m &&
          std::abs(nav::normalize_angle(p.theta_rad - exclusion->centre.theta_rad)) < exclusion->angle_rad)
        return;
    }
    if (c.score > best.score) best = c;
    return;
  }
  const int h = 1 << (level - 1);
  Candidate children[4];
  int n = 0;
  for (int j = 0; j < 2; ++j)
    for (int i = 0; i < 2; ++i) {
      Candidate child{c.angle, c.dx + i * h, c.dy + j * h, 0.0F};
      if (child.dx > window_cells_ || child.dy > window_cells_) continue;
      child.score = bound(level - 1, child);
      ++scored_;
      children[n++] = child;
    }
  for (int i = 1; i < n; ++i)  // best first (four at most)
    for (int j = i; j > 0 && children[j].score > children[j - 1].score; --j) std::swap(children[j], children[j - 1]);
  for (int i = 0; i < n; ++i) {
    if (children[i].score <= best.score || children[i].score < min_score) break;
    descend(level - 1, children[i], min_score, best, exclusion, guess);
  }
}

std::optional<Match> BranchBound::search(const nav::Pose2D& guess, std::span<const PointF> points, double min_score,
                                         const Exclusion* exclusion) noexcept {
  scored_ = 0;
  // Every stride-th point: the search only has to find the basin; the refinement after it
  // uses them all.
  const std::size_t wanted = std::min(max_points_, static_cast<std::size_t>(std::max(config_.search_points, 1)));
  const std::size_t stride = (points.size() + wanted - 1) / std::max<std::size_t>(wanted, 1);
  points_ = stride == 0 ? 0 : (points.size() + stride - 1) / stride;
  if (points_ == 0 || width_ == 0) return std::nullopt;
  double range = 0.0;
  for (const PointF& q : points) range = std::max(range, std::hypot(static_cast<double>(q.x), static_cast<double>(q.y)));
  angle_step_ = angular_step(resolution_m_, std::min(range, config_.angle_step_range_m));
  int half = static_cast<int>(std::ceil(config_.angular_window_rad / angle_step_));
  if (2 * half + 1 > max_angles_) {
    half = (max_angles_ - 1) / 2;
    angle_step_ = config_.angular_window_rad / std::max(half, 1);
  }
  angle_count_ = 2 * half + 1;
  for (int a = 0; a < angle_count_; ++a) {
    const double th = guess.theta_rad + (a - half) * angle_step_;
    const double c = std::cos(th);
    const double s = std::sin(th);
    int* cols = cols_.data() + static_cast<std::size_t>(a) * max_points_;
    int* rows = rows_.data() + static_cast<std::size_t>(a) * max_points_;
    for (std::size_t i = 0; i < points_; ++i) {
      const PointF& q = points[i * stride];
      cols[i] = static_cast<int>(std::floor(submap_.grid_x(guess.x_m + c * q.x - s * q.y)));
      rows[i] = static_cast<int>(std::floor(submap_.grid_y(guess.y_m + s * q.x + c * q.y)));
    }
  }
  const int step = 1 << config_.depth;
  std::size_t n = 0;
  for (int a = 0; a < angle_count_; ++a)
    for (int dy = -window_cells_; dy <= window_cells_; dy += step)
      for (int dx = -window_cells_; dx <= window_cells_; dx += step) {
        Candidate c{a, dx, dy, 0.0F};
        c.score = bound(config_.depth, c);
        ++scored_;
        if (c.score >= min_score && n < top_.size()) top_[n++] = c;
      }
  std::sort(top_.begin(), top_.begin() + static_cast<std::ptrdiff_t>(n),
            [](const Candidate& a, const Candidate& b) { return a.score > b.score; });
  Candidate best{0, 0, 0, static_cast<float>(min_score) - 1e-6F};
  bool found = false;
  for (std::size_t i = 0; i < n; ++i) {
    if (top_[i].score <= best.score) break;
    const float before = best.score;
    descend(config_.depth, top_[i], min_score, best, exclusion, guess);
    found = found || best.score > before;
  }
  if (!found) return std::nullopt;
  return Match{pose_of(best, guess), best.score};
}

}  // namespace sen3bot::slam
