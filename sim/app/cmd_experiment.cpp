// `sen3bot-sim experiment dol`: the thesis' moving-obstacle experiment (docs/navigation.md,
// "The moving-obstacle arena"). N runs per variant, each a whole firmware in lockstep from
// config/dol_arena.yaml with its own seed's layout of boxes; the runs go to worker processes
// (fork), each sending a fixed-size result per mission through a pipe. The table counts smooth
// navigations, wait recoveries and collisions as the thesis does.
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <climits>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "cli_util.hpp"
#include "config.hpp"
#include "experiment.hpp"
#include "firmware.hpp"
#include "simulated_mission.hpp"
#include "mission_pool.hpp"
#include "report_figure.hpp"
#include "sen3bot/json/json.hpp"
#include "sen3bot/msg/point_math.hpp"
#include "sen3bot/nav_figure/case_figure.hpp"
#include "sen3bot/sim/sim_board.hpp"
#include "sen3bot/sim/sim_config.hpp"
#include "sim_commands.hpp"

namespace sen3bot::sim {

using firmware::Firmware;
using firmware::FirmwareConfig;
using firmware::MissionState;
using firmware::MissionTask;
using namespace experiment;

namespace {

constexpr const char* kName = "sen3bot-sim experiment";
constexpr double kMaxSpeedM_s = 5.0;
// A worker that aborts on purpose when it reaches this seed: how the tests see a crashed worker.
constexpr const char* kCrashSeedVariable = "SEN3BOT_EXPERIMENT_CRASH_SEED";

enum class Variant : std::uint8_t { dol, no_dol };
const char* key(Variant v) { return v == Variant::dol ? "dol" : "no_dol"; }
const char* label(Variant v, bool prediction = true) {
  return v == Variant::no_dol ? "no DOL" : prediction ? "DOL" : "DOL, no pred.";
}

enum class Outcome : std::uint8_t { smooth, wait_recovery, collision, timeout };
const char* to_string(Outcome o) {
  switch (o) {
    case Outcome::smooth: return "smooth";
    case Outcome::wait_recovery: return "wait_recovery";
    case Outcome::collision: return "collision";
    case Outcome::timeout: return "timeout";
  }
  return "?";
}

// One mission as a worker reports it: fixed size, no pointers, written whole to a pipe.
struct MissionResult {
  std::uint64_t seed = 0;
  std::uint32_t job = 0;
  Variant variant = Variant::dol;
  bool ran = false;  // false: the mission could not run; `error` says why
  bool reached = false;
  MissionState state = MissionState::waiting;
  std::uint64_t contacts = 0;
  std::uint64_t moving_contacts = 0;
  std::uint32_t recoveries = 0;
  std::uint32_t waits = 0;
  std::uint32_t plans = 0;
  double time_s = 0;  // the goal's time (from the mission's start of the goal)
  double min_clearance_m = 0;
  double path_length_m = 0;
  double sim_s = 0;
  double wall_s = 0;
  char error[256] = {};
};
static_assert(std::is_trivially_copyable_v<MissionResult>);
static_assert(sizeof(MissionResult) <= PIPE_BUF, "one write, never interleaved");

Outcome classify(const MissionResult& r) {
  if (r.contacts > 0) return Outcome::collision;  // any overlap, a box into a standing robot too
  if (!r.reached) return Outcome::timeout;
  return r.recoveries == 0 ? Outcome::smooth : Outcome::wait_recovery;
}

struct Options {
  double speed_m_s = -1;
  std::uint64_t runs = 0;
  int boxes = 3;
  bool dol = true;
  bool prediction = true;
  bool baseline = true;
  std::uint64_t seed = 1;
  long jobs = 0;  // 0: the online CPUs
  std::string report_dir;
  std::string config_path = "config/dol_arena.yaml";
};

struct Job {
  std::uint64_t seed = 0;
  Variant variant = Variant::dol;
};

struct Plan {
  Options options;
  FirmwareConfig base;
  SimulationConfig base_world;
  std::vector<Job> jobs;  // per run, each variant in order
};

FirmwareConfig variant_config(const Plan& plan, Variant v) {
  FirmwareConfig config = plan.base;
  config.navigation.dynamic_obstacles.enabled = v == Variant::dol;
  config.navigation.dwa.mover_prediction = v == Variant::dol && plan.options.prediction;
  return config;
}

SimulationConfig run_world(const Plan& plan, std::uint64_t seed) {
  SimulationConfig world = plan.base_world;
  world.link = LinkKind::memory;
  world.seed = seed;
  world.base.noise_seed = static_cast<std::uint32_t>(seed);
  world.movers = dol_boxes(dol_layout(seed, plan.options.boxes), plan.options.speed_m_s);
  return world;
}

void set_error(MissionResult& r, std::string_view what) {
  const std::size_t n = std::min(what.size(), sizeof r.error - 1);
  std::memcpy(r.error, what.data(), n);
  r.error[n] = '\0';
}

// --- The closest approach, for the sample figure -------------------------------------------------

// The gap between the robot's footprint at `pose` and a square box (axis-aligned, side size_m)
// centred at c; 0 when they overlap.
double footprint_box_gap(const nav::Footprint& footprint, const nav::Pose2D& pose, nav::Point2D c, double size_m) {
  const double h = size_m / 2;
  if (footprint.vertex_count == 0) {
    const double dx = std::max(std::abs(pose.x_m - c.x_m) - h, 0.0), dy = std::max(std::abs(pose.y_m - c.y_m) - h, 0.0);
    return std::max(0.0, std::hypot(dx, dy) - footprint.circle_radius_m);
  }
  std::vector<nav::Point2D> poly;
  const double co = std::cos(pose.theta_rad), si = std::sin(pose.theta_rad);
  for (std::size_t i = 0; i < footprint.vertex_count; ++i) {
    const nav::Point2D v = footprint.vertices[i];
    poly.push_back({pose.x_m + co * v.x_m - si * v.y_m, pose.y_m + si * v.x_m + co * v.y_m});
  }
  const nav::Point2D corners[4] = {{c.x_m - h, c.y_m - h}, {c.x_m + h, c.y_m - h}, {c.x_m + h, c.y_m + h}, {c.x_m - h, c.y_m + h}};
  // Overlap: a box corner inside the footprint, a footprint vertex inside the box, or edges
  // crossing (then one of the two distances below is 0 up to rounding; the caller only needs
  // the minimum, so a crossing shows as a near-zero gap).
  auto inside = [&](nav::Point2D q) { return msg::inside_polygon(poly, q); };
  double gap = std::numeric_limits<double>::infinity();
  for (const nav::Point2D& q : corners) {
    if (inside(q)) return 0;
    for (std::size_t i = 0; i < poly.size(); ++i) gap = std::min(gap, segment_distance(q, poly[i], poly[(i + 1) % poly.size()]));
  }
  for (const nav::Point2D& v : poly) {
    const double dx = std::max(std::abs(v.x_m - c.x_m) - h, 0.0), dy = std::max(std::abs(v.y_m - c.y_m) - h, 0.0);
    gap = std::min(gap, std::hypot(dx, dy));
  }
  return gap;
}

// The dynamic obstacle layer's confirmed tracks, when the controller has one (it comes with the
// layer's implementation; before that the figure shows no tracks).
template <class Controller>
void copy_tracks(const Controller& controller, hal::Nanos now_ns, figure::Moment& moment) {
  if constexpr (requires { controller.dynamic_layer(); }) {
    const auto* layer = controller.dynamic_layer();
    if (layer == nullptr) return;
    msg::MovingObstacles movers;
    layer->movers(now_ns, movers);
    for (std::size_t i = 0; i < movers.count; ++i) {
      const msg::MovingObstacle& m = movers.items[i];
      moment.tracks.push_back({{m.x_m, m.y_m}, m.vx_m_s, m.vy_m_s, m.radius_m});
    }
  }
}

struct Sample {
  std::string png;
  std::string variant;  // its label in the title
  std::string description;
  double best_gap_m = std::numeric_limits<double>::infinity();
  figure::Moment moment;
  nav::Pose2D robot;  // the true pose at the moment
};

void capture(const Firmware& fw, SimBoard& board, hal::Nanos now_ns, double t_s, Sample& sample) {
  world::World& world = board.simulation().world();
  const SimulationConfig& sim = board.simulation().config();
  const nav::Pose2D pose = board.simulation().truth().pose;
  double gap = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < world.mover_count() && i < sim.movers.size(); ++i)
    if (world.mover_visible(i))
      gap = std::min(gap, footprint_box_gap(sim.footprint, pose, world.mover_position(i), sim.movers[i].size_m));
  if (!(gap < sample.best_gap_m)) return;
  sample.best_gap_m = gap;
  figure::Moment& m = sample.moment;
  m = {};
  m.t_s = t_s;
  sample.robot = pose;
  for (std::size_t i = 0; i < world.mover_count(); ++i) m.movers.push_back(world.mover_position(i));
  const nav::ControllerTask* controller = fw.controller();
  if (controller == nullptr) return;
  const nav::Costmap2D& costmap = controller->costmap();
  m.cell_m = costmap.resolution_m();
  m.cell_yaw_rad = costmap.yaw_rad();
  const nav::OccupancyMap& map = fw.map();
  const double x0 = map.origin_x_m(), y0 = map.origin_y_m();
  const double x1 = x0 + map.width() * map.resolution_m(), y1 = y0 + map.height() * map.resolution_m();
  for (int row = 0; row < costmap.height(); ++row)
    for (int col = 0; col < costmap.width(); ++col) {
      const std::uint8_t cost = costmap.at(col, row);
      if (cost == 0 || cost >= nav::kInscribedCost) continue;
      double x = 0, y = 0;
      costmap.cell_to_world(col, row, x, y);
      if (x < x0 || x > x1 || y < y0 || y > y1) continue;  // the rolling window past the map's edge
      m.cells.push_back({{x, y}, cost});
    }
  copy_tracks(*controller, now_ns, m);
}

// --- One mission -----------------------------------------------------------------------------------

// A whole firmware over the simulated arena until the mission ends or the run's limit; quiet.
// With a sample: slices of 100 ms, the closest approach to a box kept, and the figure written.
void run_mission(const FirmwareConfig& config, const SimulationConfig& world, MissionResult& r, Sample* sample) {
  const auto wall_start = std::chrono::steady_clock::now();
  const hal::Nanos slice = sample != nullptr ? hal::millis(100) : hal::millis(500);
  auto on_slice = [&](const Firmware& fw, SimBoard& board, double) {
    if (sample != nullptr)
      capture(fw, board, board.lockstep_clock()->now(), board.simulation().world().time_s(), *sample);
  };
  auto on_end = [&](Firmware& fw, SimBoard& board, double sim_s) {
    const firmware::MissionReport& report = fw.mission()->report();
    const RefereeReport& truth = board.referee().report();
    r.ran = true;
    r.state = report.state;
    r.reached = report.state == MissionState::complete;
    r.contacts = truth.contacts;
    r.moving_contacts = truth.moving_contacts;
    r.recoveries = report.recoveries;
    r.plans = report.plans;
    tasks::Sample<msg::ControllerStatus> status;
    if (fw.controller_status().read(status)) r.waits = status.value.recoveries.waits;
    for (std::size_t g = 0; g < report.goals_reached; ++g) r.time_s += report.goal_time_s[g];
    r.min_clearance_m = truth.min_clearance_m;
    r.path_length_m = truth.true_path_length_m;
    r.sim_s = sim_s;
    r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
    if (sample != nullptr) {
      figure::CaseFigure figure = case_figure("", sample->description, config, fw, board);
      figure.moment = sample->moment;
      // The robot drawn at the moment, in place of the instant nearest to it.
      if (sample->moment.t_s >= 0 && !figure.robot.empty()) {
        auto nearest = std::min_element(figure.robot.begin(), figure.robot.end(), [&](const auto& a, const auto& b) {
          return std::abs(a.t_s - sample->moment.t_s) < std::abs(b.t_s - sample->moment.t_s);
        });
        *nearest = {sample->moment.t_s, sample->robot};
      }
      char title[160];
      std::snprintf(title, sizeof title, "moving-obstacle arena, %s, seed %llu: closest approach at t = %.1f s (gap %.2f m)",
                    sample->variant.c_str(), static_cast<unsigned long long>(r.seed), sample->moment.t_s, sample->best_gap_m);
      figure.title = title;
      figure.passed = classify(r) == Outcome::smooth || classify(r) == Outcome::wait_recovery;
      if (!figure::draw_case_figure(figure).write_png(sample->png)) set_error(r, "cannot write " + sample->png);
    }
  };
  if (const std::string error = run_simulated_mission(config, world, {.slice = slice}, on_slice, on_end); !error.empty())
    set_error(r, error);
}

MissionResult run_job(const Plan& plan, std::size_t index, Sample* sample = nullptr) {
  const Job& job = plan.jobs[index];
  MissionResult r;
  r.seed = job.seed;
  r.job = static_cast<std::uint32_t>(index);
  r.variant = job.variant;
  const FirmwareConfig config = variant_config(plan, job.variant);
  run_mission(config, run_world(plan, job.seed), r, sample);
  return r;
}

// --- The worker processes ----------------------------------------------------------------------------

struct Tally {
  std::size_t runs = 0, smooth = 0, waits = 0, collisions = 0, timeouts = 0;
  void add(Outcome o) {
    ++runs;
    if (o == Outcome::smooth) ++smooth;
    if (o == Outcome::wait_recovery) ++waits;
    if (o == Outcome::collision) ++collisions;
    if (o == Outcome::timeout) ++timeouts;
  }
};

// Runs every job on `workers` processes (mission_pool.hpp); results[j] for job j. False (after
// the message) when a worker died or a mission could not run.
bool run_pool(const Plan& plan, const std::vector<Variant>& variants, std::size_t workers, std::vector<MissionResult>& results,
              std::FILE* out, std::FILE* err) {
  const std::size_t total = plan.jobs.size();
  const std::size_t every = std::max<std::size_t>(1, std::min<std::size_t>(10, total / 20));
  std::size_t done = 0;
  std::vector<Tally> tallies(variants.size());
  auto progress = [&] {
    std::fprintf(out, "dol %.2f m/s: %zu/%zu runs", plan.options.speed_m_s, done, total);
    for (std::size_t v = 0; v < variants.size(); ++v)
      std::fprintf(out, "; %s %zu done, %zu collision%s, %zu wait recover%s, %zu timeout%s so far", label(variants[v]),
                   tallies[v].runs, tallies[v].collisions, tallies[v].collisions == 1 ? "" : "s", tallies[v].waits,
                   tallies[v].waits == 1 ? "y" : "ies", tallies[v].timeouts, tallies[v].timeouts == 1 ? "" : "s");
    std::fprintf(out, "\n");
    std::fflush(out);
  };
  pool::Callbacks<MissionResult> callbacks;
  callbacks.run = [&plan](std::size_t j) {
    // A worker that aborts on purpose at the crash seed: how the tests see a crashed worker.
    const char* crash = std::getenv(kCrashSeedVariable);
    if (crash != nullptr && std::to_string(plan.jobs[j].seed) == crash) std::abort();
    return run_job(plan, j);
  };
  callbacks.accept = [&](std::size_t, const MissionResult& r) -> std::string {
    if (!r.ran) return "seed " + std::to_string(r.seed) + " (" + label(r.variant) + "): the mission could not run: " + r.error;
    ++done;
    for (std::size_t v = 0; v < variants.size(); ++v)
      if (variants[v] == r.variant) tallies[v].add(classify(r));
    if (done % every == 0 || done == total) progress();
    return {};
  };
  callbacks.describe = [&plan](std::size_t j) {
    return "seed " + std::to_string(plan.jobs[j].seed) + " (" + label(plan.jobs[j].variant) + ")";
  };
  return pool::run_pool(kName, total, workers, callbacks, results, out, err);
}

// --- The command line ----------------------------------------------------------------------------------

int bad(std::FILE* err, const std::string& message) {
  std::fprintf(err, "%s: %s\n", kName, message.c_str());
  return 2;
}

int parse_options(int argc, char** argv, Options& o, std::FILE* err) {
  if (argc < 1) return bad(err, "which experiment? (dol, crowd, operations)");
  if (std::string_view(argv[0]) != "dol") return bad(err, "no experiment named '" + std::string(argv[0]) + "' (dol, crowd, operations)");
  bool have_speed = false, have_runs = false;
  for (int i = 1; i < argc; ++i) {
    const std::string_view arg = argv[i];
    const bool has_value = i + 1 < argc;
    auto value_error = [&](const char* expected) {
      return bad(err, std::string(arg) + ": expected " + expected + ", got '" + argv[i + 1] + "'");
    };
    std::uint64_t u = 0;
    if (arg == "--no-dol") {
      o.dol = false;
    } else if (arg == "--no-prediction") {
      o.prediction = false;
    } else if (arg == "--no-baseline") {
      o.baseline = false;
    } else if (arg == "--speed" && has_value) {
      double v = 0;
      if (!firmware::parse_double(argv[i + 1], v) || !std::isfinite(v) || v <= 0 || v > kMaxSpeedM_s)
        return value_error("a speed in m/s above 0 and at most 5");
      o.speed_m_s = v;
      have_speed = true;
      ++i;
    } else if (arg == "--runs" && has_value) {
      if (!firmware::parse_u64(argv[i + 1], u) || u == 0 || u > pool::kMaxRuns) return value_error("a run count from 1 to 100000");
      o.runs = u;
      have_runs = true;
      ++i;
    } else if (arg == "--boxes" && has_value) {
      if (!firmware::parse_u64(argv[i + 1], u) || u == 0 || u > kMaxBoxes) return value_error("a box count from 1 to 8");
      o.boxes = static_cast<int>(u);
      ++i;
    } else if (arg == "--seed" && has_value) {
      if (!firmware::parse_u64(argv[i + 1], u)) return value_error("a non-negative integer");
      o.seed = u;
      ++i;
    } else if (arg == "--jobs" && has_value) {
      if (!firmware::parse_u64(argv[i + 1], u) || u == 0 || u > 1024) return value_error("a worker count from 1 to 1024");
      o.jobs = static_cast<long>(u);
      ++i;
    } else if (arg == "--report" && has_value) {
      o.report_dir = argv[++i];
      if (o.report_dir.empty()) return bad(err, "--report: expected a directory");
    } else if (arg == "--config" && has_value) {
      o.config_path = argv[++i];
    } else {
      return bad(err, "unknown or incomplete option '" + std::string(arg) + "' (sen3bot-sim --help shows the options)");
    }
  }
  if (!have_speed) return bad(err, "--speed M_S is required (the boxes' speed, e.g. 0.6)");
  if (!have_runs) return bad(err, "--runs N is required");
  if (!o.dol && !o.baseline) return bad(err, "--no-dol and --no-baseline leave nothing to run");
  if (o.jobs == 0) o.jobs = std::max(1L, ::sysconf(_SC_NPROCESSORS_ONLN));
  return 0;
}

// --- The results --------------------------------------------------------------------------------------

struct VariantResults {
  Variant variant;
  std::vector<const MissionResult*> missions;
  Tally tally;
  std::vector<double> smooth_times;
};

double percent(std::size_t count, std::size_t runs) { return runs == 0 ? 0.0 : 100.0 * static_cast<double>(count) / static_cast<double>(runs); }

void print_table(std::FILE* out, const Options& o, const std::vector<VariantResults>& variants) {
  char head[96];
  std::snprintf(head, sizeof head, "obstacles at %.2f m/s, N = %llu", o.speed_m_s, static_cast<unsigned long long>(o.runs));
  std::fprintf(out, "\n| %-30s |", head);
  for (const VariantResults& v : variants) std::fprintf(out, " %-14s |", label(v.variant, o.prediction));
  std::fprintf(out, "\n|%s|", std::string(32, '-').c_str());
  for (std::size_t i = 0; i < variants.size(); ++i) std::fprintf(out, "%s|", std::string(16, '-').c_str());
  auto row = [&](const char* name, auto count) {
    std::fprintf(out, "\n| %-30s |", name);
    for (const VariantResults& v : variants) {
      char cell[48];
      const std::size_t n = count(v.tally);
      std::snprintf(cell, sizeof cell, "%zu (%.1f %%)", n, percent(n, v.tally.runs));
      std::fprintf(out, " %-14s |", cell);
    }
  };
  row("smooth navigations", [](const Tally& t) { return t.smooth; });
  row("wait recoveries", [](const Tally& t) { return t.waits; });
  row("collisions", [](const Tally& t) { return t.collisions; });
  row("successful", [](const Tally& t) { return t.smooth + t.waits; });
  row("timeouts (not reached)", [](const Tally& t) { return t.timeouts; });
  std::fprintf(out, "\n\ntravel time of the smooth runs:\n");
  for (const VariantResults& v : variants) {
    const Quartiles q = quartiles(v.smooth_times);
    if (q.n == 0) std::fprintf(out, "  %-7s no smooth run\n", label(v.variant, o.prediction));
    else
      std::fprintf(out, "  %-7s median %.1f s, IQR %.1f s (%.1f to %.1f s), range %.1f to %.1f s, %zu runs\n",
                   label(v.variant, o.prediction), q.median, q.iqr, q.q1, q.q3, q.min, q.max, q.n);
  }
}

bool write_report_json(const std::string& path, const Options& o, const std::vector<VariantResults>& variants) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return false;
  json::FileSink sink(f);
  json::Writer w(sink, json::Style::spaced);
  w.begin_object()
      .line(2).member("experiment", "dol")
      .line(2).key("speed_m_s").fixed_or_null(o.speed_m_s, 3)
      .line(2).member_uint64("runs", o.runs)
      .line(2).member_int64("boxes", o.boxes)
      .line(2).member_uint64("seed", o.seed)
      .line(2).member_bool("mover_prediction", o.prediction)
      .line(2).key("variants").begin_object();
  for (const VariantResults& v : variants) {
    const Tally& t = v.tally;
    auto count = [&](const char* name, std::size_t n) {
      w.line(6).key(name).begin_object().member_uint64("count", n).key("percent").fixed_or_null(percent(n, t.runs), 2).end_object();
    };
    w.line(4).key(key(v.variant)).begin_object().line(6).member_uint64("runs", t.runs);
    count("smooth", t.smooth);
    count("wait_recoveries", t.waits);
    count("collisions", t.collisions);
    count("successful", t.smooth + t.waits);
    count("timeouts", t.timeouts);
    const Quartiles q = quartiles(v.smooth_times);
    w.line(6).key("travel_time_s").begin_object().member_uint64("runs", q.n);
    const std::pair<const char*, double> stats[] = {{"median", q.median}, {"q1", q.q1}, {"q3", q.q3},
                                                    {"iqr", q.iqr},       {"min", q.min}, {"max", q.max}};
    for (const auto& [name, value] : stats) {
      w.key(name);
      if (q.n == 0) w.null();
      else w.fixed_or_null(value, 3);
    }
    w.end_object();
    w.line(6).key("missions").begin_array();
    for (const auto* mission : v.missions) {
      const MissionResult& r = *mission;
      w.line(8).begin_object()
          .member_uint64("seed", r.seed)
          .member_bool("reached", r.reached)
          .member_uint64("contacts", r.contacts)
          .member_uint64("moving_contacts", r.moving_contacts)
          .member_uint32("recoveries", r.recoveries)
          .member_uint32("waits", r.waits)
          .key("time_s").fixed_or_null(r.time_s, 2)
          .key("min_clearance_m").fixed_or_null(r.min_clearance_m, 3)
          .key("path_length_m").fixed_or_null(r.path_length_m, 3)
          .key("sim_s").fixed_or_null(r.sim_s, 1)
          .key("wall_s").fixed_or_null(r.wall_s, 3)
          .member("state", firmware::to_string(r.state))
          .member("class", to_string(classify(r)))
          .end_object();
    }
    w.line(6).end_array().line(4).end_object();
  }
  w.line(2).end_object().line(0).end_object();
  const bool written = static_cast<bool>(w.finish()) && std::fputc('\n', f) != EOF;
  return std::fclose(f) == 0 && written;
}

}  // namespace

int experiment_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
#ifdef SEN3BOT_HAS_RECOGNIZER
  if (argc >= 1 && std::string_view(argv[0]) == "operations") return operations_experiment_command(argc - 1, argv + 1, out, err);
#endif
  if (argc >= 1 && std::string_view(argv[0]) == "crowd") return crowd_experiment_command(argc - 1, argv + 1, out, err);
  Plan plan;
  Options& o = plan.options;
  if (int rc = parse_options(argc, argv, o, err); rc != 0) return rc;

  Result<SimulatedRobot> loaded = load_simulated_robot(o.config_path);
  if (!loaded) return bad(err, loaded.error().c_str());
  plan.base = std::move(loaded->firmware);
  plan.base_world = std::move(loaded->world);
  if (!plan.base.navigation.enabled || plan.base.navigation.mission.goal_count == 0 || plan.base.has_fleet)
    return bad(err, o.config_path + ": needs a navigation section with a goal (and no fleet section)");
  if (!o.report_dir.empty()) {
    if (::mkdir(o.report_dir.c_str(), 0755) != 0 && errno != EEXIST)
      return bad(err, "--report: cannot create " + o.report_dir + ": " + std::strerror(errno));
    struct stat st {};
    if (::stat(o.report_dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode) || ::access(o.report_dir.c_str(), W_OK | X_OK) != 0)
      return bad(err, "--report: " + o.report_dir + " is not a writable directory");
  }

  std::vector<Variant> variants;
  if (o.dol) variants.push_back(Variant::dol);
  if (o.baseline) variants.push_back(Variant::no_dol);
  for (std::uint64_t i = 0; i < o.runs; ++i)
    for (const Variant v : variants) plan.jobs.push_back({o.seed + i, v});

  std::fprintf(out,
               "experiment dol: %d box%s of %.1f m at %.2f m/s, %llu run%s per variant (seeds %llu..%llu), variants %s%s%s, "
               "%ld worker%s\n",
               o.boxes, o.boxes == 1 ? "" : "es", kBoxSizeM, o.speed_m_s, static_cast<unsigned long long>(o.runs),
               o.runs == 1 ? "" : "s", static_cast<unsigned long long>(o.seed),
               static_cast<unsigned long long>(o.seed + o.runs - 1), o.dol ? (o.prediction ? "DOL" : "DOL (no mover prediction)") : "",
               o.dol && o.baseline ? " and " : "", o.baseline ? "no DOL" : "", o.jobs, o.jobs == 1 ? "" : "s");
  std::fflush(out);
  const auto wall_start = std::chrono::steady_clock::now();
  std::vector<MissionResult> results;
  if (!run_pool(plan, variants, static_cast<std::size_t>(o.jobs), results, out, err)) return 1;
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();

  std::vector<VariantResults> by_variant;
  for (const Variant v : variants) by_variant.push_back({v, {}, {}, {}});
  double mission_wall_s = 0;
  for (const MissionResult& r : results) {
    mission_wall_s += r.wall_s;
    for (VariantResults& v : by_variant)
      if (v.variant == r.variant) {
        v.missions.push_back(&r);
        const Outcome outcome = classify(r);
        v.tally.add(outcome);
        if (outcome == Outcome::smooth) v.smooth_times.push_back(r.time_s);
      }
  }
  print_table(out, o, by_variant);
  std::fprintf(out, "%zu missions in %.1f s wall, %.2f s of one core per mission\n", results.size(), wall_s,
               results.empty() ? 0.0 : mission_wall_s / static_cast<double>(results.size()));

  if (!o.report_dir.empty()) {
    const std::string json = o.report_dir + "/report.json";
    if (!write_report_json(json, o, by_variant)) {
      std::fprintf(err, "%s: cannot write %s\n", kName, json.c_str());
      return 1;
    }
    std::vector<BoxPlotSeries> series;
    for (const VariantResults& v : by_variant) series.push_back({label(v.variant, o.prediction), v.smooth_times});
    char title[128], subtitle[160];
    std::snprintf(title, sizeof title, "travel time of the smooth runs: %d boxes at %.2f m/s, N = %llu", o.boxes, o.speed_m_s,
                  static_cast<unsigned long long>(o.runs));
    std::snprintf(subtitle, sizeof subtitle,
                  "box: quartiles (IQR), bar: median, whiskers: furthest run within 1.5 IQR, rings: outliers; seeds %llu..%llu",
                  static_cast<unsigned long long>(o.seed), static_cast<unsigned long long>(o.seed + o.runs - 1));
    const std::string box_png = o.report_dir + "/travel_times.png";
    if (!draw_travel_time_box_plot(title, subtitle, series).write_png(box_png)) {
      std::fprintf(err, "%s: cannot write %s\n", kName, box_png.c_str());
      return 1;
    }
    // The first seed's run of the first variant again, in 100 ms slices, for its figure.
    Sample sample;
    sample.png = o.report_dir + "/sample_run.png";
    sample.variant = label(plan.jobs[0].variant, o.prediction);
    const std::vector<Lane> lanes = dol_layout(o.seed, o.boxes);
    char head[96];
    std::snprintf(head, sizeof head, "empty 10 x 6 m arena, %d box%s of 0.2 m at %.2f m/s on lanes x =", o.boxes,
                  o.boxes == 1 ? "" : "es", o.speed_m_s);
    sample.description = head;
    for (std::size_t i = 0; i < lanes.size(); ++i) {
      char lane[16];
      std::snprintf(lane, sizeof lane, "%s %.2f", i ? "," : "", lanes[i].x_m);
      sample.description += lane;
    }
    sample.description += " m; shaded: the local costmap at the closest approach";
    const MissionResult again = run_job(plan, 0, &sample);
    if (!again.ran || again.error[0] != '\0') {
      std::fprintf(err, "%s: the sample run (seed %llu): %s\n", kName, static_cast<unsigned long long>(again.seed), again.error);
      return 1;
    }
    const MissionResult& first = results[0];
    if (again.reached != first.reached || again.contacts != first.contacts || again.recoveries != first.recoveries ||
        std::abs(again.time_s - first.time_s) > 1e-9)
      std::fprintf(out, "note: the sample run (100 ms slices) ended unlike its mission: %s in %.2f s vs %s in %.2f s\n",
                   to_string(classify(again)), again.time_s, to_string(classify(first)), first.time_s);
    std::fprintf(out, "report: %s (report.json, travel_times.png, sample_run.png)\n", o.report_dir.c_str());
  }
  std::fflush(out);
  return 0;
}

}  // namespace sen3bot::sim
