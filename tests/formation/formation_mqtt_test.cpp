// `sen3bot-centre formation` on a real Mosquitto with the shipped TLS + ACL site configuration. Three
// robots (clients in the test, each under its own credential) report their poses as VDA 5050
// visualization messages and move as ideal unicycles by the commands they receive:
//   - the centre drives them at its period towards example 2's formation, on their own topics;
//   - a robot that falls silent makes the centre stop the whole team; it resumes when it is back;
//   - a robot's forged command to another robot reaches no one (the ACL);
//   - SIGTERM ends the program with a stop to every robot and its counters on standard output;
//   - bad command lines exit 2 naming the problem.
#include <fcntl.h>
#include <gtest/gtest.h>
#include <signal.h>
#include <spawn.h>
#include <sys/wait.h>
#include <time.h>
#include <unistd.h>

#include <chrono>
#include <cmath>
#include <fstream>
#include <memory>
#include <mutex>
#include <sstream>
#include <string>
#include <thread>
#include <vector>

#include "child_process.hpp"
#include "mosquitto_broker.hpp"
#include "sen3bot/formation/controller.hpp"
#include "sen3bot/formation/examples.hpp"
#include "sen3bot/hal/pubsub.hpp"
#include "sen3bot/vda5050/codec.hpp"
#include "sen3bot/vda5050/extensions.hpp"

extern char** environ;

namespace sen3bot::formation {
namespace {

using sen3bot::testing::MosquittoBroker;
using Clock = std::chrono::steady_clock;
constexpr auto kVersion = vda5050::Version::v2_1_0;

std::int64_t unix_now_ns() {
  timespec ts{};
  ::clock_gettime(CLOCK_REALTIME, &ts);
  return std::int64_t{ts.tv_sec} * 1'000'000'000 + ts.tv_nsec;
}

using sen3bot::testing::read_text_file;

std::span<const std::uint8_t> bytes(std::string_view text) {
  return {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()};
}

using Process = sen3bot::testing::ChildProcess;

// One robot as the centre sees it: its visualization out at 10 Hz, its formation commands in,
// and an ideal unicycle that drives the newest command until its hold runs out.
class FakeRobot {
 public:
  FakeRobot(std::string serial, Pose start, std::unique_ptr<hal::PubSub> link)
      : serial_(std::move(serial)), pose_(start), link_(std::move(link)), scratch_(std::make_unique<vda5050::DecodeScratch>()) {}

  void tick(double dt_s, std::int64_t unix_ns, bool report) {
    std::vector<char> topic(256);
    std::vector<std::uint8_t> payload(16 * 1024);
    for (;;) {
      auto m = link_->receive(topic, payload);
      if (!m.ok() || !m.value()) break;
      const std::string t(topic.data(), m.value()->topic_size);
      const std::string_view text(reinterpret_cast<const char*>(payload.data()), m.value()->payload_size);
      vda5050::FormationCommand c;
      if (t != vda5050::formation_topic("Sen3Bot", serial_) || !vda5050::decode_formation(text, c, *scratch_).ok()) {
        ++foreign;
        continue;
      }
      if (c.serial_number.view() != serial_ || (received > 0 && c.header_id <= last_header)) ++foreign;
      last_header = c.header_id;
      ++received;
      command_ = {c.v, c.omega};
      hold_s_ = c.hold_s;
      since_s_ = 0.0;
      last_was_stop = c.v == 0.0 && c.omega == 0.0;
      if (!last_was_stop) ++moving_commands;
    }
    since_s_ += dt_s;
    if (since_s_ <= hold_s_) {
      pose_.x_m += command_.v * std::cos(pose_.theta_rad) * dt_s;
      pose_.y_m += command_.v * std::sin(pose_.theta_rad) * dt_s;
      pose_.theta_rad += command_.w * dt_s;
    }
    if (!report) return;
    vda5050::Visualization v;
    v.header.header_id = visualization_header_++;
    v.header.timestamp = vda5050::iso8601(unix_ns);
    (void)v.header.manufacturer.assign("Sen3Bot");
    (void)v.header.serial_number.assign(serial_);
    vda5050::AgvPosition p;
    p.position_initialized = true;
    p.x = pose_.x_m;
    p.y = pose_.y_m;
    p.theta = std::remainder(pose_.theta_rad, 2.0 * 3.14159265358979323846);
    (void)p.map_id.assign("map");
    v.agv_position = p;
    // In the vehicle's frame (vx forward), as the robot's fleet task reports it.
    v.velocity = vda5050::Velocity{command_.v, 0.0, command_.w};
    std::array<char, 2048> out{};
    auto text = vda5050::encode_visualization(v, kVersion, out);
    ASSERT_TRUE(text.ok()) << text.error().c_str();
    (void)link_->publish("uagv/v2/Sen3Bot/" + serial_ + "/visualization", bytes(*text), 0, false);
  }
  void forge(const std::string& victim) {
    vda5050::FormationCommand c;
    c.header_id = 1'000'000;
    c.timestamp = vda5050::iso8601(unix_now_ns());
    (void)c.manufacturer.assign("Sen3Bot");
    (void)c.serial_number.assign(victim);
    c.v = 0.3;
    c.omega = 1.0;
    c.hold_s = 2.0;
    std::array<char, 1024> out{};
    auto text = vda5050::encode_formation(c, out);
    ASSERT_TRUE(text.ok());
    (void)link_->publish(vda5050::formation_topic("Sen3Bot", victim), bytes(*text), 0, false);
  }
  [[nodiscard]] const Pose& pose() const { return pose_; }
  [[nodiscard]] hal::PubSub& link() { return *link_; }

  std::uint64_t received = 0;
  std::uint64_t moving_commands = 0;
  std::uint64_t foreign = 0;  // not ours, undecodable, or out of order
  std::uint32_t last_header = 0;
  bool last_was_stop = false;

 private:
  std::string serial_;
  Pose pose_;
  std::unique_ptr<hal::PubSub> link_;
  std::unique_ptr<vda5050::DecodeScratch> scratch_;
  Unicycle command_;
  double hold_s_ = 0.0;
  double since_s_ = 1e9;
  std::uint32_t visualization_header_ = 1;
};

class FormationSite : public ::testing::Test {
 protected:
  FormationSite()
      : broker_(MosquittoBroker::site({{"ssc", "centre-secret"}, {"f1", "f1-secret"}, {"f2", "f2-secret"}, {"f3", "f3-secret"}})) {
    broker_.start();
    std::ofstream(dir() + "/ssc.password") << "centre-secret\n";
  }
  [[nodiscard]] const std::string& dir() const { return broker_.dir(); }
  std::unique_ptr<FakeRobot> robot(const std::string& serial, Pose start) {
    hal::PubSubOptions o;
    o.url = broker_.url("mqtts");
    o.ca_file = broker_.ca_file();
    o.username = serial;
    o.password = serial + "-secret";
    o.client_id = serial;
    o.subscriptions = {{vda5050::formation_topic("Sen3Bot", serial), 0}};
    o.reconnect_min_s = 0.1;
    o.reconnect_max_s = 0.5;
    o.keepalive_s = 5;
    auto link = hal::open_mqtt(o);
    EXPECT_TRUE(link.ok()) << link.error().c_str();
    if (!link.ok()) return nullptr;
    const auto deadline = Clock::now() + std::chrono::seconds(10);
    while (link.value()->stats().connects == 0 && Clock::now() < deadline) std::this_thread::sleep_for(std::chrono::milliseconds(20));
    return std::make_unique<FakeRobot>(serial, start, std::move(link.value()));
  }
  std::vector<std::string> centre_args(std::vector<std::string> extra = {}) const {
    std::vector<std::string> a = {SEN3BOT_CENTRE_BIN, "formation", "--broker", broker_.url("mqtts"), "--example", "2", "--team", "f1,f2,f3",
                                  "--username", "ssc", "--password-file", dir() + "/ssc.password", "--ca-file", broker_.ca_file()};
    a.insert(a.end(), extra.begin(), extra.end());
    return a;
  }

  MosquittoBroker broker_;
};

// Runs the fake robots at 100 Hz for `seconds`; `silent` stops one robot's reports.
void drive(std::vector<std::unique_ptr<FakeRobot>>& robots, double seconds, int silent = -1) {
  const auto start = Clock::now();
  auto next = start;
  int tick = 0;
  while (Clock::now() - start < std::chrono::duration<double>(seconds)) {
    const std::int64_t now = unix_now_ns();
    for (std::size_t i = 0; i < robots.size(); ++i)
      robots[i]->tick(0.01, now, tick % 10 == 0 && static_cast<int>(i) != silent);
    ++tick;
    next += std::chrono::milliseconds(10);
    std::this_thread::sleep_until(next);
  }
}

double formation_error(const std::vector<std::unique_ptr<FakeRobot>>& robots) {
  Controller k;
  const Example e = example(2);
  EXPECT_TRUE(k.configure(e.config));
  std::vector<Pose> poses;
  for (const auto& r : robots) poses.push_back(r->pose());
  k.reset(poses, 0.0);
  std::vector<Vec2> p;
  for (const Pose& q : poses) p.push_back(point_p(q, e.config.offset_m));
  return k.formation_error(p);
}

TEST_F(FormationSite, DrivesTheTeamStopsItOnASilentRobotAndOnTheWayOut) {
  const Example e = example(2);
  std::vector<std::unique_ptr<FakeRobot>> robots;
  for (std::size_t i = 0; i < 3; ++i) {
    robots.push_back(robot("f" + std::to_string(i + 1), e.starts[i]));
    ASSERT_NE(robots.back(), nullptr);
  }
  const double error_at_start = formation_error(robots);
  Process centre(centre_args({"--log", dir() + "/steps.csv"}), dir() + "/centre.out", dir() + "/centre.err");

  // Driven: about ten commands a second each, on its own topic, in order.
  drive(robots, 12.0);
  for (const auto& r : robots) {
    EXPECT_GE(r->moving_commands, 60u) << centre.err();
    EXPECT_EQ(r->foreign, 0u);
  }
  const double error_driven = formation_error(robots);
  EXPECT_LT(error_driven, 0.5 * error_at_start) << "from " << error_at_start << " m";

  // A forged command from f1 to f2: the broker's ACL drops it (f2 would count it as foreign:
  // its header id is out of the centre's sequence).
  robots[0]->forge("f2");
  drive(robots, 0.5);
  EXPECT_EQ(robots[1]->foreign, 0u);

  // f3 falls silent: within the pose timeout and a period every robot is told to stop.
  drive(robots, 1.0, 2);
  for (const auto& r : robots) EXPECT_TRUE(r->last_was_stop) << centre.err();
  const Pose frozen = robots[0]->pose();
  drive(robots, 1.0, 2);
  EXPECT_NEAR(robots[0]->pose().x_m, frozen.x_m, 1e-9);
  EXPECT_NE(centre.err().find("stale"), std::string::npos) << centre.err();

  // Back: the team moves again.
  const std::uint64_t moving = robots[0]->moving_commands;
  drive(robots, 2.0);
  EXPECT_GT(robots[0]->moving_commands, moving + 5);

  centre.signal(SIGTERM);
  ASSERT_EQ(centre.wait(10.0), 0) << centre.err();
  drive(robots, 0.5);
  for (const auto& r : robots) EXPECT_TRUE(r->last_was_stop);
  const std::string out = centre.out();
  EXPECT_NE(out.find("\"stopped_by\":\"SIGTERM\""), std::string::npos) << out;
  EXPECT_NE(out.find("\"stale_steps\":"), std::string::npos) << out;
  const std::string log = read_text_file(dir() + "/steps.csv");
  EXPECT_NE(log.find("commanded"), std::string::npos);
  EXPECT_NE(log.find("stopped"), std::string::npos);
}

TEST_F(FormationSite, BadCommandLinesExit2NamingTheProblem) {
  const auto run = [&](std::vector<std::string> args) {
    Process p(std::move(args), dir() + "/bad.out", dir() + "/bad.err");
    const int status = p.wait(20.0);
    return std::make_pair(status, p.err());
  };
  auto [status, err] = run({SEN3BOT_CENTRE_BIN, "formation", "--broker", broker_.url("mqtts"), "--example", "2"});
  EXPECT_EQ(status, 2);
  EXPECT_NE(err.find("--team"), std::string::npos) << err;
  std::tie(status, err) = run(centre_args({"--team", "f1,f2"}));
  EXPECT_EQ(status, 2);
  EXPECT_NE(err.find("3 robots"), std::string::npos) << err;
  std::tie(status, err) = run(centre_args({"--hold", "5"}));
  EXPECT_EQ(status, 2);
  EXPECT_NE(err.find("--hold"), std::string::npos) << err;
  std::tie(status, err) = run(centre_args({"--team", "f1,,f3"}));
  EXPECT_EQ(status, 2);
  EXPECT_NE(err.find("--team"), std::string::npos) << err;
  std::tie(status, err) = run({SEN3BOT_CENTRE_BIN, "formation", "--broker", broker_.url("mqtts"), "--example", "2", "--team", "f1,f2,f3",
                               "--username", "ssc", "--password-file", dir() + "/missing.password"});
  EXPECT_EQ(status, 2);
  EXPECT_NE(err.find("--password-file"), std::string::npos) << err;
}

}  // namespace
}  // namespace sen3bot::formation
