// `sen3bot-sim experiment crowd`: the crowd-navigation benchmark (docs/crowd.md, "The
// benchmark"). N runs per variant, each a whole firmware in lockstep from config/crowd.yaml on a
// scene drawn from the run's seed (crowd/scene.hpp), its people moved by a crowd model. The runs
// go to worker processes (mission_pool.hpp); each run's crowd metrics (crowd/metrics.hpp) come
// from the ground truth, sampled every 50 ms.
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <cerrno>
#include <chrono>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <cstring>
#include <limits>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <type_traits>
#include <vector>

#include "cli_util.hpp"
#include "config.hpp"
#include "experiment.hpp"
#include "firmware.hpp"
#include "mission_pool.hpp"
#include "sen3bot/crowd/metrics.hpp"
#include "sen3bot/crowd/recording.hpp"
#include "sen3bot/crowd/scene.hpp"
#include "sen3bot/json/json.hpp"
#include "sen3bot/msg/geometry.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/nav_figure/case_figure.hpp"
#include "sen3bot/sim/sim_board.hpp"
#include "sen3bot/sim/sim_config.hpp"
#include "sim_commands.hpp"
#include "simulated_mission.hpp"

namespace sen3bot::sim {

using firmware::Firmware;
using firmware::FirmwareConfig;
using firmware::MissionState;
using firmware::MissionTask;

namespace {

constexpr const char* kName = "sen3bot-sim experiment crowd";
constexpr std::uint64_t kMaxRuns = 100000;
constexpr std::uint64_t kMaxPeople = 256;
// The meter's sample period: the lockstep slice.
constexpr double kSliceS = 0.05;
// The run goes on this long past the start delay and the scene's limit (localization settling).
constexpr double kRunMarginS = 10.0;

enum class Variant : std::uint8_t { standard, no_people, perfect_perception };
const char* name_of(Variant v) {
  return v == Variant::standard ? "default" : v == Variant::no_people ? "no-people" : "perfect-perception";
}
constexpr const char* kVariantNames = "default, no-people, perfect-perception";

// One run as a worker reports it: fixed size, no pointers.
struct CrowdRun {
  std::uint64_t seed = 0;
  std::uint32_t job = 0;
  Variant variant = Variant::standard;
  bool ran = false;  // false: the run could not run; `error` says why
  crowd::RunMetrics metrics;
  double sim_s = 0;
  double wall_s = 0;
  char error[256] = {};
};
static_assert(std::is_trivially_copyable_v<CrowdRun>);

struct Options {
  std::string scene;         // circle, crossing, corridor, square
  std::string trajectories;  // or a recording
  std::uint64_t people = 0;  // 0: the scene's default
  std::optional<crowd::Behaviour> behaviour;
  std::uint64_t runs = 0;
  std::uint64_t seed = 1;
  long jobs = 0;  // 0: the online CPUs
  bool realtime = false;  // each mission in real time over ptys
  std::vector<Variant> variants;
  std::string report_dir;
  std::string config_path = "config/crowd.yaml";
};

struct Job {
  std::uint64_t seed = 0;
  Variant variant = Variant::standard;
};

struct Plan {
  Options options;
  FirmwareConfig base;
  SimulationConfig base_world;
  std::shared_ptr<const crowd::Recording> recording;
  std::string map_path;  // the scene's floor, written once
  std::vector<Job> jobs;
};

void set_error(CrowdRun& r, std::string_view what) {
  const std::size_t n = std::min(what.size(), sizeof r.error - 1);
  std::memcpy(r.error, what.data(), n);
  r.error[n] = '\0';
}

Result<crowd::Scene> make_run_scene(const Plan& plan, std::uint64_t seed) {
  if (plan.recording) return crowd::recording_scene(plan.recording, seed);
  crowd::SceneOptions options;
  options.name = plan.options.scene;
  options.people = plan.options.people > 0 ? static_cast<std::size_t>(plan.options.people) : crowd::default_people(options.name);
  options.behaviour = plan.options.behaviour;
  return crowd::make_scene(options, seed);
}

FirmwareConfig run_config(const Plan& plan, Variant v, const crowd::Scene& scene) {
  FirmwareConfig config = plan.base;
  config.navigation.map_path = plan.map_path;
  config.navigation.mcl.initial_pose = scene.robot_start;
  config.navigation.mission.goal_count = 1;
  config.navigation.mission.goals[0] = scene.robot_goal;
  // The mission gives up just after the scene's limit; the meter judges by the limit itself.
  config.navigation.mission.goal_timeout_s = scene.time_limit_s + 1.0;
  config.duration_s = config.navigation.mission.start_delay_s + scene.time_limit_s + kRunMarginS;
  if (v == Variant::no_people) {
    // The people pipeline off (the detector, the fusion, the cages); the laser layers stay.
    config.navigation.people_enabled = false;
    config.tasks.erase("detector");
    config.tasks.erase("people");
  } else if (v == Variant::perfect_perception) {
    // The people row relays the true people (SimBoard::true_people): no detector, no fusion.
    config.tasks.erase("detector");
  }
  return config;
}

SimulationConfig run_world(const Plan& plan, Variant v, std::uint64_t seed, const crowd::Scene& scene, double delay_s) {
  SimulationConfig world = plan.base_world;
  world.link = LinkKind::memory;
  world.map_path = plan.map_path;
  world.start_pose = scene.robot_start;
  world.seed = seed;
  world.base.noise_seed = static_cast<std::uint32_t>(seed);
  world.movers.clear();
  if (v != Variant::standard) world.detector.enabled = false;  // nobody reads its boxes
  // The scene's crowd time 0 is when the robot sets off: after the mission's start delay.
  auto people = std::make_shared<crowd::CrowdConfig>(scene.crowd);
  for (crowd::Person& p : people->people) p.appear_s += delay_s;
  people->recording_start_s -= delay_s;
  world.crowd = std::move(people);
  return world;
}

// --- One run -------------------------------------------------------------------------------------

// One run as the sample figure draws it (times from the robot's setting off).
struct Trace {
  std::vector<figure::RobotAt> robot;
  std::vector<figure::MoverTrack> people;
  std::vector<figure::Contact> contacts;
  std::vector<double> times_s;                // per sample
  std::vector<std::vector<msg::Point2D>> at;  // per sample, every person's place (NaN: absent)
  double start_s = 0;                         // the simulated time the robot set off
};

void record(Trace& trace, const crowd::RunStep& step, double t_s) {
  trace.robot.push_back({t_s, step.robot});
  trace.times_s.push_back(t_s);
  std::vector<msg::Point2D>& at = trace.at.emplace_back(step.people.size(), msg::Point2D{NAN, NAN});
  double nearest_m = std::numeric_limits<double>::infinity();
  msg::Point2D nearest{step.robot.x_m, step.robot.y_m};
  for (std::size_t i = 0; i < step.people.size(); ++i) {
    const crowd::PersonTruth& p = step.people[i];
    if (!p.visible) continue;
    figure::MoverTrack& m = trace.people[i];
    m.path.push_back(p.position);
    m.times_s.push_back(t_s);
    m.size_m = 2 * p.radius_m;
    at[i] = p.position;
    const double d = std::hypot(p.position.x_m - step.robot.x_m, p.position.y_m - step.robot.y_m);
    if (d < nearest_m) {
      nearest_m = d;
      nearest = p.position;
    }
  }
  // A contact is drawn halfway between the robot and the person it touched.
  if (step.contact_started)
    trace.contacts.push_back({{(step.robot.x_m + nearest.x_m) / 2, (step.robot.y_m + nearest.y_m) / 2}, t_s, step.contact_by_robot});
}

// A whole firmware on the scene until the mission ends or the run's limit, in 50 ms slices, a
// RunStep to the meter after each once the robot has set off; quiet.
void run_mission(const FirmwareConfig& config, const SimulationConfig& world, const crowd::Scene& scene, bool realtime,
                 CrowdRun& r, Trace* trace = nullptr) {
  const auto wall_start = std::chrono::steady_clock::now();
  const double free_length_m =
      std::hypot(scene.robot_goal.x_m - scene.robot_start.x_m, scene.robot_goal.y_m - scene.robot_start.y_m);
  const double max_v = config.navigation.dwa.max_v_m_s;
  crowd::RunMeter meter;
  crowd::RunSetup setup;
  setup.dt_s = kSliceS;
  setup.time_limit_s = scene.time_limit_s;
  setup.free_path_length_m = free_length_m;
  setup.free_path_time_s = max_v > 0 ? free_length_m / max_v : 0.0;

  // The crowd's movers (sized at the first slice, once the board has them).
  std::size_t first = 0, count = 0;
  bool sized = false;
  std::vector<crowd::PersonTruth> people;
  std::vector<bool> inside;        // in a person's cage
  std::vector<bool> robot_inside;  // and it was the robot's motion that entered it
  bool started_driving = false;
  double start_s = 0;
  double last_theta = 0;
  msg::Pose2D last_pose;
  std::uint64_t last_contacts = 0, last_moving = 0;
  auto on_slice = [&](const Firmware& fw, SimBoard& board, double sim_s) {
    const MissionTask& mission = *fw.mission();
    Simulation& sim = board.simulation();
    const world::World& w = sim.world();
    if (!sized) {
      first = sim.first_crowd_mover();
      count = w.mover_count() > first ? w.mover_count() - first : 0;
      people.resize(count);
      inside.assign(count, false);
      robot_inside.assign(count, false);
      if (trace != nullptr) {
        trace->people.resize(count);
        for (figure::MoverTrack& m : trace->people) {
          m.person = true;
          m.size_m = 0;
        }
      }
      sized = true;
    }
    const GroundTruth& truth = sim.truth();
    if (!started_driving) {
      if (mission.current_goal() == nullptr && !mission.finished()) {
        last_contacts = truth.contacts;
        last_moving = truth.moving_contacts;
        last_theta = truth.pose.theta_rad;
        last_pose = truth.pose;
        return;
      }
      started_driving = true;
      start_s = sim_s;
      if (trace != nullptr) trace->start_s = sim_s;
      setup.start_time_s = start_s;
      meter.start(setup);
    }
    const msg::Pose2D pose = truth.pose;
    for (std::size_t i = 0; i < count; ++i) {
      const std::size_t m = first + i;
      crowd::PersonTruth& p = people[i];
      p.position = w.mover_position(m);
      p.velocity = w.mover_velocity(m);
      p.radius_m = w.mover_script(m).size_m / 2;
      p.visible = w.mover_visible(m);
    }
    // Cage entries: the robot's when its own motion since the last sample closed the distance.
    bool in_cage = false;
    for (std::size_t i = 0; i < count; ++i) {
      const crowd::PersonTruth& p = people[i];
      const double d = std::hypot(p.position.x_m - pose.x_m, p.position.y_m - pose.y_m);
      const bool in = p.visible && d < judged_cage_reach_m(p.radius_m);
      if (in && !inside[i]) {
        const double before = std::hypot(p.position.x_m - last_pose.x_m, p.position.y_m - last_pose.y_m);
        robot_inside[i] = before - d > 0.01;
      }
      if (!in) robot_inside[i] = false;
      inside[i] = in;
      in_cage = in_cage || robot_inside[i];
    }
    crowd::RunStep step;
    step.time_s = sim_s;
    step.robot = pose;
    step.v_m_s = truth.speed_m_s;
    step.w_rad_s = msg::normalize_angle(pose.theta_rad - last_theta) / kSliceS;
    step.footprint = world.footprint;
    step.people = std::span<const crowd::PersonTruth>(people.data(), people.size());
    step.contact_started = truth.contacts > last_contacts;
    step.contact_by_robot = truth.moving_contacts > last_moving;
    step.robot_in_cage = in_cage;
    meter.observe(step);
    if (trace != nullptr) record(*trace, step, sim_s - start_s);
    last_contacts = truth.contacts;
    last_moving = truth.moving_contacts;
    last_theta = pose.theta_rad;
    last_pose = pose;
  };
  auto on_end = [&](Firmware& fw, SimBoard&, double sim_s) {
    const firmware::MissionReport& report = fw.mission()->report();
    const bool reached = report.state == MissionState::complete;
    if (!started_driving) {
      setup.start_time_s = sim_s;
      meter.start(setup);
    }
    const double end_s = reached && report.goals_reached > 0 ? start_s + report.goal_time_s[0] : sim_s;
    r.metrics = meter.finish(reached, end_s);
    r.ran = true;
    r.sim_s = sim_s;
    r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  };
  if (const std::string error =
          run_simulated_mission(config, world,
                                {.slice = hal::millis(50), .true_people = r.variant == Variant::perfect_perception, .realtime = realtime},
                                on_slice, on_end);
      !error.empty())
    set_error(r, error);
}

CrowdRun run_job(const Plan& plan, std::size_t index, Trace* trace = nullptr) {
  const Job& job = plan.jobs[index];
  CrowdRun r;
  r.seed = job.seed;
  r.job = static_cast<std::uint32_t>(index);
  r.variant = job.variant;
  Result<crowd::Scene> scene = make_run_scene(plan, job.seed);
  if (!scene) {
    set_error(r, scene.error().c_str());
    return r;
  }
  const FirmwareConfig config = run_config(plan, job.variant, *scene);
  run_mission(config, run_world(plan, job.variant, job.seed, *scene, config.navigation.mission.start_delay_s), *scene,
              plan.options.realtime, r, trace);
  return r;
}

// The sample run (run again with a trace) as a figure: the people's tracks coloured by time, the
// robot's path and footprint, the contacts and the closest approach.
bool write_sample_figure(const Plan& plan, std::size_t job_index, const std::string& path, const std::string& scene_text,
                         std::FILE* err) {
  Trace trace;
  const CrowdRun r = run_job(plan, job_index, &trace);
  if (!r.ran) {
    std::fprintf(err, "%s: the sample run: %s\n", kName, r.error);
    return false;
  }
  Result<nav::OccupancyMap> map = nav::load_map(plan.map_path);
  Result<crowd::Scene> scene = make_run_scene(plan, r.seed);
  if (!map || !scene) {
    std::fprintf(err, "%s: the sample run's map or scene: %s\n", kName, (!map ? map.error() : scene.error()).c_str());
    return false;
  }
  const crowd::RunMetrics& m = r.metrics;
  figure::CaseFigure f;
  char text[240];
  std::snprintf(text, sizeof text, "crowd sample run: %s, seed %llu, variant %s", scene_text.c_str(),
                static_cast<unsigned long long>(r.seed), name_of(r.variant));
  f.title = text;
  f.description = plan.options.realtime
                      ? "the seed of this variant that came closest to a person, run again in real time (so not the same run); "
                        "times in s since the robot set off"
                      : "the run of this variant with the closest approach to a person; times in s since the robot set off";
  if (m.reached_goal)
    std::snprintf(text, sizeof text, "goal reached in %.1f s; %u contact(s), %u by the robot; closest %.2f m; %u cage entr%s",
                  m.time_to_goal_s, m.contacts_any, m.contacts_by_robot, m.min_distance_m, m.cage_entries,
                  m.cage_entries == 1 ? "y" : "ies");
  else
    std::snprintf(text, sizeof text, "%s; %u contact(s), %u by the robot; closest %.2f m; %u cage entr%s",
                  m.timeout ? "timed out" : "goal not reached", m.contacts_any, m.contacts_by_robot, m.min_distance_m,
                  m.cage_entries, m.cage_entries == 1 ? "y" : "ies");
  f.result = text;
  f.passed = m.success;
  f.map = &*map;
  f.start = scene->robot_start;
  f.goals = {{scene->robot_goal.x_m, scene->robot_goal.y_m}};
  for (const figure::RobotAt& a : trace.robot) f.driven.push_back({a.pose.x_m, a.pose.y_m});
  f.robot = figure::robot_instants(trace.robot, 2.0);
  for (figure::MoverTrack& p : trace.people)
    if (!p.path.empty()) f.movers.push_back(std::move(p));
  f.contacts = trace.contacts;
  f.time_scale_s = trace.times_s.empty() ? 0.0 : std::max(1.0, trace.times_s.back());
  // The closest approach: the sample at its time, the person nearest the robot then.
  if (std::isfinite(m.min_distance_m) && m.min_distance_time_s >= 0 && !trace.times_s.empty()) {
    const double t = m.min_distance_time_s - trace.start_s;
    std::size_t k = 0;
    for (std::size_t j = 1; j < trace.times_s.size(); ++j)
      if (std::abs(trace.times_s[j] - t) < std::abs(trace.times_s[k] - t)) k = j;
    const msg::Pose2D robot = trace.robot[k].pose;
    double best = std::numeric_limits<double>::infinity();
    for (const msg::Point2D& p : trace.at[k]) {
      const double d = std::hypot(p.x_m - robot.x_m, p.y_m - robot.y_m);
      if (std::isfinite(d) && d < best) {
        best = d;
        f.closest = {trace.times_s[k], {robot.x_m, robot.y_m}, p, m.min_distance_m};
      }
    }
  }
  return figure::draw_case_figure(f).write_png(path);
}

// --- The command line ----------------------------------------------------------------------------

int bad(std::FILE* err, const std::string& message) {
  std::fprintf(err, "%s: %s\n", kName, message.c_str());
  return 2;
}

int parse_options(int argc, char** argv, Options& o, std::FILE* err) {
  bool have_runs = false, have_people = false;
  for (int i = 0; i < argc; ++i) {
    const std::string_view arg = argv[i];
    const bool has_value = i + 1 < argc;
    auto value_error = [&](const char* expected) {
      return bad(err, std::string(arg) + ": expected " + expected + ", got '" + argv[i + 1] + "'");
    };
    std::uint64_t u = 0;
    if (arg == "--scene" && has_value) {
      o.scene = argv[++i];
      if (o.scene != "circle" && o.scene != "crossing" && o.scene != "corridor" && o.scene != "square")
        return bad(err, "--scene: no scene named '" + o.scene + "' (circle, crossing, corridor, square; --trajectories FILE for a recording)");
    } else if (arg == "--trajectories" && has_value) {
      o.trajectories = argv[++i];
      if (o.trajectories.empty()) return bad(err, "--trajectories: expected a file");
    } else if (arg == "--people" && has_value) {
      if (!firmware::parse_u64(argv[i + 1], u) || u == 0 || u > kMaxPeople) return value_error("a person count from 1 to 256");
      o.people = u;
      have_people = true;
      ++i;
    } else if (arg == "--behaviour" && has_value) {
      o.behaviour = crowd::parse_behaviour(argv[i + 1]);
      if (!o.behaviour) return value_error("recorded, social, blind or orca");
      ++i;
    } else if (arg == "--runs" && has_value) {
      if (!firmware::parse_u64(argv[i + 1], u) || u == 0 || u > kMaxRuns) return value_error("a run count from 1 to 100000");
      o.runs = u;
      have_runs = true;
      ++i;
    } else if (arg == "--seed" && has_value) {
      if (!firmware::parse_u64(argv[i + 1], u)) return value_error("a non-negative integer");
      o.seed = u;
      ++i;
    } else if (arg == "--jobs" && has_value) {
      if (!firmware::parse_u64(argv[i + 1], u) || u == 0 || u > 1024) return value_error("a worker count from 1 to 1024");
      o.jobs = static_cast<long>(u);
      ++i;
    } else if (arg == "--variant" && has_value) {
      const std::string_view name = argv[i + 1];
      Variant v;
      if (name == "default") v = Variant::standard;
      else if (name == "no-people") v = Variant::no_people;
      else if (name == "perfect-perception") v = Variant::perfect_perception;
      else return bad(err, "--variant: no variant named '" + std::string(name) + "' (" + kVariantNames + ")");
      if (std::find(o.variants.begin(), o.variants.end(), v) == o.variants.end()) o.variants.push_back(v);
      ++i;
    } else if (arg == "--realtime") {
      o.realtime = true;
    } else if (arg == "--report" && has_value) {
      o.report_dir = argv[++i];
      if (o.report_dir.empty()) return bad(err, "--report: expected a directory");
    } else if (arg == "--config" && has_value) {
      o.config_path = argv[++i];
    } else {
      return bad(err, "unknown or incomplete option '" + std::string(arg) + "' (sen3bot-sim --help shows the options)");
    }
  }
  if (o.scene.empty() && o.trajectories.empty())
    return bad(err, "--scene NAME (circle, crossing, corridor, square) or --trajectories FILE is required");
  if (!o.scene.empty() && !o.trajectories.empty()) return bad(err, "--scene and --trajectories are alternatives: give one");
  if (!o.trajectories.empty() && have_people)
    return bad(err, "--people is for the simulated scenes: a recording (--trajectories) brings its own people");
  if (!o.trajectories.empty() && o.behaviour && *o.behaviour != crowd::Behaviour::recorded)
    return bad(err, std::string("--behaviour ") + crowd::to_string(*o.behaviour) +
                        ": a recording (--trajectories) is replayed as it was (--behaviour recorded)");
  if (!o.scene.empty() && o.behaviour && *o.behaviour == crowd::Behaviour::recorded)
    return bad(err, "--behaviour recorded needs --trajectories FILE");
  if (!have_runs) return bad(err, "--runs N is required");
  if (o.variants.empty()) o.variants = {Variant::standard, Variant::no_people, Variant::perfect_perception};
  if (o.jobs == 0) o.jobs = std::max(1L, ::sysconf(_SC_NPROCESSORS_ONLN));
  return 0;
}

// --- The results ---------------------------------------------------------------------------------

struct VariantResults {
  Variant variant;
  std::vector<const CrowdRun*> runs;
  std::vector<crowd::RunMetrics> metrics;
  crowd::Aggregate aggregate;
  crowd::Rate any_contact;
  crowd::Quartiles time_ratio;  // successful runs
  crowd::Quartiles path_ratio;  // successful runs
  std::vector<double> success_times;
  double mean_cage_entries = 0;
  double mean_jerk = 0;  // mean of the runs' mean jerks
  double max_jerk = 0;   // the largest of any run
};

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

// The scene's map: in the report folder, or in a temporary folder removed at the end.
struct MapFolder {
  std::string dir;
  bool temporary = false;
  std::string yaml;
  ~MapFolder() {
    if (!temporary || dir.empty()) return;
    if (!yaml.empty()) {
      std::remove(yaml.c_str());
      std::remove((yaml.substr(0, yaml.size() - 5) + ".pgm").c_str());
    }
    ::rmdir(dir.c_str());
  }
};

}  // namespace

int crowd_experiment_command(int argc, char** argv, std::FILE* out, std::FILE* err) {
  Plan plan;
  Options& o = plan.options;
  if (int rc = parse_options(argc, argv, o, err); rc != 0) return rc;

  if (!o.trajectories.empty()) {
    Result<crowd::Recording> recording = crowd::load_recording(o.trajectories);
    if (!recording) return bad(err, recording.error().c_str());
    plan.recording = std::make_shared<const crowd::Recording>(std::move(*recording));
  }
  // The first run's scene: its options checked before any worker starts, and its floor (the
  // same for every seed) written as the map.
  Result<crowd::Scene> first = make_run_scene(plan, o.seed);
  if (!first) return bad(err, first.error().c_str());
  std::size_t people = first->crowd.behaviour == crowd::Behaviour::recorded && first->crowd.recording
                           ? first->crowd.recording->tracks.size()
                           : first->crowd.people.size();

  Result<SimulatedRobot> loaded = load_simulated_robot(o.config_path);
  if (!loaded) return bad(err, loaded.error().c_str());
  plan.base = std::move(loaded->firmware);
  plan.base_world = std::move(loaded->world);
  if (!plan.base.navigation.enabled || plan.base.has_fleet)
    return bad(err, o.config_path + ": needs a navigation section (and no fleet section)");
  if (!o.report_dir.empty()) {
    if (::mkdir(o.report_dir.c_str(), 0755) != 0 && errno != EEXIST)
      return bad(err, "--report: cannot create " + o.report_dir + ": " + std::strerror(errno));
    struct stat st {};
    if (::stat(o.report_dir.c_str(), &st) != 0 || !S_ISDIR(st.st_mode) || ::access(o.report_dir.c_str(), W_OK | X_OK) != 0)
      return bad(err, "--report: " + o.report_dir + " is not a writable directory");
  }
  MapFolder maps;
  if (o.report_dir.empty()) {
    char dir[] = "/tmp/sen3bot-crowd-XXXXXX";
    if (::mkdtemp(dir) == nullptr) {
      std::fprintf(err, "%s: cannot create a temporary folder: %s\n", kName, std::strerror(errno));
      return 1;
    }
    maps.dir = dir;
    maps.temporary = true;
  } else {
    maps.dir = o.report_dir;
  }
  Result<std::string> map = crowd::write_scene_map(*first, maps.dir);
  if (!map) {
    std::fprintf(err, "%s: the scene's map: %s\n", kName, map.error().c_str());
    return 1;
  }
  maps.yaml = *map;
  plan.map_path = *map;

  for (std::uint64_t i = 0; i < o.runs; ++i)
    for (const Variant v : o.variants) plan.jobs.push_back({o.seed + i, v});

  std::string variant_list;
  for (const Variant v : o.variants) variant_list += std::string(variant_list.empty() ? "" : ", ") + name_of(v);
  const std::string scene_text = describe_scene(o, people, first->crowd.behaviour);
  std::fprintf(out, "experiment crowd: %s, %llu run%s per variant (seeds %llu..%llu), variants %s, %ld worker%s, %s\n",
               scene_text.c_str(), static_cast<unsigned long long>(o.runs), o.runs == 1 ? "" : "s",
               static_cast<unsigned long long>(o.seed), static_cast<unsigned long long>(o.seed + o.runs - 1),
               variant_list.c_str(), o.jobs, o.jobs == 1 ? "" : "s", o.realtime ? "real time over ptys" : "lockstep");
  std::fflush(out);

  const auto wall_start = std::chrono::steady_clock::now();
  const std::size_t total = plan.jobs.size();
  const std::size_t every = std::max<std::size_t>(1, std::min<std::size_t>(10, total / 20));
  std::size_t done = 0;
  struct Tally {
    std::size_t runs = 0, successes = 0, collisions = 0, timeouts = 0;
  };
  std::vector<Tally> tallies(o.variants.size());
  const std::string scene_name = o.trajectories.empty() ? o.scene : "recorded";
  pool::Callbacks<CrowdRun> callbacks;
  callbacks.run = [&plan](std::size_t j) { return run_job(plan, j); };
  callbacks.accept = [&](std::size_t, const CrowdRun& r) -> std::string {
    if (!r.ran)
      return "seed " + std::to_string(r.seed) + " (" + name_of(r.variant) + "): the run could not run: " + r.error;
    ++done;
    for (std::size_t v = 0; v < o.variants.size(); ++v)
      if (o.variants[v] == r.variant) {
        Tally& t = tallies[v];
        ++t.runs;
        t.successes += r.metrics.success ? 1 : 0;
        t.collisions += r.metrics.contacts_by_robot > 0 ? 1 : 0;
        t.timeouts += r.metrics.timeout ? 1 : 0;
      }
    if (done % every == 0 || done == total) {
      const double elapsed = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
      std::fprintf(out, "crowd %s: %zu/%zu runs (%.0f s)", scene_name.c_str(), done, total, elapsed);
      for (std::size_t v = 0; v < o.variants.size(); ++v)
        std::fprintf(out, "; %s %zu done, %zu success%s, %zu collision%s, %zu timeout%s so far", name_of(o.variants[v]),
                     tallies[v].runs, tallies[v].successes, tallies[v].successes == 1 ? "" : "es", tallies[v].collisions,
                     tallies[v].collisions == 1 ? "" : "s", tallies[v].timeouts, tallies[v].timeouts == 1 ? "" : "s");
      std::fprintf(out, "\n");
      std::fflush(out);
    }
    return {};
  };
  callbacks.describe = [&plan](std::size_t j) {
    return "seed " + std::to_string(plan.jobs[j].seed) + " (" + name_of(plan.jobs[j].variant) + ")";
  };
  std::vector<CrowdRun> results;
  if (!pool::run_pool(kName, total, static_cast<std::size_t>(o.jobs), callbacks, results, out, err)) return 1;
  const double wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();

  std::vector<VariantResults> by_variant;
  double run_wall_s = 0;
  for (const CrowdRun& r : results) run_wall_s += r.wall_s;
  for (const Variant v : o.variants) {
    std::vector<const CrowdRun*> runs;
    for (const CrowdRun& r : results)
      if (r.variant == v) runs.push_back(&r);
    by_variant.push_back(summarize(v, std::move(runs)));
  }
  char head[96];
  std::snprintf(head, sizeof head, "%s, N = %llu", scene_name.c_str(), static_cast<unsigned long long>(o.runs));
  print_table(out, by_variant, head);
  std::fprintf(out, "%zu runs in %.1f s wall, %.2f s of one core per run\n", results.size(), wall_s,
               results.empty() ? 0.0 : run_wall_s / static_cast<double>(results.size()));

  if (!o.report_dir.empty()) {
    const std::string json = o.report_dir + "/report.json";
    if (!write_report_json(json, o, people, by_variant)) {
      std::fprintf(err, "%s: cannot write %s\n", kName, json.c_str());
      return 1;
    }
    const std::string csv = o.report_dir + "/runs.csv";
    if (!write_runs_csv(csv, results)) {
      std::fprintf(err, "%s: cannot write %s\n", kName, csv.c_str());
      return 1;
    }
    std::vector<experiment::BoxPlotSeries> series;
    for (const VariantResults& v : by_variant) series.push_back({name_of(v.variant), v.success_times});
    char title[160], subtitle[200];
    std::snprintf(title, sizeof title, "time to goal: %s, N = %llu", scene_text.c_str(), static_cast<unsigned long long>(o.runs));
    std::snprintf(subtitle, sizeof subtitle,
                  "box: quartiles (IQR), bar: median, whiskers: furthest run within 1.5 IQR, rings: outliers; seeds %llu..%llu",
                  static_cast<unsigned long long>(o.seed), static_cast<unsigned long long>(o.seed + o.runs - 1));
    const std::string box_png = o.report_dir + "/time_to_goal.png";
    experiment::BoxPlotText words;
    words.axis = "time to goal (s)";
    words.runs = "successful";
    if (!experiment::draw_travel_time_box_plot(title, subtitle, series, words).write_png(box_png)) {
      std::fprintf(err, "%s: cannot write %s\n", kName, box_png.c_str());
      return 1;
    }
    // The sample: the first variant's run that came closest to a person (the first such seed).
    const VariantResults& sampled = by_variant.front();
    const CrowdRun* sample = nullptr;
    for (const CrowdRun* r : sampled.runs)
      if (sample == nullptr || r->metrics.min_distance_m < sample->metrics.min_distance_m) sample = r;
    const std::string sample_png = o.report_dir + "/sample_run.png";
    if (sample != nullptr) {
      std::fprintf(out, "the sample run (seed %llu, %s) again, for its figure\n", static_cast<unsigned long long>(sample->seed),
                   name_of(sample->variant));
      std::fflush(out);
      if (!write_sample_figure(plan, sample->job, sample_png, scene_text, err)) {
        std::fprintf(err, "%s: cannot write %s\n", kName, sample_png.c_str());
        return 1;
      }
    }
    std::fprintf(out, "report: %s (report.json, runs.csv, time_to_goal.png, sample_run.png, the scene's map)\n",
                 o.report_dir.c_str());
  }
  std::fflush(out);
  return 0;
}

}  // namespace sen3bot::sim
