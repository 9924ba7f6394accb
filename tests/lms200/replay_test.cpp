// The recorded session replayed through the driver: it sends exactly the recorded requests
// and decodes exactly the recorded scans; the capture decoder reproduces the checked-in JSON
// and reads mean-value and sub-range streams.
#include <gtest/gtest.h>
#include <unistd.h>

#include <cmath>
#include <cstdio>
#include <filesystem>
#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "rig.hpp"
#include "sen3bot/capture/recording_stream.hpp"
#include "sen3bot/capture/replay_stream.hpp"
#include "sen3bot/capture/writer.hpp"
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

TEST(Lms200CaptureDecode, MeanValuesAndSubrangesAreDecodedAsScans) {
  const std::filesystem::path path =
      std::filesystem::temp_directory_path() / ("lms200_stream_modes_" + std::to_string(::getpid()) + ".s3bcap");
  hal::SimClock clock;
  capture::CaptureWriter writer(1 << 20);
  capture::CaptureInfo info;
  info.channels.push_back({0, "lms200", 500000});
  ASSERT_TRUE(writer.open(path, info).ok());
  EmulatorOptions o;
  o.initial_baud = 500000;
  o.variant = {180, 50};
  WallWorld world = testing::test_world();
  hal::MemoryPipe pipe(16384);
  SimulatedLine line(500000);
  Lms200Emulator emulator(o, pipe.b(), world, &line);
  capture::RecordingStream client(pipe.a(), writer, 0, clock);
  hal::Nanos now = 0;
  std::array<std::uint8_t, 2048> sink{};
  for (const Request& r : {*request_mean_values(4), *request_subrange(171, 191, o.variant)}) {
    ASSERT_EQ(*client.write(r.span()), r.size);
    for (const hal::Nanos end = now + hal::millis(300); now < end; now += hal::micros(200)) {
      clock.advance_to(now);
      emulator.step(now);
      while (*client.read(sink) > 0) {
      }
    }
  }
  ASSERT_TRUE(writer.close().ok());
  Result<capture::CaptureFile> file = capture::CaptureFile::load(path);
  std::filesystem::remove(path);
  ASSERT_TRUE(file.ok()) << file.error().c_str();
  char* buffer = nullptr;
  std::size_t size = 0;
  std::FILE* out = open_memstream(&buffer, &size);
  Result<CaptureDecodeSummary> summary = decode_capture_json(*file, "", out);
  std::fclose(out);
  const std::string text(buffer, size);
  std::free(buffer);
  ASSERT_TRUE(summary.ok()) << summary.error().c_str();
  int means = 0;
  int subranges = 0;
  std::istringstream lines(text);
  std::string l;
  while (std::getline(lines, l)) {
    if (l.find("\"code\":\"0xb6\"") != std::string::npos) {
      ++means;
      EXPECT_NE(l.find("\"count\":361,"), std::string::npos) << l.substr(0, 200);
      EXPECT_NE(l.find("\"mean_samples\":4,"), std::string::npos) << l.substr(0, 200);
    }
    if (l.find("\"code\":\"0xb7\"") != std::string::npos) {
      ++subranges;
      EXPECT_NE(l.find("\"count\":21,"), std::string::npos) << l.substr(0, 200);
      EXPECT_NE(l.find("\"first\":171,\"last\":191"), std::string::npos) << l.substr(0, 200);
      // Straight ahead, the 11th value: the box face 1.5 m away.
      EXPECT_NE(l.find(",1.500,"), std::string::npos) << l.substr(0, 300);
    }
    EXPECT_EQ(l.find("\"error\""), std::string::npos) << l.substr(0, 200);
  }
  // 300 ms each: a mean of 4 scans every 107 ms, a sub-range every 27 ms.
  EXPECT_GE(means, 2);
  EXPECT_GE(subranges, 9);
  EXPECT_EQ(summary->scans, static_cast<std::size_t>(means + subranges));
}

}  // namespace
}  // namespace sen3bot::lms200
