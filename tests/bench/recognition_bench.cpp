// Operation recognition costs (Google Benchmark): the features of a recorded path, and a whole
// classification (features, the shipped network, the softmax) of paths of 100, 400 and 1024
// points (the recorder's capacity). The path is a held-out worker's walk, resampled to the
// length, so the cells it touches are those a real path touches. items/s = classifications/s.
#include <benchmark/benchmark.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <vector>

#include "sen3bot/cobot/operations.hpp"
#include "sen3bot/cobot/recognizer.hpp"
#include "sen3bot/sim/cobot/workers.hpp"

namespace {

using namespace sen3bot;
using namespace sen3bot::cobot;

struct Fixture {
  OperationsConfig config;
  std::unique_ptr<OperationRecognizer> recognizer;
  std::vector<float> walk;  // a held-out worker's recorded path

  static Fixture& get() {
    static Fixture f = make();
    return f;
  }

  static Fixture make() {
    Fixture f;
    Result<OperationsConfig> c = load_operations(SEN3BOT_SOURCE_DIR "/config/cobot/operations.yaml");
    if (!c) fail(c.error().c_str());
    f.config = std::move(*c);
    Result<std::unique_ptr<OperationRecognizer>> r =
        OperationRecognizer::load(SEN3BOT_SOURCE_DIR "/config/cobot/operations-model.yaml.gz", f.config);
    if (!r) fail(r.error().c_str());
    f.recognizer = std::move(*r);
    Result<nav::OccupancyMap> map = nav::load_map(f.config.map_path);
    if (!map) fail(map.error().c_str());
    Result<std::unique_ptr<WorkerSimulator>> workers = WorkerSimulator::create(f.config, *map);
    if (!workers) fail(workers.error().c_str());
    Result<WorkerWalk> w = (*workers)->walk(0, held_out_style(), Observer{}, 1);
    if (!w) fail(w.error().c_str());
    f.walk = std::move(w->xy);
    return f;
  }

  [[noreturn]] static void fail(const char* why) {
    std::fprintf(stderr, "recognition_bench: %s\n", why);
    std::exit(1);
  }

  // The walk resampled (by index) to `points` points.
  [[nodiscard]] std::vector<float> path(std::size_t points) const {
    const std::size_t n = walk.size() / 2;
    std::vector<float> xy;
    for (std::size_t i = 0; i < points; ++i) {
      const std::size_t k = i * (n - 1) / (points - 1);
      xy.insert(xy.end(), {walk[2 * k], walk[2 * k + 1]});
    }
    return xy;
  }
};

void BM_Features(benchmark::State& state) {
  const Fixture& f = Fixture::get();
  const std::vector<float> xy = f.path(static_cast<std::size_t>(state.range(0)));
  std::vector<float> out(feature_count(f.config.grid, FeatureEncoding::occupancy_order));
  for (auto _ : state) {
    path_features(xy, f.config.grid, out);
    benchmark::DoNotOptimize(out.data());
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Features)->Arg(100)->Arg(400)->Arg(1024);

void BM_Classify(benchmark::State& state) {
  Fixture& f = Fixture::get();
  const std::vector<float> xy = f.path(static_cast<std::size_t>(state.range(0)));
  std::vector<float> p(f.recognizer->operations());
  for (auto _ : state) {
    if (!f.recognizer->classify(xy, xy.size() / 2, p)) state.SkipWithError("classify failed");
    benchmark::DoNotOptimize(p.data());
  }
  state.SetItemsProcessed(state.iterations());
}
BENCHMARK(BM_Classify)->Arg(100)->Arg(400)->Arg(1024);

}  // namespace

BENCHMARK_MAIN();
