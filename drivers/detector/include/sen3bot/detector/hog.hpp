#pragma once
// The on-board people detector: OpenCV's HOG descriptor with its built-in people coefficients
// (Dalal and Triggs' 64 x 128 window, a linear SVM) over a downscaled grey copy of a camera
// frame. It is slow (tens of milliseconds a frame on the robot computer), so it runs at a low
// rate on the background thread and its boxes go out as the remote detector's do.
//
// Memory: the grey and downscaled images are allocated at init() for the frame size given;
// OpenCV's detectMultiScale allocates its own scratch on every call, which is why this never
// runs on a real-time thread.
#include <cstdint>
#include <memory>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/detector/detections.hpp"

namespace sen3bot::detector {

struct HogConfig {
  double scale = 0.5;            // the frame is shrunk by this before the search (0.1 .. 2)
  double hit_threshold = 0.3;    // the SVM margin a window must pass
  int win_stride_px = 8;         // window step, in the shrunk image (a multiple of 8)
  double pyramid_step = 1.05;    // scale step between pyramid levels (> 1)
  int group_threshold = 2;       // overlapping windows needed for a box
  double min_height_px = 0.0;    // boxes shorter than this, in the frame, are left out
};

// The view of a frame the detector reads: rows of stride_bytes, 1 (grey) or 3 (BGR) channels.
struct ImageView {
  const std::uint8_t* data = nullptr;
  std::uint32_t width_px = 0;
  std::uint32_t height_px = 0;
  std::uint32_t stride_bytes = 0;
  std::uint8_t channels = 3;
};

class HogPeopleDetector {
 public:
  HogPeopleDetector();
  ~HogPeopleDetector();
  HogPeopleDetector(const HogPeopleDetector&) = delete;
  HogPeopleDetector& operator=(const HogPeopleDetector&) = delete;

  // For frames of width x height: checks the configuration and allocates the images.
  Status init(const HogConfig& config, std::uint32_t width_px, std::uint32_t height_px);
  // The people in one frame, as boxes in the frame's pixels (class 0, confidence the
  // logistic of the SVM margin), strongest first, at most Detections::kMax. Sets
  // out.boxes and out.count only. A frame of another size or a bad view is an error.
  Status detect(const ImageView& image, Detections& out);
  [[nodiscard]] const HogConfig& config() const noexcept { return config_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  HogConfig config_;
  std::uint32_t width_px_ = 0;
  std::uint32_t height_px_ = 0;
};

}  // namespace sen3bot::detector
