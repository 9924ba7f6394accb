#include "sen3bot/sim/simulation.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sen3bot/nav/map.hpp"
#include "sen3bot/nav/scan.hpp"
#include "sen3bot/sim/referee.hpp"

namespace sen3bot::sim {

namespace {

constexpr double kClearanceLimitM = 1.5;  // clearance/person distances are capped here
// The clearance search is the costliest part of a step; 20 Hz is plenty for a report.
constexpr hal::Nanos kClearancePeriodNs = 50'000'000;
constexpr double kNanosPerSecond = 1e9;

}  // namespace

// The scanner's view: the world ray-cast from the sensor pose, with seeded range noise.
class Simulation::WorldRanges final : public lms200::RangeSource {
 public:
  WorldRanges(world::World& world, double max_range_m) : world_(world), max_range_m_(max_range_m) {}
  void ranges(hal::Nanos, const lms200::ScanGeometry& geometry, std::span<float> out_m) override {
    const lms200::SensorPose p = sensor_pose();
    const double max_m = std::min(max_range_m_, geometry.range_max_m > 0 ? geometry.range_max_m : max_range_m_);
    world_.noisy_scan({p.x_m, p.y_m, p.theta_rad}, geometry.angle_min_rad, geometry.angle_increment_rad, geometry.count,
                      max_m, out_m);
    // The world reports max range for "nothing hit"; the scanner reports no echo.
    for (float& r : out_m)
      if (!(r < max_m)) r = std::numeric_limits<float>::infinity();
  }

 private:
  world::World& world_;
  double max_range_m_;
};

// The base's view: a motion into a wall or a mover stalls the wheels; sonar rays see the world.
class Simulation::WorldObstacles final : public p2os::EmulatorWorld {
 public:
  WorldObstacles(world::World& world, const nav::Footprint& footprint) : world_(world), footprint_(footprint) {}
  bool motion_blocked(const p2os::Pose2& from, const p2os::Pose2& to) override {
    // Moving out of an overlap (a person walked into the robot) is allowed.
    return world_.collides(to, footprint_) && !world_.collides(from, footprint_);
  }
  double sonar_range_m(const p2os::Pose2& sensor, double max_range_m) override {
    return world_.cast_ray(sensor.x_m, sensor.y_m, sensor.theta_rad, max_range_m);
  }

 private:
  world::World& world_;
  nav::Footprint footprint_;
};

// The laser driver's real line rate, read from the pty master.
class Simulation::PtyLine final : public lms200::ClientLine {
 public:
  explicit PtyLine(hal::PtyPair& pty) : pty_(pty) {}
  Result<std::uint32_t> client_baud() override { return pty_.slave_baud(); }

 private:
  hal::PtyPair& pty_;
};

Simulation::Simulation(const SimulationConfig& config) : config_(config), base_(config.base) {}
Simulation::~Simulation() = default;

Result<std::unique_ptr<Simulation>> Simulation::create(const SimulationConfig& config) {
  Result<nav::OccupancyMap> map = nav::load_map(config.map_path);
  if (!map) return Error::format(map.error().code(), "simulation: %s", map.error().c_str());
  std::unique_ptr<Simulation> sim(new Simulation(config));
  if (Status s = sim->open(*map); !s) return s.error();
  return sim;
}

Status Simulation::open(const nav::OccupancyMap& map) {
  world::WorldConfig world_config;
  world_config.seed = config_.seed;
  world_config.range_noise_sigma_m = config_.range_noise_sigma_m;
  world_ = std::make_unique<world::World>(map, world_config);
  for (const world::MoverScript& mover : config_.movers) world_->add_mover(mover);
  first_crowd_mover_ = world_->mover_count();
  if (config_.crowd) {
    Result<std::unique_ptr<crowd::Crowd>> made = crowd::Crowd::create(*config_.crowd);
    if (!made) return Error::format(made.error().code(), "simulation: crowd: %s", made.error().c_str());
    crowd_ = std::move(*made);
    for (std::size_t i = 0; i < crowd_->size(); ++i) {
      world::MoverScript person;
      person.person = true;
      person.driven = true;
      person.legs = true;
      person.size_m = 2.0 * crowd_->state(i).radius_m;
      const std::size_t index = world_->add_mover(person);
      const crowd::PersonState at = crowd_->state(i);
      world_->place_mover(index, at.position, at.velocity, at.visible);
    }
  }
  world_->set_time(0.0);
  in_cage_.assign(world_->mover_count(), false);
  if (world_->collides(config_.start_pose, config_.footprint))
    return Error::format(Errc::config, "simulation: the start pose (%.2f, %.2f) m overlaps an obstacle of %s",
                         config_.start_pose.x_m, config_.start_pose.y_m, config_.map_path.c_str());
  if (config_.kidnap_time_s >= 0.0 && world_->collides(config_.kidnap_pose, config_.footprint))
    return Error::format(Errc::config, "simulation: the kidnap pose (%.2f, %.2f) m overlaps an obstacle of %s",
                         config_.kidnap_pose.x_m, config_.kidnap_pose.y_m, config_.map_path.c_str());

  ranges_ = std::make_unique<WorldRanges>(*world_, config_.laser_max_range_m);
  obstacles_ = std::make_unique<WorldObstacles>(*world_, config_.footprint);
  base_.set_world(obstacles_.get());
  base_.set_ground_truth({config_.start_pose.x_m, config_.start_pose.y_m, config_.start_pose.theta_rad});

  if (config_.link == LinkKind::memory) {
    base_pipe_ = std::make_unique<hal::MemoryPipe>(config_.pipe_bytes, "sim:base-driver", "sim:base-robot");
    laser_pipe_ = std::make_unique<hal::MemoryPipe>(config_.pipe_bytes, "sim:laser-driver", "sim:laser-scanner");
    laser_line_ = std::make_unique<lms200::SimulatedLine>(config_.laser.initial_baud);
    laser_ = std::make_unique<lms200::Lms200Emulator>(config_.laser, laser_pipe_->b(), *ranges_, laser_line_.get());
  } else {
    Result<std::unique_ptr<hal::PtyPair>> base_pty = hal::PtyPair::open();
    if (!base_pty) return Error::format(base_pty.error().code(), "simulation: base pty: %s", base_pty.error().c_str());
    Result<std::unique_ptr<hal::PtyPair>> laser_pty = hal::PtyPair::open();
    if (!laser_pty) return Error::format(laser_pty.error().code(), "simulation: laser pty: %s", laser_pty.error().c_str());
    base_pty_ = std::move(*base_pty);
    laser_pty_ = std::move(*laser_pty);
    laser_pty_line_ = std::make_unique<PtyLine>(*laser_pty_);
    laser_ = std::make_unique<lms200::Lms200Emulator>(config_.laser, *laser_pty_, *ranges_, laser_pty_line_.get());
  }
  truth_.pose = config_.start_pose;
  return Status::success();
}

hal::ByteStream* Simulation::base_driver_stream() noexcept { return base_pipe_ ? &base_pipe_->a() : nullptr; }
hal::ByteStream* Simulation::laser_driver_stream() noexcept { return laser_pipe_ ? &laser_pipe_->a() : nullptr; }
lms200::LineControl* Simulation::laser_driver_line() noexcept { return laser_line_.get(); }
std::string Simulation::base_device_path() const { return base_pty_ ? std::string(base_pty_->slave_path()) : std::string(); }
std::string Simulation::laser_device_path() const {
  return laser_pty_ ? std::string(laser_pty_->slave_path()) : std::string();
}

// The crowd sees the robot as the disc that holds its footprint, where the robot truly is.
void Simulation::place_crowd(hal::Nanos now_ns) noexcept {
  const nav::Pose2D truth = base_.ground_truth();
  const double v = base_.velocity_m_s();
  const crowd::RobotDisc robot{{truth.x_m, truth.y_m},
                               {v * std::cos(truth.theta_rad), v * std::sin(truth.theta_rad)},
                               config_.footprint.circumscribed_radius_m()};
  crowd_->advance(static_cast<double>(now_ns) / kNanosPerSecond, &robot);
  for (std::size_t i = 0; i < crowd_->size(); ++i) {
    const crowd::PersonState at = crowd_->state(i);
    world_->place_mover(first_crowd_mover_ + i, at.position, at.velocity, at.visible);
  }
}

// A person pushing the robot along the path: towards the next point, turning on the spot when
// it points far off, at a walking pace.
void Simulation::push(const nav::Pose2D& pose) noexcept {
  constexpr double kReachedM = 0.15;
  while (push_next_ < config_.push_path.size() &&
         std::hypot(config_.push_path[push_next_].x_m - pose.x_m, config_.push_path[push_next_].y_m - pose.y_m) < kReachedM)
    ++push_next_;
  if (push_next_ == config_.push_path.size()) {
    truth_.push_done = true;
    base_.set_push(0.0, 0.0);
    return;
  }
  const nav::Point2D& to = config_.push_path[push_next_];
  const double error = nav::normalize_angle(std::atan2(to.y_m - pose.y_m, to.x_m - pose.x_m) - pose.theta_rad);
  const double w = std::clamp(1.5 * error, -0.8, 0.8);
  const double v = std::abs(error) > 0.5 ? 0.0 : config_.push_speed_m_s * std::cos(error);
  base_.set_push(v, w);
}

void Simulation::step(hal::Nanos now_ns) noexcept {
  world_->set_time(static_cast<double>(now_ns) / kNanosPerSecond);
  hal::ByteStream& base_stream = base_pipe_ ? static_cast<hal::ByteStream&>(base_pipe_->b()) : *base_pty_;
  if (config_.kidnap_time_s >= 0.0 && truth_.kidnapped_ns < 0 &&
      static_cast<double>(now_ns) >= config_.kidnap_time_s * kNanosPerSecond) {
    const nav::Pose2D& to = config_.kidnap_pose;
    base_.set_ground_truth({to.x_m, to.y_m, to.theta_rad});  // the controller's odometry stays
    truth_.kidnapped_ns = now_ns;
  }
  // Pushing starts once the robot is running (its controller talking to the firmware, whose
  // odometry counts from then) and the person has waited push_start_s.
  if (!config_.push_path.empty() && base_.state() == p2os::EmulatorState::open &&
      static_cast<double>(now_ns) >= config_.push_start_s * kNanosPerSecond)
    push(base_.ground_truth());
  // A failed step means the driver's end went away; the robot keeps its state, as hardware does.
  (void)base_.step(base_stream, now_ns);
  if (crowd_) place_crowd(now_ns);

  const nav::Pose2D pose = base_.ground_truth();
  const nav::Pose2D& m = config_.laser_mount;
  const nav::Pose2D sensor = nav::compose(pose, nav::SensorMount{m.x_m, m.y_m, m.theta_rad});
  ranges_->set_sensor_pose(sensor.x_m, sensor.y_m, sensor.theta_rad);
  laser_->step(now_ns);

  truth_.stamp_ns = now_ns;
  truth_.pose = pose;
  truth_.speed_m_s = base_.velocity_m_s();
  if (now_ns >= next_clearance_ns_) {
    truth_.clearance_m = world_->clearance_m(pose, config_.footprint, kClearanceLimitM);
    next_clearance_ns_ = now_ns + kClearancePeriodNs;
  }
  double nearest = kClearanceLimitM;
  truth_.people_count = 0;
  for (std::size_t i = 0; i < world_->mover_count(); ++i) {
    if (!world_->mover_visible(i) || !world_->mover_script(i).person) continue;
    const nav::Point2D p = world_->mover_position(i);
    nearest = std::min(nearest, std::hypot(p.x_m - pose.x_m, p.y_m - pose.y_m));
    if (truth_.people_count < GroundTruth::kMaxPeople) {
      truth_.people_movers[truth_.people_count] = static_cast<std::uint32_t>(i);
      truth_.people[truth_.people_count++] = p;
    }
  }
  truth_.nearest_person_m = nearest;
  const bool contact = world_->collides(pose, config_.footprint);
  if (contact && !truth_.in_contact) {
    ++truth_.contacts;
    const int mover = world_->touching_mover(pose, config_.footprint);
    truth_.contact_person = mover >= 0 && world_->mover_script(static_cast<std::size_t>(mover)).person;
    // A person walking into a robot that has stopped, or that moves away from them, is not
    // the robot's doing.
    if (world_->robot_closing(pose, config_.footprint, truth_.speed_m_s, kRobotMovingSpeedM_s)) ++truth_.moving_contacts;
  }
  truth_.in_contact = contact;
  if (now_ns >= next_cage_judge_ns_) {
    next_cage_judge_ns_ = now_ns + static_cast<hal::Nanos>(GroundTruth::kCageJudgeS * kNanosPerSecond);
    judge_cages(pose);
  }
}

void Simulation::judge_cages(const nav::Pose2D& pose) noexcept {
  const nav::Pose2D& before = cage_judged_ ? cage_judged_pose_ : pose;
  for (std::size_t i = 0; i < world_->mover_count() && i < in_cage_.size(); ++i) {
    const world::MoverScript& mover = world_->mover_script(i);
    if (!mover.person || !world_->mover_visible(i)) {
      in_cage_[i] = false;
      continue;
    }
    const nav::Point2D at = world_->mover_position(i);
    const double d = std::hypot(at.x_m - pose.x_m, at.y_m - pose.y_m);
    const bool in = d < judged_cage_reach_m(mover.size_m / 2);
    if (in && !in_cage_[i]) {
      const bool robot_closed = std::hypot(at.x_m - before.x_m, at.y_m - before.y_m) - d > 0.01;
      ++(robot_closed ? truth_.cage_entries : truth_.cage_entries_by_person);
    }
    in_cage_[i] = in;
  }
  cage_judged_ = true;
  cage_judged_pose_ = pose;
}

}  // namespace sen3bot::sim
