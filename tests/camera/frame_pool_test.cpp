#include <gtest/gtest.h>

#include <atomic>
#include <cstring>
#include <thread>

#include "sen3bot/camera/frame_pool.hpp"

namespace sen3bot::camera {
namespace {

TEST(FramePool, RejectsBadShapes) {
  EXPECT_FALSE(FramePool::create(2, 64, 64, PixelFormat::gray8).ok());
  EXPECT_FALSE(FramePool::create(4, 0, 64, PixelFormat::gray8).ok());
  EXPECT_FALSE(FramePool::create(4, 64, 9000, PixelFormat::gray8).ok());
}

TEST(FramePool, NewestFrameAndPinning) {
  auto pool = FramePool::create(3, 4, 2, PixelFormat::bgr8);
  ASSERT_TRUE(pool.ok());
  FramePool& p = **pool;
  EXPECT_EQ(p.bytes(), 3u * 4 * 2 * 3);
  EXPECT_FALSE(p.acquire_latest());
  const int a = p.begin_write();
  ASSERT_GE(a, 0);
  p.publish(a, 4, 2, 100, 1, 2);
  FrameHandle held = p.acquire_latest();
  ASSERT_TRUE(held);
  EXPECT_EQ(held.ref().sequence, 1u);
  EXPECT_EQ(held.ref().rtp_timestamp, 100u);
  // The writer can still go on: one slot newest (pinned), two free.
  const int b = p.begin_write();
  ASSERT_GE(b, 0);
  EXPECT_NE(b, a);
  p.publish(b, 4, 2, 200, 1, 2);
  const int c = p.begin_write();
  ASSERT_GE(c, 0);
  EXPECT_NE(c, a);  // pinned by the reader
  EXPECT_NE(c, b);  // newest
  FrameHandle second = p.acquire_latest();
  EXPECT_EQ(second.ref().sequence, 2u);
  p.publish(c, 4, 2, 300, 1, 2);
  // a pinned, c newest, b pinned: no slot free, the frame is dropped by the caller.
  EXPECT_EQ(p.begin_write(), -1);
  held.release();
  EXPECT_EQ(p.begin_write(), a);
}

// A writer thread fills each slot with one byte value and publishes; readers must never see
// a frame whose first and last bytes differ (a torn frame).
TEST(FramePool, ConcurrentReadersNeverSeeTornFrames) {
  auto pool = FramePool::create(4, 320, 240, PixelFormat::gray8);
  ASSERT_TRUE(pool.ok());
  FramePool& p = **pool;
  std::atomic<bool> done{false};
  std::atomic<std::uint64_t> torn{0};
  std::atomic<std::uint64_t> reads{0};
  std::thread writer([&] {
    for (std::uint32_t i = 1; i <= 20000; ++i) {
      const int slot = p.begin_write();
      if (slot < 0) continue;
      auto pixels = p.slot_pixels(slot);
      std::memset(pixels.data(), static_cast<int>(i & 0xFF), pixels.size());
      p.publish(slot, 320, 240, i, 0, 0);
    }
    done = true;
  });
  std::thread readers[2];
  for (auto& r : readers) {
    r = std::thread([&] {
      while (!done) {
        FrameHandle f = p.acquire_latest();
        if (!f) continue;
        const std::size_t n = std::size_t{f.ref().stride_bytes} * f.ref().height_px;
        const std::uint8_t first = f.ref().data[0];
        const std::uint8_t last = f.ref().data[n - 1];
        if (first != last || first != static_cast<std::uint8_t>(f.ref().rtp_timestamp & 0xFF)) ++torn;
        ++reads;
      }
    });
  }
  writer.join();
  for (auto& r : readers) r.join();
  EXPECT_EQ(torn.load(), 0u);
  EXPECT_GT(reads.load(), 0u);
}

}  // namespace
}  // namespace sen3bot::camera
