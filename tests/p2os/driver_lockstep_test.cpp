// Driver against the emulator over an in-memory pipe in simulated time: handshake, square
// drive against ground truth, keep-alive, timeouts, faults, reconnects, shutdown.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <numbers>

#include "lockstep_harness.hpp"
#include "sen3bot/p2os/sonar.hpp"

namespace sen3bot::p2os {
namespace {

using test::Lockstep;

constexpr std::uint8_t cmd(Command c) { return static_cast<std::uint8_t>(c); }

// Index of the last logged command `c` (or -1).
long last_index_of(const P2osEmulator& emu, std::uint8_t c) {
  for (long i = static_cast<long>(emu.command_log_size()) - 1; i >= 0; --i)
    if (emu.command_log(static_cast<std::size_t>(i)).command == c) return i;
  return -1;
}

void drive_square(Lockstep& h, double side_m) {
  test::SquareDriver square(side_m, 0.5, 1.5);
  h.planner = [&](hal::Nanos t) {
    if (h.driver.take_new_sip()) h.driver.set_setpoint(square.next(h.driver.state()), t);
  };
  ASSERT_TRUE(h.run_until([&] { return square.done(); }, hal::seconds(60)));
  h.hold(0, 0);
  h.run_for(hal::seconds(2));  // come to rest, let a few SIPs report the final pose
}

TEST(P2osLockstep, HandshakeOrderAndIdentity) {
  Lockstep h;
  ASSERT_TRUE(h.connect(hal::seconds(1)));
  const P2osEmulator& emu = h.emulator;
  ASSERT_GE(emu.command_log_size(), 7u);
  EXPECT_EQ(emu.command_log(0).command, cmd(Command::sync0));
  EXPECT_EQ(emu.command_log(1).command, cmd(Command::sync1));
  EXPECT_EQ(emu.command_log(2).command, cmd(Command::sync2));
  EXPECT_EQ(emu.command_log(3).command, cmd(kOpen));
  // Zero velocity before anything else after OPEN.
  EXPECT_EQ(emu.command_log(4).command, cmd(Command::vel));
  EXPECT_EQ(emu.command_log(4).value, 0);
  EXPECT_EQ(emu.command_log(5).command, cmd(Command::rvel));
  EXPECT_EQ(emu.command_log(5).value, 0);
  EXPECT_EQ(emu.command_log(6).command, cmd(Command::config));
  EXPECT_STREQ(h.driver.robot_identity().name.data(), "Sen3Bot");
  EXPECT_STREQ(h.driver.robot_identity().subclass.data(), "p3dx-sh");
  h.run_for(hal::millis(300));
  ASSERT_TRUE(h.driver.robot_config().has_value());
  EXPECT_EQ(h.driver.robot_config()->watchdog_ms, 2000);
  // Motors stay off until someone asks for them.
  EXPECT_FALSE(h.driver.state().motors_enabled);
  EXPECT_EQ(emu.stats().bad_checksums, 0u);
  EXPECT_LT(h.driver.last_connect_duration_ns(), hal::millis(200));  // handshake + first SIP
}

TEST(P2osLockstep, EnableAndDriveOneMetreSquareMatchesGroundTruth) {
  Lockstep h;
  ASSERT_TRUE(h.connect());
  drive_square(h, 1.0);
  const BaseState& s = h.driver.state();
  const Pose2 truth = h.emulator.ground_truth();
  EXPECT_TRUE(s.motors_enabled);
  // SIPs carry whole mm and 4096ths of a turn.
  EXPECT_NEAR(s.x_m, truth.x_m, 0.002);
  EXPECT_NEAR(s.y_m, truth.y_m, 0.002);
  EXPECT_NEAR(std::remainder(s.theta_rad - truth.theta_rad, 2 * std::numbers::pi), 0.0, 0.002);
  // It really was a square: back near the start, about 4 m driven.
  EXPECT_LT(std::hypot(truth.x_m, truth.y_m), 0.1);
  EXPECT_NEAR(s.distance_m, 4.0, 0.15);
  EXPECT_EQ(h.emulator.stats().bad_checksums, 0u);
  EXPECT_EQ(s.bad_checksums, 0u);
  EXPECT_EQ(s.link_losses, 0u);
  EXPECT_EQ(h.emulator.stats().watchdog_stops, 0u);
}

TEST(P2osLockstep, SetsTheConfiguredBrakingDecelerationAfterOpen) {
  // The safety filter sizes its stop zone with this deceleration: the robot must brake so.
  P2osConfig config;
  config.trans_decel_mm_s2 = 600;
  Lockstep h(config);
  ASSERT_TRUE(h.connect());
  bool seta = false;
  for (std::size_t i = 0; i < h.emulator.command_log_size(); ++i) {
    const ReceivedCommand& c = h.emulator.command_log(i);
    if (c.command == static_cast<std::uint8_t>(Command::seta)) seta = c.value == -600;
  }
  EXPECT_TRUE(seta);
  // From 0.5 m/s, braking at 0.6 m/s^2 takes 0.83 s; at the P3-DX's own 0.3 m/s^2 it would take
  // twice that.
  h.hold(0.5, 0.0);
  h.run_for(hal::seconds(3));
  ASSERT_NEAR(h.emulator.velocity_m_s(), 0.5, 1e-6);
  h.hold(0.0, 0.0);
  h.run_for(hal::millis(950));
  EXPECT_NEAR(h.emulator.velocity_m_s(), 0.0, 1e-6);
}

TEST(P2osLockstep, KeepAliveWhileIdleNeverTripsWatchdog) {
  Lockstep h;
  ASSERT_TRUE(h.connect());
  const std::uint64_t before = h.emulator.command_log_total();
  h.run_for(hal::seconds(6));
  EXPECT_EQ(h.emulator.stats().watchdog_stops, 0u);
  // PULSE at least every 500 ms (plus one pacing slot).
  const std::uint64_t pulses = h.emulator.stats().command_counts[0];
  EXPECT_GE(pulses, 11u);
  EXPECT_GT(h.emulator.command_log_total(), before);
  for (std::size_t i = 1; i < h.emulator.command_log_size(); ++i) {
    const hal::Nanos gap = h.emulator.command_log(i).t_ns - h.emulator.command_log(i - 1).t_ns;
    EXPECT_LE(gap, hal::millis(510));
  }
}

TEST(P2osLockstep, ActiveSetpointRefreshedEvery500ms) {
  Lockstep h;
  ASSERT_TRUE(h.connect());
  // RVEL carries whole degrees per second: ask for exactly 6 deg/s.
  const double omega_rad_s = 6.0 * std::numbers::pi / 180.0;
  h.hold(0.2, omega_rad_s);
  h.run_for(hal::seconds(4));
  hal::Nanos last_vel = 0;
  int vels = 0;
  for (std::size_t i = 0; i < h.emulator.command_log_size(); ++i) {
    const ReceivedCommand& c = h.emulator.command_log(i);
    if (c.command != cmd(Command::vel) || c.value != 200) continue;
    if (last_vel != 0) {
      EXPECT_LE(c.t_ns - last_vel, hal::millis(510));
    }
    last_vel = c.t_ns;
    ++vels;
  }
  EXPECT_GE(vels, 7);
  EXPECT_NEAR(h.emulator.velocity_m_s(), 0.2, 1e-9);
  EXPECT_NEAR(h.driver.state().v_m_s, 0.2, 0.002);
  EXPECT_NEAR(h.driver.state().omega_rad_s, omega_rad_s, 0.002);
}

TEST(P2osLockstep, PlannerSilenceStopsTheRobot) {
  Lockstep h;
  ASSERT_TRUE(h.connect());
  h.hold(0.4, 0);
  h.run_for(hal::seconds(2));
  EXPECT_NEAR(h.emulator.velocity_m_s(), 0.4, 1e-6);
  h.planner = nullptr;  // the planner hangs
  const hal::Nanos hung_at = h.now_ns;
  ASSERT_TRUE(h.run_until([&] { return h.driver.state().command_timed_out; }, hal::seconds(2)));
  EXPECT_LE(h.now_ns - hung_at, hal::millis(700));
  ASSERT_TRUE(h.run_until([&] { return h.emulator.velocity_m_s() == 0.0; }, hal::seconds(2)));
  EXPECT_EQ(h.driver.state().command_timeouts, 1u);
  // Link and keep-alive carry on.
  h.run_for(hal::seconds(3));
  EXPECT_EQ(h.driver.state().link, LinkState::connected);
  EXPECT_EQ(h.emulator.stats().watchdog_stops, 0u);
}

TEST(P2osLockstep, SilentRobotReportedWithinOneSecondThenReconnectsZeroFirst) {
  Lockstep h;
  ASSERT_TRUE(h.connect());
  h.hold(0.3, 0);
  h.run_for(hal::seconds(2));
  h.emulator.set_silent(true);
  const hal::Nanos silent_at = h.now_ns;
  ASSERT_TRUE(h.run_until([&] { return h.driver.state().link != LinkState::connected; }, hal::seconds(2)));
  EXPECT_LE(h.now_ns - silent_at, hal::seconds(1));
  EXPECT_EQ(h.driver.state().link_losses, 1u);
  h.run_for(hal::seconds(3));  // the robot's watchdog stops it meanwhile
  EXPECT_TRUE(h.emulator.watchdog_tripped());
  EXPECT_EQ(h.emulator.velocity_m_s(), 0.0);
  const std::uint64_t sessions = h.emulator.stats().sessions_opened;
  h.emulator.set_silent(false);
  ASSERT_TRUE(h.connect(hal::seconds(5)));
  EXPECT_EQ(h.driver.state().reconnects, 1u);
  EXPECT_EQ(h.emulator.stats().sessions_opened, sessions + 1);
  // Still open when we came back: SIPs instead of an echo, so we closed it first.
  // After the new OPEN the first velocity commands are zero.
  const long open_at = last_index_of(h.emulator, cmd(kOpen));
  ASSERT_GE(open_at, 0);
  ASSERT_LT(static_cast<std::size_t>(open_at + 2), h.emulator.command_log_size());
  EXPECT_EQ(h.emulator.command_log(static_cast<std::size_t>(open_at + 1)).command, cmd(Command::vel));
  EXPECT_EQ(h.emulator.command_log(static_cast<std::size_t>(open_at + 1)).value, 0);
  EXPECT_EQ(h.emulator.command_log(static_cast<std::size_t>(open_at + 2)).command, cmd(Command::rvel));
  EXPECT_EQ(h.emulator.command_log(static_cast<std::size_t>(open_at + 2)).value, 0);
  // The planner still asks for 0.3 m/s, so the robot drives again, now on a fresh session.
  h.run_for(hal::seconds(2));
  EXPECT_NEAR(h.emulator.velocity_m_s(), 0.3, 1e-6);
}

TEST(P2osLockstep, NoiseBadChecksumsAndTruncationsAreSurvived) {
  Lockstep h;
  ASSERT_TRUE(h.connect());
  h.hold(0.25, 0.2);
  for (int burst = 0; burst < 5; ++burst) {
    h.run_for(hal::millis(400));
    h.emulator.inject_noise(150);
    h.run_for(hal::millis(150));
    h.emulator.inject_bad_checksums(2);
    h.run_for(hal::millis(250));
    h.emulator.inject_truncations(1);
  }
  h.run_for(hal::seconds(1));
  const BaseState& s = h.driver.state();
  EXPECT_EQ(s.link, LinkState::connected);
  EXPECT_EQ(s.link_losses, 0u);
  EXPECT_GE(s.bad_checksums, 10u);
  h.hold(0, 0);
  h.run_for(hal::seconds(2));
  const Pose2 truth = h.emulator.ground_truth();
  EXPECT_NEAR(h.driver.state().x_m, truth.x_m, 0.002);
  EXPECT_NEAR(h.driver.state().y_m, truth.y_m, 0.002);
}

TEST(P2osLockstep, FewDroppedSipsTolerated_ManyMeanLinkLoss) {
  Lockstep h;
  ASSERT_TRUE(h.connect());
  h.emulator.drop_sips(4);  // 500 ms without SIPs: under the 600 ms link timeout
  h.run_for(hal::seconds(1));
  EXPECT_EQ(h.driver.state().link_losses, 0u);
  h.emulator.drop_sips(8);
  h.run_for(hal::seconds(1));
  EXPECT_EQ(h.driver.state().link_losses, 1u);
  ASSERT_TRUE(h.connect());
}

TEST(P2osLockstep, AlreadyOpenRobotIsClosedAndReopened) {
  Lockstep first;
  ASSERT_TRUE(first.connect());
  // A second client on the same robot (the first vanished without CLOSE).
  P2osDriver second{P2osConfig{}};
  first.driver.detach();
  second.attach(first.pipe.a(), first.now_ns);
  bool ok = false;
  for (int i = 0; i < 2000 && !ok; ++i) {
    (void)first.emulator.step(first.pipe.b(), first.now_ns);
    second.step(first.now_ns);
    first.now_ns += Lockstep::kStepNs;
    ok = second.state().link == LinkState::connected;
  }
  ASSERT_TRUE(ok);
  EXPECT_EQ(first.emulator.stats().sessions_opened, 2u);
  EXPECT_GE(first.emulator.stats().command_counts[cmd(kClose)], 1u);
}

TEST(P2osLockstep, ControllerResetPacketCausesResync) {
  Lockstep h;
  ASSERT_TRUE(h.connect());
  h.emulator.inject_reset();
  h.run_for(hal::millis(50));
  EXPECT_EQ(h.driver.state().link_losses, 1u);
  ASSERT_TRUE(h.connect());
  EXPECT_EQ(h.driver.state().reconnects, 1u);
}

TEST(P2osLockstep, StallEstopAndBumpersReported) {
  Lockstep h;
  ASSERT_TRUE(h.connect());
  h.hold(0.3, 0);
  h.run_for(hal::seconds(1));
  h.emulator.set_stalled(true);
  h.emulator.set_bumpers(0x05, 0x02);
  const Pose2 before = h.emulator.ground_truth();
  h.run_for(hal::millis(500));
  BaseState s = h.driver.state();
  EXPECT_TRUE(s.left_stall);
  EXPECT_TRUE(s.right_stall);
  EXPECT_EQ(s.front_bumpers, 0x05);
  EXPECT_EQ(s.rear_bumpers, 0x02);
  EXPECT_EQ(h.emulator.ground_truth().x_m, before.x_m);
  h.emulator.set_stalled(false);
  h.emulator.set_bumpers(0, 0);
  h.emulator.set_estop(true);
  h.run_for(hal::millis(300));
  s = h.driver.state();
  EXPECT_TRUE(s.estop);
  EXPECT_FALSE(s.motors_enabled);
  EXPECT_FALSE(s.left_stall);
  EXPECT_EQ(s.front_bumpers, 0);
  EXPECT_EQ(h.emulator.velocity_m_s(), 0.0);
}

TEST(P2osLockstep, CleanShutdownStopsDisablesAndCloses) {
  Lockstep h;
  ASSERT_TRUE(h.connect());
  h.hold(0.3, 0);
  h.run_for(hal::seconds(1));
  h.planner = nullptr;
  h.driver.request_close(h.now_ns);
  ASSERT_TRUE(h.run_until([&] { return h.driver.closed(); }, hal::seconds(1)));
  h.run_for(hal::millis(20));
  const std::size_t n = h.emulator.command_log_size();
  ASSERT_GE(n, 4u);
  EXPECT_EQ(h.emulator.command_log(n - 4).command, cmd(Command::vel));
  EXPECT_EQ(h.emulator.command_log(n - 4).value, 0);
  EXPECT_EQ(h.emulator.command_log(n - 3).command, cmd(Command::rvel));
  EXPECT_EQ(h.emulator.command_log(n - 2).command, cmd(Command::enable));
  EXPECT_EQ(h.emulator.command_log(n - 2).value, 0);
  EXPECT_EQ(h.emulator.command_log(n - 1).command, cmd(kClose));
  EXPECT_EQ(h.emulator.state(), EmulatorState::sync_wait);
  EXPECT_FALSE(h.emulator.motors_enabled());
}

TEST(P2osLockstep, DeviceDisappearsIsAnErrorNotACrash) {
  Lockstep h;
  ASSERT_TRUE(h.connect());
  h.pipe.b().disconnect();
  h.run_for(hal::millis(50));
  EXPECT_FALSE(h.driver.attached());
  ASSERT_TRUE(h.driver.stream_error().has_value());
  EXPECT_EQ(h.driver.stream_error()->code(), Errc::disconnected);
  EXPECT_EQ(h.driver.state().link, LinkState::disconnected);
  h.run_for(hal::millis(50));  // stepping a detached driver is harmless
}

TEST(P2osLockstep, EncoderPacketsWhenRequested) {
  P2osConfig config;
  config.request_encoders = true;
  Lockstep h(config);
  ASSERT_TRUE(h.connect());
  h.hold(0.5, 0);
  h.run_for(hal::seconds(2));
  const BaseState& s = h.driver.state();
  ASSERT_TRUE(s.encoders_valid);
  // 128 ticks per mm on both wheels when driving straight.
  EXPECT_NEAR(s.left_encoder_ticks / 128.0 / 1000.0, h.emulator.ground_truth().x_m, 0.01);
  EXPECT_EQ(s.left_encoder_ticks, s.right_encoder_ticks);
}

TEST(P2osLockstep, OutOfSequenceSyncAndLenientArguments) {
  // Hand-written client traffic: garbage, SYNC1 out of order, ARIA-style OPEN with an int,
  // SETO with a bare type byte, unknown commands.
  hal::MemoryPipe pipe(4096);
  P2osEmulator emu(test::fast_emulator_config());
  hal::Nanos t = 0;
  std::vector<std::uint8_t> rx;
  auto exchange = [&](std::span<const std::uint8_t> bytes) {
    (void)pipe.a().write(bytes);
    (void)emu.step(pipe.b(), t);
    t += hal::millis(10);
    std::uint8_t buffer[512];
    auto got = pipe.a().read(buffer);
    if (got) rx.insert(rx.end(), buffer, buffer + *got);
  };
  const std::uint8_t garbage[] = {'W', 'M', 'S', '2', '\r'};
  exchange(garbage);
  exchange(encode_command(Command::sync1).view());  // out of sequence: ignored
  EXPECT_TRUE(rx.empty());
  exchange(encode_command(Command::sync0).view());
  exchange(encode_command(Command::sync1).view());
  exchange(encode_command(Command::sync2).view());
  exchange(encode_command_int(kOpen, 1).view());
  EXPECT_EQ(emu.state(), EmulatorState::open);
  const std::uint8_t seto_bare[] = {0xFA, 0xFB, 0x04, 0x07, 0x3B, 0x07, 0x3B};
  exchange(seto_bare);
  exchange(encode_command_int(Command::batteryinfo, 1).view());
  exchange(encode_command_int(Command::getaux, 5).view());
  EXPECT_EQ(emu.stats().command_counts[7], 1u);
  EXPECT_EQ(emu.state(), EmulatorState::open);
  EXPECT_EQ(emu.stats().bad_checksums, 0u);
  // Echoes and the SYNC2 reply came back byte-exact.
  FrameParser parser;
  std::vector<std::uint8_t> types;
  parser.feed(rx, t, [&](const Frame& f) { types.push_back(f.type); });
  ASSERT_GE(types.size(), 3u);
  EXPECT_EQ(types[0], 0);
  EXPECT_EQ(types[1], 1);
  EXPECT_EQ(types[2], 2);
}

TEST(P2osLockstep, WatchdogStopsAndResumesLastSetpointWhenConfiguredTo) {
  hal::MemoryPipe pipe(4096);
  EmulatorConfig config = test::fast_emulator_config();
  config.watchdog_resumes = true;  // the ARCOS manual's behaviour; not the default
  P2osEmulator emu(config);
  hal::Nanos t = 0;
  auto send = [&](const Packet& p) { (void)pipe.a().write(p.view()); };
  auto run = [&](hal::Nanos d) {
    const hal::Nanos end = t + d;
    std::uint8_t sink[1024];
    while (t < end) {
      (void)emu.step(pipe.b(), t);
      (void)pipe.a().read(sink);
      t += hal::millis(5);
    }
  };
  for (const Packet& p : {encode_command(Command::sync0), encode_command(Command::sync1), encode_command(Command::sync2),
                          encode_command(kOpen), encode_command_int(Command::enable, 1),
                          encode_command_int(Command::vel, 300)}) {
    send(p);
    run(hal::millis(10));
  }
  run(hal::seconds(1));
  EXPECT_NEAR(emu.velocity_m_s(), 0.3, 1e-9);
  run(hal::seconds(3));  // no client traffic
  EXPECT_TRUE(emu.watchdog_tripped());
  EXPECT_EQ(emu.velocity_m_s(), 0.0);
  send(encode_command(kPulse));
  run(hal::seconds(2));
  EXPECT_NEAR(emu.velocity_m_s(), 0.3, 1e-9);  // ARCOS resumes the old setpoint
}

TEST(P2osLockstep, EmulatorPositionHeadingAndWheelCommands) {
  hal::MemoryPipe pipe(4096);
  P2osEmulator emu(test::fast_emulator_config());
  hal::Nanos t = 0;
  auto run = [&](hal::Nanos d) {
    const hal::Nanos end = t + d;
    std::uint8_t sink[1024];
    while (t < end) {
      (void)emu.step(pipe.b(), t);
      (void)pipe.a().read(sink);
      t += hal::millis(5);
    }
  };
  auto send = [&](const Packet& p) {
    (void)pipe.a().write(p.view());
    run(hal::millis(10));
  };
  for (const Packet& p : {encode_command(Command::sync0), encode_command(Command::sync1), encode_command(Command::sync2),
                          encode_command(kOpen), encode_command_int(Command::enable, 1)})
    send(p);
  // MOVE: position mode, stops at the goal.
  send(encode_command_int(Command::move, 500));
  for (int i = 0; i < 8; ++i) {
    send(encode_command(kPulse));
    run(hal::millis(400));
  }
  EXPECT_NEAR(emu.ground_truth().x_m, 0.5, 0.003);
  EXPECT_EQ(emu.velocity_m_s(), 0.0);
  // HEAD: absolute heading in degrees, signed as ARIA sends it.
  send(encode_command_int(Command::head, -90));
  for (int i = 0; i < 8; ++i) {
    send(encode_command(kPulse));
    run(hal::millis(400));
  }
  EXPECT_NEAR(emu.ground_truth().theta_rad, -std::numbers::pi / 2, 0.01);
  // VEL2 as ARIA encodes it: left = right = 10 units (200 mm/s) -> packed 0x0A0A, positive.
  send(encode_command_int(Command::vel2, 0x0A0A));
  run(hal::seconds(1));
  EXPECT_NEAR(emu.velocity_m_s(), 0.2, 1e-9);
  EXPECT_NEAR(emu.omega_rad_s(), 0.0, 1e-9);
  // Left -10, right +10 units: packed -2550 goes out as 0x1B + 2550; a pure turn.
  send(encode_command_int(Command::vel2, static_cast<std::int16_t>((-10 << 8) + 10)));
  run(hal::seconds(1));
  EXPECT_NEAR(emu.velocity_m_s(), 0.0, 1e-9);
  EXPECT_NEAR(emu.omega_rad_s(), 200.0 * 0.0056, 1e-6);
}

// A link that garbles every byte unless both ends run at the same rate: lets the driver's
// baud probing and HOSTBAUD switch be tested without a UART.
class RateCheckedLink final : public hal::ByteStream, public BaudControl {
 public:
  RateCheckedLink(hal::ByteStream& inner, const P2osEmulator& robot) : inner_(inner), robot_(robot) {}
  Result<std::size_t> read(std::span<std::uint8_t> out) override {
    Result<std::size_t> got = inner_.read(out);
    if (got && !rates_match())
      for (std::size_t i = 0; i < *got; ++i) out[i] = static_cast<std::uint8_t>(out[i] * 7 + 3);
    return got;
  }
  Result<std::size_t> write(std::span<const std::uint8_t> data) override {
    if (rates_match()) return inner_.write(data);
    std::vector<std::uint8_t> garbled(data.begin(), data.end());
    for (auto& b : garbled) b = static_cast<std::uint8_t>(b ^ 0x55);
    return inner_.write(garbled);
  }
  [[nodiscard]] std::string_view name() const override { return "rate-checked"; }
  Status set_baud(std::uint32_t baud) override {
    client_baud = baud;
    return Status::success();
  }
  [[nodiscard]] bool rates_match() const {
    const bool switched = robot_follows_hostbaud && robot_.requested_host_baud() != 0;
    return (switched ? robot_.requested_host_baud() : robot_baud) == client_baud;
  }
  std::uint32_t client_baud = 9600;
  std::uint32_t robot_baud = 9600;
  bool robot_follows_hostbaud = true;  // false: a robot whose UART ignores HOSTBAUD

 private:
  hal::ByteStream& inner_;
  const P2osEmulator& robot_;
};

TEST(P2osLockstep, ProbesBaudRatesUntilTheRobotAnswers) {
  P2osConfig config;
  config.probe_bauds = true;
  Lockstep h(config);
  RateCheckedLink link(h.pipe.a(), h.emulator);
  link.robot_baud = 19200;  // third in the probe order
  h.driver.attach(link, h.now_ns, &link, 9600);
  ASSERT_TRUE(h.connect(hal::seconds(10)));
  EXPECT_EQ(h.driver.current_baud(), 19200u);
}

TEST(P2osLockstep, SwitchesUpWithHostbaud) {
  P2osConfig config;
  config.switch_to_baud = 38400;
  Lockstep h(config);
  RateCheckedLink link(h.pipe.a(), h.emulator);
  h.driver.attach(link, h.now_ns, &link, 9600);
  ASSERT_TRUE(h.connect());
  h.run_for(hal::seconds(2));
  EXPECT_EQ(h.emulator.requested_host_baud(), 38400u);
  EXPECT_EQ(h.driver.current_baud(), 38400u);
  EXPECT_EQ(h.driver.state().link, LinkState::connected);
  EXPECT_EQ(h.driver.state().link_losses, 0u);
}

TEST(P2osLockstep, RevertsWhenTheRobotStaysSilentAfterHostbaud) {
  P2osConfig config;
  config.switch_to_baud = 38400;
  Lockstep h(config);
  RateCheckedLink link(h.pipe.a(), h.emulator);
  link.robot_follows_hostbaud = false;
  h.driver.attach(link, h.now_ns, &link, 9600);
  ASSERT_TRUE(h.connect());
  ASSERT_TRUE(h.run_until([&] { return h.driver.current_baud() == 38400u; }, hal::seconds(2)));
  const hal::Nanos switched_at = h.now_ns;
  ASSERT_TRUE(h.run_until([&] { return h.driver.current_baud() == 9600u; }, hal::seconds(2)));
  EXPECT_NEAR(hal::to_seconds(h.now_ns - switched_at), 0.9, 0.02);
  const std::uint64_t sips = h.driver.state().sip_count;
  h.run_for(hal::seconds(1));
  EXPECT_GE(h.driver.state().sip_count, sips + 9);
  EXPECT_EQ(h.driver.state().link, LinkState::connected);
  EXPECT_EQ(h.driver.state().link_losses, 0u);
  EXPECT_EQ(link.client_baud, 9600u);
}

// ---- The task wrapper ----

}  // namespace
}  // namespace sen3bot::p2os

namespace sen3bot::p2os {
namespace {

// A wall across the world at x = wall_x (the robot starts at the origin facing +x): each ray
// returns its distance to the wall, or the range limit.
struct WallBehind final : EmulatorWorld {
  double wall_x = -1.0;
  double sonar_range_m(const Pose2& sensor, double max_range_m) override {
    const double c = std::cos(sensor.theta_rad);
    if (!(c < -1e-9)) return max_range_m;
    return std::min(max_range_m, (wall_x - sensor.x_m) / c);
  }
};

// A connected driver and emulator with the wall behind, echoes lost at miss_rate.
struct SonarBench {
  explicit SonarBench(double miss_rate) : h({}, config(miss_rate)) { h.emulator.set_world(&wall); }
  static EmulatorConfig config(double miss_rate) {
    EmulatorConfig c = test::fast_emulator_config();
    c.sonar_miss_rate = miss_rate;
    return c;
  }
  Lockstep h;
  WallBehind wall;
};

TEST(P2osLockstep, SonarFiresOneDiscPerBankPerCycleAndSeesTheWallBehind) {
  SonarBench bench(0.0);
  Lockstep& h = bench.h;
  ASSERT_TRUE(h.connect());
  // Over 32 SIPs (3.2 s, 80 cycles of 40 ms) every disc is read ten times, in disc order in
  // each bank, two or three of a bank per SIP.
  std::array<int, kSonarDiscs> reads{};
  std::array<std::uint16_t, kSonarDiscs> range_mm{};
  int sips = 0;
  int previous_front = -1;
  bool in_order = true;
  h.planner = [&](hal::Nanos) {
    if (!h.driver.take_new_sip()) return;
    const Sip& s = h.driver.last_sip();
    ++sips;
    int front = 0;
    for (std::size_t i = 0; i < s.sonar_count; ++i) {
      const SonarReading r = s.sonar[i];
      ASSERT_LT(r.disc, kSonarDiscs);
      ++reads[r.disc];
      range_mm[r.disc] = r.range_mm;
      if (r.disc < kSonarBank) {
        in_order = in_order && (previous_front < 0 || r.disc == (previous_front + 1) % kSonarBank);
        previous_front = r.disc;
        ++front;
      }
    }
    EXPECT_TRUE(front == 2 || front == 3) << front << " front readings in one SIP";
  };
  h.run_until([&] { return sips == 32; }, hal::seconds(10));
  ASSERT_EQ(sips, 32);
  EXPECT_TRUE(in_order);
  for (std::size_t d = 0; d < kSonarDiscs; ++d) EXPECT_NEAR(reads[d], 10, 1) << "disc " << d;
  // Discs 11 and 12 face 170 degrees off the heading from 0.255 m behind the centre: the wall
  // 1 m behind is (1 - 0.255) / cos(10 deg) away along their axis, a little less at the
  // cone's near edge. The front discs see nothing within 5 m.
  for (std::size_t d : {11u, 12u}) {
    const double along = (1.0 - 0.255) / std::cos(10.0 * std::numbers::pi / 180.0);
    const double edge = (1.0 - 0.255) / std::cos(2.5 * std::numbers::pi / 180.0);
    EXPECT_LE(range_mm[d], std::lround(along * 1000.0)) << "disc " << d;
    EXPECT_NEAR(range_mm[d], edge * 1000.0, 5.0) << "disc " << d;
  }
  for (std::size_t d = 0; d < kSonarBank; ++d) EXPECT_EQ(range_mm[d], 5000) << "disc " << d;
}

TEST(P2osLockstep, SonarLosesAFewEchoesAsConfigured) {
  SonarBench bench(0.1);
  Lockstep& h = bench.h;
  ASSERT_TRUE(h.connect());
  int seen = 0, lost = 0;
  h.planner = [&](hal::Nanos) {
    if (!h.driver.take_new_sip()) return;
    const Sip& s = h.driver.last_sip();
    for (std::size_t i = 0; i < s.sonar_count; ++i) {
      if (s.sonar[i].disc != 11 && s.sonar[i].disc != 12) continue;
      ++(s.sonar[i].range_mm == 5000 ? lost : seen);
    }
  };
  h.run_for(hal::seconds(60));
  const double rate = static_cast<double>(lost) / (seen + lost);
  EXPECT_GT(seen + lost, 300);
  EXPECT_NEAR(rate, 0.1, 0.05);
}

}  // namespace
}  // namespace sen3bot::p2os
