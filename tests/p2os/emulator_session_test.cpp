// The emulator on its own, driven by a raw client in simulated time: sessions start from zero
// odometry without moving the world, CLOSE ends a session, HEAD stops on its target, and a
// watchdog stop is final until a fresh motion command.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>
#include <vector>

#include "lockstep_harness.hpp"

namespace sen3bot::p2os {
namespace {

constexpr double kDegPerRad = 180.0 / std::numbers::pi;

struct Received {
  hal::Nanos t_ns = 0;
  std::uint8_t type = 0;
  std::vector<std::uint8_t> raw;  // the whole frame
};

// A client that writes packets by hand and keeps every frame the robot sends.
struct RawClient {
  static constexpr hal::Nanos kStepNs = hal::millis(5);

  explicit RawClient(const EmulatorConfig& config = test::fast_emulator_config()) : emulator(config) {}

  void send(const Packet& p) { ASSERT_EQ(*pipe.a().write(p.view()), p.size); }
  // Steps the emulator every 5 ms for `duration_ns`, calling `each` after every step.
  void run(hal::Nanos duration_ns, const std::function<void()>& each = {}) {
    const hal::Nanos end = t_ns + duration_ns;
    while (t_ns < end) {
      (void)emulator.step(pipe.b(), t_ns);
      std::uint8_t chunk[512];
      for (;;) {
        const Result<std::size_t> got = pipe.a().read(chunk);
        if (!got || *got == 0) break;
        parser.feed(std::span<const std::uint8_t>(chunk, *got), t_ns, [&](const Frame& f) {
          received.push_back(Received{t_ns, f.type, std::vector<std::uint8_t>(f.raw.begin(), f.raw.end())});
        });
      }
      if (each) each();
      t_ns += kStepNs;
    }
  }
  // Sends and lets the robot answer.
  void exchange(const Packet& p) {
    send(p);
    run(hal::millis(20));
  }
  // Keeps the watchdog fed with a PULSE every 500 ms, as ARIA does when idle.
  void run_pulsing(hal::Nanos duration_ns, const std::function<void()>& each = {}) {
    const hal::Nanos end = t_ns + duration_ns;
    while (t_ns < end) {
      send(encode_command(kPulse));
      run(std::min(hal::millis(500), end - t_ns), each);
    }
  }
  void open_session(bool enable = true) {
    for (const Packet& p : {encode_command(Command::sync0), encode_command(Command::sync1),
                            encode_command(Command::sync2), encode_command_int(kOpen, 1)})
      exchange(p);
    if (enable) exchange(encode_command_int(Command::enable, 1));
  }
  // The SIPs received since frame index `from`.
  [[nodiscard]] std::vector<Sip> sips_since(std::size_t from) const {
    std::vector<Sip> out;
    for (std::size_t i = from; i < received.size(); ++i) {
      const Received& r = received[i];
      if (r.type != kTypeSipStopped && r.type != kTypeSipMoving) continue;
      FrameParser p;
      p.feed(r.raw, 0, [&](const Frame& f) {
        if (auto sip = decode_sip(f)) out.push_back(*sip);
      });
    }
    return out;
  }
  [[nodiscard]] double odometry_heading_deg() const { return emulator.odometry_pose().theta_rad * kDegPerRad; }

  hal::MemoryPipe pipe{16384, "client", "robot"};
  P2osEmulator emulator;
  FrameParser parser;
  std::vector<Received> received;
  hal::Nanos t_ns = hal::seconds(1);
};

// ---- Sessions ----

TEST(P2osEmulatorSession, NewSessionZeroesOdometryAndCountersButNotTheWorld) {
  RawClient c;
  c.emulator.set_ground_truth(Pose2{2.0, 3.0, 0.5});
  c.open_session();
  c.send(encode_command_int(Command::vel, 400));
  c.send(encode_command_int(Command::rvel, 20));
  c.send(encode_command_int(Command::encoder, 2));
  c.run_pulsing(hal::seconds(3));
  c.exchange(encode_command_int(Command::vel, 0));
  c.exchange(encode_command_int(Command::rvel, 0));
  c.run_pulsing(hal::seconds(1));
  const Pose2 truth = c.emulator.ground_truth();
  const Pose2 odometry = c.emulator.odometry_pose();
  ASSERT_GT(std::hypot(odometry.x_m, odometry.y_m), 0.5);  // the first session drove
  ASSERT_GT(std::fabs(odometry.theta_rad), 0.5);
  ASSERT_GT(std::hypot(truth.x_m - 2.0, truth.y_m - 3.0), 0.5);

  // The client vanishes; a new one connects (what the TCP runner does on accept).
  c.pipe.reset();
  c.parser.reset();
  c.emulator.reset_session();
  const Pose2 after = c.emulator.ground_truth();
  EXPECT_EQ(after.x_m, truth.x_m);  // the robot did not move in the world
  EXPECT_EQ(after.y_m, truth.y_m);
  EXPECT_EQ(after.theta_rad, truth.theta_rad);
  EXPECT_EQ(c.emulator.odometry_pose().x_m, 0.0);
  EXPECT_EQ(c.emulator.odometry_pose().y_m, 0.0);
  EXPECT_EQ(c.emulator.odometry_pose().theta_rad, 0.0);

  const std::size_t from = c.received.size();
  c.open_session(false);
  c.exchange(encode_command_int(Command::encoder, 1));
  c.run_pulsing(hal::millis(600));
  const std::vector<Sip> sips = c.sips_since(from);
  ASSERT_GE(sips.size(), 5u);
  EXPECT_EQ(sips.front().x_raw, 0);
  EXPECT_EQ(sips.front().y_raw, 0);
  EXPECT_EQ(sips.front().theta_raw, 0);
  bool saw_encoder = false;
  for (std::size_t i = from; i < c.received.size(); ++i) {
    if (c.received[i].type != kTypeEncoder) continue;
    FrameParser p;
    p.feed(c.received[i].raw, 0, [&](const Frame& f) {
      const std::optional<EncoderPacket> e = decode_encoder(f);
      ASSERT_TRUE(e);
      EXPECT_EQ(e->left_ticks, 0);
      EXPECT_EQ(e->right_ticks, 0);
      saw_encoder = true;
    });
  }
  EXPECT_TRUE(saw_encoder);
}

TEST(P2osEmulatorSession, DriverOnANewSessionStartsAtTheOrigin) {
  test::Lockstep h;
  ASSERT_TRUE(h.connect());
  h.hold(0.4, 0.3);
  h.run_for(hal::seconds(3));
  h.hold(0, 0);
  h.run_for(hal::seconds(1));
  ASSERT_GT(std::hypot(h.driver.state().x_m, h.driver.state().y_m), 0.5);
  const Pose2 truth = h.emulator.ground_truth();

  // A second connection (a new driver on a fresh stream, a new session at the robot).
  h.driver.detach();
  h.pipe.reset();
  h.emulator.reset_session();
  P2osDriver second{P2osConfig{}};
  second.attach(h.pipe.a(), h.now_ns);
  bool connected = false;
  for (int i = 0; i < 2500 && !connected; ++i) {
    (void)h.emulator.step(h.pipe.b(), h.now_ns);
    second.step(h.now_ns);
    h.now_ns += test::Lockstep::kStepNs;
    connected = second.state().link == LinkState::connected;
  }
  ASSERT_TRUE(connected);
  EXPECT_NEAR(second.state().x_m, 0.0, 1e-9);
  EXPECT_NEAR(second.state().y_m, 0.0, 1e-9);
  EXPECT_NEAR(second.state().theta_rad, 0.0, 1e-9);
  EXPECT_EQ(h.emulator.ground_truth().x_m, truth.x_m);
  EXPECT_EQ(h.emulator.ground_truth().y_m, truth.y_m);
}

// The same driver reconnecting to a new session (as the base task does after a TCP drop):
// the robot's counters restart at zero but the driver's odometry carries on without a jump,
// so localization sees no teleport.
TEST(P2osEmulatorSession, SameDriverOnANewSessionKeepsItsOdometryContinuous) {
  test::Lockstep h;
  ASSERT_TRUE(h.connect());
  h.hold(0.4, 0.3);
  h.run_for(hal::seconds(3));
  h.hold(0, 0);
  h.run_for(hal::seconds(1));
  const double x = h.driver.state().x_m, y = h.driver.state().y_m, th = h.driver.state().theta_rad;
  ASSERT_GT(std::hypot(x, y), 0.5);

  h.driver.detach();
  h.pipe.reset();
  h.emulator.reset_session();
  h.driver.attach(h.pipe.a(), h.now_ns);
  bool connected = false;
  for (int i = 0; i < 2500 && !connected; ++i) {
    (void)h.emulator.step(h.pipe.b(), h.now_ns);
    h.driver.step(h.now_ns);
    h.now_ns += test::Lockstep::kStepNs;
    connected = h.driver.state().link == LinkState::connected;
  }
  ASSERT_TRUE(connected);
  EXPECT_NEAR(h.driver.state().x_m, x, 1e-9);
  EXPECT_NEAR(h.driver.state().y_m, y, 1e-9);
  EXPECT_NEAR(h.driver.state().theta_rad, th, 1e-9);
  h.hold(0.3, 0);  // and it follows the robot's motion from there
  h.run_for(hal::seconds(2));
  EXPECT_GT(std::hypot(h.driver.state().x_m - x, h.driver.state().y_m - y), 0.3);
}

TEST(P2osEmulatorSession, CloseEndsTheSessionOnceAndTheLineStaysUsable) {
  RawClient c;
  c.open_session();
  c.send(encode_command_int(Command::vel, 300));
  c.run_pulsing(hal::seconds(1));
  ASSERT_GT(c.emulator.velocity_m_s(), 0.2);
  EXPECT_FALSE(c.emulator.take_session_closed());

  c.exchange(encode_command_int(kClose, 1));  // ARIA's CLOSE carries an int 1
  EXPECT_EQ(c.emulator.state(), EmulatorState::sync_wait);
  EXPECT_EQ(c.emulator.velocity_m_s(), 0.0);
  EXPECT_FALSE(c.emulator.motors_enabled());
  EXPECT_TRUE(c.emulator.take_session_closed());
  EXPECT_FALSE(c.emulator.take_session_closed());  // reported once
  EXPECT_EQ(c.emulator.stats().sessions_closed, 1u);

  // No more SIPs; the same line (a pty cannot be hung up by the robot) handshakes again.
  const std::size_t from = c.received.size();
  c.run(hal::seconds(1));
  EXPECT_TRUE(c.sips_since(from).empty());
  const Packet sync0 = encode_command(Command::sync0);
  c.exchange(sync0);
  ASSERT_EQ(c.received.size(), from + 1);
  EXPECT_EQ(c.received.back().raw, std::vector<std::uint8_t>(sync0.view().begin(), sync0.view().end()));
  // A bare SYNC2 during the handshake is SYNC2, not CLOSE.
  c.exchange(encode_command(Command::sync1));
  c.exchange(encode_command(Command::sync2));
  EXPECT_EQ(c.emulator.state(), EmulatorState::synced);
  EXPECT_FALSE(c.emulator.take_session_closed());
}

// ---- HEAD / DHEAD ----

struct TurnResult {
  double peak_progress_deg = 0;  // furthest along the turn's direction
  double final_progress_deg = 0;
  double min_progress_deg = 0;   // furthest the wrong way
};

// Turns from the current heading with `command`, tracking progress along `expected_deg`.
TurnResult turn(RawClient& c, const Packet& command, double expected_deg) {
  TurnResult r;
  double last = c.odometry_heading_deg();
  double progress = 0;
  const double sign = expected_deg >= 0 ? 1.0 : -1.0;
  c.send(command);
  c.run_pulsing(hal::seconds(6), [&] {
    const double now = c.odometry_heading_deg();
    progress += std::remainder(now - last, 360.0) * sign;
    last = now;
    r.peak_progress_deg = std::max(r.peak_progress_deg, progress);
    r.min_progress_deg = std::min(r.min_progress_deg, progress);
  });
  r.final_progress_deg = progress;
  return r;
}

TEST(P2osEmulatorHeading, HeadStopsOnTheTargetWithoutOvershoot) {
  // The P3-DX defaults (RotAccel/RotDecel 100 deg/s^2) and the brisk test robot (400).
  for (const EmulatorConfig& config : {EmulatorConfig{}, test::fast_emulator_config()}) {
    RawClient c(config);
    c.open_session();
    double heading = 0;
    for (const double target : {90.0, 0.0, -90.0, 45.0, -135.0, 180.0, 170.0, -175.0, 10.0, 11.0}) {
      double delta = std::remainder(target - heading, 360.0);
      if (delta == -180.0) delta = 180.0;  // headings wrap to (-180, 180]: an about-turn goes left
      const TurnResult r = turn(c, encode_command_int(Command::head, static_cast<std::int32_t>(target)), delta);
      SCOPED_TRACE(::testing::Message() << "HEAD " << target << " from " << heading << ", decel "
                                        << config.rot_decel_deg_s2);
      EXPECT_LE(r.peak_progress_deg, std::fabs(delta) + 0.5);
      EXPECT_NEAR(r.final_progress_deg, std::fabs(delta), 0.2);
      EXPECT_GE(r.min_progress_deg, -0.01);  // never starts the wrong way
      EXPECT_NEAR(std::remainder(c.odometry_heading_deg() - target, 360.0), 0.0, 0.2);
      EXPECT_EQ(c.emulator.omega_rad_s(), 0.0);
      heading = target;
    }
  }
}

TEST(P2osEmulatorHeading, DheadTurnsByTheAngleWithoutOvershoot) {
  RawClient c(EmulatorConfig{});
  c.open_session();
  for (const double delta : {90.0, -90.0, 30.0, -170.0}) {
    const double start = c.odometry_heading_deg();
    const TurnResult r = turn(c, encode_command_int(Command::dhead, static_cast<std::int32_t>(delta)), delta);
    SCOPED_TRACE(::testing::Message() << "DHEAD " << delta);
    EXPECT_LE(r.peak_progress_deg, std::fabs(delta) + 0.5);
    EXPECT_NEAR(r.final_progress_deg, std::fabs(delta), 0.2);
    EXPECT_NEAR(std::remainder(c.odometry_heading_deg() - start - delta, 360.0), 0.0, 0.2);
  }
  // The robot came to rest: stopped SIPs again.
  const std::size_t from = c.received.size();
  c.run_pulsing(hal::millis(500));
  const std::vector<Sip> sips = c.sips_since(from);
  ASSERT_FALSE(sips.empty());
  EXPECT_FALSE(sips.back().moving);
}

// ---- Watchdog ----

// Drives, then falls silent long enough for the watchdog.
void drive_then_die(RawClient& c) {
  c.open_session();
  c.send(encode_command_int(Command::vel, 300));
  c.send(encode_command_int(Command::rvel, 15));
  c.run_pulsing(hal::seconds(1));
  ASSERT_NEAR(c.emulator.velocity_m_s(), 0.3, 1e-9);
  c.run(hal::seconds(3));  // the client died
  ASSERT_TRUE(c.emulator.watchdog_tripped());
  ASSERT_EQ(c.emulator.velocity_m_s(), 0.0);
  ASSERT_EQ(c.emulator.omega_rad_s(), 0.0);
}

TEST(P2osEmulatorWatchdog, PulseAfterAWatchdogStopDoesNotResume) {
  RawClient c;
  drive_then_die(c);
  const std::size_t from = c.received.size();
  c.run_pulsing(hal::seconds(2));
  EXPECT_FALSE(c.emulator.watchdog_tripped());
  EXPECT_EQ(c.emulator.velocity_m_s(), 0.0);
  EXPECT_EQ(c.emulator.omega_rad_s(), 0.0);
  for (const Sip& s : c.sips_since(from)) EXPECT_FALSE(s.moving);
  // A fresh motion command moves it again, and only as far as that command says.
  c.send(encode_command_int(Command::vel, 200));
  c.run_pulsing(hal::seconds(1));
  EXPECT_NEAR(c.emulator.velocity_m_s(), 0.2, 1e-9);
  EXPECT_EQ(c.emulator.omega_rad_s(), 0.0);  // the dead client's RVEL 15 is gone
  EXPECT_EQ(c.emulator.stats().watchdog_stops, 1u);
}

TEST(P2osEmulatorWatchdog, AriaReconnectAfterADeadClientFindsAStoppedRobotAndClosesIt) {
  RawClient c;
  drive_then_die(c);
  const Pose2 stopped_at = c.emulator.ground_truth();
  // ARIA's connect: SYNC0, and a stopped SIP (0x32) in answer means "still open": CLOSE 1,
  // then the handshake again.
  std::size_t from = c.received.size();
  c.exchange(encode_command(Command::sync0));
  c.run(hal::millis(300));
  std::vector<Sip> sips = c.sips_since(from);
  ASSERT_FALSE(sips.empty());
  EXPECT_EQ(c.received[from].type, kTypeSipStopped);
  for (const Sip& s : sips) EXPECT_FALSE(s.moving);
  c.exchange(encode_command_int(kClose, 1));
  EXPECT_EQ(c.emulator.state(), EmulatorState::sync_wait);
  from = c.received.size();
  c.open_session(false);
  ASSERT_GE(c.received.size(), from + 3);
  EXPECT_EQ(c.received[from].type, kTypeSync0);
  EXPECT_EQ(c.received[from + 1].type, kTypeSync1);
  EXPECT_EQ(c.received[from + 2].type, kTypeSync2);
  c.run_pulsing(hal::seconds(2));
  EXPECT_EQ(c.emulator.state(), EmulatorState::open);
  EXPECT_EQ(c.emulator.velocity_m_s(), 0.0);
  EXPECT_NEAR(c.emulator.ground_truth().x_m, stopped_at.x_m, 1e-12);
  EXPECT_NEAR(c.emulator.ground_truth().y_m, stopped_at.y_m, 1e-12);
}

TEST(P2osEmulatorWatchdog, ResumingAsTheArcosManualSaysRestartsOnAPulse) {
  // The opt-in ARCOS behaviour, and why it is not the default: the new client's SYNC0 (a
  // PULSE to an open robot) restarts the dead client's motion, and the SIPs say "moving".
  EmulatorConfig config = test::fast_emulator_config();
  config.watchdog_resumes = true;
  RawClient c(config);
  drive_then_die(c);
  const std::size_t from = c.received.size();
  c.exchange(encode_command(Command::sync0));
  c.run(hal::seconds(1));
  EXPECT_NEAR(c.emulator.velocity_m_s(), 0.3, 1e-9);
  const std::vector<Sip> sips = c.sips_since(from);
  ASSERT_FALSE(sips.empty());
  EXPECT_TRUE(sips.back().moving);
}

}  // namespace
}  // namespace sen3bot::p2os
