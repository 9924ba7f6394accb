// Simulated workers (workers.hpp). A walk is made in two passes: the body's track at a fine
// time step (routes, style, dwells), then the robot's view of it at the scan rate.
#include "sen3bot/sim/cobot/workers.hpp"

#include <algorithm>
#include <cmath>
#include <limits>
#include <memory_resource>
#include <numbers>
#include <optional>
#include <random>
#include <vector>

#include "sen3bot/msg/point_math.hpp"
#include "sen3bot/nav/costmap.hpp"
#include "sen3bot/nav/global_planner.hpp"

namespace sen3bot::cobot {

namespace {

using msg::Point2D;

// The worker's costmap: a body of 0.2 m radius keeps 0.1 m off shelves at the least (the
// inscribed radius: the planner never goes closer); costs graded out to 1 m so a style's
// preferred clearance is a cost threshold.
constexpr double kBodyClearanceM = 0.3;
constexpr double kInflationRadiusM = 1.0;
constexpr double kCostScaling = 4.0;
constexpr double kPersonCostWeight = 1.0;     // A* keeps to the middle of aisles, as people do
constexpr double kRobotClearanceM = 0.5;      // the reference route's preferred clearance
constexpr double kDenseStepM = 0.02;          // a leg's route as points this far apart
constexpr double kStepS = 0.02;               // the body's track time step
constexpr double kRampM = 0.6;                // speeding up from and slowing down to a stand
constexpr double kRampFloor = 0.3;            // the slowest fraction of the leg's speed
constexpr double kShiftTauS = 1.5;            // a standing worker drifts back to their spot
constexpr double kStartBlendS = 0.4;          // leaving a stand: the shift fades over this
constexpr double kDetourLegM = 2.0;           // legs shorter than this get no detour
constexpr double kDetourHalfM = 0.7;          // a detour leaves and rejoins this far either side
constexpr double kEngageMinS = 1.0;           // the worker at the first station once recorded
constexpr double kEngageMaxS = 4.0;
constexpr double kTrailStepM = 0.1;           // the following robot's breadcrumbs
constexpr double kCaughtUpSlackM = 0.3;       // a following robot this near its distance has caught up
constexpr long kSettleScans = 10;             // scans recorded after it caught up at the end
constexpr double kMaxExtensionS = 60.0;       // it gives up recording this long after the walk
constexpr std::int8_t kLaserBlocking = 50;    // map occupancy that stops a beam
constexpr std::uint8_t kBlocked = nav::kInscribedCost;

// The styles. Training: four ways of walking; held out: a rushed worker faster than any of
// them who cuts corners tighter, stops farther from the stations and works for very irregular
// times (docs/cobot/recognition.md, "Walking styles").
const WorkerStyle kTrainingStyles[] = {
    {.name = "direct",
     .description = "brisk, straight, short dwells, stops right at the station",
     .speed_m_s = 1.2, .speed_spread = 0.1, .sway_m = 0.02, .sway_hz = 0.95, .clearance_m = 0.4,
     .turn_radius_m = 0.3, .wide_turn_m = 0.0, .detour_probability = 0.0, .detour_m = 0.0,
     .pause_probability = 0.0, .pause_max_s = 0.0, .dwell_min_s = 3.0, .dwell_max_s = 9.0, .dwell_skew = 1.0,
     .dwell_shift_m = 0.04, .approach_m = 0.1},
    {.name = "relaxed",
     .description = "slower, swaying, rounds corners, works a while",
     .speed_m_s = 0.95, .speed_spread = 0.12, .sway_m = 0.07, .sway_hz = 0.85, .clearance_m = 0.5,
     .turn_radius_m = 0.5, .wide_turn_m = 0.1, .detour_probability = 0.1, .detour_m = 0.3,
     .pause_probability = 0.1, .pause_max_s = 2.0, .dwell_min_s = 6.0, .dwell_max_s = 14.0, .dwell_skew = 1.0,
     .dwell_shift_m = 0.06, .approach_m = 0.2},
    {.name = "hesitant",
     .description = "slow, stops on the way, small detours, long dwells moving about",
     .speed_m_s = 0.8, .speed_spread = 0.15, .sway_m = 0.04, .sway_hz = 0.8, .clearance_m = 0.45,
     .turn_radius_m = 0.3, .wide_turn_m = 0.0, .detour_probability = 0.5, .detour_m = 0.5,
     .pause_probability = 0.4, .pause_max_s = 4.0, .dwell_min_s = 8.0, .dwell_max_s = 20.0, .dwell_skew = 1.0,
     .dwell_shift_m = 0.08, .approach_m = 0.25},
    {.name = "wide",
     .description = "keeps well off shelves, swings wide round corners",
     .speed_m_s = 1.05, .speed_spread = 0.1, .sway_m = 0.04, .sway_hz = 0.9, .clearance_m = 0.65,
     .turn_radius_m = 0.8, .wide_turn_m = 0.4, .detour_probability = 0.1, .detour_m = 0.3,
     .pause_probability = 0.0, .pause_max_s = 0.0, .dwell_min_s = 5.0, .dwell_max_s = 12.0, .dwell_skew = 1.0,
     .dwell_shift_m = 0.05, .approach_m = 0.3},
};

const WorkerStyle kHeldOutStyle{
    .name = "rushed",
    .description = "fast, cuts corners tight, stops short of stations, dwells from a second to a quarter minute",
    .speed_m_s = 1.45, .speed_spread = 0.1, .sway_m = 0.03, .sway_hz = 1.05, .clearance_m = 0.3,
    .turn_radius_m = 0.15, .wide_turn_m = 0.0, .detour_probability = 0.2, .detour_m = 0.3,
    .pause_probability = 0.1, .pause_max_s = 1.5, .dwell_min_s = 1.0, .dwell_max_s = 16.0, .dwell_skew = 3.0,
    .dwell_shift_m = 0.1, .approach_m = 0.35};

// [0, 1) from the top 53 bits of one draw: the same on every platform and standard library.
double uniform(std::mt19937_64& rng) noexcept { return static_cast<double>(rng() >> 11) * 0x1.0p-53; }
double uniform(std::mt19937_64& rng, double lo, double hi) noexcept { return lo + (hi - lo) * uniform(rng); }
double normal(std::mt19937_64& rng) noexcept {  // Box-Muller
  const double u1 = 1.0 - uniform(rng);        // (0, 1]
  const double u2 = uniform(rng);
  return std::sqrt(-2.0 * std::log(u1)) * std::cos(2.0 * std::numbers::pi * u2);
}

Point2D unit(Point2D a) noexcept { return msg::unit_or(a, Point2D{1.0, 0.0}); }

double polyline_length(const std::vector<Point2D>& v) noexcept {
  double l = 0;
  for (std::size_t i = 1; i < v.size(); ++i) l += norm(v[i] - v[i - 1]);
  return l;
}

// Points every `step` along a polyline, both ends included.
std::vector<Point2D> resample(const std::vector<Point2D>& v, double step) {
  std::vector<Point2D> out;
  if (v.empty()) return out;
  out.push_back(v.front());
  double carried = 0;  // distance since the last point written
  for (std::size_t i = 1; i < v.size(); ++i) {
    const Point2D a = v[i - 1], b = v[i];
    const double len = norm(b - a);
    double at = step - carried;
    while (at <= len) {
      out.push_back(a + (at / len) * (b - a));
      at += step;
    }
    carried = len - (at - step);
  }
  if (norm(out.back() - v.back()) > 1e-6) out.push_back(v.back());
  return out;
}


// A worker drawn from a style: their pace, sway, clearance and how tight they take corners.
struct Worker {
  double speed = 0;                              // m/s
  double sway = 0, sway_hz = 0, sway_phase = 0;  // side to side: m, Hz, rad
  double clearance = 0;                          // kept off shelves
  double turn_radius = 0;                        // corners rounded this wide
};

Worker draw_worker(const WorkerStyle& style, std::mt19937_64& rng) {
  Worker k;
  k.speed = style.speed_m_s * (1.0 + style.speed_spread * uniform(rng, -1.0, 1.0));
  k.sway = style.sway_m * uniform(rng, 0.7, 1.3);
  k.sway_hz = style.sway_hz * uniform(rng, 0.9, 1.1);
  k.sway_phase = uniform(rng, 0.0, 2.0 * std::numbers::pi);
  k.clearance = std::max(kBodyClearanceM, style.clearance_m + uniform(rng, -0.05, 0.05));
  k.turn_radius = style.turn_radius_m * uniform(rng, 0.7, 1.3);
  return k;
}

// How long the worker works at a station: the style's dwell, skewed towards its short end.
double dwell_s(const WorkerStyle& style, std::mt19937_64& rng) {
  return style.dwell_min_s + (style.dwell_max_s - style.dwell_min_s) * std::pow(uniform(rng), style.dwell_skew);
}

// The body's track every kStepS.
struct Track {
  std::vector<Point2D> points;
  Point2D shift{0, 0};  // a standing worker's offset from their spot
};

// The robot that follows the worker: along the worker's breadcrumbs at its top speed until it
// is its distance behind them.
struct Follower {
  Point2D robot;
  std::vector<Point2D> trail;
  std::size_t trail_head = 0;

  void step(Point2D body, const Observer& observer) {
    if (norm(body - trail.back()) >= kTrailStepM) trail.push_back(body);
    double budget = observer.robot_speed_m_s * kStepS;
    while (budget > 0 && trail_head < trail.size() && norm(body - robot) > observer.follow_distance_m) {
      const Point2D target = trail[trail_head];
      const double d = norm(target - robot);
      if (d <= budget) {
        robot = target;
        budget -= d;
        ++trail_head;
      } else {
        robot = robot + (budget / d) * (target - robot);
        budget = 0;
      }
    }
  }
};

// The recorder's rule (cobot::PathRecorder): farther than the spacing from the last point;
// when full, every other point dropped (the first and the newest kept) and the spacing doubled.
void record_point(WorkerWalk& out, Point2D hit, double& spacing) {
  auto far_enough = [&]() {
    if (out.points() == 0) return true;
    const Point2D last{out.xy[out.xy.size() - 2], out.xy.back()};
    return norm(hit - last) > spacing;
  };
  if (!far_enough()) return;
  if (out.points() == kMaxPathPoints) {
    const std::size_t newest = out.points() - 1;
    std::size_t kept = 0;
    for (std::size_t k = 0; k <= newest; k += 2, ++kept) {
      out.xy[2 * kept] = out.xy[2 * k];
      out.xy[2 * kept + 1] = out.xy[2 * k + 1];
    }
    if (newest % 2 != 0) {
      out.xy[2 * kept] = out.xy[2 * newest];
      out.xy[2 * kept + 1] = out.xy[2 * newest + 1];
      ++kept;
    }
    out.xy.resize(2 * kept);
    spacing *= 2.0;
    ++out.halvings;
    if (!far_enough()) return;
  }
  out.xy.push_back(static_cast<float>(hit.x_m));
  out.xy.push_back(static_cast<float>(hit.y_m));
}

}  // namespace

std::span<const WorkerStyle> training_styles() noexcept { return kTrainingStyles; }
const WorkerStyle& held_out_style() noexcept { return kHeldOutStyle; }
const WorkerStyle* find_style(std::string_view name) noexcept {
  for (const WorkerStyle& s : kTrainingStyles)
    if (s.name == name) return &s;
  return name == kHeldOutStyle.name ? &kHeldOutStyle : nullptr;
}

std::uint64_t worker_seed(std::uint64_t base, std::uint64_t purpose, std::size_t operation, std::size_t index) noexcept {
  // splitmix64 over the fields in turn: nearby inputs give unrelated seeds.
  auto mix = [](std::uint64_t z) {
    z += 0x9e3779b97f4a7c15ULL;
    z = (z ^ (z >> 30)) * 0xbf58476d1ce4e5b9ULL;
    z = (z ^ (z >> 27)) * 0x94d049bb133111ebULL;
    return z ^ (z >> 31);
  };
  std::uint64_t h = mix(base);
  h = mix(h ^ purpose);
  h = mix(h ^ static_cast<std::uint64_t>(operation));
  return mix(h ^ static_cast<std::uint64_t>(index));
}

struct WorkerSimulator::Impl {
  Impl(const OperationsConfig& c, const nav::OccupancyMap& m)
      : config(c),
        map(&m),
        static_layer(m),
        inflation_config{kInflationRadiusM, kCostScaling, kBodyClearanceM},
        inflation(inflation_config) {}

  OperationsConfig config;
  const nav::OccupancyMap* map;
  nav::StaticLayer static_layer;
  nav::InflationLayerConfig inflation_config;
  nav::InflationLayer inflation;
  nav::LayeredCostmap costmap;
  std::pmr::monotonic_buffer_resource arena;
  nav::GlobalPlanner planner;
  std::vector<nav::GridCell> cells;

  [[nodiscard]] std::uint8_t cost(Point2D p) const noexcept {
    int c = 0, r = 0;
    const nav::Costmap2D& grid = costmap.costmap();
    if (!grid.world_to_cell(p.x_m, p.y_m, c, r)) return nav::kLethalCost;
    return grid.at(c, r);
  }
  [[nodiscard]] std::uint8_t threshold(double clearance_m) const noexcept {
    return nav::InflationLayer::cost_at(clearance_m, inflation_config);
  }
  // The highest cost on the segment, sampled at half cells.
  [[nodiscard]] std::uint8_t segment_cost(Point2D a, Point2D b) const noexcept {
    const double step = 0.5 * costmap.costmap().resolution_m();
    const double len = norm(b - a);
    const int n = std::max(1, static_cast<int>(std::ceil(len / step)));
    std::uint8_t worst = 0;
    for (int i = 0; i <= n; ++i) worst = std::max(worst, cost(a + (static_cast<double>(i) / n) * (b - a)));
    return worst;
  }
  [[nodiscard]] bool clear(Point2D a, Point2D b) const noexcept { return segment_cost(a, b) < kBlocked; }
  // Whether a beam from a reaches b without passing an occupied map cell.
  [[nodiscard]] bool line_of_sight(Point2D a, Point2D b) const noexcept {
    const double step = 0.5 * map->resolution_m();
    const double len = norm(b - a);
    const int n = static_cast<int>(len / step);
    for (int i = 1; i < n; ++i) {
      const Point2D p = a + (i * step / len) * (b - a);
      int c = 0, r = 0;
      if (!map->world_to_cell(p.x_m, p.y_m, c, r)) return false;
      if (map->at(c, r) >= kLaserBlocking) return false;
    }
    return true;
  }

  Result<std::vector<Point2D>> route(Point2D from, Point2D to, double clearance_m);
  void shape_leg(std::vector<Point2D>& v, const WorkerStyle& style, double turn_radius_m, std::mt19937_64& rng) const;

  // The walk's parts (walk() puts them together).
  std::vector<Point2D> station_spots(const Operation& op, const WorkerStyle& style, std::mt19937_64& rng) const;
  void stand_steps(Track& track, Point2D spot, long steps, const WorkerStyle& style, std::mt19937_64& rng) const;
  void stand(Track& track, Point2D spot, double seconds, const WorkerStyle& style, std::mt19937_64& rng) const {
    stand_steps(track, spot, std::lround(seconds / kStepS), style, rng);
  }
  void walk_leg(Track& track, const std::vector<Point2D>& dense, const Worker& worker, const WorkerStyle& style,
                double& walked_s, std::mt19937_64& rng) const;
  Result<Track> body_track(const std::vector<Point2D>& spots, const Worker& worker, const WorkerStyle& style,
                           const Observer& observer, std::mt19937_64& rng);
  Follower follower(const Track& track, const Observer& observer, std::mt19937_64& rng) const;
  std::optional<Point2D> beam_hit(Point2D robot, Point2D body, double beam_offset, const Observer& observer,
                                  std::mt19937_64& rng) const;
  WorkerWalk observe(Track& track, const Operation& op, const std::vector<Point2D>& spots, const WorkerStyle& style,
                     const Observer& observer, std::mt19937_64& rng) const;
};

Result<std::vector<Point2D>> WorkerSimulator::Impl::route(Point2D from, Point2D to, double clearance_m) {
  const nav::PlanResult r = planner.plan_world(costmap.costmap(), from, to, {}, cells);
  if (!r.ok())
    return Error::format(Errc::invalid_argument, "no route from (%.2f, %.2f) to (%.2f, %.2f): %s", from.x_m, from.y_m,
                         to.x_m, to.y_m, nav::to_string(r.status));
  std::vector<Point2D> pts(r.cells);
  for (std::size_t i = 0; i < r.cells; ++i) costmap.costmap().cell_to_world(cells[i].col, cells[i].row, pts[i].x_m, pts[i].y_m);
  pts.front() = from;
  pts.back() = to;
  // Straighten: from each kept point, the farthest point in sight, where "in sight" asks for
  // the preferred clearance only where the A* path itself had it (narrow aisles allow less).
  // Never into the inscribed band, whatever the clearance asked for.
  const auto wanted = std::min<std::uint8_t>(threshold(clearance_m), kBlocked - 1);
  std::vector<Point2D> out{pts.front()};
  std::size_t i = 0;
  while (i + 1 < pts.size()) {
    std::size_t best = i + 1;
    std::uint8_t path_worst = std::max(cost(pts[i]), cost(pts[i + 1]));
    for (std::size_t j = i + 2; j < pts.size(); ++j) {
      path_worst = std::max(path_worst, cost(pts[j]));
      const std::uint8_t allowed = std::max(wanted, path_worst);
      if (segment_cost(pts[i], pts[j]) > allowed) break;
      best = j;
    }
    out.push_back(pts[best]);
    i = best;
  }
  return out;
}

void WorkerSimulator::Impl::shape_leg(std::vector<Point2D>& v, const WorkerStyle& style, double turn_radius_m,
                                      std::mt19937_64& rng) const {
  // Wide turns: each corner pushed outward, more for sharper turns.
  if (style.wide_turn_m > 0) {
    for (std::size_t i = 1; i + 1 < v.size(); ++i) {
      const Point2D a = unit(v[i] - v[i - 1]), b = unit(v[i + 1] - v[i]);
      const double half_turn = 0.5 * std::acos(std::clamp(dot(a, b), -1.0, 1.0));
      double push = style.wide_turn_m * uniform(rng, 0.6, 1.0) * std::sin(half_turn);
      const Point2D out = unit(a - b);
      for (int attempt = 0; attempt < 3 && push > 0.02; ++attempt, push *= 0.5) {
        const Point2D moved = v[i] + push * out;
        if (clear(v[i - 1], moved) && clear(moved, v[i + 1])) {
          v[i] = moved;
          break;
        }
      }
    }
  }
  // A detour: off the longest straight stretch and back.
  if (style.detour_probability > 0 && uniform(rng) < style.detour_probability && v.size() >= 2) {
    std::size_t longest = 0;
    for (std::size_t i = 1; i < v.size(); ++i)
      if (norm(v[i] - v[i - 1]) > norm(v[longest + 1] - v[longest])) longest = i - 1;
    const Point2D a = v[longest], b = v[longest + 1];
    const double len = norm(b - a);
    const double size = style.detour_m * uniform(rng, 0.6, 1.0);
    const double side = uniform(rng) < 0.5 ? -1.0 : 1.0;
    if (len >= kDetourLegM) {
      const Point2D d = unit(b - a);
      const double at = uniform(rng, 0.35, 0.65) * len;
      const Point2D leave = a + (at - kDetourHalfM) * d, rejoin = a + (at + kDetourHalfM) * d;
      for (const double s : {side, -side}) {
        const Point2D off = a + at * d + (s * size) * msg::perpendicular(d);
        if (clear(leave, off) && clear(off, rejoin)) {
          v.insert(v.begin() + static_cast<std::ptrdiff_t>(longest) + 1, {leave, off, rejoin});
          break;
        }
      }
    }
  }
  // Rounded corners: a quadratic Bezier across each corner, shrunk until it is clear.
  if (turn_radius_m > 0 && v.size() > 2) {
    std::vector<Point2D> rounded{v.front()};
    for (std::size_t i = 1; i + 1 < v.size(); ++i) {
      const Point2D in = v[i] - v[i - 1], out = v[i + 1] - v[i];
      double d = std::min({turn_radius_m, 0.45 * norm(in), 0.45 * norm(out)});
      bool done = false;
      for (int attempt = 0; attempt < 3 && d > 0.02 && !done; ++attempt, d *= 0.5) {
        const Point2D p = v[i] - d * unit(in), q = v[i] + d * unit(out);
        constexpr int kSamples = 6;
        std::vector<Point2D> curve;
        bool ok = clear(rounded.back(), p);
        for (int k = 0; k <= kSamples && ok; ++k) {
          const double t = static_cast<double>(k) / kSamples;
          const Point2D c = ((1 - t) * (1 - t)) * p + (2 * (1 - t) * t) * v[i] + (t * t) * q;
          ok = clear(curve.empty() ? p : curve.back(), c);
          curve.push_back(c);
        }
        if (ok) {
          rounded.insert(rounded.end(), curve.begin(), curve.end());
          done = true;
        }
      }
      if (!done) rounded.push_back(v[i]);
    }
    rounded.push_back(v.back());
    v = std::move(rounded);
  }
}

WorkerSimulator::WorkerSimulator(std::unique_ptr<Impl> impl) noexcept : impl_(std::move(impl)) {}
WorkerSimulator::~WorkerSimulator() = default;

Result<std::unique_ptr<WorkerSimulator>> WorkerSimulator::create(const OperationsConfig& config,
                                                                 const nav::OccupancyMap& map) {
  auto impl = std::make_unique<Impl>(config, map);
  Status s = impl->costmap.add_layer(impl->static_layer);
  if (s) s = impl->costmap.add_layer(impl->inflation);
  if (s) s = impl->costmap.init_over_map(map, impl->arena);
  if (!s) return s.error();
  impl->costmap.update({});
  nav::GlobalPlannerConfig planner;
  planner.max_cells = impl->costmap.costmap().size();
  planner.cost_weight = kPersonCostWeight;
  if (Status p = impl->planner.init(planner, impl->arena); !p) return p.error();
  impl->cells.resize(impl->costmap.costmap().size());
  for (const Workstation& w : config.stations)
    if (impl->cost(w.position) >= kBlocked)
      return Error::format(Errc::config, "%s: station '%s' at (%.2f, %.2f) is within %.2f m of an obstacle",
                           config.source.c_str(), w.name.c_str(), w.position.x_m, w.position.y_m, kBodyClearanceM);
  return std::unique_ptr<WorkerSimulator>(new WorkerSimulator(std::move(impl)));
}

const OperationsConfig& WorkerSimulator::config() const noexcept { return impl_->config; }
const nav::OccupancyMap& WorkerSimulator::map() const noexcept { return *impl_->map; }
bool WorkerSimulator::standable(Point2D p) const noexcept { return impl_->cost(p) < kBlocked; }

Result<std::vector<Point2D>> WorkerSimulator::route(Point2D from, Point2D to, double clearance_m) {
  return impl_->route(from, to, clearance_m);
}

Result<std::vector<Point2D>> WorkerSimulator::reference_route(std::size_t operation, double spacing_m) {
  if (operation >= impl_->config.operations.size() || !(spacing_m > 0))
    return Error(Errc::invalid_argument, "reference_route: no such operation");
  const Operation& op = impl_->config.operations[operation];
  std::vector<Point2D> whole;
  for (std::size_t k = 1; k < op.stations.size(); ++k) {
    Result<std::vector<Point2D>> leg = impl_->route(impl_->config.stations[op.stations[k - 1]].position,
                                                    impl_->config.stations[op.stations[k]].position, kRobotClearanceM);
    if (!leg) return leg.error();
    whole.insert(whole.end(), leg->begin() + (whole.empty() ? 0 : 1), leg->end());
  }
  return resample(whole, spacing_m);
}

// Where they stand at each station: within approach_m of its point, where a body fits.
std::vector<Point2D> WorkerSimulator::Impl::station_spots(const Operation& op, const WorkerStyle& style,
                                                          std::mt19937_64& rng) const {
  std::vector<Point2D> spots;
  for (const std::size_t s : op.stations) {
    const Point2D centre = config.stations[s].position;
    Point2D spot = centre;
    for (int attempt = 0; attempt < 8; ++attempt) {
      const double r = style.approach_m * std::sqrt(uniform(rng));
      const double a = uniform(rng, 0.0, 2.0 * std::numbers::pi);
      const Point2D c = centre + Point2D{r * std::cos(a), r * std::sin(a)};
      if (cost(c) < kBlocked) {
        spot = c;
        break;
      }
    }
    spots.push_back(spot);
  }
  return spots;
}

// Standing at a spot: the shift drifts at random and back towards the spot.
void WorkerSimulator::Impl::stand_steps(Track& track, Point2D spot, long steps, const WorkerStyle& style,
                                        std::mt19937_64& rng) const {
  const double keep = 1.0 - kStepS / kShiftTauS;
  const double kick = style.dwell_shift_m * std::sqrt(2.0 * kStepS / kShiftTauS);
  for (long i = 0; i < steps; ++i) {
    const Point2D next = keep * track.shift + Point2D{kick * normal(rng), kick * normal(rng)};
    if (cost(spot + next) < kBlocked) track.shift = next;
    track.points.push_back(spot + track.shift);
  }
}

// Along a leg's dense route: speeding up from the stand and slowing down to the next, swaying,
// the stand's shift fading out, and maybe a pause on the way.
void WorkerSimulator::Impl::walk_leg(Track& track, const std::vector<Point2D>& dense, const Worker& worker,
                                     const WorkerStyle& style, double& walked_s, std::mt19937_64& rng) const {
  const double length = polyline_length(dense);
  const double leg_speed = worker.speed * (1.0 + 0.5 * style.speed_spread * uniform(rng, -1.0, 1.0));
  const bool pause = style.pause_probability > 0 && uniform(rng) < style.pause_probability;
  const double pause_at = uniform(rng, 0.3, 0.7) * length;
  const double pause_s = pause ? uniform(rng, 0.5, std::max(0.5, style.pause_max_s)) : 0.0;
  bool paused = false;
  const Point2D left_shift = track.shift;
  double s = 0, t_leg = 0;
  while (s < length) {
    const double ramp = std::clamp(std::min(s, length - s) / kRampM, kRampFloor, 1.0);
    s = std::min(length, s + leg_speed * ramp * kStepS);
    t_leg += kStepS;
    walked_s += kStepS;
    const std::size_t at = std::min(dense.size() - 2, static_cast<std::size_t>(s / kDenseStepM));
    const double f = std::clamp(s / kDenseStepM - static_cast<double>(at), 0.0, 1.0);
    const Point2D on_route = dense[at] + f * (dense[at + 1] - dense[at]);
    const Point2D lateral = msg::perpendicular(unit(dense[at + 1] - dense[at]));
    const double swing = worker.sway * ramp * std::sin(2.0 * std::numbers::pi * worker.sway_hz * walked_s + worker.sway_phase);
    Point2D body = on_route + swing * lateral;
    if (cost(body) >= kBlocked) body = on_route;
    const double fade = std::exp(-t_leg / kStartBlendS);
    if (cost(body + fade * left_shift) < kBlocked) body = body + fade * left_shift;
    track.points.push_back(body);
    if (pause && !paused && s >= pause_at) {
      paused = true;
      track.shift = {0, 0};
      stand(track, body, pause_s, style, rng);
    }
  }
}

// Pass 1: the body's track. The recording starts when the worker engages the robot at the
// first station (shows it their tag): a few seconds there, then the walk. Later stations get
// the style's dwell.
Result<Track> WorkerSimulator::Impl::body_track(const std::vector<Point2D>& spots, const Worker& worker,
                                                const WorkerStyle& style, const Observer& observer, std::mt19937_64& rng) {
  Track track;
  double walked_s = 0;  // walking time so far: the sway's clock
  const double engage_s = uniform(rng, kEngageMinS, kEngageMaxS);
  stand(track, spots.front(), observer.records_first_task ? dwell_s(style, rng) : engage_s, style, rng);
  for (std::size_t k = 1; k < spots.size(); ++k) {
    Result<std::vector<Point2D>> leg = route(spots[k - 1], spots[k], worker.clearance);
    if (!leg) return leg.error();
    shape_leg(*leg, style, worker.turn_radius, rng);
    const std::vector<Point2D> dense = resample(*leg, kDenseStepM);
    if (dense.size() < 2) continue;  // two stations at one spot: nothing to walk
    walk_leg(track, dense, worker, style, walked_s, rng);
    track.shift = {0, 0};
    stand(track, spots[k], dwell_s(style, rng), style, rng);
  }
  return track;
}

// The robot where it starts: at the observer's position, or following, its distance from the
// worker's start in the first clear direction from a random one.
Follower WorkerSimulator::Impl::follower(const Track& track, const Observer& observer, std::mt19937_64& rng) const {
  Follower f{observer.position, {}, 0};
  if (observer.mode != ObserverMode::following || track.points.empty()) return f;
  const Point2D start = track.points.front();
  const double a0 = uniform(rng, 0.0, 2.0 * std::numbers::pi);
  f.robot = start + Point2D{observer.follow_distance_m, 0.0};
  for (int k = 0; k < 16; ++k) {
    const double a = a0 + k * (2.0 * std::numbers::pi / 16);
    const Point2D c = start + observer.follow_distance_m * Point2D{std::cos(a), std::sin(a)};
    if (clear(start, c)) {
      f.robot = c;
      break;
    }
  }
  f.trail.push_back(start);
  return f;
}

// The beam nearest the body's bearing, its first crossing of the body's circle: where the
// laser sees the body, if it does.
std::optional<Point2D> WorkerSimulator::Impl::beam_hit(Point2D robot, Point2D body, double beam_offset,
                                                       const Observer& observer, std::mt19937_64& rng) const {
  const Point2D to_body = body - robot;
  const double distance = norm(to_body);
  if (distance <= observer.body_radius_m + 0.05) return std::nullopt;  // too close to be a clean return
  const double bearing = std::atan2(to_body.y_m, to_body.x_m);
  const double beam = beam_offset + std::round((bearing - beam_offset) / observer.beam_step_rad) * observer.beam_step_rad;
  const Point2D dir{std::cos(beam), std::sin(beam)};
  const double along = dot(to_body, dir);
  const double off2 = distance * distance - along * along;
  const double r2 = observer.body_radius_m * observer.body_radius_m;
  if (off2 >= r2 || along <= 0) return std::nullopt;  // the beam misses the body
  double range = along - std::sqrt(r2 - off2) + observer.range_noise_m * normal(rng);
  if (observer.range_step_m > 0) range = std::round(range / observer.range_step_m) * observer.range_step_m;
  if (range <= 0 || range > observer.max_range_m) return std::nullopt;
  const Point2D hit = robot + range * dir;
  if (!line_of_sight(robot, hit)) return std::nullopt;
  return hit;
}

// Pass 2: the robot and its scans. A following robot that fell behind a fast worker keeps
// recording until it has them in sight at the last station: the operation ends when they
// finish there, not before the robot could see it. The worker keeps working meanwhile.
WorkerWalk WorkerSimulator::Impl::observe(Track& track, const Operation& op, const std::vector<Point2D>& spots,
                                          const WorkerStyle& style, const Observer& observer, std::mt19937_64& rng) const {
  WorkerWalk out;
  const auto steps_per_scan = std::max<long>(1, std::lround(1.0 / (observer.scan_hz * kStepS)));
  const long scan_phase = static_cast<long>(uniform(rng) * static_cast<double>(steps_per_scan));
  const double beam_offset = uniform(rng, 0.0, observer.beam_step_rad);
  double spacing = observer.min_step_m;
  Follower f = follower(track, observer, rng);
  std::size_t next_visit = 0;
  long settled = 0;
  double extended_s = 0;
  for (std::size_t i = 0;; ++i) {
    if (i == track.points.size()) {
      if (observer.mode != ObserverMode::following || track.points.empty()) break;
      const bool caught_up = norm(track.points.back() - f.robot) <= observer.follow_distance_m + kCaughtUpSlackM &&
                             line_of_sight(f.robot, track.points.back());
      if ((caught_up && ++settled > kSettleScans) || extended_s >= kMaxExtensionS) break;
      stand_steps(track, spots.back(), steps_per_scan, style, rng);
      extended_s += static_cast<double>(steps_per_scan) * kStepS;
    }
    const Point2D body = track.points[i];
    if (observer.mode == ObserverMode::following) f.step(body, observer);
    if ((static_cast<long>(i) + scan_phase) % steps_per_scan != 0) continue;
    out.body.push_back(body);
    out.robot.push_back(f.robot);
    if (next_visit < op.stations.size()) {
      const Workstation& st = config.stations[op.stations[next_visit]];
      if (norm(body - st.position) <= st.radius_m) {
        out.arrivals.push_back(out.body.size() - 1);
        ++next_visit;
      }
    }
    if (const std::optional<Point2D> hit = beam_hit(f.robot, body, beam_offset, observer, rng)) record_point(out, *hit, spacing);
  }
  out.duration_s = static_cast<double>(track.points.size()) * kStepS;
  return out;
}

Result<WorkerWalk> WorkerSimulator::walk(std::size_t operation, const WorkerStyle& style, const Observer& observer,
                                         std::uint64_t seed) {
  Impl& w = *impl_;
  if (operation >= w.config.operations.size()) return Error(Errc::invalid_argument, "walk: no such operation");
  if (!(observer.scan_hz > 0) || !(style.speed_m_s > 0))
    return Error(Errc::invalid_argument, "walk: the scan rate and the walking speed must be positive");
  const Operation& op = w.config.operations[operation];
  std::mt19937_64 rng(seed);
  // This worker, drawn from the style, and where they stand at each station.
  const Worker worker = draw_worker(style, rng);
  const std::vector<Point2D> spots = w.station_spots(op, style, rng);
  Result<Track> track = w.body_track(spots, worker, style, observer, rng);
  if (!track) return track.error();
  return w.observe(*track, op, spots, style, observer, rng);
}

Result<std::vector<LabelledPath>> generate_paths(WorkerSimulator& workers, const DatasetSpec& spec) {
  if (spec.styles.empty()) return Error(Errc::invalid_argument, "generate_paths: no styles");
  std::vector<LabelledPath> paths;
  const std::size_t operations = workers.config().operations.size();
  paths.reserve(operations * spec.per_operation);
  for (std::size_t o = 0; o < operations; ++o) {
    for (std::size_t i = 0; i < spec.per_operation; ++i) {
      const std::uint64_t seed = worker_seed(spec.seed, spec.purpose, o, i);
      std::mt19937_64 rng(seed ^ 0x6f62736572766572ULL);  // the observer's own draws
      Observer observer;
      observer.follow_distance_m = uniform(rng, spec.follow_min_m, spec.follow_max_m);
      observer.range_noise_m = uniform(rng, spec.noise_min_m, spec.noise_max_m);
      observer.records_first_task = spec.records_first_task;
      Result<WorkerWalk> walk = workers.walk(o, spec.styles[i % spec.styles.size()], observer, seed);
      if (!walk) return walk.error();
      if (walk->points() == 0) continue;  // never seen: nothing the robot could classify
      paths.push_back({o, std::move(walk->xy)});
    }
  }
  return paths;
}

}  // namespace sen3bot::cobot
