// `sen3bot sgp`: the supervisory planner on a map and a safe curve, printed as JSON, and drawn
// (map, ellipses, curve, quiver, waypoints) with --png. The same steps as the planner task:
// the map's ellipses, the curve checked against them, the field integrated from the start.
#include <chrono>
#include <cmath>
#include <memory_resource>
#include <numbers>
#include <string>
#include <string_view>

#include "cli_util.hpp"
#include "sen3bot/json/json.hpp"
#include "commands.hpp"
#include "safe_curve.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/nav/map_ellipses.hpp"
#include "sen3bot/nav/sgp.hpp"
#include "sen3bot/nav_figure/sgp_layer.hpp"

namespace sen3bot::firmware {

namespace {

constexpr const char* kSgpUsage =
    "usage: sen3bot sgp --map MAP.yaml --curve CURVE.yaml --start X,Y --goal X,Y [--direction 1|-1] [--png FILE]\n";

std::string file_name(const std::string& path) {
  const std::size_t slash = path.find_last_of('/');
  return slash == std::string::npos ? path : path.substr(slash + 1);
}

bool write_figure(const std::string& png, const std::string& map_path, const std::string& curve_path,
                  const nav::OccupancyMap& map, const nav::SupervisoryPlanner& sgp, const nav::SgpResult& r,
                  nav::Point2D start, nav::Point2D goal) {
  figure::CaseFigure f;
  char line[256];
  std::snprintf(line, sizeof line, "SGP: (%.2f, %.2f) m to (%.2f, %.2f) m", start.x_m, start.y_m, goal.x_m, goal.y_m);
  f.title = line;
  f.description = "map " + file_name(map_path) + ", safe curve " + file_name(curve_path) +
                  "; arrows: the field's direction (eq. 1.4) with the sign of zeta taken";
  std::snprintf(line, sizeof line,
                "%s after %.2f m, %d steps (zeta %s); %zu waypoints, least b %.3g, %.2f m short of the goal",
                nav::to_string(r.stop), r.length_m, r.steps, r.direction > 0 ? "+" : "-", sgp.waypoints().size(),
                r.min_barrier, r.goal_distance_m);
  f.result = line;
  f.passed = r.stop == nav::SgpStop::nearest_to_goal;
  f.map = &map;
  f.waypoints.assign(sgp.waypoints().begin(), sgp.waypoints().end());
  f.start = {start.x_m, start.y_m, 0.0};
  f.goals = {goal};
  figure::add_sgp_layer(f, sgp, r.direction, 0.25);
  return figure::draw_case_figure(f).write_png(png);
}

}  // namespace

int sgp_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  std::string map_path, curve_path, png;
  nav::Point2D start, goal;
  bool have_start = false, have_goal = false;
  int direction = 0;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--map" && has_value) {
      map_path = argv[++i];
    } else if (arg == "--curve" && has_value) {
      curve_path = argv[++i];
    } else if (arg == "--png" && has_value) {
      png = argv[++i];
    } else if (arg == "--direction" && has_value) {
      const std::string_view d = argv[++i];
      if (d != "1" && d != "+1" && d != "-1") {
        std::fprintf(err, "sen3bot sgp: --direction: expected 1 or -1, got '%s'\n", argv[i]);
        return 2;
      }
      direction = d == "-1" ? -1 : 1;
    } else if ((arg == "--start" || arg == "--goal") && has_value) {
      nav::Point2D& p = arg == "--start" ? start : goal;
      if (!parse_point_m(argv[++i], p)) {
        std::fprintf(err, "sen3bot sgp: %s: expected X,Y in metres, got '%s'\n", argv[i - 1], argv[i]);
        return 2;
      }
      (arg == "--start" ? have_start : have_goal) = true;
    } else {
      std::fprintf(err, "sen3bot sgp: unknown or incomplete option '%s'\n%s", argv[i], kSgpUsage);
      return 2;
    }
  }
  if (map_path.empty() || curve_path.empty() || !have_start || !have_goal) {
    std::fprintf(err, "sen3bot sgp: --map, --curve, --start and --goal are required\n%s", kSgpUsage);
    return 2;
  }
  Result<nav::OccupancyMap> map = nav::load_map(map_path);
  if (!map) {
    std::fprintf(err, "sen3bot sgp: %s\n", map.error().c_str());
    return 2;
  }
  Result<SiteCurve> curve = load_safe_curve(curve_path);
  if (!curve) {
    std::fprintf(err, "sen3bot sgp: %s\n", curve.error().c_str());
    return 2;
  }
  const nav::CurveBounds bounds = curve->has_bounds ? curve->bounds : nav::map_extent(*map);

  std::pmr::monotonic_buffer_resource arena;
  nav::MapEllipsesConfig fit_config;
  fit_config.max_map_cells = std::max(fit_config.max_map_cells, map->cells().size());
  fit_config.max_map_rows = std::max(fit_config.max_map_rows, map->height());
  nav::MapEllipses ellipses;
  Status s = ellipses.init(fit_config, arena);
  const auto fit_begin = std::chrono::steady_clock::now();
  if (s) s = ellipses.fit(*map);
  const double fit_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - fit_begin).count();
  if (!s) {
    std::fprintf(err, "sen3bot sgp: %s: %s\n", map_path.c_str(), s.error().c_str());
    return 2;
  }
  nav::SgpConfig config;
  config.max_ellipses = std::max<std::size_t>(ellipses.ellipses().size(), 1);
  nav::SupervisoryPlanner sgp;
  if (s = sgp.init(config, arena); !s) {
    std::fprintf(err, "sen3bot sgp: %s\n", s.error().c_str());
    return 1;
  }
  if (s = sgp.set_site(curve->curve, bounds, ellipses.ellipses()); !s) {
    std::fprintf(err, "sen3bot sgp: %s on %s: %s\n", curve_path.c_str(), map_path.c_str(), s.error().c_str());
    return 2;
  }
  const auto begin = std::chrono::steady_clock::now();
  const nav::SgpResult r = sgp.plan(start, goal, direction);
  const double time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();

  json::FileSink sink(out);
  json::Writer w(sink, json::Style::spaced);
  w.begin_object()
      .member("stop", nav::to_string(r.stop))
      .member_int64("direction", r.direction)
      .key("length_m").fixed_or_null(r.length_m, 6)
      .member_int64("iterations", r.steps)
      .key("time_ms").fixed_or_null(time_ms, 3)
      .key("fit_time_ms").fixed_or_null(fit_ms, 3)
      .key("min_barrier");
  if (std::isfinite(r.min_barrier)) w.general(r.min_barrier, 6);
  else w.null();
  w.key("goal_distance_m").fixed_or_null(r.goal_distance_m, 6).member_bool("on_curve", r.on_curve).key("waypoints").begin_array();
  for (const nav::Point2D& p : sgp.waypoints()) w.begin_array().fixed_or_null(p.x_m, 4).fixed_or_null(p.y_m, 4).end_array();
  w.end_array().key("ellipses").begin_array();
  for (const nav::Ellipse& e : sgp.obstacles()) {
    w.begin_object()
        .key("centre").begin_array().fixed_or_null(e.cx_m, 4).fixed_or_null(e.cy_m, 4).end_array()
        .key("semi_axes").begin_array().fixed_or_null(e.semi_major_m, 4).fixed_or_null(e.semi_minor_m, 4).end_array()
        .key("angle_deg").fixed_or_null(e.angle_rad * 180.0 / std::numbers::pi, 3)
        .member_uint32("cells", e.cells)
        .end_object();
  }
  w.end_array().end_object();
  std::fputc('\n', out);
  if (!png.empty() && !write_figure(png, map_path, curve_path, *map, sgp, r, start, goal)) {
    std::fprintf(err, "sen3bot sgp: cannot write %s\n", png.c_str());
    return 1;
  }
  return r.stop == nav::SgpStop::nearest_to_goal ? 0 : 1;
}

}  // namespace sen3bot::firmware
