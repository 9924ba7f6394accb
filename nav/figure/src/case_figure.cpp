#include "sen3bot/nav_figure/case_figure.hpp"

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <functional>
#include <initializer_list>
#include <numbers>
#include <utility>

namespace sen3bot::figure {

namespace {

using namespace colours;

// The estimate's dashes; a 2 px line's round caps eat about 2 px of each gap.
constexpr double kDashPx = 8;
constexpr double kGapPx = 7;

// The header's three lines and their baselines.
struct Header {
  int title_y = 0, description_y = 0, result_y = 0, height = 0;
};

Header header_layout() {
  Header h;
  h.title_y = kMargin + Canvas::text_height(kTitleSize, 2);
  h.description_y = h.title_y + 8 + Canvas::text_height(kLineSize);
  h.result_y = h.description_y + 9 + Canvas::text_height(0.5);
  h.height = h.result_y + 34;  // and room for "y (m)" above the plot
  return h;
}

// The footprint's outline at a pose, in pixels.
std::vector<Px> outline(const View& view, const nav::Footprint& footprint, const msg::Pose2D& pose) {
  std::vector<Px> pts;
  const double c = std::cos(pose.theta_rad), s = std::sin(pose.theta_rad);
  if (footprint.vertex_count == 0) {
    for (int i = 0; i < 24; ++i) {
      const double a = 2 * std::numbers::pi * i / 24;
      pts.push_back(view(pose.x_m + footprint.circle_radius_m * std::cos(a), pose.y_m + footprint.circle_radius_m * std::sin(a)));
    }
    return pts;
  }
  for (std::size_t i = 0; i < footprint.vertex_count; ++i) {
    const msg::Point2D v = footprint.vertices[i];
    pts.push_back(view(pose.x_m + c * v.x_m - s * v.y_m, pose.y_m + s * v.x_m + c * v.y_m));
  }
  return pts;
}

double front_m(const nav::Footprint& footprint) {
  if (footprint.vertex_count == 0) return footprint.circle_radius_m;
  double x = 0;
  for (std::size_t i = 0; i < footprint.vertex_count; ++i) x = std::max(x, footprint.vertices[i].x_m);
  return x;
}

std::vector<Px> to_pixels(const View& view, std::span<const msg::Point2D> points) {
  std::vector<Px> out;
  out.reserve(points.size());
  for (const msg::Point2D& p : points) out.push_back(view(p.x_m, p.y_m));
  return out;
}

// The stretches of a path between its non-finite points (where the robot was carried off):
// a line across that gap would be a path nobody drove.
template <class Draw>
void for_each_stretch(std::span<const msg::Point2D> points, Draw draw) {
  std::size_t begin = 0;
  for (std::size_t i = 0; i <= points.size(); ++i) {
    if (i < points.size() && std::isfinite(points[i].x_m) && std::isfinite(points[i].y_m)) continue;
    if (i - begin >= 2) draw(points.subspan(begin, i - begin));
    begin = i + 1;
  }
}

// Small labels that must not overprint each other: each goes to the first of its candidate
// places still free, or is left out; placed in order of importance, drawn over everything.
class Labels {
 public:
  explicit Labels(Canvas& canvas) : canvas_(canvas) {}
  // Each candidate is where the label's centre would be.
  bool place(std::string_view text, std::initializer_list<Px> centres, Rgb colour) {
    const double w = Canvas::text_width(text, kSmallSize), h = Canvas::text_height(kSmallSize);
    for (const Px c : centres) {
      const Box box{c.x - w / 2 - 1, c.y - h / 2 - 1, c.x + w / 2 + 1, c.y + h / 2 + 1};
      if (std::any_of(placed_.begin(), placed_.end(), [&](const Box& b) { return b.overlaps(box); })) continue;
      placed_.push_back(box);
      texts_.push_back({std::string(text), {c.x - w / 2, c.y + h / 2}, colour});
      return true;
    }
    return false;
  }
  void draw() {
    for (const Text& t : texts_) canvas_.text(t.at, t.text, t.colour, kSmallSize, 1, true);
  }

 private:
  struct Text {
    std::string text;
    Px at;
    Rgb colour;
  };
  struct Box {
    double x0, y0, x1, y1;
    [[nodiscard]] bool overlaps(const Box& o) const noexcept { return x0 < o.x1 && o.x0 < x1 && y0 < o.y1 && o.y0 < y1; }
  };
  Canvas& canvas_;
  std::vector<Box> placed_;
  std::vector<Text> texts_;
};

bool moves(const MoverTrack& m) {
  return std::any_of(m.path.begin(), m.path.end(), [&](const msg::Point2D& p) {
    return std::hypot(p.x_m - m.path.front().x_m, p.y_m - m.path.front().y_m) > 1e-6;
  });
}

// Paper for cost 0 to kCost for the highest graded cost.
bool timed(const CaseFigure& f, const MoverTrack& m) {
  return f.time_scale_s > 0 && !m.times_s.empty() && m.times_s.size() == m.path.size();
}

Rgb cost_shade(std::uint8_t cost) {
  const double a = 0.15 + 0.85 * std::min(1.0, cost / 252.0);
  auto mix = [a](std::uint8_t paper, std::uint8_t full) {
    return static_cast<std::uint8_t>(std::lround(paper + a * (full - paper)));
  };
  return {mix(kPaper.r, kCost.r), mix(kPaper.g, kCost.g), mix(kPaper.b, kCost.b)};
}

std::vector<Px> ellipse_outline(const View& view, const EllipseMark& e) {
  std::vector<Px> pts;
  const double c = std::cos(e.angle_rad), s = std::sin(e.angle_rad);
  for (int i = 0; i < 48; ++i) {
    const double t = 2 * std::numbers::pi * i / 48;
    const double u = e.semi_major_m * std::cos(t), v = e.semi_minor_m * std::sin(t);
    pts.push_back(view(e.centre.x_m + c * u - s * v, e.centre.y_m + s * u + c * v));
  }
  return pts;
}

void draw_start(Canvas& canvas, Px c) { canvas.ring(c, 11, kStart, 3); }

void draw_goal(Canvas& canvas, Px c) {
  canvas.disc(c, 8, kGoal);
  canvas.disc(c, 5, kPaper);
  canvas.disc(c, 2.5, kGoal);
}

std::vector<LegendEntry> legend_entries(const CaseFigure& f) {
  std::vector<LegendEntry> entries;
  entries.push_back({"wall, rack (map)", [](Canvas& c, Px p) {
                       c.fill_rect(static_cast<int>(p.x) - 10, static_cast<int>(p.y) - 6, 20, 12, kWall);
                     }});
  if (has_unknown(grid_of(*f.map)))
    entries.push_back({"unknown (map)", [](Canvas& c, Px p) {
                         c.fill_rect(static_cast<int>(p.x) - 10, static_cast<int>(p.y) - 6, 20, 12, kUnknown);
                       }});
  if (!f.ellipses.empty())
    entries.push_back({"obstacle ellipse (SGP)", [](Canvas& c, Px p) {
                         c.outline_polygon(ellipse_outline({0, 0, 1, p.x, p.y}, {{0, 0}, 11, 6, 0}), kEllipse, 2);
                       }});
  if (!f.field.empty())
    entries.push_back({"field direction (SGP)", [](Canvas& c, Px p) {
                         draw_arrow(c, {p.x - 10, p.y}, {p.x + 10, p.y}, kField, 1);
                       }});
  if (!f.curve.empty())
    entries.push_back({"safe curve V: p(x, y) = 0", [](Canvas& c, Px p) {
                         c.line({p.x - 12, p.y}, {p.x + 12, p.y}, kCurve, 2);
                       }});
  if (!f.waypoints.empty())
    entries.push_back({"safe path waypoints", [](Canvas& c, Px p) {
                         c.disc({p.x - 6, p.y}, 3.5, kWaypoint);
                         c.disc({p.x + 6, p.y}, 3.5, kWaypoint);
                       }});
  if (!f.replanned.empty())
    entries.push_back({"online re-plan waypoints", [](Canvas& c, Px p) {
                         c.ring({p.x - 6, p.y}, 4.0, kReplanned, 2);
                         c.ring({p.x + 6, p.y}, 4.0, kReplanned, 2);
                       }});
  if (!f.cages.empty())
    entries.push_back({"person's cage (as published)", [](Canvas& c, Px p) { c.ring(p, 8.0, kCage, 1); }});
  if (!f.plans.empty())
    entries.push_back({"global plan (first per goal)", [](Canvas& c, Px p) {
                         c.line({p.x - 12, p.y}, {p.x + 12, p.y}, kPlan, 2);
                       }});
  if (!f.driven.empty())
    entries.push_back({"driven path (ground truth)", [](Canvas& c, Px p) {
                         c.line({p.x - 12, p.y}, {p.x + 12, p.y}, kDriven, 3);
                       }});
  if (!f.estimated.empty())
    entries.push_back({"estimated path (localization)", [](Canvas& c, Px p) {
                         const Px pts[] = {{p.x - 12, p.y}, {p.x + 12, p.y}};
                         c.dashed_polyline(pts, kEstimated, 2, kDashPx, kGapPx);
                       }});
  if (!f.robot.empty())
    entries.push_back({"robot footprint at t (s into the run)", [&f](Canvas& c, Px p) {
                         // Scaled to the swatch, not to the map.
                         const double scale = 11.0 / std::max(f.footprint.circumscribed_radius_m(), 0.01);
                         View v{0, 0, scale, p.x, p.y};
                         c.outline_polygon(outline(v, f.footprint, {}), kRobot, 2);
                         c.line(p, v(front_m(f.footprint), 0), kRobot, 2);
                       }});
  if (f.moment.t_s >= 0 && !f.moment.cells.empty())
    entries.push_back({"local costmap at the moment, 0 < cost < 253", [](Canvas& c, Px p) {
                         for (int i = 0; i < 4; ++i)
                           c.fill_rect(static_cast<int>(p.x) - 12 + 6 * i, static_cast<int>(p.y) - 6, 6, 12,
                                       cost_shade(static_cast<std::uint8_t>(40 + 70 * i)));
                       }});
  if (f.moment.t_s >= 0 && !f.moment.tracks.empty())
    entries.push_back({"tracked mover, its velocity (1 s ahead)", [](Canvas& c, Px p) {
                         c.ring({p.x - 7, p.y}, 5, kTrack, 2);
                         draw_arrow(c, {p.x - 7, p.y}, {p.x + 13, p.y}, kTrack, 2);
                       }});
  if (std::any_of(f.movers.begin(), f.movers.end(), [](const MoverTrack& m) { return !m.person && moves(m); }))
    entries.push_back({"moving box's track (ground truth)", [](Canvas& c, Px p) {
                         c.line({p.x - 12, p.y}, {p.x + 12, p.y}, kBoxTrack, 2);
                       }});
  if (std::any_of(f.movers.begin(), f.movers.end(), [](const MoverTrack& m) { return !m.person; }))
    entries.push_back({f.moment.t_s >= 0 ? format("box, at the moment t = %.1f s", f.moment.t_s) : std::string("box"),
                       [](Canvas& c, Px p) {
                         c.fill_rect(static_cast<int>(p.x) - 6, static_cast<int>(p.y) - 6, 12, 12, kBox);
                       }});
  if (std::any_of(f.movers.begin(), f.movers.end(), [&f](const MoverTrack& m) { return m.person && !timed(f, m); }))
    entries.push_back({"person's track, and at t (s)", [](Canvas& c, Px p) {
                         c.line({p.x - 12, p.y}, {p.x + 2, p.y}, kPerson, 2);
                         c.ring({p.x + 7, p.y}, 6, kPerson, 2);
                       }});
  if (std::any_of(f.movers.begin(), f.movers.end(), [&f](const MoverTrack& m) { return m.person && timed(f, m); }))
    entries.push_back({format("person's track by time: 0 to %.0f s", f.time_scale_s), [&f](Canvas& c, Px p) {
                         for (int i = 0; i < 8; ++i)
                           c.line({p.x - 14 + 3.5 * i, p.y}, {p.x - 10.5 + 3.5 * i, p.y},
                                  time_colour((i + 0.5) / 8 * f.time_scale_s, f.time_scale_s), 4);
                       }});
  if (f.closest.t_s >= 0)
    entries.push_back({format("closest approach: %.2f m body to body", f.closest.distance_m), [](Canvas& c, Px p) {
                         const Px pts[] = {{p.x - 12, p.y}, {p.x + 12, p.y}};
                         c.dashed_polyline(pts, kClosest, 2, 4, 3);
                         c.disc({p.x + 12, p.y}, 3, kClosest);
                       }});
  if (!f.contacts.empty())
    entries.push_back({"contact at t (s), bold: by the robot", [](Canvas& c, Px p) { draw_cross(c, p, 5, kContact, 3); }});
  entries.push_back({"start", [](Canvas& c, Px p) {
                       c.ring(p, 7, kStart, 3);
                     }});
  entries.push_back({f.goals.size() > 1 ? "goals, in order" : "goal", [](Canvas& c, Px p) { draw_goal(c, p); }});
  return entries;
}

}  // namespace

Grid grid_of(const nav::OccupancyMap& map) noexcept {
  return {map.width(), map.height(), map.resolution_m(), map.origin_x_m(), map.origin_y_m(), map.cells()};
}

double figure_scale(const nav::OccupancyMap& map) noexcept { return figure_scale(grid_of(map)); }

View figure_view(const CaseFigure& figure) noexcept {
  const nav::OccupancyMap& map = *figure.map;
  const double s = figure_scale(map);
  const double map_h = std::round(map.height() * map.resolution_m() * s);
  return {map.origin_x_m(), map.origin_y_m(), s, static_cast<double>(kMargin + kAxisLeft),
          header_layout().height + map_h};
}

Canvas draw_case_figure(const CaseFigure& f) {
  const nav::OccupancyMap& map = *f.map;
  const View view = figure_view(f);
  const Header header = header_layout();
  const double width_m = map.width() * map.resolution_m(), height_m = map.height() * map.resolution_m();
  const int map_w = static_cast<int>(std::lround(width_m * view.px_per_m));
  const int map_h = static_cast<int>(std::lround(height_m * view.px_per_m));
  const int plot_left = static_cast<int>(view.left_px), plot_top = header.height;

  const std::vector<LegendEntry> legend = legend_entries(f);
  const int legend_w = legend_width(legend);
  const int legend_x = plot_left + map_w + kLegendGap;
  const int legend_h = legend_height(legend);
  const int header_w = std::max({Canvas::text_width(f.title, kTitleSize, 2), Canvas::text_width(f.description, kLineSize),
                                 Canvas::text_width(f.result, 0.5)});
  const int width = std::max(legend_x + legend_w + kMargin, kMargin + header_w + kMargin);
  const int height = std::max(plot_top + map_h + kAxisBottom, plot_top + legend_h) + kMargin / 2;
  Canvas canvas(width, height, kPaper);

  // The header: what the case is and how it went.
  canvas.text({kMargin, static_cast<double>(header.title_y)}, f.title, kInk, kTitleSize, 2);
  canvas.text({kMargin, static_cast<double>(header.description_y)}, f.description, {90, 90, 90}, kLineSize);
  canvas.text({kMargin, static_cast<double>(header.result_y)}, f.result, f.passed ? kPassed : kFailed, 0.5, 1);

  const Grid grid = grid_of(map);
  draw_grid(canvas, view, grid);
  if (f.moment.t_s >= 0) {
    // The cells as rotated squares, in the costmap's own frame.
    const double h = f.moment.cell_m / 2, c = std::cos(f.moment.cell_yaw_rad), s = std::sin(f.moment.cell_yaw_rad);
    for (const CostCell& cell : f.moment.cells) {
      std::vector<Px> square;
      for (const auto& [dx, dy] : {std::pair{-h, -h}, std::pair{h, -h}, std::pair{h, h}, std::pair{-h, h}})
        square.push_back(view(cell.at.x_m + c * dx - s * dy, cell.at.y_m + s * dx + c * dy));
      canvas.fill_polygon(square, cost_shade(cell.cost));
    }
  }
  for (const Arrow& a : f.field) draw_arrow(canvas, view(a.from.x_m, a.from.y_m), view(a.to.x_m, a.to.y_m), kField, 1);
  for (const EllipseMark& e : f.ellipses) canvas.outline_polygon(ellipse_outline(view, e), kEllipse, 2);
  for (const auto& segment : f.curve)
    canvas.line(view(segment[0].x_m, segment[0].y_m), view(segment[1].x_m, segment[1].y_m), kCurve, 2);
  for (const std::vector<msg::Point2D>& plan : f.plans) canvas.polyline(to_pixels(view, plan), kPlan, 2);
  for (const msg::Point2D& w : f.waypoints) canvas.disc(view(w.x_m, w.y_m), 3.5, kWaypoint);
  for (const msg::Point2D& w : f.replanned) canvas.ring(view(w.x_m, w.y_m), 4.0, kReplanned, 2);
  for (const CageMark& cage : f.cages) canvas.ring(view(cage.at.x_m, cage.at.y_m), cage.radius_m * view.px_per_m, kCage, 1);
  for (const MoverTrack& m : f.movers) {
    if (m.path.empty()) continue;
    const double half_px = m.size_m / 2 * view.px_per_m;
    if (m.person && timed(f, m)) {
      for (std::size_t i = 1; i < m.path.size(); ++i)
        canvas.line(view(m.path[i - 1].x_m, m.path[i - 1].y_m), view(m.path[i].x_m, m.path[i].y_m),
                    time_colour(m.times_s[i], f.time_scale_s), 2);
    } else if (m.person) {
      canvas.polyline(to_pixels(view, m.path), kPerson, 2);
    }
    if (m.person) {
      for (const TimedPoint& p : m.marks) {
        const Px c = view(p.at.x_m, p.at.y_m);
        canvas.ring(c, half_px, kPerson, 2);
      }
      continue;
    }
    // A box stands where it was first seen; a moving one shows its track, and where it was at
    // the moment when there is one.
    msg::Point2D at = m.path.front();
    if (moves(m)) {
      canvas.polyline(to_pixels(view, m.path), kBoxTrack, 2);
      const std::size_t i = static_cast<std::size_t>(&m - f.movers.data());
      if (f.moment.t_s >= 0 && i < f.moment.movers.size()) at = f.moment.movers[i];
    }
    const Px c = view(at.x_m, at.y_m);
    if (m.square) {
      const std::vector<Px> square{{c.x - half_px, c.y - half_px}, {c.x + half_px, c.y - half_px},
                                   {c.x + half_px, c.y + half_px}, {c.x - half_px, c.y + half_px}};
      canvas.fill_polygon(square, kBox);
    } else {
      canvas.disc(c, half_px, kBox);
    }
    if (m.appear_s > 0)
      canvas.text({c.x + half_px + 4, c.y + 4}, format("appears at %.1f s", m.appear_s), kBox, kSmallSize, 1, true);
  }
  for (const TrackMark& t : f.moment.tracks) {
    const Px c = view(t.at.x_m, t.at.y_m);
    canvas.ring(c, std::max(3.0, t.radius_m * view.px_per_m), kTrack, 2);
    draw_arrow(canvas, c, view(t.at.x_m + t.vx_m_s * Moment::kArrowS, t.at.y_m + t.vy_m_s * Moment::kArrowS), kTrack, 2);
  }
  // The estimate dashed over the truth, so both show where they coincide.
  for_each_stretch(f.driven, [&](std::span<const msg::Point2D> s) { canvas.polyline(to_pixels(view, s), kDriven, 3); });
  canvas.dashed_polyline(to_pixels(view, f.estimated), kEstimated, 2, kDashPx, kGapPx);
  for (const RobotAt& r : f.robot) {
    canvas.outline_polygon(outline(view, f.footprint, r.pose), kRobot, 2);
    const double front = front_m(f.footprint), c = std::cos(r.pose.theta_rad), s = std::sin(r.pose.theta_rad);
    const Px centre = view(r.pose.x_m, r.pose.y_m);
    canvas.line(centre, view(r.pose.x_m + front * c, r.pose.y_m + front * s), kRobot, 2);
  }
  for (const Contact& c : f.contacts) {
    const Px p = view(c.at.x_m, c.at.y_m);
    draw_cross(canvas, p, 6, kContact, c.moving ? 4 : 2);
  }
  if (f.closest.t_s >= 0) {
    const Px pts[] = {view(f.closest.robot.x_m, f.closest.robot.y_m), view(f.closest.person.x_m, f.closest.person.y_m)};
    canvas.dashed_polyline(pts, kClosest, 2, 4, 3);
    canvas.disc(pts[0], 3, kClosest);
    canvas.disc(pts[1], 3, kClosest);
  }
  for (std::size_t g = 0; g < f.goals.size(); ++g) {
    const Px p = view(f.goals[g].x_m, f.goals[g].y_m);
    draw_goal(canvas, p);
    if (f.goals.size() > 1)
      canvas.text({p.x - 16, p.y - 10}, format("%.0f", static_cast<double>(g + 1)), kGoal, kLineSize, 1, true);
  }
  draw_start(canvas, view(f.start.x_m, f.start.y_m));  // a ring around a goal that is also the start

  // The times: contacts first, then the robot's (on its right-hand side if free, so an
  // out-and-back run keeps its two legs' labels apart), then the people's.
  Labels labels(canvas);
  for (const Contact& c : f.contacts) {
    const Px p = view(c.at.x_m, c.at.y_m);
    labels.place(format("%.1f", c.t_s), {{p.x - 22, p.y}, {p.x + 22, p.y}, {p.x, p.y - 16}, {p.x, p.y + 16}}, kContact);
  }
  if (f.closest.t_s >= 0) {
    const Px p = view(f.closest.person.x_m, f.closest.person.y_m);
    labels.place(format("%.1f", f.closest.t_s), {{p.x + 24, p.y}, {p.x - 24, p.y}, {p.x, p.y - 18}, {p.x, p.y + 18}}, kClosest);
  }
  const double o = f.footprint.circumscribed_radius_m() + 9 / view.px_per_m;
  for (const RobotAt& r : f.robot) {
    const double c = std::cos(r.pose.theta_rad), s = std::sin(r.pose.theta_rad);
    labels.place(format("%.0f", r.t_s),
                 {view(r.pose.x_m + o * s, r.pose.y_m - o * c), view(r.pose.x_m - o * s, r.pose.y_m + o * c),
                  view(r.pose.x_m - o * c, r.pose.y_m - o * s)},
                 kRobot);
  }
  for (const MoverTrack& m : f.movers)
    for (const TimedPoint& p : m.marks) {
      const Px c = view(p.at.x_m, p.at.y_m);
      const double d = m.size_m / 2 * view.px_per_m + 8;
      labels.place(format("%.0f", p.t_s), {{c.x, c.y - d}, {c.x, c.y + d}, {c.x + d + 4, c.y}, {c.x - d - 4, c.y}}, kPerson);
    }
  labels.draw();

  // The frame, ticks in metres and the axis names; the legend, then the scale bar under it.
  draw_axes(canvas, view, grid, plot_left, plot_top, map_w, map_h);
  draw_legend(canvas, legend_x, plot_top, legend, view.px_per_m);
  return canvas;
}

Rgb time_colour(double t_s, double time_scale_s) noexcept {
  // A perceptually ordered ramp (after viridis' ends and middle), readable on white.
  constexpr std::array<Rgb, 5> kRamp{{{68, 1, 84}, {59, 82, 139}, {33, 145, 140}, {94, 201, 98}, {220, 200, 30}}};
  const double u = time_scale_s > 0 ? std::clamp(t_s / time_scale_s, 0.0, 1.0) * (kRamp.size() - 1) : 0.0;
  const std::size_t i = std::min<std::size_t>(static_cast<std::size_t>(u), kRamp.size() - 2);
  const double w = u - static_cast<double>(i);
  const auto mix = [w](std::uint8_t a, std::uint8_t b) {
    return static_cast<std::uint8_t>(std::lround(a + w * (static_cast<double>(b) - a)));
  };
  return {mix(kRamp[i].r, kRamp[i + 1].r), mix(kRamp[i].g, kRamp[i + 1].g), mix(kRamp[i].b, kRamp[i + 1].b)};
}

std::vector<RobotAt> robot_instants(std::span<const RobotAt> poses, double spacing_m) {
  std::vector<RobotAt> out;
  if (poses.empty()) return out;
  out.push_back(poses.front());
  double travelled = 0;
  for (std::size_t i = 1; i < poses.size(); ++i) {
    travelled += std::hypot(poses[i].pose.x_m - poses[i - 1].pose.x_m, poses[i].pose.y_m - poses[i - 1].pose.y_m);
    if (travelled >= spacing_m) {
      out.push_back(poses[i]);
      travelled = 0;
    }
  }
  // The last pose: instead of the previous one when they would nearly overlap.
  if (poses.size() > 1 && out.back().t_s != poses.back().t_s) {
    if (out.size() > 1 && travelled < spacing_m / 2) out.back() = poses.back();
    else out.push_back(poses.back());
  }
  return out;
}

}  // namespace sen3bot::figure
