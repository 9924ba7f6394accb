#include "fleet_task.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <new>

#include "cli_util.hpp"
#include "sen3bot/vda5050/extensions.hpp"
#include "task_table.hpp"
#include "wiring.hpp"

namespace sen3bot::firmware {

// Everything the task decodes into and encodes from, made once in the arena.
struct FleetTask::Buffers {
  vda5050::Order order;
  vda5050::InstantActions actions;
  vda5050::State state;
  vda5050::DecodeScratch scratch;
  vda5050::PeopleMessage people;
  vda5050::FormationCommand formation;
  std::array<char, 256> topic{};
  std::array<std::uint8_t, 64 * 1024> payload{};
  std::array<char, kOutBytes> out{};
};

std::size_t FleetTask::arena_bytes_needed() noexcept {
  return sizeof(Buffers) + alignof(Buffers) + sizeof(vda5050::Vehicle) + alignof(vda5050::Vehicle);
}

Status check(const FleetConfig& c) {
  if (c.broker.empty()) return Error(Errc::config, "broker: missing (mqtt://HOST[:PORT], mqtts://HOST[:PORT] or sim)");
  if (c.serial_number.empty()) return Error(Errc::config, "serial_number: missing");
  if (c.state_period_s <= 0 || c.state_period_s > 30)
    return Error(Errc::config, "state_period_s: must be in (0, 30] (VDA 5050 sends a state at least every 30 s)");
  if (c.visualization_period_s < 0) return Error(Errc::config, "visualization_period_s: must be 0 (off) or positive");
  if (c.people_period_s < 0) return Error(Errc::config, "people_period_s: must be 0 (off) or positive");
  if (!(c.formation_max_v_m_s > 0) || !(c.formation_max_w_rad_s > 0))
    return Error(Errc::config, "formation_max_v_m_s and formation_max_w_rad_s: must be positive");
  if (!(c.battery_full_v > c.battery_empty_v)) return Error(Errc::config, "battery_full_v: must be above battery_empty_v");
  if (c.broker.starts_with("mqtts://") && c.ca_file.empty()) return Error(Errc::config, "ca_file: an mqtts:// broker needs the site CA");
  if (c.cert_file.empty() != c.key_file.empty()) return Error(Errc::config, "cert_file and key_file: give both or neither");
  std::array<char, 256> topic{};
  for (const std::string_view name : {"state"}) {
    auto made = vda5050::make_topic(topic, c.interface_name, c.version, c.manufacturer, c.serial_number, name);
    if (!made) return Error::format(Errc::config, "interface_name/manufacturer/serial_number: %s", made.error().c_str());
  }
  return Status::success();
}

FleetTask::FleetTask(const FleetConfig& config, hal::Board& board, const FleetTopics& topics)
    : config_(config), board_(board), topics_(topics) {}

FleetTask::~FleetTask() {
  // The arena (declared before the tasks) releases the memory; the objects end here.
  if (vehicle_ != nullptr) std::destroy_at(vehicle_);
  if (buffers_ != nullptr) std::destroy_at(buffers_);
}

void FleetTask::stamp(vda5050::Header& header, std::uint32_t& counter) {
  header.header_id = counter++;
  header.timestamp = vda5050::iso8601(board_.clock().unix_now_ns());
  (void)header.version.assign(vda5050::to_string(config_.version));
  (void)header.manufacturer.assign(config_.manufacturer);
  (void)header.serial_number.assign(config_.serial_number);
}

Status FleetTask::init(std::pmr::memory_resource& arena) {
  if (Status s = check(config_); !s) return Error::format(Errc::config, "fleet.%s", s.error().c_str());
  std::array<char, 256> buffer{};
  auto topic = [&](std::string_view name) {
    auto made = vda5050::make_topic(buffer, config_.interface_name, config_.version, config_.manufacturer,
                                    config_.serial_number, name);
    return made ? std::string(made.value()) : std::string();
  };
  topic_order_ = topic("order");
  topic_instant_ = topic("instantActions");
  topic_state_ = topic("state");
  topic_connection_ = topic("connection");
  topic_visualization_ = topic("visualization");
  topic_factsheet_ = topic("factsheet");
  topic_people_ = vda5050::people_topic(config_.manufacturer, config_.serial_number);
  topic_formation_ = vda5050::formation_topic(config_.manufacturer, config_.serial_number);

  std::pmr::polymorphic_allocator<std::byte> alloc(&arena);
  buffers_ = alloc.new_object<Buffers>();
  vda5050::VehicleConfig vehicle;
  (void)vehicle.manufacturer.assign(config_.manufacturer);
  (void)vehicle.serial_number.assign(config_.serial_number);
  vehicle.version = config_.version;
  vehicle.default_deviation_xy = config_.deviation_xy_m;
  vehicle_ = alloc.new_object<vda5050::Vehicle>(vehicle);

  hal::PubSubOptions options;
  options.url = config_.broker;
  options.client_id = config_.serial_number;
  options.username = config_.username;
  if (!config_.password_file.empty()) {
    std::string problem;
    if (!read_secret(config_.password_file, options.password, problem))
      return Error::format(Errc::config, "fleet.password_file: '%s': %s", config_.password_file.c_str(), problem.c_str());
  }
  options.ca_file = config_.ca_file;
  options.cert_file = config_.cert_file;
  options.key_file = config_.key_file;
  options.keepalive_s = config_.keepalive_s;
  options.max_payload = buffers_->payload.size();
  options.inbound_slots = 8;
  options.outbound_slots = 16;
  // VDA 5050 section 6.2: QoS 0 for orders and instant actions.
  options.subscriptions = {{topic_order_, 0}, {topic_instant_, 0}};
  // A late velocity is worth no more than a lost one: QoS 0, and the hold time ends it.
  if (topics_.formation != nullptr) options.subscriptions.push_back({topic_formation_, 0});
  vda5050::Connection will;
  stamp(will.header, connection_header_);
  will.state = vda5050::ConnectionState::connection_broken;
  auto will_text = vda5050::encode_connection(will, config_.version, buffers_->out);
  if (!will_text) return Error::format(Errc::config, "fleet: the last will: %s", will_text.error().c_str());
  options.will = hal::PubSubWill{topic_connection_, std::string(will_text.value()), 1, true};
  auto link = board_.open_pubsub("fleet", options);
  if (!link) return link.error();
  link_ = std::move(link.value());
  return Status::success();
}

vda5050::Pose FleetTask::current_pose() const {
  vda5050::Pose pose;
  (void)pose.map_id.assign(config_.map_id);
  tasks::Sample<msg::PoseEstimate> estimate;
  if (topics_.pose.read(estimate) && estimate.value.valid) {
    pose.x = estimate.value.pose.x_m;
    pose.y = estimate.value.pose.y_m;
    pose.theta = estimate.value.pose.theta_rad;
    pose.localized = !estimate.value.lost;
  }
  return pose;
}

void FleetTask::publish(const std::string& topic, std::string_view payload, int qos, bool retain) {
  const Status status = link_->publish(topic, hal::as_bytes(payload), qos, retain);
  if (!status) ++counters_.publish_failures;
}

void FleetTask::publish_connection(vda5050::ConnectionState state) {
  vda5050::Connection message;
  stamp(message.header, connection_header_);
  message.state = state;
  auto text = vda5050::encode_connection(message, config_.version, buffers_->out);
  if (!text) {
    ++counters_.publish_failures;
    return;
  }
  publish(topic_connection_, text.value(), 1, true);
}

void FleetTask::publish_factsheet() {
  vda5050::FactsheetInfo factsheet = vda5050::sen3bot_factsheet();
  stamp(factsheet.header, factsheet_header_);
  auto text = vda5050::encode_factsheet(factsheet, config_.version, buffers_->out);
  if (!text) {
    ++counters_.publish_failures;
    return;
  }
  publish(topic_factsheet_, text.value(), 0, true);
  vehicle_->factsheet_published();
}

void FleetTask::on_session(hal::Nanos now) {
  session_ = link_->session();
  ++counters_.sessions;
  publish_connection(vda5050::ConnectionState::online);
  publish_factsheet();
  publish_state(now);
}

bool FleetTask::check_header(const vda5050::Header& header, std::uint32_t& last_header_id, std::string_view topic_name) {
  if (header.manufacturer.view() != config_.manufacturer || header.serial_number.view() != config_.serial_number) {
    ++counters_.messages_rejected;
    (void)topic_name;
    return false;
  }
  const bool seen = topic_name == "order" ? seen_order_header_ : seen_instant_header_;
  // A headerId at or below the last one is a late duplicate, except 0: a master control that
  // restarted counts from 0 again.
  if (seen && header.header_id <= last_header_id && header.header_id != 0) {
    ++counters_.messages_rejected;
    return false;
  }
  last_header_id = header.header_id;
  (topic_name == "order" ? seen_order_header_ : seen_instant_header_) = true;
  return true;
}

void FleetTask::handle_formation(std::string_view payload, hal::Nanos now) {
  ++counters_.formation_received;
  vda5050::FormationCommand& m = buffers_->formation;
  if (!vda5050::decode_formation(payload, m, buffers_->scratch)) {
    ++counters_.formation_rejected;
    return;
  }
  const bool ours = m.manufacturer.view() == config_.manufacturer && m.serial_number.view() == config_.serial_number;
  // As for orders: at or below the last headerId is late, 0 is a centre that restarted.
  const bool in_order = !seen_formation_header_ || m.header_id > last_formation_header_ || m.header_id == 0;
  // Refused rather than clipped: a clipped velocity is not the formation's.
  const bool within = std::abs(m.v) <= config_.formation_max_v_m_s && std::abs(m.omega) <= config_.formation_max_w_rad_s;
  if (!ours || !in_order || !within) {
    ++counters_.formation_rejected;
    return;
  }
  last_formation_header_ = m.header_id;
  seen_formation_header_ = true;
  topics_.formation->publish(msg::FormationCommand{m.v, m.omega, m.hold_s, now, m.header_id}, now);
}

void FleetTask::handle(std::string_view topic, std::string_view payload, const vda5050::Pose& pose, hal::Nanos now) {
  Buffers& b = *buffers_;
  if (topics_.formation != nullptr && topic == topic_formation_) {
    handle_formation(payload, now);
    return;
  }
  if (topic == topic_order_) {
    ++counters_.orders_received;
    const vda5050::Decoded decoded = vda5050::decode_order(payload, config_.version, b.order, b.scratch);
    if (!decoded) {
      ++counters_.orders_rejected;
      vehicle_->report_rejected_message(decoded.error());
      return;
    }
    if (!check_header(b.order.header, last_order_header_, "order")) {
      ++counters_.orders_rejected;
      return;
    }
    // A refusal adds a warning; a repeated update (same orderId and orderUpdateId) adds none.
    const std::size_t errors_before = vehicle_->errors().size() + vehicle_->dropped_errors();
    if (vehicle_->receive_order(b.order, pose)) {
      ++counters_.orders_accepted;
    } else if (vehicle_->errors().size() + vehicle_->dropped_errors() > errors_before) {
      ++counters_.orders_rejected;
    }
    return;
  }
  if (topic == topic_instant_) {
    ++counters_.instant_actions_received;
    const vda5050::Decoded decoded = vda5050::decode_instant_actions(payload, config_.version, b.actions, b.scratch);
    if (!decoded) {
      ++counters_.messages_rejected;
      vehicle_->report_rejected_message(decoded.error());
      return;
    }
    if (!check_header(b.actions.header, last_instant_header_, "instantActions")) return;
    vehicle_->receive_instant_actions(b.actions);
    return;
  }
  ++counters_.messages_ignored;
}

void FleetTask::take_messages(const vda5050::Pose& pose, hal::Nanos now) {
  Buffers& b = *buffers_;
  for (std::size_t i = 0; i < kMaxMessagesPerStep; ++i) {
    auto message = link_->receive(b.topic, b.payload);
    if (!message || !message.value()) return;
    const hal::PubSubMessage& m = *message.value();
    handle({b.topic.data(), m.topic_size}, {reinterpret_cast<const char*>(b.payload.data()), m.payload_size}, pose, now);
  }
}

void FleetTask::drive() {
  const vda5050::DriveTarget& target = vehicle_->target();
  const hal::Nanos now = board_.clock().now();
  if (target.hold) {
    // Past the last released node (within its deviation) the robot still finishes its approach
    // to the node itself, and stands there; a pause, a cancel or a blocking action stops it now.
    const bool finishing = target.reason == vda5050::HoldReason::decision_point || target.reason == vda5050::HoldReason::no_order;
    if (finishing) return;
    if (!goal_hold_) {
      goal_ = msg::NavGoal{0.0, 0.0, ++counters_.goals_sent, false};
      topics_.goal.publish(goal_, now);
      goal_hold_ = true;
      first_plan_for_goal_ = 0;
    }
    return;
  }
  // A new order restarts sequence ids: a different position is a new goal too.
  if (goal_hold_ || target.sequence_id != goal_sequence_ || target.x != goal_.x_m || target.y != goal_.y_m) {
    goal_ = msg::NavGoal{target.x, target.y, ++counters_.goals_sent, true};
    topics_.goal.publish(goal_, now);
    goal_hold_ = false;
    goal_sequence_ = target.sequence_id;
    first_plan_for_goal_ = 0;
  }
}

std::optional<vda5050::AgvPosition> FleetTask::position() const {
  tasks::Sample<msg::PoseEstimate> estimate;
  if (!topics_.pose.read(estimate)) return std::nullopt;
  vda5050::AgvPosition position;
  position.position_initialized = estimate.value.valid;
  position.x = estimate.value.pose.x_m;
  position.y = estimate.value.pose.y_m;
  position.theta = std::remainder(estimate.value.pose.theta_rad, 2 * 3.14159265358979323846);
  position.deviation_range = std::sqrt(std::max(0.0, estimate.value.cov_xx + estimate.value.cov_yy));
  position.localization_score = estimate.value.lost ? 0.0 : 1.0;
  (void)position.map_id.assign(config_.map_id);
  return position;
}

std::optional<vda5050::Velocity> FleetTask::velocity() const {
  tasks::Sample<msg::Odometry> odometry;
  if (!topics_.odometry.read(odometry) || !odometry.value.valid) return std::nullopt;
  return vda5050::Velocity{odometry.value.v_m_s, 0.0, odometry.value.w_rad_s};
}

void FleetTask::publish_state(hal::Nanos now) {
  vda5050::State& state = buffers_->state;
  state = vda5050::State{};
  vehicle_->fill_state(state);
  stamp(state.header, state_header_);
  state.agv_position = position();
  state.velocity = velocity();
  if (state.velocity) state.driving = std::abs(state.velocity->vx) > 0.02 || std::abs(state.velocity->omega) > 0.02;
  tasks::Sample<msg::BaseFlags> base;
  if (topics_.base.read(base) && base.value.battery_v > 0) {
    const double fraction = (base.value.battery_v - config_.battery_empty_v) / (config_.battery_full_v - config_.battery_empty_v);
    state.battery.battery_charge = std::clamp(fraction, 0.0, 1.0) * 100.0;
    state.battery.battery_voltage = base.value.battery_v;
  }
  const std::uint32_t reasons = safety_.reasons;
  // The chain, a bumper and the reset latch all hold until someone resets at the robot.
  if ((reasons & (msg::kSafetyEstopChain | msg::kSafetyEstop | msg::kSafetyBumper | msg::kSafetyResetNeeded)) != 0)
    state.e_stop = vda5050::EStop::manual;
  state.field_violation = (reasons & (msg::kSafetyObstacle | msg::kSafetyCage | msg::kSafetyMoverApproach)) != 0;
  auto text = vda5050::encode_state(state, config_.version, buffers_->out);
  if (!text) {
    ++counters_.publish_failures;
    return;
  }
  publish(topic_state_, text.value(), 0, false);
  ++counters_.states_published;
  vehicle_->state_published();
  last_state_ns_ = now;
  was_driving_ = state.driving;
}

void FleetTask::publish_visualization() {
  vda5050::Visualization message;
  stamp(message.header, visualization_header_);
  message.agv_position = position();
  message.velocity = velocity();
  auto text = vda5050::encode_visualization(message, config_.version, buffers_->out);
  if (!text) {
    ++counters_.publish_failures;
    return;
  }
  publish(topic_visualization_, text.value(), 0, false);
  ++counters_.visualizations_published;
}

void FleetTask::publish_people() {
  tasks::Sample<msg::People> people;
  if (!topics_.people.read(people)) return;
  vda5050::PeopleMessage& m = buffers_->people;
  m = vda5050::PeopleMessage{};
  m.header_id = people_header_++;
  m.timestamp = vda5050::iso8601(board_.clock().unix_now_ns());
  (void)m.manufacturer.assign(config_.manufacturer);
  (void)m.serial_number.assign(config_.serial_number);
  (void)m.map_id.assign(config_.map_id);
  tasks::Sample<msg::PoseEstimate> estimate;
  if (topics_.pose.read(estimate)) {
    m.robot_valid = estimate.value.valid && !estimate.value.lost;
    m.robot_x = estimate.value.pose.x_m;
    m.robot_y = estimate.value.pose.y_m;
    m.robot_theta = estimate.value.pose.theta_rad;
  }
  const hal::Nanos now = board_.clock().now();
  for (std::size_t i = 0; i < people.value.count && i < msg::People::kMax; ++i) {
    const msg::TrackedPerson& p = people.value.items[i];
    vda5050::PersonReport r;
    r.id = p.id;
    r.x = p.x_m;
    r.y = p.y_m;
    r.vx = p.vx_m_s;
    r.vy = p.vy_m_s;
    r.width = p.width_m;
    r.cage_radius = p.cage_radius_m;
    r.dynamic = p.state == msg::PersonState::dynamic_person;
    r.age_s = now > p.last_seen_ns ? static_cast<double>(now - p.last_seen_ns) * 1e-9 : 0.0;
    r.laser_points = p.points;
    r.hidden = p.hidden;
    r.position_sigma = p.position_sigma_m;
    if (!m.people.push_back(r)) break;
  }
  auto text = vda5050::encode_people(m, buffers_->out);
  if (!text) {
    ++counters_.publish_failures;
    return;
  }
  publish(topic_people_, text.value(), 0, false);
  ++counters_.people_published;
}

void FleetTask::step(const tasks::StepContext& context) {
  const hal::Nanos now = context.start_ns;
  if (link_->session() != session_) on_session(now);
  const vda5050::Pose pose = current_pose();
  take_messages(pose, now);

  tasks::Sample<msg::SafetyOutput> safety;
  if (topics_.safety.read(safety)) safety_ = safety.value;
  vda5050::Progress progress;
  progress.pose = pose;
  tasks::Sample<msg::Odometry> odometry;
  if (topics_.odometry.read(odometry) && odometry.value.valid)
    progress.speed = std::max(std::abs(odometry.value.v_m_s), std::abs(odometry.value.w_rad_s));
  // The controller's verdict counts once it follows a plan made for the current goal.
  tasks::Sample<msg::PathMessage> path;
  if (!goal_hold_ && first_plan_for_goal_ == 0 && topics_.path.read(path) && path.value.goal_id == goal_.id)
    first_plan_for_goal_ = path.value.plan_id;
  tasks::Sample<msg::ControllerStatus> controller;
  if (!goal_hold_ && first_plan_for_goal_ != 0 && topics_.controller.read(controller) &&
      controller.value.plan_id >= first_plan_for_goal_) {
    progress.goal_reached = controller.value.status == msg::DwaStatus::reached;
    progress.goal_failed = controller.value.status == msg::DwaStatus::failed;
    progress.goal_sequence_id = goal_sequence_;
  }
  vehicle_->update(progress);
  drive();

  if (vehicle_->factsheet_requested()) publish_factsheet();
  const bool driving = progress.speed > 0.02;
  if (vehicle_->state_changed() || driving != was_driving_ || last_state_ns_ < 0 ||
      now - last_state_ns_ >= static_cast<hal::Nanos>(config_.state_period_s * 1e9)) {
    publish_state(now);
  }
  if (config_.visualization_period_s > 0 &&
      (last_visualization_ns_ < 0 || now - last_visualization_ns_ >= static_cast<hal::Nanos>(config_.visualization_period_s * 1e9))) {
    publish_visualization();
    last_visualization_ns_ = now;
  }
  if (config_.people_period_s > 0 &&
      (last_people_ns_ < 0 || now - last_people_ns_ >= static_cast<hal::Nanos>(config_.people_period_s * 1e9))) {
    publish_people();
    last_people_ns_ = now;
  }
}

void FleetTask::shutdown() {
  if (!link_) return;
  publish_connection(vda5050::ConnectionState::offline);
  link_->close(1.0);
}

Status make_fleet(Wiring& w) {
  if (!w.config.has_fleet) return w.absent("needs a fleet section");
  if (!w.config.navigation.enabled) return w.absent("needs a navigation section");
  const NavigationSection& n = w.config.navigation;
  const DevicesConfig& devices = w.config.devices;
  // The centre's formation commands are refused beyond what the DWA may ask of the robot (and
  // beyond what the base driver would clip it to).
  FleetConfig fleet = w.config.fleet;
  fleet.formation_max_v_m_s = n.dwa.max_v_m_s;
  fleet.formation_max_w_rad_s = n.dwa.max_w_rad_s;
  if (devices.has_base && devices.base.max_v_m_s > 0 && devices.base.max_omega_rad_s > 0) {
    fleet.formation_max_v_m_s = std::min(fleet.formation_max_v_m_s, devices.base.max_v_m_s);
    fleet.formation_max_w_rad_s = std::min(fleet.formation_max_w_rad_s, devices.base.max_omega_rad_s);
  }
  w.takes("VDA 5050 orders and instant actions, the centre's formation commands (MQTT, " + fleet.broker + ")");
  w.sends("VDA 5050 state, connection, visualization; the people seen (MQTT)");
  tasks::Topic<msg::NavGoal>& goals =
      w.config.cobot.enabled ? w.writes(&Topics::cooperative_goal) : w.writes(&Topics::goal);
  w.make<FleetTask>(fleet, w.board,
                    FleetTopics{w.reads(&Topics::pose), w.reads(&Topics::odometry), w.reads(&Topics::base_flags),
                                w.reads(&Topics::controller_status), w.reads(&Topics::path),
                                w.reads(&Topics::safety_output), w.reads(&Topics::people), goals,
                                w.writes_if(true, &Topics::formation)});
  return Status::success();
}

}  // namespace sen3bot::firmware
