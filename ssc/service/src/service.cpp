#include "sen3bot/ssc/service.hpp"

#include <algorithm>
#include <charconv>
#include <cmath>

#include "sen3bot/json/json.hpp"

namespace sen3bot::ssc {

namespace {

constexpr std::size_t kMaxLatencies = 100'000;

// "uagv/v2/MANUFACTURER/SERIAL/TOPIC" -> its three last levels.
bool split_vehicle_topic(std::string_view topic, std::string_view& manufacturer, std::string_view& serial,
                         std::string_view& leaf) {
  std::string_view parts[5];
  std::size_t n = 0;
  std::size_t start = 0;
  while (n < 5) {
    const std::size_t slash = topic.find('/', start);
    parts[n++] = topic.substr(start, slash == std::string_view::npos ? std::string_view::npos : slash - start);
    if (slash == std::string_view::npos) break;
    start = slash + 1;
  }
  if (n != 5 || topic.find('/', start) != std::string_view::npos) return false;
  manufacturer = parts[2];
  serial = parts[3];
  leaf = parts[4];
  return true;
}

// Order ids the centre writes: "ssc-SERIAL-TASK-N".
TaskId task_of_order(std::string_view order_id, std::string_view serial) {
  const std::string_view prefix = "ssc-";
  if (!order_id.starts_with(prefix)) return 0;
  order_id.remove_prefix(prefix.size());
  if (!order_id.starts_with(serial) || order_id.size() <= serial.size() || order_id[serial.size()] != '-') return 0;
  order_id.remove_prefix(serial.size() + 1);
  TaskId task = 0;
  const auto [end, error] = std::from_chars(order_id.data(), order_id.data() + order_id.size(), task);
  return error == std::errc() && end != order_id.data() ? task : 0;
}

vda5050::AdviceKind to_wire(Advice advice) {
  switch (advice) {
    case Advice::clear: return vda5050::AdviceKind::clear;
    case Advice::slow: return vda5050::AdviceKind::slow;
    case Advice::stop: return vda5050::AdviceKind::stop;
  }
  return vda5050::AdviceKind::clear;
}

}  // namespace

struct Service::Buffers {
  vda5050::State state;
  vda5050::Connection connection;
  vda5050::PeopleMessage people;
  vda5050::Order order;
  vda5050::InstantActions actions;
  vda5050::DecodeScratch scratch;
  std::array<char, 256> topic{};
  std::array<std::uint8_t, 64 * 1024> payload{};
  std::array<char, 64 * 1024> out{};
  PeopleReport report;
  AgvReport agv;
};

std::vector<hal::PubSubSubscription> Service::subscriptions(const ServiceConfig& config) {
  return {{config.interface_name + "/v2/+/+/state", 0},
          {config.interface_name + "/v2/+/+/connection", 1},
          {"sen3bot/v1/people/+/+", 1}};  // a robot that publishes people at QoS 1 gets them delivered so
}

Result<std::unique_ptr<Service>> Service::create(const SiteFile& site, std::unique_ptr<hal::PubSub> link, std::FILE* event_log) {
  if (!link) return Error(Errc::invalid_argument, "ssc: no link");
  auto centre = Centre::create(site.site, site.centre);
  if (!centre) return centre.error();
  std::unique_ptr<Service> service(new Service(site, std::move(link), event_log));
  service->centre_ = std::move(centre.value());
  return service;
}

Service::Service(const SiteFile& site, std::unique_ptr<hal::PubSub> link, std::FILE* event_log)
    : site_(site),
      link_(std::move(link)),
      event_log_(event_log),
      buffers_(std::make_unique<Buffers>()),
      order_headers_(site.robot_serials.size(), 0),
      instant_headers_(site.robot_serials.size(), 0),
      order_counts_(site.robot_serials.size(), 0),
      robot_people_stamp_(site.robot_serials.size(), 0),
      robot_poses_(site.robot_serials.size()) {
  agvs_.reserve(kMaxAgvs);
}

Service::~Service() = default;

RobotId Service::robot_id(std::string_view serial) const noexcept {
  for (std::size_t i = 0; i < site_.robot_serials.size(); ++i)
    if (site_.robot_serials[i] == serial) return static_cast<RobotId>(i);
  return kNone;
}

Service::AgvEntry* Service::agv_entry(std::string_view manufacturer, std::string_view serial, bool create) {
  for (AgvEntry& a : agvs_)
    if (a.manufacturer == manufacturer && a.serial == serial) return &a;
  if (!create) return nullptr;
  if (agvs_.size() >= kMaxAgvs) {
    ++counters_.unknown_agvs;
    return nullptr;
  }
  AgvEntry& a = agvs_.emplace_back();
  a.manufacturer.assign(manufacturer);
  a.serial.assign(serial);
  a.id = static_cast<AgvId>(agvs_.size() - 1);
  return &a;
}

void Service::publish(const std::string& topic, std::string_view payload, int qos, bool retain) {
  (void)link_->publish(topic, hal::as_bytes(payload), qos, retain);
}

void Service::on_state(std::string_view manufacturer, std::string_view serial, std::string_view text, hal::Nanos now) {
  Buffers& b = *buffers_;
  const vda5050::Decoded decoded = vda5050::decode_state(text, site_.service.version, b.state, b.scratch);
  if (!decoded) {
    ++counters_.rejected;
    return;
  }
  ++counters_.states;
  const vda5050::State& s = b.state;
  if (manufacturer == site_.service.robot_manufacturer) {
    const RobotId id = robot_id(serial);
    if (id == kNone || !s.agv_position) return;  // not one of this site's robots, or not localized yet
    RobotReport report;
    report.robot = id;
    report.stamp = now;
    report.pose = Pose{s.agv_position->x, s.agv_position->y, s.agv_position->theta};
    robot_poses_[id] = report.pose;
    report.battery = s.battery.battery_charge;
    report.charging = s.battery.charging;
    report.driving = s.driving;
    report.order_task = task_of_order(s.order_id.view(), serial);
    report.order_finished = report.order_task != 0 && s.node_states.empty() && s.last_node_id == "goal";
    (void)centre_->update_robot(report);
    return;
  }
  AgvEntry* agv = agv_entry(manufacturer, serial, true);
  if (agv == nullptr || !s.agv_position) return;
  AgvReport& report = b.agv;
  report = AgvReport{};
  report.agv = agv->id;
  report.name.assign(serial);
  report.pose = Pose{s.agv_position->x, s.agv_position->y, s.agv_position->theta};
  // The AGV's assigned route: the nodes of its order still ahead (their positions are optional
  // in VDA 5050; an AGV must send them for the centre to see where it goes).
  for (const vda5050::NodeState& node : s.node_states) {
    if (!node.position) continue;
    if (!report.route.push_back(Point{node.position->x, node.position->y})) break;
  }
  (void)centre_->update_agv(report);
}

void Service::on_connection(std::string_view manufacturer, std::string_view serial, std::string_view text, hal::Nanos now) {
  Buffers& b = *buffers_;
  if (!vda5050::decode_connection(text, site_.service.version, b.connection, b.scratch)) {
    ++counters_.rejected;
    return;
  }
  const bool online = b.connection.state == vda5050::ConnectionState::online;
  if (manufacturer == site_.service.robot_manufacturer) {
    const RobotId id = robot_id(serial);
    if (id != kNone) (void)centre_->set_online(id, online, now);
    return;
  }
  if (!online) {
    if (AgvEntry* agv = agv_entry(manufacturer, serial, false)) centre_->remove_agv(agv->id);
  }
}

void Service::on_people(std::string_view text, hal::Nanos now) {
  Buffers& b = *buffers_;
  if (!vda5050::decode_people(text, b.people, b.scratch)) {
    ++counters_.rejected;
    return;
  }
  ++counters_.people_reports;
  const RobotId id = robot_id(b.people.serial_number.view());
  if (id == kNone || !b.people.robot_valid) return;  // unlocalized: its positions mean nothing
  PeopleReport& report = b.report;
  report = PeopleReport{};
  report.robot = id;
  report.stamp = now;
  for (const vda5050::PersonReport& p : b.people.people) {
    if (!report.people.push_back(PersonObservation{p.x, p.y, p.vx, p.vy, p.id})) break;
  }
  centre_->add_people(report);
  // When the robot saw them, on the robots' clock (VDA 5050 timestamps are UTC).
  std::int64_t seen = 0;
  if (!b.people.people.empty() && vda5050::parse_iso8601(b.people.timestamp.view(), seen)) {
    robot_people_stamp_[id] = seen;
    newest_people_unix_ns_ = std::max(newest_people_unix_ns_, seen);
  }
}

void Service::take_messages(hal::Nanos now) {
  Buffers& b = *buffers_;
  for (;;) {
    auto message = link_->receive(b.topic, b.payload);
    if (!message || !message.value()) return;
    const std::string_view topic(b.topic.data(), message.value()->topic_size);
    const std::string_view text(reinterpret_cast<const char*>(b.payload.data()), message.value()->payload_size);
    if (topic.starts_with("sen3bot/v1/people/")) {
      on_people(text, now);
      continue;
    }
    std::string_view manufacturer, serial, leaf;
    if (!split_vehicle_topic(topic, manufacturer, serial, leaf)) continue;
    if (leaf == "state") {
      on_state(manufacturer, serial, text, now);
    } else if (leaf == "connection") {
      on_connection(manufacturer, serial, text, now);
    }
  }
}

void Service::send_order(RobotId robot, const Task& task, std::int64_t unix_ns) {
  const std::string& serial = site_.robot_serials[robot];
  vda5050::Order& order = buffers_->order;
  order = vda5050::Order{};
  order.header.header_id = order_headers_[robot]++;
  order.header.timestamp = vda5050::iso8601(unix_ns);
  (void)order.header.version.assign(vda5050::to_string(site_.service.version));
  (void)order.header.manufacturer.assign(site_.service.robot_manufacturer);
  (void)order.header.serial_number.assign(serial);
  const std::string id = "ssc-" + serial + "-" + std::to_string(task.id) + "-" + std::to_string(++order_counts_[robot]);
  (void)order.order_id.assign(id);
  // The first node is where the robot stands (a wide deviation makes it trivially reachable,
  // VDA 5050 section 6.6.3.1); the second is the task's goal.
  const Pose from = robot_poses_[robot];
  vda5050::Node start;
  (void)start.node_id.assign("start");
  start.sequence_id = 0;
  start.released = true;
  start.position = vda5050::NodePosition{from.x_m, from.y_m, std::nullopt, 2.0, 0.0, {}};
  (void)start.position->map_id.assign(site_.service.map_id);
  vda5050::Node goal;
  (void)goal.node_id.assign("goal");
  goal.sequence_id = 2;
  goal.released = true;
  goal.position = vda5050::NodePosition{task.goal.x_m, task.goal.y_m, std::nullopt, 0.3, 0.0, {}};
  (void)goal.position->map_id.assign(site_.service.map_id);
  vda5050::Edge edge;
  (void)edge.edge_id.assign("to-goal");
  edge.sequence_id = 1;
  edge.released = true;
  (void)edge.start_node_id.assign("start");
  (void)edge.end_node_id.assign("goal");
  (void)order.nodes.push_back(start);
  (void)order.nodes.push_back(goal);
  (void)order.edges.push_back(edge);
  auto text = vda5050::encode_order(order, site_.service.version, buffers_->out);
  if (!text) return;
  publish(site_.service.interface_name + "/v2/" + site_.service.robot_manufacturer + "/" + serial + "/order", *text, 0, false);
  ++counters_.orders_sent;
}

void Service::send_cancel(RobotId robot, std::int64_t unix_ns) {
  const std::string& serial = site_.robot_serials[robot];
  vda5050::InstantActions& actions = buffers_->actions;
  actions = vda5050::InstantActions{};
  actions.header.header_id = instant_headers_[robot]++;
  actions.header.timestamp = vda5050::iso8601(unix_ns);
  (void)actions.header.version.assign(vda5050::to_string(site_.service.version));
  (void)actions.header.manufacturer.assign(site_.service.robot_manufacturer);
  (void)actions.header.serial_number.assign(serial);
  vda5050::Action cancel;
  (void)cancel.action_type.assign("cancelOrder");
  (void)cancel.action_id.assign("ssc-cancel-" + serial + "-" + std::to_string(instant_headers_[robot]));
  cancel.blocking_type = vda5050::BlockingType::hard;
  (void)actions.actions.push_back(cancel);
  auto text = vda5050::encode_instant_actions(actions, site_.service.version, buffers_->out);
  if (!text) return;
  publish(site_.service.interface_name + "/v2/" + site_.service.robot_manufacturer + "/" + serial + "/instantActions", *text, 0, false);
  ++counters_.cancels_sent;
}

void Service::send_pause(AgvEntry& agv, bool pause, std::int64_t unix_ns) {
  vda5050::InstantActions& actions = buffers_->actions;
  actions = vda5050::InstantActions{};
  actions.header.header_id = agv.instant_header++;
  actions.header.timestamp = vda5050::iso8601(unix_ns);
  (void)actions.header.version.assign(vda5050::to_string(site_.service.version));
  (void)actions.header.manufacturer.assign(agv.manufacturer);
  (void)actions.header.serial_number.assign(agv.serial);
  vda5050::Action action;
  (void)action.action_type.assign(pause ? "startPause" : "stopPause");
  (void)action.action_id.assign("ssc-" + std::string(pause ? "pause-" : "resume-") + agv.serial + "-" + std::to_string(agv.instant_header));
  action.blocking_type = vda5050::BlockingType::hard;
  (void)actions.actions.push_back(action);
  auto text = vda5050::encode_instant_actions(actions, site_.service.version, buffers_->out);
  if (!text) return;
  publish(site_.service.interface_name + "/v2/" + agv.manufacturer + "/" + agv.serial + "/instantActions", *text, 0, false);
  agv.paused_by_us = pause;
  ++counters_.pauses_sent;
}

void Service::send_advisory(AgvEntry& agv, const Advisory& advisory, std::int64_t unix_ns, hal::Nanos now) {
  vda5050::AdvisoryMessage m;
  m.header_id = advisory_header_++;
  m.timestamp = vda5050::iso8601(unix_ns);
  (void)m.agv_manufacturer.assign(agv.manufacturer);
  (void)m.agv_serial_number.assign(agv.serial);
  m.advice = to_wire(advisory.advice);
  m.speed_factor = advisory.speed_factor;
  if (advisory.area != kNone && advisory.area < site_.area_names.size()) {
    (void)m.area_id.assign(site_.area_names[advisory.area]);
    if (const Area* area = centre_->site().area(advisory.area)) (void)m.area_type.assign(to_string(area->type));
  }
  m.people = advisory.people;
  m.dynamic_people = advisory.dynamic;
  m.distance_to_area_m = std::max(0.0, advisory.distance);
  (void)m.reason.assign(advisory.reason.view().substr(0, vda5050::Text::kCapacity));
  auto text = vda5050::encode_advisory(m, buffers_->out);
  if (!text) return;
  publish(vda5050::advisory_topic(agv.manufacturer, agv.serial), *text, 1, true);
  ++counters_.advisories_sent;
  if (advisory.advice != Advice::clear && advisory.people > 0 && newest_people_unix_ns_ > 0 && latencies_.size() < kMaxLatencies &&
      agv.last_advice != advisory.advice)
    latencies_.push_back(static_cast<double>(unix_ns - newest_people_unix_ns_) * 1e-9);
  agv.last_advice = advisory.advice;
  agv.last_sent = now;
  if (site_.service.direct_pause) {
    if (advisory.advice == Advice::stop && !agv.paused_by_us) send_pause(agv, true, unix_ns);
    if (advisory.advice != Advice::stop && agv.paused_by_us) send_pause(agv, false, unix_ns);
  }
}

void Service::log(const Event& event, std::int64_t unix_ns) {
  std::array<char, 1024> line{};
  json::Writer w(line);
  w.begin_object();
  w.member_number("timeS", static_cast<double>(event.time) * 1e-9);
  w.member("timestamp", vda5050::iso8601(unix_ns).view());
  w.member("type", to_string(event.type));
  w.key("robots").begin_array();
  for (RobotId r : event.robots) w.string(r < site_.robot_serials.size() ? site_.robot_serials[r] : std::string("?"));
  w.end_array();
  const AgvEntry* agv = event.agv != kNone && event.agv < agvs_.size() ? &agvs_[event.agv] : nullptr;
  w.member("agv", agv != nullptr ? std::string_view(agv->serial) : std::string_view());
  w.member("area", event.area != kNone && event.area < site_.area_names.size() ? std::string_view(site_.area_names[event.area])
                                                                                 : std::string_view());
  w.member_uint32("task", event.task);
  w.member("reason", event.reason.view());
  w.end_object();
  auto text = w.finish();
  if (!text) return;
  events_.emplace_back(*text);
  if (event_log_ != nullptr) {
    std::fwrite(text->data(), 1, text->size(), event_log_);
    std::fputc('\n', event_log_);
    std::fflush(event_log_);
  }
}

void Service::carry_out(const Decisions& decisions, std::int64_t unix_ns) {
  for (const RobotCommand& command : decisions.commands) {
    if (command.robot >= site_.robot_serials.size()) continue;
    switch (command.kind) {
      case CommandKind::send:
      case CommandKind::resume: send_order(command.robot, command.task, unix_ns); break;
      case CommandKind::suspend: send_cancel(command.robot, unix_ns); break;
    }
  }
  for (const Advisory& advisory : decisions.advisories) {
    if (advisory.agv < agvs_.size()) send_advisory(agvs_[advisory.agv], advisory, unix_ns, decisions.time);
  }
  for (const Event& event : decisions.events) log(event, unix_ns);
}

void Service::step(hal::Nanos now, std::int64_t unix_ns) {
  take_messages(now);
  const Decisions& decisions = centre_->step(now);
  carry_out(decisions, unix_ns);
  // A standing SLOW or STOP is repeated, so a coordination centre that missed it learns it.
  const auto repeat = static_cast<hal::Nanos>(site_.service.advisory_repeat_s * 1e9);
  for (AgvEntry& agv : agvs_) {
    if (agv.last_advice == Advice::clear || agv.last_sent < 0 || now - agv.last_sent < repeat) continue;
    if (const std::optional<Advisory> advice = centre_->advice(agv.id)) send_advisory(agv, *advice, unix_ns, now);
  }
}

}  // namespace sen3bot::ssc
