// The emulator seen from the wire, with a hand-driven client in lockstep: ACK placement,
// reply lengths, baud changes at the old rate, pacing, garbling at a wrong rate, NAK and
// 0x92, installation mode, partial scans and real-time indices, mean values and sub-ranges,
// the skipped-scan count across mode switches, and a device fault in the status reply.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "rig.hpp"
#include "sen3bot/lms200/parser.hpp"

namespace sen3bot::lms200 {
namespace {

using Bytes = std::vector<std::uint8_t>;

struct Wire {
  // `source`: what the scanner sees; the test room when null.
  explicit Wire(const EmulatorOptions& options = {}, RangeSource* source = nullptr)
      : world(testing::test_world()),
        line(options.initial_baud),
        emulator(options, pipe.b(), source != nullptr ? *source : world, &line) {}

  void send(const Request& r) { ASSERT_EQ(*pipe.a().write(r.span()), r.size); }
  void send_raw(const Bytes& b) { ASSERT_EQ(*pipe.a().write(b), b.size()); }
  // Advances time in 100 us steps, collecting what arrives.
  Bytes run_for(hal::Nanos d) {
    Bytes got;
    for (const hal::Nanos end = now + d; now < end; now += hal::micros(100)) {
      emulator.step(now);
      std::array<std::uint8_t, 1024> buf;
      for (;;) {
        const std::size_t n = *pipe.a().read(buf);
        if (n == 0) break;
        got.insert(got.end(), buf.begin(), buf.begin() + static_cast<std::ptrdiff_t>(n));
      }
    }
    return got;
  }
  // Parses `bytes` as the scanner's side of the wire.
  static std::vector<TelegramParser::Kind> kinds(const Bytes& bytes, std::vector<Bytes>* frames = nullptr) {
    TelegramParser p(Side::from_device);
    std::vector<TelegramParser::Kind> out;
    // The parser's ring holds two telegrams: push what fits, take out what is complete, repeat.
    for (std::size_t at = 0; at < bytes.size();) {
      const std::size_t pushed = p.push({bytes.data() + at, bytes.size() - at});
      at += pushed;
      TelegramParser::Event e;
      bool any = false;
      while (p.next(e)) {
        any = true;
        out.push_back(e.kind);
        if (frames && e.kind == TelegramParser::Kind::frame)
          frames->emplace_back(e.frame.bytes.begin(), e.frame.bytes.end());
      }
      if (pushed == 0 && !any) break;
    }
    return out;
  }

  hal::MemoryPipe pipe{16384};
  WallWorld world;
  SimulatedLine line;
  Lms200Emulator emulator;
  hal::Nanos now = 0;
};

using K = TelegramParser::Kind;

std::vector<Bytes> frames_with_code(const std::vector<Bytes>& frames, std::uint8_t code) {
  std::vector<Bytes> out;
  for (const Bytes& f : frames)
    if (f.size() > 4 && f[4] == code) out.push_back(f);
  return out;
}

TEST(Lms200Emulator, AckThenReplyWithFixedLengthsAndStatus0x10) {
  Wire w;
  struct Case {
    Request request;
    std::size_t reply_bytes;  // what fixed-length clients read after the ACK
  };
  const Case cases[] = {{request_status(), 160},
                        {request_type(), 29},
                        {request_read_config(), 42},
                        {request_variant({180, 100}), 13},
                        {request_mode(OperatingMode::monitoring), 9}};
  for (const Case& c : cases) {
    w.send(c.request);
    const Bytes got = w.run_for(hal::millis(300));
    ASSERT_EQ(got.size(), 1 + c.reply_bytes) << std::hex << int(c.request.command());
    EXPECT_EQ(got[0], kAck);
    EXPECT_EQ(got[1], kStx);
    EXPECT_EQ(got[2], 0x80);
    EXPECT_EQ(got[got.size() - 3], 0x10);  // status byte before the CRC
  }
}

TEST(Lms200Emulator, PacedAtTenBitsPerByte) {
  Wire w;
  w.send(request_status());
  // 161 bytes at 9600 baud take 167.7 ms; after 100 ms about 96 have arrived.
  const Bytes first = w.run_for(hal::millis(100));
  EXPECT_NEAR(static_cast<double>(first.size()), 96.0, 1.0);
  const Bytes rest = w.run_for(hal::millis(100));
  EXPECT_EQ(first.size() + rest.size(), 161u);
}

TEST(Lms200Emulator, BaudChangeAnsweredAtTheOldRate) {
  Wire w;
  w.send(request_baud(38400));
  Bytes got = w.run_for(hal::millis(5));
  EXPECT_EQ(w.emulator.baud(), 9600u);  // still sending the reply at 9600
  got = w.run_for(hal::millis(20));
  EXPECT_EQ(w.emulator.baud(), 38400u);
  // The client has not switched yet: what it sends now is noise to the scanner.
  w.send(request_status());
  EXPECT_TRUE(w.run_for(hal::millis(100)).empty());
  EXPECT_GT(w.emulator.counters().garbled_rx_bytes, 0u);
  ASSERT_TRUE(w.line.set_baud(38400).ok());
  w.send(request_status());
  EXPECT_EQ(Wire::kinds(w.run_for(hal::millis(100))), (std::vector<K>{K::ack, K::frame}));
}

TEST(Lms200Emulator, WrongRateGarblesOutput) {
  Wire w;
  w.send(request_mode(OperatingMode::continuous_all));
  w.run_for(hal::millis(20));
  ASSERT_TRUE(w.line.set_baud(19200).ok());  // the client moves away while the scanner streams
  const Bytes got = w.run_for(hal::seconds(1));
  EXPECT_GT(got.size(), 500u);
  std::vector<Bytes> frames;
  Wire::kinds(got, &frames);
  EXPECT_TRUE(frames.empty());
  EXPECT_GT(w.emulator.counters().garbled_tx_bytes, 500u);
}

TEST(Lms200Emulator, StreamedScansHaveNoAck) {
  Wire w;
  w.send(request_mode(OperatingMode::continuous_all));
  std::vector<Bytes> frames;
  const auto kinds = Wire::kinds(w.run_for(hal::seconds(2)), &frames);
  ASSERT_GE(kinds.size(), 3u);
  EXPECT_EQ(kinds[0], K::ack);
  for (std::size_t i = 1; i < kinds.size(); ++i) EXPECT_EQ(kinds[i], K::frame);
  EXPECT_EQ(frames[0][4], kReplyModeChange);
  // 180/1 at 9600: 372 bytes, 388 ms each -> 5 in two seconds, every one the newest scan.
  EXPECT_NEAR(static_cast<double>(frames.size() - 1), 5.0, 1.0);
  for (std::size_t i = 1; i < frames.size(); ++i) EXPECT_EQ(frames[i].size(), 372u);
  EXPECT_GT(w.emulator.counters().scans_skipped, 20u);
}

TEST(Lms200Emulator, NakForBadCrcAndRejectionForUnknownCommands) {
  Wire w;
  Request bad = request_status();
  bad.bytes[bad.size - 1] ^= 0xFF;
  w.send(bad);
  EXPECT_EQ(w.run_for(hal::millis(50)), (Bytes{kNak}));
  const std::uint8_t unknown[] = {0x66, 0x01};
  w.send(make_request(unknown));
  std::vector<Bytes> frames;
  EXPECT_EQ(Wire::kinds(w.run_for(hal::millis(50)), &frames), (std::vector<K>{K::ack, K::frame}));
  EXPECT_EQ(frames[0][4], kReplyRejected);
  EXPECT_EQ(w.emulator.counters().rejected, 1u);
}

TEST(Lms200Emulator, ConfigurationNeedsInstallationModeAndPassword) {
  Wire w;
  std::array<std::uint8_t, kConfigBytes> block{};
  block[config_offset::kUnits] = 1;
  w.send(request_write_config(block));
  std::vector<Bytes> frames;
  Wire::kinds(w.run_for(hal::millis(100)), &frames);
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_FALSE(decode_write_config(FrameView{frames[0]})->accepted);
  EXPECT_EQ(w.emulator.units(), Units::cm);

  w.send(request_installation_mode("WRONG_PW"));
  frames.clear();
  Wire::kinds(w.run_for(hal::millis(50)), &frames);
  EXPECT_EQ(decode_mode_change(FrameView{frames[0]})->result, kModeChangeBadPassword);

  w.send(request_installation_mode());
  w.run_for(hal::millis(50));
  w.send(request_write_config(block));
  frames.clear();
  Wire::kinds(w.run_for(hal::millis(200)), &frames);
  ASSERT_EQ(frames.size(), 1u);
  EXPECT_TRUE(decode_write_config(FrameView{frames[0]})->accepted);
  EXPECT_EQ(w.emulator.units(), Units::mm);
  EXPECT_EQ(w.emulator.counters().config_writes, 1u);
}

TEST(Lms200Emulator, PartialScansAndRealTimeIndices) {
  EmulatorOptions o;
  o.initial_baud = 500000;
  o.variant = {100, 25};
  o.availability = kAvailabilityRealTimeIndices;
  Wire w(o);
  ASSERT_TRUE(w.line.set_baud(500000).ok());
  w.send(request_mode(OperatingMode::partial_scans));
  std::vector<Bytes> frames;
  Wire::kinds(w.run_for(hal::millis(100)), &frames);
  ASSERT_GE(frames.size(), 6u);
  std::vector<int> offsets;
  for (std::size_t i = 1; i < frames.size(); ++i) {
    Result<ScanTelegram> s = decode_scan(FrameView{frames[i]});
    ASSERT_TRUE(s.ok()) << s.error().c_str();
    EXPECT_TRUE(s->partial);
    EXPECT_TRUE(s->has_indices);
    EXPECT_EQ(s->count, 101);
    offsets.push_back(s->partial_offset_qdeg);
  }
  EXPECT_EQ(std::vector<int>(offsets.begin(), offsets.begin() + 5), (std::vector<int>{0, 1, 2, 3, 0}));
}

TEST(Lms200Emulator, ScanOnRequestWhilePartialScansStreamIsComplete) {
  EmulatorOptions o;
  o.initial_baud = 500000;
  o.variant = {100, 50};
  Wire w(o);
  ASSERT_TRUE(w.line.set_baud(500000).ok());
  w.send(request_mode(OperatingMode::partial_scans));
  w.run_for(hal::millis(50));
  w.send(request_single_scan());
  std::vector<Bytes> frames;
  Wire::kinds(w.run_for(hal::millis(50)), &frames);
  int complete = 0;
  for (const Bytes& f : frames_with_code(frames, kReplyScan)) {
    Result<ScanTelegram> s = decode_scan(FrameView{f});
    ASSERT_TRUE(s.ok());
    if (s->partial) {
      EXPECT_EQ(s->count, 101);
    } else {
      ++complete;
      EXPECT_EQ(s->count, 201);
      EXPECT_EQ(s->words[100], 150);  // straight ahead: the box 1.5 m away
    }
  }
  EXPECT_EQ(complete, 1);
}

TEST(Lms200Emulator, SingleScanOnRequest) {
  Wire w;
  w.send(request_single_scan());
  std::vector<Bytes> frames;
  EXPECT_EQ(Wire::kinds(w.run_for(hal::millis(500)), &frames), (std::vector<K>{K::ack, K::frame}));
  Result<ScanTelegram> s = decode_scan(FrameView{frames[0]});
  ASSERT_TRUE(s.ok());
  EXPECT_EQ(s->count, 181);
  // Straight ahead from the room's centre: the box face 1.5 m away, in cm.
  EXPECT_EQ(s->words[90], 150);
  EXPECT_FALSE(w.emulator.streaming());
}

// Beam i at 2 m + i mm, plus 10 mm per scan number modulo 4; beam 0 hits nothing. The mean
// of any four consecutive scans is 2015 + i mm, a value no single scan has.
class Breathing final : public RangeSource {
 public:
  explicit Breathing(Variant v) : period_ns_(scan_period_ns(v)) {}
  void ranges(hal::Nanos t, const ScanGeometry& g, std::span<float> out_m) override {
    const std::int64_t scan = t / period_ns_;
    for (std::size_t i = 0; i < std::min(g.count, out_m.size()); ++i)
      out_m[i] = i == 0 ? INFINITY
                        : static_cast<float>(2.0 + 0.001 * static_cast<double>(i) + 0.01 * static_cast<double>(scan % 4));
  }

 private:
  hal::Nanos period_ns_;
};


TEST(Lms200Emulator, MeanValuesStreamTheMeanOfEveryNScans) {
  EmulatorOptions o;
  o.initial_baud = 500000;
  o.units = Units::mm;
  Breathing source(o.variant);
  Wire w(o, &source);
  ASSERT_TRUE(w.line.set_baud(500000).ok());
  w.send(*request_mean_values(4));
  std::vector<Bytes> frames;
  const auto kinds = Wire::kinds(w.run_for(hal::seconds(1)), &frames);
  ASSERT_GE(kinds.size(), 2u);
  EXPECT_EQ(kinds[0], K::ack);
  EXPECT_EQ(frames[0][4], kReplyModeChange);
  EXPECT_EQ(decode_mode_change(FrameView{frames[0]})->result, kModeChangeOk);
  const std::vector<Bytes> means = frames_with_code(frames, kReplyMeanScan);
  // One mean per four scans of 1/75 s: 18.75 per second; the first after four scans.
  EXPECT_EQ(means.size() + 1, frames.size());
  EXPECT_NEAR(static_cast<double>(means.size()), 18.0, 1.0);
  EXPECT_EQ(w.emulator.counters().scans_skipped, 0u);
  for (const Bytes& f : means) {
    Result<ScanTelegram> s = decode_mean_scan(FrameView{f});
    ASSERT_TRUE(s.ok()) << s.error().c_str();
    EXPECT_EQ(s->mean_samples, 4);
    EXPECT_EQ(s->count, 181);
    EXPECT_EQ(s->units, Units::mm);
    EXPECT_EQ(decode_value(s->words[0], MeasuringMode::range8_fields_dazzle).reason, InvalidReason::over_maximum);
    for (std::size_t i = 1; i < s->count; ++i) ASSERT_EQ(s->words[i], 2015 + i) << i;
  }
  // Monitoring mode stops the stream.
  w.send(request_mode(OperatingMode::monitoring));
  w.run_for(hal::millis(100));
  EXPECT_FALSE(w.emulator.streaming());
  EXPECT_TRUE(w.run_for(hal::millis(200)).empty());
}

TEST(Lms200Emulator, SubrangeStreamsOnlyTheRequestedValues) {
  EmulatorOptions o;
  o.variant = {180, 50};
  o.availability = kAvailabilityRealTimeIndices;
  Wire w(o);
  std::array<std::uint16_t, kMaxValues> full{};
  ASSERT_EQ(w.emulator.scan_words(0, full), 361u);
  // Values 171..191 of 361: 10 degrees either side of straight ahead, the box 1.5 m away.
  w.send(*request_subrange(171, 191, o.variant));
  std::vector<Bytes> frames;
  Wire::kinds(w.run_for(hal::seconds(2)), &frames);
  const std::vector<Bytes> subranges = frames_with_code(frames, kReplySubrangeScan);
  // 58 bytes a telegram take 60.4 ms at 9600 baud: about 33 in two seconds, where complete
  // 361-value B0 telegrams (763 ms each) manage two or three.
  EXPECT_NEAR(static_cast<double>(subranges.size()), 32.0, 2.0);
  for (const Bytes& f : subranges) {
    EXPECT_EQ(f.size(), 2 * 21 + 16u);
    Result<ScanTelegram> s = decode_subrange_scan(FrameView{f});
    ASSERT_TRUE(s.ok()) << s.error().c_str();
    EXPECT_EQ(s->first_index, 171);
    EXPECT_EQ(s->last_index, 191);
    EXPECT_EQ(s->count, 21);
    EXPECT_TRUE(s->has_indices);
    for (std::size_t i = 0; i < s->count; ++i) ASSERT_EQ(s->words[i], full[170 + i]) << i;
  }
  // Straight ahead (value 181, the 11th sent): the box face 1.5 m away, in cm.
  ASSERT_FALSE(subranges.empty());
  EXPECT_EQ(decode_subrange_scan(FrameView{subranges.front()})->words[10], 150);
}

TEST(Lms200Emulator, MalformedMeanAndSubrangeRequestsAreRejected) {
  EmulatorOptions o;
  o.variant = {180, 50};
  Wire w(o);
  const Bytes bad[] = {
      {0x20, 0x26, 1},                  // fewer than 2 scans
      {0x20, 0x26, 251},                // more than 250
      {0x20, 0x26},                     // no sample count
      {0x20, 0x27, 0, 0, 10, 0},        // first 0 (indices are 1-based)
      {0x20, 0x27, 11, 0, 10, 0},       // first > last
      {0x20, 0x27, 1, 0, 0x6A, 0x01},   // last 362 > 361
      {0x20, 0x27, 1, 0, 10},           // short
  };
  for (const Bytes& payload : bad) {
    w.send(make_request(payload));
    std::vector<Bytes> frames;
    Wire::kinds(w.run_for(hal::millis(50)), &frames);
    ASSERT_EQ(frames.size(), 1u);
    EXPECT_EQ(frames[0][4], kReplyRejected) << int(payload[1]) << " " << payload.size();
    EXPECT_FALSE(w.emulator.streaming());
  }
  EXPECT_EQ(w.emulator.counters().rejected, std::size(bad));
}

TEST(Lms200Emulator, SkippedScansStayPlausibleAcrossModeSwitches) {
  EmulatorOptions o;
  o.initial_baud = 500000;
  o.variant = {100, 25};  // four mirror turns per complete scan
  Wire w(o);
  ASSERT_TRUE(w.line.set_baud(500000).ok());
  // An hour after power-on, so scan numbers counted in the wrong period differ by far.
  w.now = hal::seconds(3600);
  const hal::Nanos began = w.now;
  auto check = [&](const char* after) {
    const EmulatorCounters& c = w.emulator.counters();
    // Everything sent or skipped happened on a mirror turn since streaming began.
    const auto turns = static_cast<std::uint64_t>((w.now - began) / kMirrorPeriodNs) + 1;
    EXPECT_LE(c.scans_sent + c.scans_skipped, turns) << after;
    // At 500 kbaud every telegram here leaves before the next scan: nothing to skip.
    EXPECT_EQ(c.scans_skipped, 0u) << after;
  };
  w.send(request_mode(OperatingMode::partial_scans));
  w.run_for(hal::millis(500));
  check("partial scans");
  EXPECT_GT(w.emulator.counters().scans_sent, 30u);
  w.send(request_mode(OperatingMode::continuous_all));
  w.run_for(hal::millis(500));
  check("complete scans");
  w.send(request_mode(OperatingMode::partial_scans));
  w.run_for(hal::millis(500));
  check("partial scans again");
  w.send(*request_subrange(1, 401, o.variant));
  w.run_for(hal::millis(500));
  check("sub-range");
  w.send(*request_mean_values(2));
  w.run_for(hal::millis(500));
  check("mean values");
  w.send(request_mode(OperatingMode::partial_scans));
  w.run_for(hal::millis(500));
  check("partial scans after mean values");
}

TEST(Lms200Emulator, DeviceFaultShowsInTheStatusReplyAndTheStatusByte) {
  struct Case {
    std::uint8_t status;
    bool device_fault;
    std::uint8_t want_device_status;
    std::uint8_t want_status;
  };
  const Case cases[] = {
      {0x10, false, kDeviceStatusOk, 0x10},
      {0x12, false, kDeviceStatusOk, 0x12},     // a warning is not a fault
      {0x13, false, kDeviceStatusFault, 0x13},  // --status with level "error"
      {0x14, false, kDeviceStatusFault, 0x14},  // level "fatal"
      {0x10, true, kDeviceStatusFault, 0x13},
      {0x14, true, kDeviceStatusFault, 0x14},
  };
  for (const Case& c : cases) {
    EmulatorOptions o;
    o.status = c.status;
    o.faults.device_fault = c.device_fault;
    Wire w(o);
    w.send(request_status());
    std::vector<Bytes> frames;
    Wire::kinds(w.run_for(hal::millis(300)), &frames);
    ASSERT_EQ(frames.size(), 1u);
    Result<StatusReply> s = decode_status(FrameView{frames[0]});
    ASSERT_TRUE(s.ok()) << s.error().c_str();
    EXPECT_EQ(s->device_status, c.want_device_status) << std::hex << int(c.status) << " " << c.device_fault;
    EXPECT_EQ(s->status, c.want_status) << std::hex << int(c.status) << " " << c.device_fault;
    // Streamed scans carry the same status byte.
    w.send(request_single_scan());
    frames.clear();
    Wire::kinds(w.run_for(hal::millis(500)), &frames);
    ASSERT_EQ(frames.size(), 1u);
    EXPECT_EQ(decode_scan(FrameView{frames[0]})->status, c.want_status);
  }
}

}  // namespace
}  // namespace sen3bot::lms200
