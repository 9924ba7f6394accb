#pragma once
// A world of wall segments and round posts (people, pillars) for the SLAM tests, and the scans a
// 180-degree, 1-degree laser takes in it.
#include <algorithm>
#include <cmath>
#include <numbers>
#include <vector>

#include "sen3bot/slam/grid.hpp"
#include "sen3bot/slam/laser_record.hpp"

namespace sen3bot::slam::test {

struct Segment {
  double ax, ay, bx, by;
};
struct Post {
  double x, y, radius;
};

struct World {
  std::vector<Segment> walls;
  std::vector<Post> posts;

  void box(double x0, double y0, double x1, double y1) {
    walls.push_back({x0, y0, x1, y0});
    walls.push_back({x1, y0, x1, y1});
    walls.push_back({x1, y1, x0, y1});
    walls.push_back({x0, y1, x0, y0});
  }

  // Everything moved by (dx, dy): tests keep walls off the cells' boundaries, where a wall's hits
  // would split between two rows of cells.
  [[nodiscard]] World shifted(double dx, double dy) const {
    World w = *this;
    for (Segment& s : w.walls) s = {s.ax + dx, s.ay + dy, s.bx + dx, s.by + dy};
    for (Post& p : w.posts) p = {p.x + dx, p.y + dy, p.radius};
    return w;
  }

  // The nearest hit along a ray, or `max_range` when none.
  [[nodiscard]] double cast(double ox, double oy, double angle, double max_range) const {
    const double dx = std::cos(angle);
    const double dy = std::sin(angle);
    double best = max_range;
    for (const Segment& s : walls) {
      const double ex = s.bx - s.ax;
      const double ey = s.by - s.ay;
      const double den = dx * ey - dy * ex;
      if (std::abs(den) < 1e-12) continue;
      const double t = ((s.ax - ox) * ey - (s.ay - oy) * ex) / den;
      const double u = ((s.ax - ox) * dy - (s.ay - oy) * dx) / den;
      if (t > 0.0 && u >= 0.0 && u <= 1.0) best = std::min(best, t);
    }
    for (const Post& p : posts) {
      const double fx = ox - p.x;
      const double fy = oy - p.y;
      const double b = fx * dx + fy * dy;
      const double c = fx * fx + fy * fy - p.radius * p.radius;
      const double disc = b * b - c;
      if (disc < 0.0) continue;
      const double t = -b - std::sqrt(disc);
      if (t > 0.0) best = std::min(best, t);
    }
    return best;
  }

  // A scan from `truth` (the laser at the robot's origin), tagged with `odometry`.
  [[nodiscard]] LaserRecord scan(const nav::Pose2D& truth, const nav::Pose2D& odometry, double max_range = 30.0) const {
    LaserRecord r;
    r.odometry = odometry;
    r.count = 181;
    r.start_angle_rad = -std::numbers::pi / 2.0;
    r.angle_increment_rad = std::numbers::pi / 180.0;
    r.max_range_m = max_range;
    for (std::uint32_t i = 0; i < r.count; ++i) {
      const double range = cast(truth.x_m, truth.y_m, truth.theta_rad + r.start_angle_rad + i * r.angle_increment_rad,
                                max_range);
      r.ranges[i] = static_cast<float>(range);
    }
    return r;
  }
};

// A scan's returns in the robot frame, as the mapper keeps them.
inline std::vector<PointF> returns(const LaserRecord& r) {
  std::vector<PointF> out;
  for (std::uint32_t i = 0; i < r.count; ++i) {
    if (!(r.ranges[i] > 0.1F && r.ranges[i] < r.max_range_m)) continue;
    const double a = r.start_angle_rad + i * r.angle_increment_rad;
    out.push_back({static_cast<float>(r.ranges[i] * std::cos(a)), static_cast<float>(r.ranges[i] * std::sin(a))});
  }
  return out;
}

}  // namespace sen3bot::slam::test
