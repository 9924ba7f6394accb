// The centre's formation service against the in-process broker, with fake robots: clients that
// publish VDA 5050 visualization messages and read the formation commands sent to them.
#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/formation/service.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/vda5050/codec.hpp"
#include "sen3bot/vda5050/extensions.hpp"

namespace sen3bot::formation {
namespace {

constexpr std::int64_t kEpoch = hal::SimClock::kEpochUnixNs;

struct Received {
  std::string topic;
  vda5050::FormationCommand command;
  hal::Nanos at = 0;
};

// Two robots driving their P points to targets 2 m apart.
FormationServiceConfig two_robots() {
  FormationServiceConfig c;
  c.team = {{"Sen3Bot", "f1"}, {"Sen3Bot", "f2"}};
  c.controller.task = TaskKind::targets;
  c.controller.robots = 2;
  c.controller.workspace = {-3.5, -2.0, 3.5, 2.0};
  c.controller.targets[0] = {1.0, 1.0};
  c.controller.targets[1] = {-1.0, -1.0};
  return c;
}

class Site {
 public:
  explicit Site(const FormationServiceConfig& config = two_robots()) : config_(config) {
    auto subscriptions = FormationService::subscriptions(config_);
    EXPECT_TRUE(subscriptions.ok());
    hal::PubSubOptions link;
    link.client_id = "centre";
    link.subscriptions = subscriptions.value();
    link.inbound_slots = 64;
    auto client = broker_.connect(link);
    EXPECT_TRUE(client.ok());
    auto service = FormationService::create(config_, std::move(client.value()));
    EXPECT_TRUE(service.ok()) << (service.ok() ? "" : service.error().c_str());
    service_ = std::move(service.value());
    hal::PubSubOptions listener;
    listener.client_id = "robots";
    listener.subscriptions = {{"sen3bot/v1/formation/+/+", 0}};
    listener.inbound_slots = 512;
    robots_ = std::move(broker_.connect(listener).value());
    scratch_ = std::make_unique<vda5050::DecodeScratch>();
  }

  // Robot i's visualization, stamped at `stamp_ns` of simulated time.
  void report(std::size_t robot, double x, double y, double theta, hal::Nanos stamp_ns, double v = 0.0, double omega = 0.0) {
    vda5050::Visualization m;
    m.header.header_id = ++visualization_ids_[robot];
    m.header.timestamp = vda5050::iso8601(kEpoch + stamp_ns);
    (void)m.header.manufacturer.assign("Sen3Bot");
    (void)m.header.serial_number.assign(config_.team[robot].serial_number);
    vda5050::AgvPosition p;
    p.position_initialized = true;
    p.x = x;
    p.y = y;
    p.theta = theta;
    (void)p.map_id.assign("formation");
    m.agv_position = p;
    m.velocity = vda5050::Velocity{v, 0.0, omega};
    std::vector<char> out(4096);
    auto text = vda5050::encode_visualization(m, config_.version, out);
    ASSERT_TRUE(text.ok());
    broker_.publish(topic(robot), hal::as_bytes(*text), false);
  }
  std::string topic(std::size_t robot) const { return "uagv/v2/Sen3Bot/" + config_.team[robot].serial_number + "/visualization"; }

  // Steps the service every 10 ms until `to`, collecting what the robots received.
  void run_until(hal::Nanos to, bool fresh_poses = true) {
    while (now_ < to) {
      now_ += hal::millis(10);
      if (fresh_poses && now_ % hal::millis(100) == 0) report_all(now_);
      service_->step(now_, kEpoch + now_);
      collect();
    }
  }
  void report_all(hal::Nanos stamp) {
    for (std::size_t i = 0; i < config_.team.size(); ++i) report(i, poses[i].x_m, poses[i].y_m, poses[i].theta_rad, stamp);
  }
  void collect() {
    std::array<char, 256> topic{};
    std::vector<std::uint8_t> payload(64 * 1024);
    for (;;) {
      auto m = robots_->receive(topic, payload);
      if (!m || !m.value()) return;
      Received r;
      r.topic.assign(topic.data(), m.value()->topic_size);
      r.at = now_;
      const std::string_view text(reinterpret_cast<const char*>(payload.data()), m.value()->payload_size);
      EXPECT_TRUE(vda5050::decode_formation(text, r.command, *scratch_).ok()) << text;
      received.push_back(r);
    }
  }
  std::vector<Received> for_robot(std::size_t robot) const {
    std::vector<Received> out;
    for (const Received& r : received)
      if (r.topic == "sen3bot/v1/formation/Sen3Bot/" + config_.team[robot].serial_number) out.push_back(r);
    return out;
  }

  FormationServiceConfig config_;
  hal::MemoryBroker broker_;
  std::unique_ptr<FormationService> service_;
  std::unique_ptr<hal::PubSub> robots_;
  std::unique_ptr<vda5050::DecodeScratch> scratch_;
  std::array<std::uint32_t, kMaxRobots> visualization_ids_{};
  std::vector<Received> received;
  std::vector<Pose> poses{{-1.0, 0.0, 0.0}, {1.0, 0.0, 3.14159}};
  hal::Nanos now_ = 0;
};

TEST(FormationService, CommandsGoOutAtThePeriodToEachRobotsTopicWithIncreasingHeaderIds) {
  Site site;
  site.run_until(hal::seconds(2));
  for (std::size_t robot = 0; robot < 2; ++robot) {
    const std::vector<Received> got = site.for_robot(robot);
    // One per 0.1 s from the first step at 10 ms: 20 in two seconds.
    ASSERT_EQ(got.size(), 20u) << robot;
    for (std::size_t k = 0; k < got.size(); ++k) {
      EXPECT_EQ(got[k].command.header_id, k + 1);
      EXPECT_EQ(got[k].command.serial_number.view(), site.config_.team[robot].serial_number);
      EXPECT_DOUBLE_EQ(got[k].command.hold_s, 0.5);
      if (k > 0) {
        EXPECT_EQ(got[k].at - got[k - 1].at, hal::millis(100));
      }
    }
    // The first step came before any pose: stop. Once every robot has reported, the targets pull.
    EXPECT_EQ(got.front().command.v, 0.0);
    EXPECT_GT(std::abs(got.back().command.v) + std::abs(got.back().command.omega), 0.01);
  }
  EXPECT_EQ(site.service_->counters().poses, 40u);
  EXPECT_GE(site.service_->counters().controller_steps, 18u);
  EXPECT_EQ(site.service_->counters().commands_sent, 40u);
  EXPECT_EQ(site.service_->counters().rejected, 0u);
}

TEST(FormationService, AStalePoseStopsTheWholeTeamUntilItIsFreshAgain) {
  Site site;
  site.run_until(hal::seconds(1));
  ASSERT_GT(std::abs(site.for_robot(0).back().command.v) + std::abs(site.for_robot(0).back().command.omega), 0.01);
  // Robot 2 falls silent; robot 1 goes on reporting.
  const std::uint64_t stale_before = site.service_->counters().stale_steps;
  const hal::Nanos silent_from = site.now_;
  while (site.now_ < hal::seconds(2)) {
    site.now_ += hal::millis(10);
    if (site.now_ % hal::millis(100) == 0) site.report(0, -1.0, 0.0, 0.0, site.now_);
    site.service_->step(site.now_, kEpoch + site.now_);
    site.collect();
  }
  for (std::size_t robot = 0; robot < 2; ++robot) {
    for (const Received& r : site.for_robot(robot)) {
      // Within the timeout the team is still driven; past it, every robot is told to stop.
      if (r.at > silent_from + hal::millis(600)) {
        EXPECT_EQ(r.command.v, 0.0) << robot << " at " << r.at;
        EXPECT_EQ(r.command.omega, 0.0);
      }
    }
  }
  EXPECT_GE(site.service_->counters().stale_steps - stale_before, 4u);
  // Robot 2 is back: commands again.
  site.run_until(hal::seconds(3));
  const Received last = site.for_robot(1).back();
  EXPECT_GT(std::abs(last.command.v) + std::abs(last.command.omega), 0.01);
}

TEST(FormationService, NoPoseFromOneRobotMeansStopForEveryRobot) {
  Site site;
  while (site.now_ < hal::seconds(1)) {
    site.now_ += hal::millis(10);
    if (site.now_ % hal::millis(100) == 0) site.report(0, -1.0, 0.0, 0.0, site.now_);
    EXPECT_NE(site.service_->step(site.now_, kEpoch + site.now_), StepOutcome::commanded);
    site.collect();
  }
  ASSERT_EQ(site.received.size(), 20u);
  for (const Received& r : site.received) {
    EXPECT_EQ(r.command.v, 0.0);
    EXPECT_EQ(r.command.omega, 0.0);
  }
  EXPECT_EQ(site.service_->counters().controller_steps, 0u);
  EXPECT_EQ(site.service_->counters().stale_steps, 10u);
}

TEST(FormationService, MalformedAndForeignVisualizationsAreCountedAndIgnored) {
  Site site;
  site.run_until(hal::seconds(1));
  const Pose before = site.service_->poses()[0];
  site.broker_.publish(site.topic(0), hal::as_bytes("{\"headerId\": 1, \"agvPosition\": "), false);
  site.broker_.publish(site.topic(0), hal::as_bytes("[1, 2, 3]"), false);
  // A well-formed message on robot 1's topic that names robot 2.
  vda5050::Visualization m;
  m.header.timestamp = vda5050::iso8601(kEpoch + site.now_);
  (void)m.header.manufacturer.assign("Sen3Bot");
  (void)m.header.serial_number.assign("f2");
  m.agv_position = vda5050::AgvPosition{true, std::nullopt, std::nullopt, 3.0, 1.0, 0.0, {}};
  (void)m.agv_position->map_id.assign("formation");
  std::vector<char> out(4096);
  auto text = vda5050::encode_visualization(m, vda5050::Version::v2_1_0, out);
  ASSERT_TRUE(text.ok());
  site.broker_.publish(site.topic(0), hal::as_bytes(*text), false);
  site.run_until(hal::seconds(2));
  EXPECT_EQ(site.service_->counters().rejected, 3u);
  EXPECT_EQ(site.service_->counters().stale_steps, 1u);  // only the very first step, before any pose
  EXPECT_NEAR(site.service_->poses()[0].x_m, before.x_m, 1e-9);
  const Received last = site.for_robot(0).back();
  EXPECT_GT(std::abs(last.command.v) + std::abs(last.command.omega), 0.01);
}

TEST(FormationService, PosesArePredictedToTheStepByTheirReportedVelocity) {
  FormationServiceConfig config = two_robots();
  config.lookahead_s = 0.0;  // the report's own prediction alone; the next test adds the command's
  Site site(config);
  site.run_until(hal::seconds(1));
  // Stamped 0.3 s before the step that uses them, driving at 0.5 m/s straight.
  const hal::Nanos step_at = hal::millis(1410);
  site.report(0, -1.0, 0.0, 0.0, step_at - hal::millis(300), 0.5, 0.0);
  site.report(1, 1.0, 0.0, 3.14159265358979, step_at - hal::millis(300), 0.0, 0.5);
  while (site.now_ < step_at) {
    site.now_ += hal::millis(10);
    site.service_->step(site.now_, kEpoch + site.now_);
  }
  const std::span<const Pose> poses = site.service_->poses();
  EXPECT_NEAR(poses[0].x_m, -1.0 + 0.15, 1e-6);
  EXPECT_NEAR(poses[0].y_m, 0.0, 1e-6);
  EXPECT_NEAR(poses[1].x_m, 1.0, 1e-6);  // turning on the spot
  EXPECT_NEAR(std::remainder(poses[1].theta_rad - (3.14159265358979 + 0.15), 2 * 3.14159265358979), 0.0, 1e-6);
}

TEST(FormationService, PosesAreCarriedOnToWhenTheCommandActsByTheLastCommand) {
  FormationServiceConfig config = two_robots();
  config.lookahead_s = 0.2;
  Site site(config);
  site.run_until(hal::seconds(1));
  // Fresh reports, standing: between steps only the last commands move the poses, by 0.2 s.
  for (int k = 0; k < 5; ++k) {
    const hal::Nanos step_at = site.now_ + hal::millis(100);
    site.report(0, -1.0, 0.2, 0.3, step_at);
    site.report(1, 1.0, -0.2, 2.8, step_at);
    const std::array<Unicycle, 2> last = {site.service_->commands()[0], site.service_->commands()[1]};
    while (site.now_ < step_at) {
      site.now_ += hal::millis(10);
      site.service_->step(site.now_, kEpoch + site.now_);
    }
    const std::array<Pose, 2> reported = {Pose{-1.0, 0.2, 0.3}, Pose{1.0, -0.2, 2.8}};
    for (std::size_t i = 0; i < 2; ++i) {
      const Pose& got = site.service_->poses()[i];
      // The closed form of a unicycle's arc over 0.2 s.
      const Pose& q = reported[i];
      const double th = q.theta_rad + last[i].w * 0.2;
      const double x = std::abs(last[i].w) < 1e-6 ? q.x_m + last[i].v * 0.2 * std::cos(q.theta_rad)
                                                  : q.x_m + last[i].v / last[i].w * (std::sin(th) - std::sin(q.theta_rad));
      EXPECT_NEAR(got.x_m, x, 1e-6) << "step " << k << " robot " << i;
      EXPECT_NEAR(std::remainder(got.theta_rad - th, 2 * 3.14159265358979), 0.0, 1e-6);
    }
  }
  EXPECT_GT(std::abs(site.service_->commands()[0].v) + std::abs(site.service_->commands()[0].w), 0.0);
}

TEST(FormationService, OlderPosesDoNotReplaceNewerOnes) {
  Site site;
  site.run_until(hal::seconds(1));
  site.report(0, 2.0, 0.0, 0.0, site.now_ - hal::millis(300));
  site.run_until(site.now_ + hal::millis(10), false);
  EXPECT_EQ(site.service_->counters().out_of_order, 1u);
}

TEST(FormationService, StepAllocatesNothing) {
  Site site;
  site.run_until(hal::seconds(1));
  // Pre-encoded messages, so only the service's own work is counted.
  std::vector<std::string> texts;
  for (int k = 0; k < 2; ++k) {
    vda5050::Visualization m;
    m.header.timestamp = vda5050::iso8601(kEpoch + hal::seconds(1));
    (void)m.header.manufacturer.assign("Sen3Bot");
    (void)m.header.serial_number.assign(k == 0 ? "f1" : "f2");
    m.agv_position = vda5050::AgvPosition{true, std::nullopt, std::nullopt, k == 0 ? -1.0 : 1.0, 0.0, 0.0, {}};
    (void)m.agv_position->map_id.assign("formation");
    std::vector<char> out(4096);
    texts.emplace_back(*vda5050::encode_visualization(m, vda5050::Version::v2_1_0, out));
  }
  const std::string topics[] = {site.topic(0), site.topic(1)};
  std::array<char, 256> topic{};
  std::vector<std::uint8_t> payload(64 * 1024);
  mem::testing::AllocationScope scope;
  hal::Nanos now = site.now_;
  for (int k = 0; k < 50; ++k) {
    now += hal::millis(100);
    site.broker_.publish(topics[0], hal::as_bytes(texts[0]), false);
    site.broker_.publish(topics[1], hal::as_bytes(texts[1]), false);
    // Every step is a controller step: the poses' stamps stay within the timeout of `now`.
    (void)site.service_->step(now, kEpoch + hal::seconds(1) + hal::millis(100));
    while (true) {
      auto m = site.robots_->receive(topic, payload);
      if (!m || !m.value()) break;
    }
  }
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(site.service_->counters().stale_steps, 1u);
}

TEST(FormationService, CreateRefusesAMismatchedTeamAndBadTimes) {
  hal::MemoryBroker broker;
  int n = 0;
  auto link = [&] {
    hal::PubSubOptions o;
    o.client_id = "c" + std::to_string(++n);
    return std::move(broker.connect(o).value());
  };
  FormationServiceConfig c = two_robots();
  c.team.pop_back();
  EXPECT_FALSE(FormationService::create(c, link()).ok());
  c = two_robots();
  c.hold_s = 3.0;
  EXPECT_FALSE(FormationService::create(c, link()).ok());
  c = two_robots();
  c.team[1].serial_number = "f/2";
  EXPECT_FALSE(FormationService::create(c, link()).ok());
  c = two_robots();
  c.team[1].serial_number = "f1";
  EXPECT_FALSE(FormationService::create(c, link()).ok());
  EXPECT_TRUE(FormationService::create(two_robots(), link()).ok());
}

}  // namespace
}  // namespace sen3bot::formation
