// `sen3bot-sim sim`: named scenarios on the simulated robot, each case a whole firmware run in
// lockstep (or real) time, with a report folder: a figure per case (report_figure.hpp) and a
// JSON summary with per-task statistics.
#include <signal.h>
#include <sys/stat.h>

#include <algorithm>
#include <array>
#include <memory>
#include <memory_resource>
#include <cerrno>
#include <cmath>
#include <chrono>
#include <cstdio>
#include <cstring>
#include <span>
#include <numbers>
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "cli_util.hpp"
#include "config.hpp"
#include "firmware.hpp"
#include "report_figure.hpp"
#include "runner.hpp"
#include "sen3bot/crowd/crowd.hpp"
#include "sen3bot/json/json.hpp"
#include "sen3bot/sim/sim_board.hpp"
#include "sen3bot/sim/sim_config.hpp"
#include "sim_commands.hpp"
#include "sen3bot/view/server.hpp"

namespace sen3bot::sim {

using firmware::Firmware;
using firmware::FirmwareConfig;
using firmware::MissionReport;
using firmware::MissionState;
using firmware::MissionTask;

namespace {

constexpr double kKidnapRecoveryAlphaSlow = 0.001;
constexpr double kKidnapRecoveryAlphaFast = 0.1;
constexpr hal::Nanos kIoSliceNs = hal::millis(10);
constexpr double kStandingM_s = 0.005;

struct Kidnap {
  double time_s = -1.0;  // < 0: none
  msg::Pose2D to;
};

struct Case {
  const char* name;
  const char* description;
  std::vector<world::MoverScript> movers;
  Kidnap kidnap = {};
  // What happens to the CAN safety I/O node (needs sim.io_node and devices.io_node).
  std::vector<SimIoEvent> io_events = {};
};

SimIoEvent io_inputs(double at_s, std::uint8_t inputs) { return {at_s, SimIoEvent::What::inputs, inputs}; }
SimIoEvent io_fault(double at_s, SimIoEvent::What what) { return {at_s, what, 0}; }
// config/sim.yaml's wiring: the e-stop chain on input 1 (active-low), reset on 2, a bumper on 3.
constexpr std::uint8_t kChainClosed = 0x01, kEstopPressed = 0x00, kResetPressed = 0x03, kBumperHit = 0x05;
// The reset button pressed for 0.2 s at at_s.
std::vector<SimIoEvent> reset_at(double at_s) {
  return {io_inputs(at_s, kResetPressed), io_inputs(at_s + 0.2, kChainClosed)};
}
std::vector<SimIoEvent> events(std::initializer_list<std::vector<SimIoEvent>> parts) {
  std::vector<SimIoEvent> all;
  for (const auto& part : parts) all.insert(all.end(), part.begin(), part.end());
  return all;
}

struct Scenario {
  const char* name;
  const char* description;
  msg::Pose2D start;
  std::vector<msg::Point2D> goals;
  // The safe path, relative to the base configuration's folder: a curve file for the
  // supervisory planner, or a waypoint file; both "" keep the base configuration's.
  const char* safe_curve;
  const char* waypoints;
  std::vector<Case> cases;
  // People on: the simulated detector, the fusion, the cages and the online SGP; the report
  // adds replans_triggered, min_person_distance_m and cage_entries per case.
  bool people = false;
  // The thesis' supervised-planning test ran without a moving-obstacle layer; at 5 scans/s the
  // layer tracks a still box's faces, coming into view one after another, as a slow mover for
  // a few seconds and the robot waits behind it (docs/navigation.md).
  bool without_movers_layer = false;
};

world::MoverScript box_at(double x_m, double y_m, double appear_s) {
  world::MoverScript box;
  box.path = {{x_m, y_m}};
  box.size_m = 0.4;  // the thesis' obstacle: a 40 cm box
  box.shape = world::MoverShape::square;
  box.appear_time_s = appear_s;
  return box;
}

// How fast a walker slows down and sets off again at the ends of a walk.
constexpr double kWalkerAccelMS2 = 1.0;

world::MoverScript person_walking(std::vector<msg::Point2D> path, double speed_m_s, double start_s) {
  world::MoverScript person;
  person.path = std::move(path);
  person.speed_m_s = speed_m_s;
  person.size_m = 0.45;
  person.start_time_s = start_s;
  person.accel_m_s2 = kWalkerAccelMS2;
  person.person = true;
  return person;
}

std::vector<Scenario> scenarios() {
  const msg::Pose2D thesis_start{4.0, 7.0, -std::numbers::pi / 2};
  return {
      {"thesis-sgp",
       "the thesis' supervised-planning test: (4, 7) m to (2.5, 2) m on the lab map along the safe path",
       thesis_start,
       {{2.5, 2.0}},
       "maps/lab_curve.yaml",
       "",
       {{"no-obstacle", "nothing unexpected on the way", {}},
        {"obstacle-before-planning", "a 40 cm box on the safe path, there from the start", {box_at(3.3, 5.37, 0.0)}},
        {"obstacle-during-motion", "a 40 cm box that appears on the safe path while the robot drives",
         {box_at(2.81, 3.25, 8.2)}}},
       false,
       true},
      {"person-crossing",
       "the main mission: (2.5, 2) m to (4, 7) m and back while a worker crosses the upper area",
       {2.5, 2.0, std::numbers::pi / 2},
       {{4.0, 7.0}, {2.5, 2.0}},
       "",
       "",
       {{"worker", "a person walking across the robot's way, back and forth",
         {person_walking({{5.0, 5.3}, {1.0, 5.3}}, 0.6, 6.0)}}}},
      {"people-crossing",
       "the main mission among people: (2.5, 2) m to (4, 7) m and back on the lab's safe curve, two workers "
       "crossing its way at 0.6 and 1.0 m/s, found by the camera and the laser and caged (each seed starts "
       "them at other points of their walks)",
       {2.5, 2.0, std::numbers::pi / 2},
       {{4.0, 7.0}, {2.5, 2.0}},
       "maps/lab_curve.yaml",
       "",
       {{"two-workers", "one across the upper area, one across the lower area",
         {person_walking({{6.8, 5.5}, {0.8, 5.5}}, 0.6, 0.0), person_walking({{1.8, 3.0}, {6.8, 3.0}}, 1.0, 0.0)}}},
       true},
      {"kidnapped",
       "(2.5, 2) m to (4, 7) m and back; on the way back the robot is carried into the lower work area, its odometry "
       "not told",
       {2.5, 2.0, std::numbers::pi / 2},
       {{4.0, 7.0}, {2.5, 2.0}},
       "",
       "",
       {{"carried-downstairs",
         "at t = 19 s, leaving (4, 7) m in the upper storage area, carried to (5, 3.5) m in the lower work area, facing east",
         {},
         {19.0, {5.0, 3.5, 0.0}}}}},
      {"estop",
       "the main mission, (2.5, 2) m to (4, 7) m and back, with the CAN safety I/O node's e-stop chain: each case stops "
       "the robot while it drives, and it goes on only once the cause is gone and the reset button was pressed",
       {2.5, 2.0, std::numbers::pi / 2},
       {{4.0, 7.0}, {2.5, 2.0}},
       "",
       "",
       {{"estop-pressed", "the e-stop pressed at t = 6 s, released at 9 s, reset at 11 s", {}, {},
         events({{io_inputs(6.0, kEstopPressed), io_inputs(9.0, kChainClosed)}, reset_at(11.0)})},
        {"bumper-hit", "a bumper pressed for 0.3 s at t = 6 s, reset at 8 s", {}, {},
         events({{io_inputs(6.0, kBumperHit), io_inputs(6.3, kChainClosed)}, reset_at(8.0)})},
        {"node-silent", "the I/O node silent from t = 6 s to 7 s (a cut cable), reset at 9 s", {}, {},
         events({{io_fault(6.0, SimIoEvent::What::silent), io_fault(7.0, SimIoEvent::What::talking)}, reset_at(9.0)})},
        {"bus-off", "the CAN bus off from t = 6 s to 6.5 s, reset at 8 s", {}, {},
         events({{io_fault(6.0, SimIoEvent::What::bus_off), io_fault(6.5, SimIoEvent::What::bus_on)}, reset_at(8.0)})},
        {"node-reboot", "the I/O node reboots at t = 6 s (configured and started again), reset at 8 s", {}, {},
         events({{io_fault(6.0, SimIoEvent::What::reboot)}, reset_at(8.0)})}}},
      {"osgp",
       "the source's online-SGP cases: (4, 7) m to (2.5, 2) m on the lab's safe curve, with people found by the camera "
       "and the laser and kept in cages",
       thesis_start,
       {{2.5, 2.0}},
       "maps/lab_curve.yaml",
       "",
       {{"person-on-path", "a person standing by the right-hand rack, 0.45 m beside the safe path: re-plan, pass at a distance",
         {world::standing_person(4.3, 5.7)}},
        {"person-far", "a person standing 1.3 m beyond the goal, off the route: caged, no re-plan",
         {world::standing_person(3.3, 1.0)}},
        {"box-on-path", "a 40 cm box where the person of case 1 stands: the local planner goes round it, no re-plan",
         {box_at(4.3, 5.7, 0.0)}}},
       true},
  };
}


// The referee's person position errors, 1-6 m from the robot.
struct PersonErrors {
  std::size_t samples = 0;
  double median_m = 0;
  double p95_m = 0;
  std::uint64_t false_people = 0;
};

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

struct CaseResult {
  std::string name;
  std::string title;  // the figure's: "case 2/3: NAME"
  std::string description;
  MissionReport report;
  RefereeReport truth;
  std::vector<TimedPose> contacts;  // where and when each began
  double sim_time_s = 0;
  double wall_time_s = 0;
  msg::Pose2D final_pose;  // the estimate when the case ended
  bool kidnapped = false;
  std::vector<tasks::TaskStats> stats;
  // The safe path: the supervisory planner's (its runs and last result) or a file's.
  bool sgp = false;
  std::uint32_t sgp_runs = 0;
  nav::SgpResult sgp_result;
  double sgp_time_ms = 0;
  std::size_t safe_path_points = 0;
  // With people on.
  bool people = false;
  std::uint64_t replans_triggered = 0;
  std::uint64_t cage_entries = 0;            // the robot moved into a person's cage
  std::uint64_t cage_entries_by_person = 0;  // a person walked up to the robot
  std::uint64_t boxes_located = 0;
  PersonErrors person_errors;
  std::vector<figure::CageMark> cages;
  std::vector<msg::Point2D> planned;    // the last goal's safe path, before any re-plan
  std::vector<msg::Point2D> replanned;  // the last online re-plan's safe path
  // With safety I/O events (lockstep): the first event's effect on the true robot.
  bool safety_io = false;
  std::uint64_t io_trips = 0;
  double io_speed_at_event_m_s = 0;
  double io_stop_s = -1;  // from the first event to the robot standing (-1: it never stood)
  double io_stop_distance_m = 0;
  double io_held_s = 0;   // time the safety I/O held the robot (its stop reasons on)
};

bool write_json(const std::string& path, const Scenario& scenario, std::uint64_t seed, const std::vector<CaseResult>& results) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return false;
  json::FileSink sink(f);
  json::Writer w(sink, json::Style::spaced);
  w.begin_object().line(2).member("scenario", scenario.name).line(2).member_uint64("seed", seed).line(2).key("cases");
  w.begin_array();
  for (const CaseResult& c : results) {
    const MissionReport& r = c.report;
    const RefereeReport& truth = c.truth;
    double time_s = 0;
    for (std::size_t g = 0; g < r.goals_reached; ++g) time_s += r.goal_time_s[g];
    w.line(4).begin_object()
        .member("name", c.name)
        .member_bool("reached", r.state == MissionState::complete)
        .member_uint64("collisions", truth.moving_contacts)
        .member_uint64("contacts", truth.contacts)
        .key("time_s").fixed_or_null(time_s, 2)
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
    if (c.safety_io) {
      w.line(5).key("safety_io").begin_object()
          .member_uint64("trips", c.io_trips)
          .key("speed_at_event_m_s").fixed_or_null(c.io_speed_at_event_m_s, 3)
          .key("stop_s").fixed_or_null(c.io_stop_s, 3)
          .key("stop_distance_m").fixed_or_null(c.io_stop_distance_m, 3)
          .key("held_s").fixed_or_null(c.io_held_s, 2)
          .end_object();
    }
    if (c.people) {
      w.line(5).member_uint64("replans_triggered", c.replans_triggered)
          .key("min_person_distance_m").fixed_or_null(truth.min_person_distance_m, 3)
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
    w.line(5).key("tasks").begin_array();
    for (const tasks::TaskStats& t : c.stats) {
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
    w.end_array().end_object();
  }
  w.line(2).end_array().line(0).end_object();
  const bool written = static_cast<bool>(w.finish()) && std::fputc('\n', f) != EOF;
  return std::fclose(f) == 0 && written;
}

// The case's walkers (people walking a two-point path back and forth) as a crowd's social or
// blind walkers: each from where its script would be at t = 0, heading where it would head, at
// its scripted speed, round the same route for ever. The crowd knows no walls of the map: the
// scenarios' walks run down open aisles.
void walkers_to_crowd(SimulationConfig& world, crowd::Behaviour behaviour) {
  auto people = std::make_shared<crowd::CrowdConfig>();
  people->behaviour = behaviour;
  std::vector<world::MoverScript> kept;
  for (const world::MoverScript& m : world.movers) {
    if (!m.person || m.path.size() != 2 || !(m.speed_m_s > 0) || m.appear_time_s > 0) {
      kept.push_back(m);
      continue;
    }
    const msg::Point2D a = m.path[0], b = m.path[1];
    const double length = std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
    const double along = length > 0 ? std::fmod(std::max(0.0, m.phase_m), 2.0 * length) : 0.0;
    const bool out = along < length;  // on the way from a to b
    const double u = length > 0 ? (out ? along : along - length) / length : 0.0;
    const msg::Point2D from = out ? a : b, to = out ? b : a;
    crowd::Person p;
    p.start = {from.x_m + u * (to.x_m - from.x_m), from.y_m + u * (to.y_m - from.y_m)};
    p.goals[0] = to;
    p.goals[1] = from;
    p.goal_count = 2;
    p.loop = true;
    p.desired_speed_m_s = m.speed_m_s;
    p.radius_m = m.size_m / 2;
    p.appear_s = m.start_time_s;
    people->people.push_back(p);
  }
  world.movers = std::move(kept);
  if (!people->people.empty()) world.crowd = std::move(people);
}

// One case: a whole firmware over the simulated robot, until the mission ends or times out.
int run_case(const FirmwareConfig& config, const SimulationConfig& world, bool realtime, const std::string& label,
             const std::string& report_dir, CaseResult& result, view::Server* view, std::FILE* out, std::FILE* err) {
  Result<std::unique_ptr<SimBoard>> created = SimBoard::create(world, !realtime);
  if (!created) {
    std::fprintf(err, "sen3bot-sim sim: %s: %s\n", label.c_str(), created.error().c_str());
    return 1;
  }
  SimBoard& board = **created;
  std::FILE* quiet = std::fopen("/dev/null", "w");  // the per-task status lines of `run`
  if (quiet == nullptr) quiet = out;
  Firmware fw(config, board, quiet);
  fw.use_view_server(view);
  board.referee().watch_estimate(&fw.pose_estimate());
  board.referee().watch_people(&fw.people());
  auto fail = [&](const Error& e) {
    std::fprintf(err, "sen3bot-sim sim: %s: %s\n", label.c_str(), e.c_str());
    fw.shutdown();
    board.stop();
    if (quiet != out) std::fclose(quiet);
    return 1;
  };
  if (Status s = board.start(); !s) return fail(s.error());
  if (Status s = fw.init(); !s) return fail(s.error());
  tasks::Scheduler& scheduler = fw.scheduler();
  const MissionTask& mission = *fw.mission();
  const double limit_s = config.duration_s > 0 ? config.duration_s : 600.0;
  const auto wall_start = std::chrono::steady_clock::now();
  double sim_s = 0;
  double next_progress_s = 0;
  // For the figure: the published cages every second, and the safe path after each online
  // re-plan.
  double next_cage_s = 0;
  std::uint64_t replans_seen = 0;
  std::uint32_t sgp_runs_seen = 0;
  auto sample_people = [&] {
    if (fw.people_task() == nullptr) return;
    if (sim_s >= next_cage_s) {
      next_cage_s = sim_s + 1.0;
      tasks::Sample<msg::People> people;
      if (fw.people().read(people))
        for (std::size_t i = 0; i < std::min<std::size_t>(people.value.count, msg::People::kMax); ++i) {
          const msg::TrackedPerson& p = people.value.items[i];
          result.cages.push_back({{p.x_m, p.y_m}, p.cage_radius_m, sim_s});
        }
    }
    const nav::OsgpTrigger* osgp = fw.planner() != nullptr ? fw.planner()->osgp() : nullptr;
    if (osgp == nullptr) return;
    if (osgp->count(nav::OsgpOutcome::triggered) != replans_seen) {
      replans_seen = osgp->count(nav::OsgpOutcome::triggered);
      result.replanned.assign(fw.safe_path().begin(), fw.safe_path().end());
    } else if (fw.planner()->sgp_runs() != sgp_runs_seen) {
      result.planned.assign(fw.safe_path().begin(), fw.safe_path().end());  // a new goal's
    }
    sgp_runs_seen = fw.planner()->sgp_runs();
  };
  auto progress = [&] {
    // The estimate: in real time the world steps on the board's own thread.
    tasks::Sample<msg::PoseEstimate> pose;
    fw.pose_estimate().read(pose);
    std::fprintf(out, "  %-28s t=%6.1f s  pose (%5.2f, %5.2f) m  goals %zu  %s\n", label.c_str(), sim_s,
                 pose.value.pose.x_m, pose.value.pose.y_m, mission.report().goals_reached,
                 to_string(mission.report().state));
    std::fflush(out);
  };
  if (realtime) {
    if (Status s = scheduler.start(); !s) return fail(s.error());
    while (!mission.finished() && sim_s < limit_s) {
      std::this_thread::sleep_for(std::chrono::milliseconds(100));
      sim_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
      sample_people();
      if (sim_s >= next_progress_s) {
        progress();
        next_progress_s += 5.0;
      }
    }
  } else {
    hal::SimClock& clock = *board.lockstep_clock();
    // Safety I/O events are watched in 10 ms slices: when the robot stands, and how far it went.
    const std::vector<SimIoEvent>& io_events = board.simulation().config().io_node.events;
    result.safety_io = !io_events.empty();
    const double first_event_s = result.safety_io ? io_events.front().at_s : 0.0;
    msg::Pose2D last_pose{};
    bool event_seen = false;
    auto watch_io = [&] {
      const GroundTruth& truth = board.simulation().truth();
      const double now_s = hal::to_seconds(truth.stamp_ns);
      if (now_s >= first_event_s && result.io_stop_s < 0) {
        if (!event_seen) {
          event_seen = true;
          result.io_speed_at_event_m_s = truth.speed_m_s;
          last_pose = truth.pose;
        }
        result.io_stop_distance_m += std::hypot(truth.pose.x_m - last_pose.x_m, truth.pose.y_m - last_pose.y_m);
        last_pose = truth.pose;
        if (std::fabs(truth.speed_m_s) < kStandingM_s) result.io_stop_s = now_s - first_event_s;
      }
      tasks::Sample<msg::SafetyOutput> safety;
      constexpr std::uint32_t kIoStops =
          msg::kSafetyEstopChain | msg::kSafetyBumper | msg::kSafetyIoLost | msg::kSafetyResetNeeded;
      if (fw.safety_output().read(safety) && (safety.value.reasons & kIoStops) != 0) result.io_held_s += hal::to_seconds(kIoSliceNs);
    };
    while (!mission.finished() && sim_s < limit_s) {
      const hal::Nanos slice = result.safety_io ? kIoSliceNs : hal::millis(500);
      if (Status s = scheduler.run_lockstep(clock, slice); !s) return fail(s.error());
      sim_s = hal::to_seconds(clock.now() - scheduler.start_time_ns());
      if (result.safety_io) watch_io();
      sample_people();
      if (sim_s >= next_progress_s) {
        progress();
        next_progress_s += 5.0;
      }
    }
  }
  fw.shutdown();
  board.stop();
  if (tasks::Sample<msg::PoseEstimate> estimate; fw.pose_estimate().read(estimate)) result.final_pose = estimate.value.pose;
  result.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  result.sim_time_s = sim_s;
  result.report = mission.report();
  result.truth = board.referee().report();
  const std::span<const TimedPose> contacts = board.referee().contact_poses();
  result.contacts.assign(contacts.begin(), contacts.end());
  for (std::size_t i = 0; i < scheduler.task_count(); ++i) result.stats.push_back(scheduler.stats(i));
  result.safe_path_points = fw.safe_path().size();
  if (result.safety_io) {
    if (fw.safety() != nullptr && fw.safety()->latch() != nullptr) result.io_trips = fw.safety()->latch()->trips();
    std::fprintf(out, "  safety I/O: %llu stops; the robot stood %.2f s after the first event, from %.2f m/s in %.3f m; held %.1f s\n",
                 static_cast<unsigned long long>(result.io_trips), result.io_stop_s, result.io_speed_at_event_m_s,
                 result.io_stop_distance_m, result.io_held_s);
  }
  if (const nav::PeopleTask* people = fw.people_task(); people != nullptr) {
    result.people = true;
    result.boxes_located = people->fusion().count(nav::BoxVerdict::located);
    if (const nav::OsgpTrigger* osgp = fw.planner()->osgp(); osgp != nullptr)
      result.replans_triggered = osgp->count(nav::OsgpOutcome::triggered);
    // Cage entries, judged by the simulation against the true people as they moved (scripted or
    // walking a crowd model).
    result.cage_entries = board.simulation().truth().cage_entries;
    result.cage_entries_by_person = board.simulation().truth().cage_entries_by_person;
    result.person_errors = summarize(board.referee().person_errors(), board.referee().report().false_people);
    std::fprintf(out, "  people: %llu boxes placed, %llu online re-plans, %llu cage entries (and %llu by a person)\n",
                 static_cast<unsigned long long>(result.boxes_located),
                 static_cast<unsigned long long>(result.replans_triggered),
                 static_cast<unsigned long long>(result.cage_entries),
                 static_cast<unsigned long long>(result.cage_entries_by_person));
    std::fprintf(out, "  people against the truth (1-6 m): %zu samples, error median %.3f m, p95 %.3f m; %llu false\n",
                 result.person_errors.samples, result.person_errors.median_m, result.person_errors.p95_m,
                 static_cast<unsigned long long>(result.person_errors.false_people));
  }
  if (const nav::PlannerTask* planner = fw.planner(); planner != nullptr && planner->sgp() != nullptr) {
    result.sgp = true;
    result.sgp_runs = planner->sgp_runs();
    result.sgp_result = planner->sgp_result();
    result.sgp_time_ms = planner->sgp_time_ms();
    std::fprintf(out, "  safe path: supervisory planner, %u run%s; the last %s after %.2f m, %zu waypoints, %.3f ms\n",
                 result.sgp_runs, result.sgp_runs == 1 ? "" : "s", nav::to_string(result.sgp_result.stop),
                 result.sgp_result.length_m, result.safe_path_points, result.sgp_time_ms);
  }
  mission.print_report(out);
  board.referee().print(out);
  if (!report_dir.empty()) {
    const std::string png = report_dir + "/" + result.name + ".png";
    figure::CaseFigure figure = case_figure(result.title, result.description, config, fw, board);
    figure.cages = result.cages;
    figure.replanned = result.replanned;
    if (!result.planned.empty()) figure.waypoints = result.planned;
    if (!draw_case_figure(figure).write_png(png))
      std::fprintf(err, "sen3bot-sim sim: cannot write %s\n", png.c_str());
  }
  if (quiet != out) std::fclose(quiet);
  return 0;
}

constexpr const char* kSimUsage =
    "usage: sen3bot-sim sim --list\n"
    "       sen3bot-sim sim --scenario NAME [--case NAME] [--config FILE] [--realtime] [--seed N] [--report DIR]\n"
    "                       [--walkers scripted|social|blind]\n"
    "                       [--view [--view-port P] [--view-address A] [--view-token T] [--view-hold S]]\n"
    "       sen3bot-sim sim --scenario cobot [--attempts N] [--case NAME] [--config FILE] [--seed N] [--report DIR]\n";

// Creates and starts the view's server for a configuration's channels, and says where it is.
Status start_view(const FirmwareConfig& config, std::unique_ptr<view::Server>& server, std::FILE* out, std::FILE* err) {
  std::array<view::ChannelSpec, firmware::kViewChannels> specs{};
  Result<std::size_t> n = Firmware::view_channels(config, false, specs);
  if (!n) {
    std::fprintf(err, "sen3bot-sim sim: --view: %s\n", n.error().c_str());
    return n.error();
  }
  auto created = view::Server::create(config.view.task.server, std::span(specs).first(*n), *std::pmr::new_delete_resource());
  if (!created) {
    std::fprintf(err, "sen3bot-sim sim: --view: %s\n", created.error().c_str());
    return created.error();
  }
  server = std::move(*created);
  if (Status s = server->start(); !s) {
    std::fprintf(err, "sen3bot-sim sim: --view: %s\n", s.error().c_str());
    return s;
  }
  const std::string& a = server->config().address;
  const std::string host = a.find(':') != std::string::npos ? "[" + a + "]" : a;
  std::fprintf(out, "view: http://%s:%d/ (foxglove.websocket.v1 on ws://%s:%d/)\n", host.c_str(), server->port(), host.c_str(),
               server->port());
  std::fflush(out);
  return Status::success();
}

// After the run: the last state stays served for hold_s seconds (< 0: until SIGINT/SIGTERM).
void hold_view(view::Server& server, double hold_s, std::FILE* out) {
  if (hold_s == 0) return;
  const firmware::StopSignalsBlocked blocked;
  if (hold_s < 0) std::fprintf(out, "view: serving the final state until SIGINT or SIGTERM\n");
  else std::fprintf(out, "view: serving the final state for %.0f s\n", hold_s);
  std::fflush(out);
  const auto until = std::chrono::steady_clock::now() + std::chrono::duration<double>(hold_s < 0 ? 1e9 : hold_s);
  while (std::chrono::steady_clock::now() < until) {
    const double left_s = std::chrono::duration<double>(until - std::chrono::steady_clock::now()).count();
    const double wait_s = std::clamp(left_s, 0.0, 0.5);
    timespec wait{static_cast<time_t>(wait_s), static_cast<long>((wait_s - std::floor(wait_s)) * 1e9)};
    if (sigtimedwait(&blocked.signals(), nullptr, &wait) > 0) break;
  }
  server.stop();
}

}  // namespace

int sim_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  std::string scenario_name, report_dir, config_path = "config/sim.yaml";
  bool realtime = false, list = false, have_seed = false;
  std::uint64_t seed = 0;
  std::uint64_t attempts = 3;
  std::string only_case;
  bool view = false;
  view::ServerConfig view_server;
  double view_hold_s = 0;
  std::optional<crowd::Behaviour> walkers;  // none: the scripted walkers
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--list") {
      list = true;
    } else if (arg == "--realtime") {
      realtime = true;
    } else if (arg == "--scenario" && has_value) {
      scenario_name = argv[++i];
    } else if (arg == "--config" && has_value) {
      config_path = argv[++i];
    } else if (arg == "--report" && has_value) {
      report_dir = argv[++i];
    } else if (arg == "--attempts" && has_value) {
      if (!firmware::parse_u64(argv[++i], attempts) || attempts < 1 || attempts > 1000) {
        std::fprintf(err, "sen3bot-sim sim: --attempts: expected 1 to 1000, got '%s'\n", argv[i]);
        return 2;
      }
    } else if (arg == "--case" && has_value) {
      only_case = argv[++i];
    } else if (arg == "--walkers" && has_value) {
      const std::string_view w = argv[++i];
      if (w == "social") walkers = crowd::Behaviour::social;
      else if (w == "blind") walkers = crowd::Behaviour::blind;
      else if (w != "scripted") {
        std::fprintf(err, "sen3bot-sim sim: --walkers: expected scripted, social or blind, got '%s'\n", argv[i]);
        return 2;
      }
    } else if (arg == "--view") {
      view = true;
    } else if (arg == "--view-port" && has_value) {
      std::uint64_t port = 0;
      if (!firmware::parse_u64(argv[++i], port) || port > 65535) {
        std::fprintf(err, "sen3bot-sim sim: --view-port: expected 0 to 65535, got '%s'\n", argv[i]);
        return 2;
      }
      view_server.port = static_cast<int>(port);
    } else if (arg == "--view-address" && has_value) {
      view_server.address = argv[++i];
    } else if (arg == "--view-token" && has_value) {
      view_server.token = argv[++i];
    } else if (arg == "--view-hold" && has_value) {
      char* end = nullptr;
      view_hold_s = std::strtod(argv[++i], &end);
      if (end == argv[i] || *end != '\0' || !(view_hold_s >= -1)) {
        std::fprintf(err, "sen3bot-sim sim: --view-hold: expected seconds (-1: until SIGINT), got '%s'\n", argv[i]);
        return 2;
      }
    } else if (arg == "--seed" && has_value) {
      if (!firmware::parse_u64(argv[++i], seed)) {
        std::fprintf(err, "sen3bot-sim sim: --seed: expected a non-negative integer, got '%s'\n", argv[i]);
        return 2;
      }
      have_seed = true;
    } else {
      std::fprintf(err, "sen3bot-sim sim: unknown or incomplete option '%s'\n%s", argv[i], kSimUsage);
      return 2;
    }
  }
  const std::vector<Scenario> all = scenarios();
  if (list) {
    for (const Scenario& s : all) {
      std::fprintf(out, "%s: %s\n", s.name, s.description);
      for (const Case& c : s.cases) std::fprintf(out, "  %s: %s\n", c.name, c.description);
    }
#ifdef SEN3BOT_HAS_COBOT_SIM
    list_cobot_scenario(out);
#endif
    return 0;
  }
#ifdef SEN3BOT_HAS_COBOT_SIM
  if (scenario_name == "cobot") {
    if (realtime) {
      std::fprintf(err, "sen3bot-sim sim: the cobot scenario runs in lockstep time only (its camera renders between slices)\n");
      return 2;
    }
    if (!report_dir.empty() && ::mkdir(report_dir.c_str(), 0755) != 0 && errno != EEXIST) {
      std::fprintf(err, "sen3bot-sim sim: cannot create %s: %s\n", report_dir.c_str(), std::strerror(errno));
      return 1;
    }
    return cobot_scenario(config_path, report_dir, seed, have_seed, static_cast<std::size_t>(attempts), only_case, out, err);
  }
#endif
  if (attempts != 3) {
    std::fprintf(err, "sen3bot-sim sim: --attempts is the cobot scenario's\n%s", kSimUsage);
    return 2;
  }
  const Scenario* scenario = nullptr;
  for (const Scenario& s : all)
    if (scenario_name == s.name) scenario = &s;
  if (scenario == nullptr) {
    std::fprintf(err, "sen3bot-sim sim: %s '%s' (sen3bot-sim sim --list shows them)\n%s",
                 scenario_name.empty() ? "--scenario is required" : "no scenario named", scenario_name.c_str(), kSimUsage);
    return 2;
  }

  Result<SimulatedRobot> loaded = load_simulated_robot(config_path);
  if (!loaded) {
    std::fprintf(err, "sen3bot-sim sim: %s\n", loaded.error().c_str());
    return 2;
  }
  const FirmwareConfig& base = loaded->firmware;
  const SimulationConfig& base_world = loaded->world;
  if (!base.navigation.enabled || base.has_fleet) {
    std::fprintf(err, "sen3bot-sim sim: %s: needs a navigation section%s\n", config_path.c_str(),
                 base.has_fleet ? " and no fleet section (a scenario gives its own goals)" : "");
    return 2;
  }
  if (!report_dir.empty() && ::mkdir(report_dir.c_str(), 0755) != 0 && errno != EEXIST) {
    std::fprintf(err, "sen3bot-sim sim: cannot create %s: %s\n", report_dir.c_str(), std::strerror(errno));
    return 1;
  }

  if (!only_case.empty() && std::none_of(scenario->cases.begin(), scenario->cases.end(),
                                         [&](const Case& c) { return only_case == c.name; })) {
    std::fprintf(err, "sen3bot-sim sim: scenario %s has no case '%s' (sen3bot-sim sim --list shows them)\n", scenario->name,
                 only_case.c_str());
    return 2;
  }
  // The live view: one server for every case, so a viewer stays connected from one to the next.
  std::unique_ptr<view::Server> view_server_owned;
  if (view) {
    FirmwareConfig shaped = base;
    shaped.view.enabled = true;
    shaped.view.task.server = view_server;
    if (Status s = start_view(shaped, view_server_owned, out, err); !s) return 2;
  }
  std::fprintf(out, "scenario %s (%zu cases, %s time%s%s%s)\n", scenario->name, scenario->cases.size(),
               realtime ? "real" : "lockstep simulated", have_seed ? "" : ", seed from the configuration",
               walkers ? ", walkers: " : "", walkers ? crowd::to_string(*walkers) : "");
  std::vector<CaseResult> results;
  int rc = 0;
  for (std::size_t i = 0; i < scenario->cases.size(); ++i) {
    const Case& c = scenario->cases[i];
    if (!only_case.empty() && only_case != c.name) continue;
    FirmwareConfig config = base;
    if (view) {
      config.view.enabled = true;
      config.view.task.server = view_server;
    }
    config.clock = realtime ? firmware::ClockMode::realtime : firmware::ClockMode::lockstep;
    SimulationConfig world = base_world;
    world.start_pose = scenario->start;
    world.movers = c.movers;
    world.kidnap_time_s = c.kidnap.time_s;
    world.kidnap_pose = c.kidnap.to;
    if (!c.io_events.empty()) {
      if (!world.io_node.enabled || !config.devices.has_io_node) {
        std::fprintf(err, "sen3bot-sim sim: %s: scenario %s needs sim.io_node and devices.io_node (config/sim.yaml has both)\n",
                     config_path.c_str(), scenario->name);
        return 2;
      }
      world.io_node.events = c.io_events;
    }
    if (have_seed) {
      world.seed = seed;
      world.base.noise_seed = static_cast<std::uint32_t>(seed);
    }
    // Among walking people each seed starts them elsewhere on their walks (a low-discrepancy
    // sequence, so nearby seeds differ).
    const std::uint64_t phase_seed = have_seed ? seed : base_world.seed;
    for (std::size_t m = 0; scenario->people && m < world.movers.size(); ++m) {
      world::MoverScript& mover = world.movers[m];
      if (mover.path.size() < 2 || !(mover.speed_m_s > 0)) continue;
      double length = 0;
      for (std::size_t k = 1; k < mover.path.size(); ++k)
        length += std::hypot(mover.path[k].x_m - mover.path[k - 1].x_m, mover.path[k].y_m - mover.path[k - 1].y_m);
      const double u = std::fmod(static_cast<double>(phase_seed) * 0.6180339887 + static_cast<double>(m) * 0.4142135624, 1.0);
      mover.phase_m = u * 2.0 * length;  // a ping-pong cycle is there and back
    }
    if (walkers) walkers_to_crowd(world, *walkers);
    // Carrying the robot off tests recovery: on at AMCL's usual rates if the configuration
    // leaves it off (it is off by default; docs/navigation.md says why).
    if (c.kidnap.time_s >= 0 && !(config.navigation.mcl.recovery_alpha_slow > 0 && config.navigation.mcl.recovery_alpha_fast > 0)) {
      config.navigation.mcl.recovery_alpha_slow = kKidnapRecoveryAlphaSlow;
      config.navigation.mcl.recovery_alpha_fast = kKidnapRecoveryAlphaFast;
      std::fprintf(out, "localization recovery on for this case: alpha_slow %g, alpha_fast %g\n", kKidnapRecoveryAlphaSlow,
                   kKidnapRecoveryAlphaFast);
    }
    config.navigation.mcl.initial_pose = scenario->start;
    config.navigation.mission.goal_count = scenario->goals.size();
    for (std::size_t g = 0; g < scenario->goals.size(); ++g) config.navigation.mission.goals[g] = scenario->goals[g];
    const std::size_t slash = config_path.find_last_of('/');
    const std::string folder = slash == std::string::npos ? "" : config_path.substr(0, slash + 1);
    if (scenario->people) {
      config.navigation.people_enabled = true;
      config.navigation.people_detector = "sim";
      config.tasks["detector"].arena_bytes = 4 * 1024;
      config.tasks["people"].arena_bytes = 64 * 1024;
      world.detector.enabled = true;
      // Walking people are also moving obstacles to the laser: the layer predicts their way.
      const bool walking = std::any_of(c.movers.begin(), c.movers.end(), [](const world::MoverScript& m) {
        return m.person && m.path.size() > 1 && m.speed_m_s > 0;
      });
      if (walking) config.navigation.dynamic_obstacles.enabled = true;
    }
    if (scenario->without_movers_layer) config.navigation.dynamic_obstacles.enabled = false;
    if (scenario->safe_curve[0] != '\0') {
      config.navigation.safe_curve_path = folder + scenario->safe_curve;
      config.navigation.waypoints_path.clear();
    } else if (scenario->waypoints[0] != '\0') {
      config.navigation.waypoints_path = folder + scenario->waypoints;
      config.navigation.safe_curve_path.clear();
    }
    std::fprintf(out, "\ncase %zu/%zu %s: %s\n", i + 1, scenario->cases.size(), c.name, c.description);
    CaseResult& result = results.emplace_back();
    result.name = c.name;
    result.title = "case " + std::to_string(i + 1) + "/" + std::to_string(scenario->cases.size()) + ": " + c.name;
    result.description = std::string(scenario->name) + ": " + c.description;
    result.kidnapped = c.kidnap.time_s >= 0;
    if (run_case(config, world, realtime, c.name, report_dir, result, view_server_owned.get(), out, err) != 0) return 1;
    if (result.report.state != MissionState::complete || result.truth.moving_contacts != 0 || result.cage_entries != 0)
      rc = 3;
  }

  std::fprintf(out, "\nsummary of %s:\n", scenario->name);
  for (const CaseResult& r : results) {
    double time_s = 0;
    for (std::size_t g = 0; g < r.report.goals_reached; ++g) time_s += r.report.goal_time_s[g];
    std::fprintf(out, "  %-26s %-11s collisions %llu  time %5.1f s  path %5.2f m  clearance %.2f m  replans %u  recoveries %u\n",
                 r.name.c_str(), r.report.state == MissionState::complete ? "reached" : "NOT REACHED",
                 static_cast<unsigned long long>(r.truth.moving_contacts), time_s, r.truth.true_path_length_m,
                 r.truth.min_clearance_m, r.report.plans > 0 ? r.report.plans - 1 : 0, r.report.recoveries);
  }
  if (!report_dir.empty()) {
    const std::string json = report_dir + "/report.json";
    if (!write_json(json, *scenario, have_seed ? seed : base_world.seed, results)) {
      std::fprintf(err, "sen3bot-sim sim: cannot write %s\n", json.c_str());
      return 1;
    }
    std::fprintf(out, "report: %s (report.json and one PNG per case)\n", report_dir.c_str());
  }
  if (view_server_owned) hold_view(*view_server_owned, view_hold_s, out);
  return rc;
}

}  // namespace sen3bot::sim
