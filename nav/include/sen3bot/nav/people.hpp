#pragma once
// People on the map from the camera and the laser (system.md: the calibration and eq. 2.3-2.4;
// navigation.md §5): every laser return is projected into the image, the returns inside a
// person's box place that person on the map, and each person keeps a track with a virtual cage.
//
// The projection, c = K (Phi^-1 L - Delta), u = c_x / c_z, v = c_y / c_z. L is the return in
// the thesis' convention: the camera's axes, at the laser (x right, y down, z forward). A
// return at range r and bearing a (counter-clockwise from the laser's forward axis) is
// L = (-r sin a, 0, r cos a). With the thesis' calibration (the camera pitched 10 degrees
// down, the laser 0.21 m below it) a return 2 m straight ahead lands at (742.2, 146.7) px.
//
// Placing a person: of the returns inside the box (and in front of the camera), the ones on
// the static map (within background_m of an occupied cell) are background and left out; of the
// rest, those within depth_band_m of the nearest, with the unbroken run of returns around the
// nearest (in case the box cuts the body), are the person's near side. Their mean,
// moved back along the ray as a round body as wide as those returns would be (pi/4 of the
// half width), is the person's position. A box with too few such returns places nobody.
#include <array>
#include <cstdint>
#include <memory_resource>
#include <numbers>
#include <span>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/msg/laser.hpp"
#include "sen3bot/msg/navigation.hpp"
#include "sen3bot/msg/people.hpp"
#include "sen3bot/nav/assignment.hpp"
#include "sen3bot/nav/costmap.hpp"
#include "sen3bot/nav/cv_filter.hpp"
#include "sen3bot/nav/geometry.hpp"
#include "sen3bot/nav/map.hpp"

namespace sen3bot::nav {

struct CameraCalibration {
  std::array<double, 9> k = {1304.6, 0.0, 727.7219, 0.0, 1306.4, 241.5278, 0.0, 0.0, 1.0};  // row-major
  std::array<double, 9> phi = {1.0, 0.0, 0.0, 0.0, 0.9848, 0.1736, 0.0, -0.1736, 0.9848};  // camera -> laser
  std::array<double, 3> delta = {-0.0215, -0.2065, 0.0304};                                   // metres
  int width_px = 1280;
  int height_px = 720;
};

class CameraProjection {
 public:
  // Errors: Phi singular, a focal length not positive, an empty image.
  Status set(const CameraCalibration& calibration) noexcept;
  // The pixel of a laser return (laser frame: forward, left); false when it lies behind the
  // camera (depth under 5 cm) or outside the image.
  bool project(double forward_m, double left_m, double& u_px, double& v_px) const noexcept;
  // A point up_m above the laser's plane, its pixel wherever it falls (off the image too);
  // false only behind the camera.
  bool project_point(double forward_m, double left_m, double up_m, double& u_px, double& v_px) const noexcept;
  [[nodiscard]] int width_px() const noexcept { return width_; }
  [[nodiscard]] int height_px() const noexcept { return height_; }
  [[nodiscard]] double focal_x_px() const noexcept { return fx_; }

 private:
  std::array<double, 9> m_{};  // K Phi^-1
  std::array<double, 3> t_{};  // K Delta
  double fx_ = 1.0;
  int width_ = 0;
  int height_ = 0;
};

struct FusionConfig {
  double match_window_s = 0.15;  // a box and a scan at most this far apart in time
  float min_confidence = 0.4f;
  std::uint16_t person_class = 0;  // COCO's person
  double depth_band_m = 0.35;      // returns this close behind the nearest one are the person
  std::size_t min_points = 2;
  double segment_jump_m = 0.08;     // neighbouring returns closer in range than this are one body
  double max_body_radius_m = 0.3;  // the centre is at most pi/4 of this behind the returns' mean
  std::int8_t occupied_threshold = 65;  // map cells at least this are background
  double background_m = 0.15;  // returns this close to them too (the map's and the pose's error)
};

enum class BoxVerdict : std::uint8_t {
  located,
  other_class,     // not a person
  low_confidence,
  out_of_window,   // frame and scan too far apart in time
  no_returns,      // too few returns on the person (background only, or nothing in range)
};
inline constexpr std::size_t kBoxVerdicts = 5;
[[nodiscard]] const char* to_string(BoxVerdict verdict) noexcept;

// Where a box places a person (map frame).
struct PersonFix {
  double x_m = 0.0;
  double y_m = 0.0;
  double range_m = 0.0;  // from the laser
  double width_m = 0.0;  // the box's horizontal extent at that range
  // The unit ray from the laser to the fix: a partial body's range is measured, its place across
  // the ray is not.
  double ray_x = 0.0;
  double ray_y = 0.0;
  // The body's returns are cut short by something nearer in front of it or by the edge of the
  // scan: their mean is off towards the part in view.
  bool partial = false;
  std::uint16_t points = 0;
  std::uint8_t box = 0;  // which box of the frame
};

class PeopleFusion {
 public:
  // map: the static map whose obstacles are background (kept by reference); max_beams: the
  // longest scan.
  Status init(const FusionConfig& config, const CameraCalibration& calibration, const OccupancyMap* map,
              std::size_t max_beams, std::pmr::memory_resource& resource);
  // One frame's boxes against one scan, taken from laser_pose (the laser's pose on the map at
  // the scan). Writes at most out.size() fixes and returns how many; a verdict per box counts.
  std::size_t fuse(const msg::ScanView& scan, const Pose2D& laser_pose, const msg::PersonDetections& frame,
                   std::span<PersonFix> out) noexcept;
  // Laser only, for people out of the camera's view: for each predicted position, the returns
  // within gate_m of it (background left out) placed as a box's are. out[t].points == 0: none
  // there. Returns how many were found.
  std::size_t follow(const msg::ScanView& scan, const Pose2D& laser_pose, std::span<const Point2D> predicted,
                     double gate_m, std::span<PersonFix> out) noexcept;
  [[nodiscard]] std::uint64_t count(BoxVerdict verdict) const noexcept {
    return counts_[static_cast<std::size_t>(verdict)];
  }
  [[nodiscard]] const CameraProjection& projection() const noexcept { return projection_; }

 private:
  [[nodiscard]] bool background(double x_m, double y_m) const noexcept;
  // Each return's map position (NaN: out of range or on the map's background).
  void locate(const msg::ScanView& scan, const Pose2D& laser_pose, std::size_t beams) noexcept;
  template <typename Region>
  bool place(const msg::ScanView& scan, const Pose2D& laser_pose, std::size_t beams, const Region& region,
             PersonFix& fix) const noexcept;

  FusionConfig config_;
  CameraProjection projection_;
  const OccupancyMap* map_ = nullptr;
  std::span<float> u_;
  std::span<float> v_;
  std::span<double> x_;
  std::span<double> y_;
  int background_cells_ = 1;
  std::array<std::uint64_t, kBoxVerdicts> counts_{};
};

struct PersonTrackerConfig {
  std::size_t max_tracks = msg::People::kMax;
  double gate_m = 0.8;             // a fix farther than this from every track starts a new one
  // An unmatched fix nearer than this to a track is that person seen twice, not a new one.
  double min_separation_m = 0.3;
  double expire_s = 2.0;           // a track (and its cage) without a fix for this long ends
  double dynamic_after_m = 1.0;    // moved farther than this from where first seen: dynamic
  double safety_radius_m = 0.5;    // the cage: half the person's width plus this
  // A box cut by the image's edge, or a person seen side-on, is narrower than a person: the
  // cage counts at least this width.
  double min_width_m = 0.4;
  // A constant-velocity Kalman filter per person: a fix's error (along the ray; across it too
  // unless the body is cut), how far a partial fix may be off across the ray, walkers'
  // changes of pace and the speed of someone not seen before.
  double fix_sigma_m = 0.05;
  double partial_sigma_m = 0.3;
  double accel_sigma_m_s2 = 2.0;
  double start_speed_sigma_m_s = 1.0;
  double max_speed_m_s = 3.0;      // a velocity estimate is clamped to this
  std::uint32_t confirm_hits = 3;  // camera fixes before a track is published (a stray box is not)
  // Out of the camera's view, a confirmed person is followed by the laser alone (the returns
  // within follow_gate_m of the prediction) for up to laser_follow_s after the last box.
  double laser_follow_s = 8.0;
  double follow_gate_m = 0.45;
  // A walking person (dynamic, or faster than walking_speed_m_s) is carried on by their
  // velocity to the time asked, for at most coast_s past the last fix; a standing one is held
  // where last seen (their velocity is the fixes' noise).
  double coast_s = 1.0;
  double walking_speed_m_s = 0.3;
  // Hidden people (docs/people.md): a confirmed person not seen for expire_s is kept while their
  // place has not been seen empty, by the laser or the sonar, for a person out of sight is not
  // a person gone. Unseen, their position's variance grows by hidden_wander_m2_s a second once
  // held (the walker's coast grows it through the Kalman prediction); they end when it is seen
  // empty, when the position's sigma passes hidden_max_sigma_m, or hidden_max_s after hiding or
  // the last sonar echo from their place. A hidden person's cage grows by their sigma, at most
  // hidden_cage_growth_m (a guess must not close the map). Off by default: with walkers who
  // react to the robot (people-crossing --walkers social) the grown cages of people kept
  // behind the door jamb held the robot at the door, and goals reached fell (docs/people.md).
  bool keep_hidden = false;
  double hidden_max_s = 30.0;
  double hidden_max_sigma_m = 1.5;
  double hidden_cage_growth_m = 0.5;
  double hidden_wander_m2_s = 0.1;
  // The sonar: a disc's cone (the P3-DX's is 15 degrees across), how old a reading may be, and
  // how near the place's near side an echo must be to count as the person.
  double sonar_half_angle_rad = 7.5 * std::numbers::pi / 180.0;
  double sonar_max_age_s = 1.0;
  double sonar_window_m = 0.3;
};

// A tracked person's cage radius: half the width (at least min_width_m) plus safety_radius_m,
// and while hidden the position's sigma, at most hidden_cage_growth_m.
[[nodiscard]] double cage_radius(const PersonTrackerConfig& config, double width_m, double safety_radius_m, bool hidden,
                                 double position_sigma_m) noexcept;

// What the sensors saw last, to tell a person hidden from a person gone. Null: that sensor has
// nothing.
struct SensorCoverage {
  const msg::ScanView* scan = nullptr;  // the latest posed scan
  Pose2D laser_pose;                    // the laser on the map at that scan
  const msg::Sonar* sonar = nullptr;    // the ring's newest readings (body frame mounts)
  Pose2D robot_pose;                    // the body on the map, for the sonar's mounts
};

class PersonTracker {
 public:
  struct Track {
    std::uint32_t id = 0;
    Point2D at;
    Point2D velocity;
    std::array<double, 16> covariance{};  // of x, y, vx, vy, row-major (CvFilter::P)
    Point2D first_seen;
    double width_m = 0.0;
    hal::Nanos last_seen_ns = 0;    // the last fix, camera or laser
    hal::Nanos camera_seen_ns = 0;  // the last box
    std::uint32_t hits = 0;         // boxes matched
    std::uint16_t points = 0;
    msg::PersonState state = msg::PersonState::static_person;
    bool hidden = false;
    hal::Nanos hidden_since_ns = 0;  // when it was hidden, or the last sonar echo from its place
  };

  Status init(const PersonTrackerConfig& config, std::pmr::memory_resource& resource);
  // The fixes of one frame, taken at stamp_ns: tracks are predicted to it, matched to the fixes
  // (Hungarian on distance, gated), corrected; unmatched fixes start tracks; stale tracks end.
  void update(std::span<const PersonFix> fixes, hal::Nanos stamp_ns) noexcept;
  // The confirmed tracks that the laser may follow at stamp_ns: their predicted positions
  // (in track order, at most out.size()); returns how many, with their indices in which.
  std::size_t followable(hal::Nanos stamp_ns, std::span<Point2D> out, std::span<std::uint8_t> which) const noexcept;
  // A laser-only fix of tracks()[index] at stamp_ns: position and velocity, not width or hits.
  void follow(std::size_t index, const PersonFix& fix, hal::Nanos stamp_ns) noexcept;
  // Ends the tracks not seen for expire_s by now_ns, but keeps (hidden) the confirmed ones whose
  // place the coverage has not seen empty, up to the caps. Without a scan or sonar readings
  // nothing is known to be hidden: they end.
  void expire(hal::Nanos now_ns, const SensorCoverage& coverage = {}) noexcept;
  // The tracks predicted to now_ns, with their cages.
  void publish(hal::Nanos now_ns, msg::People& out) const noexcept;
  [[nodiscard]] std::span<const Track> tracks() const noexcept { return tracks_.first(count_); }
  [[nodiscard]] std::uint32_t started() const noexcept { return next_id_ - 1; }
  // Fixes dropped as a second sighting of a tracked person in the same frame.
  [[nodiscard]] std::uint64_t duplicates() const noexcept { return duplicates_; }
  // Hidden tracks ended because their place was seen empty, because the caps (sigma, time)
  // were reached, or to make room for a person seen.
  [[nodiscard]] std::uint64_t seen_empty() const noexcept { return seen_empty_; }
  [[nodiscard]] std::uint64_t forgotten() const noexcept { return forgotten_; }
  // The position's standard deviation along its longest axis, predicted to stamp_ns.
  [[nodiscard]] double position_sigma(const Track& track, hal::Nanos stamp_ns) const noexcept;

 private:
  PersonTrackerConfig config_;
  Hungarian hungarian_;
  std::span<Track> tracks_;
  std::size_t count_ = 0;
  std::span<double> cost_;
  std::span<int> assignment_;
  std::span<std::uint8_t> fix_used_;
  std::uint32_t next_id_ = 1;
  std::uint64_t duplicates_ = 0;
  std::uint64_t seen_empty_ = 0;
  std::uint64_t forgotten_ = 0;

  // Whether a confirmed track not seen for expire_s is kept, hidden (marks it so).
  bool keep_hidden(Track& track, hal::Nanos now_ns, const SensorCoverage& coverage) noexcept;
  void correct(Track& track, const PersonFix& fix, hal::Nanos stamp_ns) noexcept;
  [[nodiscard]] Point2D predict(const Track& track, hal::Nanos stamp_ns) const noexcept;
  [[nodiscard]] bool walking(const Track& track) const noexcept;
};

struct PeopleLayerConfig {
  double expire_s = 2.0;      // a person not seen for this long has no cage
  double max_radius_m = 2.0;  // a cage is never larger (a wrong width must not close the map)
  bool predict = true;        // paint each person where their velocity takes them by the update
  // A cage stops this far from the robot's centre (the inscribed radius and a little more):
  // a person who walks up to the robot, or whom it came upon unseen, must not leave it inside
  // a lethal region with no move allowed; the inflation around the shrunken cage still pushes
  // it away. Closer than that the safety filter's stop zone is what protects them.
  double robot_clearance_m = 0.25;
};

// The virtual cages: a lethal disc of each tracked person's cage radius, painted before the
// inflation layer so that the normal inflation surrounds it. It reads the People it is given
// (the fusion's, copied in by the task before each update) and keeps nothing between updates.
class PeopleLayer final : public CostmapLayer {
 public:
  explicit PeopleLayer(const msg::People& people, PeopleLayerConfig config = {}) noexcept
      : people_(people), config_(config) {}
  [[nodiscard]] const char* name() const noexcept override { return "people"; }
  Status init(const Costmap2D& master, std::pmr::memory_resource& resource) override;
  void update(Costmap2D& master, const CostmapInputs& inputs) noexcept override;
  // Cages painted by the last update.
  [[nodiscard]] std::size_t cages() const noexcept { return cages_; }

 private:
  const msg::People& people_;
  PeopleLayerConfig config_;
  std::size_t cages_ = 0;
};

}  // namespace sen3bot::nav
