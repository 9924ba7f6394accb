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
#include <optional>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "case_run.hpp"
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
#include "sim_scenarios.hpp"
#include "sen3bot/view/server.hpp"

namespace sen3bot::sim {

using firmware::Firmware;
using firmware::FirmwareConfig;
using firmware::MissionState;
using firmware::MissionTask;
using namespace scenario;

namespace {

constexpr double kKidnapRecoveryAlphaSlow = 0.001;
constexpr double kKidnapRecoveryAlphaFast = 0.1;
constexpr hal::Nanos kIoSliceNs = hal::millis(10);
constexpr double kStandingM_s = 0.005;

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

// The figure's people: the published cages every second, and the safe path as planned for a
// goal and after each online re-plan.
struct PeopleSampler {
  double next_cage_s = 0;
  std::uint64_t replans_seen = 0;
  std::uint32_t sgp_runs_seen = 0;

  void sample(const Firmware& fw, double sim_s, CaseResult& result) {
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
  }
};

// What the run does after each step: the figure's samples, and a progress line every 5 s.
struct CaseWatch {
  CaseWatch(const Firmware& f, const std::string& l, CaseResult& r, std::FILE* o) : fw(f), label(l), result(r), out(o) {}

  const Firmware& fw;
  const std::string& label;
  CaseResult& result;
  std::FILE* out;
  PeopleSampler people;
  double next_progress_s = 0;

  void after_step(double sim_s) {
    people.sample(fw, sim_s, result);
    if (sim_s < next_progress_s) return;
    // The estimate: in real time the world steps on the board's own thread.
    tasks::Sample<msg::PoseEstimate> pose;
    fw.pose_estimate().read(pose);
    const MissionTask& mission = *fw.mission();
    std::fprintf(out, "  %-28s t=%6.1f s  pose (%5.2f, %5.2f) m  goals %zu  %s\n", label.c_str(), sim_s,
                 pose.value.pose.x_m, pose.value.pose.y_m, mission.report().goals_reached,
                 to_string(mission.report().state));
    std::fflush(out);
    next_progress_s += 5.0;
  }
};

// The first safety I/O event's effect on the true robot: its speed then, when it stood and
// how far it went meanwhile; and how long the I/O held it.
class IoWatch {
 public:
  explicit IoWatch(const std::vector<SimIoEvent>& events) : first_event_s_(events.empty() ? 0.0 : events.front().at_s) {}

  void watch(const GroundTruth& truth, const Firmware& fw, CaseResult& result) {
    const double now_s = hal::to_seconds(truth.stamp_ns);
    if (now_s >= first_event_s_ && result.io_stop_s < 0) {
      if (!event_seen_) {
        event_seen_ = true;
        result.io_speed_at_event_m_s = truth.speed_m_s;
        last_pose_ = truth.pose;
      }
      result.io_stop_distance_m += std::hypot(truth.pose.x_m - last_pose_.x_m, truth.pose.y_m - last_pose_.y_m);
      last_pose_ = truth.pose;
      if (std::fabs(truth.speed_m_s) < kStandingM_s) result.io_stop_s = now_s - first_event_s_;
    }
    tasks::Sample<msg::SafetyOutput> safety;
    constexpr std::uint32_t kIoStops =
        msg::kSafetyEstopChain | msg::kSafetyBumper | msg::kSafetyIoLost | msg::kSafetyResetNeeded;
    if (fw.safety_output().read(safety) && (safety.value.reasons & kIoStops) != 0) result.io_held_s += hal::to_seconds(kIoSliceNs);
  }

 private:
  double first_event_s_;
  msg::Pose2D last_pose_{};
  bool event_seen_ = false;
};

// In real time: the scheduler's threads run the firmware; this one looks every 100 ms.
Status run_realtime(Firmware& fw, double limit_s, std::chrono::steady_clock::time_point wall_start, CaseWatch& watch,
                    double& sim_s) {
  const MissionTask& mission = *fw.mission();
  if (Status s = fw.scheduler().start(); !s) return s;
  while (!mission.finished() && sim_s < limit_s) {
    std::this_thread::sleep_for(std::chrono::milliseconds(100));
    sim_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
    watch.after_step(sim_s);
  }
  return Status::success();
}

// In lockstep: 500 ms slices, or 10 ms ones when safety I/O events are watched.
Status run_lockstep(Firmware& fw, SimBoard& board, double limit_s, CaseWatch& watch, double& sim_s) {
  tasks::Scheduler& scheduler = fw.scheduler();
  const MissionTask& mission = *fw.mission();
  hal::SimClock& clock = *board.lockstep_clock();
  CaseResult& result = watch.result;
  const std::vector<SimIoEvent>& io_events = board.simulation().config().io_node.events;
  result.safety_io = !io_events.empty();
  IoWatch io(io_events);
  while (!mission.finished() && sim_s < limit_s) {
    const hal::Nanos slice = result.safety_io ? kIoSliceNs : hal::millis(500);
    if (Status s = scheduler.run_lockstep(clock, slice); !s) return s;
    sim_s = hal::to_seconds(clock.now() - scheduler.start_time_ns());
    if (result.safety_io) io.watch(board.simulation().truth(), fw, result);
    watch.after_step(sim_s);
  }
  return Status::success();
}

// What the run left: the mission's report, the truth's, the contacts and the task statistics.
void record_run(CaseResult& result, Firmware& fw, SimBoard& board) {
  result.report = fw.mission()->report();
  result.truth = board.referee().report();
  const std::span<const TimedPose> contacts = board.referee().contact_poses();
  result.contacts.assign(contacts.begin(), contacts.end());
  tasks::Scheduler& scheduler = fw.scheduler();
  for (std::size_t i = 0; i < scheduler.task_count(); ++i) result.stats.push_back(scheduler.stats(i));
  result.safe_path_points = fw.safe_path().size();
}

void report_safety_io(CaseResult& result, const Firmware& fw, std::FILE* out) {
  if (fw.safety() != nullptr && fw.safety()->latch() != nullptr) result.io_trips = fw.safety()->latch()->trips();
  std::fprintf(out, "  safety I/O: %llu stops; the robot stood %.2f s after the first event, from %.2f m/s in %.3f m; held %.1f s\n",
               static_cast<unsigned long long>(result.io_trips), result.io_stop_s, result.io_speed_at_event_m_s,
               result.io_stop_distance_m, result.io_held_s);
}

void report_people(CaseResult& result, const nav::PeopleTask& people, const Firmware& fw, SimBoard& board, std::FILE* out) {
  result.people = true;
  result.boxes_located = people.fusion().count(nav::BoxVerdict::located);
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

void report_safe_path(CaseResult& result, const nav::PlannerTask& planner, std::FILE* out) {
  result.sgp = true;
  result.sgp_runs = planner.sgp_runs();
  result.sgp_result = planner.sgp_result();
  result.sgp_time_ms = planner.sgp_time_ms();
  std::fprintf(out, "  safe path: supervisory planner, %u run%s; the last %s after %.2f m, %zu waypoints, %.3f ms\n",
               result.sgp_runs, result.sgp_runs == 1 ? "" : "s", nav::to_string(result.sgp_result.stop),
               result.sgp_result.length_m, result.safe_path_points, result.sgp_time_ms);
}

void write_case_figure(const std::string& report_dir, const CaseResult& result, const FirmwareConfig& config,
                       const Firmware& fw, SimBoard& board, std::FILE* err) {
  const std::string png = report_dir + "/" + result.name + ".png";
  figure::CaseFigure figure = case_figure(result.title, result.description, config, fw, board);
  figure.cages = result.cages;
  figure.replanned = result.replanned;
  if (!result.planned.empty()) figure.waypoints = result.planned;
  if (!draw_case_figure(figure).write_png(png))
    std::fprintf(err, "sen3bot-sim sim: cannot write %s\n", png.c_str());
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
  const QuietLog quiet(out);
  Firmware fw(config, board, quiet.file());
  fw.use_view_server(view);
  if (Status s = start_case(fw, board); !s) return stop_case(fw, board, label, s.error(), err);
  const double limit_s = config.duration_s > 0 ? config.duration_s : 600.0;
  const auto wall_start = std::chrono::steady_clock::now();
  double sim_s = 0;
  CaseWatch watch(fw, label, result, out);
  const Status ran =
      realtime ? run_realtime(fw, limit_s, wall_start, watch, sim_s) : run_lockstep(fw, board, limit_s, watch, sim_s);
  if (!ran) return stop_case(fw, board, label, ran.error(), err);
  fw.shutdown();
  board.stop();
  if (tasks::Sample<msg::PoseEstimate> estimate; fw.pose_estimate().read(estimate)) result.final_pose = estimate.value.pose;
  result.wall_time_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  result.sim_time_s = sim_s;
  record_run(result, fw, board);
  if (result.safety_io) report_safety_io(result, fw, out);
  if (const nav::PeopleTask* people = fw.people_task(); people != nullptr) report_people(result, *people, fw, board, out);
  if (const nav::PlannerTask* planner = fw.planner(); planner != nullptr && planner->sgp() != nullptr)
    report_safe_path(result, *planner, out);
  fw.mission()->print_report(out);
  board.referee().print(out);
  if (!report_dir.empty()) write_case_figure(report_dir, result, config, fw, board, err);
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

struct SimOptions {
  std::string scenario_name, report_dir, config_path = "config/sim.yaml";
  bool realtime = false, list = false, have_seed = false;
  std::uint64_t seed = 0;
  std::uint64_t attempts = 3;
  std::string only_case;
  bool view = false;
  view::ServerConfig view_server;
  double view_hold_s = 0;
  std::optional<crowd::Behaviour> walkers;  // none: the scripted walkers
};

// 0, or the exit status of a bad command line (said on err).
int parse_sim_options(int argc, char** argv, SimOptions& o, std::FILE* err) {
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    const bool has_value = i + 1 < argc;
    if (arg == "--list") {
      o.list = true;
    } else if (arg == "--realtime") {
      o.realtime = true;
    } else if (arg == "--scenario" && has_value) {
      o.scenario_name = argv[++i];
    } else if (arg == "--config" && has_value) {
      o.config_path = argv[++i];
    } else if (arg == "--report" && has_value) {
      o.report_dir = argv[++i];
    } else if (arg == "--attempts" && has_value) {
      if (!firmware::parse_u64(argv[++i], o.attempts) || o.attempts < 1 || o.attempts > 1000) {
        std::fprintf(err, "sen3bot-sim sim: --attempts: expected 1 to 1000, got '%s'\n", argv[i]);
        return 2;
      }
    } else if (arg == "--case" && has_value) {
      o.only_case = argv[++i];
    } else if (arg == "--walkers" && has_value) {
      const std::string_view w = argv[++i];
      if (w == "social") o.walkers = crowd::Behaviour::social;
      else if (w == "blind") o.walkers = crowd::Behaviour::blind;
      else if (w != "scripted") {
        std::fprintf(err, "sen3bot-sim sim: --walkers: expected scripted, social or blind, got '%s'\n", argv[i]);
        return 2;
      }
    } else if (arg == "--view") {
      o.view = true;
    } else if (arg == "--view-port" && has_value) {
      std::uint64_t port = 0;
      if (!firmware::parse_u64(argv[++i], port) || port > 65535) {
        std::fprintf(err, "sen3bot-sim sim: --view-port: expected 0 to 65535, got '%s'\n", argv[i]);
        return 2;
      }
      o.view_server.port = static_cast<int>(port);
    } else if (arg == "--view-address" && has_value) {
      o.view_server.address = argv[++i];
    } else if (arg == "--view-token" && has_value) {
      o.view_server.token = argv[++i];
    } else if (arg == "--view-hold" && has_value) {
      char* end = nullptr;
      o.view_hold_s = std::strtod(argv[++i], &end);
      if (end == argv[i] || *end != '\0' || !(o.view_hold_s >= -1)) {
        std::fprintf(err, "sen3bot-sim sim: --view-hold: expected seconds (-1: until SIGINT), got '%s'\n", argv[i]);
        return 2;
      }
    } else if (arg == "--seed" && has_value) {
      if (!firmware::parse_u64(argv[++i], o.seed)) {
        std::fprintf(err, "sen3bot-sim sim: --seed: expected a non-negative integer, got '%s'\n", argv[i]);
        return 2;
      }
      o.have_seed = true;
    } else {
      std::fprintf(err, "sen3bot-sim sim: unknown or incomplete option '%s'\n%s", argv[i], kSimUsage);
      return 2;
    }
  }
  return 0;
}

void list_scenarios(const std::vector<Scenario>& all, std::FILE* out) {
  for (const Scenario& s : all) {
    std::fprintf(out, "%s: %s\n", s.name, s.description);
    for (const Case& c : s.cases) std::fprintf(out, "  %s: %s\n", c.name, c.description);
  }
#ifdef SEN3BOT_HAS_COBOT_SIM
  list_cobot_scenario(out);
#endif
}

// The report folder, unless none was asked for or it is there (a failure said on err).
bool make_report_dir(const std::string& report_dir, std::FILE* err) {
  if (report_dir.empty() || ::mkdir(report_dir.c_str(), 0755) == 0 || errno == EEXIST) return true;
  std::fprintf(err, "sen3bot-sim sim: cannot create %s: %s\n", report_dir.c_str(), std::strerror(errno));
  return false;
}

#ifdef SEN3BOT_HAS_COBOT_SIM
int cobot_command(const SimOptions& o, std::FILE* out, std::FILE* err) {
  if (o.realtime) {
    std::fprintf(err, "sen3bot-sim sim: the cobot scenario runs in lockstep time only (its camera renders between slices)\n");
    return 2;
  }
  if (!make_report_dir(o.report_dir, err)) return 1;
  return cobot_scenario(o.config_path, o.report_dir, o.seed, o.have_seed, static_cast<std::size_t>(o.attempts), o.only_case,
                        out, err);
}
#endif

// Among walking people each seed starts them elsewhere on their walks (a low-discrepancy
// sequence, so nearby seeds differ).
void spread_walkers(SimulationConfig& world, std::uint64_t phase_seed) {
  for (std::size_t m = 0; m < world.movers.size(); ++m) {
    world::MoverScript& mover = world.movers[m];
    if (mover.path.size() < 2 || !(mover.speed_m_s > 0)) continue;
    double length = 0;
    for (std::size_t k = 1; k < mover.path.size(); ++k)
      length += std::hypot(mover.path[k].x_m - mover.path[k - 1].x_m, mover.path[k].y_m - mover.path[k - 1].y_m);
    const double u = std::fmod(static_cast<double>(phase_seed) * 0.6180339887 + static_cast<double>(m) * 0.4142135624, 1.0);
    mover.phase_m = u * 2.0 * length;  // a ping-pong cycle is there and back
  }
}

// People on: the simulated detector, the fusion and the cages.
void people_on(FirmwareConfig& config, SimulationConfig& world, const Case& c) {
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

// The scenario's safe path, its file relative to the configuration's folder.
void use_safe_path(FirmwareConfig& config, const Scenario& scenario, const std::string& config_path) {
  const std::size_t slash = config_path.find_last_of('/');
  const std::string folder = slash == std::string::npos ? "" : config_path.substr(0, slash + 1);
  if (scenario.safe_curve[0] != '\0') {
    config.navigation.safe_curve_path = folder + scenario.safe_curve;
    config.navigation.waypoints_path.clear();
  } else if (scenario.waypoints[0] != '\0') {
    config.navigation.waypoints_path = folder + scenario.waypoints;
    config.navigation.safe_curve_path.clear();
  }
}

// A case's firmware and world from the base configuration; 0, or 2 when the case needs what
// the configuration lacks (said on err).
int prepare_case(const SimOptions& o, const Scenario& scenario, const Case& c, const SimulatedRobot& base,
                 FirmwareConfig& config, SimulationConfig& world, std::FILE* out, std::FILE* err) {
  config = base.firmware;
  if (o.view) {
    config.view.enabled = true;
    config.view.task.server = o.view_server;
  }
  config.clock = o.realtime ? firmware::ClockMode::realtime : firmware::ClockMode::lockstep;
  world = base.world;
  world.start_pose = scenario.start;
  world.movers = c.movers;
  world.kidnap_time_s = c.kidnap.time_s;
  world.kidnap_pose = c.kidnap.to;
  if (!c.io_events.empty()) {
    if (!world.io_node.enabled || !config.devices.has_io_node) {
      std::fprintf(err, "sen3bot-sim sim: %s: scenario %s needs sim.io_node and devices.io_node (config/sim.yaml has both)\n",
                   o.config_path.c_str(), scenario.name);
      return 2;
    }
    world.io_node.events = c.io_events;
  }
  if (o.have_seed) {
    world.seed = o.seed;
    world.base.noise_seed = static_cast<std::uint32_t>(o.seed);
  }
  if (scenario.people) spread_walkers(world, o.have_seed ? o.seed : base.world.seed);
  if (o.walkers) walkers_to_crowd(world, *o.walkers);
  // Carrying the robot off tests recovery: on at AMCL's usual rates if the configuration
  // leaves it off (it is off by default; docs/navigation.md says why).
  if (c.kidnap.time_s >= 0 && !(config.navigation.mcl.recovery_alpha_slow > 0 && config.navigation.mcl.recovery_alpha_fast > 0)) {
    config.navigation.mcl.recovery_alpha_slow = kKidnapRecoveryAlphaSlow;
    config.navigation.mcl.recovery_alpha_fast = kKidnapRecoveryAlphaFast;
    std::fprintf(out, "localization recovery on for this case: alpha_slow %g, alpha_fast %g\n", kKidnapRecoveryAlphaSlow,
                 kKidnapRecoveryAlphaFast);
  }
  config.navigation.mcl.initial_pose = scenario.start;
  config.navigation.mission.goal_count = scenario.goals.size();
  for (std::size_t g = 0; g < scenario.goals.size(); ++g) config.navigation.mission.goals[g] = scenario.goals[g];
  if (scenario.people) people_on(config, world, c);
  if (scenario.without_movers_layer) config.navigation.dynamic_obstacles.enabled = false;
  use_safe_path(config, scenario, o.config_path);
  return 0;
}

// The scenario's cases (or the one asked for), each prepared and run: 0 when they all ran
// (passed false when one missed its goal, collided or entered a cage), or the exit status of
// the first that could not.
int run_cases(const SimOptions& o, const Scenario& scenario, const SimulatedRobot& base, view::Server* view,
              std::vector<CaseResult>& results, bool& passed, std::FILE* out, std::FILE* err) {
  for (std::size_t i = 0; i < scenario.cases.size(); ++i) {
    const Case& c = scenario.cases[i];
    if (!o.only_case.empty() && o.only_case != c.name) continue;
    FirmwareConfig config;
    SimulationConfig world;
    if (int bad = prepare_case(o, scenario, c, base, config, world, out, err); bad != 0) return bad;
    std::fprintf(out, "\ncase %zu/%zu %s: %s\n", i + 1, scenario.cases.size(), c.name, c.description);
    CaseResult& result = results.emplace_back();
    result.name = c.name;
    result.title = "case " + std::to_string(i + 1) + "/" + std::to_string(scenario.cases.size()) + ": " + c.name;
    result.description = std::string(scenario.name) + ": " + c.description;
    result.kidnapped = c.kidnap.time_s >= 0;
    if (run_case(config, world, o.realtime, c.name, o.report_dir, result, view, out, err) != 0) return 1;
    if (result.report.state != MissionState::complete || result.truth.moving_contacts != 0 || result.cage_entries != 0)
      passed = false;
  }
  return 0;
}

void print_summary(const Scenario& scenario, const std::vector<CaseResult>& results, std::FILE* out) {
  std::fprintf(out, "\nsummary of %s:\n", scenario.name);
  for (const CaseResult& r : results) {
    std::fprintf(out, "  %-26s %-11s collisions %llu  time %5.1f s  path %5.2f m  clearance %.2f m  replans %u  recoveries %u\n",
                 r.name.c_str(), r.report.state == MissionState::complete ? "reached" : "NOT REACHED",
                 static_cast<unsigned long long>(r.truth.moving_contacts), mission_time_s(r.report),
                 r.truth.true_path_length_m, r.truth.min_clearance_m, r.report.plans > 0 ? r.report.plans - 1 : 0,
                 r.report.recoveries);
  }
}
}  // namespace

int sim_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  SimOptions o;
  if (int rc = parse_sim_options(argc, argv, o, err); rc != 0) return rc;
  const std::vector<Scenario> all = scenario::all();
  if (o.list) {
    list_scenarios(all, out);
    return 0;
  }
#ifdef SEN3BOT_HAS_COBOT_SIM
  if (o.scenario_name == "cobot") return cobot_command(o, out, err);
#endif
  if (o.attempts != 3) {
    std::fprintf(err, "sen3bot-sim sim: --attempts is the cobot scenario's\n%s", kSimUsage);
    return 2;
  }
  const Scenario* scenario = nullptr;
  for (const Scenario& s : all)
    if (o.scenario_name == s.name) scenario = &s;
  if (scenario == nullptr) {
    std::fprintf(err, "sen3bot-sim sim: %s '%s' (sen3bot-sim sim --list shows them)\n%s",
                 o.scenario_name.empty() ? "--scenario is required" : "no scenario named", o.scenario_name.c_str(), kSimUsage);
    return 2;
  }

  Result<SimulatedRobot> loaded = load_simulated_robot(o.config_path);
  if (!loaded) {
    std::fprintf(err, "sen3bot-sim sim: %s\n", loaded.error().c_str());
    return 2;
  }
  const FirmwareConfig& base = loaded->firmware;
  if (!base.navigation.enabled || base.has_fleet) {
    std::fprintf(err, "sen3bot-sim sim: %s: needs a navigation section%s\n", o.config_path.c_str(),
                 base.has_fleet ? " and no fleet section (a scenario gives its own goals)" : "");
    return 2;
  }
  if (!make_report_dir(o.report_dir, err)) return 1;

  if (!o.only_case.empty() && std::none_of(scenario->cases.begin(), scenario->cases.end(),
                                           [&](const Case& c) { return o.only_case == c.name; })) {
    std::fprintf(err, "sen3bot-sim sim: scenario %s has no case '%s' (sen3bot-sim sim --list shows them)\n", scenario->name,
                 o.only_case.c_str());
    return 2;
  }
  // The live view: one server for every case, so a viewer stays connected from one to the next.
  std::unique_ptr<view::Server> view_server;
  if (o.view) {
    FirmwareConfig shaped = base;
    shaped.view.enabled = true;
    shaped.view.task.server = o.view_server;
    if (Status s = start_view(shaped, view_server, out, err); !s) return 2;
  }
  std::fprintf(out, "scenario %s (%zu cases, %s time%s%s%s)\n", scenario->name, scenario->cases.size(),
               o.realtime ? "real" : "lockstep simulated", o.have_seed ? "" : ", seed from the configuration",
               o.walkers ? ", walkers: " : "", o.walkers ? crowd::to_string(*o.walkers) : "");
  std::vector<CaseResult> results;
  bool passed = true;
  if (int stop = run_cases(o, *scenario, *loaded, view_server.get(), results, passed, out, err); stop != 0) return stop;

  print_summary(*scenario, results, out);
  if (!o.report_dir.empty()) {
    const std::string json = o.report_dir + "/report.json";
    if (!scenario::write_json(json, *scenario, o.have_seed ? o.seed : loaded->world.seed, results)) {
      std::fprintf(err, "sen3bot-sim sim: cannot write %s\n", json.c_str());
      return 1;
    }
    std::fprintf(out, "report: %s (report.json and one PNG per case)\n", o.report_dir.c_str());
  }
  if (view_server) hold_view(*view_server, o.view_hold_s, out);
  return passed ? 0 : 3;
}

}  // namespace sen3bot::sim
