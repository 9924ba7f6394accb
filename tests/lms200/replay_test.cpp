// The recorded session replayed through the driver: it sends exactly the recorded requests
// and decodes exactly the recorded scans; the capture decoder reproduces the checked-in JSON.
#include <gtest/gtest.h>

#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "sen3bot/capture/replay_stream.hpp"
#include "sen3bot/lms200/capture_decode.hpp"
#include "sen3bot/lms200/parser.hpp"
#include "session.hpp"

namespace sen3bot::lms200 {
namespace {

const std::string kCapture = std::string(SEN3BOT_SOURCE_DIR) + "/tests/data/captures/lms200_session.s3bcap";
const std::string kJson = std::string(SEN3BOT_SOURCE_DIR) + "/tests/data/captures/lms200_session.jsonl";

class NoLine final : public LineControl {
 public:
  Status set_baud(std::uint32_t baud) override {
    bauds.push_back(baud);
    return Status::success();
  }
  std::vector<std::uint32_t> bauds;
};

// Offline: every CRC-valid B0 in the recorded rx bytes.
std::vector<ScanTelegram> recorded_scans(const capture::CaptureFile& file) {
  std::vector<ScanTelegram> scans;
  TelegramParser parser(Side::from_device);
  for (const capture::Record& r : file.records()) {
    if (r.kind == capture::RecordKind::baud_change) parser.reset();
    if (r.kind != capture::RecordKind::rx) continue;
    std::span<const std::uint8_t> bytes = r.payload;
    while (!bytes.empty()) {
      const std::size_t n = parser.push(bytes);
      bytes = bytes.subspan(n);
      TelegramParser::Event e;
      while (parser.next(e))
        if (e.kind == TelegramParser::Kind::frame && e.frame.code() == kReplyScan)
          if (auto s = decode_scan(e.frame)) scans.push_back(*s);
    }
  }
  return scans;
}

TEST(Lms200Replay, DriverReproducesTheRecordedSession) {
  Result<capture::CaptureFile> file = capture::CaptureFile::load(kCapture);
  ASSERT_TRUE(file.ok()) << file.error().c_str();
  hal::SimClock clock;
  capture::ReplayStream replay(*file, testing::kSessionChannel, clock, capture::ReplayTiming::original);
  NoLine line;
  Lms200Device device(testing::session_driver_config(), replay, &line);
  std::vector<LaserScan> scans;
  hal::Nanos now = 0;
  device.start(now);
  bool stop_sent = false;
  while (now < hal::seconds(20) && device.phase() != Lms200Device::Phase::stopped) {
    clock.advance_to(now);
    device.step(now);
    LaserScan s;
    if (device.take_new_scan(s)) scans.push_back(s);
    // The recording stopped after the 8th scan.
    if (!stop_sent && device.counters().scans >= 8) {
      device.request_stop(now);
      stop_sent = true;
    }
    now += testing::kSessionStepNs;
  }
  EXPECT_EQ(device.phase(), Lms200Device::Phase::stopped) << device.last_error().c_str();
  EXPECT_TRUE(replay.tx_comparison().identical())
      << "first mismatch at tx offset " << replay.tx_comparison().first_mismatch_offset;
  // Probe 38400 (silence), probe 9600, switch to 38400, clean stop back to 9600.
  EXPECT_EQ(line.bauds, (std::vector<std::uint32_t>{38400, 9600, 38400, 9600}));

  const std::vector<ScanTelegram> recorded = recorded_scans(*file);
  // One more telegram was on the wire while the stop request went out; the driver,
  // no longer streaming, ignores it.
  ASSERT_EQ(scans.size(), 8u);
  ASSERT_EQ(recorded.size(), scans.size() + 1);
  for (std::size_t k = 0; k < scans.size(); ++k) {
    ASSERT_EQ(scans[k].count, recorded[k].count);
    for (std::size_t i = 0; i < recorded[k].count; ++i) {
      const ScanValue v = decode_value(recorded[k].words[i], MeasuringMode::range8_fields_dazzle);
      if (v.reason == InvalidReason::none) {
        EXPECT_FLOAT_EQ(scans[k].ranges_m[i], static_cast<float>(v.distance * 0.001)) << k << "/" << i;
      } else {
        EXPECT_TRUE(std::isnan(scans[k].ranges_m[i]));
        EXPECT_EQ(scans[k].invalid_reason[i], static_cast<std::uint8_t>(v.reason));
      }
    }
  }
  EXPECT_GT(device.parser_stats().crc_errors, 0u);  // the injected faults are in the recording
}

TEST(Lms200Replay, CaptureDecodesToTheCheckedInJson) {
  Result<capture::CaptureFile> file = capture::CaptureFile::load(kCapture);
  ASSERT_TRUE(file.ok()) << file.error().c_str();
  char* buffer = nullptr;
  std::size_t size = 0;
  std::FILE* out = open_memstream(&buffer, &size);
  Result<CaptureDecodeSummary> summary = decode_capture_json(*file, "", out);
  std::fclose(out);
  const std::string decoded(buffer, size);
  std::free(buffer);
  ASSERT_TRUE(summary.ok());
  EXPECT_GE(summary->scans, 8u);
  std::ifstream in(kJson);
  std::stringstream want;
  want << in.rdbuf();
  EXPECT_EQ(decoded, want.str());
}

}  // namespace
}  // namespace sen3bot::lms200
