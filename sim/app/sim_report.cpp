// A case's result of `sen3bot-sim sim` and DIR/report.json (sim_scenarios.hpp): the mission,
// what the ground truth says, the safe path, the safety I/O, the people and the tasks.
#include <algorithm>
#include <cstdio>
#include <span>
#include <string>
#include <vector>

#include "sen3bot/json/json.hpp"
#include "sim_scenarios.hpp"

namespace sen3bot::sim::scenario {

using firmware::MissionReport;
using firmware::MissionState;

namespace {

// The mission as the truth saw it, the final estimate and where contacts began.
void write_mission(json::Writer& w, const CaseResult& c) {
  const MissionReport& r = c.report;
  const RefereeReport& truth = c.truth;
  w.line(4).begin_object()
      .member("name", c.name)
      .member_bool("reached", r.state == MissionState::complete)
      .member_uint64("collisions", truth.moving_contacts)
      .member_uint64("contacts", truth.contacts)
      .key("time_s").fixed_or_null(mission_time_s(r), 2)
      .key("path_length_m").fixed_or_null(truth.true_path_length_m, 3)
      .key("min_clearance_m").fixed_or_null(truth.min_clearance_m, 3)
      .member_uint32("recoveries", r.recoveries)
      .member_uint32("replans", r.plans > 0 ? r.plans - 1 : 0)
      .member_uint32("plan_failures", r.plan_failures)
      .member_uint64("safety_limited_steps", r.safety_limited_steps)
      .key("localization_error_max_m").fixed_or_null(truth.localization_error_max_m, 3)
      .key("simulated_s").fixed_or_null(c.sim_time_s, 2)
      .key("wall_s").fixed_or_null(c.wall_time_s, 3);
  w.key("separation").begin_object()
      .member_uint64("limited_steps", r.separation_limited_steps)
      .key("min_cap_m_s").fixed_or_null(r.separation_min_cap_m_s, 3)
      .key("gap_at_min_m").fixed_or_null(r.separation_gap_at_min_m, 3)
      .end_object();
  w.key("final_pose").begin_object()
      .key("x").fixed_or_null(c.final_pose.x_m, 4)
      .key("y").fixed_or_null(c.final_pose.y_m, 4)
      .key("theta").fixed_or_null(c.final_pose.theta_rad, 4)
      .end_object();
  w.line(5).key("contact_events").begin_array();
  for (const TimedPose& contact : c.contacts) {
    w.begin_object()
        .key("t_s").fixed_or_null(contact.t_s, 2)
        .key("x").fixed_or_null(contact.pose.x_m, 3)
        .key("y").fixed_or_null(contact.pose.y_m, 3)
        .member_bool("by_robot", contact.moving)
        .member("with", contact.person ? "person" : "map or box")
        .end_object();
  }
  w.end_array();
  if (c.kidnapped) {
    w.key("relocalization_s");
    if (truth.relocalization_s >= 0) w.fixed_or_null(truth.relocalization_s, 2);
    else w.null();
  }
}

void write_safe_path(json::Writer& w, const CaseResult& c) {
  w.line(5).key("safe_path").begin_object();
  if (c.sgp) {
    w.member("source", "sgp")
        .member_uint32("runs", c.sgp_runs)
        .member("stop", nav::to_string(c.sgp_result.stop))
        .member_uint64("waypoints", c.safe_path_points)
        .key("length_m").fixed_or_null(c.sgp_result.length_m, 3)
        .key("time_ms").fixed_or_null(c.sgp_time_ms, 3);
  } else {
    w.member("source", "file").member_uint64("waypoints", c.safe_path_points);
  }
  w.end_object();
}

void write_safety_io(json::Writer& w, const CaseResult& c) {
  w.line(5).key("safety_io").begin_object()
      .member_uint64("trips", c.io_trips)
      .key("speed_at_event_m_s").fixed_or_null(c.io_speed_at_event_m_s, 3)
      .key("stop_s").fixed_or_null(c.io_stop_s, 3)
      .key("stop_distance_m").fixed_or_null(c.io_stop_distance_m, 3)
      .key("held_s").fixed_or_null(c.io_held_s, 2)
      .end_object();
}

void write_people(json::Writer& w, const CaseResult& c) {
  w.line(5).member_uint64("replans_triggered", c.replans_triggered)
      .key("min_person_distance_m").fixed_or_null(c.truth.min_person_distance_m, 3)
      .member_uint64("cage_entries", c.cage_entries)
      .member_uint64("cage_entries_by_person", c.cage_entries_by_person)
      .member_uint64("person_boxes_located", c.boxes_located);
  w.line(5).key("person_error").begin_object()
      .member_uint64("samples", c.person_errors.samples)
      .key("median_m").fixed_or_null(c.person_errors.median_m, 3)
      .key("p95_m").fixed_or_null(c.person_errors.p95_m, 3)
      .member_uint64("false_people", c.person_errors.false_people)
      .end_object();
}

void write_tasks(json::Writer& w, const std::vector<tasks::TaskStats>& stats) {
  w.line(5).key("tasks").begin_array();
  for (const tasks::TaskStats& t : stats) {
    w.line(7).begin_object()
        .member("name", t.name)
        .member_int64("period_us", t.period_us)
        .member_int64("budget_us", t.budget_us)
        .member_uint64("runs", t.runs)
        .member_uint64("overruns", t.overruns)
        .member_uint64("slips", t.slips)
        .member_uint64("skips", t.skips)
        .key("exec_mean_us").fixed_or_null(static_cast<double>(t.exec_mean_ns) / 1e3, 1)
        .key("exec_max_us").fixed_or_null(static_cast<double>(t.exec_max_ns) / 1e3, 1)
        .key("jitter_p99_us").fixed_or_null(static_cast<double>(t.jitter_p99_ns) / 1e3, 1)
        .key("cpu_mean_us").fixed_or_null(static_cast<double>(t.cpu_mean_ns) / 1e3, 1)
        .key("cpu_max_us").fixed_or_null(static_cast<double>(t.cpu_max_ns) / 1e3, 1)
        .member_uint64("cpu_overruns", t.cpu_overruns)
        .end_object();
  }
  w.end_array();
}

}  // namespace

PersonErrors summarize(std::span<const float> errors, std::uint64_t false_people) {
  PersonErrors e;
  e.samples = errors.size();
  e.false_people = false_people;
  if (errors.empty()) return e;
  std::vector<float> sorted(errors.begin(), errors.end());
  std::sort(sorted.begin(), sorted.end());
  const auto at = [&](double q) { return static_cast<double>(sorted[static_cast<std::size_t>(q * static_cast<double>(sorted.size() - 1) + 0.5)]); };
  e.median_m = at(0.5);
  e.p95_m = at(0.95);
  return e;
}

double mission_time_s(const MissionReport& r) {
  double time_s = 0;
  for (std::size_t g = 0; g < r.goals_reached; ++g) time_s += r.goal_time_s[g];
  return time_s;
}

bool write_json(const std::string& path, const Scenario& scenario, std::uint64_t seed, const std::vector<CaseResult>& results) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return false;
  json::FileSink sink(f);
  json::Writer w(sink, json::Style::spaced);
  w.begin_object().line(2).member("scenario", scenario.name).line(2).member_uint64("seed", seed).line(2).key("cases");
  w.begin_array();
  for (const CaseResult& c : results) {
    write_mission(w, c);
    write_safe_path(w, c);
    if (c.safety_io) write_safety_io(w, c);
    if (c.people) write_people(w, c);
    write_tasks(w, c.stats);
    w.end_object();
  }
  w.line(2).end_array().line(0).end_object();
  const bool written = static_cast<bool>(w.finish()) && std::fputc('\n', f) != EOF;
  return std::fclose(f) == 0 && written;
}

}  // namespace sen3bot::sim::scenario
