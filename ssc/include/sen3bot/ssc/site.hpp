#pragma once
// The site model: the areas of interest (thesis §2.1.2, after ANSI/ITSDF B56.5 and
// ANSI/RIA R15.08) as polygons in the map frame, the sentry poses robots monitor them from,
// and each robot's home: a charging station placed so that a robot at home already overlooks
// a critical area. Plus the geometry the centre needs on them: point in polygon, segment
// against polygon, and an AGV route against every area.
#include <optional>
#include <span>
#include <string_view>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/ssc/types.hpp"

namespace sen3bot::ssc {

enum class AreaType : std::uint8_t {
  blind_intersection,  // 1.1 critical: non-restricted, limited visibility for the AGV
  transition,          // 1.2 critical: people likely to pass
  workstation,         // 2 sub-critical: cobot and manual stations, people mostly static
  not_monitored,       // 3 non-critical: restricted or full visibility; the AGV's own sensors suffice
};
std::string_view to_string(AreaType type) noexcept;  // "1.1", "1.2", "2", "3"
[[nodiscard]] constexpr bool monitored(AreaType type) noexcept { return type != AreaType::not_monitored; }

using Polygon = StaticVector<Point, kMaxVertices>;

struct Area {
  AreaId id = kNone;
  Name name;
  AreaType type = AreaType::not_monitored;
  Polygon outline;                                 // simple polygon, either winding
  StaticVector<Pose, kMaxSentryPoses> sentries;    // where monitoring robots stand, best first
};

struct RobotHome {
  RobotId robot = kNone;
  Name name;
  Pose pose;                  // at the robot's charging station
  AreaId overlooks = kNone;   // the critical area seen from there (kNone: none)
};

struct Site {
  StaticVector<Area, kMaxAreas> areas;
  StaticVector<RobotHome, kMaxRobots> robots;  // every robot of the fleet has a home

  [[nodiscard]] const Area* area(AreaId id) const noexcept;
  [[nodiscard]] const RobotHome* robot(RobotId id) const noexcept;
  // Unique ids (robots' below kMaxRobots), outlines of at least three vertices with a surface, homes
  // that overlook existing areas, and a way to monitor every monitored area (a sentry pose or
  // a home overlooking it).
  [[nodiscard]] Status validate() const;
};

// --- geometry -----------------------------------------------------------------------------
// Points on the boundary count as inside: a person on the edge of an area is in it.
[[nodiscard]] bool contains(std::span<const Point> polygon, Point p) noexcept;
// 0 inside, else the distance to the nearest edge.
[[nodiscard]] double distance_to(std::span<const Point> polygon, Point p) noexcept;
[[nodiscard]] Point centroid(std::span<const Point> polygon) noexcept;

// The part of segment a→b inside the closed polygon, as parameters t in [0, 1] along it: the
// first and the last point inside. For a concave polygon the segment may leave and re-enter
// in between; the centre only needs where it first enters and where it finally leaves.
struct SegmentSpan {
  double first = 0;
  double last = 0;
};
[[nodiscard]] std::optional<SegmentSpan> segment_span(std::span<const Point> polygon, Point a, Point b) noexcept;
[[nodiscard]] inline bool intersects(std::span<const Point> polygon, Point a, Point b) noexcept {
  return segment_span(polygon, a, b).has_value();
}

// An area a route passes through, with distances along the route (m) from its first point.
struct Crossing {
  AreaId area = kNone;
  AreaType type = AreaType::not_monitored;
  double entry = 0;  // to the first point inside (0 when the route starts inside)
  double exit = 0;   // to the last point inside
};
using Crossings = StaticVector<Crossing, kMaxAreas>;

// The areas the polyline crosses, in route order (by entry distance). A one-point route is
// a vehicle standing still: it crosses the areas it stands in. Unmonitored areas (type 3)
// are left out unless asked for.
[[nodiscard]] Crossings crossings(const Site& site, std::span<const Point> route, bool include_unmonitored = false);

}  // namespace sen3bot::ssc
