// The CAN I/O task's cost per 10 ms cycle (Google Benchmark), in steady state: the firmware's
// task over an in-memory bus with the CANopen I/O node's emulator on the other station, as
// config/sim.yaml wires it. BM_NodeOnly is the emulator's share of BM_TaskAndNode; the task's
// own cost is the difference.
#include <benchmark/benchmark.h>

#include <memory_resource>

#include "can_board.hpp"

namespace {

using namespace sen3bot;

// Up and running, and driving (the light's driving output), a command every cycle.
struct Rig : testing::CanIoRig {
  std::pmr::monotonic_buffer_resource arena;
  Rig() {
    if (!task->init(arena)) std::abort();
    for (int i = 0; i < 200; ++i) step(true);
    if (task->master().state() != canopen::IoNodeState::operational) std::abort();
  }
  void step(bool with_task) {
    command.publish(msg::VelocityCommand{0.4, 0.0, now}, now);
    cycle_once(with_task);
  }
  bool healthy() const {
    tasks::Sample<msg::SafetyIo> s;
    return io.read(s) && s.value.healthy;
  }
};

void BM_TaskAndNode(benchmark::State& state) {
  Rig rig;
  for (auto _ : state) rig.step(true);
  if (!rig.healthy()) state.SkipWithError("the node dropped out");
}
BENCHMARK(BM_TaskAndNode);

void BM_NodeOnly(benchmark::State& state) {
  Rig rig;
  for (auto _ : state) rig.step(false);
}
BENCHMARK(BM_NodeOnly);

}  // namespace

BENCHMARK_MAIN();
