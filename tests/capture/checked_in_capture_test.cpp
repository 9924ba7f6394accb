// The checked-in captures: they decode to exactly the session the generator scripts, and a
// replay through the same firmware-side code re-records byte-identical rx streams.
#include <gmock/gmock.h>
#include <gtest/gtest.h>

#include <algorithm>

#include "capture_test_util.hpp"
#include "loopback_session.hpp"
#include "sen3bot/capture/reader.hpp"
#include "sen3bot/capture/recording_stream.hpp"
#include "sen3bot/capture/replay_stream.hpp"
#include "sen3bot/capture/writer.hpp"

namespace sen3bot::capture {
namespace {

using test::Bytes;

CaptureFile load_checked_in(const std::filesystem::path& path) {
  auto file = CaptureFile::load(path);
  if (!file) ADD_FAILURE() << file.error().c_str();
  return std::move(file).value();
}

// What the generator's script says the capture must hold.
void expect_matches_script(const CaptureFile& capture) {
  ASSERT_EQ(capture.info().channels.size(), 2u);
  const ChannelDecl* p2os = capture.find_channel("p2os");
  const ChannelDecl* lms = capture.find_channel("lms200");
  ASSERT_NE(p2os, nullptr);
  ASSERT_NE(lms, nullptr);
  EXPECT_EQ(p2os->id, test::kP2osChannel);
  EXPECT_EQ(lms->id, test::kLms200Channel);
  EXPECT_EQ(p2os->baud, test::kStartBaud);
  EXPECT_EQ(lms->baud, test::kStartBaud);
  EXPECT_TRUE(capture.complete());
  EXPECT_NE(capture.info().start_wall_ns, 0);

  const test::Script p2os_script = test::p2os_script();
  const test::Script lms_script = test::lms200_script();
  EXPECT_EQ(capture.stream_bytes(test::kP2osChannel, Direction::tx), test::script_tx(p2os_script));
  EXPECT_EQ(capture.stream_bytes(test::kP2osChannel, Direction::rx), test::script_rx(p2os_script));
  EXPECT_EQ(capture.stream_bytes(test::kLms200Channel, Direction::tx), test::script_tx(lms_script));
  EXPECT_EQ(capture.stream_bytes(test::kLms200Channel, Direction::rx), test::script_rx(lms_script));

  std::vector<std::uint32_t> bauds;
  std::uint64_t dropped = 0;
  for (const Record& r : capture.records()) {
    if (r.kind == RecordKind::baud_change) {
      EXPECT_EQ(r.channel, test::kLms200Channel);
      bauds.push_back(r.baud);
    }
    if (r.kind == RecordKind::gap) dropped += r.dropped_records;
    if (r.kind == RecordKind::rx) {
      EXPECT_LE(r.payload.size(), test::kFirmwareReadBytes);
    }
  }
  EXPECT_EQ(bauds, std::vector<std::uint32_t>{test::kLmsFastBaud});
  EXPECT_EQ(dropped, 0u);
}

struct RxRecord {
  hal::Nanos t_ns;
  Bytes bytes;
  bool operator==(const RxRecord&) const = default;
};

std::vector<RxRecord> rx_records(const CaptureFile& capture, std::uint8_t channel) {
  std::vector<RxRecord> out;
  for (const Record& r : capture.records())
    if (r.channel == channel && r.kind == RecordKind::rx) out.push_back({r.t_ns, Bytes(r.payload.begin(), r.payload.end())});
  return out;
}

// capture -> ReplayStream (original timing, one lockstep SimClock) -> the firmware-side
// session code -> RecordingStream -> new capture. The rx records must come out identical,
// time and chunking included, and the firmware must have sent exactly the recorded tx.
void replay_and_rerecord(const CaptureFile& original) {
  hal::SimClock clock(0);
  ReplayStream p2os_replay(original, test::kP2osChannel, clock, ReplayTiming::original);
  ReplayStream lms_replay(original, test::kLms200Channel, clock, ReplayTiming::original);

  const auto path = test::scratch_path("rerecorded.s3bcap");
  CaptureWriter writer(1 << 20);
  ASSERT_TRUE(writer.open(path, test::session_info(original.info().start_wall_ns, clock.now())));
  RecordingStream p2os(p2os_replay, writer, test::kP2osChannel, clock);
  RecordingStream lms(lms_replay, writer, test::kLms200Channel, clock);
  const test::Script p2os_script = test::p2os_script();
  const test::Script lms_script = test::lms200_script();
  test::FirmwareChannel channels[] = {{p2os, p2os_script, &p2os}, {lms, lms_script, &lms}};

  int waits = 0;
  const Status session = test::run_firmware_side(channels, [&] {
    // Lockstep: jump to whichever replay has the next record due.
    std::optional<hal::Nanos> next_ns;
    for (const ReplayStream* r : {&p2os_replay, &lms_replay})
      if (auto due = r->next_due_ns(); due && (!next_ns || *due < *next_ns)) next_ns = due;
    if (!next_ns || ++waits > 100'000) return false;
    clock.advance_to(*next_ns);
    return true;
  });
  ASSERT_TRUE(session) << session.error().c_str();
  ASSERT_TRUE(writer.close());

  EXPECT_TRUE(p2os_replay.finished());
  EXPECT_TRUE(lms_replay.finished());
  for (const ReplayStream* r : {&p2os_replay, &lms_replay}) {
    const TxComparison& c = r->tx_comparison();
    EXPECT_TRUE(c.identical()) << r->name() << ": first mismatch at tx offset " << c.first_mismatch_offset;
    EXPECT_GT(c.matched_bytes, 0u);
  }

  const CaptureFile rerecorded = load_checked_in(path);
  for (const std::uint8_t channel : {test::kP2osChannel, test::kLms200Channel}) {
    const auto before = rx_records(original, channel);
    const auto after = rx_records(rerecorded, channel);
    ASSERT_EQ(after.size(), before.size()) << "channel " << int{channel};
    for (std::size_t i = 0; i < before.size(); ++i) {
      EXPECT_EQ(after[i].t_ns, before[i].t_ns) << "channel " << int{channel} << " record " << i;
      EXPECT_EQ(after[i].bytes, before[i].bytes) << "channel " << int{channel} << " record " << i;
    }
    EXPECT_EQ(rerecorded.stream_bytes(channel, Direction::tx), original.stream_bytes(channel, Direction::tx));
  }
}

TEST(LoopbackCapture, DecodesToTheScriptedSession) {
  expect_matches_script(load_checked_in(test::captures_dir() / "loopback_session.s3bcap"));
}

TEST(LoopbackCapture, ReplayReRecordsByteIdenticalRxStreams) {
  replay_and_rerecord(load_checked_in(test::captures_dir() / "loopback_session.s3bcap"));
}

TEST(LoopbackCapture, AsFastReplayEndsAtTheLastRecordTime) {
  const CaptureFile capture = load_checked_in(test::captures_dir() / "loopback_session.s3bcap");
  const std::vector<RxRecord> expected = rx_records(capture, test::kLms200Channel);
  ASSERT_FALSE(expected.empty());
  hal::SimClock clock;
  ReplayStream replay(capture, test::kLms200Channel, clock, ReplayTiming::as_fast_as_possible);
  Bytes received;
  std::uint8_t buf[test::kFirmwareReadBytes];
  for (auto n = replay.read(buf); n; n = replay.read(buf)) received.insert(received.end(), buf, buf + *n);
  EXPECT_EQ(received, test::script_rx(test::lms200_script()));
  EXPECT_EQ(clock.now(), expected.back().t_ns);
  // The session took real time to record; the replay's simulated time says so.
  EXPECT_GT(clock.now(), hal::millis(100));
}

TEST(SyntheticCapture, DecodesToTheScriptedSession) {
  expect_matches_script(load_checked_in(test::captures_dir() / "synthetic_session.s3bcap"));
}

TEST(SyntheticCapture, ReplayReRecordsByteIdenticalRxStreams) {
  replay_and_rerecord(load_checked_in(test::captures_dir() / "synthetic_session.s3bcap"));
}

// The generator's live path still works: a fresh recording over real pseudo-terminals.
TEST(LiveLoopback, RecordsASessionOverRealPseudoTerminals) {
  const auto path = test::scratch_path("live.s3bcap");
  const Status recorded = test::record_loopback_session(path);
  if (!recorded && recorded.error().code() == Errc::not_supported) GTEST_SKIP() << recorded.error().c_str();
  ASSERT_TRUE(recorded) << recorded.error().c_str();
  const CaptureFile capture = load_checked_in(path);
  expect_matches_script(capture);
  replay_and_rerecord(capture);
}

}  // namespace
}  // namespace sen3bot::capture
