#pragma once
// One simulated case as a figure, from plain data: the map with axes in metres and a scale bar,
// the safe path's waypoints (and the supervisory planner's ellipses, curve and field), the global plans, the true and the estimated path, the robot's
// footprint at a few instants, the boxes and people with their tracks, the contacts, start and
// goals, and a legend; above it the case's name, description and result line.
#include <array>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "sen3bot/msg/geometry.hpp"
#include "sen3bot/nav/geometry.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/figure/map_figure.hpp"

namespace sen3bot::figure {

struct RobotAt {
  double t_s = 0;
  msg::Pose2D pose;
};

struct TimedPoint {
  double t_s = 0;
  msg::Point2D at;
};

struct MoverTrack {
  std::vector<msg::Point2D> path;  // where it was while it could be seen, in time order
  // When it was at each point of `path` (empty or of path's size): with CaseFigure::time_scale_s
  // a person's track is coloured by time.
  std::vector<double> times_s;
  std::vector<TimedPoint> marks;   // a person drawn at these instants
  double size_m = 0.4;
  double appear_s = 0;  // a box that appears later is labelled with the time
  bool person = false;
  bool square = false;
};

struct Contact {
  msg::Point2D at;
  double t_s = 0;
  bool moving = false;  // the robot was moving: a collision
};

// One moment of the run drawn over the rest (a box's closest approach): the local costmap's
// graded cells, the dynamic obstacle layer's tracks, and every mover's true place then.
struct CostCell {
  msg::Point2D at;  // the cell's centre
  std::uint8_t cost = 0;
};

struct TrackMark {
  msg::Point2D at;
  double vx_m_s = 0;
  double vy_m_s = 0;
  double radius_m = 0;
};

struct Moment {
  double t_s = -1;  // < 0: no moment drawn
  double cell_m = 0.05;
  double cell_yaw_rad = 0;
  std::vector<CostCell> cells;         // shaded by cost; 0 < cost < 253
  std::vector<TrackMark> tracks;       // the velocity drawn as what is covered in kArrowS
  std::vector<msg::Point2D> movers;    // per movers[i] of the figure: its centre at t_s
  static constexpr double kArrowS = 1.0;
};

// The supervisory planner's picture (sgp_layer.hpp fills it from a planner).
struct EllipseMark {
  msg::Point2D centre;
  double semi_major_m = 0;
  double semi_minor_m = 0;
  double angle_rad = 0;
};

struct Arrow {
  msg::Point2D from;
  msg::Point2D to;
};

// A person's virtual cage as the firmware published it, at a time.
struct CageMark {
  msg::Point2D at;
  double radius_m = 0;
  double t_s = 0;
};

// The run's closest approach: the robot and the person nearest it, body to body.
struct Closest {
  double t_s = -1;  // < 0: none drawn
  msg::Point2D robot;
  msg::Point2D person;
  double distance_m = 0;
};

struct CaseFigure {
  std::string title;        // "case 2/3: obstacle-before-planning"
  std::string description;  // what the case is
  std::string result;       // "goal reached in 15.2 s, 0 contacts, 1 recovery"
  bool passed = false;      // the result line in green, else red
  const nav::OccupancyMap* map = nullptr;
  std::vector<msg::Point2D> waypoints;
  std::vector<msg::Point2D> replanned;  // the safe path of the last online re-plan
  std::vector<CageMark> cages;          // people's cages, a sample every second or so
  std::vector<EllipseMark> ellipses;                 // the obstacles as the SGP sees them
  std::vector<std::array<msg::Point2D, 2>> curve;    // the safe curve V, as short segments
  std::vector<Arrow> field;                          // the SGP's field direction (a quiver plot)
  std::vector<std::vector<msg::Point2D>> plans;
  std::vector<msg::Point2D> driven;     // ground truth; a non-finite point breaks the line
  std::vector<msg::Point2D> estimated;  // the firmware's pose estimate
  nav::Footprint footprint = nav::Footprint::pioneer();
  std::vector<RobotAt> robot;  // the footprint drawn at these true poses, labelled with t
  std::vector<MoverTrack> movers;
  std::vector<Contact> contacts;
  msg::Pose2D start;
  std::vector<msg::Point2D> goals;
  Moment moment;
  Closest closest;
  // > 0: people's tracks with times are coloured from 0 to this many seconds (a colour bar in
  // the legend), instead of in one colour.
  double time_scale_s = 0;
};

// The colour of time t on a time_scale_s scale: dark blue through green to yellow.
[[nodiscard]] Rgb time_colour(double t_s, double time_scale_s) noexcept;

// The colours, shared by the drawing and its legend (and the tests); the paper, ink, wall
// and unknown are map_figure.hpp's.
namespace colours {
inline constexpr Rgb kWaypoint{0, 80, 255};
inline constexpr Rgb kPlan{0, 170, 0};
inline constexpr Rgb kDriven{220, 0, 0};
inline constexpr Rgb kEstimated{140, 40, 200};
inline constexpr Rgb kRobot{120, 0, 0};
inline constexpr Rgb kBox{200, 90, 0};
inline constexpr Rgb kPerson{255, 140, 0};
inline constexpr Rgb kContact{230, 0, 230};
inline constexpr Rgb kStart{0, 150, 150};
inline constexpr Rgb kGoal{0, 0, 0};
inline constexpr Rgb kPassed{0, 130, 0};
inline constexpr Rgb kFailed{180, 0, 50};
inline constexpr Rgb kCost{60, 90, 230};     // the local costmap's cells, lighter for lower costs
inline constexpr Rgb kTrack{0, 110, 90};     // a tracked mover and its velocity
inline constexpr Rgb kBoxTrack{235, 170, 110};  // a moving box's true track
inline constexpr Rgb kEllipse{200, 150, 0};     // an obstacle's ellipse (SGP)
inline constexpr Rgb kCurve{170, 0, 110};       // the safe curve V
inline constexpr Rgb kField{150, 150, 150};     // the SGP field's arrows
inline constexpr Rgb kCage{230, 60, 60};         // a person's virtual cage (published)
inline constexpr Rgb kReplanned{0, 190, 230};    // waypoints of an online re-plan
inline constexpr Rgb kClosest{0, 90, 200};       // the closest approach
}  // namespace colours

// The map as the figure reads it (a view: the map must outlive it).
[[nodiscard]] Grid grid_of(const nav::OccupancyMap& map) noexcept;
// Pixels per metre for a map: 80, less for maps over 9.5 m (then 760 px across).
[[nodiscard]] double figure_scale(const nav::OccupancyMap& map) noexcept;
// Where the map is drawn on draw_case_figure()'s canvas.
[[nodiscard]] View figure_view(const CaseFigure& figure) noexcept;
// The whole figure; figure.map must be set.
[[nodiscard]] Canvas draw_case_figure(const CaseFigure& figure);

// The instants to draw the robot at: the first pose, then each after at least spacing_m of
// travel since the last one chosen, and the last pose.
[[nodiscard]] std::vector<RobotAt> robot_instants(std::span<const RobotAt> poses, double spacing_m);

}  // namespace sen3bot::figure
