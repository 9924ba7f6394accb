#pragma once
// The simulated ground truth: the static map plus moving obstacles (boxes, people) that walk
// scripted polylines or are placed by a crowd model each step. Everything is a pure function of (map, scripts, seed, time), so a
// lockstep run is reproducible bit for bit.
//
// The laser emulator adapts to scan(): ranges for a sensor pose, angle_min, increment, count
// and max range. Ray casting walks the grid cell by cell (exact boundary crossings) and
// intersects movers analytically.
#include <array>
#include <cstdint>
#include <random>
#include <span>
#include <utility>
#include <vector>

#include "sen3bot/crowd/legs.hpp"
#include "sen3bot/nav/geometry.hpp"
#include "sen3bot/nav/map.hpp"

namespace sen3bot::world {

using nav::Footprint;
using nav::Point2D;
using nav::Pose2D;

enum class MoverShape : std::uint8_t { circle, square };

// One scripted obstacle. With one vertex (or speed 0) it stands still. Otherwise it walks
// the polyline at speed_m_s from start_time_s on, back and forth (ping-pong) or around
// (loop, closing the last vertex to the first). phase_m shifts where in that cycle it is: at
// start_time_s it has already walked phase_m (a ping-pong cycle is twice the polyline, there
// and back; a loop's is once round), and it waits there before.
struct MoverScript {
  std::vector<Point2D> path;
  double speed_m_s = 0.0;
  double size_m = 0.4;      // circle diameter or square side
  MoverShape shape = MoverShape::circle;
  bool loop = false;
  double start_time_s = 0.0;   // before this it waits where phase_m puts it (the first vertex at 0)
  double phase_m = 0.0;        // distance already walked along the cycle at start_time_s (>= 0)
  double appear_time_s = 0.0;  // invisible (not hit by rays, no collisions) before this
  double vanish_time_s = 1e300;  // and again from this time on (walked out of the scene)
  // A walk there and back (not a loop) slows to a stop at each end and sets off again at this
  // acceleration; 0 turns back at full speed. People turn in about a second, not in no time.
  double accel_m_s2 = 0.0;
  bool person = false;
  // A timed walk instead of the polyline: the mover is at timeline[i] at times_s[i] (same
  // length, times increasing) and moves straight between them, standing before the first and
  // after the last. For an operator who stops, shows a tag, turns and walks on.
  std::vector<Point2D> timeline;
  std::vector<double> times_s;
  // Moved by the caller (World::place_mover) instead of the script: a walker of a crowd model
  // that reacts to the robot. The script's path, speed and times are ignored.
  bool driven = false;
  // Seen by rays as two legs (circles of crowd::kLegRadiusM) swinging with the walking speed,
  // as a laser at shin height sees a person; the body (a circle of size_m) still counts for
  // contacts and clearance.
  bool legs = false;
};

// A person standing still at (x, y): a 0.45 m body, as the scenarios' people are.
inline MoverScript standing_person(double x_m, double y_m) {
  MoverScript person;
  person.path = {{x_m, y_m}};
  person.size_m = 0.45;
  person.person = true;
  return person;
}

// A person walking the path at speed_m_s from start_s (slowing down and setting off again at the
// ends at 1 m/s^2), a 0.45 m body as the scenarios' people are.
inline MoverScript walking_person(std::vector<Point2D> path, double speed_m_s, double start_s) {
  MoverScript person;
  person.path = std::move(path);
  person.speed_m_s = speed_m_s;
  person.size_m = 0.45;
  person.start_time_s = start_s;
  person.accel_m_s2 = 1.0;
  person.person = true;
  return person;
}

struct WorldConfig {
  int occupied_threshold = 50;  // map cells with occupancy >= this are solid (unknown is free)
  double range_noise_sigma_m = 0.0;  // Gaussian range noise added by noisy_scan()
  std::uint64_t seed = 1;
};

class World {
 public:
  World(const nav::OccupancyMap& map, WorldConfig config = {});

  [[nodiscard]] const nav::OccupancyMap& map() const noexcept { return map_; }
  std::size_t add_mover(const MoverScript& script);
  // Appends a keyframe to a timed mover's walk (time after its last): a script written as the
  // run goes, e.g. an operator who reacts to where the robot stopped. Allocates.
  void extend_timeline(std::size_t index, Point2D at, double time_s);
  [[nodiscard]] std::size_t mover_count() const noexcept { return movers_.size(); }

  // Moves every scripted obstacle to its place at time_s; driven movers stay where they were
  // placed, and every mover with legs steps its gait on.
  void set_time(double time_s) noexcept;
  // Puts a driven mover where its model has it: position, velocity (for the legs' gait) and
  // whether it is in the scene.
  void place_mover(std::size_t index, Point2D position, Point2D velocity, bool visible) noexcept;
  [[nodiscard]] double time_s() const noexcept { return time_s_; }
  // Current centre of a mover (for tests and reports); visible() says whether it exists yet.
  [[nodiscard]] Point2D mover_position(std::size_t index) const noexcept { return movers_[index].position; }
  [[nodiscard]] bool mover_visible(std::size_t index) const noexcept { return movers_[index].visible; }
  [[nodiscard]] const MoverScript& mover_script(std::size_t index) const noexcept { return movers_[index].script; }
  // Its velocity: a driven mover's as placed, a scripted one's over the last set_time step.
  [[nodiscard]] Point2D mover_velocity(std::size_t index) const noexcept { return movers_[index].velocity; }
  // Where a mover with legs has them now.
  [[nodiscard]] std::array<Point2D, 2> mover_legs(std::size_t index) const noexcept;

  // Distance along the ray to the first solid thing, or max_range_m if none is nearer.
  [[nodiscard]] double cast_ray(double x_m, double y_m, double angle_rad, double max_range_m) const noexcept;

  // Noise-free ranges of a planar scanner at `sensor` (map frame): beam i points at
  // sensor.theta + angle_min + i * increment. Writes min(count, ranges.size()) values.
  void scan(const Pose2D& sensor, double angle_min_rad, double increment_rad, std::size_t count,
            double max_range_m, std::span<float> ranges_m) const noexcept;
  // The same with the configured Gaussian range noise from the world's seeded generator
  // (deterministic for a given sequence of calls).
  void noisy_scan(const Pose2D& sensor, double angle_min_rad, double increment_rad, std::size_t count,
                  double max_range_m, std::span<float> ranges_m) noexcept;

  // True when the footprint at `pose` overlaps a solid map cell, a visible mover or leaves the map.
  [[nodiscard]] bool collides(const Pose2D& pose, const Footprint& footprint) const noexcept;
  // The map alone: a solid cell or outside it.
  [[nodiscard]] bool touches_map(const Pose2D& pose, const Footprint& footprint) const noexcept;
  // The first visible mover the footprint at `pose` overlaps, or -1.
  [[nodiscard]] int touching_mover(const Pose2D& pose, const Footprint& footprint) const noexcept;
  // For a contact at `pose`, whether the robot's own motion (forward speed v_m_s) was closing
  // on what it touches: the map at more than min_speed_m_s, a mover when the robot moves
  // towards the mover's centre at more than min_speed_m_s along that line.
  [[nodiscard]] bool robot_closing(const Pose2D& pose, const Footprint& footprint, double v_m_s,
                                   double min_speed_m_s) const noexcept;
  // Distance from the footprint at `pose` to the nearest visible mover or solid cell centre,
  // searched up to limit_m (returns limit_m when nothing is nearer).
  [[nodiscard]] double clearance_m(const Pose2D& pose, const Footprint& footprint, double limit_m) const noexcept;

 private:
  struct Mover {
    MoverScript script;
    std::vector<double> cumulative_m;  // arc length at each vertex (loop: closing edge appended)
    Point2D position;
    Point2D velocity;
    crowd::Gait gait;
    bool visible = true;
  };

  [[nodiscard]] bool solid(int col, int row) const noexcept;
  [[nodiscard]] double ray_to_map(double x_m, double y_m, double dx, double dy, double max_range_m) const noexcept;
  static Point2D position_at(const Mover& mover, double time_s) noexcept;

  nav::OccupancyMap map_;
  WorldConfig config_;
  std::vector<Mover> movers_;
  double time_s_ = 0.0;
  std::mt19937_64 rng_;
};

}  // namespace sen3bot::world
