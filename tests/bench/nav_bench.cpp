// Navigation benchmarks: prints timings, asserts nothing. Run from anywhere:
//   build/tests/bench/sen3bot_nav_bench [repetitions]
// Numbers are host wall-clock medians (p50) and 99th percentiles over the repetitions.
#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstdlib>
#include <numbers>
#include <string>
#include <vector>

#include "movingai.hpp"
#include "sen3bot/mem/budget_arena.hpp"
#include "sen3bot/nav/costmap.hpp"
#include "sen3bot/nav/crossings.hpp"
#include "sen3bot/nav/dynamic_obstacles.hpp"
#include "sen3bot/nav/global_planner.hpp"
#include "sen3bot/nav/local_planner.hpp"
#include "sen3bot/nav/localization.hpp"
#include "sen3bot/nav/map_ellipses.hpp"
#include "sen3bot/nav/people.hpp"
#include "sen3bot/nav/safety.hpp"
#include "sen3bot/nav/sgp.hpp"
#include "sen3bot/nav/waypoints.hpp"
#include "sen3bot/world/world.hpp"

namespace {

using namespace sen3bot;
using namespace sen3bot::nav;
using Clock = std::chrono::steady_clock;

struct Stats {
  double p50_ms = 0.0;
  double p99_ms = 0.0;
  double mean_ms = 0.0;
};

template <typename Body>
Stats measure(int repetitions, Body&& body) {
  std::vector<double> ms;
  ms.reserve(static_cast<std::size_t>(repetitions));
  for (int i = 0; i < repetitions; ++i) {
    const auto t0 = Clock::now();
    body(i);
    ms.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
  }
  std::sort(ms.begin(), ms.end());
  Stats s;
  s.p50_ms = ms[ms.size() / 2];
  s.p99_ms = ms[std::min(ms.size() - 1, ms.size() * 99 / 100)];
  for (double v : ms) s.mean_ms += v;
  s.mean_ms /= static_cast<double>(ms.size());
  return s;
}

ScanMessage lab_scan(const world::World& truth, const Pose2D& pose, std::uint16_t beams) {
  ScanMessage scan;
  scan.count = beams;
  scan.angle_min_rad = static_cast<float>(-M_PI / 2.0);
  scan.increment_rad = static_cast<float>(M_PI / (beams - 1));
  scan.range_max_m = 8.0f;
  truth.scan(pose, scan.angle_min_rad, scan.increment_rad, beams, scan.range_max_m,
             std::span<float>(scan.ranges_m.data(), beams));
  return scan;
}

}  // namespace

int main(int argc, char** argv) {
  const int reps = argc > 1 ? std::max(10, std::atoi(argv[1])) : 300;
  auto map = load_map(SEN3BOT_SOURCE_DIR "/config/maps/lab.yaml");
  auto waypoints = load_waypoints(SEN3BOT_SOURCE_DIR "/config/maps/lab_waypoints.txt");
  if (!map || !waypoints) {
    std::fprintf(stderr, "cannot load the lab map or waypoints\n");
    return 1;
  }
  const world::World truth(*map);
  mem::BudgetArena arena("bench", 64 << 20);

  // Global costmap and A*.
  StaticLayer st(*map);
  ObstacleLayer obs;
  InflationLayer infl;
  LayeredCostmap global;
  (void)global.add_layer(st);
  (void)global.add_layer(obs);
  (void)global.add_layer(infl);
  (void)global.init_over_map(*map, arena);
  global.update({});
  const Pose2D at_start{4.0, 7.0, -M_PI / 2.0};
  const ScanMessage scan361 = lab_scan(truth, at_start, 361);
  ProjectedScan view361;
  view361.assign(scan361.view(), {});
  Stats s = measure(reps, [&](int) { global.update({at_start, at_start, &view361}); });
  std::printf("global costmap update (160x190, static+obstacle+inflation, 361 beams): p50 %.3f ms  p99 %.3f ms\n", s.p50_ms, s.p99_ms);

  GlobalPlanner planner;
  GlobalPlannerConfig pcfg;
  (void)planner.init(pcfg, arena);
  std::vector<GridCell> path(global.costmap().size());
  PlanResult r;
  s = measure(reps, [&](int) { r = planner.plan_world(global.costmap(), {4.0, 7.0}, {2.5, 2.0}, {}, path); });
  std::printf("A* lab (4,7)->(2.5,2), cost-aware: %s, %zu expansions, %.2f m; p50 %.3f ms  p99 %.3f ms  (%.2f M expansions/s)\n",
              to_string(r.status), r.expansions, r.length_m, s.p50_ms, s.p99_ms, static_cast<double>(r.expansions) / s.p50_ms / 1000.0);
  std::vector<Point2D> reversed(waypoints->rbegin(), waypoints->rend());
  s = measure(reps, [&](int) { r = planner.plan_world(global.costmap(), {4.0, 7.0}, {2.5, 2.0}, reversed, path); });
  std::printf("A* lab with %zu waypoints: %s, %zu expansions, %u passed, %.2f m; p50 %.3f ms  p99 %.3f ms\n", reversed.size(),
              to_string(r.status), r.expansions, r.waypoints_passed, r.length_m, s.p50_ms, s.p99_ms);
  s = measure(reps, [&](int) { r = planner.plan_world(global.costmap(), {0.4, 0.4}, {7.6, 9.1}, {}, path); });
  std::printf("A* lab corner to corner: %s, %zu expansions; p50 %.3f ms  p99 %.3f ms\n", to_string(r.status), r.expansions,
              s.p50_ms, s.p99_ms);

  // Moving AI maps, unit cost.
  for (const char* name : {"random-32-32-10", "random-64-64-20", "maze-32-32-2", "room-32-32-4", "warehouse-64-32"}) {
    const std::string base = std::string(SEN3BOT_SOURCE_DIR) + "/tests/data/movingai/" + name;
    testing::MovingAiMap m;
    if (!testing::load_movingai_map(base + ".map", m)) continue;
    const auto scen = testing::load_movingai_scen(base + ".map.scen");
    Costmap2D grid;
    (void)grid.init(m.width, m.height, 1.0, arena);
    testing::fill_costmap(m, grid);
    GlobalPlanner unit;
    GlobalPlannerConfig ucfg;
    ucfg.unit_cost = true;
    ucfg.max_cells = grid.size();
    (void)unit.init(ucfg, arena);
    std::size_t expansions = 0;
    const Stats ms = measure(static_cast<int>(scen.size()) * 20, [&](int i) {
      const auto& sc = scen[static_cast<std::size_t>(i) % scen.size()];
      expansions += unit.plan(grid, sc.start, sc.goal, {}, path).expansions;
    });
    std::printf("A* Moving AI %-16s %zu scenarios: mean %.4f ms  p99 %.4f ms  (%.2f M expansions/s)\n", name, scen.size(),
                ms.mean_ms, ms.p99_ms, static_cast<double>(expansions) / (ms.mean_ms * static_cast<double>(scen.size()) * 20.0) / 1000.0);
  }

  // Local costmap (6 x 6 m rolling) for a 361-beam scan.
  StaticLayer lst(*map);
  ObstacleLayer lobs;
  InflationLayer linfl;
  LayeredCostmap local;
  (void)local.add_layer(lst);
  (void)local.add_layer(lobs);
  (void)local.add_layer(linfl);
  CostmapConfig lcfg;
  lcfg.rolling = true;
  (void)local.init(lcfg, arena);
  s = measure(reps * 3, [&](int i) {
    Pose2D p = at_start;
    p.y_m -= 0.002 * (i % 100);
    local.update({p, p, &view361});
  });
  std::printf("local costmap update (120x120 rolling, static+obstacle+inflation, 361 beams): p50 %.3f ms  p99 %.3f ms\n",
              s.p50_ms, s.p99_ms);
  s = measure(reps * 3, [&](int) { lobs.update(local.costmap(), {at_start, at_start, &view361}); });
  std::printf("  obstacle layer alone (raytrace + mark 361 beams): p50 %.3f ms\n", s.p50_ms);
  ProjectedScan projected;
  s = measure(reps * 3, [&](int) { projected.assign(scan361.view(), {0.16, 0.0, 0.0}); });
  std::printf("  scan projection, once per scan for each reader (361 beams): p50 %.4f ms\n", s.p50_ms);

  // Dynamic obstacle layer on the local costmap: three boxes going back and forth across the
  // view of a standing robot, a scan every update (detection + blobs + tracking + painting).
  // The static and obstacle layers run before it, untimed. Blob link 1 is 8-connectivity;
  // 2 (the default) also joins the pieces a box sliding along its face shows (fewer duplicate
  // tracks).
  world::World movers(*map);
  for (int i = 0; i < 3; ++i) {
    world::MoverScript box;
    box.path = {{2.9, 6.9 + 0.6 * i}, {5.3, 6.9 + 0.6 * i}};  // back and forth
    box.speed_m_s = 0.4 + 0.2 * i;
    box.size_m = 0.2;
    box.shape = world::MoverShape::square;
    movers.add_mover(box);
  }
  const auto percentile = [](std::vector<double> v, double q) {
    std::sort(v.begin(), v.end());
    return v[std::min(v.size() - 1, static_cast<std::size_t>(q * static_cast<double>(v.size())))];
  };
  for (const int link : {2, 1}) {
    StaticLayer dst(*map);
    ObstacleLayer dobs;
    LayeredCostmap dcm;
    (void)dcm.add_layer(dst);
    (void)dcm.add_layer(dobs);
    (void)dcm.init(lcfg, arena);
    DynamicObstacleConfig dcfg;
    dcfg.detector.blob_link_cells = link;
    DynamicObstacleLayer dol(dcfg, &*map);
    const Pose2D robot{4.0, 6.0, M_PI / 2.0};
    dcm.update({robot, robot, nullptr, 0});
    (void)dol.init(dcm.costmap(), arena);
    const SensorMount mount{0.1, 0.0, 0.0};
    ProjectedScan view;
    std::vector<double> with_scan;
    std::vector<double> paint_only;
    std::size_t confirmed = 0;
    const int updates = reps * 3;
    for (int i = 0; i < updates; ++i) {
      const hal::Nanos now = static_cast<hal::Nanos>(i) * 100'000'000;
      movers.set_time(static_cast<double>(i) * 0.1);
      ScanMessage scan = lab_scan(movers, compose(robot, mount), 361);
      scan.stamp_ns = now;
      view.assign(scan.view(), mount);
      dcm.update({robot, robot, &view, now});
      auto t0 = Clock::now();
      dol.update(dcm.costmap(), {robot, robot, &view, now});
      with_scan.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
      t0 = Clock::now();
      dol.update(dcm.costmap(), {robot, robot, nullptr, now + 50'000'000});
      paint_only.push_back(std::chrono::duration<double, std::milli>(Clock::now() - t0).count());
      for (const DolTrack& t : dol.tracks()) confirmed += t.confirmed ? 1 : 0;
    }
    std::printf("dynamic obstacle layer (120x120, 3 moving boxes, blob link %d: %.1f confirmed tracks on average): scan update "
                "p50 %.3f ms  p99 %.3f ms; repaint only p50 %.3f ms  p99 %.3f ms\n",
                link, static_cast<double>(confirmed) / updates, percentile(with_scan, 0.5), percentile(with_scan, 0.99),
                percentile(paint_only, 0.5), percentile(paint_only, 0.99));
    if (link != 2) continue;
    Costmap2D grid;
    (void)grid.init(120, 120, 0.05, arena);
    s = measure(reps * 10, [&](int i) {
      paint_mover(dcfg.cost, 3.0, 3.0, 0.6 * std::cos(0.1 * i), 0.6 * std::sin(0.1 * i), grid);
    });
    std::printf("  paint_mover alone (0.6 m/s, the default shape): p50 %.4f ms\n", s.p50_ms);
  }

  // DWA on the local costmap, following the lab plan.
  DwaPlanner dwa;
  DwaConfig dcfg;
  (void)dwa.init(dcfg, arena);
  (void)planner.plan_world(global.costmap(), {4.0, 7.0}, {2.5, 2.0}, {}, path);
  const PlanResult lab = planner.plan_world(global.costmap(), {4.0, 7.0}, {2.5, 2.0}, {}, path);
  std::vector<PathPoint> points;
  for (std::size_t i = 0; i < lab.cells; ++i) {
    double x = 0.0;
    double y = 0.0;
    global.costmap().cell_to_world(path[i].col, path[i].row, x, y);
    points.push_back({static_cast<float>(x), static_cast<float>(y)});
  }
  dwa.set_path(points);
  local.update({at_start, at_start, &view361});
  DwaCommand cmd;
  s = measure(reps * 3, [&](int) { cmd = dwa.compute(at_start, 0.3, 0.0, local.costmap()); });
  std::printf("DWA cycle (%d x %d = %u samples, %.1f s rollouts): p50 %.3f ms  p99 %.3f ms  (%u admissible)\n",
              dcfg.v_samples, dcfg.w_samples, cmd.evaluated, dcfg.sim_time_s, s.p50_ms, s.p99_ms, cmd.admissible);
  // With three tracked movers: two crossing ahead, and the worst case, one keeping pace inside
  // the margin beside the robot, which refuses every rollout and sends each through the
  // escape's touch checks.
  {
    const double c = std::cos(at_start.theta_rad);
    const double sn = std::sin(at_start.theta_rad);
    const auto ahead = [&](double fwd, double left, double v_fwd, double v_left) {
      return msg::MovingObstacle{0, at_start.x_m + c * fwd - sn * left, at_start.y_m + sn * fwd + c * left,
                                 c * v_fwd - sn * v_left, sn * v_fwd + c * v_left, 0.15, 0.0, 0.0};
    };
    const double side = dcfg.footprint.vertices[0].y_m + dcfg.footprint_padding_m + 0.2;
    for (const bool beside : {false, true}) {
      const std::array<msg::MovingObstacle, 3> three = {ahead(1.5, -1.0, 0.0, 0.8), ahead(2.5, 1.5, 0.0, -0.8),
                                                         beside ? ahead(0.0, side, 0.3, 0.0) : ahead(3.0, -2.0, 0.0, 0.8)};
      s = measure(reps * 3, [&](int) { cmd = dwa.compute(at_start, 0.3, 0.0, local.costmap(), three); });
      std::printf("DWA cycle with 3 movers, %s: p50 %.3f ms  p99 %.3f ms  (%u admissible, %u refused)\n",
                  beside ? "one beside inside the margin (every rollout refused)" : "crossing ahead", s.p50_ms, s.p99_ms,
                  cmd.admissible, cmd.mover_rejected);
    }
  }

  // Among people: the control step's people-dependent parts with the messages full (16 laser
  // movers and 16 tracked people, every one walking across the robot's way within 4 m): the DWA
  // with its mover check, the crossing gate and making way over the 32 tracks, and the safety
  // filter with the sonar ring.
  {
    const double c = std::cos(at_start.theta_rad);
    const double sn = std::sin(at_start.theta_rad);
    msg::MovingObstacles walkers;
    msg::People people;
    std::vector<CrossingTrack> tracks;
    for (std::size_t i = 0; i < msg::MovingObstacles::kMax; ++i) {
      const double fwd = 0.8 + 0.2 * static_cast<double>(i);
      const double left = (i % 2 == 0 ? -1.0 : 1.0) * (0.8 + 0.1 * static_cast<double>(i % 5));
      const double v_left = (i % 2 == 0 ? 1.0 : -1.0) * (0.6 + 0.05 * static_cast<double>(i % 7));
      const double x = at_start.x_m + c * fwd - sn * left, y = at_start.y_m + sn * fwd + c * left;
      const double vx = -sn * v_left, vy = c * v_left;
      walkers.items[i] = {static_cast<std::uint32_t>(i + 1), x, y, vx, vy, 0.25, 0.0, 0.0};
      msg::TrackedPerson& p = people.items[i];
      p.id = static_cast<std::uint32_t>(i + 1);
      p.x_m = x + 0.3 * c;
      p.y_m = y + 0.3 * sn;
      p.vx_m_s = vx;
      p.vy_m_s = vy;
      p.width_m = 0.45;
      p.cage_radius_m = 0.725;
      tracks.push_back({walkers.items[i].id, x, y, vx, vy, 0.75, 0.25});
      tracks.push_back({p.id | 0x8000'0000u, p.x_m, p.y_m, vx, vy, 0.725, 0.225});
    }
    walkers.count = static_cast<std::uint8_t>(msg::MovingObstacles::kMax);
    people.count = static_cast<std::uint8_t>(msg::People::kMax);
    s = measure(reps * 3, [&](int) {
      cmd = dwa.compute(at_start, 0.3, 0.0, local.costmap(), std::span(walkers.items.data(), walkers.count));
    });
    std::printf("DWA cycle with 16 walkers crossing within 4 m: p50 %.3f ms  p99 %.3f ms  (%u admissible, %u refused)\n",
                s.p50_ms, s.p99_ms, cmd.admissible, cmd.mover_rejected);
    LaneMap lanes;
    (void)lanes.init({}, -1.0, -1.0, 10.0, 12.0, arena);
    for (const CrossingTrack& t : tracks) lanes.walk(t.x_m, t.y_m, t.body_m, 100.0);
    CrossingGate gate;
    CrossingConfig on;
    on.enabled = true;
    (void)gate.init(on, dcfg.footprint.circumscribed_radius_m(), dcfg.max_v_m_s, dcfg.acc_v_m_s2);
    CrossingDecision decision;
    s = measure(reps * 10, [&](int) {
      decision = gate.decide({at_start, 0.3, std::span<const PathPoint>(points), tracks, &lanes, 100.0});
    });
    std::printf("crossing gate over 32 walking tracks (4 m of path, 6 s): p50 %.3f ms  p99 %.3f ms  (%s)\n", s.p50_ms,
                s.p99_ms, msg::to_string(decision.action));
    MakeWayConfig way;
    way.enabled = true;
    MakeWayDecision made;
    s = measure(reps * 10, [&](int) { made = make_way(way, at_start, 0.0, dcfg.footprint.circumscribed_radius_m(), tracks); });
    std::printf("making way over 32 walking tracks: p50 %.4f ms  p99 %.4f ms\n", s.p50_ms, s.p99_ms);
    SafetyConfig scfg;
    scfg.mover_cage_m = 0.5;
    const SafetyFilter filter(scfg);
    msg::Sonar sonar;
    sonar.count = 16;
    for (std::size_t d = 0; d < 16; ++d) {
      sonar.mount[d] = {0.0, 0.0, static_cast<double>(d) * std::numbers::pi / 8.0};
      sonar.range_m[d] = 1.0 + 0.1 * static_cast<double>(d);
      sonar.stamp_ns[d] = 0;
    }
    SafetyInputs in;
    in.scan = &view361;
    in.odom_stamp_ns = view361.stamp_ns();
    in.now_ns = view361.stamp_ns() + 50'000'000;
    in.requested = {0.4, 0.1, in.now_ns};
    in.measured_v_m_s = 0.4;
    in.pose = at_start;
    walkers.stamp_ns = in.now_ns;
    people.stamp_ns = in.now_ns;
    in.movers = &walkers;
    in.people = &people;
    in.sonar = &sonar;
    SafetyOutput out;
    s = measure(reps * 10, [&](int) { out = filter.filter(in); });
    std::printf("safety filter with 16 people, 16 movers and the sonar ring: p50 %.3f ms  p99 %.3f ms  (reasons 0x%x)\n",
                s.p50_ms, s.p99_ms, out.reasons);
  }

  // SGP on the lab: the map's ellipses (once per map, with the curve's check), then the field's
  // path for the thesis query (4, 7) -> (2.5, 2) m on the lab's safe curve (lab_curve.yaml, a
  // loop through the door), both directions of zeta integrated as the planner task does.
  {
    MapEllipsesConfig ecfg;
    mem::BudgetArena earena("ellipses", MapEllipses::storage_bytes(ecfg));
    MapEllipses ellipses;
    (void)ellipses.init(ecfg, earena);
    s = measure(reps, [&](int) { (void)ellipses.fit(*map); });
    std::printf("SGP map ellipses (lab, %zu ellipses, %zu splits): p50 %.3f ms  p99 %.3f ms\n", ellipses.ellipses().size(),
                ellipses.splits(), s.p50_ms, s.p99_ms);
    const SafeCurve loop = SafeCurve::ellipse({4.95, 4.78}, 2.1, 0.8, 0.0);  // config/maps/lab_curve.yaml
    s = measure(reps, [&](int) { (void)check_curve(loop, map_extent(*map), ellipses.ellipses()); });
    std::printf("SGP curve check (lab loop against %zu ellipses): p50 %.3f ms  p99 %.3f ms\n", ellipses.ellipses().size(),
                s.p50_ms, s.p99_ms);
    mem::BudgetArena sarena("sgp", 1 << 20);
    SupervisoryPlanner sgp;
    (void)sgp.init({}, sarena);
    (void)sgp.set_site(loop, map_extent(*map), ellipses.ellipses());
    SgpResult sr;
    s = measure(reps, [&](int) { sr = sgp.plan({4.0, 7.0}, {2.5, 2.0}); });
    std::printf("SGP plan (lab, thesis query (4, 7) -> (2.5, 2) m on the lab loop, both directions): "
                "p50 %.3f ms  p99 %.3f ms  (%s, %zu waypoints, %.2f m, %d steps, min b %.3g)\n",
                s.p50_ms, s.p99_ms, to_string(sr.stop), sgp.waypoints().size(), sr.length_m, sr.steps, sr.min_barrier);
    s = measure(reps, [&](int) { sr = sgp.plan({1.0, 8.9}, {7.0, 1.0}); });
    std::printf("SGP plan (lab, (1, 8.9) -> (7, 1) m: from the far corner round the racks): "
                "p50 %.3f ms  p99 %.3f ms  (%s, %zu waypoints, %.2f m, %d steps)\n",
                s.p50_ms, s.p99_ms, to_string(sr.stop), sgp.waypoints().size(), sr.length_m, sr.steps);
  }

  constexpr double kPi = std::numbers::pi;
  // Camera-laser fusion: a 361-beam scan (legs in front of a wall at 5 m) and 8 person boxes
  // spread across the image, against the lab map's background, then the tracker.
  {
    mem::BudgetArena farena("fusion", 64 * 1024);
    PeopleFusion fusion;
    (void)fusion.init({}, {}, &*map, 401, farena);
    std::vector<float> ranges(361);
    for (std::size_t i = 0; i < ranges.size(); ++i) {
      const double a = -kPi / 2 + static_cast<double>(i) * kPi / 360.0;
      ranges[i] = static_cast<float>(std::min(5.0 / std::max(std::cos(a), 0.05), 9.0));
      if (std::abs(a) < 0.6 && static_cast<int>(i) % 12 < 3) ranges[i] = 2.0f + 0.05f * static_cast<float>(i % 5);
    }
    const msg::ScanView scan{ranges, static_cast<float>(-kPi / 2), static_cast<float>(kPi / 360.0), 0.05f, 30.0f, 0};
    msg::PersonDetections frame;
    for (std::size_t b = 0; b < 8; ++b) {
      const float u0 = 100.0f + 140.0f * static_cast<float>(b);
      frame.boxes[b] = {u0, 20.0f, u0 + 120.0f, 700.0f, 0.9f, 0};
    }
    frame.count = 8;
    std::array<PersonFix, 8> fixes{};
    std::size_t placed = 0;
    s = measure(reps * 10, [&](int) { placed = fusion.fuse(scan, {2.5, 2.0, kPi / 2}, frame, fixes); });
    std::printf("people fusion (361 beams, 8 boxes, lab background): p50 %.4f ms  p99 %.4f ms  (%zu placed)\n", s.p50_ms,
                s.p99_ms, placed);
    PersonTracker tracker;
    (void)tracker.init({}, farena);
    hal::Nanos t = 0;
    s = measure(reps * 10, [&](int) { tracker.update(std::span(fixes).first(placed), t += 100'000'000); });
    std::printf("person tracker update (%zu fixes, %zu tracks): p50 %.4f ms  p99 %.4f ms\n", placed,
                tracker.tracks().size(), s.p50_ms, s.p99_ms);
  }

  // MCL sensor update: particles x 60 beams.
  for (const std::size_t particles : {500u, 1000u, 2000u}) {
    MclConfig mcfg;
    mcfg.min_particles = particles;
    mcfg.max_particles = particles;
    mcfg.initial_pose = at_start;
    mcfg.update_max_interval_s = 1e-9;  // every call updates
    mem::BudgetArena marena("mcl", MonteCarloLocalization::storage_bytes(mcfg, *map));
    MonteCarloLocalization mcl;
    (void)mcl.init(mcfg, *map, marena);
    hal::Nanos t = 0;
    s = measure(reps, [&](int) {
      t += 1000;
      const Odometry o{0.0, 0.0, 0.0, 0.0, 0.0, t, true};
      (void)mcl.update(o, &view361);
    });
    std::printf("MCL update (%zu particles x 60 beams, motion + likelihood + KLD resample): p50 %.3f ms  p99 %.3f ms  (arena %zu B)\n",
                particles, s.p50_ms, s.p99_ms, marena.used_bytes());
  }
  return 0;
}
