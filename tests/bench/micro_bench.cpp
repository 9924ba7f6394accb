// Costs of the scheduler and bus primitives per operation (Google Benchmark).
#include <benchmark/benchmark.h>

#include "sen3bot/tasks/bus.hpp"
#include "sen3bot/tasks/histogram.hpp"
#include "sen3bot/tasks/scheduler.hpp"

namespace {

using namespace sen3bot;

class NopTask final : public tasks::Task {
 public:
  Status init(std::pmr::memory_resource&) override { return Status::success(); }
  void step(const tasks::StepContext&) override { benchmark::ClobberMemory(); }
};

// Simulated time per wall time: one 1 kHz, one 100 Hz and one 10 Hz task for a minute.
void BM_LockstepSimulatedMinute(benchmark::State& state) {
  for (auto _ : state) {
    hal::SimClock clock;
    tasks::Scheduler scheduler(clock);
    NopTask a, b, c;
    (void)scheduler.add({"a", 1'000, 100, 80, "control"}, a);
    (void)scheduler.add({"b", 10'000, 100, 70, "io"}, b);
    (void)scheduler.add({"c", 100'000, 100, 0, "background"}, c);
    (void)scheduler.run_lockstep(clock, hal::seconds(60));
    benchmark::DoNotOptimize(scheduler.stats(0).runs);
  }
  state.counters["ticks"] = benchmark::Counter(66'600.0 * static_cast<double>(state.iterations()), benchmark::Counter::kIsRate);
}
BENCHMARK(BM_LockstepSimulatedMinute)->Unit(benchmark::kMillisecond);

void BM_TopicPublishRead(benchmark::State& state) {
  tasks::Topic<tasks::HealthReport> topic;
  tasks::Sample<tasks::HealthReport> sample;
  tasks::HealthReport report;
  std::int64_t t = 0;
  for (auto _ : state) {
    topic.publish(report, ++t);
    benchmark::DoNotOptimize(topic.read(sample));
  }
}
BENCHMARK(BM_TopicPublishRead);

void BM_HistogramRecord(benchmark::State& state) {
  tasks::LatencyHistogram h;
  std::int64_t v = 1;
  for (auto _ : state) {
    h.record(v);
    v = (v * 1103515245 + 12345) & 0xFFFFF;
  }
  benchmark::DoNotOptimize(h.count());
}
BENCHMARK(BM_HistogramRecord);

void BM_EventPostPop(benchmark::State& state) {
  tasks::EventLog<256> log;
  tasks::Event e;
  for (auto _ : state) {
    log.post(1, tasks::Severity::info, "bench", "value %d", 42);
    benchmark::DoNotOptimize(log.pop(e));
  }
}
BENCHMARK(BM_EventPostPop);

}  // namespace

BENCHMARK_MAIN();
