// LMS200 numbers: decode cost of a 361-value telegram, the CPU share needed to keep up with
// a 500 kbaud line, and the scan rate achieved per baud (lockstep simulation against the
// emulator, compared with the serial ceiling 10 + 2N bytes at 10 bits per byte).
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdio>
#include <vector>

#include "sen3bot/hal/memory_stream.hpp"
#include "sen3bot/lms200/device.hpp"
#include "sen3bot/sim/lms200/emulator.hpp"
#include "sen3bot/lms200/parser.hpp"
#include "sen3bot/lms200/protocol.hpp"

namespace {

using namespace sen3bot;
using namespace sen3bot::lms200;

std::vector<std::uint8_t> scan_telegram(std::size_t values) {
  std::vector<std::uint8_t> data = {static_cast<std::uint8_t>(values & 0xFF),
                                    static_cast<std::uint8_t>((values >> 8) | 0x40)};
  for (std::size_t i = 0; i < values; ++i) {
    const auto v = static_cast<std::uint16_t>(500 + (i * 37) % 7000);
    data.push_back(static_cast<std::uint8_t>(v & 0xFF));
    data.push_back(static_cast<std::uint8_t>(v >> 8));
  }
  std::vector<std::uint8_t> frame(data.size() + 8);
  frame.resize(make_reply(kReplyScan, data, 0x10, frame));
  return frame;
}

// Bytes in -> ranges in metres out: parser, CRC, B0 decode, per-value split and scaling.
void BM_Decode361(benchmark::State& state) {
  const std::vector<std::uint8_t> frame = scan_telegram(361);
  TelegramParser parser(Side::from_device);
  std::array<float, kMaxValues> ranges_m{};
  for (auto _ : state) {
    parser.push(frame);
    TelegramParser::Event e;
    while (parser.next(e)) {
      Result<ScanTelegram> s = decode_scan(e.frame);
      for (std::size_t i = 0; i < s->count; ++i) {
        const ScanValue v = decode_value(s->words[i], MeasuringMode::range8_fields_dazzle);
        ranges_m[i] = v.reason == InvalidReason::none ? static_cast<float>(v.distance * 0.001) : NAN;
      }
    }
    benchmark::DoNotOptimize(ranges_m);
  }
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * frame.size()));
  state.counters["telegram_bytes"] = static_cast<double>(frame.size());
  // 500 kbaud carries 50 000 bytes/s: telegrams per second at full line rate times the cost
  // of one is the share of a core the decoding needs (an inverted rate: seconds per
  // iteration times 100 x telegrams per second).
  state.counters["cpu_share_at_500k_pct"] = benchmark::Counter(
      static_cast<double>(frame.size()) / (100.0 * 50'000.0),
      benchmark::Counter::kIsIterationInvariantRate | benchmark::Counter::kInvert);
}
BENCHMARK(BM_Decode361);

void BM_Crc732(benchmark::State& state) {
  const std::vector<std::uint8_t> frame = scan_telegram(361);
  for (auto _ : state) benchmark::DoNotOptimize(crc16(frame));
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * frame.size()));
}
BENCHMARK(BM_Crc732);

// Driver + emulator in lockstep for 20 simulated seconds per case.
void print_scan_rates() {
  std::printf("achieved scan rate per baud (lockstep, 20 s simulated; ceiling = min(mirror, line))\n");
  std::printf("%8s %8s %7s %10s %10s\n", "baud", "variant", "values", "ceiling_hz", "achieved_hz");
  for (std::uint32_t baud : kSupportedBauds) {
    for (Variant v : {Variant{100, 100}, Variant{180, 100}, Variant{100, 50}, Variant{180, 50}, Variant{100, 25}}) {
      hal::MemoryPipe pipe(16384);
      WallWorld world = WallWorld::room_with_box(8, 6, 6, 3, 1);
      SimulatedLine line;
      Lms200Emulator emulator(EmulatorOptions{}, pipe.b(), world, &line);
      Lms200Config c;
      c.baud = baud;
      c.variant = v;
      Lms200Device device(c, pipe.a(), &line);
      hal::Nanos now = 0;
      device.start(now);
      while (device.phase() != Lms200Device::Phase::streaming && now < hal::seconds(20)) {
        emulator.step(now);
        device.step(now);
        now += hal::micros(500);
      }
      const std::uint64_t before = device.counters().scans;
      const hal::Nanos start = now;
      while (now < start + hal::seconds(20)) {
        emulator.step(now);
        device.step(now);
        now += hal::micros(500);
      }
      const std::size_t bytes = 10u + 2u * value_count(v);
      const double line_hz = 1e9 / static_cast<double>(transmission_ns(bytes, baud));
      const double mirror_hz = 1e9 / static_cast<double>(scan_period_ns(v));
      const double achieved = static_cast<double>(device.counters().scans - before) / 20.0;
      char variant[16];
      std::snprintf(variant, sizeof variant, "%u/%.2g", v.angle_deg, v.resolution_cdeg / 100.0);
      std::printf("%8u %8s %7u %10.2f %10.2f\n", baud, variant, value_count(v), std::min(line_hz, mirror_hz), achieved);
    }
  }
  std::fflush(stdout);
}

}  // namespace

int main(int argc, char** argv) {
  print_scan_rates();
  benchmark::Initialize(&argc, argv);
  benchmark::RunSpecifiedBenchmarks();
  benchmark::Shutdown();
  return 0;
}
