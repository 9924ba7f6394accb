// sen3bot-sim formation: the formation examples (docs/formation/examples.md) in lockstep, N
// whole firmwares and the centre's formation service on one in-process broker
// (formation_sim.hpp). Run 0 starts from the example's poses, runs 1.. from seeded
// perturbations of them; every run is judged from the ground truth: the closest two robots
// came, contacts with the walls, targets reached, the formation error and when it settled.
// --report writes formation.json, trajectories.png, distances.png and distances.csv.
#include <sys/stat.h>

#include <algorithm>
#include <cerrno>
#include <charconv>
#include <cmath>
#include <cstring>
#include <random>
#include <string>
#include <vector>

#include "formation_sim.hpp"
#include "sen3bot/figure/canvas.hpp"
#include "sen3bot/json/json.hpp"
#include "sen3bot/nav_figure/case_figure.hpp"
#include "sim_commands.hpp"

namespace sen3bot::sim {

namespace {

namespace colours = figure::colours;
using figure::Canvas;
using figure::Px;
using figure::Rgb;

constexpr Rgb kRobotColours[] = {{214, 39, 40}, {31, 119, 180}, {44, 160, 44}, {148, 103, 189}, {255, 127, 14},
                                 {140, 86, 75}, {227, 119, 194}, {127, 127, 127}, {188, 189, 34}, {23, 190, 207}};
constexpr std::size_t kColourCount = sizeof kRobotColours / sizeof kRobotColours[0];
constexpr Rgb kGrid{225, 225, 225};
constexpr Rgb kBound{200, 0, 0};
constexpr Rgb kSwitch{150, 150, 150};

int fail(std::FILE* err, const std::string& message, int code = 2) {
  std::fprintf(err, "sen3bot-sim formation: %s\n", message.c_str());
  return code;
}

bool write_text(const std::string& path, const std::string& text) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return false;
  const bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  return std::fclose(f) == 0 && ok;
}

std::string fmt(const char* format, double value) {
  char text[64];
  std::snprintf(text, sizeof text, format, value);
  return text;
}

bool parse_number(const std::string& text, double& value) {
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  return ec == std::errc() && ptr == end && std::isfinite(value);
}

bool parse_count(const std::string& text, std::uint64_t& value) {
  const char* end = text.data() + text.size();
  const auto [ptr, ec] = std::from_chars(text.data(), end, value);
  return ec == std::errc() && ptr == end && !text.empty();
}

// Tick spacing giving about `count` ticks over `extent`.
double tick_step(double extent, double count) {
  const double raw = extent / count;
  const double p = std::pow(10.0, std::floor(std::log10(raw)));
  for (double m : {1.0, 2.0, 5.0, 10.0})
    if (m * p >= raw) return m * p;
  return 10 * p;
}

struct RunResult {
  std::vector<formation::Pose> starts;
  FormationMetrics metrics;
};

// Run 0's record, for the figures and the CSV.
struct Record {
  std::vector<FormationSample> samples;
  std::vector<double> switches_s;
  std::vector<formation::Vec2> curve;
  const nav::OccupancyMap* map = nullptr;
};

std::string pair_name(std::size_t i, std::size_t j) { return formation_serial(i) + "-" + formation_serial(j); }

// The run-0 trajectories: the walls, the targets or the curve, each robot's P as a line from
// its start pose to its end pose with its body circle, axes in metres, a legend and a title.
bool draw_trajectories(const std::string& path, const FormationExample& ex, const Record& rec, const FormationMetrics& m,
                       double duration_s) {
  const nav::OccupancyMap& map = *rec.map;
  const double px_per_m = 100;
  const double x0 = map.origin_x_m(), y0 = map.origin_y_m();
  const double width_m = map.width() * map.resolution_m(), height_m = map.height() * map.resolution_m();
  const int left = 70, bottom = 60, top = 86, legend_w = 250;
  const int w = left + static_cast<int>(width_m * px_per_m) + legend_w, h = top + static_cast<int>(height_m * px_per_m) + bottom;
  Canvas canvas(w, h, colours::kPaper);
  const figure::View view{x0, y0, px_per_m, static_cast<double>(left), static_cast<double>(h - bottom)};
  const double cell_px = map.resolution_m() * px_per_m;
  // Grid lines every 0.5 m, under everything.
  for (double x = std::ceil(x0 * 2) / 2; x <= x0 + width_m + 1e-9; x += 0.5)
    canvas.line(view(x, y0), view(x, y0 + height_m), kGrid, 1);
  for (double y = std::ceil(y0 * 2) / 2; y <= y0 + height_m + 1e-9; y += 0.5)
    canvas.line(view(x0, y), view(x0 + width_m, y), kGrid, 1);
  for (int row = 0; row < map.height(); ++row)
    for (int col = 0; col < map.width(); ++col)
      if (map.at(col, row) > 50 || map.at(col, row) < 0) {
        const Px p = view(x0 + col * map.resolution_m(), y0 + (row + 1) * map.resolution_m());
        canvas.fill_rect(static_cast<int>(p.x), static_cast<int>(p.y), static_cast<int>(std::ceil(cell_px)) + 1,
                         static_cast<int>(std::ceil(cell_px)) + 1, map.at(col, row) < 0 ? colours::kUnknown : colours::kWall);
      }
  if (rec.curve.size() > 1) {
    std::vector<Px> curve;
    for (const formation::Vec2& p : rec.curve) curve.push_back(view(p.x_m, p.y_m));
    curve.push_back(curve.front());
    canvas.dashed_polyline(curve, colours::kCurve, 2, 10, 6);
  }
  const std::size_t n = ex.starts.size();
  for (std::size_t i = 0; i < ex.targets.size(); ++i) {
    const Px c = view(ex.targets[i].x_m, ex.targets[i].y_m);
    const Rgb colour = kRobotColours[i % kColourCount];
    canvas.line({c.x - 9, c.y - 9}, {c.x + 9, c.y + 9}, colour, 3);
    canvas.line({c.x - 9, c.y + 9}, {c.x + 9, c.y - 9}, colour, 3);
    canvas.text({c.x + 10, c.y - 10}, "target " + formation_serial(i), colour, 0.42, 1, true);
  }
  for (std::size_t i = 0; i < n; ++i) {
    const Rgb colour = kRobotColours[i % kColourCount];
    std::vector<Px> line;
    for (const FormationSample& s : rec.samples) {
      const nav::Pose2D& a = s.truth[i];
      const formation::Vec2 p = formation::point_p(a, kFormationOffsetM);
      line.push_back(view(p.x_m, p.y_m));
    }
    if (line.size() > 1) canvas.polyline(line, colour, 2);
    if (rec.samples.empty()) continue;
    // Start: a small disc at the axle with its heading; end: the body circle and heading.
    const nav::Pose2D& s = rec.samples.front().truth[i];
    canvas.ring(view(s.x_m, s.y_m), kFormationRadiusM * px_per_m, colour, 1);
    canvas.disc(view(s.x_m, s.y_m), 4, colour);
    canvas.line(view(s.x_m, s.y_m), view(s.x_m + 0.3 * std::cos(s.theta_rad), s.y_m + 0.3 * std::sin(s.theta_rad)), colour, 2);
    canvas.text(view(s.x_m - 0.12, s.y_m - 0.45), formation_serial(i), colour, 0.45, 1, true);
    const nav::Pose2D& e = rec.samples.back().truth[i];
    canvas.ring(view(e.x_m, e.y_m), kFormationRadiusM * px_per_m, colour, 3);
    canvas.disc(view(e.x_m, e.y_m), 5, colour);
    canvas.line(view(e.x_m, e.y_m), view(e.x_m + 0.3 * std::cos(e.theta_rad), e.y_m + 0.3 * std::sin(e.theta_rad)), colour, 3);
  }
  // Axes in metres.
  const Rgb ink = colours::kInk;
  canvas.line(view(x0, y0), view(x0 + width_m, y0), ink, 1);
  canvas.line(view(x0, y0), view(x0, y0 + height_m), ink, 1);
  for (double x = std::ceil(x0); x <= x0 + width_m + 1e-9; x += 1) {
    const Px p = view(x, y0);
    canvas.line(p, {p.x, p.y + 6}, ink, 1);
    const std::string label = fmt("%.0f", x);
    canvas.text({p.x - Canvas::text_width(label, 0.42) / 2.0, p.y + 22}, label, ink, 0.42);
  }
  for (double y = std::ceil(y0); y <= y0 + height_m + 1e-9; y += 1) {
    const Px p = view(x0, y);
    canvas.line(p, {p.x - 6, p.y}, ink, 1);
    const std::string label = fmt("%.0f", y);
    canvas.text({p.x - 10 - Canvas::text_width(label, 0.42), p.y + 5}, label, ink, 0.42);
  }
  canvas.text({view(x0 + width_m / 2, y0).x - 20, static_cast<double>(h - 14)}, "x (m)", ink, 0.5);
  canvas.text({10, static_cast<double>(top) - 8}, "y (m)", ink, 0.5);
  char title[200];
  std::snprintf(title, sizeof title, "Example %d: %s, %zu robots (run 0, %.0f s)", ex.number, ex.name, n, duration_s);
  canvas.text({static_cast<double>(left), 28}, title, ink, 0.62, 1);
  char result[240];
  if (ex.config.task == formation::TaskKind::targets)
    std::snprintf(result, sizeof result, "min distance %.2f m, %llu contacts, %zu/%zu targets, converged %s, error after %.3f m",
                  m.min_robot_distance_m, static_cast<unsigned long long>(m.obstacle_contacts), m.targets_reached, ex.targets.size(),
                  m.converge_s < 0 ? "never" : fmt("at %.1f s", m.converge_s).c_str(), m.formation_error_m);
  else
    std::snprintf(result, sizeof result, "min distance %.2f m, %llu contacts, converged %s, formation error after %.3f m",
                  m.min_robot_distance_m, static_cast<unsigned long long>(m.obstacle_contacts),
                  m.converge_s < 0 ? "never" : fmt("at %.1f s", m.converge_s).c_str(), m.formation_error_m);
  canvas.text({static_cast<double>(left), 56}, result, m.passed ? colours::kPassed : colours::kFailed, 0.5, 1);
  // Legend.
  const double lx = left + width_m * px_per_m + 20;
  double ly = top + 16;
  for (std::size_t i = 0; i < n; ++i) {
    const Rgb colour = kRobotColours[i % kColourCount];
    canvas.line({lx, ly - 4}, {lx + 24, ly - 4}, colour, 2);
    std::string label = formation_serial(i) + ": path of P";
    if (ex.config.task == formation::TaskKind::leader) label += i == 0 ? " (leader)" : " (follower)";
    canvas.text({lx + 32, ly}, label, ink, 0.42);
    ly += 24;
  }
  ly += 6;
  canvas.disc({lx + 12, ly - 4}, 4, ink);
  canvas.line({lx + 12, ly - 4}, {lx + 26, ly - 4}, ink, 2);
  canvas.text({lx + 32, ly}, "start (axle, heading)", ink, 0.42);
  ly += 26;
  canvas.ring({lx + 12, ly - 4}, 10, ink, 3);
  canvas.text({lx + 32, ly}, "end: body circle 0.3 m", ink, 0.42);
  ly += 26;
  if (!ex.targets.empty()) {
    canvas.line({lx + 5, ly - 11}, {lx + 19, ly + 3}, ink, 3);
    canvas.line({lx + 5, ly + 3}, {lx + 19, ly - 11}, ink, 3);
    canvas.text({lx + 32, ly}, "target of P", ink, 0.42);
    ly += 26;
  }
  if (rec.curve.size() > 1) {
    const Px dash[] = {{lx, ly - 4}, {lx + 24, ly - 4}};
    canvas.dashed_polyline(dash, colours::kCurve, 2, 8, 4);
    canvas.text({lx + 32, ly}, ex.config.task == formation::TaskKind::patrol ? "patrolled curve" : "leader's curve", ink, 0.42);
    ly += 26;
  }
  canvas.fill_rect(static_cast<int>(lx), static_cast<int>(ly - 12), 24, 12, colours::kWall);
  canvas.text({lx + 32, ly}, "wall", ink, 0.42);
  ly += 26;
  canvas.fill_rect(static_cast<int>(lx), static_cast<int>(ly - 12), 24, 12, colours::kUnknown);
  canvas.text({lx + 32, ly}, "outside (unknown)", ink, 0.42);
  return canvas.write_png(path);
}

// Inter-robot axle distances over time, the 2 x radius line and the switching instants.
bool draw_distances(const std::string& path, const FormationExample& ex, const Record& rec, double duration_s) {
  const std::size_t n = ex.starts.size();
  const int left = 70, right = 230, top = 60, bottom = 60, plot_w = 900, plot_h = 420;
  const int w = left + plot_w + right, h = top + plot_h + bottom;
  Canvas canvas(w, h, colours::kPaper);
  double d_max = 2 * kFormationRadiusM;
  for (const FormationSample& s : rec.samples)
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = 0; j < i; ++j)
        d_max = std::max(d_max, std::hypot(s.truth[i].x_m - s.truth[j].x_m, s.truth[i].y_m - s.truth[j].y_m));
  const double t_step = tick_step(duration_s, 10), d_step = tick_step(d_max, 8);
  const double t_top = std::ceil(duration_s / t_step) * t_step, d_top = std::ceil(d_max * 1.05 / d_step) * d_step;
  auto at = [&](double t, double d) -> Px {
    return {left + t / t_top * plot_w, static_cast<double>(top + plot_h) - d / d_top * plot_h};
  };
  const Rgb ink = colours::kInk;
  for (double t = 0; t <= t_top + 1e-9; t += t_step) {
    canvas.line(at(t, 0), at(t, d_top), kGrid, 1);
    const std::string label = fmt(t_step < 1 ? "%.1f" : "%.0f", t);
    canvas.text({at(t, 0).x - Canvas::text_width(label, 0.42) / 2.0, at(t, 0).y + 22}, label, ink, 0.42);
  }
  for (double d = 0; d <= d_top + 1e-9; d += d_step) {
    canvas.line(at(0, d), at(t_top, d), kGrid, 1);
    const std::string label = fmt(d_step < 1 ? "%.1f" : "%.0f", d);
    canvas.text({at(0, d).x - 10 - Canvas::text_width(label, 0.42), at(0, d).y + 5}, label, ink, 0.42);
  }
  for (double t : rec.switches_s) canvas.line(at(t, 0), at(t, d_top), kSwitch, 1);
  const Px bound[] = {at(0, 2 * kFormationRadiusM), at(t_top, 2 * kFormationRadiusM)};
  canvas.dashed_polyline(bound, kBound, 2, 10, 6);
  std::size_t pair = 0;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j, ++pair) {
      std::vector<Px> line;
      for (const FormationSample& s : rec.samples)
        line.push_back(at(s.t_s, std::hypot(s.truth[i].x_m - s.truth[j].x_m, s.truth[i].y_m - s.truth[j].y_m)));
      if (line.size() > 1) canvas.polyline(line, kRobotColours[pair % kColourCount], 2);
    }
  canvas.line(at(0, 0), at(t_top, 0), ink, 1);
  canvas.line(at(0, 0), at(0, d_top), ink, 1);
  canvas.text({left + plot_w / 2.0 - 20, static_cast<double>(h - 14)}, "t (s)", ink, 0.5);
  canvas.text({10, static_cast<double>(top) - 10}, "distance (m)", ink, 0.5);
  char title[200];
  std::snprintf(title, sizeof title, "Example %d: %s, distance between the robots' axles (run 0)", ex.number, ex.name);
  canvas.text({static_cast<double>(left), 30}, title, ink, 0.62, 1);
  const double lx = left + plot_w + 20;
  double ly = top + 16;
  pair = 0;
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j, ++pair) {
      canvas.line({lx, ly - 4}, {lx + 24, ly - 4}, kRobotColours[pair % kColourCount], 2);
      canvas.text({lx + 32, ly}, pair_name(i, j), ink, 0.42);
      ly += 24;
    }
  ly += 6;
  const Px dash[] = {{lx, ly - 4}, {lx + 24, ly - 4}};
  canvas.dashed_polyline(dash, kBound, 2, 8, 4);
  canvas.text({lx + 32, ly}, "2 x radius (0.6 m)", ink, 0.42);
  ly += 24;
  canvas.line({lx + 12, ly - 14}, {lx + 12, ly + 4}, kSwitch, 1);
  canvas.text({lx + 32, ly}, "gain switch", ink, 0.42);
  return canvas.write_png(path);
}

std::string distances_csv(const FormationExample& ex, const Record& rec) {
  const std::size_t n = ex.starts.size();
  std::string csv = "t_s";
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = i + 1; j < n; ++j) csv += ",d_" + pair_name(i, j) + "_m";
  csv += ",F,switched,formation_error_m,centre_error_m\n";
  char cell[64];
  for (const FormationSample& s : rec.samples) {
    std::snprintf(cell, sizeof cell, "%.2f", s.t_s);
    csv += cell;
    for (std::size_t i = 0; i < n; ++i)
      for (std::size_t j = i + 1; j < n; ++j) {
        std::snprintf(cell, sizeof cell, ",%.4f", std::hypot(s.truth[i].x_m - s.truth[j].x_m, s.truth[i].y_m - s.truth[j].y_m));
        csv += cell;
      }
    std::snprintf(cell, sizeof cell, ",%.4f,%d,%.4f,%.4f\n", s.scale, s.switched ? 1 : 0, s.formation_error_m, s.centre_error_m);
    csv += cell;
  }
  return csv;
}

void write_run(json::Writer& w, std::size_t index, const RunResult& r) {
  const FormationMetrics& m = r.metrics;
  w.begin_object().member_uint64("run", index).member_bool("passed", m.passed).key("starts").begin_array();
  for (const auto& start : r.starts) {
    w.begin_array().fixed_or_null(start.x_m, 4).fixed_or_null(start.y_m, 4).fixed_or_null(start.theta_rad, 4).end_array();
  }
  w.end_array()
      .key("min_robot_distance_m").fixed_or_null(m.min_robot_distance_m, 4)
      .member_uint64("obstacle_contacts", m.obstacle_contacts)
      .member_uint64("targets_reached", m.targets_reached)
      .key("formation_error_m").fixed_or_null(m.formation_error_m, 4)
      .key("final_formation_error_m").fixed_or_null(m.final_formation_error_m, 4)
      .key("converge_s").fixed_or_null(m.converge_s, 1)
      .key("centre_converge_s").fixed_or_null(m.centre_converge_s, 1)
      .key("min_scale").fixed_or_null(m.min_scale, 4)
      .member_uint64("commands_sent", m.commands_sent)
      .member_uint64("stale_steps", m.stale_steps)
      .member_uint64("safety_stops", m.safety_stops)
      .member_uint64("switch_count", m.switches_s.size())
      .key("switches_s").begin_array();
  for (const double t : m.switches_s) w.fixed_or_null(t, 1);
  w.end_array().key("failures").begin_array();
  for (const std::string& f : m.failures) w.string(f);
  w.end_array().end_object();
}

struct FormationOptions {
  int number = 0;
  std::string report_dir;
  std::string config_path;
  std::uint64_t runs = 1;
  std::uint64_t seed = 1;
  double duration_s = -1;
  bool help = false;  // --help: the usage, nothing run
};

// 0, or the exit status of a bad command line (said on err); --help ends the parsing.
int parse_formation(int argc, char** argv, FormationOptions& o, std::FILE* err) {
  for (int i = 0; i < argc; ++i) {
    const std::string arg = argv[i];
    auto value = [&](std::string& v) {
      if (i + 1 >= argc) return false;
      v = argv[++i];
      return true;
    };
    std::string v;
    if (arg == "--help" || arg == "-h") {
      o.help = true;
      return 0;
    } else if (arg == "--example") {
      if (!value(v)) return fail(err, "--example: expected 1, 2 or 3");
      if (v == "1" || v == "2" || v == "3")
        o.number = v[0] - '0';
      else
        return fail(err, "--example: expected 1, 2 or 3, got '" + v + "'");
    } else if (arg == "--report") {
      if (!value(o.report_dir) || o.report_dir.empty()) return fail(err, "--report: expected a folder");
    } else if (arg == "--config") {
      if (!value(o.config_path) || o.config_path.empty()) return fail(err, "--config: expected a file");
    } else if (arg == "--runs") {
      if (!value(v) || !parse_count(v, o.runs) || o.runs < 1 || o.runs > 10000)
        return fail(err, "--runs: expected a whole number from 1 to 10000, got '" + v + "'");
    } else if (arg == "--seed") {
      if (!value(v) || !parse_count(v, o.seed)) return fail(err, "--seed: expected a whole number, got '" + v + "'");
    } else if (arg == "--duration") {
      if (!value(v) || !parse_number(v, o.duration_s) || o.duration_s <= 0 || o.duration_s > 3600)
        return fail(err, "--duration: expected seconds above 0, at most 3600, got '" + v + "'");
    } else {
      return fail(err, "unknown argument '" + arg + "' (try --help)");
    }
  }
  return 0;
}

// One run from `starts` for duration_s, with a progress line every 10 s when `progress`; the
// rig, shut down, with its samples and metrics.
Result<std::unique_ptr<FormationRig>> run_formation(const FormationExample& ex, const std::vector<formation::Pose>& starts,
                                                    const FormationRunOptions& options, double duration_s, bool progress,
                                                    std::FILE* out) {
  auto rig = FormationRig::create(ex, starts, options);
  if (!rig) return rig.error();
  FormationRig& g = **rig;
  double next_progress_s = 10;
  const auto slices = static_cast<std::int64_t>(std::llround(duration_s * 1e9 / static_cast<double>(kFormationSliceNs)));
  for (std::int64_t k = 0; k < slices; ++k) {
    if (Status s = g.advance(); !s) return s.error();
    if (progress && g.t_s() + 1e-9 >= next_progress_s && !g.samples().empty()) {
      next_progress_s += 10;
      std::fprintf(out, "  t=%5.1f s of %.0f s  formation error %.3f m (the centre's estimate %.3f m)  F %.2f  closest %.2f m\n",
                   g.t_s(), duration_s, g.samples().back().formation_error_m, g.service().controller().last().formation_error_m,
                   g.samples().back().scale, g.min_robot_distance_m());
      std::fflush(out);
    }
  }
  g.shutdown();
  return rig;
}

void print_run(std::FILE* out, std::uint64_t run, std::uint64_t runs, const FormationMetrics& m) {
  std::fprintf(out, "run %llu/%llu: %s  min distance %.3f m, %llu contacts, targets %zu, formation error %.3f m, converged %s "
                    "(on the centre's estimates %s), %zu switches, min F %.3f\n",
               static_cast<unsigned long long>(run + 1), static_cast<unsigned long long>(runs), m.passed ? "ok" : "FAILED",
               m.min_robot_distance_m, static_cast<unsigned long long>(m.obstacle_contacts), m.targets_reached, m.formation_error_m,
               m.converge_s < 0 ? "never" : fmt("at %.1f s", m.converge_s).c_str(),
               m.centre_converge_s < 0 ? "never" : fmt("at %.1f s", m.centre_converge_s).c_str(), m.switches_s.size(), m.min_scale);
  for (const std::string& f : m.failures) std::fprintf(out, "  %s\n", f.c_str());
  std::fflush(out);
}

// The runs taken together: the worst of each measure.
struct Summary {
  double worst_distance = 1e9, worst_error = 0, worst_converge = 0, worst_centre_converge = 0, least_scale = 1;
  std::uint64_t contacts = 0;
  std::size_t min_targets = 0, passed = 0;
  bool all_converged = true;
};

Summary summarize(const FormationExample& ex, const std::vector<RunResult>& results) {
  Summary s;
  s.min_targets = ex.targets.size();
  for (const RunResult& r : results) {
    const FormationMetrics& m = r.metrics;
    s.worst_distance = std::min(s.worst_distance, m.min_robot_distance_m);
    s.worst_error = std::max(s.worst_error, m.formation_error_m);
    s.contacts += m.obstacle_contacts;
    s.min_targets = std::min(s.min_targets, m.targets_reached);
    if (m.converge_s < 0) s.all_converged = false;
    s.worst_converge = std::max(s.worst_converge, m.converge_s);
    s.worst_centre_converge = m.centre_converge_s < 0 || s.worst_centre_converge < 0
                                  ? -1.0
                                  : std::max(s.worst_centre_converge, m.centre_converge_s);
    s.least_scale = std::min(s.least_scale, m.min_scale);
    s.passed += m.passed ? 1 : 0;
  }
  return s;
}

void print_summary(std::FILE* out, const FormationExample& ex, std::size_t runs, const Summary& s) {
  std::fprintf(out, "\nexample %d over %zu run%s: %zu passed; worst min distance %.3f m (bound %.2f), %llu contacts, ", ex.number,
               runs, runs == 1 ? "" : "s", s.passed, s.worst_distance, 2 * kFormationRadiusM,
               static_cast<unsigned long long>(s.contacts));
  if (ex.config.task == formation::TaskKind::targets) std::fprintf(out, "fewest targets reached %zu of %zu, ", s.min_targets, ex.targets.size());
  std::fprintf(out, "worst formation error %.3f m, slowest convergence %s\n", s.worst_error,
               s.all_converged ? fmt("%.1f s", s.worst_converge).c_str() : "never (a run did not converge)");
}

Result<std::string> formation_json(const FormationExample& ex, const FormationOptions& o, double duration_s,
                                   const std::vector<RunResult>& results, const Summary& s) {
  std::string json;
  json::StringSink sink(json);
  json::Writer w(sink, json::Style::spaced);
  w.begin_object()
      .line(2).member_int64("example", ex.number)
      .line(2).member("name", ex.name)
      .line(2).member("description", ex.description)
      .line(2).member_uint64("robots", ex.starts.size())
      .line(2).key("robot_radius_m").fixed_or_null(kFormationRadiusM, 2)
      .line(2).key("offset_m").fixed_or_null(kFormationOffsetM, 2)
      .line(2).key("duration_s").fixed_or_null(duration_s, 1)
      .line(2).member_uint64("seed", o.seed)
      .line(2).key("runs").begin_array();
  for (std::size_t i = 0; i < results.size(); ++i) write_run(w.line(4), i, results[i]);
  w.line(2).end_array()
      .line(2).key("summary").begin_object()
      .member_uint64("runs", results.size())
      .member_uint64("runs_passed", s.passed)
      .key("min_robot_distance_m").fixed_or_null(s.worst_distance, 4)
      .member_uint64("obstacle_contacts", s.contacts)
      .member_uint64("targets_reached", ex.config.task == formation::TaskKind::targets ? s.min_targets : std::size_t{0})
      .key("formation_error_m").fixed_or_null(s.worst_error, 4)
      .key("converge_s").fixed_or_null(s.all_converged ? s.worst_converge : -1.0, 1)
      .key("centre_converge_s").fixed_or_null(s.worst_centre_converge, 1)
      .key("min_scale").fixed_or_null(s.least_scale, 4)
      .end_object()
      .line(0)
      .end_object();
  if (auto written = w.finish(); !written) return written.error();
  return json;
}

// formation.json, distances.csv and the two figures; 0, or the exit status of a failure (said
// on err).
int write_report(const FormationExample& ex, const FormationOptions& o, double duration_s, const std::vector<RunResult>& results,
                 const Summary& s, const Record& record, std::FILE* out, std::FILE* err) {
  Result<std::string> json = formation_json(ex, o, duration_s, results, s);
  if (!json) return fail(err, std::string("formation.json: ") + json.error().c_str(), 1);
  *json += '\n';
  const std::string base = o.report_dir + "/";
  if (!write_text(base + "formation.json", *json)) return fail(err, "cannot write " + base + "formation.json", 1);
  if (!write_text(base + "distances.csv", distances_csv(ex, record))) return fail(err, "cannot write " + base + "distances.csv", 1);
  if (!draw_trajectories(base + "trajectories.png", ex, record, results.front().metrics, duration_s))
    return fail(err, "cannot write " + base + "trajectories.png", 1);
  if (!draw_distances(base + "distances.png", ex, record, duration_s))
    return fail(err, "cannot write " + base + "distances.png", 1);
  std::fprintf(out, "report: %sformation.json, trajectories.png, distances.png, distances.csv\n", base.c_str());
  return 0;
}

}  // namespace

int formation_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  FormationOptions o;
  if (int rc = parse_formation(argc, argv, o, err); rc != 0) return rc;
  if (o.help) {
    std::fprintf(out, "usage: sen3bot-sim formation --example 1|2|3 [--report DIR] [--runs N] [--seed S] [--duration S] "
                      "[--config FILE]\n");
    return 0;
  }
  if (o.number == 0) return fail(err, "--example: missing (1 targets, 2 patrol, 3 leader)");
  const FormationExample& ex = *formation_example(o.number);
  const double duration_s = o.duration_s < 0 ? ex.duration_s : o.duration_s;
  if (!o.report_dir.empty() && ::mkdir(o.report_dir.c_str(), 0755) != 0 && errno != EEXIST)
    return fail(err, "--report: cannot create " + o.report_dir + ": " + std::strerror(errno), 1);

  std::fprintf(out, "formation example %d (%s): %s\n", ex.number, ex.name, ex.description);
  std::fflush(out);
  std::mt19937_64 rng(o.seed);
  FormationRunOptions options;
  options.config_path = o.config_path;
  options.seed = o.seed;
  std::vector<RunResult> results;
  Record record;
  std::unique_ptr<FormationRig> first;  // run 0's rig, kept for the figures (its map and curve)
  for (std::uint64_t run = 0; run < o.runs; ++run) {
    RunResult& r = results.emplace_back();
    r.starts = run == 0 ? ex.starts : perturbed_starts(ex, rng);
    auto rig = run_formation(ex, r.starts, options, duration_s, o.runs == 1, out);
    if (!rig) return fail(err, std::string("run ") + std::to_string(run) + ": " + rig.error().c_str(), 1);
    r.metrics = (*rig)->metrics();
    print_run(out, run, o.runs, r.metrics);
    if (run == 0) {
      record.samples = (*rig)->samples();
      record.switches_s = (*rig)->switches_s();
      const auto curve = (*rig)->service().controller().curve_points();
      record.curve.assign(curve.begin(), curve.end());
      first = std::move(rig.value());
      record.map = &first->map();
    }
  }

  const Summary summary = summarize(ex, results);
  print_summary(out, ex, results.size(), summary);
  if (!o.report_dir.empty())
    if (int rc = write_report(ex, o, duration_s, results, summary, record, out, err); rc != 0) return rc;
  return summary.passed == results.size() ? 0 : 1;
}

}  // namespace sen3bot::sim
