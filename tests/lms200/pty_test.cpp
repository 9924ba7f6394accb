// Driver against emulator over a real pseudo-terminal in real time: every rate including
// 500000, every variant, cm and mm, baud probing, faults, and a scanner that vanishes.
// Bounds are generous; these runs carry the `pty` label.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdlib>
#include <string>

#include "rig.hpp"
#include "sen3bot/hal/serial.hpp"
#include "sen3bot/sim/lms200/pty_runner.hpp"

namespace sen3bot::lms200 {
namespace {

struct Session {
  std::unique_ptr<Lms200PtyRunner> runner;
  std::unique_ptr<hal::SerialPort> port;
  std::unique_ptr<Lms200Device> device;
  hal::PosixClock clock;

  // Steps the driver every millisecond until pred() or the limit.
  bool run_until(const std::function<bool()>& pred, hal::Nanos limit) {
    const hal::Nanos end = clock.now() + limit;
    while (!pred() && clock.now() < end) {
      device->step(clock.now());
      clock.sleep_until(clock.now() + hal::millis(1));
    }
    return pred();
  }
};

// qemu-user cannot set rates without a Bxxx constant up to 460800 (the CI sets
// SEN3BOT_QEMU_USER when it runs the cross-built tests).
bool runtime_has_baud(std::uint32_t baud) { return std::getenv("SEN3BOT_QEMU_USER") == nullptr || baud <= 460800; }

Lms200Config pty_config(std::uint32_t baud, Variant v, Units u) {
  Lms200Config c;
  c.baud = baud;
  c.variant = v;
  c.units = u;
  c.probe_timeout_ms = 150;
  return c;
}

void open_session(Session& s, const EmulatorOptions& eo, RangeSource& world, const Lms200Config& c) {
  Result<std::unique_ptr<Lms200PtyRunner>> runner = Lms200PtyRunner::open(eo, world);
  ASSERT_TRUE(runner.ok()) << runner.error().c_str();
  s.runner = std::move(*runner);
  s.runner->start();
  Result<std::unique_ptr<hal::SerialPort>> port = hal::SerialPort::open(s.runner->slave_path(), c.baud);
  ASSERT_TRUE(port.ok()) << port.error().c_str();
  s.port = std::move(*port);
  s.device = std::make_unique<Lms200Device>(c, *s.port, s.port.get());
  s.device->start(s.clock.now());
}

void expect_matches_world(const WallWorld& world, const LaserScan& scan) {
  int valid = 0;
  for (std::size_t i = 0; i < scan.count; ++i) {
    const float want = testing::expected_range_m(world, scan, i);
    if (std::isnan(want)) continue;
    ASSERT_TRUE(scan.valid(i)) << i;
    EXPECT_NEAR(scan.ranges_m[i], want, 1e-4) << i;
    ++valid;
  }
  EXPECT_GT(valid, scan.count / 2);
}

struct PtyCase {
  std::uint32_t baud;
  Variant variant;
  Units units;
};

class Lms200Pty : public ::testing::TestWithParam<PtyCase> {};

TEST_P(Lms200Pty, StreamsOverARealPty) {
  const PtyCase c = GetParam();
  if (!runtime_has_baud(c.baud)) GTEST_SKIP() << "qemu-user cannot translate " << c.baud << " baud";
  WallWorld world = testing::test_world();
  Session s;
  open_session(s, EmulatorOptions{}, world, pty_config(c.baud, c.variant, c.units));
  ASSERT_TRUE(s.run_until([&] { return s.device->phase() == Lms200Device::Phase::streaming; }, hal::seconds(40)))
      << s.device->phase_name() << ": " << s.device->last_error().c_str();
  ASSERT_TRUE(s.run_until([&] { return s.device->counters().scans >= 4; }, hal::seconds(40)));
  auto baud = s.port->baud();
  ASSERT_TRUE(baud.ok());
  EXPECT_EQ(*baud, c.baud);
  const LaserScan& scan = s.device->latest_scan();
  EXPECT_EQ(scan.count, value_count(c.variant));
  EXPECT_EQ(scan.units, static_cast<std::uint8_t>(c.units));
  expect_matches_world(world, scan);
  EXPECT_EQ(s.device->counters().errors, 0u) << s.device->last_error().c_str();
  EXPECT_EQ(s.device->parser_stats().crc_errors, 0u);
}

std::string pty_name(const ::testing::TestParamInfo<PtyCase>& info) {
  const PtyCase& c = info.param;
  return std::to_string(c.baud) + "_" + std::to_string(c.variant.angle_deg) + "_" +
         std::to_string(c.variant.resolution_cdeg) + "_" + std::string(to_string(c.units));
}

INSTANTIATE_TEST_SUITE_P(
    Rates, Lms200Pty,
    ::testing::Values(PtyCase{9600, {100, 100}, Units::cm}, PtyCase{19200, {100, 50}, Units::mm},
                      PtyCase{38400, {180, 100}, Units::mm}, PtyCase{500000, {180, 100}, Units::cm},
                      PtyCase{500000, {180, 50}, Units::mm}, PtyCase{500000, {100, 100}, Units::mm},
                      PtyCase{500000, {100, 50}, Units::cm}, PtyCase{500000, {100, 25}, Units::mm}),
    pty_name);

TEST(Lms200PtyProbe, FindsAScannerLeftAt38400AndMovesItTo500000) {
  if (!runtime_has_baud(500000)) GTEST_SKIP() << "qemu-user cannot translate 500000 baud";
  WallWorld world = testing::test_world();
  EmulatorOptions eo;
  eo.initial_baud = 38400;
  Session s;
  open_session(s, eo, world, pty_config(500000, {180, 50}, Units::mm));
  ASSERT_TRUE(s.run_until([&] { return s.device->counters().scans >= 3; }, hal::seconds(40)))
      << s.device->phase_name() << ": " << s.device->last_error().c_str();
  EXPECT_EQ(s.device->baud(), 500000u);
  std::uint64_t garbled = 0;
  s.runner->with_emulator([&](Lms200Emulator& e) { garbled = e.counters().garbled_rx_bytes; });
  EXPECT_GT(garbled, 0u);  // the wrong-rate probes arrived as garbage
}

TEST(Lms200PtyFaults, CorruptTelegramsAtFullRate) {
  if (!runtime_has_baud(500000)) GTEST_SKIP() << "qemu-user cannot translate 500000 baud";
  WallWorld world = testing::test_world();
  EmulatorOptions eo;
  eo.faults.corrupt_crc_every = 3;
  eo.faults.false_header_every = 4;
  eo.faults.truncate_every = 7;
  Session s;
  open_session(s, eo, world, pty_config(500000, {180, 50}, Units::mm));
  ASSERT_TRUE(s.run_until([&] { return s.device->counters().scans >= 20; }, hal::seconds(40)))
      << s.device->phase_name() << ": " << s.device->last_error().c_str();
  EXPECT_GT(s.device->parser_stats().crc_errors, 0u);
  expect_matches_world(world, s.device->latest_scan());
}

TEST(Lms200PtyVanish, ScannerDisappearsErrorNoHang) {
  WallWorld world = testing::test_world();
  Session s;
  open_session(s, EmulatorOptions{}, world, pty_config(38400, {180, 100}, Units::cm));
  ASSERT_TRUE(s.run_until([&] { return s.device->counters().scans >= 3; }, hal::seconds(40)));
  s.runner.reset();  // master closed: the slave reads EIO
  const auto t0 = s.clock.now();
  ASSERT_TRUE(s.run_until([&] { return s.device->has_error() && s.device->link_state() == LinkState::error; },
                          hal::seconds(5)));
  EXPECT_LT(s.clock.now() - t0, hal::seconds(4));
  EXPECT_TRUE(s.device->last_error().code() == Errc::disconnected || s.device->last_error().code() == Errc::timeout)
      << s.device->last_error().c_str();
  // Keeps running (restarting, failing) without crashing or blocking.
  s.run_until([] { return false; }, hal::millis(1500));
  EXPECT_EQ(s.device->link_state(), LinkState::error);
}

}  // namespace
}  // namespace sen3bot::lms200
