#include "sen3bot/ssc/site.hpp"

#include <algorithm>
#include <cmath>

#include "sen3bot/geometry/point_math.hpp"

namespace sen3bot::ssc {
namespace {

constexpr double kEps = 1e-9;

// Parameters along a→b where it meets edge c→d (one point, or the ends of a collinear overlap).
void edge_hits(Point a, Point b, Point c, Point d, double& lo, double& hi, bool& any) noexcept {
  const Point r = b - a;
  const Point s = d - c;
  const Point ca = c - a;
  const double denom = geometry::cross(r, s);
  const double rr = r.x_m * r.x_m + r.y_m * r.y_m;
  auto take = [&](double t) {
    t = std::clamp(t, 0.0, 1.0);
    lo = any ? std::min(lo, t) : t;
    hi = any ? std::max(hi, t) : t;
    any = true;
  };
  const double scale = std::max({1.0, rr, s.x_m * s.x_m + s.y_m * s.y_m});
  if (std::fabs(denom) <= kEps * scale) {
    if (rr <= 0) return;
    if (std::fabs(geometry::cross(ca, r)) > kEps * scale) return;  // parallel, apart
    const double t0 = (ca.x_m * r.x_m + ca.y_m * r.y_m) / rr;
    const double t1 = ((d.x_m - a.x_m) * r.x_m + (d.y_m - a.y_m) * r.y_m) / rr;
    const double from = std::max(0.0, std::min(t0, t1));
    const double to = std::min(1.0, std::max(t0, t1));
    if (from <= to + kEps) {
      take(from);
      take(to);
    }
    return;
  }
  const double t = geometry::cross(ca, s) / denom;
  const double u = geometry::cross(ca, r) / denom;
  if (t >= -kEps && t <= 1 + kEps && u >= -kEps && u <= 1 + kEps) take(t);
}

}  // namespace

std::string_view to_string(AreaType type) noexcept {
  switch (type) {
    case AreaType::blind_intersection: return "1.1";
    case AreaType::transition: return "1.2";
    case AreaType::workstation: return "2";
    case AreaType::not_monitored: return "3";
  }
  return "?";
}

const Area* Site::area(AreaId id) const noexcept {
  for (const Area& a : areas)
    if (a.id == id) return &a;
  return nullptr;
}

const RobotHome* Site::robot(RobotId id) const noexcept {
  for (const RobotHome& r : robots)
    if (r.robot == id) return &r;
  return nullptr;
}

Status Site::validate() const {
  for (std::size_t i = 0; i < areas.size(); ++i) {
    const Area& a = areas[i];
    if (a.id == kNone) return Error::format(Errc::config, "area '%s' has no id", a.name.c_str());
    for (std::size_t j = 0; j < i; ++j)
      if (areas[j].id == a.id) return Error::format(Errc::config, "area id %u is used twice", a.id);
    if (a.outline.size() < 3) return Error::format(Errc::config, "area '%s' needs at least three vertices", a.name.c_str());
    double twice_area = 0;
    for (std::size_t k = 0; k < a.outline.size(); ++k)
      twice_area += geometry::cross(a.outline[k], a.outline[(k + 1) % a.outline.size()]);
    if (std::fabs(twice_area) < 1e-6) return Error::format(Errc::config, "area '%s' has no surface", a.name.c_str());
    if (monitored(a.type) && a.sentries.empty()) {
      const bool overlooked = std::any_of(robots.begin(), robots.end(), [&](const RobotHome& r) { return r.overlooks == a.id; });
      if (!overlooked) return Error::format(Errc::config, "area '%s' has no sentry pose and no home overlooks it", a.name.c_str());
    }
  }
  for (std::size_t i = 0; i < robots.size(); ++i) {
    const RobotHome& r = robots[i];
    // The people map marks which robots see a track in a mask of kMaxRobots bits.
    if (r.robot >= kMaxRobots) return Error::format(Errc::config, "robot '%s' needs an id below %zu", r.name.c_str(), kMaxRobots);
    for (std::size_t j = 0; j < i; ++j)
      if (robots[j].robot == r.robot) return Error::format(Errc::config, "robot id %u is used twice", r.robot);
    if (r.overlooks != kNone && area(r.overlooks) == nullptr)
      return Error::format(Errc::config, "robot '%s' overlooks unknown area %u", r.name.c_str(), r.overlooks);
  }
  return Status::success();
}

namespace {

// The polygon's axis-aligned bounds: what lies outside them needs no edge-by-edge test, which
// keeps the centre's step short with many areas, routes and people.
struct Bounds {
  double x0, x1, y0, y1;
};

Bounds bounds(std::span<const Point> polygon) noexcept {
  Bounds b{polygon[0].x_m, polygon[0].x_m, polygon[0].y_m, polygon[0].y_m};
  for (const Point& v : polygon) {
    b.x0 = std::min(b.x0, v.x_m);
    b.x1 = std::max(b.x1, v.x_m);
    b.y0 = std::min(b.y0, v.y_m);
    b.y1 = std::max(b.y1, v.y_m);
  }
  return b;
}

}  // namespace

bool contains(std::span<const Point> polygon, Point p) noexcept {
  if (polygon.size() < 3) return false;
  const Bounds box = bounds(polygon);
  if (p.x_m < box.x0 - kEps || p.x_m > box.x1 + kEps || p.y_m < box.y0 - kEps || p.y_m > box.y1 + kEps) return false;
  // The crossing test may put a point on an edge either way: within kEps of one is inside.
  return geometry::inside_polygon(polygon, p) || geometry::polygon_edge_distance(polygon, p) <= kEps;
}

double distance_to(std::span<const Point> polygon, Point p) noexcept {
  if (contains(polygon, p)) return 0;
  if (polygon.size() == 1) return distance(p, polygon[0]);  // the edge distance wants two corners
  return geometry::polygon_edge_distance(polygon, p);
}

Point centroid(std::span<const Point> polygon) noexcept {
  Point c;
  if (polygon.empty()) return c;
  for (const Point& p : polygon) {
    c.x_m += p.x_m;
    c.y_m += p.y_m;
  }
  const double n = static_cast<double>(polygon.size());
  return {c.x_m / n, c.y_m / n};
}

std::optional<SegmentSpan> segment_span(std::span<const Point> polygon, Point a, Point b) noexcept {
  if (polygon.size() < 3) return std::nullopt;
  const Bounds box = bounds(polygon);
  const double slack = 1e-6 * std::max({1.0, box.x1 - box.x0, box.y1 - box.y0});
  if (std::max(a.x_m, b.x_m) < box.x0 - slack || std::min(a.x_m, b.x_m) > box.x1 + slack ||
      std::max(a.y_m, b.y_m) < box.y0 - slack || std::min(a.y_m, b.y_m) > box.y1 + slack)
    return std::nullopt;
  double lo = 0;
  double hi = 0;
  bool any = false;
  if (contains(polygon, a)) {
    lo = hi = 0;
    any = true;
  }
  if (contains(polygon, b)) {
    lo = any ? lo : 1;
    hi = 1;
    any = true;
  }
  for (std::size_t i = 0; i < polygon.size(); ++i) edge_hits(a, b, polygon[i], polygon[(i + 1) % polygon.size()], lo, hi, any);
  if (!any) return std::nullopt;
  return SegmentSpan{lo, hi};
}

Crossings crossings(const Site& site, std::span<const Point> route, bool include_unmonitored) {
  Crossings out;
  if (route.empty()) return out;
  for (const Area& area : site.areas) {
    if (!include_unmonitored && !monitored(area.type)) continue;
    std::optional<Crossing> found;
    if (route.size() == 1) {
      if (contains(area.outline.as_span(), route[0])) found = Crossing{area.id, area.type, 0, 0};
    } else {
      double along = 0;
      for (std::size_t i = 0; i + 1 < route.size(); ++i) {
        const double length = distance(route[i], route[i + 1]);
        if (const auto span = segment_span(area.outline.as_span(), route[i], route[i + 1])) {
          if (!found) found = Crossing{area.id, area.type, along + span->first * length, 0};
          found->exit = along + span->last * length;
        }
        along += length;
      }
    }
    if (found) (void)out.push_back(*found);  // as many slots as areas: never full
  }
  std::stable_sort(out.begin(), out.end(), [](const Crossing& x, const Crossing& y) { return x.entry < y.entry; });
  return out;
}

}  // namespace sen3bot::ssc
