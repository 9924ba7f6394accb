// The CAN I/O task's pieces: its configuration keys and checks, the light's modes, and the
// task itself against the I/O node's emulator on an in-memory bus (the whole chain to the
// wheels is tests/sim/estop_test.cpp).
#include <gtest/gtest.h>

#include <string>

#include "can_board.hpp"
#include "can_io_task.hpp"
#include "config.hpp"
#include "sen3bot/sim/canopen/io_node_emulator.hpp"
#include "sen3bot/hal/clock.hpp"

namespace sen3bot::firmware {
namespace {

constexpr const char* kBase = R"(
robot: { name: test-bot }
run: { clock: lockstep, duration_s: 1 }
tasks: { health: { arena_bytes: 4KiB } }
devices:
  io_node:
)";

Result<FirmwareConfig> parse_io(const std::string& io_node) {
  return parse_config(std::string(kBase) + io_node, "robot.yaml");
}

TEST(CanIoConfig, ParsesEveryKey) {
  Result<FirmwareConfig> r = parse_io(R"(
    interface: can1
    node: 33
    heartbeat_ms: 50
    heartbeat_timeout_s: 0.2
    inputs_period_ms: 40
    reset_at_start: true
    inputs: { estop: 8, estop_active_low: false, reset: 7, bumpers: [1, 2], bumpers_active_low: true }
    outputs: { idle: 0, driving: 1, wait4col: 2, fault: 3, buzzer: 4, buzzer_period_s: 0.4 }
)");
  ASSERT_TRUE(r) << r.error().c_str();
  ASSERT_TRUE(r->devices.has_io_node);
  const CanIoConfig& c = r->devices.io_node;
  EXPECT_EQ(c.interface, "can1");
  EXPECT_EQ(c.master.node, 33);
  EXPECT_EQ(c.master.heartbeat_ms, 50);
  EXPECT_DOUBLE_EQ(c.master.heartbeat_timeout_s, 0.2);
  EXPECT_EQ(c.master.inputs_period_ms, 40);
  EXPECT_TRUE(c.reset_at_start);
  EXPECT_EQ(c.estop_input, 8);
  EXPECT_FALSE(c.estop_active_low);
  EXPECT_EQ(c.reset_input, 7);
  EXPECT_EQ(c.bumper_inputs, 0x03);
  EXPECT_TRUE(c.bumpers_active_low);
  EXPECT_EQ(c.light_outputs[static_cast<int>(msg::LightMode::idle)], 0);
  EXPECT_EQ(c.light_outputs[static_cast<int>(msg::LightMode::fault)], 3);
  EXPECT_EQ(c.buzzer_output, 4);
  EXPECT_DOUBLE_EQ(c.buzzer_period_s, 0.4);
}

TEST(CanIoConfig, MistakesAreNamed) {
  const auto message = [](const std::string& io) {
    Result<FirmwareConfig> r = parse_io(io);
    EXPECT_FALSE(r);
    return r ? std::string() : std::string(r.error().message());
  };
  std::string m = message("    node: 16\n");
  EXPECT_NE(m.find("devices.io_node.interface: missing"), std::string::npos) << m;
  m = message("    interface: can0\n    node: 200\n");
  EXPECT_NE(m.find("devices.io_node.node"), std::string::npos) << m;
  m = message("    interface: can0\n    node: 16\n    inputs: { estop: 1, reset: 1 }\n");
  EXPECT_NE(m.find("inputs.reset: the e-stop chain's input cannot also be the reset"), std::string::npos) << m;
  m = message("    interface: can0\n    node: 16\n    inputs: { bumpers: [1] }\n");
  EXPECT_NE(m.find("inputs.bumpers"), std::string::npos) << m;
  m = message("    interface: can0\n    node: 16\n    outputs: { idle: 2, driving: 2 }\n");
  EXPECT_NE(m.find("output 2 is used twice"), std::string::npos) << m;
  m = message("    interface: can0\n    node: 16\n    heartbeat_ms: 500\n    heartbeat_timeout_s: 0.3\n");
  EXPECT_NE(m.find("devices.io_node"), std::string::npos) << m;
  m = message("    interface: can0\n    node: 16\n    colour: red\n");
  EXPECT_NE(m.find("unknown key"), std::string::npos) << m;
}

TEST(CanIoLight, FaultBeatsDrivingBeatsWait4colBeatsIdle) {
  using msg::LightMode;
  for (std::uint32_t fault : {msg::kSafetyEstop, msg::kSafetyEstopChain, msg::kSafetyBumper, msg::kSafetyIoLost,
                              msg::kSafetyResetNeeded})
    EXPECT_EQ(light_mode(fault, true, true), LightMode::fault);
  // Stops that are not faults (an obstacle, a person's cage) do not light the fault lamp.
  EXPECT_EQ(light_mode(msg::kSafetyObstacle | msg::kSafetyCage, true, false), LightMode::driving);
  EXPECT_EQ(light_mode(msg::kSafetyNone, false, true), LightMode::wait4col);
  EXPECT_EQ(light_mode(msg::kSafetyNone, false, false), LightMode::idle);

  CanIoConfig c;
  c.buzzer_output = 5;
  EXPECT_EQ(output_levels(c, LightMode::idle, false), 0x01);
  EXPECT_EQ(output_levels(c, LightMode::driving, false), 0x02);
  EXPECT_EQ(output_levels(c, LightMode::wait4col, false), 0x04);
  EXPECT_EQ(output_levels(c, LightMode::fault, true), 0x08 | 0x10);
  EXPECT_EQ(output_levels(c, LightMode::off, false), 0x00);
  c.light_outputs[static_cast<int>(LightMode::idle)] = 0;
  EXPECT_EQ(output_levels(c, LightMode::idle, false), 0x00);
}

using TaskRig = testing::CanIoRig;

// The newest SafetyIo the task published.
msg::SafetyIo latest(const TaskRig& rig) {
  tasks::Sample<msg::SafetyIo> s;
  EXPECT_TRUE(rig.io.read(s));
  return s.value;
}

TEST(CanIoTask, OpensTheBusOrSaysWhyNot) {
  TaskRig rig;
  rig.config.interface = "can7";
  CanIoTask missing(rig.config, rig.board, CanIoTopics{rig.safety, rig.command, rig.io, &rig.mode});
  std::pmr::monotonic_buffer_resource arena;
  const Status s = missing.init(arena);
  ASSERT_FALSE(s);
  EXPECT_NE(std::string(s.error().c_str()).find("no such CAN interface"), std::string::npos);
  rig.config.interface = "test";
  rig.config.reset_input = 1;
  CanIoTask bad(rig.config, rig.board, CanIoTopics{rig.safety, rig.command, rig.io, &rig.mode});
  const Status b = bad.init(arena);
  ASSERT_FALSE(b);
  EXPECT_NE(std::string(b.error().c_str()).find("devices.io_node.inputs.reset"), std::string::npos) << b.error().c_str();
}

TEST(CanIoTask, PublishesTheChainTheBumpersAndResetEdges) {
  TaskRig rig;
  std::pmr::monotonic_buffer_resource arena;
  ASSERT_TRUE(rig.task->init(arena));
  rig.run(hal::millis(20));
  EXPECT_FALSE(latest(rig).healthy) << "not healthy before the node is operational";
  rig.run(hal::millis(500));
  msg::SafetyIo io = latest(rig);
  EXPECT_TRUE(io.healthy);
  EXPECT_TRUE(io.ever_healthy);
  EXPECT_FALSE(io.estop);
  EXPECT_FALSE(io.bumper);
  EXPECT_EQ(rig.node.outputs(), 0x01) << "idle light";

  rig.node.set_inputs(0x00);  // the chain opens (active-low)
  rig.run(hal::millis(20));
  EXPECT_TRUE(latest(rig).estop);
  rig.node.set_inputs(0x01 | 0x08);
  rig.run(hal::millis(20));
  io = latest(rig);
  EXPECT_FALSE(io.estop);
  EXPECT_TRUE(io.bumper);
  // Each press of the reset button is one request, however long it is held.
  rig.node.set_inputs(0x01 | 0x02);
  rig.run(hal::millis(300));
  rig.node.set_inputs(0x01);
  rig.run(hal::millis(20));
  rig.node.set_inputs(0x01 | 0x02);
  rig.run(hal::millis(20));
  EXPECT_EQ(latest(rig).resets, 2u);

  // The light follows the safety task and the command.
  msg::SafetyOutput stop;
  stop.reasons = msg::kSafetyResetNeeded;
  rig.safety.publish(stop, rig.now);
  rig.run(hal::millis(20));
  EXPECT_EQ(rig.task->light(), msg::LightMode::fault);
  EXPECT_EQ(rig.node.outputs() & 0x08, 0x08);
  rig.safety.publish(msg::SafetyOutput{}, rig.now);
  rig.command.publish(msg::VelocityCommand{0.3, 0.0, rig.now}, rig.now);
  rig.run(hal::millis(20));
  EXPECT_EQ(rig.node.outputs(), 0x02) << "driving light";
  rig.run(hal::seconds(1));  // the command is old now
  rig.mode.publish(msg::OperatingMode{true}, rig.now);
  rig.run(hal::millis(20));
  EXPECT_EQ(rig.node.outputs(), 0x04) << "wait4col light";

  // Bus-off: not healthy at once, though the master has not missed a heartbeat yet.
  rig.board.bus.set_link_state(hal::CanLinkState::bus_off);
  rig.run(hal::millis(10));
  EXPECT_FALSE(latest(rig).healthy);
  EXPECT_GT(rig.task->bus_errors(), 0u);
}

}  // namespace
}  // namespace sen3bot::firmware
