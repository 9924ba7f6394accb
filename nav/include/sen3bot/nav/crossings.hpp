#pragma once
// Crossings planned in time, and the lanes people walk.
//
// LaneMap: where walkers went in the last minutes. Each cell keeps the time a walker's body
// (its radius plus half_width_m) last covered it; the cell's weight is exp(-age / decay_s) and
// it is in a band while that weight is at least band_weight. Bands outlive the tracks that
// drew them: a worker who walks an aisle back and forth is out of view half the time. Fixed
// memory: the map's extent at cell_m, coarsened until it fits max_cells.
//
// CrossingGate: path-velocity decomposition along the local path. The path ahead is sampled
// every sample_m up to lookahead_m. Each walking track (people and laser movers, predicted
// at constant velocity) sweeps a disc over time: its keep-out radius (cage for a person) plus
// the robot's radius plus margin_m, plus spread_m_s * t, the constant-velocity error
// growing with the horizon (docs/crowd.md measures it on the recordings). That marks which
// path samples are taken at which times, where the walker goes across the path (within 35
// degrees of along it, they follow or meet the robot: not a crossing). Then:
//  * go: the robot driving on (accelerating to go_share of max_v_m_s) meets no taken sample
//    while on it;
//  * wait: otherwise it stops before the first sample any track takes, by stop_margin_m, and
//    further back while its body there would stand in a band (so it never waits in a lane,
//    and two bands too close to stand between are one). The result is a speed cap that brakes
//    it there; beyond that point's braking reach the cap does not bind;
//  * a robot that can no longer stop before that point stops where braking ends if that is
//    short of every walker's body sweep (wait, cap 0); if it is not (commit), it is left to
//    the DWA's mover check and the safety filter: a forced stop would stand it in the way.
//
// make_way: a walker whose body, going on as it goes, would sweep over the robot where it
// stands (or waits) within horizon_s: the robot moves along its own axis, forwards (on its
// way) or backwards (the way it came), out of that sweep, when it gets out at least slack_s
// before the walker arrives and where it ends up is in no other walker's sweep; otherwise it
// stays still (moving when they meet would make the contact the robot's). The safety filter
// still checks every such move (the laser ahead, the rear sonar behind).
// Pure: no allocation after init, no clock.
#include <cstdint>
#include <memory_resource>
#include <span>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/msg/navigation.hpp"
#include "sen3bot/nav/geometry.hpp"

namespace sen3bot::nav {

struct LaneConfig {
  double cell_m = 0.1;
  std::size_t max_cells = 256 * 256;  // 256 KiB of float stamps
  double decay_s = 60.0;
  double band_weight = 0.2;      // exp(-age / 60 s) >= 0.2: walked in the last 96 s
  double min_speed_m_s = 0.3;    // only walking tracks draw lanes
  double half_width_m = 0.1;     // sway beyond the body's radius
};

class LaneMap {
 public:
  // The lanes cover the rectangle [origin, origin + size] of the map frame.
  Status init(const LaneConfig& config, double origin_x_m, double origin_y_m, double width_m, double height_m,
              std::pmr::memory_resource& resource);
  // A walker of body radius radius_m at (x, y) now.
  void walk(double x_m, double y_m, double radius_m, double now_s) noexcept;
  [[nodiscard]] double weight(double x_m, double y_m, double now_s) const noexcept;
  // Whether a disc at (x, y) of radius_m overlaps a band.
  [[nodiscard]] bool in_band(double x_m, double y_m, double radius_m, double now_s) const noexcept;
  void clear() noexcept;
  [[nodiscard]] const LaneConfig& config() const noexcept { return config_; }
  [[nodiscard]] double cell_m() const noexcept { return cell_m_; }
  [[nodiscard]] int columns() const noexcept { return columns_; }
  [[nodiscard]] int rows() const noexcept { return rows_; }
  [[nodiscard]] std::size_t bytes() const noexcept { return walked_.size_bytes(); }

 private:
  struct Cells {
    int col0, col1, row0, row1;  // inclusive, clipped to the grid
  };
  // The cells a disc of radius r about (x, y) may touch.
  [[nodiscard]] Cells cells_around(double x_m, double y_m, double r) const noexcept;

  LaneConfig config_;
  // The time a walker last covered the cell (s of the caller's clock), or -inf. A float keeps
  // a second's resolution for 190 days of uptime; the 60 s decay needs no finer.
  std::span<float> walked_;
  double origin_x_m_ = 0.0, origin_y_m_ = 0.0, cell_m_ = 0.1;
  int columns_ = 0, rows_ = 0;
  double min_walked_s_ = 0.0;  // the stamp below which a cell is out of its band
};

struct CrossingConfig {
  // Runs where people are tracked (the controller's people input): on people-crossing it
  // halves the robot's cage entries and lowers its contacts (docs/navigation.md).
  bool enabled = true;
  double lookahead_m = 4.0;
  double sample_m = 0.1;
  double horizon_s = 6.0;
  double time_step_s = 0.2;
  // The constant-velocity prediction's error grows about this fast: the recordings' median
  // rate (0.12-0.17 m/s at 2 s; their 90th percentile grows at 0.3-0.4 m/s, which leaves a
  // robot at 0.5 m/s no gap to cross a lane in).
  double spread_m_s = 0.15;
  double margin_m = 0.1;
  double min_speed_m_s = 0.25;  // slower tracks are left to the costmap and the cages
  // A walker heading within acos(along_cos) (35 degrees) of the path's direction, either way,
  // walks along it there, not across: the robot following an operator, or meeting someone.
  double along_cos = 0.82;
  double stop_margin_m = 0.1;
  double decel_m_s2 = 0.45;     // the braking the cap counts on (below the base's)
  double reaction_s = 0.2;      // command to wheels, and one period
  // Going first counts on this share of the top speed and acceleration (curves and the
  // DWA's other critics slow it).
  double go_share = 0.75;
};

// A track predicted to now (map frame): position, velocity and the radius to keep out of.
struct CrossingTrack {
  std::uint32_t id = 0;
  double x_m = 0.0, y_m = 0.0, vx_m_s = 0.0, vy_m_s = 0.0;
  double keep_out_m = 0.0;  // a person's cage radius; a mover's radius and what cages add
  double body_m = 0.0;      // the body's own radius (the lanes it draws)
};

struct MakeWayConfig {
  // Off: on people-crossing it did not lower the contacts (docs/navigation.md, "Making way").
  bool enabled = false;
  double horizon_s = 6.0;
  double margin_m = 0.1;          // beyond the walker's body and the robot's radius
  // And this much per second they take to get here: their heading is a prediction. Small: a
  // wide sweep leaves no time to get out of it, and the decision is taken again every cycle.
  double spread_m_s = 0.05;
  double min_walker_m_s = 0.3;    // slower tracks are the cages' and the costmap's
  double forward_m_s = 0.5;
  double reverse_m_s = 0.25;      // the safety filter caps reversing further without the sonar
  double accel_m_s2 = 0.6;
  double slack_s = 0.5;           // out of their way this long before they get there
  double min_cross_sin = 0.3;     // moving along its axis gets it out of a walker's way no faster
};

using MakeWayMove = msg::MakeWayAction;

struct MakeWayDecision {
  MakeWayMove move = MakeWayMove::none;
  double v_m_s = 0.0;        // forward > 0, backward < 0; 0 when staying
  double exit_m = 0.0;       // how far along its axis it goes (signed)
  double arrives_s = 0.0;    // when the walker's sweep reaches where it stands
  std::uint32_t track_id = 0;
};

// pose: the robot (map frame); v_m_s: its measured forward speed; body_radius_m: the robot
// as a disc.
[[nodiscard]] MakeWayDecision make_way(const MakeWayConfig& config, const Pose2D& pose, double v_m_s,
                                       double body_radius_m, std::span<const CrossingTrack> tracks) noexcept;

using Crossing = msg::CrossingAction;

struct CrossingDecision {
  Crossing action = Crossing::clear;
  double v_cap_m_s = 0.0;    // wait: the speed from which the robot still stops at wait_at_m
  double wait_at_m = 0.0;    // wait: along the path from the robot
  double conflict_at_m = 0.0;  // the first path sample a track takes
  std::uint32_t track_id = 0;  // the track that takes it
};

struct CrossingInputs {
  Pose2D pose;                           // the robot, map frame
  double v_m_s = 0.0;                    // measured forward speed
  std::span<const msg::PathPoint> path;  // the path from the point nearest the robot on
  std::span<const CrossingTrack> tracks;
  const LaneMap* lanes = nullptr;
  double now_s = 0.0;
};

class CrossingGate {
 public:
  static constexpr std::size_t kMaxSamples = 128;
  static constexpr std::size_t kMaxSteps = 64;
  // body_radius_m: the robot as a disc (its footprint's circumscribed radius); max_v_m_s,
  // acc_v_m_s2: its drive.
  Status init(const CrossingConfig& config, double body_radius_m, double max_v_m_s, double acc_v_m_s2) noexcept;
  [[nodiscard]] CrossingDecision decide(const CrossingInputs& in) noexcept;
  [[nodiscard]] const CrossingConfig& config() const noexcept { return config_; }
  // The samples of the last decide(): the path from the robot (map frame).
  [[nodiscard]] std::span<const Point2D> samples() const noexcept { return {samples_.data(), sample_count_}; }

 private:
  // The first time step at which the robot, starting at v0 and accelerating, is on a sample
  // taken in `taken`; -1 when none is.
  [[nodiscard]] int first_meeting(std::span<const std::uint64_t> taken, double v0, double share) const noexcept;
  void sample_path(const CrossingInputs& in) noexcept;
  // What a walker's disc is: keep-out plus the spread, keep-out alone, or their body alone.
  enum class Reach : std::uint8_t { spread, keep_out, body };
  // The track stands on the path now (within reach_m of a sample) walking along it there.
  [[nodiscard]] bool walks_along(const CrossingTrack& t, double ux, double uy, double reach_m) const noexcept;
  void mark(const CrossingInputs& in, Reach reach, std::span<std::uint64_t> taken,
            std::span<std::uint32_t> by) const noexcept;

  CrossingConfig config_;
  double body_m_ = 0.0;
  double max_v_m_s_ = 0.5;
  double acc_v_m_s2_ = 0.6;
  std::size_t steps_ = 0;
  std::size_t max_samples_ = 0;  // the look-ahead's samples (init checks them against kMaxSamples)
  std::array<Point2D, kMaxSamples> samples_{};
  std::array<Point2D, kMaxSamples> tangent_{};  // the path's direction there (unit)
  std::size_t sample_count_ = 0;
  std::array<std::uint64_t, kMaxSamples> taken_{};  // bit i: taken at step i
  std::array<std::uint32_t, kMaxSamples> taken_by_{};
  std::array<std::uint64_t, kMaxSamples> touched_{};  // the keep-outs alone, no spread
  std::array<std::uint32_t, kMaxSamples> touched_by_{};
  std::array<std::uint64_t, kMaxSamples> bodies_{};  // the bodies' sweep
  std::array<std::uint32_t, kMaxSamples> bodies_by_{};
};

}  // namespace sen3bot::nav
