// CANopen costs (Google Benchmark): the codec's throughput (classify and decode) over the mix
// of frames the robot's bus carries, candump log lines read and written, the master's cost
// per 10 ms cycle in steady state (on_frame for what the node sent in the cycle, then poll),
// and the master and the emulated node together per cycle.
#include <benchmark/benchmark.h>

#include <array>
#include <cstdint>
#include <string>
#include <vector>

#include "sen3bot/canopen/codec.hpp"
#include "sen3bot/canopen/io_node.hpp"
#include "sen3bot/sim/canopen/io_node_emulator.hpp"
#include "sen3bot/hal/candump.hpp"

namespace {

using namespace sen3bot;
using namespace sen3bot::canopen;

constexpr std::uint8_t kNode = 0x10;

// A second of the robot's bus in proportion: heartbeats and TPDO1 every 100 ms, RPDO1 on
// change, an SDO exchange, an EMCY, NMT; and two malformed frames (a decoder's error path).
std::vector<CanFrame> frame_mix() {
  const std::array<std::uint8_t, 1> inputs = {0x01};
  const std::array<std::uint8_t, 1> outputs = {0x02};
  std::vector<CanFrame> mix;
  for (int i = 0; i < 10; ++i) {
    mix.push_back(*heartbeat(kNode, NmtState::operational));
    mix.push_back(*pdo(kNode, 1, true, inputs));
  }
  for (int i = 0; i < 3; ++i) mix.push_back(*pdo(kNode, 1, false, outputs));
  mix.push_back(*sdo_download_request(kNode, {0x1017, 0}, 100, 2));
  mix.push_back(*sdo_download_response(kNode, {0x1017, 0}));
  mix.push_back(*sdo_upload_request(kNode, {0x1018, 1}));
  mix.push_back(*sdo_upload_response(kNode, {0x1018, 1}, 0x53E, 4));
  mix.push_back(*sdo_abort(kNode, {0x6206, 1}, abort_code::kNoObject, true));
  mix.push_back(*emergency(kNode, Emergency{0x2310, 0x03, {}}));
  mix.push_back(*nmt(NmtCommand::start, kNode));
  CanFrame short_heartbeat;
  short_heartbeat.id = 0x700u + kNode;
  mix.push_back(short_heartbeat);
  CanFrame short_emcy;
  short_emcy.id = 0x080u + kNode;
  short_emcy.dlc = 2;
  mix.push_back(short_emcy);
  return mix;
}

// Classify every frame, then decode it with its kind's decoder (what `can dump` and the
// master do per frame).
void BM_CodecClassifyDecode(benchmark::State& state) {
  const std::vector<CanFrame> mix = frame_mix();
  std::uint64_t decoded = 0;
  for (auto _ : state) {
    for (const CanFrame& f : mix) {
      const Classified c = classify(f);
      switch (c.kind) {
        case Kind::heartbeat: decoded += decode_heartbeat(f).ok(); break;
        case Kind::sdo_request:
        case Kind::sdo_response: decoded += decode_sdo(f).ok(); break;
        case Kind::emcy: decoded += decode_emergency(f).ok(); break;
        case Kind::nmt: decoded += decode_nmt(f).ok(); break;
        case Kind::tpdo:
        case Kind::rpdo: decoded += f.dlc >= 1 ? f.data[0] & 1u : 0u; break;
        default: break;
      }
    }
    benchmark::DoNotOptimize(decoded);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * mix.size()));
}
BENCHMARK(BM_CodecClassifyDecode);

// A candump line read (hal::parse_candump_line) and written back (format_candump_line).
void BM_CandumpParseFormat(benchmark::State& state) {
  const std::array<const char*, 4> lines = {
      "(1717405200.310272) can0 610#2B17100064000000\n",
      "(1717405200.410860) can0 710#05\n",
      "(1717405200.450860) can0 190#01\n",
      "(1717405204.500972) can0 090#1023030000000000\n",
  };
  std::array<char, hal::kMaxCandumpLine> text{};
  std::size_t bytes = 0;
  for (auto _ : state) {
    for (const char* line : lines) {
      const Result<hal::CandumpLine> parsed = hal::parse_candump_line(line);
      if (parsed) bytes += hal::format_candump_line(*parsed, text);
    }
    benchmark::DoNotOptimize(bytes);
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations() * lines.size()));
}
BENCHMARK(BM_CandumpParseFormat);

// The master and the node brought up in lockstep (10 ms cycles); the node's frames of
// `cycles` steady-state cycles are recorded per cycle.
struct SteadyState {
  IoNodeMaster master{IoNodeConfig{}};
  IoNodeEmulator node{IoNodeEmulatorConfig{}};
  hal::Nanos now = 0;
  std::vector<std::vector<CanFrame>> node_frames;

  void cycle(std::vector<CanFrame>* record) {
    now += hal::millis(10);
    std::array<CanFrame, 4> out{};
    const std::size_t m = master.poll(now, out);
    for (std::size_t i = 0; i < m; ++i) node.on_frame(out[i], now);
    const std::size_t k = node.poll(now, out);
    for (std::size_t i = 0; i < k; ++i) {
      master.on_frame(out[i], now);
      if (record != nullptr) record->push_back(out[i]);
    }
  }
  explicit SteadyState(int cycles) {
    node.set_inputs(0x01);
    node.power_up(0);
    for (int i = 0; i < 100; ++i) cycle(nullptr);  // 1 s: configured, started, inputs valid
    master.set_outputs(0x02);
    node_frames.resize(static_cast<std::size_t>(cycles));
    for (auto& frames : node_frames) cycle(&frames);
  }
};

// The master alone: one 10 ms cycle of a running node (on_frame for its heartbeat and TPDO1
// when they come, every 10th cycle; poll every cycle, an RPDO1 every 50th), replayed from a
// recorded second over and over with time moving on.
void BM_MasterCycleSteadyState(benchmark::State& state) {
  SteadyState s(100);
  IoNodeMaster& master = s.master;
  hal::Nanos now = s.now;
  std::array<CanFrame, 4> out{};
  std::size_t i = 0;
  std::uint64_t sent = 0;
  for (auto _ : state) {
    now += hal::millis(10);
    for (const CanFrame& f : s.node_frames[i]) master.on_frame(f, now);
    sent += master.poll(now, out);
    if (++i == s.node_frames.size()) i = 0;
  }
  benchmark::DoNotOptimize(sent);
  if (master.state() != IoNodeState::operational || !master.inputs_valid())
    state.SkipWithError("the master left operational");
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
  state.counters["frames_sent_per_s"] =
      benchmark::Counter(static_cast<double>(sent) * 100.0 / static_cast<double>(state.iterations()));
}
BENCHMARK(BM_MasterCycleSteadyState);

// Master and emulated node together per 10 ms cycle (what `can io --iface sim` and the
// lockstep tests spend per cycle).
void BM_MasterAndNodeCycle(benchmark::State& state) {
  SteadyState s(0);
  for (auto _ : state) s.cycle(nullptr);
  if (s.master.state() != IoNodeState::operational) state.SkipWithError("the master left operational");
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_MasterAndNodeCycle);

}  // namespace

BENCHMARK_MAIN();
