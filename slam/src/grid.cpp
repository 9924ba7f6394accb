#include "sen3bot/slam/grid.hpp"

#include <algorithm>
#include <cstdlib>
#include <limits>
#include <new>

#include "sen3bot/nav/arena.hpp"
#include "sen3bot/nav/grid_geometry.hpp"

namespace sen3bot::slam {
namespace {

// Log-odds in thousandths: logit(0.9) = 2.197.
constexpr double kLogOddsScale = 1000.0;
constexpr int kKeepBeforeHit = 3;
constexpr std::int16_t kUnknownLogOdds = std::numeric_limits<std::int16_t>::min();
const std::int16_t kMaxLogOdds =
    static_cast<std::int16_t>(std::lround(std::log(kMaxProbability / (1.0 - kMaxProbability)) * kLogOddsScale));

std::int16_t log_odds_of(double p) noexcept {
  return static_cast<std::int16_t>(std::lround(std::log(p / (1.0 - p)) * kLogOddsScale));
}

}  // namespace

const std::array<float, 256>& probability_table() noexcept {
  static const std::array<float, 256> table = [] {
    std::array<float, 256> t{};
    t[0] = static_cast<float>(kMinProbability);
    for (int b = 1; b < 256; ++b)
      t[static_cast<std::size_t>(b)] =
          static_cast<float>(kMinProbability + (kMaxProbability - kMinProbability) * (b - 1) / 254.0);
    return t;
  }();
  return table;
}

std::uint8_t probability_byte(double p) noexcept {
  const double q = std::clamp((p - kMinProbability) / (kMaxProbability - kMinProbability), 0.0, 1.0);
  return static_cast<std::uint8_t>(1 + std::lround(q * 254.0));
}

std::size_t BuildGrid::bytes_for(int side) noexcept {
  const auto cells = static_cast<std::size_t>(side) * static_cast<std::size_t>(side);
  return cells * (sizeof(std::int16_t) + sizeof(std::uint8_t) + sizeof(std::uint16_t)) + 64;
}

Status BuildGrid::init(std::pmr::memory_resource& arena, int side, double resolution_m, const InsertionConfig& config) {
  if (side < 16 || side > 8192 || !(resolution_m > 0.0) || !std::isfinite(resolution_m))
    return Error::format(Errc::invalid_argument, "submap grid: side %d cells at %g m is not a grid", side, resolution_m);
  if (!(config.hit_probability > 0.5 && config.hit_probability < 1.0 && config.miss_probability > 0.0 &&
        config.miss_probability < 0.5))
    return Error(Errc::invalid_argument, "submap grid: a hit must raise a cell (0.5 < p < 1), a miss lower it (0 < p < 0.5)");
  side_ = side;
  resolution_m_ = resolution_m;
  hit_delta_ = log_odds_of(config.hit_probability);
  miss_delta_ = log_odds_of(config.miss_probability);
  const auto cells = static_cast<std::size_t>(side) * static_cast<std::size_t>(side);
  return nav::guarded("submap grid", [&]() -> Status {
    log_odds_ = nav::allocate_array<std::int16_t>(arena, cells);
    bytes_ = nav::allocate_array<std::uint8_t>(arena, cells);
    marks_ = nav::allocate_array<std::uint16_t>(arena, cells);
    reset();
    return {};
  });
}

void BuildGrid::reset() noexcept {
  std::fill(log_odds_.begin(), log_odds_.end(), kUnknownLogOdds);
  std::fill(bytes_.begin(), bytes_.end(), std::uint8_t{0});
  std::fill(marks_.begin(), marks_.end(), std::uint16_t{0});
  mark_ = 0;
  bounds_ = {};
}

ProbabilityView BuildGrid::view() const noexcept {
  const double half = 0.5 * side_ * resolution_m_;
  return {bytes_.data(), side_, side_, resolution_m_, -half, -half};
}

void BuildGrid::update(std::size_t index, std::int16_t delta) noexcept {
  if (marks_[index] == mark_) return;
  marks_[index] = mark_;
  const int old = log_odds_[index] == kUnknownLogOdds ? 0 : log_odds_[index];
  const auto value = static_cast<std::int16_t>(std::clamp(old + delta, -static_cast<int>(kMaxLogOdds), static_cast<int>(kMaxLogOdds)));
  log_odds_[index] = value;
  bytes_[index] = probability_byte(1.0 / (1.0 + std::exp(-value / kLogOddsScale)));
  const int col = static_cast<int>(index % static_cast<std::size_t>(side_));
  const int row = static_cast<int>(index / static_cast<std::size_t>(side_));
  if (bounds_.empty()) {
    bounds_ = {col, row, col, row};
  } else {
    bounds_.min_col = std::min(bounds_.min_col, col);
    bounds_.max_col = std::max(bounds_.max_col, col);
    bounds_.min_row = std::min(bounds_.min_row, row);
    bounds_.max_row = std::max(bounds_.max_row, row);
  }
}

// From (c0, r0) up to, not including, (c1, r1); both are inside the grid.
void BuildGrid::ray(int c0, int r0, int c1, int r1) noexcept {
  // A wall cell among the last cells before the hit is left as it is: a ray that grazes a wall
  // crosses the wall's own cells just before it ends there, and clearing them would thin the
  // wall ahead of every scan (which pulls later scans back towards where the walls were seen
  // from). Free and unknown cells there are cleared as anywhere else.
  const int length = std::max(std::abs(c1 - c0), std::abs(r1 - r0));
  nav::walk_line(c0, r0, c1, r1, [&](int c, int r, int step) noexcept {
    const std::size_t index = static_cast<std::size_t>(r) * static_cast<std::size_t>(side_) + static_cast<std::size_t>(c);
    if (length - step > kKeepBeforeHit || log_odds_[index] <= 0) update(index, miss_delta_);
    return true;
  });
}

void BuildGrid::insert(const PointF& sensor, std::span<const PointF> hits) noexcept {
  if (++mark_ == 0) {  // the marks wrapped: none may look current
    std::fill(marks_.begin(), marks_.end(), std::uint16_t{0});
    mark_ = 1;
  }
  const ProbabilityView v = view();
  const auto cell = [&](const PointF& p, int& col, int& row) {
    col = static_cast<int>(std::floor(v.grid_x(p.x)));
    row = static_cast<int>(std::floor(v.grid_y(p.y)));
    return v.in_bounds(col, row);
  };
  int sc = 0;
  int sr = 0;
  if (!cell(sensor, sc, sr)) return;
  for (const PointF& h : hits) {
    int c = 0;
    int r = 0;
    if (cell(h, c, r))
      update(static_cast<std::size_t>(r) * static_cast<std::size_t>(side_) + static_cast<std::size_t>(c), hit_delta_);
  }
  for (const PointF& h : hits) {
    int c = 0;
    int r = 0;
    if (cell(h, c, r)) ray(sc, sr, c, r);
  }
}

Result<ProbabilityView> freeze(const BuildGrid& grid, std::pmr::memory_resource& arena) {
  const BuildGrid::Bounds b = grid.known_bounds();
  const ProbabilityView full = grid.view();
  if (b.empty()) return ProbabilityView{nullptr, 0, 0, full.resolution_m, 0.0, 0.0};
  const int w = b.max_col - b.min_col + 1;
  const int h = b.max_row - b.min_row + 1;
  std::span<std::uint8_t> cells;
  if (Status s = nav::guarded("finished submap", [&]() -> Status {
        cells = nav::allocate_array<std::uint8_t>(arena, static_cast<std::size_t>(w) * static_cast<std::size_t>(h));
        return {};
      });
      !s)
    return s.error();
  for (int r = 0; r < h; ++r)
    for (int c = 0; c < w; ++c)
      cells[static_cast<std::size_t>(r) * static_cast<std::size_t>(w) + static_cast<std::size_t>(c)] =
          full.byte(b.min_col + c, b.min_row + r);
  return ProbabilityView{cells.data(), w, h, full.resolution_m, full.origin_x_m + b.min_col * full.resolution_m,
                         full.origin_y_m + b.min_row * full.resolution_m};
}

}  // namespace sen3bot::slam
