// Regenerates the checked-in P2OS test data:
//   <data-dir>/captures/p2os_session.s3bcap   the scripted session (session.hpp), recorded in
//                                             lockstep against the emulator: byte-identical
//                                             on every run
//   <data-dir>/captures/p2os_session.jsonl    its decoding, the replay test's expectation
//   <data-dir>/fuzz/p2os/*                    seed corpus for fuzz.p2os_parser
//
// usage: p2os_generate --data-dir tests/data
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <string>
#include <vector>

#include "lockstep_harness.hpp"
#include "sen3bot/capture/reader.hpp"
#include "sen3bot/capture/recording_stream.hpp"
#include "sen3bot/capture/writer.hpp"
#include "sen3bot/hal/memory_stream.hpp"
#include "sen3bot/p2os/describe.hpp"
#include "sen3bot/sim/p2os/emulator.hpp"
#include "session.hpp"

namespace {

using namespace sen3bot;
using namespace sen3bot::p2os;
using Bytes = std::vector<std::uint8_t>;

void write_bytes(const std::filesystem::path& path, std::span<const std::uint8_t> bytes) {
  std::ofstream out(path, std::ios::binary | std::ios::trunc);
  out.write(reinterpret_cast<const char*>(bytes.data()), static_cast<std::streamsize>(bytes.size()));
}

Status record_session(const std::filesystem::path& path) {
  hal::SimClock clock(hal::seconds(100));
  hal::MemoryPipe pipe(16384, "driver", "robot");
  P2osEmulator robot(test::fast_emulator_config());
  capture::CaptureWriter writer(1 << 20);
  capture::CaptureInfo info;
  info.start_monotonic_ns = clock.now();
  info.channels.push_back(capture::ChannelDecl{0, "p2os", 9600});
  if (Status s = writer.open(path, info); !s) return s;
  capture::RecordingStream recording(pipe.a(), writer, 0, clock);
  (void)test::run_session(recording, clock, [&] { (void)robot.step(pipe.b(), clock.now()); });
  return writer.close();
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3 || std::strcmp(argv[1], "--data-dir") != 0) {
    std::fprintf(stderr, "usage: p2os_generate --data-dir tests/data\n");
    return 2;
  }
  const std::filesystem::path data = argv[2];
  const std::filesystem::path captures = data / "captures";
  const std::filesystem::path corpus = data / "fuzz" / "p2os";
  std::filesystem::create_directories(captures);
  std::filesystem::create_directories(corpus);

  const std::filesystem::path session = captures / "p2os_session.s3bcap";
  if (Status s = record_session(session); !s) {
    std::fprintf(stderr, "p2os_generate: %s\n", s.error().c_str());
    return 1;
  }
  auto loaded = capture::CaptureFile::load(session);
  if (!loaded) {
    std::fprintf(stderr, "p2os_generate: %s\n", loaded.error().c_str());
    return 1;
  }
  std::ofstream jsonl(captures / "p2os_session.jsonl", std::ios::trunc);
  if (Status s = decode_capture(*loaded, "", [&](const std::string& line) { jsonl << line << '\n'; }); !s) {
    std::fprintf(stderr, "p2os_generate: %s\n", s.error().c_str());
    return 1;
  }

  // Seeds: both directions of the session, golden packets, and hostile shapes.
  write_bytes(corpus / "session_rx.bin", loaded->stream_bytes(0, capture::Direction::rx));
  write_bytes(corpus / "session_tx.bin", loaded->stream_bytes(0, capture::Direction::tx));
  write_bytes(corpus / "sync2_reply.bin", encode_sync2_reply("EMU", "Pioneer", "p3dx-sh").view());
  write_bytes(corpus / "encoder_odd.bin", encode_encoder({1000, -1000}).view());
  ConfigPacket config;
  config.auto_baud = 2;
  config.watchdog_ms = 2000;
  write_bytes(corpus / "config.bin", encode_config(config).view());
  Sip sip;
  sip.sonar_count = 16;
  sip.has_battery_x10 = sip.has_charge_state = sip.has_rot_vel = sip.has_fault_flags = true;
  write_bytes(corpus / "sip_full.bin", encode_sip(sip).view());
  const Bytes short_n{0xFA, 0xFB, 0x02, 0x00, 0x00, 0xFA, 0xFB, 0x01, 0xFA, 0xFB, 0x00};
  write_bytes(corpus / "short_lengths.bin", short_n);
  Bytes oversize{0xFA, 0xFB, 0xFF};
  for (int i = 0; i < 40; ++i) {
    const Packet p = encode_command_int(Command::vel, i * 10 - 200);
    oversize.insert(oversize.end(), p.view().begin(), p.view().end());
  }
  write_bytes(corpus / "oversize_header.bin", oversize);
  const Bytes lenient{0xFA, 0xFB, 0x04, 0x07, 0x3B, 0x07, 0x3B, 'W', 'M', 'S', '2', '\r'};
  write_bytes(corpus / "lenient_seto.bin", lenient);
  std::printf("wrote %s, %s and the corpus in %s\n", session.c_str(), (captures / "p2os_session.jsonl").c_str(),
              corpus.c_str());
  return 0;
}
