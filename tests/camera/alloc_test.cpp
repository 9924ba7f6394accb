// The steady-state frame path allocates nothing: RTP parsing, sequence tracking, the reorder
// buffer, both depacketizers and the frame hand-off, after start-up. (The decoders' library
// internals are outside this proof: libjpeg allocates work memory per image and libavcodec
// manages its reference pictures.)
#include <gtest/gtest.h>

#include "alloc_counter.hpp"
#include "camera_test_util.hpp"
#include "sen3bot/camera/depacketizer.hpp"
#include "sen3bot/camera/frame_pool.hpp"
#include "sen3bot/camera/rtp.hpp"

namespace sen3bot::camera {
namespace {

using mem::testing::AllocationScope;

struct CountingSink : EncodedFrameSink {
  std::uint64_t frames = 0;
  void on_frame(const EncodedFrame&) override { ++frames; }
};

TEST(CameraAllocation, FramePathAllocatesNothingInSteadyState) {
  H264Depacketizer h264(256 * 1024);
  h264.set_parameter_sets({{0x67, 0x42, 0xC0, 0x16}, {0x68, 0xCE, 0x3C, 0x80}});
  JpegDepacketizer jpeg(256 * 1024);
  ReorderBuffer reorder(8, 2048);
  SequenceTracker tracker;
  auto pool = FramePool::create(4, 64, 64, PixelFormat::gray8);
  ASSERT_TRUE(pool.ok());
  CountingSink sink;

  // Pre-built packets: an IDR in three FU-A fragments, then P slices; and two-packet JPEGs.
  std::vector<std::vector<std::uint8_t>> packets;
  std::uint16_t seq = 65000;  // wraps during the run
  std::uint32_t ts = 0;
  for (int frame = 0; frame < 300; ++frame, ts += 3000) {
    if (frame % 30 == 0) {
      packets.push_back(testing::rtp_packet(seq++, ts, false, 96, {0x7C, 0x85, 1, 2, 3}));
      packets.push_back(testing::rtp_packet(seq++, ts, false, 96, {0x7C, 0x05, 4, 5, 6}));
      packets.push_back(testing::rtp_packet(seq++, ts, true, 96, {0x7C, 0x45, 7, 8, 9}));
    } else {
      packets.push_back(testing::rtp_packet(seq++, ts, true, 96, {0x41, 0x9A, 1, 2}));
    }
  }
  std::vector<std::vector<std::uint8_t>> jpegs;
  for (int frame = 0; frame < 100; ++frame) {
    const auto t = static_cast<std::uint32_t>(frame * 6000);
    jpegs.push_back(testing::rtp_packet(seq++, t, false, 26, {0, 0, 0, 0, 1, 50, 8, 8, 1, 2, 3, 4}));
    jpegs.push_back(testing::rtp_packet(seq++, t, true, 26, {0, 0, 0, 4, 1, 50, 8, 8, 5, 6}));
  }

  auto run = [&] {
    for (const auto& bytes : packets) {
      auto p = parse_rtp(bytes);
      std::uint64_t ext = 0;
      if (!p || tracker.update(p->sequence, ext) != SequenceTracker::Verdict::accept) continue;
      (void)reorder.push(ext, bytes);
      ReorderBuffer::Released r;
      while (reorder.pop(r)) {
        auto q = parse_rtp(r.packet);
        h264.push(*q, r.lost_before > 0, 0, sink);
      }
    }
    for (const auto& bytes : jpegs) {
      auto p = parse_rtp(bytes);
      jpeg.push(*p, false, 0, sink);
    }
    for (int i = 0; i < 1000; ++i) {
      const int slot = (*pool)->begin_write();
      if (slot >= 0) (*pool)->publish(slot, 64, 64, 0, 0, 0);
      FrameHandle f = (*pool)->acquire_latest();
      ASSERT_TRUE(f);
    }
  };
  run();  // warm-up
  tracker.reset();
  reorder.clear();
  const std::uint64_t frames_before = sink.frames;
  AllocationScope scope;
  run();
  EXPECT_EQ(scope.allocations(), 0u);
  if (mem::testing::counts_malloc()) {
    EXPECT_EQ(scope.malloc_calls(), 0u);
  }
  EXPECT_GE(sink.frames - frames_before, 300u + 100u);
}

}  // namespace
}  // namespace sen3bot::camera

#include <atomic>
#include <thread>

#include "sen3bot/tasks/task.hpp"

namespace sen3bot::camera {
namespace {

// A real-time task reading the newest frame each step, as camera-laser fusion will: no
// allocation in step(), while a decoder-like thread publishes.
class FrameConsumerTask final : public tasks::Task {
 public:
  explicit FrameConsumerTask(FramePool& pool) : reader_(pool) {}
  Status init(std::pmr::memory_resource&) override { return {}; }
  void step(const tasks::StepContext&) override {
    if (FrameHandle f = reader_.newer()) {
      checksum_ += f.ref().data[0];
      ++frames_;
    }
  }
  FrameReader reader_;
  std::uint64_t frames_ = 0;
  std::uint64_t checksum_ = 0;
};

TEST(CameraAllocation, RealTimeReaderTaskAllocatesNothing) {
  auto pool = FramePool::create(4, 32, 32, PixelFormat::gray8);
  ASSERT_TRUE(pool.ok());
  FrameConsumerTask task(**pool);
  std::atomic<bool> done{false};
  // Warm-up publish so the first step already has something to read.
  (*pool)->publish((*pool)->begin_write(), 32, 32, 0, 0, 0);
  std::thread writer([&] {
    while (!done) {
      const int slot = (*pool)->begin_write();
      if (slot >= 0) (*pool)->publish(slot, 32, 32, 0, 0, 0);
      std::this_thread::yield();
    }
  });
  AllocationScope scope;
  for (std::uint64_t cycle = 0; cycle < 200'000; ++cycle) task.step(tasks::StepContext{0, 0, cycle});
  const auto allocations = scope.allocations();
  done = true;
  writer.join();
  EXPECT_EQ(allocations, 0u);
  EXPECT_GT(task.frames_, 0u);
  (void)task.reader_.newer();  // at most one frame published after the last step
  EXPECT_FALSE(task.reader_.newer());
}

}  // namespace
}  // namespace sen3bot::camera
