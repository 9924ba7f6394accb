// RecordingStream and ReplayStream.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <chrono>
#include <thread>

#include "capture_test_util.hpp"
#include "loopback_session.hpp"
#include "sen3bot/capture/reader.hpp"
#include "sen3bot/capture/recording_stream.hpp"
#include "sen3bot/capture/replay_stream.hpp"
#include "sen3bot/capture/writer.hpp"

namespace sen3bot::capture {
namespace {

using test::Bytes;
using ::testing::HasSubstr;

CaptureFile parse_ok(const Bytes& bytes) {
  auto file = CaptureFile::parse(bytes);
  if (!file) ADD_FAILURE() << file.error().c_str();
  return std::move(file).value();
}

CaptureFile load_stream_capture(const std::filesystem::path& path) {
  auto file = CaptureFile::load(path);
  if (!file) ADD_FAILURE() << file.error().c_str();
  return std::move(file).value();
}

Bytes span_bytes(std::span<const std::uint8_t> s) { return Bytes(s.begin(), s.end()); }

// --------------------------------- RecordingStream ---------------------------------

TEST(RecordingStream, RecordsReadsAsRxAndAcceptedWritesAsTx) {
  const CaptureInfo info = test::two_channel_info();
  hal::SimClock clock(info.start_monotonic_ns);
  const auto path = test::scratch_path("recording.s3bcap");
  CaptureWriter writer(4096);
  ASSERT_TRUE(writer.open(path, info));
  test::ScriptedStream inner;
  RecordingStream stream(inner, writer, 1, clock);
  EXPECT_EQ(stream.name(), "scripted");
  EXPECT_EQ(stream.poll_fd(), -1);
  EXPECT_EQ(stream.channel(), 1);

  std::uint8_t buf[4];
  auto n = stream.read(buf);  // nothing available: no record
  ASSERT_TRUE(n);
  EXPECT_EQ(*n, 0u);

  inner.push_rx({1, 2, 3, 4, 5, 6});
  clock.advance_by(hal::millis(2));
  n = stream.read(buf);  // the caller's buffer limits the read to 4 bytes
  ASSERT_TRUE(n);
  EXPECT_EQ(*n, 4u);
  clock.advance_by(hal::millis(1));
  n = stream.read(buf);
  ASSERT_TRUE(n);
  EXPECT_EQ(*n, 2u);

  inner.push_read_error(Errc::disconnected);
  n = stream.read(buf);
  ASSERT_FALSE(n);
  EXPECT_EQ(n.error().code(), Errc::disconnected);

  inner.max_write_bytes = 3;
  const Bytes command = {0xFA, 0xFB, 0x03, 0x01, 0x00, 0x01};
  clock.advance_by(hal::millis(1));
  auto w = stream.write(command);
  ASSERT_TRUE(w);
  EXPECT_EQ(*w, 3u);
  inner.max_write_bytes = 0;
  w = stream.write(std::span<const std::uint8_t>(command).subspan(3));  // nothing accepted: no record
  ASSERT_TRUE(w);
  EXPECT_EQ(*w, 0u);
  stream.note_baud_change(38400);
  ASSERT_TRUE(writer.close());

  const CaptureFile file = load_stream_capture(path);
  const auto r = file.records();
  ASSERT_EQ(r.size(), 5u);
  EXPECT_EQ(r[0].kind, RecordKind::rx);
  EXPECT_EQ(r[0].channel, 1);
  EXPECT_EQ(r[0].t_ns, hal::millis(2));
  EXPECT_EQ(span_bytes(r[0].payload), (Bytes{1, 2, 3, 4}));
  EXPECT_EQ(r[1].t_ns, hal::millis(3));
  EXPECT_EQ(span_bytes(r[1].payload), (Bytes{5, 6}));
  EXPECT_EQ(r[2].kind, RecordKind::tx);
  EXPECT_EQ(r[2].t_ns, hal::millis(4));
  EXPECT_EQ(span_bytes(r[2].payload), (Bytes{0xFA, 0xFB, 0x03}));
  EXPECT_EQ(r[3].kind, RecordKind::baud_change);
  EXPECT_EQ(r[3].baud, 38400u);
  EXPECT_EQ(r[4].kind, RecordKind::end);
}

// ---------------------------------- ReplayStream -----------------------------------

// Channel 0 rx: "abc" at 10 ms, "defgh" and "ij" at 25 ms; tx 6 bytes; channel 1 rx "zz" at 5 ms.
CaptureFile small_capture() {
  test::FileBuilder b;
  b.header(test::two_channel_info())
      .rx(hal::millis(5), 1, Bytes{'z', 'z'})
      .tx(hal::millis(6), 0, Bytes{1, 2, 3})
      .rx(hal::millis(10), 0, Bytes{'a', 'b', 'c'})
      .tx(hal::millis(12), 0, Bytes{4, 5, 6})
      .baud(hal::millis(20), 0, 19200)
      .rx(hal::millis(25), 0, Bytes{'d', 'e', 'f', 'g', 'h'})
      .rx(hal::millis(25), 0, Bytes{'i', 'j'})
      .rx(hal::millis(26), 0, Bytes{})
      .end(hal::millis(30), 8, 0);
  return parse_ok(b.bytes());
}

Bytes read_now(ReplayStream& replay, std::size_t buffer_bytes) {
  Bytes buf(buffer_bytes);
  auto n = replay.read(buf);
  if (!n) {
    ADD_FAILURE() << n.error().c_str();
    return {};
  }
  buf.resize(*n);
  return buf;
}

TEST(ReplayStream, OriginalTimingOnSimClockReleasesBytesAtTheirTimestamps) {
  const CaptureFile capture = small_capture();
  hal::SimClock clock(hal::seconds(50));  // the replay time line starts wherever the clock is
  ReplayStream replay(capture, 0, clock, ReplayTiming::original);
  EXPECT_EQ(replay.name(), "replay:p2os");
  EXPECT_EQ(replay.poll_fd(), -1);
  EXPECT_EQ(replay.rx_bytes_total(), 10u);
  ASSERT_EQ(replay.baud_changes().size(), 1u);
  EXPECT_EQ(replay.baud_changes()[0].baud, 19200u);
  EXPECT_EQ(replay.next_due_ns(), hal::seconds(50) + hal::millis(10));

  EXPECT_TRUE(read_now(replay, 64).empty());
  clock.advance_to(hal::seconds(50) + hal::millis(10) - 1);
  EXPECT_TRUE(read_now(replay, 64).empty());  // one nanosecond early
  clock.advance_by(1);
  EXPECT_EQ(read_now(replay, 64), (Bytes{'a', 'b', 'c'}));
  EXPECT_TRUE(read_now(replay, 64).empty());

  clock.advance_to(hal::seconds(51));  // long after: both 25 ms records are due
  EXPECT_EQ(read_now(replay, 2), (Bytes{'d', 'e'}));       // smaller buffer: fewer bytes
  EXPECT_EQ(read_now(replay, 64), (Bytes{'f', 'g', 'h'}));  // never across a record boundary
  EXPECT_EQ(read_now(replay, 64), (Bytes{'i', 'j'}));
  EXPECT_TRUE(replay.finished());  // the empty record carries nothing to deliver
  EXPECT_FALSE(replay.next_due_ns().has_value());
  Bytes buf(8);
  auto n = replay.read(buf);
  ASSERT_FALSE(n);
  EXPECT_EQ(n.error().code(), Errc::disconnected);
  EXPECT_THAT(std::string(n.error().message()), HasSubstr("replay finished"));
  EXPECT_EQ(replay.rx_bytes_delivered(), 10u);
}

TEST(ReplayStream, ReplayStartCanBeMoved) {
  const CaptureFile capture = small_capture();
  hal::SimClock clock;
  ReplayStream replay(capture, 1, clock, ReplayTiming::original);
  replay.set_replay_start(hal::seconds(2));
  EXPECT_EQ(replay.replay_start_ns(), hal::seconds(2));
  clock.advance_to(hal::seconds(2) + hal::millis(5) - 1);
  EXPECT_TRUE(read_now(replay, 8).empty());
  clock.advance_by(1);
  EXPECT_EQ(read_now(replay, 8), (Bytes{'z', 'z'}));
}

TEST(ReplayStream, OriginalTimingOnPosixClockFollowsRealTime) {
  test::FileBuilder b;
  b.header(test::two_channel_info()).rx(0, 0, Bytes{1}).rx(hal::millis(30), 0, Bytes{2});
  const CaptureFile capture = parse_ok(b.bytes());
  hal::PosixClock clock;
  const hal::Nanos start_ns = clock.now();
  ReplayStream replay(capture, 0, clock, ReplayTiming::original);
  EXPECT_EQ(read_now(replay, 8), Bytes{1});
  Bytes second;
  while (second.empty() && clock.now() - start_ns < hal::seconds(5)) {
    second = read_now(replay, 8);
    if (second.empty()) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_EQ(second, Bytes{2});
  EXPECT_GE(clock.now() - replay.replay_start_ns(), hal::millis(30));
}

TEST(ReplayStream, AsFastAsPossibleAdvancesTheSimClockThroughTheWholeCapture) {
  const CaptureFile capture = load_stream_capture(test::captures_dir() / "synthetic_session.s3bcap");
  for (const std::uint8_t channel : {test::kP2osChannel, test::kLms200Channel}) {
    hal::SimClock clock;
    ReplayStream replay(capture, channel, clock, ReplayTiming::as_fast_as_possible);
    hal::Nanos last_rx_ns = 0;
    std::size_t rx_records = 0;
    for (const Record& r : capture.records()) {
      if (r.channel == channel && r.kind == RecordKind::rx) {
        last_rx_ns = r.t_ns;
        ++rx_records;
      }
    }
    ASSERT_GT(rx_records, 0u);
    Bytes received;
    std::size_t reads = 0;
    const auto wall_start = std::chrono::steady_clock::now();
    for (;;) {
      std::uint8_t buf[test::kFirmwareReadBytes];
      auto n = replay.read(buf);
      if (!n) {
        EXPECT_EQ(n.error().code(), Errc::disconnected);
        break;
      }
      ASSERT_GT(*n, 0u) << "as fast as possible never returns an empty read";
      received.insert(received.end(), buf, buf + *n);
      ++reads;
    }
    EXPECT_EQ(reads, rx_records);
    EXPECT_EQ(received, capture.stream_bytes(channel, Direction::rx));
    EXPECT_EQ(clock.now(), last_rx_ns);  // the sim clock ends at the last record's time
    EXPECT_LT(std::chrono::steady_clock::now() - wall_start, std::chrono::seconds(1));
  }
}

TEST(ReplayStream, AsFastAsPossibleOnARealClockIgnoresTimestamps) {
  test::FileBuilder b;
  b.header(test::two_channel_info()).rx(hal::seconds(3600), 0, Bytes{9, 9});
  const CaptureFile capture = parse_ok(b.bytes());
  hal::PosixClock clock;
  ReplayStream replay(capture, 0, clock, ReplayTiming::as_fast_as_possible);
  EXPECT_EQ(read_now(replay, 8), (Bytes{9, 9}));
}

TEST(ReplayStream, RecordTimesNearTheLimitSaturate) {
  test::FileBuilder b;
  b.header(test::two_channel_info()).rx(INT64_MAX - 1, 0, Bytes{7});
  const CaptureFile capture = parse_ok(b.bytes());
  hal::SimClock clock(hal::seconds(5));
  ReplayStream replay(capture, 0, clock, ReplayTiming::original);
  EXPECT_EQ(replay.next_due_ns(), INT64_MAX);
  EXPECT_TRUE(read_now(replay, 8).empty());
  clock.advance_to(INT64_MAX);
  EXPECT_EQ(read_now(replay, 8), Bytes{7});
}

TEST(ReplayStream, ChannelWithoutRxIsFinishedAtOnce) {
  const CaptureFile capture = small_capture();
  hal::SimClock clock;
  ReplayStream replay(capture, 7, clock, ReplayTiming::original);  // not declared
  EXPECT_EQ(replay.name(), "replay:channel-7");
  EXPECT_TRUE(replay.finished());
  Bytes buf(4);
  EXPECT_FALSE(replay.read(buf));
}

TEST(ReplayStream, TxComparisonMatchesWhatWasRecorded) {
  const CaptureFile capture = small_capture();
  hal::SimClock clock;
  ReplayStream replay(capture, 0, clock, ReplayTiming::original);
  auto w = replay.write(Bytes{1, 2});
  ASSERT_TRUE(w);
  EXPECT_EQ(*w, 2u);
  ASSERT_TRUE(replay.write(Bytes{3, 4, 5, 6}));  // split differently from the recording: fine
  const TxComparison& c = replay.tx_comparison();
  EXPECT_EQ(c.expected_bytes, 6u);
  EXPECT_EQ(c.written_bytes, 6u);
  EXPECT_EQ(c.matched_bytes, 6u);
  EXPECT_EQ(c.mismatched_bytes, 0u);
  EXPECT_EQ(c.first_mismatch_offset, -1);
  EXPECT_TRUE(c.identical());
}

TEST(ReplayStream, TxComparisonReportsTheFirstMismatch) {
  const CaptureFile capture = small_capture();
  hal::SimClock clock;
  ReplayStream replay(capture, 0, clock, ReplayTiming::original);
  ASSERT_TRUE(replay.write(Bytes{1, 2, 3, 4, 0x55, 6}));  // offset 4: 5 expected
  ASSERT_TRUE(replay.write(Bytes{7}));                    // one byte more than recorded
  const TxComparison& c = replay.tx_comparison();
  EXPECT_EQ(c.written_bytes, 7u);
  EXPECT_EQ(c.matched_bytes, 5u);
  EXPECT_EQ(c.mismatched_bytes, 2u);
  EXPECT_EQ(c.first_mismatch_offset, 4);
  EXPECT_EQ(c.first_mismatch_expected, 5);
  EXPECT_EQ(c.first_mismatch_actual, 0x55);
  EXPECT_FALSE(c.identical());
}

TEST(ReplayStream, TxComparisonPastTheEndAndShortWrites) {
  const CaptureFile capture = small_capture();
  hal::SimClock clock;
  ReplayStream extra(capture, 0, clock, ReplayTiming::original);
  ASSERT_TRUE(extra.write(Bytes{1, 2, 3, 4, 5, 6, 0xEE}));
  EXPECT_EQ(extra.tx_comparison().first_mismatch_offset, 6);
  EXPECT_EQ(extra.tx_comparison().first_mismatch_expected, -1);
  EXPECT_EQ(extra.tx_comparison().first_mismatch_actual, 0xEE);

  ReplayStream short_write(capture, 0, clock, ReplayTiming::original);
  ASSERT_TRUE(short_write.write(Bytes{1, 2, 3}));
  EXPECT_EQ(short_write.tx_comparison().mismatched_bytes, 0u);
  EXPECT_FALSE(short_write.tx_comparison().identical());  // three recorded bytes never sent
}

}  // namespace
}  // namespace sen3bot::capture
