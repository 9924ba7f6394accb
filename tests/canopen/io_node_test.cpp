#include <gtest/gtest.h>

#include <array>
#include <cstdint>
#include <string_view>

#include "sen3bot/canopen/io_node.hpp"
#include "sen3bot/sim/canopen/io_node_emulator.hpp"

namespace sen3bot::canopen {
namespace {

constexpr hal::Nanos kMs = 1'000'000;

// The master and the emulated node on one bus, in 10 ms lockstep cycles: each cycle the
// master's frames reach the node and the node's reach the master.
struct Bus {
  explicit Bus(IoNodeConfig master_config = {}, IoNodeEmulatorConfig node_config = {})
      : master(master_config), node(node_config) {}
  IoNodeMaster master;
  IoNodeEmulator node;
  hal::Nanos now = 0;
  std::uint64_t frames = 0;

  void cycle() {
    now += 10 * kMs;
    std::array<CanFrame, 4> out{};
    const std::size_t m = master.poll(now, out);
    for (std::size_t i = 0; i < m; ++i) node.on_frame(out[i], now);
    const std::size_t k = node.poll(now, out);
    for (std::size_t i = 0; i < k; ++i) master.on_frame(out[i], now);
    frames += m + k;
  }
  void run(hal::Nanos duration) {
    const hal::Nanos end = now + duration;
    while (now < end) cycle();
  }
  // Cycles until the master is in `state`, at most `limit`; the time it took.
  hal::Nanos until(IoNodeState state, hal::Nanos limit) {
    const hal::Nanos start = now;
    while (master.state() != state && now - start < limit) cycle();
    return now - start;
  }
};

TEST(IoNode, TheMasterConfiguresAndStartsANodeThatBoots) {
  Bus bus;
  bus.node.power_up(0);
  EXPECT_LT(bus.until(IoNodeState::operational, 1000 * kMs), 200 * kMs);
  EXPECT_EQ(bus.node.state(), NmtState::operational);
  EXPECT_EQ(bus.node.heartbeat_ms(), 100);  // 0x1017 written
  EXPECT_EQ(bus.master.count(IoNodeEvent::boot_up), 1u);
  EXPECT_EQ(bus.master.count(IoNodeEvent::configured), 1u);
  bus.run(100 * kMs);
  EXPECT_TRUE(bus.master.inputs_valid());  // TPDO1 at its event timer (100 ms)
  EXPECT_EQ(bus.master.inputs(), 0);
  // An input changes: the master has it within two cycles. An output: the node within two.
  bus.node.set_inputs(0x05);
  bus.run(20 * kMs);
  EXPECT_EQ(bus.master.inputs(), 0x05);
  bus.master.set_outputs(0x81);
  bus.run(20 * kMs);
  EXPECT_EQ(bus.node.outputs(), 0x81);
  // Steady state over 10 s: no event but the start's, and heartbeats keep it operational.
  bus.run(10'000 * kMs);
  EXPECT_EQ(bus.master.state(), IoNodeState::operational);
  EXPECT_EQ(bus.master.count(IoNodeEvent::heartbeat_lost), 0u);
  EXPECT_EQ(bus.master.count(IoNodeEvent::unexpected_frame), 0u);
}

TEST(IoNode, ANodeAlreadyRunningIsConfiguredFromItsHeartbeat) {
  IoNodeEmulatorConfig running;
  running.heartbeat_ms = 50;
  Bus bus({}, running);
  bus.node.power_up(0);
  // The boot-up was lost (the master was not listening yet): the heartbeats are enough.
  std::array<CanFrame, 4> out{};
  (void)bus.node.poll(0, out);
  EXPECT_LT(bus.until(IoNodeState::operational, 1000 * kMs), 300 * kMs);
  EXPECT_EQ(bus.node.heartbeat_ms(), 100);
}

TEST(IoNode, ASilentNodeIsLostAfterTheHeartbeatTimeoutAndComesBack) {
  Bus bus;
  bus.node.power_up(0);
  bus.until(IoNodeState::operational, 1000 * kMs);
  bus.run(100 * kMs);
  bus.node.set_silent(true);
  const hal::Nanos lost = bus.until(IoNodeState::lost, 2000 * kMs);
  // The last heartbeat was at most 100 ms before the cable was cut; lost 350 ms after it.
  EXPECT_GE(lost, 250 * kMs);
  EXPECT_LE(lost, 370 * kMs);
  EXPECT_FALSE(bus.master.inputs_valid());
  EXPECT_EQ(bus.master.count(IoNodeEvent::heartbeat_lost), 1u);
  // Reconnected: the next heartbeat brings configuration and start again.
  bus.node.set_silent(false);
  EXPECT_LT(bus.until(IoNodeState::operational, 2000 * kMs), 400 * kMs);
  bus.run(100 * kMs);
  EXPECT_TRUE(bus.master.inputs_valid());
  EXPECT_EQ(bus.master.count(IoNodeEvent::configured), 2u);
}

TEST(IoNode, ARebootInTheMiddleOfOperationIsNoticedAndTheOutputsComeBack) {
  Bus bus;
  bus.node.power_up(0);
  bus.until(IoNodeState::operational, 1000 * kMs);
  bus.master.set_outputs(0x03);
  bus.run(50 * kMs);
  ASSERT_EQ(bus.node.outputs(), 0x03);
  bus.node.reboot(bus.now);
  EXPECT_EQ(bus.node.outputs(), 0x00);
  bus.cycle();
  EXPECT_EQ(bus.master.state(), IoNodeState::configuring);
  EXPECT_FALSE(bus.master.inputs_valid());
  EXPECT_EQ(bus.master.count(IoNodeEvent::boot_up), 2u);
  bus.until(IoNodeState::operational, 1000 * kMs);
  bus.run(20 * kMs);
  EXPECT_EQ(bus.node.outputs(), 0x03);
}

TEST(IoNode, ANodeStoppedBySomeoneElseIsStartedAgain) {
  Bus bus;
  bus.node.power_up(0);
  bus.until(IoNodeState::operational, 1000 * kMs);
  bus.node.on_frame(*nmt(NmtCommand::stop, 0x10), bus.now);
  EXPECT_EQ(bus.node.state(), NmtState::stopped);
  EXPECT_EQ(bus.until(IoNodeState::starting, 500 * kMs) <= 110 * kMs, true);
  EXPECT_LT(bus.until(IoNodeState::operational, 500 * kMs), 150 * kMs);
  EXPECT_EQ(bus.node.state(), NmtState::operational);
}

TEST(IoNode, ARefusedConfigurationIsAFaultWithItsAbortCodeAndIsRetried) {
  Bus bus;
  bus.node.refuse_write(0x6206, abort_code::kNoObject);
  bus.node.power_up(0);
  bus.until(IoNodeState::fault, 1000 * kMs);
  ASSERT_EQ(bus.master.state(), IoNodeState::fault);
  EXPECT_EQ(bus.master.count(IoNodeEvent::sdo_abort), 1u);
  EXPECT_EQ(bus.master.last_abort(), abort_code::kNoObject);
  EXPECT_EQ(bus.master.last_abort_at(), (SdoAddress{0x6206, 1}));
  EXPECT_STREQ(describe_abort(bus.master.last_abort()), "object does not exist in the object dictionary");
  // 2 s later the master resets the node's communication; this time the write is taken.
  EXPECT_LT(bus.until(IoNodeState::operational, 4000 * kMs), 2500 * kMs);
}

TEST(IoNode, ANodeThatNeverAnswersTheConfigurationTimesOut) {
  Bus bus;
  bus.node.power_up(0);
  bus.cycle();  // the boot-up reaches the master
  ASSERT_EQ(bus.master.state(), IoNodeState::configuring);
  bus.node.set_silent(true);
  bus.until(IoNodeState::fault, 1000 * kMs);
  EXPECT_EQ(bus.master.count(IoNodeEvent::sdo_timeout) + bus.master.count(IoNodeEvent::heartbeat_lost), 1u);
  EXPECT_NE(bus.master.state(), IoNodeState::operational);
}

TEST(IoNode, EmergenciesAndMalformedFramesAreCountedAndDoNotStopTheNode) {
  Bus bus;
  bus.node.power_up(0);
  bus.until(IoNodeState::operational, 1000 * kMs);
  bus.node.raise_emergency(0x8120, 0x11);
  bus.cycle();
  EXPECT_EQ(bus.master.count(IoNodeEvent::emergency), 1u);
  EXPECT_EQ(bus.master.last_emergency().code, 0x8120);
  EXPECT_STREQ(describe_emergency(bus.master.last_emergency().code), "CAN in error passive mode");
  bus.node.raise_emergency(0x0000, 0x00);
  bus.cycle();
  EXPECT_EQ(bus.master.count(IoNodeEvent::emergency_reset), 1u);
  bus.node.send_malformed();
  bus.cycle();
  EXPECT_EQ(bus.master.count(IoNodeEvent::unexpected_frame), 2u);
  EXPECT_EQ(bus.master.state(), IoNodeState::operational);
  // An SDO answer nobody asked for is counted too.
  bus.master.on_frame(*sdo_download_response(0x10, {0x6200, 1}), bus.now);
  EXPECT_EQ(bus.master.count(IoNodeEvent::unexpected_frame), 3u);
  // Another node's frames are none of this master's business.
  bus.master.on_frame(*heartbeat(0x11, NmtState::boot_up), bus.now);
  EXPECT_EQ(bus.master.count(IoNodeEvent::boot_up), 1u);
}

TEST(IoNode, TheNodesOutputsTakeTheirErrorValuesWhenItLosesTheMaster) {
  IoNodeConfig config;
  config.outputs_error_mode = 0x0F;   // the low four switch on an error
  config.outputs_error_value = 0x01;  // output 1 on (the warning light), 2-4 off
  Bus bus(config);
  bus.node.power_up(0);
  bus.until(IoNodeState::operational, 1000 * kMs);
  bus.master.set_outputs(0xF6);
  bus.run(20 * kMs);
  bus.node.communication_error();
  EXPECT_EQ(bus.node.outputs(), 0xF1);
}

TEST(IoNode, BadConfigurationsAreRefusedWithTheReason) {
  EXPECT_TRUE(IoNodeMaster::check({}));
  IoNodeConfig c;
  c.node = 0;
  EXPECT_FALSE(IoNodeMaster::check(c));
  c = {};
  c.heartbeat_timeout_s = 0.1;  // not longer than the 100 ms period
  const Status s = IoNodeMaster::check(c);
  ASSERT_FALSE(s);
  EXPECT_NE(s.error().message().find("longer than its period"), std::string_view::npos) << s.error().message();
  c = {};
  c.sdo_timeout_s = 0.0;
  EXPECT_FALSE(IoNodeMaster::check(c));
}

}  // namespace
}  // namespace sen3bot::canopen
