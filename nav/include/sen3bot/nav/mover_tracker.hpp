#pragma once
// The dynamic obstacle layer's tracking (dynamic_obstacles.hpp): blobs to tracks, and which
// tracks are movers. Fixed memory from init().
#include <array>
#include <cstdint>
#include <memory_resource>
#include <span>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/nav/assignment.hpp"
#include "sen3bot/nav/cv_filter.hpp"
#include "sen3bot/nav/mover_detection.hpp"

namespace sen3bot::nav {

struct DolTrackerConfig {
  std::size_t max_tracks = 16;
  std::size_t max_blobs = 32;
  double gate_m = 1.0;             // a blob farther than this from a track's prediction is not it
  // Hits before a tentative track is confirmed. A static object coming into view is dynamic
  // for 3 updates with the default averages (P_s catches up), so 4 keeps it out.
  int confirm_hits = 4;
  double max_coast_s = 0.6;        // unmatched for longer where the laser should see it: deleted
  double max_coast_unseen_s = 4.0; // the same where it cannot (beside or behind the robot, out
                                   // of range): its prediction goes on meanwhile
  double accel_sigma_m_s2 = 1.0;   // white-noise acceleration (process noise)
  double measurement_sigma_m = 0.07;
  double initial_velocity_sigma_m_s = 1.5;
  double min_radius_m = 0.1;       // a track's size from its blobs' extent, clamped
  double max_radius_m = 0.6;
  // A confirmed track becomes a mover (painted, published) once it is faster than
  // moving_min_speed_m_s and has left where it was born: it is moving_min_travel_m away and
  // the laser sees no mark within vacated_radius_m of its birth place any more, or it is
  // moving_far_travel_m away (measured on blob centroids, not on the filter). It stays one
  // while it is hit at least every publish_max_coast_s, or, out of the laser's view, while it
  // lives. Why: the laser's marks on a still object flicker as the robot passes it, and a
  // box's faces come into view one after another, so their blobs wander by up to the object's
  // size, but they never leave the place where they were first seen.
  double moving_min_speed_m_s = 0.15;
  double moving_min_travel_m = 0.3;
  double moving_far_travel_m = 0.45;
  double vacated_radius_m = 0.1;
  double publish_max_coast_s = 0.6;
  // The axis a track travels along: the line fitted (least squares, principal direction)
  // through its measured centroids, each older one weighed down by exp(-d / axis_memory_m)
  // for the distance d the track has travelled since. Once the fitted segment is
  // axis_min_travel_m long and at least four times as long as it is wide, a velocity within
  // axis_max_angle_rad of the axis is turned onto it, in the state after every correction
  // and every coasting step, and so in what is published and painted; a track coasting
  // unseen is also held on the line, at the along-axis speed it kept while in view.
  // Why: a box seen at the edge of the laser's field of view, or half hidden, shows less and
  // less of itself; its centroid slides sideways and lags, and a coasting track would drift
  // with it out of its lane and fall behind the box.
  double axis_memory_m = 3.0;
  double axis_min_travel_m = 0.5;
  double axis_max_angle_rad = 0.5;
  // A track the camera vouches for is a mover at once (MoverTracker::vouch): hit by the newest
  // scan at least vouch_min_hits times, within vouch_reach_m of a walking person the camera and
  // laser placed, moving their way (velocities within vouch_max_angle_rad, speeds within a
  // factor of vouch_speed_ratio) and at least moving_min_speed_m_s. Why: a walker coming into
  // view is a person in the camera after three frames (0.3 s), a mover for the laser alone only
  // after confirm_hits scans and moving_min_travel_m (about 1 s at 5 scans/s); still boxes
  // are never people and never move their way. Off: on people-crossing it changed nothing
  // measurable (the laser tracks the workers before the camera confirms them there), and a
  // wrongly vouched still object would have its cells left to the mover check.
  bool camera_vouches = false;
  int vouch_min_hits = 2;
  double vouch_reach_m = 0.5;
  double vouch_max_angle_rad = 0.6;
  double vouch_speed_ratio = 2.0;
};

// A walking person as the camera and laser placed them, predicted to a scan's time.
struct Vouch {
  double x_m = 0.0, y_m = 0.0, vx_m_s = 0.0, vy_m_s = 0.0;
};

struct DolTrack {
  std::uint32_t id = 0;
  bool confirmed = false;
  int hits = 0;
  hal::Nanos stamp_ns = 0;      // time of the filter's state
  hal::Nanos last_hit_ns = 0;
  CvFilter kf;                  // x, y, vx, vy (world)
  double radius_m = 0.1;
  geometry::Point2D birth;  // first position
  geometry::Point2D seen;   // last blob centroid
  // The axis fit (axis_memory_m): weighed sums of the centroids relative to birth, and of their
  // squares (xx, xy, yy).
  double axis_weight = 1.0;
  geometry::Point2D axis_sum;
  std::array<double, 3> axis_squares{};
  double axis_speed_m_s = 0.0;  // along the axis, averaged while in view
  bool mover = false;  // has shown that it moves (MoverTracker::classify)
  bool in_view = true;  // where the laser should see it, at the last update
};

// Where the laser looked: a sector around the sensor (world frame).
struct LaserView {
  double x_m = 0.0;
  double y_m = 0.0;
  double heading_rad = 0.0;
  double half_angle_rad = 3.2;  // > pi: all around
  double range_m = 1e9;
};

class MoverTracker {
 public:
  Status init(const DolTrackerConfig& config, std::pmr::memory_resource& resource);
  // Predicts every track to stamp_ns, matches the blobs, corrects, births and deaths.
  // Blobs past max_blobs are ignored. A tentative track that misses a scan is deleted at once
  // (a real mover shows up in every scan; clutter rarely twice in a row); a confirmed one
  // coasts for max_coast_s, or max_coast_unseen_s outside view (where the laser looked for
  // these blobs). Pairs farther apart than gate_m all cost the same in the assignment, so
  // one far pair cannot pull the matching away from the near ones.
  void update(std::span<const Blob> blobs, hal::Nanos stamp_ns, const LaserView& view = {}) noexcept;
  [[nodiscard]] std::span<const DolTrack> tracks() const noexcept { return {tracks_.data(), count_}; }
  // Marks the confirmed tracks that have shown they move, given the image the blobs came
  // from (255: marked) on its grid (see DolTrackerConfig).
  void classify(std::span<const std::uint8_t> image, const GridGeometry& geometry) noexcept;
  // Makes movers of the tracks the people vouch for (DolTrackerConfig::camera_vouches);
  // returns how many it made. After classify(), with the people predicted to the last update.
  std::size_t vouch(std::span<const Vouch> people) noexcept;
  // Whether a track counts as a mover now (classified, and hit recently).
  [[nodiscard]] bool moving(const DolTrack& track) const noexcept;
  // Whether a track is a candidate: confirmed, hit by the newest update and faster than
  // moving_min_speed_m_s, but not (yet) a mover.
  [[nodiscard]] bool candidate(const DolTrack& track) const noexcept;
  // A track's position predicted to stamp_ns (constant velocity), without changing it; a
  // stamp before the track's own gives its current position.
  [[nodiscard]] static geometry::Point2D predict_position(const DolTrack& track, hal::Nanos stamp_ns) noexcept;
  // The whole state and covariance predicted to stamp_ns (the filter's prediction step).
  [[nodiscard]] DolTrack predicted(const DolTrack& track, hal::Nanos stamp_ns) const noexcept;
  void clear() noexcept { count_ = 0; }
  // The track's velocity, held to its travel axis (DolTrackerConfig::axis_memory_m).
  [[nodiscard]] geometry::Point2D velocity(const DolTrack& track) const noexcept;
  // The track's velocity reversed: a coasting mover predicted into a wall has turned there.
  void turn_back(std::size_t index) noexcept;

 private:
  struct Axis {
    geometry::Point2D centre;
    geometry::Point2D direction;  // unit
  };
  [[nodiscard]] bool axis(const DolTrack& track, Axis& out) const noexcept;  // false: none yet
  // Adds the centroid z (before track.seen becomes z) to the axis fit.
  void follow_axis(DolTrack& track, geometry::Point2D z) const noexcept;
  // axis() exists and the filter's velocity lies within axis_max_angle_rad of it.
  [[nodiscard]] bool along_axis(const DolTrack& track, Axis& out) const noexcept;
  // The state's velocity := velocity(track); measured: the along-axis speed is averaged;
  // unseen: the position goes onto the line, and the speed up to that average.
  enum class Hold : std::uint8_t { measured, coasting, unseen };
  void hold_to_axis(DolTrack& track, Hold hold) const noexcept;

  DolTrackerConfig config_;
  Hungarian hungarian_;
  std::span<DolTrack> tracks_;
  std::size_t count_ = 0;
  std::uint32_t next_id_ = 1;
  hal::Nanos last_update_ns_ = 0;
  std::span<double> cost_;
  std::span<int> assignment_;
  std::span<std::uint8_t> blob_used_;
};

}  // namespace sen3bot::nav
