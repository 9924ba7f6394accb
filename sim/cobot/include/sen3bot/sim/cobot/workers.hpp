#pragma once
// Simulated workers doing operations on the site map, recorded as the robot records them
// (docs/cobot/recognition.md, "Simulated workers").
//
// A walk: the worker engages the robot at the operation's first station (a few seconds there:
// the recording starts then), walks to the next along a route planned on the map (A* of the
// global planner on a costmap inflated by the body's clearance, then straightened), works
// there, and so on to the last station. How
// they walk is a WorkerStyle: speed, sway, how close they pass shelves and round corners or
// swing wide, detours, hesitation stops, dwell times, how close they stop to each station.
//
// The recording: per laser scan (5 Hz) the nearest return on a 0.2 m-radius body from the
// observer (the robot following the worker, or standing at a place), on the beam grid of the
// LMS200 (0.5 degrees) with range noise and the 1 cm range unit, hidden behind walls; appended
// only when farther than 5 cm from the last point kept, and thinned when the recorder's 1024
// points are full, as cobot::PathRecorder does on the robot.
//
// Everything is a function of the seed (std::mt19937_64, the uniform and normal draws written
// here so they are the same on every standard library).
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "sen3bot/cobot/operations.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/msg/geometry.hpp"
#include "sen3bot/nav/map.hpp"

namespace sen3bot::cobot {

struct WorkerStyle {
  std::string name;
  std::string description;
  double speed_m_s = 1.1;        // mean walking speed
  double speed_spread = 0.1;     // per worker ± this fraction; per leg ± half of it
  double sway_m = 0.03;          // lateral sway amplitude of the body's centre while walking
  double sway_hz = 0.9;          // one sway per stride
  double clearance_m = 0.45;     // how far they keep from shelves and corners when they can
  double turn_radius_m = 0.3;    // corners rounded over this much of each leg
  double wide_turn_m = 0.0;      // corners swung outward by up to this much
  double detour_probability = 0.0;  // per leg: a bump off the route
  double detour_m = 0.0;
  double pause_probability = 0.0;   // per leg: a hesitation stop on the way
  double pause_max_s = 0.0;
  double dwell_min_s = 4.0;      // working at a station (after the first)
  double dwell_max_s = 10.0;
  double dwell_skew = 1.0;       // dwell = min + (max - min) * u^skew: > 1 mostly short, some long
  double dwell_shift_m = 0.05;   // how far a standing worker shifts about (standard deviation)
  double approach_m = 0.15;      // they stop anywhere within this of the station's point
};

// The styles the classifier learns from, and the one kept for testing only.
[[nodiscard]] std::span<const WorkerStyle> training_styles() noexcept;
[[nodiscard]] const WorkerStyle& held_out_style() noexcept;
// A training or the held-out style by name; nullptr when there is none.
[[nodiscard]] const WorkerStyle* find_style(std::string_view name) noexcept;

enum class ObserverMode : std::uint8_t { following, fixed };

struct Observer {
  ObserverMode mode = ObserverMode::following;
  msg::Point2D position;           // fixed: where the robot's laser is
  double follow_distance_m = 1.2;  // following: the robot keeps this far behind, on the worker's track
  double robot_speed_m_s = 1.0;    // following: its top speed (a rushed worker gets ahead)
  double body_radius_m = 0.2;      // the worker as the laser sees them
  double range_noise_m = 0.015;    // LMS200: a systematic error of about ±15 mm (its data sheet)
  double beam_step_rad = 0.00872664626;  // 0.5 degrees: the 180/0.5 variant's beam spacing
  double range_step_m = 0.01;      // ranges in centimetres
  double max_range_m = 8.0;        // the cm mode's 8 m range
  double scan_hz = 5.0;            // the rate the path recorder samples at
  double min_step_m = 0.05;        // the recorder's spacing (PathConfig::min_spacing_m)
  // false: recording starts when the worker engages the robot at the first station (a few
  // seconds there); true: it starts with their first task there (a full dwell, as at the others).
  bool records_first_task = false;
};

struct WorkerWalk {
  std::vector<float> xy;            // the recorded path: x0, y0, x1, y1, ...
  std::vector<msg::Point2D> body;   // the body's centre at each scan (ground truth)
  std::vector<msg::Point2D> robot;  // the laser's position at each scan
  std::vector<std::size_t> arrivals;  // per visit: the first body sample within the station's radius
  double duration_s = 0.0;
  std::size_t halvings = 0;         // times the recorder filled up and thinned the path
  [[nodiscard]] std::size_t points() const noexcept { return xy.size() / 2; }
};

// A seed per path from a base seed, a purpose (training, validation, testing: separate streams
// that never meet), the operation and the path's number.
[[nodiscard]] std::uint64_t worker_seed(std::uint64_t base, std::uint64_t purpose, std::size_t operation,
                                        std::size_t index) noexcept;
inline constexpr std::uint64_t kTrainingSeeds = 1;
inline constexpr std::uint64_t kValidationSeeds = 2;
inline constexpr std::uint64_t kTestSeeds = 3;

class WorkerSimulator {
 public:
  // The map must outlive the simulator. Fails when a station is not where a worker can stand.
  static Result<std::unique_ptr<WorkerSimulator>> create(const OperationsConfig& config, const nav::OccupancyMap& map);
  ~WorkerSimulator();
  WorkerSimulator(const WorkerSimulator&) = delete;
  WorkerSimulator& operator=(const WorkerSimulator&) = delete;

  Result<WorkerWalk> walk(std::size_t operation, const WorkerStyle& style, const Observer& observer,
                          std::uint64_t seed);

  // A straightened route between two points (A* on the worker's costmap, then the longest clear
  // straight stretches keeping clearance_m where the A* path itself had it), first point first.
  Result<std::vector<msg::Point2D>> route(msg::Point2D from, msg::Point2D to, double clearance_m);

  // The robot's route through an operation's stations (the route above at the robot's
  // clearance, station to station), resampled every spacing_m: the reference trajectory.
  Result<std::vector<msg::Point2D>> reference_route(std::size_t operation, double spacing_m = 0.25);

  // Whether a body centre here keeps the worker's clearance from every obstacle.
  [[nodiscard]] bool standable(msg::Point2D p) const noexcept;

  [[nodiscard]] const OperationsConfig& config() const noexcept;
  [[nodiscard]] const nav::OccupancyMap& map() const noexcept;

 private:
  struct Impl;
  explicit WorkerSimulator(std::unique_ptr<Impl> impl) noexcept;
  std::unique_ptr<Impl> impl_;
};

// A set of labelled paths: per_operation walks of each operation, walk i of operation o in
// styles[i % styles.size()] with seed worker_seed(seed, purpose, o, i), watched by a robot
// following at a distance drawn from follow_min_m..follow_max_m with a range noise drawn from
// noise_min_m..noise_max_m (per walk, from the same seed).
struct DatasetSpec {
  std::span<const WorkerStyle> styles;
  std::size_t per_operation = 0;
  std::uint64_t seed = 1;
  std::uint64_t purpose = kTrainingSeeds;
  double follow_min_m = 0.8;
  double follow_max_m = 1.6;
  double noise_min_m = 0.01;
  double noise_max_m = 0.02;
  bool records_first_task = false;  // Observer::records_first_task
};
Result<std::vector<LabelledPath>> generate_paths(WorkerSimulator& workers, const DatasetSpec& spec);

}  // namespace sen3bot::cobot
