// record(), ReplayStream::read/write and RecordingStream never allocate once constructed.
// This executable replaces global operator new with a counting one.
#include <gtest/gtest.h>

#include <atomic>
#include <cstdlib>
#include <new>

#include "capture_test_util.hpp"
#include "loopback_session.hpp"
#include "sen3bot/capture/reader.hpp"
#include "sen3bot/capture/recording_stream.hpp"
#include "sen3bot/capture/replay_stream.hpp"
#include "sen3bot/capture/writer.hpp"

namespace {
std::atomic<long> g_allocations{0};

// Out of line so GCC does not pair the inlined malloc/free with new/delete and warn
// (-Wmismatched-new-delete) about the replacement functions themselves.
[[gnu::noinline]] void* counted_alloc(std::size_t size) {
  g_allocations.fetch_add(1, std::memory_order_relaxed);
  if (void* p = std::malloc(size > 0 ? size : 1)) return p;
  throw std::bad_alloc();
}
[[gnu::noinline]] void counted_free(void* p) noexcept { std::free(p); }
}  // namespace

void* operator new(std::size_t size) { return counted_alloc(size); }
void* operator new[](std::size_t size) { return counted_alloc(size); }
void operator delete(void* p) noexcept { counted_free(p); }
void operator delete[](void* p) noexcept { counted_free(p); }
void operator delete(void* p, std::size_t) noexcept { counted_free(p); }
void operator delete[](void* p, std::size_t) noexcept { counted_free(p); }

namespace sen3bot::capture {
namespace {

using test::Bytes;

TEST(CaptureAllocations, RecordNeverAllocates) {
  const auto path = test::scratch_path("alloc-record.s3bcap");
  CaptureWriter writer(1 << 16);
  ASSERT_TRUE(writer.open(path, test::two_channel_info()));
  const Bytes payload(100, 0x42);
  const hal::Nanos t0 = test::two_channel_info().start_monotonic_ns;
  const long before = g_allocations.load();
  for (int i = 0; i < 10'000; ++i) {  // fills the ring, then drops: both paths covered
    (void)writer.record(t0 + i, static_cast<std::uint8_t>(i % 2), Direction::rx, payload);
    (void)writer.record_baud_change(t0 + i, 1, 38400);
  }
  EXPECT_EQ(g_allocations.load() - before, 0);
  EXPECT_GT(writer.dropped_records(), 0u);
  ASSERT_TRUE(writer.close());
}

TEST(CaptureAllocations, ReplayAndRecordingStreamsNeverAllocate) {
  auto capture = CaptureFile::load(test::captures_dir() / "synthetic_session.s3bcap");
  ASSERT_TRUE(capture) << capture.error().c_str();
  hal::SimClock clock;
  ReplayStream replay(*capture, test::kLms200Channel, clock, ReplayTiming::as_fast_as_possible);
  CaptureWriter writer(1 << 20);
  ASSERT_TRUE(writer.open(test::scratch_path("alloc-replay.s3bcap"), test::session_info(1, 0)));
  RecordingStream stream(replay, writer, test::kLms200Channel, clock);
  const Bytes tx = test::script_tx(test::lms200_script());
  std::uint8_t buf[test::kFirmwareReadBytes];

  const long before = g_allocations.load();
  ASSERT_TRUE(stream.write(tx));
  std::size_t received = 0;
  for (auto n = stream.read(buf); n; n = stream.read(buf)) received += *n;
  const long during = g_allocations.load() - before;

  EXPECT_EQ(during, 0);
  EXPECT_EQ(received, replay.rx_bytes_total());
  EXPECT_TRUE(replay.tx_comparison().identical());
  ASSERT_TRUE(writer.close());
}

}  // namespace
}  // namespace sen3bot::capture
