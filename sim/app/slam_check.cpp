#include "slam_check.hpp"

#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <fstream>
#include <iterator>
#include <limits>
#include <memory>
#include <sstream>
#include <tuple>

#include "cli_util.hpp"
#include "sen3bot/figure/map_figure.hpp"
#include "sen3bot/slam/carmen.hpp"

namespace sen3bot::sim::slam_check {

namespace {

// The pair grid: scan i's returns reach kMaxRangeM from its origin, scan j's from up to
// max_distance + the window away; 51.2 m a side holds both.
constexpr int kPairGridSide = 1024;
constexpr double kRadToDeg = 180.0 / std::numbers::pi;
constexpr int kMapMarginCells = 10;
constexpr int kMaxGridSide = 8192;  // BuildGrid's largest
constexpr double kMaxMapExtentM = 100000.0;  // a map wider is a broken trajectory, not a building

constexpr double kMaxPlotPx = 1000.0;
constexpr figure::Rgb kTrajectoryColour{220, 0, 0};
constexpr figure::Rgb kStartColour{0, 150, 150};
constexpr figure::Rgb kSubtitleColour{90, 90, 90};

std::vector<std::string_view> split_fields(std::string_view line) {
  std::vector<std::string_view> fields;
  std::size_t at = 0;
  while (at < line.size()) {
    while (at < line.size() && (line[at] == ' ' || line[at] == '\t' || line[at] == '\r')) ++at;
    const std::size_t start = at;
    while (at < line.size() && line[at] != ' ' && line[at] != '\t' && line[at] != '\r') ++at;
    if (at > start) fields.push_back(line.substr(start, at - start));
  }
  return fields;
}

}  // namespace

std::vector<slam::PointF> robot_points(const slam::LaserRecord& record) {
  std::vector<slam::PointF> points;
  const double far = std::min(kMaxRangeM, record.max_range_m > 0.0 ? record.max_range_m : kMaxRangeM);
  const double mc = std::cos(record.laser_mount.theta_rad);
  const double ms = std::sin(record.laser_mount.theta_rad);
  const std::uint32_t count = std::min<std::uint32_t>(record.count, static_cast<std::uint32_t>(slam::kMaxBeams));
  points.reserve(count);
  for (std::uint32_t i = 0; i < count; ++i) {
    const double r = record.ranges[i];
    if (!(r > kMinRangeM && r < far)) continue;
    const double a = record.start_angle_rad + i * record.angle_increment_rad;
    const double lx = r * std::cos(a);
    const double ly = r * std::sin(a);
    points.push_back({static_cast<float>(record.laser_mount.x_m + mc * lx - ms * ly),
                      static_cast<float>(record.laser_mount.y_m + ms * lx + mc * ly)});
  }
  return points;
}

Result<std::vector<Scan>> read_log(const std::string& path) {
  Result<slam::CarmenReader> reader = slam::CarmenReader::open(path);
  if (!reader) return reader.error();
  auto record = std::make_unique<slam::LaserRecord>();  // 4 KiB of ranges: not on the stack
  std::vector<Scan> scans;
  for (;;) {
    Result<bool> more = reader->next(*record);
    if (!more) return more.error();
    if (!*more) break;
    scans.push_back({record->odometry, record->laser_mount, robot_points(*record)});
  }
  return scans;
}

Result<std::vector<nav::Pose2D>> parse_poses(std::string_view text, std::string_view source) {
  std::vector<nav::Pose2D> poses;
  const int name_len = static_cast<int>(std::min<std::size_t>(source.size(), 160));
  std::uint64_t line_number = 0;
  while (!text.empty()) {
    const std::size_t eol = text.find('\n');
    const std::string_view line = text.substr(0, eol);
    text.remove_prefix(eol == std::string_view::npos ? text.size() : eol + 1);
    ++line_number;
    const std::vector<std::string_view> fields = split_fields(line);
    if (fields.empty() || fields[0].front() == '#') continue;
    const auto bad = [&](const char* what) {
      return Error::format(Errc::protocol, "%.*s:%llu: %s", name_len, source.data(),
                           static_cast<unsigned long long>(line_number), what);
    };
    if (fields.size() != 4) {
      char what[96];
      std::snprintf(what, sizeof what, "expected 'index x y theta', got %zu field%s", fields.size(),
                    fields.size() == 1 ? "" : "s");
      return bad(what);
    }
    std::uint64_t index = 0;
    if (!firmware::parse_u64(fields[0], index)) return bad("the index is not a whole number");
    if (index != poses.size()) {
      char what[96];
      std::snprintf(what, sizeof what, "expected index %zu (one line per scan, in order), got %llu", poses.size(),
                    static_cast<unsigned long long>(index));
      return bad(what);
    }
    nav::Pose2D p;
    if (!firmware::parse_double(fields[1], p.x_m)) return bad("x is not a finite number");
    if (!firmware::parse_double(fields[2], p.y_m)) return bad("y is not a finite number");
    if (!firmware::parse_double(fields[3], p.theta_rad)) return bad("theta is not a finite number");
    poses.push_back(p);
  }
  return poses;
}

Result<std::vector<nav::Pose2D>> read_poses(const std::string& path) {
  struct stat st {};
  if (::stat(path.c_str(), &st) == 0 && S_ISDIR(st.st_mode))
    return Error::format(Errc::invalid_argument, "%s: is a directory", path.c_str());
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error::format(Errc::not_found, "%s: cannot open (%s)", path.c_str(), std::strerror(errno));
  std::ostringstream text;
  text << in.rdbuf();
  if (in.bad()) return Error::format(Errc::io, "%s: read failed", path.c_str());
  return parse_poses(text.str(), path);
}

std::vector<nav::Pose2D> odometry_poses(std::span<const Scan> scans) {
  std::vector<nav::Pose2D> poses;
  poses.reserve(scans.size());
  for (const Scan& s : scans) poses.push_back(nav::relative_pose(scans.front().odometry, s.odometry));
  return poses;
}

std::vector<ScanPair> choose_pairs(std::span<const nav::Pose2D> poses, const PairOptions& options) {
  std::vector<ScanPair> pairs;
  const std::size_t n = poses.size();
  const std::size_t stride = std::max<std::size_t>(options.stride, 1);
  const std::size_t gap = std::max<std::size_t>(options.min_gap, 1);
  for (std::size_t block = 0; block < n; block += stride) {
    bool found = false;
    ScanPair best;
    double best_d = 0.0, best_a = 0.0;
    for (std::size_t i = block; i < std::min(block + stride, n); ++i) {
      if (n - i <= gap) break;  // no j far enough in time, here or later in the block
      for (std::size_t j = i + gap; j < n; ++j) {
        const double d = std::hypot(poses[j].x_m - poses[i].x_m, poses[j].y_m - poses[i].y_m);
        const double a = std::abs(nav::normalize_angle(poses[j].theta_rad - poses[i].theta_rad));
        if (!(d <= options.max_distance_m) || !(a <= options.max_angle_rad)) continue;
        // The scans visited in order of i then j: ties stay with the first found.
        if (!found || std::tie(d, a) < std::tie(best_d, best_a)) {
          found = true;
          best = {i, j};
          best_d = d;
          best_a = a;
        }
      }
    }
    if (found) pairs.push_back(best);
  }
  return pairs;
}

PairChecker::PairChecker()
    : memory_(slam::BuildGrid::bytes_for(kPairGridSide) + slam::kMaxBeams * 2 * sizeof(int) + 129 * 129 * sizeof(float) +
              1024),
      arena_(memory_.data(), memory_.size(), std::pmr::null_memory_resource()) {
  slam::LocalMatchConfig config;
  config.linear_window_m = kMatchWindowM;
  config.angular_window_rad = kMatchWindowRad;
  ready_ = grid_.init(arena_, kPairGridSide, kResolutionM, kPairOdds).ok() &&
           matcher_.init(arena_, slam::kMaxBeams, config).ok();
}

PairCheck PairChecker::check(const Scan& a, const Scan& b, const nav::Pose2D& relative) noexcept {
  PairCheck c;
  c.relative = relative;
  c.matched = relative;
  // A relative pose off the grid cannot overlap scan a (and would overflow its cell indices).
  const bool on_grid = std::isfinite(relative.theta_rad) &&
                       std::hypot(relative.x_m, relative.y_m) < 0.5 * kPairGridSide * kResolutionM;
  if (!ready_ || a.points.empty() || b.points.empty() || !on_grid) return c;
  grid_.reset();
  const slam::PointF sensor{static_cast<float>(a.mount.x_m), static_cast<float>(a.mount.y_m)};
  for (int k = 0; k < kInsertions; ++k) grid_.insert(sensor, a.points);
  const slam::Match m = matcher_.match(grid_.view(), relative, b.points);
  c.matched = m.pose;
  c.score = m.score;
  c.matched_ok = m.score >= kMinScore;
  c.translation_m = std::hypot(m.pose.x_m - relative.x_m, m.pose.y_m - relative.y_m);
  const double turn = nav::normalize_angle(m.pose.theta_rad - relative.theta_rad);
  c.rotation_deg = std::abs(turn) * kRadToDeg;
  c.at_window_edge = std::max(std::abs(m.pose.x_m - relative.x_m), std::abs(m.pose.y_m - relative.y_m)) >
                         kMatchWindowM - 0.5 * kResolutionM ||
                     std::abs(turn) > kMatchWindowRad - 0.25 / kRadToDeg;
  return c;
}

PairCheck check_pair(PairChecker& checker, std::span<const Scan> scans, std::span<const nav::Pose2D> poses,
                     const ScanPair& pair) noexcept {
  PairCheck c = checker.check(scans[pair.i], scans[pair.j], nav::relative_pose(poses[pair.i], poses[pair.j]));
  c.pair = pair;
  return c;
}

double quantile(std::vector<double> values, double q) {
  if (values.empty()) return std::numeric_limits<double>::quiet_NaN();
  std::sort(values.begin(), values.end());
  const double at = std::clamp(q, 0.0, 1.0) * static_cast<double>(values.size() - 1);
  const auto lo = static_cast<std::size_t>(std::floor(at));
  const std::size_t hi = std::min(lo + 1, values.size() - 1);
  const double w = at - static_cast<double>(lo);
  return values[lo] + w * (values[hi] - values[lo]);
}

Summary summarise(std::span<const PairCheck> checks) {
  Summary s;
  s.pairs = checks.size();
  std::vector<double> t, r, scores;
  for (const PairCheck& c : checks) {
    scores.push_back(c.score);
    if (!c.matched_ok) continue;
    t.push_back(c.translation_m);
    r.push_back(c.rotation_deg);
    s.matched_at_window_edge += c.at_window_edge ? 1 : 0;
  }
  s.matched = t.size();
  s.score_median = quantile(scores, 0.5);
  const auto stats = [](const std::vector<double>& v) {
    Stats st;
    double sum = 0.0;
    for (double x : v) sum += x;
    st.mean = v.empty() ? std::numeric_limits<double>::quiet_NaN() : sum / static_cast<double>(v.size());
    st.median = quantile(v, 0.5);
    st.p95 = quantile(v, 0.95);
    return st;
  };
  s.translation_m = stats(t);
  s.rotation_deg = stats(r);
  return s;
}

double score_ceiling() noexcept {
  const slam::InsertionConfig insertion = kPairOdds;
  const double log_odds = kInsertions * std::log(insertion.hit_probability / (1.0 - insertion.hit_probability));
  return 1.0 / (1.0 + std::exp(-log_odds));
}

Result<MapGrid> render_map(std::span<const Scan> scans, std::span<const nav::Pose2D> poses, double resolution_m) {
  if (scans.empty() || scans.size() != poses.size() || !(resolution_m > 0.0))
    return Error(Errc::invalid_argument, "map: no scans, no resolution, or not a pose per scan");
  double min_x = 1e300, min_y = 1e300, max_x = -1e300, max_y = -1e300;
  const auto extend = [&](double x, double y) {
    min_x = std::min(min_x, x);
    max_x = std::max(max_x, x);
    min_y = std::min(min_y, y);
    max_y = std::max(max_y, y);
  };
  for (std::size_t i = 0; i < scans.size(); ++i) {
    const nav::Pose2D& p = poses[i];
    if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m) || !std::isfinite(p.theta_rad))
      return Error::format(Errc::invalid_argument, "map: pose %zu is not finite", i);
    const double c = std::cos(p.theta_rad), s = std::sin(p.theta_rad);
    for (const slam::PointF& q : scans[i].points) extend(p.x_m + c * q.x - s * q.y, p.y_m + s * q.x + c * q.y);
    extend(p.x_m, p.y_m);
  }
  // Cells: the extent and a margin; coarser cells when BuildGrid's largest side would not hold it.
  const double extent = std::max(max_x - min_x, max_y - min_y);
  if (!(extent < kMaxMapExtentM))
    return Error::format(Errc::invalid_argument, "map: the poses and returns spread over more than %.0f km",
                         kMaxMapExtentM / 1000.0);
  double res = resolution_m;
  while (std::ceil(extent / res) + 2 * kMapMarginCells + 2 > kMaxGridSide) res *= 2.0;
  const int side = std::max(16, static_cast<int>(std::ceil(extent / res)) + 2 * kMapMarginCells + 2);
  const double cx = 0.5 * (min_x + max_x), cy = 0.5 * (min_y + max_y);
  std::vector<std::byte> memory(slam::BuildGrid::bytes_for(side) + 256);
  std::pmr::monotonic_buffer_resource arena(memory.data(), memory.size(), std::pmr::null_memory_resource());
  slam::BuildGrid grid;
  if (Status st = grid.init(arena, side, res, slam::InsertionConfig{}); !st) return st.error();
  std::vector<slam::PointF> hits;
  for (std::size_t i = 0; i < scans.size(); ++i) {
    const nav::Pose2D& p = poses[i];
    const nav::Pose2D sensor = nav::apply_motion(p, scans[i].mount);
    const double c = std::cos(p.theta_rad), s = std::sin(p.theta_rad);
    hits.clear();
    for (const slam::PointF& q : scans[i].points)
      hits.push_back({static_cast<float>(p.x_m + c * q.x - s * q.y - cx), static_cast<float>(p.y_m + s * q.x + c * q.y - cy)});
    grid.insert({static_cast<float>(sensor.x_m - cx), static_cast<float>(sensor.y_m - cy)}, hits);
  }
  const slam::ProbabilityView v = grid.view();
  // The known cells and the poses, with the margin, inside the grid.
  slam::BuildGrid::Bounds b = grid.known_bounds();
  for (const nav::Pose2D& p : poses) {
    const int col = static_cast<int>(std::floor(v.grid_x(p.x_m - cx)));
    const int row = static_cast<int>(std::floor(v.grid_y(p.y_m - cy)));
    if (b.empty()) b = {col, row, col, row};
    b.min_col = std::min(b.min_col, col);
    b.max_col = std::max(b.max_col, col);
    b.min_row = std::min(b.min_row, row);
    b.max_row = std::max(b.max_row, row);
  }
  const int c0 = std::max(0, b.min_col - kMapMarginCells), c1 = std::min(side - 1, b.max_col + kMapMarginCells);
  const int r0 = std::max(0, b.min_row - kMapMarginCells), r1 = std::min(side - 1, b.max_row + kMapMarginCells);
  MapGrid map;
  map.width = c1 - c0 + 1;
  map.height = r1 - r0 + 1;
  map.resolution_m = res;
  map.origin_x_m = v.origin_x_m + cx + c0 * res;
  map.origin_y_m = v.origin_y_m + cy + r0 * res;
  map.cells.resize(static_cast<std::size_t>(map.width) * static_cast<std::size_t>(map.height));
  const auto& table = slam::probability_table();
  for (int r = r0; r <= r1; ++r)
    for (int c = c0; c <= c1; ++c) {
      const std::uint8_t byte = v.byte(c, r);
      map.cells[static_cast<std::size_t>(r - r0) * static_cast<std::size_t>(map.width) + static_cast<std::size_t>(c - c0)] =
          byte == 0 ? std::int8_t{-1} : static_cast<std::int8_t>(std::lround(100.0 * table[byte]));
    }
  return map;
}

namespace {

// Cells smaller than a pixel: blocks of k x k cells, a wall where any cell is one, else free
// where any is known, else unknown (draw_grid would drop the cells that round to no pixel).
MapGrid pooled_for_drawing(const MapGrid& m, int k) {
  MapGrid p;
  p.width = (m.width + k - 1) / k;
  p.height = (m.height + k - 1) / k;
  p.resolution_m = m.resolution_m * k;
  p.origin_x_m = m.origin_x_m;
  p.origin_y_m = m.origin_y_m;
  p.cells.assign(static_cast<std::size_t>(p.width) * static_cast<std::size_t>(p.height), std::int8_t{-1});
  for (int r = 0; r < m.height; ++r)
    for (int c = 0; c < m.width; ++c) {
      const auto at = [](int row, int col, int width) {
        return static_cast<std::size_t>(row) * static_cast<std::size_t>(width) + static_cast<std::size_t>(col);
      };
      const std::int8_t v = m.cells[at(r, c, m.width)];
      std::int8_t& out = p.cells[at(r / k, c / k, p.width)];
      if (v >= 50 ? out < 50 : (v >= 0 && out < 0)) out = v;
    }
  return p;
}

}  // namespace

figure::Canvas draw_map_figure(const MapFigure& f) {
  using namespace figure;
  using namespace figure::colours;
  const MapGrid& fine = *f.map;
  // The project's scale, or up to 2 px a cell while the plot stays within kMaxPlotPx: a map of
  // a building is read for its doubled walls.
  const Grid fine_grid{fine.width, fine.height, fine.resolution_m, fine.origin_x_m, fine.origin_y_m, fine.cells};
  const double extent_m = std::max(fine_grid.width_m(), fine_grid.height_m());
  const double scale = std::max(figure_scale(fine_grid), std::min(2.0 / fine.resolution_m, kMaxPlotPx / extent_m));
  const int k = static_cast<int>(std::ceil(1.0 / (scale * fine.resolution_m) - 1e-9));
  MapGrid pooled;
  if (k > 1) pooled = pooled_for_drawing(fine, k);
  const MapGrid& m = k > 1 ? pooled : fine;
  const Grid grid{m.width, m.height, m.resolution_m, m.origin_x_m, m.origin_y_m, m.cells};
  // The header: the title, then what the check found; room for "y (m)" above the plot.
  const int title_y = kMargin + Canvas::text_height(kTitleSize, 2);
  const int subtitle_y = title_y + 8 + Canvas::text_height(kLineSize);
  const int plot_top = subtitle_y + 34;
  const int map_w = static_cast<int>(std::lround(grid.width_m() * scale));
  const int map_h = static_cast<int>(std::lround(grid.height_m() * scale));
  const int plot_left = kMargin + kAxisLeft;
  const View view{grid.origin_x_m, grid.origin_y_m, scale, static_cast<double>(plot_left),
                  static_cast<double>(plot_top + map_h)};

  std::vector<LegendEntry> legend;
  legend.push_back({"walls (p >= 0.5)", [](Canvas& c, Px p) {
                      c.fill_rect(static_cast<int>(p.x) - 12, static_cast<int>(p.y) - 6, 24, 12, kWall);
                    }});
  legend.push_back({"free", [](Canvas& c, Px p) {
                      const std::vector<Px> box{
                          {p.x - 12, p.y - 6}, {p.x + 12, p.y - 6}, {p.x + 12, p.y + 6}, {p.x - 12, p.y + 6}};
                      c.outline_polygon(box, kInk, 1);
                    }});
  if (has_unknown(grid))
    legend.push_back({"unknown", [](Canvas& c, Px p) {
                        c.fill_rect(static_cast<int>(p.x) - 12, static_cast<int>(p.y) - 6, 24, 12, kUnknown);
                      }});
  legend.push_back({"trajectory", [](Canvas& c, Px p) {
                      c.line({p.x - 12, p.y}, {p.x + 12, p.y}, kTrajectoryColour, 2);
                    }});
  legend.push_back({"start", [](Canvas& c, Px p) { c.ring(p, 6, kStartColour, 2); }});

  const int legend_x = plot_left + map_w + kLegendGap;
  const int header_w = std::max(Canvas::text_width(f.title, kTitleSize, 2), Canvas::text_width(f.subtitle, kLineSize));
  // The scale bar under the legend reaches past the entries when it is long: "scale", the bar, its label.
  const int bar_w = 52 + static_cast<int>(std::lround(scale_bar_length_m(scale) * scale)) + 24;
  const int width = std::max(legend_x + std::max(legend_width(legend), bar_w) + kMargin, kMargin + header_w + kMargin);
  const int height = std::max(plot_top + map_h + kAxisBottom, plot_top + legend_height(legend)) + kMargin / 2;
  Canvas canvas(width, height, kPaper);
  canvas.text({kMargin, static_cast<double>(title_y)}, f.title, kInk, kTitleSize, 2);
  canvas.text({kMargin, static_cast<double>(subtitle_y)}, f.subtitle, kSubtitleColour, kLineSize);

  draw_grid(canvas, view, grid);
  std::vector<Px> line;
  line.reserve(f.trajectory.size());
  for (const nav::Pose2D& p : f.trajectory) line.push_back(view(p.x_m, p.y_m));
  canvas.polyline(line, kTrajectoryColour, 1);
  if (!line.empty()) canvas.ring(line.front(), 6, kStartColour, 2);

  draw_axes(canvas, view, grid, plot_left, plot_top, map_w, map_h);
  draw_legend(canvas, legend_x, plot_top, legend, view.px_per_m);
  return canvas;
}

}  // namespace sen3bot::sim::slam_check
