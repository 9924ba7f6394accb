// Fuzz target: arbitrary bytes as robot output through the frame parser and every decoder,
// and as client traffic into the emulator. Nothing may crash, read out of bounds or loop,
// and every delivered frame must be self-consistent.
#include <cstdint>
#include <cstdlib>
#include <span>

#include "sen3bot/hal/memory_stream.hpp"
#include "sen3bot/p2os/codec.hpp"
#include "sen3bot/p2os/describe.hpp"
#include "sen3bot/sim/p2os/emulator.hpp"

namespace {

void check(bool condition) {
  if (!condition) std::abort();
}

}  // namespace

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sen3bot;
  using namespace sen3bot::p2os;
  const std::span<const std::uint8_t> bytes(data, size);

  // Parser in chunks whose sizes come from the input itself, with a gap now and then.
  FrameParser parser;
  std::size_t pos = 0;
  hal::Nanos t = 0;
  std::size_t frames = 0;
  while (pos < bytes.size()) {
    const std::size_t chunk = 1 + (bytes[pos] % 23);
    const std::size_t n = std::min(chunk, bytes.size() - pos);
    t += (bytes[pos] & 0x80) ? hal::millis(150) : hal::millis(1);
    parser.feed(bytes.subspan(pos, n), t, [&](const Frame& f) {
      ++frames;
      check(f.raw.size() >= 6 && f.raw[0] == 0xFA && f.raw[1] == 0xFB);
      check(f.raw.size() == static_cast<std::size_t>(f.raw[2]) + 3);
      check(checksum(f.body) == ((f.raw[f.raw.size() - 2] << 8) | f.raw[f.raw.size() - 1]));
      if (auto sip = decode_sip(f)) check(sip->sonar_count <= kMaxSonarPerSip && (sip->x_raw & 0x8000) == 0);
      (void)decode_config(f);
      (void)decode_encoder(f);
      if (auto reply = decode_sync2_reply(f)) check(reply->name.back() == '\0');
      const CommandArgument arg = decode_argument(f.payload);
      check(arg.text.size() <= f.payload.size());
      (void)decode_vel2(arg);
      (void)describe_packet_json(0, PacketDirection::from_robot, f);
      (void)describe_packet_json(0, PacketDirection::to_robot, f);
    });
    pos += n;
  }
  check(frames == parser.stats().frames);

  // The same bytes as a client talking to the emulator.
  hal::MemoryPipe pipe(1024);
  P2osEmulator emulator;
  std::uint8_t sink[1024];
  pos = 0;
  t = 0;
  while (pos < bytes.size()) {
    const std::size_t n = std::min<std::size_t>(64, bytes.size() - pos);
    (void)pipe.a().write(bytes.subspan(pos, n));
    (void)emulator.step(pipe.b(), t);
    (void)pipe.a().read(sink);
    t += hal::millis(30);
    pos += n;
  }
  return 0;
}
