// The emulator seen from the wire, with a hand-driven client in lockstep: ACK placement,
// reply lengths, baud changes at the old rate, pacing, garbling at a wrong rate, NAK and
// 0x92, installation mode, partial scans and real-time indices.
#include <gtest/gtest.h>

#include <vector>

#include "rig.hpp"
#include "sen3bot/lms200/parser.hpp"

namespace sen3bot::lms200 {
namespace {

using Bytes = std::vector<std::uint8_t>;

struct Wire {
  explicit Wire(const EmulatorOptions& options = {})
      : world(testing::test_world()), line(options.initial_baud), emulator(options, pipe.b(), world, &line) {}

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
    p.push(bytes);
    std::vector<TelegramParser::Kind> out;
    TelegramParser::Event e;
    while (p.next(e)) {
      out.push_back(e.kind);
      if (frames && e.kind == TelegramParser::Kind::frame) frames->emplace_back(e.frame.bytes.begin(), e.frame.bytes.end());
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

}  // namespace
}  // namespace sen3bot::lms200
