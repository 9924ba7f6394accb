// Regenerates the checked-in P2OS test data:
//   <data-dir>/captures/p2os_session.s3bcap   the scripted session (session.hpp), recorded in
//                                             lockstep against the emulator: byte-identical
//                                             on every run
//   <data-dir>/captures/p2os_session.jsonl    its decoding, the replay test's expectation
//   <data-dir>/captures/aria_session.s3bcap   what an ARIA client sends over TCP on one
//                                             connection, with ARIA's timing (tx records
//                                             only); replayed against the emulator
//   <data-dir>/captures/aria_session.jsonl    its decoding
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

// An ARIA client (ArRobotConnector + ArRobot) on a fresh TCP connection, written from the
// protocol facts (docs/p2os.md, "ARIA's session"): SYNC0-2 about 70 ms apart, each sent once
// its reply has come; OPEN 1 with CONFIG 1; BATTERYINFO 1 and ENABLE 1 (simpleConnect enables
// the motors); the six limit commands from the CONFIGpac in one burst; PULSE every ~510 ms
// while idle; VEL and RVEL re-sent every ~510 ms while driving; stop() = VEL 0 + RVEL 0;
// disconnect = ENABLE 0, then CLOSE 1 90 ms later. Times in ms after the connection was accepted;
// ENABLE 0 falls mid-way between two SIPs (they run on OPEN's 100 ms phase), so one SIP lands
// between it and CLOSE to show the motors off.
struct AriaPacket {
  int t_ms;
  Packet packet;
};

std::vector<AriaPacket> aria_client_packets() {
  // Command 62 (BATTERYINFO) is not in the P3's command table; ARIA sends it anyway.
  constexpr auto kBatteryInfo = static_cast<Command>(62);
  return {
      {930, encode_command(Command::sync0)},
      {1001, encode_command(Command::sync1)},
      {1071, encode_command(Command::sync2)},
      {1165, encode_command_int(kOpen, 1)},
      {1165, encode_command_int(Command::config, 1)},
      {1236, encode_command_int(kBatteryInfo, 1)},
      {1236, encode_command_int(Command::enable, 1)},
      {1267, encode_command_int(Command::setv, 1200)},
      {1267, encode_command_int(Command::seta, 300)},
      {1267, encode_command_int(Command::seta, -300)},
      {1267, encode_command_int(Command::setrv, 300)},
      {1267, encode_command_int(Command::setra, 100)},
      {1267, encode_command_int(Command::setra, -100)},
      {1369, encode_command(kPulse)},
      {1879, encode_command(kPulse)},
      {2389, encode_command_int(Command::vel, 250)},
      {2389, encode_command_int(Command::rvel, 0)},
      {2899, encode_command_int(Command::vel, 250)},
      {2899, encode_command_int(Command::rvel, 0)},
      {3409, encode_command_int(Command::vel, 250)},
      {3409, encode_command_int(Command::rvel, 20)},
      {3919, encode_command_int(Command::vel, 250)},
      {3919, encode_command_int(Command::rvel, 20)},
      {4429, encode_command_int(Command::vel, 0)},
      {4429, encode_command_int(Command::rvel, 0)},
      {4939, encode_command(kPulse)},
      {5420, encode_command_int(Command::enable, 0)},
      {5510, encode_command_int(kClose, 1)},
  };
}

Status write_aria_session(const std::filesystem::path& path) {
  hal::SimClock clock(hal::seconds(100));
  const hal::Nanos start = clock.now();
  capture::CaptureWriter writer(1 << 16);
  capture::CaptureInfo info;
  info.start_monotonic_ns = start;
  info.channels.push_back(capture::ChannelDecl{0, "p2os", 0});  // TCP: no line rate
  if (Status s = writer.open(path, info); !s) return s;
  for (const AriaPacket& p : aria_client_packets()) {
    clock.advance_to(start + hal::millis(p.t_ms));
    // One record per packet: ARIA writes each packet with its own write().
    if (!writer.record(clock.now(), 0, capture::Direction::tx, p.packet.view()))
      return Error::format(Errc::io, "%s: capture buffer full", path.c_str());
  }
  return writer.close();
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

  const std::filesystem::path aria = captures / "aria_session.s3bcap";
  if (Status s = write_aria_session(aria); !s) {
    std::fprintf(stderr, "p2os_generate: %s\n", s.error().c_str());
    return 1;
  }
  auto aria_loaded = capture::CaptureFile::load(aria);
  if (!aria_loaded) {
    std::fprintf(stderr, "p2os_generate: %s\n", aria_loaded.error().c_str());
    return 1;
  }
  std::ofstream aria_jsonl(captures / "aria_session.jsonl", std::ios::trunc);
  if (Status s = decode_capture(*aria_loaded, "", [&](const std::string& line) { aria_jsonl << line << '\n'; }); !s) {
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
  std::printf("wrote %s, %s, %s and the corpus in %s\n", session.c_str(), (captures / "p2os_session.jsonl").c_str(),
              aria.c_str(), corpus.c_str());
  return 0;
}
