#include "formation_sim.hpp"

#include <algorithm>
#include <cmath>

namespace sen3bot::sim {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr double kStartSeparationM = 0.8;
constexpr double kStartWallMarginM = 0.1;
constexpr double kStartJitterM = 0.15;
constexpr double kStartJitterRad = 0.3;
constexpr double kUnconvergedWindowS = 10.0;  // the error reported when the formation never settles

}  // namespace

formation::Workspace formation_workspace() noexcept { return formation::example(1).config.workspace; }

const std::vector<FormationExample>& formation_examples() {
  // The controller's own table of the thesis' examples (formation/core examples.hpp), named.
  static const std::vector<FormationExample> examples = [] {
    constexpr const char* kNames[] = {"targets", "patrol", "leader"};
    constexpr const char* kDescriptions[] = {
        "Four robots in a row cross the room: each drives its point P to its own target.",
        "Three robots patrol an ellipse (2.5 m x 1.25 m semi-axes), evenly spaced along it.",
        "A leader patrols a 0.8 m circle; two followers keep 1.25 m from it, behind it either side.",
    };
    std::vector<FormationExample> all;
    for (int number = 1; number <= formation::kExampleCount; ++number) {
      const formation::Example core = formation::example(number);
      FormationExample& e = all.emplace_back();
      e.number = number;
      e.name = kNames[number - 1];
      e.description = kDescriptions[number - 1];
      e.config = core.config;
      e.starts.assign(core.starts.begin(), core.starts.begin() + static_cast<std::ptrdiff_t>(core.config.robots));
      if (core.config.task == formation::TaskKind::targets)
        e.targets.assign(core.config.targets.begin(), core.config.targets.begin() + static_cast<std::ptrdiff_t>(core.config.robots));
      e.duration_s = core.duration_s;
    }
    return all;
  }();
  return examples;
}

const FormationExample* formation_example(int number) {
  for (const FormationExample& e : formation_examples())
    if (e.number == number) return &e;
  return nullptr;
}

formation::ControllerConfig formation_controller_config(const FormationExample& example, double v_max_m_s, double w_max_rad_s) {
  formation::ControllerConfig c = example.config;
  c.v_max_m_s = v_max_m_s;
  c.w_max_rad_s = w_max_rad_s;
  return c;
}

std::string formation_serial(std::size_t robot) { return "f" + std::to_string(robot + 1); }

bool formation_starts_admissible(std::span<const formation::Pose> starts) noexcept {
  const formation::Workspace w = formation_workspace();
  const double inset = kFormationRadiusM + kStartWallMarginM;
  for (std::size_t i = 0; i < starts.size(); ++i) {
    const formation::Pose& a = starts[i];
    if (a.x_m < w.x0_m + inset || a.x_m > w.x1_m - inset || a.y_m < w.y0_m + inset || a.y_m > w.y1_m - inset) return false;
    for (std::size_t j = 0; j < i; ++j)
      if (std::hypot(a.x_m - starts[j].x_m, a.y_m - starts[j].y_m) < kStartSeparationM) return false;
  }
  return true;
}

std::vector<formation::Pose> perturbed_starts(const FormationExample& example, std::mt19937_64& rng) {
  std::uniform_real_distribution<double> dxy(-kStartJitterM, kStartJitterM);
  std::uniform_real_distribution<double> dtheta(-kStartJitterRad, kStartJitterRad);
  std::vector<formation::Pose> starts(example.starts.size());
  for (;;) {
    for (std::size_t i = 0; i < starts.size(); ++i) {
      const formation::Pose& s = example.starts[i];
      // Drawn in a fixed order (x, y, theta) so a seed gives the same starts everywhere.
      const double x = s.x_m + dxy(rng);
      const double y = s.y_m + dxy(rng);
      const double theta = s.theta_rad + dtheta(rng);
      starts[i] = formation::Pose{x, y, std::remainder(theta, 2 * kPi)};
    }
    if (formation_starts_admissible(starts)) return starts;
  }
}

FormationRig::FormationRig(const FormationExample& example) : example_(example) {}

FormationRig::~FormationRig() {
  shutdown();
  if (quiet_ != nullptr) std::fclose(quiet_);
}

Result<std::unique_ptr<FormationRig>> FormationRig::create(const FormationExample& example, std::span<const formation::Pose> starts,
                                                           const FormationRunOptions& options) {
  if (starts.size() != example.starts.size())
    return Error::format(Errc::invalid_argument, "example %d: %zu starts for %zu robots", example.number, starts.size(),
                         example.starts.size());
  const std::string config_path = options.config_path.empty() ? SEN3BOT_SOURCE_DIR "/config/sim.yaml" : options.config_path;
  const std::string map_path = options.map_path.empty() ? SEN3BOT_SOURCE_DIR "/config/maps/formation.yaml" : options.map_path;
  Result<SimulatedRobot> base = load_simulated_robot(config_path);
  if (!base) return base.error();

  std::unique_ptr<FormationRig> rig(new FormationRig(example));
  rig->quiet_ = std::fopen("/dev/null", "w");
  rig->robots_.reserve(starts.size());
  for (std::size_t i = 0; i < starts.size(); ++i) {
    const formation::Pose& s = starts[i];
    RobotRun& run = rig->robots_.emplace_back();
    run.serial = formation_serial(i);
    // The simulated robot of config/sim.yaml, in the formation workspace, as a fleet vehicle
    // with no goals of its own: the centre's commands drive it.
    firmware::FirmwareConfig& c = run.config;
    c = base->firmware;
    c.navigation.map_path = map_path;
    c.navigation.waypoints_path.clear();
    c.navigation.safe_curve_path.clear();
    c.navigation.mission.goal_count = 0;
    c.navigation.mcl.initial_pose = s;
    c.tasks.erase("mission");
    c.has_fleet = true;
    c.fleet = firmware::FleetConfig{};
    c.fleet.broker = "sim";
    c.fleet.serial_number = run.serial;
    c.fleet.map_id = "formation";
    c.fleet.visualization_period_s = options.visualization_period_s;
    c.fleet.people_period_s = 0;
    c.tasks["fleet"].arena_bytes = 4 * 1024 * 1024;
    SimulationConfig world = base->world;
    world.map_path = map_path;
    world.start_pose = s;
    // The teammates, in this robot's world: its laser sees them and its safety filter stops
    // for them, as on the floor. Each is a round body where the teammate truly is (moved on
    // in advance()).
    world.movers.clear();
    for (std::size_t k = 0; k < starts.size(); ++k) {
      if (k == i) continue;
      world::MoverScript teammate;
      teammate.size_m = kTeammateDiameterM;
      teammate.timeline = {{starts[k].x_m, starts[k].y_m}};
      teammate.times_s = {0.0};
      world.movers.push_back(std::move(teammate));
    }
    world.seed = options.seed + i;
    auto board = SimBoard::create(world, true);
    if (!board) return Error::format(board.error().code(), "%s: %s", run.serial.c_str(), board.error().c_str());
    run.board = std::move(board.value());
    run.board->set_site_broker(&rig->broker_);
    run.fw = std::make_unique<firmware::Firmware>(run.config, *run.board, rig->quiet_);
    if (Status st = run.fw->init(); !st) return Error::format(st.error().code(), "%s: %s", run.serial.c_str(), st.error().c_str());
  }

  const nav::DwaConfig& limits = base->firmware.navigation.dwa;
  formation::FormationServiceConfig sc;
  sc.interface_name = base->firmware.fleet.interface_name;
  sc.version = base->firmware.fleet.version;
  for (const RobotRun& r : rig->robots_) sc.team.push_back({r.config.fleet.manufacturer, r.serial});
  sc.controller = formation_controller_config(example, limits.max_v_m_s, limits.max_w_rad_s);
  auto subscriptions = formation::FormationService::subscriptions(sc);
  if (!subscriptions) return subscriptions.error();
  hal::PubSubOptions link;
  link.client_id = kFormationCentreId;
  link.subscriptions = std::move(subscriptions.value());
  link.inbound_slots = 256;
  link.max_payload = sc.max_payload;
  auto client = rig->broker_.connect(link);
  if (!client) return client.error();
  auto service = formation::FormationService::create(sc, std::move(client.value()));
  if (!service) return service.error();
  rig->service_ = std::move(service.value());
  rig->p_.resize(starts.size());
  return rig;
}

const nav::Pose2D& FormationRig::truth(std::size_t robot) noexcept { return robots_[robot].board->simulation().truth().pose; }

Status FormationRig::advance() {
  for (RobotRun& r : robots_)
    if (Status s = r.fw->scheduler().run_lockstep(*r.board->lockstep_clock(), kFormationSliceNs); !s)
      return Error::format(s.error().code(), "%s: %s", r.serial.c_str(), s.error().c_str());
  now_ += kFormationSliceNs;
  if (now_ >= next_teammates_ns_) {
    next_teammates_ns_ = now_ + kTeammateStepNs;
    const std::size_t n = robots_.size();
    for (std::size_t j = 0; j < n; ++j)
      for (std::size_t k = 0; k < n; ++k) {
        if (k == j) continue;
        const nav::Pose2D& p = truth(k);
        robots_[j].board->simulation().world().extend_timeline(k < j ? k : k - 1, {p.x_m, p.y_m}, t_s());
      }
  }
  if (centre_stepping_) {
    const formation::StepOutcome outcome = service_->step(now_, hal::SimClock::kEpochUnixNs + now_);
    if (outcome != formation::StepOutcome::idle) last_command_s_ = t_s();
    if (outcome == formation::StepOutcome::commanded) {
      const formation::StepInfo& info = service_->controller().last();
      last_scale_ = info.scale;
      min_scale_ = std::min(min_scale_, info.scale);
      if (info.switched) {
        switches_s_.push_back(t_s());
        switched_since_sample_ = true;
      }
    } else if (outcome == formation::StepOutcome::stopped) {
      last_scale_ = 0;
    }
  }
  record();
  return Status::success();
}

Status FormationRig::run_for(double seconds) {
  const auto slices = static_cast<std::int64_t>(std::llround(seconds * 1e9 / static_cast<double>(kFormationSliceNs)));
  for (std::int64_t i = 0; i < slices; ++i)
    if (Status s = advance(); !s) return s;
  return Status::success();
}

void FormationRig::record() {
  const std::size_t n = robots_.size();
  for (std::size_t i = 0; i < n; ++i)
    for (std::size_t j = 0; j < i; ++j) {
      const nav::Pose2D& a = truth(i);
      const nav::Pose2D& b = truth(j);
      min_distance_m_ = std::min(min_distance_m_, std::hypot(a.x_m - b.x_m, a.y_m - b.y_m));
    }
  if (now_ < next_sample_ns_) return;
  next_sample_ns_ += static_cast<hal::Nanos>(kFormationSampleS * 1e9);
  FormationSample& s = samples_.emplace_back();
  s.t_s = t_s();
  s.truth.reserve(n);
  for (std::size_t i = 0; i < n; ++i) {
    const nav::Pose2D& p = truth(i);
    s.truth.push_back(p);
    p_[i] = formation::point_p(p, kFormationOffsetM);
  }
  s.formation_error_m = service_->controller().formation_error(p_);
  s.scale = last_scale_;
  s.centre_error_m = last_scale_ > 0 ? service_->controller().last().formation_error_m : -1.0;
  s.switched = switched_since_sample_;
  switched_since_sample_ = false;
}

void FormationRig::shutdown() {
  if (shut_down_) return;
  shut_down_ = true;
  for (RobotRun& r : robots_)
    if (r.fw) r.fw->shutdown();
}

FormationMetrics FormationRig::metrics() const {
  FormationMetrics m;
  m.min_robot_distance_m = min_distance_m_;
  for (const RobotRun& r : robots_) {
    m.obstacle_contacts += r.board->simulation().truth().contacts;
    if (r.fw->safety() != nullptr) m.safety_stops += r.fw->safety()->stops();
  }
  const formation::FormationCounters& c = service_->counters();
  m.commands_sent = c.commands_sent;
  m.stale_steps = c.stale_steps;
  m.rejected = c.rejected;
  m.switches_s = switches_s_;
  m.min_scale = min_scale_;
  if (!samples_.empty()) {
    const FormationSample& last = samples_.back();
    m.final_formation_error_m = last.formation_error_m;
    if (example_.config.task == formation::TaskKind::targets) {
      for (std::size_t i = 0; i < last.truth.size() && i < example_.targets.size(); ++i) {
        const nav::Pose2D& p = last.truth[i];
        const formation::Vec2 at = formation::point_p(p, kFormationOffsetM);
        if (std::hypot(at.x_m - example_.targets[i].x_m, at.y_m - example_.targets[i].y_m) <= kFormationTargetToleranceM)
          ++m.targets_reached;
      }
    }
    // Converged from the sample after the last one above the bound.
    std::size_t from = 0;
    for (std::size_t k = 0; k < samples_.size(); ++k)
      if (samples_[k].formation_error_m > kFormationErrorBoundM) from = k + 1;
    if (from < samples_.size()) m.converge_s = samples_[from].t_s;
    std::size_t centre_from = 0;
    for (std::size_t k = 0; k < samples_.size(); ++k)
      if (samples_[k].centre_error_m < 0 || samples_[k].centre_error_m > kFormationErrorBoundM) centre_from = k + 1;
    if (centre_from < samples_.size()) m.centre_converge_s = samples_[centre_from].t_s;
    const double window_from = m.converge_s >= 0 ? m.converge_s : last.t_s - kUnconvergedWindowS;
    m.formation_error_m = 0;
    for (const FormationSample& s : samples_)
      if (s.t_s >= window_from) m.formation_error_m = std::max(m.formation_error_m, s.formation_error_m);
  }
  char line[160];
  if (m.min_robot_distance_m < 2 * kFormationRadiusM) {
    std::snprintf(line, sizeof line, "robots came within %.3f m of each other (bound %.2f m)", m.min_robot_distance_m, 2 * kFormationRadiusM);
    m.failures.emplace_back(line);
  }
  if (m.obstacle_contacts > 0) {
    std::snprintf(line, sizeof line, "%llu contact%s with the walls", static_cast<unsigned long long>(m.obstacle_contacts),
                  m.obstacle_contacts == 1 ? "" : "s");
    m.failures.emplace_back(line);
  }
  if (example_.config.task == formation::TaskKind::targets && m.targets_reached < example_.targets.size()) {
    std::snprintf(line, sizeof line, "%zu of %zu targets reached", m.targets_reached, example_.targets.size());
    m.failures.emplace_back(line);
  }
  if (m.converge_s < 0) {
    std::snprintf(line, sizeof line, "the formation error never stayed within %.2f m (%.3f m over the last %.0f s)", kFormationErrorBoundM,
                  m.formation_error_m, kUnconvergedWindowS);
    m.failures.emplace_back(line);
  }
  m.passed = m.failures.empty();
  return m;
}

}  // namespace sen3bot::sim
