// The results of `sen3bot-sim experiment crowd` (crowd_experiment.hpp): per variant the rates
// with their Wilson intervals and the quartiles, as the printed table, report.json, runs.csv and
// the time-to-goal box plot.
#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "crowd_experiment.hpp"
#include "experiment.hpp"
#include "sen3bot/json/json.hpp"

namespace sen3bot::sim::crowd_experiment {

namespace {


std::string rate_cell(const crowd::Rate& r) {
  char cell[64];
  std::snprintf(cell, sizeof cell, "%zu/%zu %.0f %% [%.0f, %.0f]", r.count, r.n, 100 * r.rate, 100 * r.lower, 100 * r.upper);
  return cell;
}

std::string number_cell(double v, const char* format) {
  if (!std::isfinite(v)) return "-";
  char cell[64];
  std::snprintf(cell, sizeof cell, format, v);
  return cell;
}

void json_rate(json::Writer& w, std::string_view name, const crowd::Rate& r) {
  w.key(name).begin_object()
      .member_uint64("count", r.count)
      .member_uint64("n", r.n)
      .key("rate").fixed_or_null(r.rate, 4)
      .key("lower").fixed_or_null(r.lower, 4)
      .key("upper").fixed_or_null(r.upper, 4)
      .end_object();
}

void json_quartiles(json::Writer& w, std::string_view name, const crowd::Quartiles& q) {
  w.key(name).begin_object()
      .member_uint64("n", q.n)
      .key("median").fixed_or_null(q.median, 4)
      .key("q1").fixed_or_null(q.q1, 4)
      .key("q3").fixed_or_null(q.q3, 4)
      .key("iqr").fixed_or_null(q.iqr, 4)
      .key("min").fixed_or_null(q.min, 4)
      .key("max").fixed_or_null(q.max, 4)
      .end_object();
}

void json_metrics(json::Writer& w, const crowd::RunMetrics& m) {
  w.member_bool("reached_goal", m.reached_goal)
      .member_bool("success", m.success)
      .member_bool("timeout", m.timeout)
      .member_uint32("contacts_any", m.contacts_any)
      .member_uint32("contacts_by_robot", m.contacts_by_robot)
      .member_uint32("cage_entries", m.cage_entries)
      .key("time_to_goal_s").fixed_or_null(m.time_to_goal_s, 4);
  const std::pair<const char*, double> rest[] = {
      {"time_ratio", m.time_ratio},           {"path_length_m", m.path_length_m},
      {"path_ratio", m.path_ratio},           {"min_distance_m", m.min_distance_m},
      {"min_distance_time_s", m.min_distance_time_s}, {"intimate_zone_s", m.intimate_zone_s},
      {"personal_zone_s", m.personal_zone_s}, {"danger_frequency", m.danger_frequency},
      {"mean_jerk_m_s3", m.mean_jerk_m_s3},   {"max_jerk_m_s3", m.max_jerk_m_s3},
      {"mean_angular_jerk_rad_s3", m.mean_angular_jerk_rad_s3}, {"max_angular_jerk_rad_s3", m.max_angular_jerk_rad_s3}};
  for (const auto& [key, value] : rest) w.key(key).fixed_or_null(value, 4);
  w.member_uint64("steps", m.steps);
}

}  // namespace

VariantResults summarize(Variant v, std::vector<const CrowdRun*> runs) {
  VariantResults s{v, std::move(runs), {}, {}, {}, {}, {}, {}, 0, 0, 0};
  std::vector<double> time_ratios, path_ratios;
  std::size_t any = 0;
  for (const CrowdRun* r : s.runs) {
    const crowd::RunMetrics& m = r->metrics;
    s.metrics.push_back(m);
    if (m.contacts_any > 0) ++any;
    if (m.success) {
      s.success_times.push_back(m.time_to_goal_s);
      if (m.time_ratio >= 0) time_ratios.push_back(m.time_ratio);
      if (m.path_ratio >= 0) path_ratios.push_back(m.path_ratio);
    }
    s.mean_cage_entries += m.cage_entries;
    s.mean_jerk += m.mean_jerk_m_s3;
    s.max_jerk = std::max(s.max_jerk, m.max_jerk_m_s3);
  }
  const double n = static_cast<double>(s.runs.size());
  if (n > 0) {
    s.mean_cage_entries /= n;
    s.mean_jerk /= n;
  }
  s.aggregate = crowd::aggregate(s.metrics);
  const crowd::Interval i = crowd::wilson_interval(any, s.runs.size());
  s.any_contact = {any, s.runs.size(), n > 0 ? static_cast<double>(any) / n : 0.0, i.lower, i.upper};
  s.time_ratio = crowd::quartiles(time_ratios);
  s.path_ratio = crowd::quartiles(path_ratios);
  return s;
}

std::string describe_scene(const Options& o, std::size_t people, crowd::Behaviour behaviour) {
  if (!o.trajectories.empty()) return "recording " + o.trajectories + " replayed";
  char text[160];
  std::snprintf(text, sizeof text, "%s scene, %zu %s", o.scene.c_str(), people, crowd::to_string(behaviour));
  return std::string(text) + (people == 1 ? " person" : " people");
}

void print_table(std::FILE* out, const std::vector<VariantResults>& variants, const std::string& head) {
  std::fprintf(out, "\n| %-40s |", head.c_str());
  for (const VariantResults& v : variants) std::fprintf(out, " %-24s |", name_of(v.variant));
  std::fprintf(out, "\n|%s|", std::string(42, '-').c_str());
  for (std::size_t i = 0; i < variants.size(); ++i) std::fprintf(out, "%s|", std::string(26, '-').c_str());
  auto row = [&](const char* name, auto cell) {
    std::fprintf(out, "\n| %-40s |", name);
    for (const VariantResults& v : variants) std::fprintf(out, " %-24s |", cell(v).c_str());
  };
  row("runs", [](const VariantResults& v) { return std::to_string(v.runs.size()); });
  row("success (95 % Wilson interval)", [](const VariantResults& v) { return rate_cell(v.aggregate.success); });
  row("collisions (robot moving into someone)", [](const VariantResults& v) { return rate_cell(v.aggregate.collision); });
  row("runs with any contact", [](const VariantResults& v) { return rate_cell(v.any_contact); });
  row("timeouts", [](const VariantResults& v) { return rate_cell(v.aggregate.timeout); });
  row("time to goal, s: median (IQR) *", [](const VariantResults& v) {
    const crowd::Quartiles& q = v.aggregate.time_to_goal_s;
    if (q.n == 0) return std::string("-");
    char cell[64];
    std::snprintf(cell, sizeof cell, "%.1f (%.1f)", q.median, q.iqr);
    return std::string(cell);
  });
  row("time ratio to the free path: median *", [](const VariantResults& v) { return number_cell(v.time_ratio.median, "%.2f"); });
  row("path ratio to the free path: median *", [](const VariantResults& v) { return number_cell(v.path_ratio.median, "%.2f"); });
  row("min distance to a person, m: median", [](const VariantResults& v) { return number_cell(v.aggregate.min_distance_m.median, "%.2f"); });
  row("intimate zone (< 0.45 m), s: mean", [](const VariantResults& v) { return number_cell(v.aggregate.mean_intimate_zone_s, "%.2f"); });
  row("personal zone (< 1.2 m), s: mean", [](const VariantResults& v) { return number_cell(v.aggregate.mean_personal_zone_s, "%.2f"); });
  row("danger frequency (< 0.2 m): mean", [](const VariantResults& v) { return number_cell(v.aggregate.mean_danger_frequency, "%.3f"); });
  row("cage entries: mean", [](const VariantResults& v) { return number_cell(v.mean_cage_entries, "%.2f"); });
  row("jerk, m/s^3: mean / max", [](const VariantResults& v) {
    char cell[64];
    std::snprintf(cell, sizeof cell, "%.2f / %.2f", v.mean_jerk, v.max_jerk);
    return std::string(cell);
  });
  std::fprintf(out, "\n* successful runs only\n");
}

bool write_report_json(const std::string& path, const Options& o, std::size_t people, const std::vector<VariantResults>& variants) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return false;
  json::FileSink sink(f);
  json::Writer w(sink, json::Style::spaced);
  w.begin_object().line(2).member("experiment", "crowd").line(2).member("scene", o.trajectories.empty() ? std::string_view(o.scene) : std::string_view("recorded"));
  w.line(2).key("trajectories");
  if (o.trajectories.empty()) w.null();
  else w.string(o.trajectories);
  w.line(2).member_uint64("people", people).line(2).key("behaviour");
  if (!o.trajectories.empty()) w.string("recorded");
  else if (o.behaviour) w.string(crowd::to_string(*o.behaviour));
  else w.null();
  w.line(2).member_uint64("runs", o.runs)
      .line(2).member_uint64("seed", o.seed)
      .line(2).member_int64("jobs", o.jobs)
      .line(2).member("clock", o.realtime ? "realtime" : "lockstep")
      .line(2).member("config", o.config_path);
  w.line(2).key("variants").begin_object();
  for (const VariantResults& v : variants) {
    const crowd::Aggregate& a = v.aggregate;
    w.line(4).key(name_of(v.variant)).begin_object().line(6).key("aggregate").begin_object().member_uint64("runs", a.n);
    json_rate(w, "success", a.success);
    json_rate(w, "collision", a.collision);
    json_rate(w, "any_contact", v.any_contact);
    json_rate(w, "timeout", a.timeout);
    json_quartiles(w.line(8), "time_to_goal_s", a.time_to_goal_s);
    json_quartiles(w.line(8), "time_ratio", v.time_ratio);
    json_quartiles(w.line(8), "path_ratio", v.path_ratio);
    json_quartiles(w.line(8), "min_distance_m", a.min_distance_m);
    w.line(8).key("mean_intimate_zone_s").fixed_or_null(a.mean_intimate_zone_s, 4)
        .key("mean_personal_zone_s").fixed_or_null(a.mean_personal_zone_s, 4)
        .key("mean_danger_frequency").fixed_or_null(a.mean_danger_frequency, 4)
        .key("mean_cage_entries").fixed_or_null(v.mean_cage_entries, 4)
        .key("mean_jerk_m_s3").fixed_or_null(v.mean_jerk, 4)
        .key("max_jerk_m_s3").fixed_or_null(v.max_jerk, 4)
        .end_object();
    w.line(6).key("runs").begin_array();
    for (const auto& run : v.runs) {
      const CrowdRun& r = *run;
      w.line(8).begin_object().member_uint64("seed", r.seed);
      json_metrics(w, r.metrics);
      w.key("sim_s").fixed_or_null(r.sim_s, 2).key("wall_s").fixed_or_null(r.wall_s, 3).end_object();
    }
    w.line(6).end_array().line(4).end_object();
  }
  w.line(2).end_object().line(0).end_object();
  const bool written = static_cast<bool>(w.finish()) && std::fputc('\n', f) != EOF;
  return std::fclose(f) == 0 && written;
}

bool write_runs_csv(const std::string& path, const std::vector<CrowdRun>& runs) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return false;
  std::fputs("variant,seed,reached_goal,success,timeout,contacts_any,contacts_by_robot,cage_entries,time_to_goal_s,time_ratio,"
             "path_length_m,path_ratio,min_distance_m,min_distance_time_s,intimate_zone_s,personal_zone_s,danger_frequency,"
             "mean_jerk_m_s3,max_jerk_m_s3,mean_angular_jerk_rad_s3,max_angular_jerk_rad_s3,steps,sim_s\n",
             f);
  for (const CrowdRun& r : runs) {
    const crowd::RunMetrics& m = r.metrics;
    std::fprintf(f, "%s,%llu,%d,%d,%d,%u,%u,%u", name_of(r.variant), static_cast<unsigned long long>(r.seed), m.reached_goal ? 1 : 0,
                 m.success ? 1 : 0, m.timeout ? 1 : 0, m.contacts_any, m.contacts_by_robot, m.cage_entries);
    for (const double v : {m.time_to_goal_s, m.time_ratio, m.path_length_m, m.path_ratio, m.min_distance_m, m.min_distance_time_s,
                           m.intimate_zone_s, m.personal_zone_s, m.danger_frequency, m.mean_jerk_m_s3, m.max_jerk_m_s3,
                           m.mean_angular_jerk_rad_s3, m.max_angular_jerk_rad_s3}) {
      if (std::isfinite(v)) std::fprintf(f, ",%.4f", v);
      else std::fputs(",", f);
    }
    std::fprintf(f, ",%llu,%.2f\n", static_cast<unsigned long long>(m.steps), r.sim_s);
  }
  return std::fclose(f) == 0;
}


bool write_time_box_plot(const std::string& path, const Options& o, const std::string& scene_text,
                         const std::vector<VariantResults>& variants) {
  std::vector<experiment::BoxPlotSeries> series;
  for (const VariantResults& v : variants) series.push_back({name_of(v.variant), v.success_times});
  char title[160], subtitle[200];
  std::snprintf(title, sizeof title, "time to goal: %s, N = %llu", scene_text.c_str(), static_cast<unsigned long long>(o.runs));
  std::snprintf(subtitle, sizeof subtitle,
                "box: quartiles (IQR), bar: median, whiskers: furthest run within 1.5 IQR, rings: outliers; seeds %llu..%llu",
                static_cast<unsigned long long>(o.seed), static_cast<unsigned long long>(o.seed + o.runs - 1));
  experiment::BoxPlotText words;
  words.axis = "time to goal (s)";
  words.runs = "successful";
  return experiment::draw_travel_time_box_plot(title, subtitle, series, words).write_png(path);
}

}  // namespace sen3bot::sim::crowd_experiment
