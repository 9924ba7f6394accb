// The Sensors Synergy Centre on a real Mosquitto with the shipped TLS + ACL site configuration:
// the `sen3bot-centre ssc` and `sen3bot-sim agv` programs, and ssc::Service with SimAgv in-process, each
// under its own credential. A robot (a client in the test, credential r1) reports its pose and a
// person in the area `cross` of config/fleet/site.yaml; an AGV's route crosses it.
//   - the centre orders r1 to the area and advises the AGV (read by the `agvcc` credential);
//   - a centre killed and restarted learns the robot again from its retained connection and
//     its next state, and advises again;
//   - with agv_cc.direct_pause, STOP also pauses the AGV itself and CLEAR resumes it;
//   - bad command lines and site files exit 2 naming the problem.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <chrono>
#include <cmath>
#include <fstream>
#include <functional>
#include <memory>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "child_process.hpp"
#include "mosquitto_broker.hpp"
#include "sen3bot/hal/pubsub.hpp"
#include "sen3bot/sim/agv.hpp"
#include "sen3bot/ssc/service.hpp"
#include "sen3bot/vda5050/codec.hpp"
#include "sen3bot/vda5050/extensions.hpp"

extern char** environ;

namespace sen3bot::ssc {
namespace {

using sen3bot::testing::MosquittoBroker;
using Clock = std::chrono::steady_clock;
constexpr auto kVersion = vda5050::Version::v2_1_0;
constexpr double kPi = 3.14159265358979323846;

std::int64_t clock_ns(clockid_t clock) {
  timespec ts{};
  ::clock_gettime(clock, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

std::span<const std::uint8_t> bytes(std::string_view text) {
  return {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()};
}

std::string read_file(const std::string& path) { return sen3bot::testing::read_text_file(path); }

void write_file(const std::string& path, const std::string& text) { std::ofstream(path) << text; }

using Process = sen3bot::testing::ChildProcess;

// Runs a program to its end: exit status, standard output, standard error.
struct Ran {
  int status = -1;
  std::string out, err;
};
Ran run_program(std::vector<std::string> args, const std::string& dir) {
  Process p(std::move(args), dir + "/run.out", dir + "/run.err");
  Ran r;
  r.status = p.wait(20.0);
  r.out = p.out();
  r.err = p.err();
  return r;
}

struct Message {
  std::string topic, payload;
  bool retained = false;
};

void drain(hal::PubSub& link, std::vector<Message>& into) {
  std::vector<char> topic(256);
  std::vector<std::uint8_t> payload(64 * 1024);
  for (;;) {
    auto m = link.receive(topic, payload);
    if (!m.ok() || !m.value()) return;
    into.push_back({std::string(topic.data(), m.value()->topic_size),
                    std::string(reinterpret_cast<const char*>(payload.data()), m.value()->payload_size), m.value()->retained});
  }
}

// Robot r1 as the centre sees it: a VDA 5050 vehicle on the broker (its connection, its
// state) that runs a people layer. It stands at its home by the area and does not drive.
class FakeRobot {
 public:
  explicit FakeRobot(std::unique_ptr<hal::PubSub> link) : link_(std::move(link)), scratch_(std::make_unique<vda5050::DecodeScratch>()),
                                                           order_(std::make_unique<vda5050::Order>()) {}

  void online() {
    vda5050::Connection c;
    header(c.header, connection_header_++);
    c.state = vda5050::ConnectionState::online;
    auto text = vda5050::encode_connection(c, kVersion, out_);
    ASSERT_TRUE(text.ok());
    ASSERT_TRUE(link_->publish("uagv/v2/Sen3Bot/r1/connection", bytes(*text), 1, true).ok());
  }
  // The state every second and the people report five times a second, as the firmware sends them.
  void tick(std::int64_t now) {
    if (last_state_ < 0 || now - last_state_ >= 1'000'000'000) {
      last_state_ = now;
      auto state = std::make_unique<vda5050::State>();
      header(state->header, state_header_++);
      vda5050::AgvPosition p;
      p.position_initialized = true;
      p.x = 12.6;
      p.y = 5.6;
      p.theta = -kPi / 2;
      (void)p.map_id.assign("plant");
      state->agv_position = p;
      state->battery.battery_charge = 90;
      auto text = vda5050::encode_state(*state, kVersion, out_);
      ASSERT_TRUE(text.ok()) << text.error().c_str();
      (void)link_->publish("uagv/v2/Sen3Bot/r1/state", bytes(*text), 0, false);
    }
    if (last_people_ < 0 || now - last_people_ >= 200'000'000) {
      last_people_ = now;
      vda5050::PeopleMessage m;
      m.header_id = people_header_++;
      m.timestamp = vda5050::iso8601(clock_ns(CLOCK_REALTIME));
      (void)m.manufacturer.assign("Sen3Bot");
      (void)m.serial_number.assign("r1");
      (void)m.map_id.assign("plant");
      m.robot_valid = true;
      m.robot_x = 12.6;
      m.robot_y = 5.6;
      m.robot_theta = -kPi / 2;
      if (person_) {
        vda5050::PersonReport p;
        p.id = 7;
        p.x = person_x_;
        p.y = person_y_;
        p.width = 0.5;
        p.cage_radius = 0.6;
        p.laser_points = 12;
        (void)m.people.push_back(p);
      }
      auto text = vda5050::encode_people(m, out_);
      ASSERT_TRUE(text.ok()) << text.error().c_str();
      (void)link_->publish(vda5050::people_topic("Sen3Bot", "r1"), bytes(*text), 0, false);
    }
    std::vector<Message> in;
    drain(*link_, in);
    for (const Message& m : in) {
      if (m.topic != "uagv/v2/Sen3Bot/r1/order") continue;
      const vda5050::Decoded decoded = vda5050::decode_order(m.payload, kVersion, *order_, *scratch_);
      EXPECT_TRUE(decoded) << m.payload;
      if (!decoded) continue;
      orders.push_back({std::string(order_->order_id.view()), order_->header.header_id, order_->nodes.size(),
                        order_->nodes.empty() || !order_->nodes.back().position ? 0.0 : order_->nodes.back().position->x,
                        order_->nodes.empty() || !order_->nodes.back().position ? 0.0 : order_->nodes.back().position->y});
    }
  }
  void see_person(double x, double y) {
    person_ = true;
    person_x_ = x;
    person_y_ = y;
  }

  // An order to r1's post for `cross`: the site says r1 overlooks it from its home (12.6, 5.6),
  // so that is where the centre sends it (from the from-th order on).
  [[nodiscard]] bool ordered_to_post(std::size_t from = 0) const {
    for (std::size_t i = from; i < orders.size(); ++i) {
      if (std::abs(orders[i].goal_x - 12.6) < 0.01 && std::abs(orders[i].goal_y - 5.6) < 0.01) return true;
    }
    return false;
  }

  struct ReceivedOrder {
    std::string id;
    std::uint32_t header_id;
    std::size_t nodes;
    double goal_x, goal_y;
  };
  std::vector<ReceivedOrder> orders;

 private:
  static void header(vda5050::Header& h, std::uint32_t id) {
    h.header_id = id;
    h.timestamp = vda5050::iso8601(clock_ns(CLOCK_REALTIME));
    (void)h.version.assign(vda5050::to_string(kVersion));
    (void)h.manufacturer.assign("Sen3Bot");
    (void)h.serial_number.assign("r1");
  }
  std::unique_ptr<hal::PubSub> link_;
  std::unique_ptr<vda5050::DecodeScratch> scratch_;
  std::unique_ptr<vda5050::Order> order_;
  std::array<char, 16 * 1024> out_{};
  std::uint32_t connection_header_ = 0, state_header_ = 0, people_header_ = 0;
  std::int64_t last_state_ = -1, last_people_ = -1;
  bool person_ = false;
  double person_x_ = 0, person_y_ = 0;
};

// The advisories the plant's AGV coordination centre reads (credential agvcc).
struct AdvisoryReader {
  explicit AdvisoryReader(std::unique_ptr<hal::PubSub> l) : link(std::move(l)) {}
  std::unique_ptr<hal::PubSub> link;
  std::unique_ptr<vda5050::DecodeScratch> scratch = std::make_unique<vda5050::DecodeScratch>();
  struct Seen {
    vda5050::AdvisoryMessage message;
    bool retained;
  };
  std::vector<Seen> seen;
  void poll() {
    std::vector<Message> in;
    drain(*link, in);
    for (const Message& m : in) {
      if (m.topic != vda5050::advisory_topic("PlantAGV", "agv1")) continue;
      Seen s{{}, m.retained};
      const Status decoded = vda5050::decode_advisory(m.payload, s.message, *scratch);
      EXPECT_TRUE(decoded.ok()) << m.payload;
      if (decoded.ok()) seen.push_back(s);
    }
  }
  [[nodiscard]] bool any(vda5050::AdviceKind kind, std::size_t from = 0) const {
    for (std::size_t i = from; i < seen.size(); ++i)
      if (seen[i].message.advice == kind) return true;
    return false;
  }
  [[nodiscard]] bool any_not_clear(std::size_t from = 0) const {
    return any(vda5050::AdviceKind::slow, from) || any(vda5050::AdviceKind::stop, from);
  }
};

// The plant's master control for the AGV: its order along the lane through `cross` (y 1.8),
// from where it stands to the far end of the hall.
void send_agv_order(hal::PubSub& link, double from_x, double to_x) {
  auto order = std::make_unique<vda5050::Order>();
  order->header.timestamp = vda5050::iso8601(clock_ns(CLOCK_REALTIME));
  (void)order->header.version.assign(vda5050::to_string(kVersion));
  (void)order->header.manufacturer.assign("PlantAGV");
  (void)order->header.serial_number.assign("agv1");
  (void)order->order_id.assign("plant-agv1");
  const double xs[2] = {from_x, to_x};
  for (int i = 0; i < 2; ++i) {
    vda5050::Node node;
    (void)node.node_id.assign("p" + std::to_string(i));
    node.sequence_id = static_cast<std::uint32_t>(2 * i);
    node.released = true;
    node.position = vda5050::NodePosition{xs[i], 1.8, std::nullopt, 0.5, 0.0, {}};
    (void)node.position->map_id.assign("plant");
    (void)order->nodes.push_back(node);
  }
  vda5050::Edge edge;
  (void)edge.edge_id.assign("e0");
  edge.sequence_id = 1;
  edge.released = true;
  (void)edge.start_node_id.assign("p0");
  (void)edge.end_node_id.assign("p1");
  (void)order->edges.push_back(edge);
  std::vector<char> out(64 * 1024);
  auto text = vda5050::encode_order(*order, kVersion, out);
  ASSERT_TRUE(text.ok()) << text.error().c_str();
  ASSERT_TRUE(link.publish("uagv/v2/PlantAGV/agv1/order", bytes(*text), 0, false).ok());
}

class SscSite : public ::testing::Test {
 protected:
  SscSite()
      : broker_(MosquittoBroker::site({{"ssc", "centre-secret"},
                                       {"r1", "robot1-secret"},
                                       {"agvcc", "agvcc-secret"},
                                       {"agv1", "agv1-secret"}})) {
    broker_.start();
    for (const char* user : {"ssc", "agv1"}) write_file(dir() + "/" + user + ".password", std::string(user == std::string("ssc") ? "centre-secret" : "agv1-secret") + "\n");
  }
  [[nodiscard]] const std::string& dir() const { return broker_.dir(); }
  hal::PubSubOptions tls(const std::string& user, const std::string& password, const std::string& client_id,
                         std::vector<hal::PubSubSubscription> subs = {}) const {
    hal::PubSubOptions o;
    o.url = broker_.url("mqtts");
    o.ca_file = broker_.ca_file();
    o.username = user;
    o.password = password;
    o.client_id = client_id;
    o.subscriptions = std::move(subs);
    o.reconnect_min_s = 0.1;
    o.reconnect_max_s = 0.5;
    o.keepalive_s = 5;
    return o;
  }
  std::unique_ptr<hal::PubSub> open(const hal::PubSubOptions& o) {
    auto link = hal::open_mqtt(o);
    EXPECT_TRUE(link.ok()) << link.error().c_str();
    return link.ok() ? std::move(link.value()) : nullptr;
  }
  static bool wait_connected(const hal::PubSub& link) {
    const auto deadline = Clock::now() + std::chrono::seconds(5);
    while (Clock::now() < deadline && link.state() != hal::PubSubState::connected) std::this_thread::sleep_for(std::chrono::milliseconds(5));
    return link.state() == hal::PubSubState::connected;
  }
  // Calls tick every 50 ms until done() or timeout_s; true when done.
  static bool pump(double timeout_s, const std::function<void()>& tick, const std::function<bool()>& done) {
    const auto deadline = Clock::now() + std::chrono::duration_cast<Clock::duration>(std::chrono::duration<double>(timeout_s));
    auto next = Clock::now();
    while (Clock::now() < deadline) {
      tick();
      if (done()) return true;
      next += std::chrono::milliseconds(50);
      std::this_thread::sleep_until(next);
    }
    return false;
  }
  std::vector<std::string> ssc_args(const std::string& event_log) const {
    return {SEN3BOT_CENTRE_BIN, "ssc", "--broker", broker_.url("mqtts"), "--site", std::string(SEN3BOT_SOURCE_DIR) + "/config/fleet/site.yaml",
            "--username", "ssc", "--password-file", dir() + "/ssc.password", "--ca-file", broker_.ca_file(), "--event-log", event_log};
  }

  MosquittoBroker broker_;
};

std::size_t count_lines(const std::string& text) { return static_cast<std::size_t>(std::count(text.begin(), text.end(), '\n')); }

// Both programs on the site's broker; the centre is killed mid-run and a second one started.
TEST_F(SscSite, TheCentreOrdersTheRobotAdvisesTheAgvAndARestartLosesNoRobot) {
  FakeRobot robot(open(tls("r1", "robot1-secret", "r1", {{"uagv/v2/Sen3Bot/r1/order", 0}, {"uagv/v2/Sen3Bot/r1/instantActions", 0}})));
  AdvisoryReader agvcc(open(tls("agvcc", "agvcc-secret", "agvcc", {{"sen3bot/v1/advisory/#", 1}})));
  // The AGV's master control writes orders, which the ACL gives only the centre's credential.
  auto master = open(tls("ssc", "centre-secret", "plant-master", {{"uagv/v2/PlantAGV/agv1/connection", 1}}));
  ASSERT_TRUE(wait_connected(*agvcc.link) && wait_connected(*master));
  robot.online();
  robot.see_person(12.0, 1.5);  // inside `cross`, standing

  Process agv({SEN3BOT_SIM_BIN, "agv", "--broker", broker_.url("mqtts"), "--serial", "agv1", "--map-id", "plant", "--speed", "0.1", "--x",
               "4.0", "--y", "1.8", "--username", "agv1", "--password-file", dir() + "/agv1.password", "--ca-file", broker_.ca_file()},
              dir() + "/agv.out", dir() + "/agv.err");
  ASSERT_TRUE(agv.started());
  std::vector<Message> at_master;
  ASSERT_TRUE(pump(10, [&] { drain(*master, at_master); }, [&] { return !at_master.empty(); })) << agv.err() << broker_.log();
  send_agv_order(*master, 4.0, 24.0);

  const std::string event_log = dir() + "/events.jsonl";
  const auto started = Clock::now();
  auto centre = std::make_unique<Process>(ssc_args(event_log), dir() + "/ssc1.out", dir() + "/ssc1.err");
  ASSERT_TRUE(centre->started());
  auto tick = [&] {
    robot.tick(clock_ns(CLOCK_MONOTONIC));
    agvcc.poll();
  };
  ASSERT_TRUE(pump(15, tick, [&] { return robot.ordered_to_post() && agvcc.any_not_clear(); }))
      << "orders " << robot.orders.size() << ", advisories " << agvcc.seen.size() << "\n"
      << centre->err() << agv.err() << read_file(event_log);
  std::printf("first centre: order and advisory %.2f s after start\n",
              std::chrono::duration<double>(Clock::now() - started).count());
  for (const FakeRobot::ReceivedOrder& o : robot.orders) {
    EXPECT_EQ(o.id.rfind("ssc-r1-", 0), 0u) << o.id;
    EXPECT_EQ(o.nodes, 2u);
  }
  const auto& advice = agvcc.seen.back().message;
  EXPECT_EQ(advice.area_id.view(), "cross");
  EXPECT_GE(advice.people, 1u);

  // Killed: no goodbye, nothing cleaned up. The robot and the AGV go on as before.
  centre->signal(SIGKILL);
  EXPECT_EQ(centre->wait(), 128 + SIGKILL);
  pump(0.5, tick, [] { return false; });
  const std::size_t orders_before = robot.orders.size();
  const std::size_t advisories_before = agvcc.seen.size();

  // A second centre knows nothing but what the broker gives back: the robot's retained ONLINE,
  // then its next state. The robot does not announce itself again.
  const auto restarted = Clock::now();
  centre = std::make_unique<Process>(ssc_args(event_log), dir() + "/ssc2.out", dir() + "/ssc2.err");
  ASSERT_TRUE(pump(15, tick, [&] {
    return robot.ordered_to_post(orders_before) && agvcc.any_not_clear(advisories_before);
  })) << "orders " << robot.orders.size() << ", advisories " << agvcc.seen.size() << "\n"
      << centre->err() << read_file(event_log);
  std::printf("second centre: order and advisory %.2f s after restart\n",
              std::chrono::duration<double>(Clock::now() - restarted).count());
  EXPECT_EQ(robot.orders[orders_before].header_id, 0u);  // a new centre's first order
  EXPECT_EQ(robot.orders[orders_before].id.rfind("ssc-r1-", 0), 0u);
  EXPECT_FALSE(agvcc.seen[advisories_before].retained);  // published live by the new centre
  EXPECT_EQ(agvcc.seen.back().message.area_id.view(), "cross");

  centre->signal(SIGTERM);
  ASSERT_EQ(centre->wait(), 0) << centre->err();
  const std::string summary = centre->out();
  EXPECT_EQ(count_lines(summary), 1u) << summary;
  EXPECT_NE(summary.find("\"stopped_by\":\"SIGTERM\""), std::string::npos) << summary;
  EXPECT_EQ(summary.find("\"orders_sent\":0,"), std::string::npos) << summary;
  EXPECT_EQ(summary.find("\"advisories_sent\":0,"), std::string::npos) << summary;
  // Both centres' decisions, appended to one log, each line a JSON object.
  const std::string events = read_file(event_log);
  EXPECT_GE(count_lines(events), 4u) << events;
  EXPECT_NE(events.find("\"type\":\"allocation\""), std::string::npos) << events;
  EXPECT_NE(events.find("\"type\":\"advisory\""), std::string::npos) << events;

  agv.signal(SIGINT);
  ASSERT_EQ(agv.wait(), 0) << agv.err();
  EXPECT_NE(agv.out().find("\"serial\":\"agv1\""), std::string::npos) << agv.out();
}

// direct_pause: the centre's STOP also reaches the AGV itself as startPause, CLEAR as stopPause.
TEST_F(SscSite, WithDirectPauseAStopPausesTheAgvAndAClearResumesIt) {
  std::string yaml = read_file(std::string(SEN3BOT_SOURCE_DIR) + "/config/fleet/site.yaml");
  const std::size_t at = yaml.find("direct_pause: false");
  ASSERT_NE(at, std::string::npos);
  yaml.replace(at, std::string("direct_pause: false").size(), "direct_pause: true");
  write_file(dir() + "/site.yaml", yaml);
  Result<SiteFile> site = load_site(dir() + "/site.yaml");
  ASSERT_TRUE(site.ok()) << site.error().c_str();
  ASSERT_TRUE(site->service.direct_pause);

  hal::PubSubOptions centre_link = tls("ssc", "centre-secret", "ssc", Service::subscriptions(site->service));
  centre_link.inbound_slots = 256;
  auto service = Service::create(*site, open(centre_link), nullptr);
  ASSERT_TRUE(service.ok()) << service.error().c_str();

  // The AGV stands 2.5 m before `cross` and creeps: within the stop distance from the start.
  sim::SimAgvConfig agv_config;
  agv_config.serial_number = "agv1";
  agv_config.map_id = "plant";
  agv_config.x = 8.0;
  agv_config.y = 1.8;
  agv_config.speed_m_s = 0.05;
  sim::SimAgv agv(agv_config, open(tls("agv1", "agv1-secret", "agv1", sim::SimAgv::subscriptions(agv_config))));
  FakeRobot robot(open(tls("r1", "robot1-secret", "r1", {{"uagv/v2/Sen3Bot/r1/order", 0}})));
  AdvisoryReader agvcc(open(tls("agvcc", "agvcc-secret", "agvcc", {{"sen3bot/v1/advisory/#", 1}})));
  auto master = open(tls("ssc", "centre-secret", "plant-master"));
  ASSERT_TRUE(wait_connected(*master) && wait_connected(*agvcc.link) && wait_connected((*service)->link()));
  robot.online();

  std::int64_t last_centre = -1;
  std::int64_t last_order = -1;
  double person_x = 10.9;
  bool walking_out = false;
  auto tick = [&] {
    const std::int64_t now = clock_ns(CLOCK_MONOTONIC);
    agv.step(now, clock_ns(CLOCK_REALTIME), 0.05);
    // The order is QoS 0: sent again until the AGV has taken it (it may not have subscribed yet).
    if (agv.vehicle().route().empty() && (last_order < 0 || now - last_order >= 1'000'000'000)) {
      last_order = now;
      send_agv_order(*master, 8.0, 24.0);
    }
    // A person walks 1.2 m/s along the lane: into `cross` and on (dynamic after 1 m), or out.
    const double target = walking_out ? 15.0 : 12.9;
    person_x = std::min(target, person_x + 0.06);
    robot.see_person(person_x, 1.0);
    robot.tick(now);
    if (last_centre < 0 || now - last_centre >= 100'000'000) {
      last_centre = now;
      (*service)->step(now, clock_ns(CLOCK_REALTIME));
    }
    agvcc.poll();
  };
  const auto started = Clock::now();
  ASSERT_TRUE(pump(15, tick, [&] { return agv.vehicle().paused(); }))
      << "advisories " << agvcc.seen.size() << ", pauses sent " << (*service)->counters().pauses_sent;
  std::printf("STOP and startPause %.2f s after start\n", std::chrono::duration<double>(Clock::now() - started).count());
  EXPECT_TRUE(agvcc.any(vda5050::AdviceKind::stop));
  EXPECT_EQ((*service)->counters().pauses_sent, 1u);
  // Paused, it stands (it would have crept on otherwise).
  pump(1.0, tick, [] { return false; });
  const double x_paused = agv.x();
  pump(1.0, tick, [] { return false; });
  EXPECT_NEAR(agv.x(), x_paused, 1e-6);
  EXPECT_TRUE(agv.vehicle().paused());

  walking_out = true;
  const auto cleared = Clock::now();
  ASSERT_TRUE(pump(15, tick, [&] { return !agv.vehicle().paused(); }))
      << "advisories " << agvcc.seen.size() << ", pauses sent " << (*service)->counters().pauses_sent;
  std::printf("CLEAR and stopPause %.2f s after the person left\n", std::chrono::duration<double>(Clock::now() - cleared).count());
  EXPECT_EQ(agvcc.seen.back().message.advice, vda5050::AdviceKind::clear);
  EXPECT_EQ((*service)->counters().pauses_sent, 2u);
  pump(1.0, tick, [] { return false; });
  EXPECT_GT(agv.x(), x_paused + 0.01);  // moving again
}

TEST(SscCommand, ArgumentAndSiteFileErrorsExitTwoNamingTheProblem) {
  char path[] = "/tmp/sen3bot-ssc-args-XXXXXX";
  ASSERT_NE(::mkdtemp(path), nullptr);
  const std::string dir = path;
  const std::string site = std::string(SEN3BOT_SOURCE_DIR) + "/config/fleet/site.yaml";

  Ran r = run_program({SEN3BOT_CENTRE_BIN, "ssc", "--broker", "mqtt://127.0.0.1:1"}, dir);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--site is required"), std::string::npos) << r.err;

  r = run_program({SEN3BOT_CENTRE_BIN, "ssc", "--site", site}, dir);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--broker is required"), std::string::npos) << r.err;

  r = run_program({SEN3BOT_CENTRE_BIN, "ssc", "--broker", "mqtt://127.0.0.1:1", "--site", dir + "/none.yaml"}, dir);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find(dir + "/none.yaml"), std::string::npos) << r.err;

  write_file(dir + "/bad.yaml", read_file(site) + "colour: blue\n");
  r = run_program({SEN3BOT_CENTRE_BIN, "ssc", "--broker", "mqtt://127.0.0.1:1", "--site", dir + "/bad.yaml"}, dir);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("colour"), std::string::npos) << r.err;
  EXPECT_NE(r.err.find("bad.yaml"), std::string::npos) << r.err;

  r = run_program({SEN3BOT_CENTRE_BIN, "ssc", "--broker", "mqtt://127.0.0.1:1", "--site", site, "--duration", "soon"}, dir);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--duration"), std::string::npos) << r.err;

  r = run_program({SEN3BOT_CENTRE_BIN, "ssc", "--broker", "mqtt://127.0.0.1:1", "--site", site, "--colour", "blue"}, dir);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("unknown option '--colour'"), std::string::npos) << r.err;

  r = run_program({SEN3BOT_CENTRE_BIN, "ssc", "--broker", "mqtts://127.0.0.1:1", "--site", site}, dir);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("CA"), std::string::npos) << r.err;

  r = run_program({SEN3BOT_CENTRE_BIN, "ssc", "--broker", "mqtt://127.0.0.1:1", "--site", site, "--username", "ssc", "--password-file",
                   dir + "/none.password"},
                  dir);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--password-file"), std::string::npos) << r.err;

  // A broker nobody answers: the centre runs its duration and reports no connection.
  r = run_program({SEN3BOT_CENTRE_BIN, "ssc", "--broker", "mqtt://127.0.0.1:1", "--site", site, "--duration", "0.5"}, dir);
  EXPECT_EQ(r.status, 0) << r.err;
  EXPECT_NE(r.out.find("\"stopped_by\":\"duration\""), std::string::npos) << r.out;
  EXPECT_NE(r.out.find("\"connects\":0"), std::string::npos) << r.out;

  r = run_program({SEN3BOT_SIM_BIN, "agv", "--broker", "mqtt://127.0.0.1:1"}, dir);
  EXPECT_EQ(r.status, 2);
  EXPECT_NE(r.err.find("--serial is required"), std::string::npos) << r.err;

  EXPECT_EQ(std::system(("rm -rf " + dir).c_str()), 0);
}

}  // namespace
}  // namespace sen3bot::ssc
