// CaptureWriter -> file -> CaptureReader / CaptureFile round trips, drop accounting, golden file.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <cstdint>
#include <atomic>
#include <thread>

#include "capture_test_util.hpp"
#include "loopback_session.hpp"
#include "sen3bot/capture/reader.hpp"
#include "sen3bot/capture/writer.hpp"

namespace sen3bot::capture {
namespace {

using test::Bytes;
using ::testing::HasSubstr;

Bytes all_byte_values() {
  Bytes b(256);
  for (std::size_t i = 0; i < b.size(); ++i) b[i] = static_cast<std::uint8_t>(i);
  return b;
}

CaptureFile load_ok(const std::filesystem::path& path) {
  auto file = CaptureFile::load(path);
  if (!file) ADD_FAILURE() << file.error().c_str();
  return std::move(file).value();
}

TEST(CaptureWriter, RoundTripsChannelsDirectionsTimesAndPayloads) {
  const CaptureInfo info = test::two_channel_info();
  const hal::Nanos t0 = info.start_monotonic_ns;
  const auto path = test::scratch_path("roundtrip.s3bcap");
  const Bytes every_byte = all_byte_values();
  const Bytes sync0 = {0xFA, 0xFB, 0x03, 0x00, 0x00, 0x00};
  {
    CaptureWriter writer(4096);
    ASSERT_TRUE(writer.open(path, info));
    EXPECT_TRUE(writer.record(t0 + 0, 0, Direction::tx, sync0));
    EXPECT_TRUE(writer.record(t0 + hal::micros(1500), 0, Direction::rx, every_byte));
    EXPECT_TRUE(writer.record(t0 + hal::micros(1500), 1, Direction::tx, Bytes{}));  // empty payload
    EXPECT_TRUE(writer.record_baud_change(t0 + hal::millis(7), 1, 38400));
    EXPECT_TRUE(writer.record(t0 + hal::seconds(3) + 1, 1, Direction::rx, Bytes{0x06}));
    EXPECT_EQ(writer.records_written(), 5u);
    EXPECT_EQ(writer.dropped_records(), 0u);
    ASSERT_TRUE(writer.close());
    EXPECT_FALSE(writer.is_open());
  }
  const CaptureFile file = load_ok(path);
  EXPECT_EQ(file.info().start_wall_ns, info.start_wall_ns);
  EXPECT_EQ(file.info().start_monotonic_ns, info.start_monotonic_ns);
  ASSERT_EQ(file.info().channels.size(), 2u);
  EXPECT_EQ(file.info().channels[0].name, "p2os");
  EXPECT_EQ(file.info().channels[0].baud, 9600u);
  EXPECT_EQ(file.info().channels[1].id, 1);
  EXPECT_EQ(file.info().channels[1].name, "lms200");
  ASSERT_NE(file.find_channel("lms200"), nullptr);
  EXPECT_EQ(file.find_channel("camera"), nullptr);
  EXPECT_TRUE(file.complete());

  const auto records = file.records();
  ASSERT_EQ(records.size(), 6u);
  EXPECT_EQ(records[0].t_ns, 0);
  EXPECT_EQ(records[0].kind, RecordKind::tx);
  EXPECT_EQ(Bytes(records[0].payload.begin(), records[0].payload.end()), sync0);
  EXPECT_EQ(records[1].t_ns, hal::micros(1500));
  EXPECT_EQ(records[1].kind, RecordKind::rx);
  EXPECT_EQ(records[1].channel, 0);
  EXPECT_EQ(Bytes(records[1].payload.begin(), records[1].payload.end()), every_byte);
  EXPECT_EQ(records[2].channel, 1);
  EXPECT_EQ(records[2].kind, RecordKind::tx);
  EXPECT_TRUE(records[2].payload.empty());
  EXPECT_EQ(records[3].kind, RecordKind::baud_change);
  EXPECT_EQ(records[3].baud, 38400u);
  EXPECT_EQ(records[3].t_ns, hal::millis(7));
  EXPECT_EQ(records[4].t_ns, hal::seconds(3) + 1);
  EXPECT_EQ(records[5].kind, RecordKind::end);
  EXPECT_EQ(records[5].written_records, 5u);
  EXPECT_EQ(records[5].dropped_records, 0u);
  EXPECT_EQ(records[5].t_ns, records[4].t_ns);
  EXPECT_EQ(file.stream_bytes(0, Direction::rx), every_byte);
  EXPECT_EQ(file.stream_bytes(0, Direction::tx), sync0);
}

TEST(CaptureWriter, CursorReaderSeesTheSameRecordsAsCaptureFile) {
  const auto path = test::scratch_path("synthetic.s3bcap");
  ASSERT_TRUE(test::write_synthetic_session(path));
  const Bytes bytes = test::read_bytes(path);
  auto reader = CaptureReader::open(bytes);
  ASSERT_TRUE(reader) << reader.error().c_str();
  const CaptureFile file = load_ok(path);
  std::size_t i = 0;
  for (;;) {
    auto next = reader->next();
    ASSERT_TRUE(next) << next.error().c_str();
    if (!next->has_value()) break;
    ASSERT_LT(i, file.records().size());
    EXPECT_EQ((*next)->file_offset, file.records()[i].file_offset);
    EXPECT_EQ((*next)->t_ns, file.records()[i].t_ns);
    ++i;
  }
  EXPECT_EQ(i, file.records().size());
  EXPECT_TRUE(reader->saw_end_record());
  EXPECT_EQ(reader->offset(), bytes.size());
  auto again = reader->next();  // stays at the end
  ASSERT_TRUE(again);
  EXPECT_FALSE(again->has_value());
}

TEST(CaptureWriter, TimesAreRelativeToStartAndNeverDecrease) {
  const CaptureInfo info = test::two_channel_info();
  const hal::Nanos t0 = info.start_monotonic_ns;
  const auto path = test::scratch_path("clamp.s3bcap");
  CaptureWriter writer(1024);
  ASSERT_TRUE(writer.open(path, info));
  EXPECT_TRUE(writer.record(t0 - 5, 0, Direction::rx, Bytes{1}));             // before the start
  EXPECT_TRUE(writer.record(t0 + hal::millis(5), 0, Direction::rx, Bytes{2}));
  EXPECT_TRUE(writer.record(t0 + hal::millis(3), 1, Direction::rx, Bytes{3}));  // a caller's clock went back
  EXPECT_TRUE(writer.record(INT64_MIN, 1, Direction::rx, Bytes{4}));  // now - start would overflow
  ASSERT_TRUE(writer.close());
  const CaptureFile file = load_ok(path);
  ASSERT_EQ(file.records().size(), 5u);
  EXPECT_EQ(file.records()[0].t_ns, 0);
  EXPECT_EQ(file.records()[1].t_ns, hal::millis(5));
  EXPECT_EQ(file.records()[2].t_ns, hal::millis(5));
  EXPECT_EQ(file.records()[3].t_ns, hal::millis(5));
}

TEST(CaptureWriter, SplitsPayloadsLargerThanTheBound) {
  const auto path = test::scratch_path("split.s3bcap");
  Bytes big(2 * kMaxPayloadBytes + 100);
  for (std::size_t i = 0; i < big.size(); ++i) big[i] = static_cast<std::uint8_t>(i * 7);
  CaptureWriter writer(4 * kMaxPayloadBytes);
  ASSERT_TRUE(writer.open(path, test::two_channel_info()));
  EXPECT_TRUE(writer.record(test::two_channel_info().start_monotonic_ns + 42, 1, Direction::rx, big));
  EXPECT_EQ(writer.records_written(), 3u);
  ASSERT_TRUE(writer.close());
  const CaptureFile file = load_ok(path);
  ASSERT_EQ(file.records().size(), 4u);
  EXPECT_EQ(file.records()[0].payload.size(), kMaxPayloadBytes);
  EXPECT_EQ(file.records()[2].payload.size(), 100u);
  EXPECT_EQ(file.records()[2].t_ns, 42);
  EXPECT_EQ(file.stream_bytes(1, Direction::rx), big);
}

TEST(CaptureWriter, FullBufferDropsCountsAndMarksGaps) {
  const CaptureInfo info = test::two_channel_info();
  const hal::Nanos t0 = info.start_monotonic_ns;
  const auto path = test::scratch_path("drops.s3bcap");
  const Bytes fifty(50, 0xAB);
  CaptureWriter writer(100);  // room for one 50-byte record (66 bytes) at a time
  ASSERT_TRUE(writer.open(path, info));
  EXPECT_TRUE(writer.record(t0 + 1, 0, Direction::rx, fifty));
  EXPECT_EQ(writer.buffered_bytes(), 66u);
  EXPECT_FALSE(writer.record(t0 + 2, 0, Direction::rx, fifty));
  EXPECT_FALSE(writer.record(t0 + 3, 0, Direction::tx, Bytes(20, 1)));
  EXPECT_EQ(writer.dropped_records(), 2u);
  EXPECT_EQ(writer.dropped_bytes(), 70u);
  ASSERT_TRUE(writer.flush());
  EXPECT_EQ(writer.buffered_bytes(), 0u);
  // Fits with the gap record in front of it (32 + 26 bytes), and wraps around the ring.
  EXPECT_TRUE(writer.record(t0 + 4, 1, Direction::rx, Bytes(10, 0xCD)));
  EXPECT_EQ(writer.buffered_bytes(), 58u);
  EXPECT_FALSE(writer.record(t0 + 5, 1, Direction::rx, fifty));  // reported by close()
  EXPECT_FALSE(writer.record(t0 + 6, 1, Direction::rx, Bytes(200, 0)));  // larger than the ring
  EXPECT_EQ(writer.dropped_records(), 4u);
  ASSERT_TRUE(writer.close());

  const CaptureFile file = load_ok(path);
  const auto r = file.records();
  ASSERT_EQ(r.size(), 5u);
  EXPECT_EQ(r[0].kind, RecordKind::rx);
  EXPECT_EQ(r[1].kind, RecordKind::gap);
  EXPECT_EQ(r[1].dropped_records, 2u);
  EXPECT_EQ(r[1].dropped_bytes, 70u);
  EXPECT_EQ(r[1].t_ns, 4);  // where recording resumed
  EXPECT_EQ(r[2].kind, RecordKind::rx);
  EXPECT_EQ(r[2].payload.size(), 10u);
  EXPECT_EQ(r[3].kind, RecordKind::gap);
  EXPECT_EQ(r[3].dropped_records, 2u);
  EXPECT_EQ(r[3].dropped_bytes, 250u);
  EXPECT_EQ(r[4].kind, RecordKind::end);
  EXPECT_EQ(r[4].written_records, 2u);
  EXPECT_EQ(r[4].dropped_records, 4u);
}

TEST(CaptureWriter, RefusesUndeclaredChannelsAndRecordsWhileClosed) {
  const auto path = test::scratch_path("refuse.s3bcap");
  CaptureWriter writer(1024);
  EXPECT_FALSE(writer.record(0, 0, Direction::rx, Bytes{1}));  // not open yet
  EXPECT_EQ(writer.rejected_records(), 1u);
  ASSERT_TRUE(writer.open(path, test::two_channel_info()));  // starts counting afresh
  EXPECT_FALSE(writer.record(0, 7, Direction::rx, Bytes{1}));
  EXPECT_FALSE(writer.record(0, kNoChannel, Direction::rx, Bytes{1}));
  EXPECT_FALSE(writer.record_baud_change(0, 9, 19200));
  ASSERT_TRUE(writer.close());
  EXPECT_FALSE(writer.record(0, 0, Direction::rx, Bytes{1}));
  EXPECT_EQ(writer.rejected_records(), 4u);
  EXPECT_EQ(writer.dropped_records(), 0u);
  const CaptureFile file = load_ok(path);
  EXPECT_EQ(file.records().size(), 1u);  // just the end record
}

TEST(CaptureWriter, OpenValidatesTheChannelTable) {
  const auto path = test::scratch_path("bad-open.s3bcap");
  CaptureInfo info = test::two_channel_info();
  info.channels[1].id = 0;
  CaptureWriter writer(64);
  Status s = writer.open(path, info);
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code(), Errc::invalid_argument);
  EXPECT_THAT(s.error().message(), HasSubstr("declared twice"));

  info = test::two_channel_info();
  info.channels[0].id = kNoChannel;
  EXPECT_FALSE(writer.open(path, info));
  info = test::two_channel_info();
  info.channels[0].name = "has space";
  EXPECT_FALSE(writer.open(path, info));
  info.channels[0].name = "";
  EXPECT_FALSE(writer.open(path, info));
  info = test::two_channel_info();
  info.channels.clear();
  for (std::uint8_t i = 0; i <= kMaxChannels; ++i) info.channels.push_back({i, "c" + std::to_string(i), 0});
  EXPECT_FALSE(writer.open(path, info));

  s = writer.open("/nonexistent-dir/x.s3bcap", test::two_channel_info());
  ASSERT_FALSE(s);
  EXPECT_EQ(s.error().code(), Errc::not_found);
  ASSERT_TRUE(writer.open(path, test::two_channel_info()));
  EXPECT_FALSE(writer.open(path, test::two_channel_info()));  // already open
}

TEST(CaptureWriter, DestructorClosesTheFile) {
  const auto path = test::scratch_path("destructor.s3bcap");
  {
    CaptureWriter writer(256);
    ASSERT_TRUE(writer.open(path, test::two_channel_info()));
    EXPECT_TRUE(writer.record(test::two_channel_info().start_monotonic_ns, 0, Direction::rx, Bytes{1, 2}));
  }
  const CaptureFile file = load_ok(path);
  EXPECT_TRUE(file.complete());
  EXPECT_EQ(file.records().size(), 2u);
}

// One producer thread records sequence-numbered records through a small ring while a second
// thread flushes: everything that was accepted arrives in order, every loss is accounted for.
TEST(CaptureWriter, ProducerAndFlusherThreadsKeepOrderAndAccounting) {
  const auto path = test::scratch_path("spsc.s3bcap");
  constexpr std::uint32_t kRecords = 50'000;
  CaptureWriter writer(4096);
  ASSERT_TRUE(writer.open(path, test::two_channel_info()));
  std::atomic<bool> producing{true};
  std::thread flusher([&] {
    while (producing.load()) ASSERT_TRUE(writer.flush());
  });
  const hal::Nanos t0 = test::two_channel_info().start_monotonic_ns;
  for (std::uint32_t seq = 0; seq < kRecords; ++seq) {
    std::uint8_t payload[4 + 13];
    le::put_u32(payload, seq);
    for (std::size_t i = 4; i < sizeof payload; ++i) payload[i] = static_cast<std::uint8_t>(seq + i);
    (void)writer.record(t0 + seq, static_cast<std::uint8_t>(seq % 2), Direction::rx,
                        std::span<const std::uint8_t>(payload, 4 + seq % 14));
  }
  producing.store(false);
  flusher.join();
  ASSERT_TRUE(writer.close());
  EXPECT_EQ(writer.records_written() + writer.dropped_records(), kRecords);

  const CaptureFile file = load_ok(path);
  std::int64_t last_seq = -1;
  std::uint64_t data = 0, gap_dropped = 0;
  for (const Record& r : file.records()) {
    if (r.kind == RecordKind::gap) gap_dropped += r.dropped_records;
    if (r.kind != RecordKind::rx) continue;
    ++data;
    ASSERT_GE(r.payload.size(), 4u);
    const std::uint32_t seq = le::get_u32(r.payload.data());
    ASSERT_GT(static_cast<std::int64_t>(seq), last_seq);
    ASSERT_EQ(r.payload.size(), 4 + seq % 14);
    ASSERT_EQ(r.t_ns, static_cast<hal::Nanos>(seq));
    ASSERT_EQ(r.channel, seq % 2);
    for (std::size_t i = 4; i < r.payload.size(); ++i) {
      ASSERT_EQ(r.payload[i], static_cast<std::uint8_t>(seq + i));
    }
    last_seq = seq;
  }
  EXPECT_EQ(data, writer.records_written());
  EXPECT_EQ(gap_dropped, writer.dropped_records());
}

TEST(CaptureWriter, SyntheticSessionIsByteIdenticalToTheCheckedInFile) {
  // The checked-in file pins the format: if this fails, the writer changed the bytes it
  // produces; bump kFormatVersion or fix the writer, then regenerate (loopback_session.hpp).
  const auto path = test::scratch_path("synthetic-golden.s3bcap");
  ASSERT_TRUE(test::write_synthetic_session(path));
  const Bytes golden = test::read_bytes(test::captures_dir() / "synthetic_session.s3bcap");
  ASSERT_FALSE(golden.empty());
  EXPECT_TRUE(test::read_bytes(path) == golden);
}

TEST(CaptureReader, AcceptsACaptureThatWasNeverClosed) {
  test::FileBuilder b;
  b.header(test::two_channel_info()).rx(5, 0, Bytes{1, 2, 3}).tx(6, 1, Bytes{4});
  auto file = CaptureFile::parse(b.bytes());
  ASSERT_TRUE(file) << file.error().c_str();
  EXPECT_FALSE(file->complete());
  EXPECT_EQ(file->records().size(), 2u);
}

TEST(CaptureReader, AcceptsHeaderOnlyAndZeroChannels) {
  CaptureInfo info;
  test::FileBuilder b;
  b.header(info);
  auto file = CaptureFile::parse(b.bytes());
  ASSERT_TRUE(file) << file.error().c_str();
  EXPECT_TRUE(file->info().channels.empty());
  EXPECT_TRUE(file->records().empty());
  b.end(0, 0, 0);
  auto closed = CaptureFile::parse(b.bytes());
  ASSERT_TRUE(closed) << closed.error().c_str();
  EXPECT_TRUE(closed->complete());
}

}  // namespace
}  // namespace sen3bot::capture
