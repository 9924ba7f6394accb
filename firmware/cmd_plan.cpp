// `sen3bot plan`: one global plan on a map, printed as JSON. The costmap is the planner
// task's (static layer, inflation, the same clearance band), or with --unit-cost the bare
// occupancy grid (occupied cells blocked, everything else free at unit cost: pure grid
// geometry, so lengths can be checked against benchmark optima).
#include <chrono>
#include <cmath>
#include <cstdlib>
#include <memory_resource>
#include <string>
#include <string_view>
#include <vector>

#include "cli_util.hpp"
#include "sen3bot/json/json.hpp"
#include "commands.hpp"
#include "sen3bot/nav/costmap.hpp"
#include "sen3bot/nav/global_planner.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/nav/nav_tasks.hpp"
#include "sen3bot/nav/waypoints.hpp"

namespace sen3bot::firmware {

namespace {

constexpr const char* kPlanUsage =
    "usage: sen3bot plan --map MAP.yaml --start X,Y --goal X,Y [--waypoints FILE] [--unit-cost]\n";

}  // namespace

int plan_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  std::string map_path, waypoints_path;
  nav::Point2D start, goal;
  bool have_start = false, have_goal = false, unit_cost = false;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--unit-cost") {
      unit_cost = true;
    } else if (arg == "--map" && has_value) {
      map_path = argv[++i];
    } else if (arg == "--waypoints" && has_value) {
      waypoints_path = argv[++i];
    } else if ((arg == "--start" || arg == "--goal") && has_value) {
      nav::Point2D& p = arg == "--start" ? start : goal;
      if (!parse_point_m(argv[++i], p)) {
        std::fprintf(err, "sen3bot plan: %s: expected X,Y in metres, got '%s'\n", argv[i - 1], argv[i]);
        return 2;
      }
      (arg == "--start" ? have_start : have_goal) = true;
    } else {
      std::fprintf(err, "sen3bot plan: unknown or incomplete option '%s'\n%s", argv[i], kPlanUsage);
      return 2;
    }
  }
  if (map_path.empty() || !have_start || !have_goal) {
    std::fprintf(err, "sen3bot plan: --map, --start and --goal are required\n%s", kPlanUsage);
    return 2;
  }

  Result<nav::OccupancyMap> map = nav::load_map(map_path);
  if (!map) {
    std::fprintf(err, "sen3bot plan: %s\n", map.error().c_str());
    return 2;
  }
  std::vector<nav::Point2D> waypoints;
  if (!waypoints_path.empty()) {
    Result<std::vector<nav::Point2D>> loaded = nav::load_waypoints(waypoints_path);
    if (!loaded) {
      std::fprintf(err, "sen3bot plan: %s\n", loaded.error().c_str());
      return 2;
    }
    waypoints = std::move(*loaded);
  }

  // The planner task's costmap and bar, or the bare grid.
  const nav::PlannerTaskConfig task;
  nav::StaticLayer static_layer(*map, task.static_layer);
  nav::InflationLayer inflation(task.inflation);
  nav::LayeredCostmap costmap;
  std::pmr::monotonic_buffer_resource arena;
  Status s = costmap.add_layer(static_layer);
  if (s && !unit_cost) s = costmap.add_layer(inflation);
  if (s) s = costmap.init_over_map(*map, arena);
  if (!s) {
    std::fprintf(err, "sen3bot plan: %s: %s\n", map_path.c_str(), s.error().c_str());
    return 2;
  }
  costmap.update({});
  nav::GlobalPlannerConfig config = task.planner;
  config.max_cells = costmap.costmap().size();
  config.max_waypoints = std::max(config.max_waypoints, waypoints.size());
  config.unit_cost = unit_cost;
  if (!unit_cost && task.plan_clearance_m > 0.0)
    config.blocked_cost = std::min(config.blocked_cost, nav::InflationLayer::cost_at(task.plan_clearance_m, task.inflation));
  nav::GlobalPlanner planner;
  if (Status init = planner.init(config, arena); !init) {
    std::fprintf(err, "sen3bot plan: %s\n", init.error().c_str());
    return 1;
  }
  std::vector<nav::GridCell> path(costmap.costmap().size());
  const auto begin = std::chrono::steady_clock::now();
  const nav::PlanResult r = planner.plan_world(costmap.costmap(), start, goal, waypoints, path);
  const double time_ms = std::chrono::duration<double, std::milli>(std::chrono::steady_clock::now() - begin).count();
  switch (r.status) {
    case nav::PlanStatus::ok: break;
    case nav::PlanStatus::start_outside:
    case nav::PlanStatus::goal_outside:
    case nav::PlanStatus::start_blocked:
    case nav::PlanStatus::goal_blocked:
      std::fprintf(err, "sen3bot plan: %s (start %.3f,%.3f goal %.3f,%.3f)\n", nav::to_string(r.status), start.x_m,
                   start.y_m, goal.x_m, goal.y_m);
      return 2;
    default:
      std::fprintf(err, "sen3bot plan: %s after %zu expansions\n", nav::to_string(r.status), r.expansions);
      return 1;
  }
  json::FileSink sink(out);
  json::Writer w(sink, json::Style::spaced);
  w.begin_object()
      .key("length_m").fixed_or_null(r.length_m, 6)
      .member_uint64("cells", r.cells)
      .member_uint64("expansions", r.expansions)
      .key("time_ms").fixed_or_null(time_ms, 3)
      .key("cost").fixed_or_null(r.cost, 3)
      .member_uint32("waypoints_passed", r.waypoints_passed)
      .member_bool("unit_cost", unit_cost)
      .key("path").begin_array();
  for (std::size_t i = 0; i < r.cells; ++i) {
    double x = 0, y = 0;
    costmap.costmap().cell_to_world(path[i].col, path[i].row, x, y);
    w.begin_array().fixed_or_null(x, 3).fixed_or_null(y, 3).end_array();
  }
  w.end_array().end_object();
  std::fputc('\n', out);
  return 0;
}

}  // namespace sen3bot::firmware
