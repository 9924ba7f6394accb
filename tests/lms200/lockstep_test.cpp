// Driver against emulator in lockstep simulated time: every rate, variant and unit; baud
// probing; configuration written only when it differs; faults; stale data; disconnection.
#include <gtest/gtest.h>

#include <cmath>
#include <string>

#include "rig.hpp"

namespace sen3bot::lms200 {
namespace {

using testing::Rig;

Lms200Config driver_config(std::uint32_t baud, Variant v, Units u) {
  Lms200Config c;
  c.baud = baud;
  c.variant = v;
  c.units = u;
  return c;
}

// Every value of the newest scan equals the world's range, quantised (or is NaN there).
void expect_scan_matches_world(const Rig& rig, const LaserScan& scan) {
  ASSERT_GT(scan.count, 0);
  int checked = 0;
  for (std::size_t i = 0; i < scan.count; ++i) {
    const float want = testing::expected_range_m(rig.world, scan, i);
    if (std::isnan(want)) {
      EXPECT_FALSE(scan.valid(i)) << i;
      continue;
    }
    ASSERT_TRUE(scan.valid(i)) << "beam " << i;
    EXPECT_NEAR(scan.ranges_m[i], want, 1e-4) << "beam " << i;
    ++checked;
  }
  EXPECT_GT(checked, scan.count / 2);
}

struct MatrixCase {
  std::uint32_t baud;
  Variant variant;
  Units units;
};

class Lms200Matrix : public ::testing::TestWithParam<MatrixCase> {};

TEST_P(Lms200Matrix, StreamsExactRanges) {
  const MatrixCase c = GetParam();
  EmulatorOptions eo;  // power-on: 9600, 180/1, cm
  Rig rig(eo, driver_config(c.baud, c.variant, c.units));
  rig.device.start(rig.now);
  ASSERT_TRUE(rig.until_streaming()) << rig.device.last_error().c_str();
  EXPECT_EQ(rig.device.baud(), c.baud);
  EXPECT_EQ(rig.emulator.baud(), c.baud);
  EXPECT_EQ(rig.line.baud(), c.baud);
  EXPECT_EQ(rig.emulator.variant(), c.variant);
  EXPECT_EQ(rig.emulator.units(), c.units);
  // Three scans' worth at the slowest line.
  const hal::Nanos interval = rig.device.expected_scan_interval_ns();
  const std::uint64_t before = rig.device.counters().scans;
  rig.run_for(10 * interval);
  const std::uint64_t got = rig.device.counters().scans - before;
  EXPECT_GE(got, 9u);
  EXPECT_LE(got, 11u);
  const LaserScan& scan = rig.device.latest_scan();
  EXPECT_EQ(scan.count, value_count(c.variant));
  EXPECT_EQ(scan.units, static_cast<std::uint8_t>(c.units));
  EXPECT_EQ(scan.baud, c.baud);
  EXPECT_NEAR(scan.angle_min_rad, -c.variant.angle_deg / 2.0 * M_PI / 180.0, 1e-6);
  EXPECT_NEAR(scan.angle_increment_rad, c.variant.resolution_cdeg / 100.0 * M_PI / 180.0, 1e-7);
  // Stamp = last byte minus transmission time of the whole telegram.
  const std::size_t frame_bytes = 2u * scan.count + 10u;
  EXPECT_EQ(scan.received_ns - scan.stamp_ns, transmission_ns(frame_bytes, c.baud));
  expect_scan_matches_world(rig, scan);
  EXPECT_EQ(rig.device.counters().errors, 0u) << rig.device.last_error().c_str();
  EXPECT_EQ(rig.device.parser_stats().crc_errors, 0u);
}

std::vector<MatrixCase> matrix() {
  std::vector<MatrixCase> cases;
  for (std::uint32_t baud : kSupportedBauds)
    for (Variant v : {Variant{180, 100}, Variant{180, 50}, Variant{100, 100}, Variant{100, 50}, Variant{100, 25}})
      for (Units u : {Units::cm, Units::mm}) cases.push_back({baud, v, u});
  return cases;
}

std::string case_name(const ::testing::TestParamInfo<MatrixCase>& info) {
  const MatrixCase& c = info.param;
  return std::to_string(c.baud) + "_" + std::to_string(c.variant.angle_deg) + "_" +
         std::to_string(c.variant.resolution_cdeg) + "_" + std::string(to_string(c.units));
}

INSTANTIATE_TEST_SUITE_P(AllRates, Lms200Matrix, ::testing::ValuesIn(matrix()), case_name);

TEST(Lms200Lockstep, ScanRateFollowsMirrorOrLine) {
  struct Expect {
    std::uint32_t baud;
    Variant v;
    double hz;
  };
  // The brief's serial ceiling: 10 + 2N bytes at 10 bits per byte, or the mirror rate.
  const Expect cases[] = {
      {500000, {180, 100}, 75.0}, {500000, {180, 50}, 37.5}, {500000, {100, 25}, 18.75},
      // Slower lines: back-to-back telegrams, each with the newest complete scan.
      {38400, {180, 100}, 1e9 / static_cast<double>(transmission_ns(372, 38400))},  // 97 ms
      {38400, {180, 50}, 1e9 / static_cast<double>(transmission_ns(732, 38400))},   // 191 ms
      {9600, {180, 50}, 1e9 / static_cast<double>(transmission_ns(732, 9600))},     // 763 ms
  };
  for (const Expect& e : cases) {
    Rig rig(EmulatorOptions{}, driver_config(e.baud, e.v, Units::mm));
    rig.device.start(rig.now);
    ASSERT_TRUE(rig.until_streaming());
    rig.run_for(hal::seconds(1));
    const std::uint64_t before = rig.device.counters().scans;
    rig.run_for(hal::seconds(8));
    const double hz = static_cast<double>(rig.device.counters().scans - before) / 8.0;
    EXPECT_NEAR(hz, e.hz, e.hz * 0.06 + 0.15) << e.baud << " " << e.v.angle_deg << "/" << e.v.resolution_cdeg;
  }
}

TEST(Lms200Lockstep, ProbesAScannerLeftAtAnotherRate) {
  EmulatorOptions eo;
  eo.initial_baud = 38400;
  Rig rig(eo, driver_config(500000, {180, 50}, Units::cm));
  rig.device.start(rig.now);
  ASSERT_TRUE(rig.until_streaming()) << rig.device.last_error().c_str();
  EXPECT_EQ(rig.device.baud(), 500000u);
  // Tried 500000 (configured), 9600 and 19200 before finding 38400.
  EXPECT_GE(rig.emulator.counters().garbled_rx_bytes, 3u * 8u);
  EXPECT_EQ(rig.emulator.counters().baud_changes, 1u);
}

TEST(Lms200Lockstep, WithoutLineControlOnlyTheConfiguredRate) {
  EmulatorOptions eo;
  eo.initial_baud = 38400;
  Rig rig(eo, driver_config(38400, {180, 100}, Units::cm));
  Lms200Device fixed(driver_config(38400, {180, 100}, Units::cm), rig.pipe.a(), nullptr);
  fixed.start(0);
  for (int i = 0; i < 3000; ++i) {
    rig.emulator.step(rig.now);
    fixed.step(rig.now);
    rig.now += hal::millis(1);
  }
  EXPECT_EQ(fixed.phase(), Lms200Device::Phase::streaming) << fixed.last_error().c_str();
}

TEST(Lms200Lockstep, ConfigurationWrittenOnlyWhenItDiffers) {
  EmulatorOptions eo;  // cm, mode 00
  Rig rig(eo, driver_config(38400, {180, 100}, Units::mm));
  rig.device.start(rig.now);
  ASSERT_TRUE(rig.until_streaming()) << rig.device.last_error().c_str();
  EXPECT_EQ(rig.device.counters().config_writes, 1u);
  EXPECT_EQ(rig.emulator.counters().config_writes, 1u);
  EXPECT_EQ(rig.emulator.units(), Units::mm);
  // A second session (warm restart at the target rate) finds mm already set.
  Lms200Device again(driver_config(38400, {180, 100}, Units::mm), rig.pipe.a(), &rig.line);
  again.start(rig.now);
  for (int i = 0; i < 5000 && again.phase() != Lms200Device::Phase::streaming; ++i) {
    rig.emulator.step(rig.now);
    again.step(rig.now);
    rig.now += hal::millis(1);
  }
  EXPECT_EQ(again.phase(), Lms200Device::Phase::streaming) << again.last_error().c_str();
  EXPECT_EQ(again.counters().config_writes, 0u);
  EXPECT_EQ(rig.emulator.counters().config_writes, 1u);
}

TEST(Lms200Lockstep, MeasuringModeChangeAndFlags) {
  Lms200Config c = driver_config(500000, {180, 100}, Units::mm);
  c.measuring_mode = MeasuringMode::range32_field_a;
  Rig rig(EmulatorOptions{}, c);
  rig.device.start(rig.now);
  ASSERT_TRUE(rig.until_streaming()) << rig.device.last_error().c_str();
  EXPECT_EQ(rig.emulator.measuring_mode(), MeasuringMode::range32_field_a);
  rig.run_for(hal::millis(100));
  const LaserScan& s = rig.device.latest_scan();
  EXPECT_EQ(s.measuring_mode, 0x06);
  EXPECT_NEAR(s.range_max_m, 32.758f, 1e-3);
  expect_scan_matches_world(rig, s);
}

TEST(Lms200Lockstep, InvalidValuesAndDazzleAreReportedNotDistances) {
  Rig rig(EmulatorOptions{}, driver_config(500000, {180, 100}, Units::cm));
  rig.device.start(rig.now);
  ASSERT_TRUE(rig.until_streaming());
  FaultPlan f;
  f.invalid_values_every = 1;
  f.dazzle_every = 1;
  rig.emulator.set_faults(f);
  rig.run_for(hal::millis(100));
  const LaserScan& s = rig.device.latest_scan();
  int codes = 0;
  for (std::size_t i = 3; i < s.count; i += 10) {
    EXPECT_FALSE(s.valid(i));
    EXPECT_TRUE(std::isnan(s.ranges_m[i]));
    EXPECT_NE(s.invalid_reason[i], 0);
    ++codes;
  }
  EXPECT_EQ(codes, 18);
  for (std::size_t i = 5; i < s.count; i += 10) {
    EXPECT_TRUE(s.flags[i] & scan_flag::kDazzle);
    EXPECT_TRUE(s.valid(i));
  }
}

TEST(Lms200Lockstep, CorruptTelegramsNeverBecomeScans) {
  Rig rig(EmulatorOptions{}, driver_config(500000, {180, 50}, Units::mm));
  rig.device.start(rig.now);
  ASSERT_TRUE(rig.until_streaming());
  FaultPlan f;
  f.corrupt_crc_every = 3;
  f.truncate_every = 5;
  f.false_header_every = 4;
  f.oversize_len_every = 2;
  rig.emulator.set_faults(f);
  const std::uint64_t sent_before = rig.emulator.counters().scans_sent;
  const std::uint64_t got_before = rig.device.counters().scans;
  std::uint64_t last_seq = 0;
  for (int i = 0; i < 3000; ++i) {
    rig.step();
    const LaserScan& s = rig.device.latest_scan();
    if (s.sequence != last_seq) {
      last_seq = s.sequence;
      expect_scan_matches_world(rig, s);
    }
  }
  const std::uint64_t sent = rig.emulator.counters().scans_sent - sent_before;
  const std::uint64_t got = rig.device.counters().scans - got_before;
  // Every 3rd, 5th (and both) telegram is broken; every other one arrives.
  std::uint64_t broken = 0;
  for (std::uint64_t k = sent_before + 1; k <= sent_before + sent; ++k) broken += (k % 3 == 0 || k % 5 == 0);
  EXPECT_NEAR(static_cast<double>(got), static_cast<double>(sent - broken), 2.0);
  EXPECT_GT(rig.device.parser_stats().crc_errors, 0u);
  EXPECT_EQ(rig.device.phase(), Lms200Device::Phase::streaming);
}

TEST(Lms200Lockstep, WarmRestartFindsAScannerStillStreaming) {
  Rig rig(EmulatorOptions{}, driver_config(500000, {180, 50}, Units::mm));
  rig.device.start(rig.now);
  ASSERT_TRUE(rig.until_streaming());
  rig.run_for(hal::millis(200));
  // A new driver instance (process restart) while the scanner keeps streaming at 500000.
  Lms200Device again(driver_config(500000, {180, 50}, Units::mm), rig.pipe.a(), &rig.line);
  again.start(rig.now);
  for (int i = 0; i < 5000 && again.phase() != Lms200Device::Phase::streaming; ++i) {
    rig.emulator.step(rig.now);
    again.step(rig.now);
    rig.now += hal::millis(1);
  }
  ASSERT_EQ(again.phase(), Lms200Device::Phase::streaming) << again.last_error().c_str();
  EXPECT_EQ(again.counters().errors, 0u);
  EXPECT_EQ(again.counters().config_writes, 0u);
  for (int i = 0; i < 200; ++i) {
    rig.emulator.step(rig.now);
    again.step(rig.now);
    rig.now += hal::millis(1);
  }
  EXPECT_GE(again.counters().scans, 6u);
}

TEST(Lms200Lockstep, StaleDataRestartsTheSequence) {
  Rig rig(EmulatorOptions{}, driver_config(500000, {180, 100}, Units::cm));
  rig.device.start(rig.now);
  ASSERT_TRUE(rig.until_streaming());
  FaultPlan silent;
  silent.silent = true;
  rig.emulator.set_faults(silent);
  const hal::Nanos silenced_at = rig.now;
  ASSERT_TRUE(rig.run_until([&] { return rig.device.counters().stale_events > 0; }, hal::seconds(1)));
  // Three scan periods (13.3 ms each) plus the inter-byte allowance, to the step.
  EXPECT_LE(rig.now - silenced_at, 3 * kMirrorPeriodNs + hal::millis(37));
  EXPECT_EQ(rig.device.last_error().code(), Errc::timeout);
  // The scanner comes back (e.g. after a power cycle at 9600): the driver finds it again.
  rig.emulator.power_cycle(rig.now);
  rig.emulator.set_faults({});
  ASSERT_TRUE(rig.until_streaming()) << rig.device.last_error().c_str();
  EXPECT_GE(rig.device.counters().restarts, 1u);
  const std::uint64_t before = rig.device.counters().scans;
  rig.run_for(hal::millis(200));
  EXPECT_GT(rig.device.counters().scans, before + 10);
}

TEST(Lms200Lockstep, DeviceDisappearsErrorNotHang) {
  Rig rig(EmulatorOptions{}, driver_config(500000, {180, 100}, Units::cm));
  rig.device.start(rig.now);
  ASSERT_TRUE(rig.until_streaming());
  rig.pipe.b().disconnect();
  rig.run_for(hal::millis(50));
  EXPECT_EQ(rig.device.phase(), Lms200Device::Phase::error_wait);
  EXPECT_EQ(rig.device.last_error().code(), Errc::disconnected);
  // Restarts keep failing cleanly.
  rig.run_for(hal::seconds(3));
  EXPECT_GE(rig.device.counters().restarts, 3u);
  EXPECT_EQ(rig.device.link_state(), LinkState::error);
}

TEST(Lms200Lockstep, StatusByteOtherThan0x10IsTolerated) {
  EmulatorOptions eo;
  eo.status = 0x00;
  Rig rig(eo, driver_config(38400, {100, 100}, Units::cm));
  rig.device.start(rig.now);
  ASSERT_TRUE(rig.until_streaming()) << rig.device.last_error().c_str();
  rig.run_for(hal::millis(500));
  EXPECT_EQ(rig.device.latest_scan().status, 0x00);
}

TEST(Lms200Lockstep, HealthyScannerReportsNoFault) {
  Rig rig(EmulatorOptions{}, driver_config(38400, {180, 100}, Units::cm));
  rig.device.start(rig.now);
  ASSERT_TRUE(rig.until_streaming()) << rig.device.last_error().c_str();
  rig.run_for(hal::millis(500));
  EXPECT_EQ(rig.device.status().device_status, kDeviceStatusOk);
  EXPECT_FALSE(rig.device.scanner_fault());
  EXPECT_FALSE(rig.device.latest_scan().scanner_fault);
  EXPECT_EQ(rig.device.counters().fault_reports, 0u);
}

TEST(Lms200Lockstep, FaultAtStartUpIsSurfacedAndScansStillFlow) {
  EmulatorOptions eo;
  eo.faults.device_fault = true;
  Rig rig(eo, driver_config(38400, {180, 100}, Units::cm));
  rig.device.start(rig.now);
  ASSERT_TRUE(rig.until_streaming()) << rig.device.last_error().c_str();
  rig.run_for(hal::millis(500));
  EXPECT_EQ(rig.device.status().device_status, kDeviceStatusFault);
  EXPECT_EQ(rig.device.counters().fault_reports, 1u);
  EXPECT_TRUE(rig.device.scanner_fault());
  const LaserScan& scan = rig.device.latest_scan();
  ASSERT_GT(scan.sequence, 0u);
  EXPECT_EQ(scan.device_status, kDeviceStatusFault);
  EXPECT_EQ(status_level(scan.status), StatusLevel::error);
  EXPECT_TRUE(scan.scanner_fault);
}

TEST(Lms200Lockstep, FaultWhileStreamingShowsInTheNextScans) {
  Rig rig(EmulatorOptions{}, driver_config(500000, {180, 100}, Units::mm));
  rig.device.start(rig.now);
  ASSERT_TRUE(rig.until_streaming()) << rig.device.last_error().c_str();
  rig.run_for(hal::millis(200));
  ASSERT_FALSE(rig.device.latest_scan().scanner_fault);
  FaultPlan faults;
  faults.device_fault = true;
  rig.emulator.set_faults(faults);
  const std::uint64_t before = rig.device.latest_scan().sequence;
  rig.run_for(hal::millis(200));
  ASSERT_GT(rig.device.latest_scan().sequence, before + 5);
  // The B1 from start-up said OK; the status byte of each scan now says error.
  EXPECT_EQ(rig.device.latest_scan().device_status, kDeviceStatusOk);
  EXPECT_TRUE(rig.device.latest_scan().scanner_fault);
  EXPECT_TRUE(rig.device.scanner_fault());
  // And the fault clears with the scanner's report.
  rig.emulator.set_faults(FaultPlan{});
  rig.run_for(hal::millis(200));
  EXPECT_FALSE(rig.device.latest_scan().scanner_fault);
  EXPECT_FALSE(rig.device.scanner_fault());
}

TEST(Lms200Lockstep, MissingAckIsCountedNotFatal) {
  EmulatorOptions eo;
  eo.faults.suppress_ack = true;
  Rig rig(eo, driver_config(38400, {180, 100}, Units::cm));
  rig.device.start(rig.now);
  ASSERT_TRUE(rig.until_streaming());
  EXPECT_GE(rig.device.counters().missing_acks, 4u);
}

TEST(Lms200Lockstep, ShortConfigurationBlockAccepted) {
  EmulatorOptions eo;
  eo.short_config = true;
  Rig rig(eo, driver_config(500000, {180, 100}, Units::mm));
  rig.device.start(rig.now);
  ASSERT_TRUE(rig.until_streaming()) << rig.device.last_error().c_str();
  EXPECT_EQ(rig.device.config_block().size, kConfigBytesShort);
  EXPECT_EQ(rig.emulator.units(), Units::mm);
}

TEST(Lms200Lockstep, CleanStopLeavesTheScannerAt9600) {
  Rig rig(EmulatorOptions{}, driver_config(500000, {180, 100}, Units::cm));
  rig.device.start(rig.now);
  ASSERT_TRUE(rig.until_streaming());
  rig.run_for(hal::millis(100));
  rig.device.request_stop(rig.now);
  ASSERT_TRUE(rig.run_until([&] { return rig.device.phase() == Lms200Device::Phase::stopped; }, hal::seconds(5)));
  rig.run_for(hal::millis(10));
  EXPECT_FALSE(rig.emulator.streaming());
  EXPECT_EQ(rig.emulator.baud(), 9600u);
  EXPECT_EQ(rig.line.baud(), 9600u);
  EXPECT_EQ(rig.device.counters().errors, 0u) << rig.device.last_error().c_str();
}

TEST(Lms200Lockstep, SensorPoseMovesTheRanges) {
  Rig rig(EmulatorOptions{}, driver_config(500000, {180, 100}, Units::mm));
  rig.device.start(rig.now);
  ASSERT_TRUE(rig.until_streaming());
  rig.world.set_sensor_pose(2.0, 3.0, 0.0);
  rig.run_for(hal::millis(100));
  const LaserScan& s = rig.device.latest_scan();
  // Straight ahead (beam 90): the box's near face at x = 5.5.
  EXPECT_NEAR(s.ranges_m[90], 3.5f, 1e-4);
  // Straight left (beam 180): the wall at y = 6.
  EXPECT_NEAR(s.ranges_m[180], 3.0f, 1e-4);
  // Right (beam 0): the wall at y = 0.
  EXPECT_NEAR(s.ranges_m[0], 3.0f, 1e-4);
}

}  // namespace
}  // namespace sen3bot::lms200
