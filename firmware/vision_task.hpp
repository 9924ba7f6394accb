#pragma once
// The on-board people detector as a row of the task table, on its own non-real-time "vision"
// thread: at most rate_hz times a second it takes the camera's newest frame (a FrameReader on
// the camera's pool), runs the HOG detector on a shrunk grey copy and publishes the boxes, in
// the calibration's pixels, on the same topic the remote detector's datagrams feed. The
// people task cannot tell the two sources apart.
//
// Memory: the detector's images are allocated at init() for the camera's frame size; OpenCV's
// search allocates scratch on every call, which is why this runs on a thread of its own and
// never on the io or control threads.
#include <memory_resource>
#include <optional>

#include "sen3bot/camera/frame_pool.hpp"
#include "sen3bot/detector/hog.hpp"
#include "sen3bot/msg/people.hpp"
#include "sen3bot/tasks/task.hpp"
#include "sen3bot/tasks/topic.hpp"
#include "camera_task.hpp"

namespace sen3bot::firmware {

struct VisionTaskConfig {
  detector::HogConfig hog;
  double rate_hz = 2.0;                 // frames searched a second, at most (the row runs at 2 Hz)
  std::uint32_t calibration_width_px = 1280;  // the boxes are scaled to the calibration's image
  std::uint32_t calibration_height_px = 720;
};

class VisionTask final : public tasks::Task {
 public:
  static constexpr std::uint32_t kSource = 0x484F47;  // "HOG"

  VisionTask(const VisionTaskConfig& config, const FrameSource& frames, tasks::Topic<msg::PersonDetections>& topic)
      : config_(config), source_(frames), topic_(topic) {}
  Status init(std::pmr::memory_resource& arena) override;
  void step(const tasks::StepContext& context) override;

  [[nodiscard]] std::uint64_t frames_searched() const noexcept { return searched_; }
  [[nodiscard]] std::uint64_t errors() const noexcept { return errors_; }

 private:
  VisionTaskConfig config_;
  FrameSource source_;
  camera::FramePool* frames_ = nullptr;  // from source_, at init()
  tasks::Topic<msg::PersonDetections>& topic_;
  std::optional<camera::FrameReader> reader_;
  detector::HogPeopleDetector hog_;
  detector::Detections out_;
  msg::PersonDetections message_;
  hal::Nanos last_ns_ = -1;
  std::uint64_t searched_ = 0;
  std::uint64_t errors_ = 0;
};

}  // namespace sen3bot::firmware
