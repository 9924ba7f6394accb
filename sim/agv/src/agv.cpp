#include "sen3bot/sim/agv.hpp"

#include <algorithm>
#include <cmath>

namespace sen3bot::sim {

namespace {
constexpr double kPi = 3.14159265358979323846;
}

struct SimAgv::Buffers {
  vda5050::Order order;
  vda5050::InstantActions actions;
  vda5050::State state;
  vda5050::AdvisoryMessage advisory;
  vda5050::DecodeScratch scratch;
  std::array<char, 256> topic{};
  std::array<std::uint8_t, 64 * 1024> payload{};
  std::array<char, 64 * 1024> out{};
};

std::vector<hal::PubSubSubscription> SimAgv::subscriptions(const SimAgvConfig& c) {
  const std::string prefix = c.interface_name + "/v2/" + c.manufacturer + "/" + c.serial_number + "/";
  return {{prefix + "order", 0}, {prefix + "instantActions", 0}, {vda5050::advisory_topic(c.manufacturer, c.serial_number), 1}};
}

SimAgv::SimAgv(const SimAgvConfig& config, std::unique_ptr<hal::PubSub> link)
    : config_(config), link_(std::move(link)), buffers_(std::make_unique<Buffers>()), x_(config.x), y_(config.y), theta_(config.theta) {
  vda5050::VehicleConfig vehicle;
  (void)vehicle.manufacturer.assign(config.manufacturer);
  (void)vehicle.serial_number.assign(config.serial_number);
  vehicle.version = config.version;
  vehicle.default_deviation_xy = 0.1;
  vehicle_ = std::make_unique<vda5050::Vehicle>(vehicle);
  const std::string prefix = config.interface_name + "/v2/" + config.manufacturer + "/" + config.serial_number + "/";
  topic_order_ = prefix + "order";
  topic_instant_ = prefix + "instantActions";
  topic_state_ = prefix + "state";
  topic_connection_ = prefix + "connection";
  topic_advisory_ = vda5050::advisory_topic(config.manufacturer, config.serial_number);
}

SimAgv::~SimAgv() = default;

void SimAgv::take_messages() {
  Buffers& b = *buffers_;
  for (int i = 0; i < 16; ++i) {
    auto message = link_->receive(b.topic, b.payload);
    if (!message || !message.value()) return;
    const std::string_view topic(b.topic.data(), message.value()->topic_size);
    const std::string_view text(reinterpret_cast<const char*>(b.payload.data()), message.value()->payload_size);
    vda5050::Pose pose;
    pose.x = x_;
    pose.y = y_;
    pose.theta = theta_;
    pose.localized = true;
    (void)pose.map_id.assign(config_.map_id);
    if (topic == topic_order_) {
      const vda5050::Decoded decoded = vda5050::decode_order(text, config_.version, b.order, b.scratch);
      if (decoded) {
        (void)vehicle_->receive_order(b.order, pose);
      } else {
        vehicle_->report_rejected_message(decoded.error());
      }
    } else if (topic == topic_instant_) {
      const vda5050::Decoded decoded = vda5050::decode_instant_actions(text, config_.version, b.actions, b.scratch);
      if (decoded) {
        vehicle_->receive_instant_actions(b.actions);
      } else {
        vehicle_->report_rejected_message(decoded.error());
      }
    } else if (topic == topic_advisory_ && config_.obey_advisory) {
      if (vda5050::decode_advisory(text, b.advisory, b.scratch).ok()) {
        advice_ = b.advisory.advice;
        factor_ = advice_ == Advice::clear ? 1.0 : advice_ == Advice::stop ? 0.0 : std::clamp(b.advisory.speed_factor, 0.0, 1.0);
        ++advisories_;
      }
    }
  }
}

void SimAgv::publish_state(std::int64_t unix_ns) {
  vda5050::State& state = buffers_->state;
  state = vda5050::State{};
  vehicle_->fill_state(state);
  state.header.header_id = state_header_++;
  state.header.timestamp = vda5050::iso8601(unix_ns);
  vda5050::AgvPosition position;
  position.position_initialized = true;
  position.x = x_;
  position.y = y_;
  position.theta = std::remainder(theta_, 2 * kPi);
  (void)position.map_id.assign(config_.map_id);
  state.agv_position = position;
  state.velocity = vda5050::Velocity{speed_, 0, 0};
  state.driving = speed_ > 0.01;
  state.battery.battery_charge = 80;
  state.field_violation = own_stop_;
  auto text = vda5050::encode_state(state, config_.version, buffers_->out);
  if (text) {
    (void)link_->publish(topic_state_, hal::as_bytes(*text), 0, false);
    vehicle_->state_published();
  }
}

void SimAgv::step(hal::Nanos now_ns, std::int64_t unix_ns, double dt_s, std::span<const msg::Point2D> people) {
  if (link_->session() != session_) {
    session_ = link_->session();
    vda5050::Connection online;
    online.header.header_id = connection_header_++;
    online.header.timestamp = vda5050::iso8601(unix_ns);
    online.state = vda5050::ConnectionState::online;
    auto text = vda5050::encode_connection(online, config_.version, buffers_->out);
    if (text) (void)link_->publish(topic_connection_, hal::as_bytes(*text), 1, true);
    last_state_ns_ = -1;
  }
  take_messages();

  // Drive straight at the target node, slowing to stop on it.
  const vda5050::DriveTarget& target = vehicle_->target();
  double wanted = 0;
  double heading = theta_;
  double remaining = 0;
  if (!target.hold) {
    const double dx = target.x - x_, dy = target.y - y_;
    remaining = std::hypot(dx, dy);
    heading = std::atan2(dy, dx);
    const double cruise = config_.speed_m_s * factor_ * (target.max_speed ? std::min(1.0, *target.max_speed / config_.speed_m_s) : 1.0);
    // The decision point is the only place it must stop; elsewhere it drives through nodes.
    const bool last = vehicle_->route().size() <= 1;
    const double braking = last ? std::sqrt(2 * config_.accel_m_s2 * remaining) : cruise;
    wanted = std::min(cruise, braking);
  }
  // Its own scanner: a person within sensor_range_m ahead (in a 60 degree cone) stops it.
  own_stop_ = false;
  for (const msg::Point2D& p : people) {
    const double dx = p.x_m - x_, dy = p.y_m - y_;
    const double range = std::hypot(dx, dy);
    const double bearing = std::remainder(std::atan2(dy, dx) - heading, 2 * kPi);
    if (range < config_.sensor_range_m && std::abs(bearing) < kPi / 6) own_stop_ = true;
  }
  if (own_stop_) wanted = 0;
  const double dv = config_.accel_m_s2 * dt_s;
  speed_ = std::clamp(wanted, speed_ - dv, speed_ + dv);
  speed_ = std::max(0.0, speed_);
  if (!target.hold && remaining > 1e-6) {
    const double step = std::min(speed_ * dt_s, remaining);
    x_ += step * std::cos(heading);
    y_ += step * std::sin(heading);
    theta_ = heading;
  }

  vda5050::Progress progress;
  progress.pose.x = x_;
  progress.pose.y = y_;
  progress.pose.theta = theta_;
  progress.pose.localized = true;
  (void)progress.pose.map_id.assign(config_.map_id);
  progress.speed = speed_;
  vehicle_->update(progress);

  const bool driving = speed_ > 0.01;
  if (vehicle_->state_changed() || driving != was_driving_ || last_state_ns_ < 0 ||
      now_ns - last_state_ns_ >= static_cast<hal::Nanos>(config_.state_period_s * 1e9)) {
    publish_state(unix_ns);
    last_state_ns_ = now_ns;
    was_driving_ = driving;
  }
}

}  // namespace sen3bot::sim
