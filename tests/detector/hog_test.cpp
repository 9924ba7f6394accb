// The on-board people detector on real photographs: the sample images OpenCV publishes with
// its sources (Apache-2.0; Debian's opencv-doc installs them). People are found where they
// stand; pictures without anyone give no box; bad frames and configurations are errors.
#include <gtest/gtest.h>

#include <sys/stat.h>

#include <cstdio>
#include <cstdlib>
#include <limits>
#include <string>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "sen3bot/detector/hog.hpp"

namespace sen3bot::detector {
namespace {

const std::string kData = "/usr/share/doc/opencv-doc/examples/data/";

cv::Mat load(const std::string& name) {
  cv::Mat image = cv::imread(kData + name, cv::IMREAD_COLOR);
  EXPECT_FALSE(image.empty()) << kData << name << " is missing: toolchain/bootstrap.sh installs opencv-doc";
  return image;
}

ImageView view_of(const cv::Mat& m) {
  return {m.data, static_cast<std::uint32_t>(m.cols), static_cast<std::uint32_t>(m.rows),
          static_cast<std::uint32_t>(m.step[0]), static_cast<std::uint8_t>(m.channels())};
}

detector::Detections detect(const cv::Mat& image, HogConfig config = {}) {
  HogPeopleDetector hog;
  detector::Detections found;
  EXPECT_TRUE(hog.init(config, static_cast<std::uint32_t>(image.cols), static_cast<std::uint32_t>(image.rows)));
  const Status s = hog.detect(view_of(image), found);
  EXPECT_TRUE(s) << s.error().c_str();
  return found;
}

// A man about 3 m away in an office doorway (left), another cut off by the frame (right).
TEST(HogPeopleDetector, FindsThePersonStandingInAnOffice) {
  for (const char* name : {"basketball1.png", "basketball2.png"}) {
    const cv::Mat image = load(name);
    ASSERT_FALSE(image.empty());
    const detector::Detections found = detect(image);
    ASSERT_EQ(found.count, 1u) << name;
    const detector::Box& box = found.boxes[0];
    // Around him: his head is near (85, 100) px and his feet near (100, 465) px.
    EXPECT_LT(box.u0, 60.0f) << name;
    EXPECT_GT(box.u1, 140.0f) << name;
    EXPECT_LT(box.u1, 260.0f) << name;
    EXPECT_LT(box.v0, 100.0f) << name;
    EXPECT_GT(box.v1, 440.0f) << name;
    EXPECT_GT(box.confidence, 0.6f) << name;
    EXPECT_EQ(box.class_id, 0) << name;
  }
}

// The same frame as grey gives the same boxes (the camera driver can deliver either).
TEST(HogPeopleDetector, GreyFramesGiveTheSameBoxes) {
  const cv::Mat image = load("basketball1.png");
  ASSERT_FALSE(image.empty());
  cv::Mat grey;
  cv::cvtColor(image, grey, cv::COLOR_BGR2GRAY);
  const detector::Detections a = detect(image);
  const detector::Detections b = detect(grey);
  ASSERT_EQ(a.count, b.count);
  for (std::size_t i = 0; i < a.count; ++i) {
    EXPECT_EQ(a.boxes[i].u0, b.boxes[i].u0);
    EXPECT_EQ(a.boxes[i].v1, b.boxes[i].v1);
  }
}

// Six walkers crossing a yard (frame 300 of the pedestrian video, seen from a first floor),
// enlarged twice as a robot would see them closer; none in the empty lawn below.
TEST(HogPeopleDetector, FindsTheWalkersInTheYard) {
  char dir_template[] = "/tmp/sen3bot-hog-XXXXXX";
  ASSERT_NE(::mkdtemp(dir_template), nullptr);
  const std::string frame = std::string(dir_template) + "/frame.png";
  const std::string command = "ffmpeg -loglevel error -y -i " + kData + "vtest.avi -vf 'select=eq(n\\,300)' -vsync 0 " +
                              frame;
  ASSERT_EQ(std::system(command.c_str()), 0) << command;
  const cv::Mat image = cv::imread(frame, cv::IMREAD_COLOR);
  ASSERT_EQ(image.cols, 768);
  HogConfig config;
  config.scale = 2.0;
  const detector::Detections found = detect(image, config);
  EXPECT_GE(found.count, 5u);
  EXPECT_LE(found.count, 7u);
  for (std::size_t i = 0; i < found.count; ++i) {
    const detector::Box& box = found.boxes[i];
    EXPECT_LT(box.v1, 330.0f) << "box " << i << " reaches the lawn";
    EXPECT_GT(box.v0, 130.0f) << "box " << i << " above the path";
    EXPECT_GT((box.v1 - box.v0) / (box.u1 - box.u0), 1.5f) << "box " << i << " is not a standing person's shape";
  }
}

TEST(HogPeopleDetector, NothingInPicturesWithoutPeople) {
  for (const char* name : {"building.jpg", "home.jpg", "fruits.jpg", "board.jpg", "stuff.jpg", "aero1.jpg"}) {
    const cv::Mat image = load(name);
    ASSERT_FALSE(image.empty());
    EXPECT_EQ(detect(image).count, 0u) << name;
  }
}

TEST(HogPeopleDetector, BadFramesAndConfigurationsAreErrors) {
  HogPeopleDetector hog;
  detector::Detections found;
  std::uint8_t pixels[640 * 480 * 3] = {};
  EXPECT_FALSE(hog.detect({pixels, 640, 480, 640 * 3, 3}, found));  // not initialised
  EXPECT_FALSE(hog.init({}, 100, 100));                             // under the 64 x 128 window once shrunk
  HogConfig odd;
  odd.win_stride_px = 12;
  EXPECT_FALSE(hog.init(odd, 640, 480));
  HogConfig nan_threshold;
  nan_threshold.hit_threshold = std::numeric_limits<double>::quiet_NaN();
  EXPECT_FALSE(hog.init(nan_threshold, 640, 480));
  ASSERT_TRUE(hog.init({}, 640, 480));
  found.count = 3;
  EXPECT_FALSE(hog.detect({pixels, 320, 240, 320 * 3, 3}, found));  // another size
  EXPECT_EQ(found.count, 0u);
  EXPECT_FALSE(hog.detect({nullptr, 640, 480, 640 * 3, 3}, found));
  EXPECT_FALSE(hog.detect({pixels, 640, 480, 100, 3}, found));  // rows shorter than the width
  EXPECT_FALSE(hog.detect({pixels, 640, 480, 640 * 3, 2}, found));
  // A blank frame is fine, and empty.
  const Status s = hog.detect({pixels, 640, 480, 640 * 3, 3}, found);
  EXPECT_TRUE(s) << s.error().c_str();
  EXPECT_EQ(found.count, 0u);
}

}  // namespace
}  // namespace sen3bot::detector
