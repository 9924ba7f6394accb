// One run of `sen3bot-sim experiment crowd` (crowd_experiment.hpp): a whole firmware in
// lockstep from the plan's configuration on the run's scene, its crowd metrics from the ground
// truth sampled every 50 ms; and the sample run's figure.
#include <algorithm>
#include <chrono>
#include <cmath>
#include <cstring>
#include <limits>
#include <memory>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "crowd_experiment.hpp"
#include "firmware.hpp"
#include "sen3bot/msg/geometry.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/nav_figure/case_figure.hpp"
#include "sen3bot/sim/sim_board.hpp"
#include "simulated_mission.hpp"

namespace sen3bot::sim::crowd_experiment {

using firmware::Firmware;
using firmware::FirmwareConfig;
using firmware::MissionState;
using firmware::MissionTask;

namespace {

// The meter's sample period: the lockstep slice.
constexpr double kSliceS = 0.05;
// The run goes on this long past the start delay and the scene's limit (localization settling).
constexpr double kRunMarginS = 10.0;


void set_error(CrowdRun& r, std::string_view what) {
  const std::size_t n = std::min(what.size(), sizeof r.error - 1);
  std::memcpy(r.error, what.data(), n);
  r.error[n] = '\0';
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

// Feeds the run's meter from the ground truth once the robot has set off (its mission's first
// goal taken): the people's truth, the robot's motion and contacts, and whether the robot's
// own motion took it into a person's cage; and the trace when one is kept.
class RunObserver {
 public:
  RunObserver(const FirmwareConfig& config, const SimulationConfig& world, const crowd::Scene& scene, Trace* trace)
      : footprint_(world.footprint), trace_(trace) {
    const double free_length_m =
        std::hypot(scene.robot_goal.x_m - scene.robot_start.x_m, scene.robot_goal.y_m - scene.robot_start.y_m);
    const double max_v = config.navigation.dwa.max_v_m_s;
    setup_.dt_s = kSliceS;
    setup_.time_limit_s = scene.time_limit_s;
    setup_.free_path_length_m = free_length_m;
    setup_.free_path_time_s = max_v > 0 ? free_length_m / max_v : 0.0;
  }

  void slice(const Firmware& fw, SimBoard& board, double sim_s) {
    const MissionTask& mission = *fw.mission();
    Simulation& sim = board.simulation();
    const world::World& w = sim.world();
    if (!sized_) size(sim);
    const GroundTruth& truth = sim.truth();
    if (!started_driving_) {
      if (mission.current_goal() == nullptr && !mission.finished()) {
        remember(truth);
        return;
      }
      started_driving_ = true;
      start_s_ = sim_s;
      if (trace_ != nullptr) trace_->start_s = sim_s;
      setup_.start_time_s = start_s_;
      meter_.start(setup_);
    }
    const msg::Pose2D pose = truth.pose;
    for (std::size_t i = 0; i < count_; ++i) {
      const std::size_t m = first_ + i;
      crowd::PersonTruth& p = people_[i];
      p.position = w.mover_position(m);
      p.velocity = w.mover_velocity(m);
      p.radius_m = w.mover_script(m).size_m / 2;
      p.visible = w.mover_visible(m);
    }
    crowd::RunStep step;
    step.time_s = sim_s;
    step.robot = pose;
    step.v_m_s = truth.speed_m_s;
    step.w_rad_s = msg::normalize_angle(pose.theta_rad - last_theta_) / kSliceS;
    step.footprint = footprint_;
    step.people = std::span<const crowd::PersonTruth>(people_.data(), people_.size());
    step.contact_started = truth.contacts > last_contacts_;
    step.contact_by_robot = truth.moving_contacts > last_moving_;
    step.robot_in_cage = robot_in_cage(pose);
    meter_.observe(step);
    if (trace_ != nullptr) record(*trace_, step, sim_s - start_s_);
    remember(truth);
  }

  void finish(const Firmware& fw, double sim_s, CrowdRun& r) {
    const firmware::MissionReport& report = fw.mission()->report();
    const bool reached = report.state == MissionState::complete;
    if (!started_driving_) {
      setup_.start_time_s = sim_s;
      meter_.start(setup_);
    }
    const double end_s = reached && report.goals_reached > 0 ? start_s_ + report.goal_time_s[0] : sim_s;
    r.metrics = meter_.finish(reached, end_s);
    r.ran = true;
    r.sim_s = sim_s;
  }

 private:
  // The crowd's movers, known once the board has them (the first slice).
  void size(Simulation& sim) {
    const world::World& w = sim.world();
    first_ = sim.first_crowd_mover();
    count_ = w.mover_count() > first_ ? w.mover_count() - first_ : 0;
    people_.resize(count_);
    inside_.assign(count_, false);
    robot_inside_.assign(count_, false);
    if (trace_ != nullptr) {
      trace_->people.resize(count_);
      for (figure::MoverTrack& m : trace_->people) {
        m.person = true;
        m.size_m = 0;
      }
    }
    sized_ = true;
  }

  // Cage entries: the robot's when its own motion since the last sample closed the distance.
  bool robot_in_cage(const msg::Pose2D& pose) {
    bool in_cage = false;
    for (std::size_t i = 0; i < count_; ++i) {
      const crowd::PersonTruth& p = people_[i];
      const double d = std::hypot(p.position.x_m - pose.x_m, p.position.y_m - pose.y_m);
      const bool in = p.visible && d < judged_cage_reach_m(p.radius_m);
      if (in && !inside_[i]) {
        const double before = std::hypot(p.position.x_m - last_pose_.x_m, p.position.y_m - last_pose_.y_m);
        robot_inside_[i] = before - d > 0.01;
      }
      if (!in) robot_inside_[i] = false;
      inside_[i] = in;
      in_cage = in_cage || robot_inside_[i];
    }
    return in_cage;
  }

  void remember(const GroundTruth& truth) {
    last_contacts_ = truth.contacts;
    last_moving_ = truth.moving_contacts;
    last_theta_ = truth.pose.theta_rad;
    last_pose_ = truth.pose;
  }

  crowd::RunMeter meter_;
  crowd::RunSetup setup_;
  nav::Footprint footprint_;
  Trace* trace_;
  std::size_t first_ = 0, count_ = 0;
  bool sized_ = false;
  std::vector<crowd::PersonTruth> people_;
  std::vector<bool> inside_;        // in a person's cage
  std::vector<bool> robot_inside_;  // and it was the robot's motion that entered it
  bool started_driving_ = false;
  double start_s_ = 0;
  double last_theta_ = 0;
  msg::Pose2D last_pose_;
  std::uint64_t last_contacts_ = 0, last_moving_ = 0;
};

// A whole firmware on the scene until the mission ends or the run's limit, in 50 ms slices, a
// RunStep to the meter after each once the robot has set off; quiet.
void run_mission(const FirmwareConfig& config, const SimulationConfig& world, const crowd::Scene& scene, bool realtime,
                 CrowdRun& r, Trace* trace) {
  const auto wall_start = std::chrono::steady_clock::now();
  RunObserver observer(config, world, scene, trace);
  auto on_slice = [&](const Firmware& fw, SimBoard& board, double sim_s) { observer.slice(fw, board, sim_s); };
  auto on_end = [&](Firmware& fw, SimBoard&, double sim_s) {
    observer.finish(fw, sim_s, r);
    r.wall_s = std::chrono::duration<double>(std::chrono::steady_clock::now() - wall_start).count();
  };
  if (const std::string error =
          run_simulated_mission(config, world,
                                {.slice = hal::millis(50), .true_people = r.variant == Variant::perfect_perception, .realtime = realtime},
                                on_slice, on_end);
      !error.empty())
    set_error(r, error);
}

CrowdRun run_traced(const Plan& plan, std::size_t index, Trace* trace) {
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

// The closest approach: the sample at its time, the person nearest the robot then.
void mark_closest(figure::CaseFigure& f, const Trace& trace, const crowd::RunMetrics& m) {
  if (!std::isfinite(m.min_distance_m) || m.min_distance_time_s < 0 || trace.times_s.empty()) return;
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

}  // namespace

Result<crowd::Scene> make_run_scene(const Plan& plan, std::uint64_t seed) {
  if (plan.recording) return crowd::recording_scene(plan.recording, seed);
  crowd::SceneOptions options;
  options.name = plan.options.scene;
  options.people = plan.options.people > 0 ? static_cast<std::size_t>(plan.options.people) : crowd::default_people(options.name);
  options.behaviour = plan.options.behaviour;
  return crowd::make_scene(options, seed);
}

CrowdRun run_job(const Plan& plan, std::size_t index) { return run_traced(plan, index, nullptr); }

bool write_sample_figure(const Plan& plan, std::size_t job_index, const std::string& path, const std::string& scene_text,
                         std::FILE* err) {
  Trace trace;
  const CrowdRun r = run_traced(plan, job_index, &trace);
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
  mark_closest(f, trace, m);
  return figure::draw_case_figure(f).write_png(path);
}

}  // namespace sen3bot::sim::crowd_experiment
