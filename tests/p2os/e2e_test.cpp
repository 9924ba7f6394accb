// Driver and emulator in real time over a real pseudo-terminal and over TCP. Bounds are
// generous (these also run under sanitizers and qemu); exact timing is tested in lockstep.
#include <gtest/gtest.h>

#include <cmath>
#include <functional>
#include <numbers>

#include "lockstep_harness.hpp"
#include "sen3bot/hal/serial.hpp"
#include "sen3bot/sim/p2os/emulator_runner.hpp"
#include "sen3bot/hal/board.hpp"
#include "sen3bot/hal/tcp.hpp"

namespace sen3bot::p2os {
namespace {

constexpr std::uint8_t cmd(Command c) { return static_cast<std::uint8_t>(c); }

EmulatorConfig quick_robot() {
  EmulatorConfig c = test::fast_emulator_config();
  // Brisker than a real P3-DX so the square takes a few seconds of wall clock.
  c.trans_accel_mm_s2 = 4000;
  c.trans_decel_mm_s2 = 4000;
  c.rot_accel_deg_s2 = 1500;
  c.rot_decel_deg_s2 = 1500;
  c.trans_acc_top_mm_s2 = 4000;
  c.rot_acc_top_deg_s2 = 1500;
  return c;
}

// Steps the driver on the monotonic clock every 2 ms until `done` or the time limit.
struct RealtimeLoop {
  P2osDriver& driver;
  hal::PosixClock clock;
  std::function<void(hal::Nanos)> planner;

  bool run_until(const std::function<bool()>& done, hal::Nanos max_ns) {
    const hal::Nanos end = clock.now() + max_ns;
    while (clock.now() < end) {
      const hal::Nanos now = clock.now();
      if (planner) planner(now);
      driver.step(now);
      if (done()) return true;
      clock.sleep_until(now + hal::millis(2));
    }
    return false;
  }
  void run_for(hal::Nanos d) {
    (void)run_until([] { return false; }, d);
  }
  void hold(double v_m_s, double omega_rad_s) {
    planner = [this, v_m_s, omega_rad_s](hal::Nanos t) { driver.set_setpoint(BaseSetpoint{v_m_s, omega_rad_s, true}, t); };
  }
};

TEST(P2osPty, ConnectEnableDriveSquareMatchesGroundTruth) {
  auto runner = PtyEmulatorRunner::start(quick_robot());
  ASSERT_TRUE(runner) << runner.error().c_str();
  auto port = hal::SerialPort::open((*runner)->slave_path(), 9600);
  ASSERT_TRUE(port) << port.error().c_str();
  P2osDriver driver{P2osConfig{}};
  RealtimeLoop loop{driver, {}, {}};
  driver.attach(**port, loop.clock.now());
  ASSERT_TRUE(loop.run_until([&] { return driver.state().link == LinkState::connected; }, hal::seconds(5)));

  test::SquareDriver square(1.0, 1.5, 4.0, 3.0, 15.0);
  loop.planner = [&](hal::Nanos t) {
    if (driver.take_new_sip()) driver.set_setpoint(square.next(driver.state()), t);
  };
  ASSERT_TRUE(loop.run_until([&] { return square.done(); }, hal::seconds(40)));
  loop.hold(0, 0);
  ASSERT_TRUE(loop.run_until([&] { return !driver.state().moving && driver.state().sip_count > 0; }, hal::seconds(5)));
  loop.run_for(hal::millis(300));  // SIPs after the robot came to rest

  const Pose2 truth = (*runner)->with_emulator([](P2osEmulator& e) { return e.ground_truth(); });
  const BaseState& s = driver.state();
  EXPECT_NEAR(s.x_m, truth.x_m, 0.003);
  EXPECT_NEAR(s.y_m, truth.y_m, 0.003);
  EXPECT_NEAR(std::remainder(s.theta_rad - truth.theta_rad, 2 * std::numbers::pi), 0.0, 0.003);
  EXPECT_LT(std::hypot(truth.x_m, truth.y_m), 0.25);
  EXPECT_NEAR(s.distance_m, 4.0, 0.4);
  EXPECT_EQ(s.bad_checksums, 0u);
  EXPECT_EQ((*runner)->with_emulator([](P2osEmulator& e) { return e.stats().bad_checksums; }), 0u);
}

TEST(P2osPty, SilenceNoiseAndVanishingDevice) {
  auto runner = PtyEmulatorRunner::start(quick_robot());
  ASSERT_TRUE(runner) << runner.error().c_str();
  PtyEmulatorRunner& emu = **runner;
  auto port = hal::SerialPort::open(emu.slave_path(), 9600);
  ASSERT_TRUE(port) << port.error().c_str();
  P2osDriver driver{P2osConfig{}};
  RealtimeLoop loop{driver, {}, {}};
  driver.attach(**port, loop.clock.now());
  ASSERT_TRUE(loop.run_until([&] { return driver.state().link == LinkState::connected; }, hal::seconds(5)));
  loop.hold(0.3, 0);
  loop.run_for(hal::millis(400));

  // The robot falls silent: reported within a second.
  emu.with_emulator([](P2osEmulator& e) { e.set_silent(true); });
  const hal::Nanos silent_at = loop.clock.now();
  ASSERT_TRUE(loop.run_until([&] { return driver.state().link != LinkState::connected; }, hal::seconds(3)));
  EXPECT_LE(loop.clock.now() - silent_at, hal::seconds(1));
  loop.run_for(hal::millis(200));
  emu.with_emulator([](P2osEmulator& e) { e.set_silent(false); });
  ASSERT_TRUE(loop.run_until([&] { return driver.state().link == LinkState::connected; }, hal::seconds(5)));
  EXPECT_EQ(driver.state().reconnects, 1u);
  // The first velocity commands after the new OPEN are zero.
  const bool zero_first = emu.with_emulator([](P2osEmulator& e) {
    long open_at = -1;
    for (std::size_t i = 0; i < e.command_log_size(); ++i)
      if (e.command_log(i).command == cmd(kOpen)) open_at = static_cast<long>(i);
    if (open_at < 0 || static_cast<std::size_t>(open_at + 2) >= e.command_log_size()) return false;
    const ReceivedCommand& a = e.command_log(static_cast<std::size_t>(open_at + 1));
    const ReceivedCommand& b = e.command_log(static_cast<std::size_t>(open_at + 2));
    return a.command == cmd(Command::vel) && a.value == 0 && b.command == cmd(Command::rvel) && b.value == 0;
  });
  EXPECT_TRUE(zero_first);

  // Noise bursts and corrupt packets: the link holds.
  for (int i = 0; i < 3; ++i) {
    emu.with_emulator([](P2osEmulator& e) {
      e.inject_noise(120);
      e.inject_bad_checksums(1);
    });
    loop.run_for(hal::millis(150));
  }
  loop.run_for(hal::millis(200));
  EXPECT_EQ(driver.state().link, LinkState::connected);
  EXPECT_EQ(driver.state().link_losses, 1u);  // only the silence
  EXPECT_GE(driver.state().bad_checksums, 3u);

  // The device disappears: an error, promptly, and no hang.
  emu.close_device();
  ASSERT_TRUE(loop.run_until([&] { return !driver.attached(); }, hal::seconds(2)));
  ASSERT_TRUE(driver.stream_error().has_value());
  EXPECT_EQ(driver.state().link, LinkState::disconnected);
}

TEST(P2osPty, ProbesTheRateThenSwitchesUpWithHostbaud) {
  // The emulator garbles everything while the pty's line rate differs from its HOST rate,
  // like a UART would. The robot is at 9600; the driver opens at 19200 and must find it.
  auto runner = PtyEmulatorRunner::start(quick_robot(), {}, PtyRunnerOptions{true});
  ASSERT_TRUE(runner) << runner.error().c_str();
  P2osConfig config;
  config.port = (*runner)->slave_path();
  config.baud = 19200;
  config.probe_bauds = true;
  config.sync_misses_per_baud = 1;
  config.sync_timeout_ms = 300;
  config.switch_to_baud = 38400;
  hal::PosixBoard board;
  auto link = board.open_link("base", hal::LinkRequest{config.port, config.baud});
  ASSERT_TRUE(link) << link.error().c_str();
  P2osDriver driver(config);
  RealtimeLoop loop{driver, {}, {}};
  driver.attach(*link->stream, loop.clock.now(), link->baud_control, link->baud);
  ASSERT_TRUE(loop.run_until([&] { return driver.state().link == LinkState::connected; }, hal::seconds(8)));
  EXPECT_EQ(driver.current_baud(), 9600u);
  // CONFIGpac says AutoBaud 2: HOSTBAUD to 38400, both ends switch, the link holds.
  ASSERT_TRUE(loop.run_until([&] { return driver.current_baud() == 38400u; }, hal::seconds(3)));
  loop.run_for(hal::seconds(1));
  EXPECT_EQ(driver.state().link, LinkState::connected);
  EXPECT_EQ(driver.state().link_losses, 0u);
  EXPECT_EQ((*runner)->with_emulator([](P2osEmulator& e) { return e.host_baud(); }), 38400u);
  const std::uint64_t sips = driver.state().sip_count;
  loop.run_for(hal::millis(500));
  EXPECT_GE(driver.state().sip_count, sips + 3);
}

// A raw client on a real socket: writes packets by hand, keeps what the robot sends.
struct SocketClient {
  static Result<SocketClient> connect(std::uint16_t port) {
    auto stream = hal::TcpStream::connect("127.0.0.1", port, 2000);
    if (!stream) return stream.error();
    return SocketClient{std::move(*stream)};
  }
  bool send(const Packet& p) {
    const Result<std::size_t> n = stream->write(p.view());
    return n && *n == p.size;
  }
  // Reads for `duration_ns` or until the robot closes the connection; true if it did.
  bool read_for(hal::Nanos duration_ns) {
    const hal::Nanos end = clock.now() + duration_ns;
    while (clock.now() < end) {
      std::uint8_t chunk[512];
      const Result<std::size_t> got = stream->read(chunk);
      if (!got) {
        closed_by_robot = got.error().code() == Errc::disconnected;
        return closed_by_robot;
      }
      if (*got == 0) {
        clock.sleep_until(clock.now() + hal::millis(1));
        continue;
      }
      parser.feed(std::span<const std::uint8_t>(chunk, *got), clock.now(), [&](const Frame& f) {
        types.push_back(f.type);
        if (auto sip = decode_sip(f)) sips.push_back(*sip);
      });
    }
    return false;
  }
  // SYNC0-2 and ARIA's OPEN 1; true if each SYNC got its own answer.
  bool open_session() {
    const std::size_t from = types.size();
    for (const Command c : {Command::sync0, Command::sync1, Command::sync2}) {
      if (!send(encode_command(c))) return false;
      (void)read_for(hal::millis(60));
    }
    const bool synced = types.size() >= from + 3 && types[from] == kTypeSync0 && types[from + 1] == kTypeSync1 &&
                        types[from + 2] == kTypeSync2;
    return synced && send(encode_command_int(kOpen, 1));
  }

  std::unique_ptr<hal::TcpStream> stream;
  hal::PosixClock clock{};
  FrameParser parser{};
  std::vector<std::uint8_t> types{};
  std::vector<Sip> sips{};
  bool closed_by_robot = false;
};

TEST(P2osTcp, CloseClosesTheConnectionAndTheNextSessionStartsFromZero) {
  auto runner = TcpEmulatorRunner::start(quick_robot(), 0);
  ASSERT_TRUE(runner) << runner.error().c_str();
  TcpEmulatorRunner& emu = **runner;
  auto first = SocketClient::connect(emu.port());
  ASSERT_TRUE(first) << first.error().c_str();
  ASSERT_TRUE(first->open_session());
  ASSERT_TRUE(first->send(encode_command_int(Command::enable, 1)));
  ASSERT_TRUE(first->send(encode_command_int(Command::vel, 400)));
  ASSERT_TRUE(first->send(encode_command_int(Command::rvel, 30)));
  for (int i = 0; i < 3; ++i) {
    ASSERT_FALSE(first->read_for(hal::millis(400)));
    ASSERT_TRUE(first->send(encode_command(kPulse)));
  }
  ASSERT_TRUE(first->send(encode_command_int(Command::vel, 0)));
  ASSERT_TRUE(first->send(encode_command_int(Command::rvel, 0)));
  ASSERT_FALSE(first->read_for(hal::millis(500)));
  ASSERT_FALSE(first->sips.empty());
  EXPECT_GT(first->sips.back().x_raw, 200);  // mm: it drove
  EXPECT_GT(first->sips.back().theta_raw, 100);
  const Pose2 truth = emu.with_emulator([](P2osEmulator& e) { return e.ground_truth(); });

  // ARIA's disconnect: the robot hangs up, promptly.
  ASSERT_TRUE(first->send(encode_command_int(Command::enable, 0)));
  ASSERT_TRUE(first->send(encode_command_int(kClose, 1)));
  const hal::Nanos closed_at = first->clock.now();
  ASSERT_TRUE(first->read_for(hal::seconds(1))) << "still connected after CLOSE";
  EXPECT_LT(first->clock.now() - closed_at, hal::millis(200));
  EXPECT_EQ(emu.connections_closed(), 1u);

  // The next connection is a new session: odometry from zero, the robot where it was.
  auto second = SocketClient::connect(emu.port());
  ASSERT_TRUE(second) << second.error().c_str();
  ASSERT_TRUE(second->open_session());
  ASSERT_FALSE(second->read_for(hal::millis(350)));
  ASSERT_FALSE(second->sips.empty());
  EXPECT_EQ(second->sips.front().x_raw, 0);
  EXPECT_EQ(second->sips.front().y_raw, 0);
  EXPECT_EQ(second->sips.front().theta_raw, 0);
  const Pose2 now = emu.with_emulator([](P2osEmulator& e) { return e.ground_truth(); });
  EXPECT_EQ(now.x_m, truth.x_m);
  EXPECT_EQ(now.y_m, truth.y_m);
  EXPECT_EQ(now.theta_rad, truth.theta_rad);
  EXPECT_EQ(emu.clients_served(), 2u);
}

TEST(P2osTcp, AWaitingClientTakesOverFromOneThatWentSilent) {
  auto runner = TcpEmulatorRunner::start(quick_robot(), 0);
  ASSERT_TRUE(runner) << runner.error().c_str();
  TcpEmulatorRunner& emu = **runner;
  auto dead = SocketClient::connect(emu.port());
  ASSERT_TRUE(dead) << dead.error().c_str();
  ASSERT_TRUE(dead->open_session());
  ASSERT_TRUE(dead->send(encode_command_int(Command::enable, 1)));
  ASSERT_TRUE(dead->send(encode_command_int(Command::vel, 300)));
  ASSERT_FALSE(dead->read_for(hal::millis(300)));
  // The first client hangs (its socket stays open); a second one keeps asking, as ARIA does.
  auto next = SocketClient::connect(emu.port());
  ASSERT_TRUE(next) << next.error().c_str();
  const hal::Nanos asked_at = next->clock.now();
  bool echoed = false;
  while (!echoed && next->clock.now() - asked_at < hal::seconds(5)) {
    ASSERT_TRUE(next->send(encode_command(Command::sync0)));
    (void)next->read_for(hal::millis(500));
    echoed = !next->types.empty() && next->types.back() == kTypeSync0;
  }
  ASSERT_TRUE(echoed) << "never taken over";
  // Taken over once the first had been silent for the 2 s watchdog time, not before.
  EXPECT_GE(next->clock.now() - asked_at, hal::millis(1500));
  EXPECT_TRUE(next->sips.empty());  // a fresh session: echoes, not "already open" SIPs
  EXPECT_TRUE(dead->read_for(hal::millis(500)));  // the silent one was hung up
  EXPECT_EQ(emu.with_emulator([](P2osEmulator& e) { return e.velocity_m_s(); }), 0.0);
  EXPECT_EQ(emu.clients_served(), 2u);
}

}  // namespace
}  // namespace sen3bot::p2os
