#include "sen3bot/formation/service.hpp"

#include <algorithm>
#include <cmath>
#include <numbers>

#include "sen3bot/nav/geometry.hpp"
#include "sen3bot/vda5050/codec.hpp"
#include "sen3bot/vda5050/extensions.hpp"

namespace sen3bot::formation {

namespace {

// Where a unicycle at `pose` gets to in dt_s at a constant (v, omega): along its arc.
Pose predict(const Pose& pose, double v, double omega, double dt_s) noexcept {
  Pose p = pose;
  nav::advance_arc(p, v, omega, dt_s);
  return {p.x_m, p.y_m, std::remainder(p.theta_rad, 2.0 * std::numbers::pi)};
}

}  // namespace

struct FormationService::Buffers {
  vda5050::Visualization visualization;
  vda5050::FormationCommand command;
  vda5050::DecodeScratch scratch;
  std::array<char, 256> topic{};
  std::vector<std::uint8_t> payload;
  std::array<char, 1024> out{};
};

Result<std::vector<hal::PubSubSubscription>> FormationService::subscriptions(const FormationServiceConfig& config) {
  std::vector<hal::PubSubSubscription> out;
  std::array<char, 256> topic{};
  for (const TeamMember& m : config.team) {
    auto t = vda5050::make_topic(topic, config.interface_name, config.version, m.manufacturer, m.serial_number, "visualization");
    if (!t) return Error::format(Errc::config, "team: %s/%s: %s", m.manufacturer.c_str(), m.serial_number.c_str(), t.error().c_str());
    out.push_back({std::string(*t), 0});
  }
  return out;
}

Result<std::unique_ptr<FormationService>> FormationService::create(const FormationServiceConfig& config,
                                                                   std::unique_ptr<hal::PubSub> link) {
  if (!link) return Error(Errc::invalid_argument, "formation service: no link");
  if (config.team.empty() || config.team.size() > kMaxRobots)
    return Error::format(Errc::config, "team: 1 to %zu robots, got %zu", kMaxRobots, config.team.size());
  if (config.team.size() != config.controller.robots)
    return Error::format(Errc::config, "team: %zu robots for a controller of %zu", config.team.size(), config.controller.robots);
  if (!(config.period_s >= 0.01 && config.period_s <= 1.0)) return Error(Errc::config, "period_s: 0.01 to 1 s");
  if (!(config.pose_timeout_s > 0 && config.pose_timeout_s <= 10.0)) return Error(Errc::config, "pose_timeout_s: above 0, at most 10 s");
  if (!(config.hold_s > 0 && config.hold_s <= vda5050::kMaxFormationHoldS))
    return Error(Errc::config, "hold_s: above 0, at most 2 s (the formation command's bound)");
  if (!(config.lookahead_s >= 0 && config.lookahead_s <= 1.0)) return Error(Errc::config, "lookahead_s: 0 to 1 s");
  if (config.max_payload < 1024 || config.max_payload > vda5050::kMaxMessageBytes)
    return Error(Errc::config, "max_payload: 1 KiB to 256 KiB");
  auto topics = subscriptions(config);
  if (!topics) return topics.error();
  for (std::size_t i = 0; i < config.team.size(); ++i)
    for (std::size_t j = 0; j < i; ++j)
      if (config.team[i].manufacturer == config.team[j].manufacturer && config.team[i].serial_number == config.team[j].serial_number)
        return Error::format(Errc::config, "team: %s twice", config.team[i].serial_number.c_str());
  auto controller = std::make_unique<Controller>();
  if (Status s = controller->configure(config.controller); !s) return Error::format(Errc::config, "controller: %s", s.error().c_str());
  std::unique_ptr<FormationService> service(new FormationService(config, std::move(link)));
  service->controller_ = std::move(controller);
  for (std::size_t i = 0; i < config.team.size(); ++i) {
    Robot& r = service->robots_.emplace_back();
    r.visualization_topic = topics.value()[i].filter;
    r.command_topic = vda5050::formation_topic(config.team[i].manufacturer, config.team[i].serial_number);
  }
  return service;
}

FormationService::FormationService(const FormationServiceConfig& config, std::unique_ptr<hal::PubSub> link)
    : config_(config), link_(std::move(link)), buffers_(std::make_unique<Buffers>()) {
  buffers_->payload.resize(config.max_payload);
  robots_.reserve(config.team.size());
  period_ns_ = hal::from_seconds(config.period_s);
}

FormationService::~FormationService() = default;

void FormationService::on_visualization(std::size_t robot, std::string_view text) {
  Buffers& b = *buffers_;
  b.visualization = vda5050::Visualization{};
  const auto decoded = vda5050::decode_visualization(text, config_.version, b.visualization, b.scratch);
  std::int64_t stamp = 0;
  const TeamMember& member = config_.team[robot];
  if (!decoded || !vda5050::parse_iso8601(b.visualization.header.timestamp.view(), stamp) ||
      b.visualization.header.manufacturer.view() != member.manufacturer ||
      b.visualization.header.serial_number.view() != member.serial_number) {
    ++counters_.rejected;
    return;
  }
  const vda5050::Visualization& m = b.visualization;
  if (!m.agv_position || !m.agv_position->position_initialized || !std::isfinite(m.agv_position->x) ||
      !std::isfinite(m.agv_position->y) || !std::isfinite(m.agv_position->theta)) {
    ++counters_.unpositioned;
    return;
  }
  Robot& r = robots_[robot];
  if (r.have_pose && stamp < r.stamp_unix_ns) {
    ++counters_.out_of_order;
    return;
  }
  r.have_pose = true;
  r.pose = Pose{m.agv_position->x, m.agv_position->y, m.agv_position->theta};
  r.v = m.velocity && std::isfinite(m.velocity->vx) ? m.velocity->vx : 0.0;
  r.omega = m.velocity && std::isfinite(m.velocity->omega) ? m.velocity->omega : 0.0;
  r.stamp_unix_ns = stamp;
  ++counters_.poses;
}

void FormationService::take_messages() {
  Buffers& b = *buffers_;
  for (;;) {
    auto m = link_->receive(b.topic, b.payload);
    if (!m || !m.value()) return;  // an error leaves the message queued: try again next step
    const std::string_view topic(b.topic.data(), m.value()->topic_size);
    const std::string_view text(reinterpret_cast<const char*>(b.payload.data()), m.value()->payload_size);
    std::size_t robot = robots_.size();
    for (std::size_t i = 0; i < robots_.size(); ++i)
      if (robots_[i].visualization_topic == topic) robot = i;
    if (robot == robots_.size()) {
      ++counters_.unknown;
      continue;
    }
    on_visualization(robot, text);
  }
}

void FormationService::send(std::size_t robot, Unicycle command, std::int64_t unix_ns) {
  Buffers& b = *buffers_;
  Robot& r = robots_[robot];
  vda5050::FormationCommand& c = b.command;
  c = vda5050::FormationCommand{};
  c.header_id = ++r.header_id;
  c.timestamp = vda5050::iso8601(unix_ns);
  (void)c.manufacturer.assign(config_.team[robot].manufacturer);
  (void)c.serial_number.assign(config_.team[robot].serial_number);
  // A command that is not a number is no command: stop.
  const bool finite = std::isfinite(command.v) && std::isfinite(command.w);
  c.v = finite ? command.v : 0.0;
  c.omega = finite ? command.w : 0.0;
  c.hold_s = config_.hold_s;
  commands_[robot] = Unicycle{c.v, c.omega};
  auto text = vda5050::encode_formation(c, b.out);
  if (!text || !link_->publish(r.command_topic, hal::as_bytes(text.value()), 0, false)) {
    ++counters_.publish_failures;
    return;
  }
  ++counters_.commands_sent;
}

StepOutcome FormationService::step(hal::Nanos now, std::int64_t unix_ns) {
  take_messages();
  if (!started_) {
    started_ = true;
    next_ns_ = now;
  }
  if (now < next_ns_) return StepOutcome::idle;
  // A late call does not make up for the periods it missed.
  next_ns_ = now - next_ns_ >= period_ns_ ? now + period_ns_ : next_ns_ + period_ns_;

  const std::size_t n = robots_.size();
  const auto timeout_ns = static_cast<std::int64_t>(config_.pose_timeout_s * 1e9);
  bool whole = true;
  for (std::size_t i = 0; i < n; ++i) {
    const Robot& r = robots_[i];
    const std::int64_t age = unix_ns - r.stamp_unix_ns;
    if (!r.have_pose || age > timeout_ns || age < -timeout_ns) {
      whole = false;
      continue;
    }
    poses_[i] = predict(r.pose, r.v, r.omega, static_cast<double>(std::clamp<std::int64_t>(age, 0, timeout_ns)) * 1e-9);
    // And on to when this step's command will act: until then the robot drives the last one.
    poses_[i] = predict(poses_[i], commands_[i].v, commands_[i].w, config_.lookahead_s);
  }
  if (!whole) {
    running_ = false;
    ++counters_.stale_steps;
    for (std::size_t i = 0; i < n; ++i) send(i, Unicycle{}, unix_ns);
    return StepOutcome::stopped;
  }
  const double t_s = hal::to_seconds(now);
  const std::span<const Pose> poses{poses_.data(), n};
  if (!running_) {
    controller_->reset(poses, t_s);
    running_ = true;
  }
  std::array<Unicycle, kMaxRobots> out{};
  (void)controller_->step(t_s, poses, std::span<Unicycle>{out.data(), n});
  ++counters_.controller_steps;
  for (std::size_t i = 0; i < n; ++i) send(i, out[i], unix_ns);
  return StepOutcome::commanded;
}

void FormationService::stop_team(std::int64_t unix_ns) {
  running_ = false;
  for (std::size_t i = 0; i < robots_.size(); ++i) send(i, Unicycle{}, unix_ns);
}

}  // namespace sen3bot::formation
