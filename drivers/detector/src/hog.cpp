#include "sen3bot/detector/hog.hpp"

#include <algorithm>
#include <cmath>
#include <numeric>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/objdetect.hpp>

namespace sen3bot::detector {

struct HogPeopleDetector::Impl {
  cv::HOGDescriptor hog;
  cv::Mat grey;
  cv::Mat small;
  std::vector<cv::Rect> found;
  std::vector<double> weights;
  std::vector<std::size_t> order;
};

HogPeopleDetector::HogPeopleDetector() = default;
HogPeopleDetector::~HogPeopleDetector() = default;

Status HogPeopleDetector::init(const HogConfig& config, std::uint32_t width_px, std::uint32_t height_px) {
  if (!(config.scale >= 0.1 && config.scale <= 2.0) || config.win_stride_px < 8 || config.win_stride_px % 8 != 0 ||
      !(config.pyramid_step > 1.0 && config.pyramid_step <= 2.0) || config.group_threshold < 0 ||
      !(config.min_height_px >= 0.0) || !std::isfinite(config.hit_threshold)) {
    return Error::format(Errc::config, "hog detector: scale in [0.1, 2], win_stride_px a multiple of 8, "
                                       "pyramid_step in (1, 2], group_threshold >= 0, min_height_px >= 0");
  }
  const int w = static_cast<int>(std::lround(width_px * config.scale));
  const int h = static_cast<int>(std::lround(height_px * config.scale));
  if (w < 64 || h < 128 || width_px > 8192 || height_px > 8192) {
    return Error::format(Errc::config,
                         "hog detector: a %ux%u frame shrunk by %.2f is %dx%d, smaller than the 64x128 window "
                         "(or the frame is over 8192 px)",
                         width_px, height_px, config.scale, w, h);
  }
  try {
    auto impl = std::make_unique<Impl>();
    impl->hog.setSVMDetector(cv::HOGDescriptor::getDefaultPeopleDetector());
    impl->grey.create(static_cast<int>(height_px), static_cast<int>(width_px), CV_8UC1);
    impl->small.create(h, w, CV_8UC1);
    impl->found.reserve(256);
    impl->weights.reserve(256);
    impl->order.reserve(256);
    impl_ = std::move(impl);
  } catch (const std::exception& e) {
    return Error::format(Errc::capacity, "hog detector: %s", e.what());
  }
  config_ = config;
  width_px_ = width_px;
  height_px_ = height_px;
  return Status::success();
}

Status HogPeopleDetector::detect(const ImageView& image, Detections& out) {
  out.count = 0;
  if (!impl_) return Error::format(Errc::invalid_argument, "hog detector: not initialised");
  if (image.data == nullptr || image.width_px != width_px_ || image.height_px != height_px_ ||
      (image.channels != 1 && image.channels != 3) ||
      image.stride_bytes < static_cast<std::uint64_t>(image.width_px) * image.channels) {
    return Error::format(Errc::invalid_argument,
                         "hog detector: a %ux%u frame with %u channels and %u bytes a row, expected %ux%u, 1 or 3 "
                         "channels",
                         image.width_px, image.height_px, image.channels, image.stride_bytes, width_px_, height_px_);
  }
  Impl& m = *impl_;
  try {
    // A view of the caller's pixels: OpenCV does not write through it.
    const cv::Mat frame(static_cast<int>(image.height_px), static_cast<int>(image.width_px),
                        image.channels == 3 ? CV_8UC3 : CV_8UC1, const_cast<std::uint8_t*>(image.data),
                        image.stride_bytes);
    const cv::Mat* grey = &frame;
    if (image.channels == 3) {
      cv::cvtColor(frame, m.grey, cv::COLOR_BGR2GRAY);
      grey = &m.grey;
    }
    cv::resize(*grey, m.small, m.small.size(), 0, 0, cv::INTER_AREA);
    m.found.clear();
    m.weights.clear();
    const cv::Size stride(config_.win_stride_px, config_.win_stride_px);
    m.hog.detectMultiScale(m.small, m.found, m.weights, config_.hit_threshold, stride, cv::Size(8, 8),
                           config_.pyramid_step, config_.group_threshold);
  } catch (const cv::Exception& e) {
    return Error::format(Errc::io, "hog detector: %s", e.what());
  }
  m.order.resize(m.found.size());
  std::iota(m.order.begin(), m.order.end(), std::size_t{0});
  // Grouped boxes may come without weights; those rank last.
  const auto weight = [&](std::size_t i) { return i < m.weights.size() ? m.weights[i] : 0.0; };
  std::sort(m.order.begin(), m.order.end(), [&](std::size_t a, std::size_t b) { return weight(a) > weight(b); });
  const double back = 1.0 / config_.scale;
  const float right = static_cast<float>(width_px_ - 1);
  const float bottom = static_cast<float>(height_px_ - 1);
  for (const std::size_t i : m.order) {
    if (out.count >= Detections::kMax) break;
    const cv::Rect& r = m.found[i];
    Box box;
    box.u0 = std::clamp(static_cast<float>(r.x * back), 0.0f, right);
    box.v0 = std::clamp(static_cast<float>(r.y * back), 0.0f, bottom);
    box.u1 = std::clamp(static_cast<float>((r.x + r.width) * back), 0.0f, right);
    box.v1 = std::clamp(static_cast<float>((r.y + r.height) * back), 0.0f, bottom);
    if (box.v1 - box.v0 < config_.min_height_px || box.u1 <= box.u0) continue;
    box.confidence = static_cast<float>(1.0 / (1.0 + std::exp(-weight(i))));
    box.class_id = 0;
    out.boxes[out.count++] = box;
  }
  return Status::success();
}

}  // namespace sen3bot::detector
