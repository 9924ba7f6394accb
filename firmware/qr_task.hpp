#pragma once
// The operators' QR tags as a row of the task table, on the non-real-time "cobot" thread: at
// most rate_hz times a second it takes the camera's newest frame (a FrameReader on the
// camera's pool) and reads the tags (cobot/qr_reader.hpp), only where a tracked person stands
// within reach: around the pixel where each such person's leg band must be. Nobody near, no
// search: a waiting robot in an empty bay costs nothing. Every searched frame is published,
// with or without tags, so the trigger sees the gaps too.
//
// Memory: the reader's grey image is allocated at init(); OpenCV's search allocates scratch on
// every call, which is why this runs on a thread of its own and never on the io or control
// threads.
#include <cstdint>
#include <memory_resource>
#include <optional>

#include "sen3bot/camera/frame_pool.hpp"
#include "sen3bot/cobot/qr_reader.hpp"
#include "sen3bot/msg/messages.hpp"
#include "sen3bot/nav/people.hpp"
#include "sen3bot/tasks/task.hpp"
#include "sen3bot/tasks/topic.hpp"
#include "camera_task.hpp"

namespace sen3bot::firmware {

struct QrTaskConfig {
  double rate_hz = 5.0;          // frames searched a second, at most
  double reach_m = 2.0;          // people farther than this from the laser are not searched
  double band_height_m = 0.35;   // the leg band's height above the floor
  double laser_height_m = 0.3;   // the scan plane's
  double tag_side_m = 0.10;
  bool whole_frame = false;      // search the whole frame, people or not (for a bench camera)
  nav::CameraCalibration camera;
  msg::SensorMount laser_mount;
};

struct QrTopics {
  const tasks::Topic<msg::People>& people;
  const tasks::Topic<msg::PoseEstimate>& pose;
  tasks::Topic<msg::TagFrame>& tags;
};

class QrTask final : public tasks::Task {
 public:
  QrTask(const QrTaskConfig& config, const FrameSource& frames, const QrTopics& topics)
      : config_(config), source_(frames), topics_(topics) {}
  Status init(std::pmr::memory_resource& arena) override;
  void step(const tasks::StepContext& context) override;

  [[nodiscard]] std::uint64_t frames_searched() const noexcept { return searched_; }
  [[nodiscard]] std::uint64_t frames_without_people() const noexcept { return no_people_; }
  [[nodiscard]] const cobot::QrReader& reader() const noexcept { return qr_; }

 private:
  // The part of the frame where the leg bands of the people within reach are; false: nobody.
  bool region(cobot::PixelRect& roi) const noexcept;

  QrTaskConfig config_;
  FrameSource source_;
  camera::FramePool* frames_ = nullptr;  // from source_, at init()
  QrTopics topics_;
  std::optional<camera::FrameReader> reader_;
  cobot::QrReader qr_;
  nav::CameraProjection projection_;
  msg::TagFrame out_;
  hal::Nanos last_ns_ = -1;
  std::uint64_t searched_ = 0;
  std::uint64_t no_people_ = 0;
};

}  // namespace sen3bot::firmware
