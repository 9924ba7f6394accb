// Regenerates the checked-in capture data from code:
//   <data-dir>/captures/synthetic_session.s3bcap  deterministic (SimClock, computed timing)
//   <data-dir>/captures/loopback_session.s3bcap   live recording over two real pseudo-terminals
//   <data-dir>/fuzz/capture/*                     seed corpus for fuzz.capture_reader
//
// usage: capture_generate --data-dir tests/data [--no-pty]
//   --no-pty keeps the existing loopback_session.s3bcap (its timing differs on every run).
#include <cstdint>
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <string>

#include "capture_test_util.hpp"
#include "loopback_session.hpp"
#include "sen3bot/capture/format.hpp"

namespace {

using namespace sen3bot;
using namespace sen3bot::capture;
using test::Bytes;
using test::FileBuilder;

void write_corpus(const std::filesystem::path& dir, const std::filesystem::path& synthetic) {
  std::filesystem::create_directories(dir);
  const CaptureInfo info = test::two_channel_info();
  auto save = [&](const char* name, const Bytes& bytes) { test::write_bytes(dir / name, bytes); };
  Bytes every_byte(256);
  for (std::size_t i = 0; i < every_byte.size(); ++i) every_byte[i] = static_cast<std::uint8_t>(i);

  // Valid inputs.
  save("valid_header_only.s3bcap", FileBuilder().header(CaptureInfo{}).bytes());
  save("valid_closed_empty.s3bcap", FileBuilder().header(CaptureInfo{}).end(0, 0, 0).bytes());
  save("valid_two_channels.s3bcap", FileBuilder()
                                        .header(info)
                                        .tx(0, 0, Bytes{0xFA, 0xFB, 0x03, 0x00, 0x00, 0x00})
                                        .rx(1000, 0, Bytes{0xFA, 0xFB, 0x03, 0x00, 0x00, 0x00})
                                        .tx(1000, 1, Bytes{})
                                        .baud(2000, 1, 38400)
                                        .rx(3000, 1, Bytes{0x06})
                                        .end(3000, 5, 0)
                                        .bytes());
  save("valid_gaps.s3bcap",
       FileBuilder().header(info).rx(5, 0, Bytes{1}).gap(9, 3, 30).rx(9, 1, Bytes{2}).gap(9, 1, 1).end(9, 2, 4).bytes());
  save("valid_all_byte_values.s3bcap", FileBuilder().header(info).rx(7, 1, every_byte).end(7, 1, 0).bytes());
  save("valid_unclosed.s3bcap", FileBuilder().header(info).rx(1, 0, Bytes{1, 2, 3}).tx(2, 0, Bytes{4}).bytes());
  CaptureInfo many;
  for (std::uint8_t i = 0; i < kMaxChannels; ++i)
    many.channels.push_back({static_cast<std::uint8_t>(i * 7), std::string(kMaxChannelNameBytes, static_cast<char>('A' + i % 26)), 115200});
  save("valid_max_channels.s3bcap", FileBuilder().header(many).rx(0, 217, Bytes{0xFF}).bytes());
  save("valid_synthetic_session.s3bcap", test::read_bytes(synthetic));
  CaptureInfo extreme = info;
  extreme.start_wall_ns = INT64_MIN;
  extreme.start_monotonic_ns = INT64_MAX;
  save("valid_extreme_times.s3bcap", FileBuilder().header(extreme).rx(0, 0, Bytes{1}).rx(INT64_MAX, 0, Bytes{2}).bytes());

  // Invalid inputs, one defect each.
  Bytes b = FileBuilder().header(info).bytes();
  b[2] = 'X';
  save("bad_magic.s3bcap", b);
  b = FileBuilder().header(info).bytes();
  le::put_u16(&b[8], 2);
  save("bad_version.s3bcap", b);
  b = FileBuilder().header(info).rx(1, 0, Bytes(30, 9)).bytes();
  b.resize(b.size() - 1);
  save("bad_truncated_record.s3bcap", b);
  b = FileBuilder().header(info).rx(1, 0, Bytes{1}).bytes();
  le::put_u32(&b[b.size() - 1 - 4], static_cast<std::uint32_t>(kMaxPayloadBytes + 1));
  save("bad_payload_over_bound.s3bcap", b);
  save("bad_unknown_channel.s3bcap", FileBuilder().header(info).rx(1, 9, Bytes{1}).bytes());
  save("bad_time_backwards.s3bcap", FileBuilder().header(info).rx(10, 0, Bytes{1}).rx(9, 0, Bytes{1}).bytes());
  save("bad_data_after_end.s3bcap", FileBuilder().header(info).end(0, 0, 0).rx(1, 0, Bytes{1}).bytes());
}

int fail(const char* what, const Status& s) {
  std::fprintf(stderr, "capture_generate: %s: %s\n", what, s.error().c_str());
  return 1;
}

}  // namespace

int main(int argc, char** argv) {
  std::filesystem::path data_dir;
  bool pty = true;
  for (int i = 1; i < argc; ++i) {
    if (std::strcmp(argv[i], "--data-dir") == 0 && i + 1 < argc) {
      data_dir = argv[++i];
    } else if (std::strcmp(argv[i], "--no-pty") == 0) {
      pty = false;
    } else {
      data_dir.clear();
      break;
    }
  }
  if (data_dir.empty()) {
    std::fprintf(stderr, "usage: capture_generate --data-dir tests/data [--no-pty]\n");
    return 2;
  }
  const std::filesystem::path captures = data_dir / "captures";
  std::filesystem::create_directories(captures);

  const auto synthetic = captures / "synthetic_session.s3bcap";
  if (Status s = test::write_synthetic_session(synthetic); !s) return fail("synthetic session", s);
  std::printf("wrote %s\n", synthetic.c_str());
  if (pty) {
    const auto loopback = captures / "loopback_session.s3bcap";
    if (Status s = test::record_loopback_session(loopback); !s) return fail("loopback session", s);
    std::printf("wrote %s\n", loopback.c_str());
  }
  write_corpus(data_dir / "fuzz" / "capture", synthetic);
  std::printf("wrote %s\n", (data_dir / "fuzz" / "capture").c_str());
  return 0;
}
