#pragma once
// `sen3bot-sim slam-check`: how far a mapping trajectory agrees with itself where the robot came
// back to a place it had been long before. Pairs of scans (i, j) far apart in time whose poses
// under the trajectory are close are matched directly, scan j against a grid of scan i alone,
// starting from the trajectory's relative pose; the disagreement is how far the match moves
// from that start. No reference relations needed (the published relative-pose error wants
// hand-checked ones): this is self-consistency against an independent scan-to-scan match.
//
// The pure part: reading the log and the poses files, choosing pairs, matching them, the
// statistics, and the map figure drawn on a canvas. cmd_slam_check.cpp is the command.
#include <cstddef>
#include <cstdint>
#include <memory_resource>
#include <numbers>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "sen3bot/figure/canvas.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/nav/geometry.hpp"
#include "sen3bot/slam/grid.hpp"
#include "sen3bot/slam/laser_record.hpp"
#include "sen3bot/slam/scan_matcher.hpp"

namespace sen3bot::sim::slam_check {

inline constexpr std::size_t kDefaultMinGap = 200;       // scans between i and j at least
inline constexpr double kDefaultMaxDistanceM = 1.0;      // poses of a pair at most this far apart
inline constexpr double kMaxAngleRad = std::numbers::pi / 6.0;  // and this far turned (30 degrees)
inline constexpr std::size_t kPairStride = 10;           // at most one pair per this many scans of i
inline constexpr double kMinRangeM = 0.1;                // the returns used, as the mapper's
inline constexpr double kMaxRangeM = 20.0;
inline constexpr double kMatchWindowM = 0.3;             // the match's window around the trajectory's
inline constexpr double kMatchWindowRad = std::numbers::pi / 12.0;  // relative pose (15 degrees)
// Below: "not matched". A grid of one scan scores 0.646 at most (kScoreCeiling), neighbouring
// scans a median of 0.50; 0.4 keeps the pairs that overlap and drops those that do not.
inline constexpr double kMinScore = 0.4;
// The odds scan i's grid is built with: fixed here, so the check means the same whatever the
// mapper's own odds are (three hits at 0.55 give the 0.646 ceiling).
inline constexpr slam::InsertionConfig kPairOdds{0.55, 0.49};
inline constexpr int kInsertions = 3;                    // scan i goes into its grid this many times
inline constexpr double kResolutionM = 0.05;             // the pair grid's and the figure map's cells

// One scan as the check uses it: its odometry and its returns in the robot frame (the laser
// mount applied), kMinRangeM..kMaxRangeM.
struct Scan {
  nav::Pose2D odometry;
  nav::Pose2D mount;  // the scanner in the robot frame: where the rays start
  std::vector<slam::PointF> points;
};

// The returns of a record in the robot frame, kMinRangeM < r < min(kMaxRangeM, its max range).
[[nodiscard]] std::vector<slam::PointF> robot_points(const slam::LaserRecord& record);
// Every scan of a CARMEN log (plain or gzipped), in order. The reader's errors (missing file,
// malformed line with its number).
[[nodiscard]] Result<std::vector<Scan>> read_log(const std::string& path);

// A poses file of `sen3bot map --poses`: lines `index x y theta` (metres, radians), the index
// counting from 0 in order; blank lines and lines starting with '#' are skipped. Errors name
// `source` and the 1-based line: "poses.txt:7: expected 'index x y theta', got 3 fields".
[[nodiscard]] Result<std::vector<nav::Pose2D>> parse_poses(std::string_view text, std::string_view source);
[[nodiscard]] Result<std::vector<nav::Pose2D>> read_poses(const std::string& path);
// Each scan's odometry in the frame of the first scan's.
[[nodiscard]] std::vector<nav::Pose2D> odometry_poses(std::span<const Scan> scans);

struct PairOptions {
  std::size_t min_gap = kDefaultMinGap;
  double max_distance_m = kDefaultMaxDistanceM;
  double max_angle_rad = kMaxAngleRad;
  std::size_t stride = kPairStride;
};

struct ScanPair {
  std::size_t i = 0;
  std::size_t j = 0;
  friend bool operator==(const ScanPair&, const ScanPair&) = default;
  friend auto operator<=>(const ScanPair&, const ScanPair&) = default;
};

// The pairs a trajectory offers: for each block of `stride` scans of i (0-9, 10-19, ...), the
// pair (i, j) with i in the block, j - i >= min_gap, the poses within max_distance_m and
// max_angle_rad of each other, that is nearest (then least turned, then smallest i, then
// smallest j); none when the block has no such pair. In order of i.
[[nodiscard]] std::vector<ScanPair> choose_pairs(std::span<const nav::Pose2D> poses, const PairOptions& options);

struct PairCheck {
  ScanPair pair;
  nav::Pose2D relative;  // scan j in scan i's frame, as the trajectory has it
  nav::Pose2D matched;   // as the match has it
  double score = 0.0;    // the match's mean probability
  bool matched_ok = false;  // score >= kMinScore
  double translation_m = 0.0;  // |matched - relative|
  double rotation_deg = 0.0;   // |matched.theta - relative.theta|
  // The match ended within half a cell (or a quarter of a degree) of the window's edge: the
  // disagreement is then a lower bound (the best fit may lie beyond the window).
  bool at_window_edge = false;
};

// The grid of scan i and the matcher, in memory taken once.
class PairChecker {
 public:
  PairChecker();
  PairChecker(const PairChecker&) = delete;
  PairChecker& operator=(const PairChecker&) = delete;

  // Scan b against a grid of scan a alone (inserted kInsertions times, the sensor at a's mount),
  // with ScanMatcher over +-kMatchWindowM and +-kMatchWindowRad from `relative`.
  [[nodiscard]] PairCheck check(const Scan& a, const Scan& b, const nav::Pose2D& relative) noexcept;
  [[nodiscard]] bool ready() const noexcept { return ready_; }

 private:
  std::vector<std::byte> memory_;
  std::pmr::monotonic_buffer_resource arena_;
  slam::BuildGrid grid_;
  slam::ScanMatcher matcher_;
  bool ready_ = false;
};

// One pair of a trajectory: its relative pose under the poses, then the check.
[[nodiscard]] PairCheck check_pair(PairChecker& checker, std::span<const Scan> scans,
                                   std::span<const nav::Pose2D> poses, const ScanPair& pair) noexcept;

struct Stats {
  double mean = 0.0;
  double median = 0.0;
  double p95 = 0.0;
};

struct Summary {
  std::size_t pairs = 0;
  std::size_t matched = 0;  // the statistics are over these; NaN when none
  std::size_t matched_at_window_edge = 0;
  double score_median = 0.0;  // over every pair, matched or not (NaN for none)
  Stats translation_m;
  Stats rotation_deg;
};

// What a scan's own returns score in its pair grid: every point on a cell hit kInsertions times.
// No pair can score more; kMinScore is to be read against it.
[[nodiscard]] double score_ceiling() noexcept;

// The q-quantile (0..1) by linear interpolation between order statistics (NumPy's default);
// NaN for no values.
[[nodiscard]] double quantile(std::vector<double> values, double q);
[[nodiscard]] Summary summarise(std::span<const PairCheck> checks);

// A map drawn from every scan at a trajectory's poses: BuildGrid's log-odds at `resolution_m`,
// then round(100 p) per known cell, -1 unknown, cropped to the known cells and the poses with a
// margin of 10 cells; row-major from the lower-left corner.
struct MapGrid {
  int width = 0;
  int height = 0;
  double resolution_m = kResolutionM;
  double origin_x_m = 0.0;
  double origin_y_m = 0.0;
  std::vector<std::int8_t> cells;
};
// A map wider than BuildGrid's 8192 cells is drawn with coarser cells (resolution_m says).
[[nodiscard]] Result<MapGrid> render_map(std::span<const Scan> scans, std::span<const nav::Pose2D> poses,
                                         double resolution_m = kResolutionM);

struct MapFigure {
  std::string title;     // "intel-raw.log.gz: trajectory ours"
  std::string subtitle;  // what the check found
  const MapGrid* map = nullptr;
  std::span<const nav::Pose2D> trajectory;
};
// The map with axes in metres, the trajectory as a line from a ring at its start, and a legend
// (walls, free, unknown, trajectory, start, scale). figure.map must be set.
[[nodiscard]] figure::Canvas draw_map_figure(const MapFigure& figure);

}  // namespace sen3bot::sim::slam_check
