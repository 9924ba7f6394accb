// The on-board detector's row: a real photograph put into the camera's frame pool as the
// decoder would, found by the task at its rate, and published in the calibration's pixels on
// the detections topic with the frame's arrival time.
#include <gtest/gtest.h>

#include <cstring>
#include <memory_resource>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>

#include "vision_task.hpp"

namespace sen3bot::firmware {
namespace {

constexpr hal::Nanos kMs = 1'000'000;

// basketball1.png (OpenCV's samples, Apache-2.0, from Debian's opencv-doc) as a decoded frame.
void publish_photo(camera::FramePool& pool, hal::Nanos arrival_ns) {
  const cv::Mat photo = cv::imread("/usr/share/doc/opencv-doc/examples/data/basketball1.png", cv::IMREAD_COLOR);
  ASSERT_FALSE(photo.empty()) << "opencv-doc's sample images are missing: toolchain/bootstrap.sh installs them";
  ASSERT_EQ(photo.cols, 640);
  const int slot = pool.begin_write();
  ASSERT_GE(slot, 0);
  const std::span<std::uint8_t> pixels = pool.slot_pixels(slot);
  for (int row = 0; row < photo.rows; ++row)
    std::memcpy(pixels.data() + static_cast<std::size_t>(row) * 640 * 3, photo.ptr(row), 640 * 3);
  pool.publish(slot, 640, 480, 1234, arrival_ns, arrival_ns + 5 * kMs);
}

TEST(VisionTask, FindsThePersonInTheNewestFrameAtItsRate) {
  auto pool = camera::FramePool::create(3, 640, 480, camera::PixelFormat::bgr8);
  ASSERT_TRUE(pool);
  tasks::Topic<msg::PersonDetections> topic;
  VisionTaskConfig config;
  config.rate_hz = 1.0;
  VisionTask task(config, pool->get(), topic);
  std::pmr::monotonic_buffer_resource arena;
  ASSERT_TRUE(task.init(arena));
  // No frame yet: nothing.
  task.step({0, 0, 0});
  EXPECT_EQ(topic.published(), 0u);
  publish_photo(**pool, 90 * kMs);
  task.step({100 * kMs, 100 * kMs, 1});
  ASSERT_EQ(topic.published(), 1u);
  tasks::Sample<msg::PersonDetections> got;
  ASSERT_TRUE(topic.read(got));
  ASSERT_EQ(got.value.count, 1u);
  EXPECT_EQ(got.value.capture_ns, 90 * kMs);
  EXPECT_EQ(got.value.source, VisionTask::kSource);
  // The man at the left, in 1280 x 720 pixels: x doubled, y times 1.5.
  const msg::PersonBox& box = got.value.boxes[0];
  EXPECT_LT(box.u0, 120.0f);
  EXPECT_GT(box.u1, 280.0f);
  EXPECT_LT(box.u1, 520.0f);
  EXPECT_GT(box.v1, 660.0f);
  // The same frame again is not searched again; a new one within the second waits.
  task.step({600 * kMs, 600 * kMs, 2});
  publish_photo(**pool, 700 * kMs);
  task.step({800 * kMs, 800 * kMs, 3});
  EXPECT_EQ(topic.published(), 1u);
  task.step({1100 * kMs, 1100 * kMs, 4});
  EXPECT_EQ(topic.published(), 2u);
  EXPECT_EQ(task.frames_searched(), 2u);
}

TEST(VisionTask, WithoutACameraOrWithABadRateInitFails) {
  tasks::Topic<msg::PersonDetections> topic;
  std::pmr::monotonic_buffer_resource arena;
  VisionTask no_camera({}, nullptr, topic);
  EXPECT_FALSE(no_camera.init(arena));
  auto pool = camera::FramePool::create(3, 640, 480, camera::PixelFormat::bgr8);
  ASSERT_TRUE(pool);
  VisionTaskConfig config;
  config.rate_hz = 0.0;
  VisionTask bad_rate(config, pool->get(), topic);
  EXPECT_FALSE(bad_rate.init(arena));
}

}  // namespace
}  // namespace sen3bot::firmware
