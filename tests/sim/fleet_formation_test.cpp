// The centre's formation commands, end to end in lockstep: the whole firmware on the simulated
// robot (config/sim.yaml with a fleet section, the worker taken out of the world), its link a
// client of the site's in-process broker, and a centre in the test that writes formation
// commands with the codec and watches the robot's ground truth: it drives the velocity, stops
// on its own when the centre falls silent, refuses what is not for it, and its safety filter
// still stops it before a wall.
#include <gtest/gtest.h>

#include <algorithm>
#include <array>
#include <cmath>
#include <cstdio>
#include <memory>
#include <string>
#include <vector>

#include "firmware.hpp"
#include "sen3bot/vda5050/extensions.hpp"
#include "sim_rig.hpp"

namespace sen3bot {
namespace {

constexpr double kPi = 3.14159265358979323846;

std::span<const std::uint8_t> bytes(std::string_view text) {
  return {reinterpret_cast<const std::uint8_t*>(text.data()), text.size()};
}

// One slice of the run, as the test saw it after the slice.
struct Sample {
  double t_s = 0;
  double true_speed = 0;
  double odom_v = 0;
  double odom_w = 0;
  double request_v = 0;
  double request_w = 0;
  nav::Pose2D truth;
};

class FormationRig {
 public:
  FormationRig() : rig_(testing::load_sim_rig()) {
    rig_.world.movers.clear();  // no one walking into the robot's way
    rig_.make_board();
    firmware::FirmwareConfig& c = rig_.config;
    c.navigation.mission.goal_count = 0;
    c.tasks.erase("mission");
    c.tasks["fleet"] = firmware::TaskConfig{firmware::FleetTask::arena_bytes_needed() + 64 * 1024};
    c.has_fleet = true;
    c.fleet.broker = "sim";
    c.fleet.serial_number = "r1";
    c.fleet.map_id = "lab";
    sink_ = std::fopen("/dev/null", "w");
    fw_ = std::make_unique<firmware::Firmware>(c, *rig_.board, sink_);
    hal::PubSubOptions centre;
    centre.client_id = "ssc";
    auto client = rig_.board->site_broker().connect(centre);
    EXPECT_TRUE(client.ok());
    if (client.ok()) centre_ = std::move(client.value());
  }
  ~FormationRig() {
    fw_->shutdown();
    std::fclose(sink_);
  }
  [[nodiscard]] Status init() { return fw_->init(); }
  firmware::Firmware& firmware() { return *fw_; }
  [[nodiscard]] const firmware::FleetCounters& counters() const { return fw_->fleet()->counters(); }
  [[nodiscard]] const nav::Pose2D& truth() { return rig_.board->simulation().truth().pose; }
  [[nodiscard]] const sim::GroundTruth& ground_truth() { return rig_.board->simulation().truth(); }
  [[nodiscard]] double now_s() { return hal::to_seconds(rig_.clock().now()); }
  [[nodiscard]] double base_decel_m_s2() const { return static_cast<double>(rig_.config.devices.base.trans_decel_mm_s2) / 1000.0; }

  // Publishes one command as the centre writes it.
  void send(std::uint32_t header_id, double v, double w, double hold_s, const char* serial = "r1") {
    vda5050::FormationCommand m;
    m.header_id = header_id;
    m.timestamp = vda5050::iso8601(rig_.clock().now());
    (void)m.manufacturer.assign("Sen3Bot");
    (void)m.serial_number.assign(serial);
    m.v = v;
    m.omega = w;
    m.hold_s = hold_s;
    std::array<char, 512> out{};
    auto text = vda5050::encode_formation(m, out);
    ASSERT_TRUE(text.ok()) << text.error().c_str();
    send_text(*text);
  }
  void send_text(std::string_view text) {
    ASSERT_TRUE(centre_->publish(vda5050::formation_topic("Sen3Bot", "r1"), bytes(text), 0, false).ok());
    last_send_s_ = now_s();
  }

  // Runs `seconds`, sending (v, w) every `period_s` when send is set, sampling every slice.
  void run_for(double seconds, bool sending = false, double v = 0, double w = 0, double hold_s = 0.5,
               double period_s = 0.1) {
    const hal::Nanos end = rig_.clock().now() + static_cast<hal::Nanos>(seconds * 1e9);
    while (rig_.clock().now() < end) {
      if (sending && (next_send_s_ < 0 || now_s() >= next_send_s_ - 1e-9)) {
        send(++header_id_, v, w, hold_s);
        next_send_s_ = now_s() + period_s;
      }
      ASSERT_TRUE(fw_->scheduler().run_lockstep(rig_.clock(), hal::millis(10)));
      record();
    }
    if (!sending) next_send_s_ = -1;
  }
  void drive(double v, double w, double hold_s, double seconds) { run_for(seconds, true, v, w, hold_s); }

  [[nodiscard]] const std::vector<Sample>& samples() const { return samples_; }
  [[nodiscard]] double last_send_s() const { return last_send_s_; }
  [[nodiscard]] std::uint32_t header_id() const { return header_id_; }
  void set_header_id(std::uint32_t id) { header_id_ = id; }

 private:
  void record() {
    Sample s;
    s.t_s = now_s();
    s.true_speed = ground_truth().speed_m_s;
    s.truth = ground_truth().pose;
    tasks::Sample<msg::Odometry> odom;
    if (fw_->odometry().read(odom)) {
      s.odom_v = odom.value.v_m_s;
      s.odom_w = odom.value.w_rad_s;
    }
    tasks::Sample<msg::VelocityCommand> request;
    if (fw_->request().read(request)) {
      s.request_v = request.value.v_m_s;
      s.request_w = request.value.w_rad_s;
    }
    samples_.push_back(s);
  }

  testing::SimRig rig_;
  std::FILE* sink_ = nullptr;
  std::unique_ptr<firmware::Firmware> fw_;
  std::unique_ptr<hal::PubSub> centre_;
  std::vector<Sample> samples_;
  std::uint32_t header_id_ = 0;
  double next_send_s_ = -1;
  double last_send_s_ = -1;
};

// The samples from `from_s` on (until `to_s`).
std::vector<Sample> between(const std::vector<Sample>& all, double from_s, double to_s = 1e18) {
  std::vector<Sample> out;
  for (const Sample& s : all)
    if (s.t_s >= from_s && s.t_s <= to_s) out.push_back(s);
  return out;
}

double wrap(double a) { return std::remainder(a, 2 * kPi); }

TEST(FleetFormation, TheRobotDrivesTheCentresVelocity) {
  FormationRig rig;
  ASSERT_TRUE(rig.init().ok());
  rig.run_for(2.0);  // localized, the link up

  // An arc to the right from (2.5, 2) m facing +y: 0.2 m/s and -0.4 rad/s (0.5 m radius).
  const double t0 = rig.now_s();
  rig.drive(0.2, -0.4, 0.5, 3.0);
  tasks::Sample<msg::ControllerStatus> status;
  ASSERT_TRUE(rig.firmware().controller_status().read(status));
  EXPECT_TRUE(status.value.formation);
  EXPECT_EQ(status.value.status, msg::DwaStatus::idle);
  // After the base's acceleration (under a second to these speeds).
  const std::vector<Sample> arc = between(rig.samples(), t0 + 1.5, t0 + 3.0);
  ASSERT_GE(arc.size(), 100u);
  for (const Sample& s : arc) {
    EXPECT_NEAR(s.true_speed, 0.2, 0.02) << "t " << s.t_s;
    EXPECT_NEAR(s.odom_v, 0.2, 0.03) << "t " << s.t_s;
    EXPECT_NEAR(s.odom_w, -0.4, 0.05) << "t " << s.t_s;
    EXPECT_EQ(s.request_v, 0.2);
    EXPECT_EQ(s.request_w, -0.4);
  }
  const double turn_rate = wrap(arc.back().truth.theta_rad - arc.front().truth.theta_rad) / (arc.back().t_s - arc.front().t_s);
  EXPECT_NEAR(turn_rate, -0.4, 0.04);

  // Then straight on at 0.3 m/s, the heading kept.
  const double t1 = rig.now_s();
  rig.drive(0.3, 0.0, 0.5, 3.0);
  const std::vector<Sample> straight = between(rig.samples(), t1 + 1.5, t1 + 3.0);
  ASSERT_GE(straight.size(), 100u);
  for (const Sample& s : straight) {
    EXPECT_NEAR(s.true_speed, 0.3, 0.02) << "t " << s.t_s;
    EXPECT_NEAR(s.odom_v, 0.3, 0.03) << "t " << s.t_s;
  }
  const Sample& a = straight.front();
  const Sample& b = straight.back();
  EXPECT_NEAR(wrap(b.truth.theta_rad - a.truth.theta_rad), 0.0, 0.02);
  EXPECT_NEAR(std::hypot(b.truth.x_m - a.truth.x_m, b.truth.y_m - a.truth.y_m) / (b.t_s - a.t_s), 0.3, 0.02);
  EXPECT_EQ(rig.counters().formation_rejected, 0u);
  EXPECT_GE(rig.counters().formation_received, 59u);
  EXPECT_EQ(rig.ground_truth().contacts, 0u);

  // Silence: back to the DWA's output, which without a path is zero.
  rig.run_for(2.0);
  ASSERT_TRUE(rig.firmware().controller_status().read(status));
  EXPECT_FALSE(status.value.formation);
  EXPECT_LT(std::abs(rig.ground_truth().speed_m_s), 1e-3);
}

// When the centre falls silent the controller drops its last command hold_s after it was
// taken (within one controller period) and the robot brakes at the base's deceleration: it
// stands within hold_s + 0.1 s + v / deceleration, within hold_s + 0.3 s from 0.1 m/s.
TEST(FleetFormation, TheRobotStopsOnItsOwnWhenTheCentreFallsSilent) {
  struct Case {
    double hold_s;
    double v;
  };
  for (const Case c : {Case{0.5, 0.1}, Case{1.0, 0.1}, Case{2.0, 0.1}, Case{0.5, 0.3}}) {
    SCOPED_TRACE(::testing::Message() << "hold " << c.hold_s << " s, " << c.v << " m/s");
    FormationRig rig;
    ASSERT_TRUE(rig.init().ok());
    const double decel_m_s2 = rig.base_decel_m_s2();
    rig.run_for(2.0);
    rig.drive(c.v, 0.0, c.hold_s, 2.5);
    ASSERT_NEAR(rig.ground_truth().speed_m_s, c.v, 0.02);
    const double last_sent_s = rig.last_send_s();
    rig.run_for(c.hold_s + 2.0);
    tasks::Sample<msg::FormationCommand> last;
    ASSERT_TRUE(rig.firmware().formation().read(last));
    EXPECT_EQ(last.value.header_id, rig.header_id());
    const double received_s = hal::to_seconds(last.value.received_ns);
    EXPECT_GE(received_s, last_sent_s);
    EXPECT_LE(received_s, last_sent_s + 0.1 + 1e-6);  // within the fleet row's period
    double request_zero_s = -1, standing_s = -1;
    for (const Sample& s : between(rig.samples(), last_sent_s)) {
      if (request_zero_s < 0 && s.request_v == 0.0 && s.request_w == 0.0) request_zero_s = s.t_s;
      if (standing_s < 0 && std::abs(s.true_speed) < 1e-3) standing_s = s.t_s;
      if (standing_s >= 0) {
        EXPECT_LT(std::abs(s.true_speed), 1e-3) << "moving again at " << s.t_s;
      }
    }
    ASSERT_GE(request_zero_s, 0);
    ASSERT_GE(standing_s, 0);
    std::printf("hold %.1f s at %.1f m/s: request zero %.2f s and standing %.2f s after the last command was taken\n",
                c.hold_s, c.v, request_zero_s - received_s, standing_s - received_s);
    EXPECT_GE(request_zero_s - received_s, c.hold_s - 1e-6);
    EXPECT_LE(request_zero_s - received_s, c.hold_s + 0.1 + 0.011);
    EXPECT_LE(standing_s - received_s, c.hold_s + 0.1 + c.v / decel_m_s2 + 0.05);
    if (c.v <= 0.1) {
      EXPECT_LE(standing_s - received_s, c.hold_s + 0.3);
    }
  }
}

TEST(FleetFormation, CommandsForAnotherRobotOutOfOrderOrTooFastAreRefused) {
  FormationRig rig;
  ASSERT_TRUE(rig.init().ok());
  rig.run_for(2.0);
  const nav::Pose2D start = rig.truth();
  rig.send(5, 0.0, 0.0, 0.5);  // taken: the last headerId is 5
  rig.run_for(0.2);
  EXPECT_EQ(rig.counters().formation_received, 1u);
  EXPECT_EQ(rig.counters().formation_rejected, 0u);

  rig.send(6, 0.3, 0.0, 2.0, "r2");  // another robot's, on this robot's topic
  rig.run_for(0.2);
  rig.send(4, 0.3, 0.0, 2.0);  // older than the last
  rig.run_for(0.2);
  rig.send(5, 0.3, 0.0, 2.0);  // the same again
  rig.run_for(0.2);
  rig.send(7, 0.8, 0.0, 2.0);  // beyond navigation.max_v_m_s (0.5)
  rig.run_for(0.2);
  rig.send(8, -0.6, 0.0, 2.0);
  rig.run_for(0.2);
  rig.send(9, 0.1, 1.5, 2.0);  // beyond the DWA's 1.2 rad/s
  rig.run_for(0.2);
  rig.send_text(R"({"schemaVersion":"1.0.0","headerId":10,"v":0.3,"omega":0,"holdS":2})");  // no header
  rig.run_for(0.2);
  rig.send_text(R"({"schemaVersion":"1.0.0","headerId":11,"timestamp":"t","manufacturer":"Sen3Bot",)"
                R"("serialNumber":"r1","v":0.3,"omega":0,"holdS":3})");  // hold beyond 2 s
  rig.run_for(0.2);
  rig.send_text("{not json");
  rig.run_for(2.0);
  EXPECT_EQ(rig.counters().formation_received, 10u);
  EXPECT_EQ(rig.counters().formation_rejected, 9u);
  EXPECT_LT(std::hypot(rig.truth().x_m - start.x_m, rig.truth().y_m - start.y_m), 0.01);
  for (const Sample& s : rig.samples()) {
    EXPECT_LT(std::abs(s.true_speed), 1e-3) << "t " << s.t_s;
    EXPECT_EQ(s.request_v, 0.0) << "t " << s.t_s;
  }
  tasks::Sample<msg::FormationCommand> taken;
  ASSERT_TRUE(rig.firmware().formation().read(taken));
  EXPECT_EQ(taken.value.header_id, 5u);

  // headerId 0: a centre that restarted; it is taken and the robot drives.
  rig.send(0, 0.2, 0.0, 0.5);
  rig.set_header_id(0);
  rig.drive(0.2, 0.0, 0.5, 2.0);
  EXPECT_EQ(rig.counters().formation_rejected, 9u);
  EXPECT_NEAR(rig.ground_truth().speed_m_s, 0.2, 0.02);
}

// Driving straight up the lab (+y) from (2.5, 2) m leads through the door to the rack at
// y = 6.0 m: the formation command goes on asking for 0.3 m/s, the safety filter stops the
// robot short of the rack, and holds it there.
TEST(FleetFormation, TheSafetyFilterStillStopsAFormationCommandBeforeAWall) {
  FormationRig rig;
  ASSERT_TRUE(rig.init().ok());
  rig.run_for(2.0);
  rig.drive(0.3, 0.0, 0.5, 20.0);
  const sim::GroundTruth& truth = rig.ground_truth();
  EXPECT_EQ(truth.contacts, 0u);
  EXPECT_LT(std::abs(truth.speed_m_s), 1e-3);
  EXPECT_GT(truth.clearance_m, 0.1);
  EXPECT_GT(truth.pose.y_m, 5.0);  // through the door
  EXPECT_LT(truth.pose.y_m, 6.0 - 0.2);
  tasks::Sample<msg::SafetyOutput> safety;
  ASSERT_TRUE(rig.firmware().safety_output().read(safety));
  EXPECT_NE(safety.value.reasons & msg::kSafetyObstacle, 0u) << safety.value.reasons;
  EXPECT_EQ(safety.value.command.v_m_s, 0.0);
  tasks::Sample<msg::VelocityCommand> request;
  ASSERT_TRUE(rig.firmware().request().read(request));
  EXPECT_NEAR(request.value.v_m_s, 0.3, 1e-9);  // still asked for
  std::printf("stopped at (%.2f, %.2f) m, clearance %.2f m\n", truth.pose.x_m, truth.pose.y_m, truth.clearance_m);
}

}  // namespace
}  // namespace sen3bot
