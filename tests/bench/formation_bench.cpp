// One step of the centralised formation controller: the P points, the field with its
// barriers, V, rho, the hybrid rule's check (and, when it fails, every gain set tried), the
// unicycle inputs and the common scaling. The target is 0.1 ms for 8 robots on the host.
#include <benchmark/benchmark.h>

#include <cmath>
#include <numbers>
#include <vector>

#include "sen3bot/formation/controller.hpp"

namespace {

using namespace sen3bot::formation;

ControllerConfig team(TaskKind task, std::size_t robots) {
  ControllerConfig c;
  c.task = task;
  c.robots = robots;
  c.workspace = {-20.0, -20.0, 20.0, 20.0};
  for (std::size_t i = 0; i < robots; ++i) {
    // Each target across the ring from its robot: every path crosses the crowd.
    const double a = 2.0 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(robots) + std::numbers::pi;
    c.targets[i] = {4.0 * std::cos(a), 4.0 * std::sin(a)};
    c.offsets[i] = {-1.2 * static_cast<double>(i), 0.0};  // followers in a file behind the leader
  }
  c.curve = sen3bot::nav::SafeCurve::ellipse({0.0, 0.0}, 4.0, 3.0, 0.2);
  c.curve_start = {0.0, 3.0};
  return c;
}

// Robots on a ring; at 1.14 m neighbours are 2 cm past their barrier's zero, the worst case.
std::vector<Pose> crowded(std::size_t robots, double radius) {
  std::vector<Pose> p(robots);
  for (std::size_t i = 0; i < robots; ++i) {
    const double a = 2.0 * std::numbers::pi * static_cast<double>(i) / static_cast<double>(robots);
    p[i] = {radius * std::cos(a), radius * std::sin(a), a + 1.0};
  }
  return p;
}

void run(benchmark::State& state, TaskKind task, double ring) {
  const auto n = static_cast<std::size_t>(state.range(0));
  Controller k;
  if (!k.configure(team(task, n))) {
    state.SkipWithError("configure");
    return;
  }
  std::vector<Pose> poses = crowded(n, ring);
  std::vector<Unicycle> cmd(n);
  k.reset(poses, 0.0);
  double t = 0.0;
  for (auto _ : state) {
    // Move a little each step so the hybrid rule is checked on new states.
    for (Pose& p : poses) p.theta_rad += 1e-3;
    benchmark::DoNotOptimize(k.step(t += 1.0, poses, cmd));
  }
  state.counters["switches"] = static_cast<double>(k.switches());
  state.counters["unresolved"] = k.last().unresolved ? 1.0 : 0.0;
}

void BM_TargetsCrowded(benchmark::State& s) { run(s, TaskKind::targets, 1.137); }
void BM_TargetsSpread(benchmark::State& s) { run(s, TaskKind::targets, 4.0); }
void BM_PatrolCrowded(benchmark::State& s) { run(s, TaskKind::patrol, 1.137); }
void BM_LeaderCrowded(benchmark::State& s) { run(s, TaskKind::leader, 1.137); }

}  // namespace

BENCHMARK(BM_TargetsCrowded)->Arg(3)->Arg(4)->Arg(8)->Arg(10)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_TargetsSpread)->Arg(8)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_PatrolCrowded)->Arg(3)->Arg(8)->Arg(10)->Unit(benchmark::kMicrosecond);
BENCHMARK(BM_LeaderCrowded)->Arg(3)->Arg(8)->Unit(benchmark::kMicrosecond);
BENCHMARK_MAIN();
