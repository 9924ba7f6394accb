// The on-board people detector's time per camera frame: OpenCV's sample photograph of a man in
// an office (basketball1.png, Apache-2.0, from Debian's opencv-doc) enlarged to the camera's
// 1280 x 720, searched at the shrink factors a robot would use. The firmware's vision row
// budgets 300 ms a frame on the robot computer; its rate (rate_hz) comes from these numbers.
#include <benchmark/benchmark.h>

#include <cstdio>

#include <opencv2/core.hpp>
#include <opencv2/imgcodecs.hpp>
#include <opencv2/imgproc.hpp>

#include "sen3bot/detector/hog.hpp"

namespace {

cv::Mat camera_frame() {
  const cv::Mat photo = cv::imread("/usr/share/doc/opencv-doc/examples/data/basketball1.png", cv::IMREAD_COLOR);
  if (photo.empty()) return {};
  cv::Mat frame;
  cv::resize(photo, frame, cv::Size(1280, 720), 0, 0, cv::INTER_LINEAR);
  return frame;
}

void BM_HogFrame(benchmark::State& state) {
  static const cv::Mat frame = camera_frame();
  if (frame.empty()) {
    state.SkipWithError("opencv-doc's sample images are missing (toolchain/bootstrap.sh installs them)");
    return;
  }
  sen3bot::detector::HogConfig config;
  config.scale = static_cast<double>(state.range(0)) / 100.0;
  sen3bot::detector::HogPeopleDetector hog;
  if (!hog.init(config, 1280, 720)) {
    state.SkipWithError("init failed");
    return;
  }
  const sen3bot::detector::ImageView view{frame.data, 1280, 720, static_cast<std::uint32_t>(frame.step[0]), 3};
  sen3bot::detector::Detections found;
  for (auto _ : state) {
    (void)hog.detect(view, found);
    benchmark::DoNotOptimize(found.count);
  }
  state.counters["people"] = static_cast<double>(found.count);
}
// Scale in percent: 0.25, 0.375 and 0.5 of 1280 x 720.
BENCHMARK(BM_HogFrame)->Arg(25)->Arg(38)->Arg(50)->Unit(benchmark::kMillisecond)->MinTime(1.0);

}  // namespace

BENCHMARK_MAIN();
