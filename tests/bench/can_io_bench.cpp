// The CAN I/O task's cost per 10 ms cycle (Google Benchmark), in steady state: the firmware's
// task over an in-memory bus with the CANopen I/O node's emulator on the other station, as
// config/sim.yaml wires it. BM_NodeOnly is the emulator's share of BM_TaskAndNode; the task's
// own cost is the difference.
#include <benchmark/benchmark.h>

#include <memory_resource>

#include "can_board.hpp"
#include "can_io_task.hpp"

namespace {

using namespace sen3bot;

constexpr hal::Nanos kCycleNs = hal::millis(10);

struct Rig {
  firmware::CanIoConfig config;
  testing::CanBoard board;
  tasks::Topic<msg::SafetyOutput> safety;
  tasks::Topic<msg::VelocityCommand> command;
  tasks::Topic<msg::OperatingMode> mode;
  tasks::Topic<msg::SafetyIo> io;
  canopen::IoNodeEmulator node{canopen::IoNodeEmulatorConfig{}};
  std::unique_ptr<firmware::CanIoTask> task;
  std::pmr::monotonic_buffer_resource arena;
  hal::Nanos now = 0;
  std::uint64_t cycle = 0;

  Rig() {
    config.interface = "test";
    config.reset_input = 2;
    config.bumper_inputs = 0x0C;
    config.buzzer_output = 5;
    task = std::make_unique<firmware::CanIoTask>(config, board,
                                                 firmware::CanIoTopics{safety, command, mode, io});
    if (!task->init(arena)) std::abort();
    node.set_inputs(0x01);
    node.power_up(0);
    // Up and running, and driving (the light's driving output).
    command.publish(msg::VelocityCommand{0.4, 0.0, 0}, 0);
    for (int i = 0; i < 200; ++i) cycle_once(true);
    if (task->master().state() != canopen::IoNodeState::operational) std::abort();
  }
  void cycle_once(bool with_task) {
    board.step_node(node, now);
    board.step_node(node, now + kCycleNs / 2);
    if (with_task) {
      command.publish(msg::VelocityCommand{0.4, 0.0, now}, now);
      task->step(tasks::StepContext{now, now, cycle++});
    }
    now += kCycleNs;
  }
  bool healthy() const {
    tasks::Sample<msg::SafetyIo> s;
    return io.read(s) && s.value.healthy;
  }
};

void BM_TaskAndNode(benchmark::State& state) {
  Rig rig;
  for (auto _ : state) rig.cycle_once(true);
  if (!rig.healthy()) state.SkipWithError("the node dropped out");
}
BENCHMARK(BM_TaskAndNode);

void BM_NodeOnly(benchmark::State& state) {
  Rig rig;
  for (auto _ : state) rig.cycle_once(false);
}
BENCHMARK(BM_NodeOnly);

}  // namespace

BENCHMARK_MAIN();
