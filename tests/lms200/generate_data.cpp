// lms200_generate_data --data-dir tests/data: rewrites the recorded session, its decoded
// JSON lines, and the parser's fuzz seed corpus.
#include <cstdio>
#include <cstring>
#include <filesystem>
#include <fstream>
#include <random>
#include <string>
#include <vector>

#include "sen3bot/capture/reader.hpp"
#include "sen3bot/lms200/capture_decode.hpp"
#include "sen3bot/lms200/protocol.hpp"
#include "session.hpp"

namespace {

using namespace sen3bot;
using namespace sen3bot::lms200;
using Bytes = std::vector<std::uint8_t>;

void write(const std::filesystem::path& p, const Bytes& b) {
  std::ofstream out(p, std::ios::binary);
  out.write(reinterpret_cast<const char*>(b.data()), static_cast<std::streamsize>(b.size()));
}

Bytes reply(std::uint8_t code, const Bytes& data) {
  std::array<std::uint8_t, 1024> out{};
  const std::size_t n = make_reply(code, data, 0x10, out);
  return Bytes(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(n));
}

Bytes scan(std::size_t n, bool indices, std::uint16_t units_bits) {
  Bytes d = {static_cast<std::uint8_t>(n & 0xFF), static_cast<std::uint8_t>((n >> 8) | (units_bits >> 8))};
  for (std::size_t i = 0; i < n; ++i) {
    const auto v = static_cast<std::uint16_t>(i % 5 == 0 ? 8183 + i % 9 : 1000 + i);
    d.push_back(static_cast<std::uint8_t>(v & 0xFF));
    d.push_back(static_cast<std::uint8_t>(v >> 8));
  }
  if (indices) d.insert(d.end(), {1, 2});
  return reply(kReplyScan, d);
}

// B6 (mean of `samples` scans) or, with first > 0, B7 (values first..first + n - 1).
Bytes stream_scan(std::uint8_t code, std::size_t n, std::uint8_t samples, std::uint16_t first, bool indices) {
  Bytes d;
  if (code == kReplyMeanScan) d.push_back(samples);
  if (code == kReplySubrangeScan) {
    const auto last = static_cast<std::uint16_t>(first + n - 1);
    d.insert(d.end(), {static_cast<std::uint8_t>(first & 0xFF), static_cast<std::uint8_t>(first >> 8),
                       static_cast<std::uint8_t>(last & 0xFF), static_cast<std::uint8_t>(last >> 8)});
  }
  d.push_back(static_cast<std::uint8_t>(n & 0xFF));
  d.push_back(static_cast<std::uint8_t>((n >> 8) | 0x40));  // mm
  for (std::size_t i = 0; i < n; ++i) {
    const auto v = static_cast<std::uint16_t>(i % 7 == 0 ? 8191 : 2000 + 3 * i);
    d.push_back(static_cast<std::uint8_t>(v & 0xFF));
    d.push_back(static_cast<std::uint8_t>(v >> 8));
  }
  if (indices) d.insert(d.end(), {3, 4});
  return reply(code, d);
}

Bytes of(const Request& r) { return Bytes(r.span().begin(), r.span().end()); }

}  // namespace

int main(int argc, char** argv) {
  if (argc != 3 || std::strcmp(argv[1], "--data-dir") != 0) {
    std::fprintf(stderr, "usage: %s --data-dir DIR\n", argv[0]);
    return 2;
  }
  const std::filesystem::path dir = argv[2];
  const std::filesystem::path capture_path = dir / "captures" / "lms200_session.s3bcap";
  if (Status s = testing::record_session(capture_path); !s) {
    std::fprintf(stderr, "record: %s\n", s.error().c_str());
    return 1;
  }
  Result<capture::CaptureFile> file = capture::CaptureFile::load(capture_path);
  if (!file) {
    std::fprintf(stderr, "load: %s\n", file.error().c_str());
    return 1;
  }
  std::FILE* json = std::fopen((dir / "captures" / "lms200_session.jsonl").c_str(), "w");
  if (json == nullptr || !decode_capture_json(*file, "", json)) return 1;
  std::fclose(json);

  const std::filesystem::path corpus = dir / "fuzz" / "lms200";
  std::filesystem::create_directories(corpus);
  write(corpus / "session_rx.bin", file->stream_bytes(testing::kSessionChannel, capture::Direction::rx));
  write(corpus / "session_tx.bin", file->stream_bytes(testing::kSessionChannel, capture::Direction::tx));
  Bytes requests;
  for (const Request& r : {request_status(), request_type(), request_read_config(), request_installation_mode(),
                           request_variant({100, 25}), request_baud(500000), request_mode(OperatingMode::continuous_all)})
    for (std::uint8_t b : of(r)) requests.push_back(b);
  write(corpus / "golden_requests.bin", requests);
  Bytes replies = {kAck};
  for (const Bytes& r : {reply(kReplyModeChange, {0}), reply(kReplyVariant, {1, 0xB4, 0, 0x32, 0}),
                         reply(kReplyReadConfig, Bytes(34, 0)), reply(kReplyReadConfig, Bytes(32, 0)),
                         reply(kReplyWriteConfig, Bytes(35, 1)), reply(kReplyType, Bytes(21, 'L')),
                         reply(kReplyRejected, {}), reply(kReplyStatus, Bytes(152, 0))})
    replies.insert(replies.end(), r.begin(), r.end());
  replies.push_back(kNak);
  write(corpus / "golden_replies.bin", replies);
  write(corpus / "scan_401_indices_mm.bin", scan(401, true, 0x4000));
  write(corpus / "scan_181_cm.bin", scan(181, false, 0));
  // Mean values and sub-ranges, their requests, and a stream mixing them with B0.
  write(corpus / "mean_181_mm.bin", stream_scan(kReplyMeanScan, 181, 10, 0, false));
  write(corpus / "subrange_22_indices_mm.bin", stream_scan(kReplySubrangeScan, 22, 0, 1, true));
  write(corpus / "subrange_401_indices_mm.bin", stream_scan(kReplySubrangeScan, 401, 0, 1, true));
  Bytes mixed = of(*request_mean_values(4));
  for (std::uint8_t b : of(*request_subrange(171, 191, {180, 50}))) mixed.push_back(b);
  for (const Bytes& r : {stream_scan(kReplyMeanScan, 101, 250, 0, true), scan(101, false, 0),
                         stream_scan(kReplySubrangeScan, 21, 0, 171, false),
                         stream_scan(kReplyMeanScan, 361, 2, 0, false)})
    mixed.insert(mixed.end(), r.begin(), r.end());
  write(corpus / "stream_modes_mix.bin", mixed);
  Bytes hostile = {0x02, 0x80, 0xD6, 0x02};
  const Bytes s361 = scan(361, false, 0x4000);
  hostile.insert(hostile.end(), s361.begin(), s361.end());
  hostile.insert(hostile.end(), {0x02, 0x80, 0xFF, 0xFF, 0x02, 0x80, 0x00, 0x00});
  Bytes broken = s361;
  if (broken.size() > 8) broken[broken.size() - 1] = static_cast<std::uint8_t>(~broken[broken.size() - 1]);
  hostile.insert(hostile.end(), broken.begin(), broken.end());
  hostile.insert(hostile.end(), s361.begin(), s361.begin() + 100);
  hostile.insert(hostile.end(), s361.begin(), s361.end());
  write(corpus / "hostile_mix.bin", hostile);
  Bytes noise(600);
  std::mt19937 rng(42);
  for (auto& b : noise) b = static_cast<std::uint8_t>(rng());
  write(corpus / "noise.bin", noise);
  std::printf("wrote %s, its .jsonl and %s\n", capture_path.c_str(), corpus.c_str());
  return 0;
}
