// Pioneer base costs (Google Benchmark): parser throughput, the cost of one SIP through
// parser + decoder + odometry, a driver step per SIP, the emulator's SIP, and the time to
// connect to the emulator (lockstep and over a real pseudo-terminal).
#include <benchmark/benchmark.h>

#include <vector>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/memory_stream.hpp"
#include "sen3bot/hal/serial.hpp"
#include "sen3bot/p2os/codec.hpp"
#include "sen3bot/p2os/driver.hpp"
#include "sen3bot/sim/p2os/emulator.hpp"
#include "sen3bot/sim/p2os/emulator_runner.hpp"
#include "sen3bot/p2os/odometry.hpp"

namespace {

using namespace sen3bot;
using namespace sen3bot::p2os;

Packet moving_sip(int i) {
  Sip s;
  s.moving = true;
  s.x_raw = static_cast<std::uint16_t>((i * 25) & kPositionMask);
  s.y_raw = static_cast<std::uint16_t>((i * 3) & kPositionMask);
  s.theta_raw = static_cast<std::int16_t>((i % 4096) - 2048);
  s.left_vel_mm_s = 240;
  s.right_vel_mm_s = 260;
  s.battery_dv = 130;
  s.flags = 0x1F;
  s.sonar_count = 16;
  for (std::uint8_t d = 0; d < 16; ++d) s.sonar[d] = {d, 5000};
  s.digin = s.digout = 0xFF;
  s.has_battery_x10 = s.has_charge_state = s.has_rot_vel = s.has_fault_flags = true;
  s.has_lat_vel = s.has_temperature = s.has_soc = true;
  return encode_sip(s);
}

std::vector<std::uint8_t> sip_stream(int count) {
  std::vector<std::uint8_t> out;
  for (int i = 0; i < count; ++i) {
    const Packet p = moving_sip(i);
    out.insert(out.end(), p.view().begin(), p.view().end());
  }
  return out;
}

// Bytes per second through the frame parser (89-byte SIPs, fed in 64-byte reads).
void BM_ParserThroughput(benchmark::State& state) {
  const std::vector<std::uint8_t> stream = sip_stream(1000);
  FrameParser parser;
  std::uint64_t frames = 0;
  for (auto _ : state) {
    for (std::size_t pos = 0; pos < stream.size(); pos += 64) {
      const std::size_t n = std::min<std::size_t>(64, stream.size() - pos);
      parser.feed(std::span<const std::uint8_t>(stream.data() + pos, n), 0, [&](const Frame&) { ++frames; });
    }
  }
  benchmark::DoNotOptimize(frames);
  state.SetBytesProcessed(static_cast<std::int64_t>(state.iterations() * stream.size()));
}
BENCHMARK(BM_ParserThroughput);

// One SIP: parse, decode every field, update odometry.
void BM_SipParseDecodeOdometry(benchmark::State& state) {
  const std::vector<std::uint8_t> stream = sip_stream(256);
  const std::size_t sip_bytes = stream.size() / 256;
  FrameParser parser;
  Odometry odometry;
  std::size_t i = 0;
  for (auto _ : state) {
    parser.feed(std::span<const std::uint8_t>(stream.data() + (i % 256) * sip_bytes, sip_bytes), 0,
                [&](const Frame& f) {
                  if (auto s = decode_sip(f)) odometry.update(*s);
                });
    ++i;
  }
  benchmark::DoNotOptimize(odometry.pose());
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
}
BENCHMARK(BM_SipParseDecodeOdometry);

// Driver and emulator together in lockstep: one 100 ms SIP cycle (50 ticks of 2 ms) with the
// robot driving. The pair, because neither side makes progress alone.
void BM_LockstepSipCycle(benchmark::State& state) {
  hal::MemoryPipe pipe(16384);
  P2osEmulator emulator;
  P2osDriver driver{P2osConfig{}};
  hal::Nanos now = hal::seconds(1);
  driver.attach(pipe.a(), now);
  auto tick = [&] {
    (void)emulator.step(pipe.b(), now);
    driver.set_setpoint(BaseSetpoint{0.3, 0.2, true}, now);
    driver.step(now);
    now += hal::millis(2);
  };
  for (int i = 0; i < 1000; ++i) tick();
  for (auto _ : state) {
    for (int i = 0; i < 50; ++i) tick();
  }
  state.SetItemsProcessed(static_cast<std::int64_t>(state.iterations()));
  state.counters["sips"] = static_cast<double>(driver.state().sip_count);
}
BENCHMARK(BM_LockstepSipCycle);

// Simulated time from attach to the first SIP (handshake + OPEN + first SipCycle).
void BM_ConnectLockstep(benchmark::State& state) {
  hal::Nanos connect_ns = 0;
  for (auto _ : state) {
    hal::MemoryPipe pipe(16384);
    P2osEmulator emulator;
    P2osDriver driver{P2osConfig{}};
    hal::Nanos now = 0;
    driver.attach(pipe.a(), now);
    while (driver.state().link != LinkState::connected && now < hal::seconds(5)) {
      (void)emulator.step(pipe.b(), now);
      driver.step(now);
      now += hal::millis(1);
    }
    connect_ns = driver.last_connect_duration_ns();
  }
  state.counters["sim_connect_ms"] = static_cast<double>(connect_ns) / 1e6;
}
BENCHMARK(BM_ConnectLockstep)->Unit(benchmark::kMicrosecond);

// Wall-clock connect over a real pseudo-terminal with the emulator on its own thread.
void BM_ConnectOverPty(benchmark::State& state) {
  for (auto _ : state) {
    auto runner = PtyEmulatorRunner::start(EmulatorConfig{});
    auto port = hal::SerialPort::open((*runner)->slave_path(), 9600);
    if (!runner || !port) {
      state.SkipWithError("no pty");
      return;
    }
    hal::PosixClock clock;
    P2osDriver driver{P2osConfig{}};
    driver.attach(**port, clock.now());
    const hal::Nanos deadline = clock.now() + hal::seconds(5);
    while (driver.state().link != LinkState::connected && clock.now() < deadline) {
      driver.step(clock.now());
      clock.sleep_until(clock.now() + hal::millis(1));
    }
    state.counters["connect_ms"] = static_cast<double>(driver.last_connect_duration_ns()) / 1e6;
  }
}
BENCHMARK(BM_ConnectOverPty)->Unit(benchmark::kMillisecond)->Iterations(3)->UseRealTime();

}  // namespace

BENCHMARK_MAIN();
