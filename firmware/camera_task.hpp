#pragma once
// The camera as a row of the task table, on its own non-real-time thread: each step does the
// RTSP/RTP I/O that is ready, depacketizes and decodes what arrived into the fixed frame pool.
// Readers take the newest frame from frames() without blocking. A camera that failed for good
// (see camera::RtspClient::step) is reported once on the event log with its reason and by
// failed() to the health report; the row then does nothing and the firmware runs without it.
#include <memory>
#include <memory_resource>

#include "sen3bot/camera/camera.hpp"
#include "sen3bot/hal/board.hpp"
#include "sen3bot/tasks/bus.hpp"
#include "sen3bot/tasks/task.hpp"

namespace sen3bot::firmware {

class CameraTask final : public tasks::Task {
 public:
  // At init() the camera's address is written to *camera_out (when given): the firmware reads
  // its frames and status there, without calling into this class, which lives in a module.
  CameraTask(const camera::CameraConfig& config, hal::Board& board, tasks::Bus& bus,
             camera::Camera** camera_out = nullptr)
      : config_(config), board_(board), bus_(bus), camera_out_(camera_out) {}

  // Builds the client, the decoder's converter and the frame pool (slots x the largest frame,
  // from the configuration: the camera's memory, sized once here). Connecting happens in step().
  Status init(std::pmr::memory_resource& arena) override;
  void step(const tasks::StepContext& context) override;
  // TEARDOWN.
  void shutdown() override;
  [[nodiscard]] bool failed() const noexcept override { return camera_ != nullptr && camera_->failed(); }

  // Null before init().
  [[nodiscard]] camera::Camera* camera() noexcept { return camera_.get(); }

 private:
  camera::CameraConfig config_;
  hal::Board& board_;
  tasks::Bus& bus_;
  camera::Camera** camera_out_;
  std::unique_ptr<camera::Camera> camera_;
  bool failure_reported_ = false;
};

// Where a frame reader's frames come from: the camera's pool, its camera written to a slot once
// the camera row's init() ran (it runs first: the readers' rows come after it in the table), or
// a pool given outright (a simulated camera). A slot, not the row: the row's class lives in its
// module, and code outside it must not call it (with -fsanitize=vptr each call needs its
// type_info, which only the module has).
struct FrameSource {
  // From a pool alone, or from the camera row's slot when pool is null.
  FrameSource(camera::FramePool* frames = nullptr, camera::Camera* const* camera_slot = nullptr) noexcept  // NOLINT(google-explicit-constructor)
      : pool(frames), camera(camera_slot) {}
  camera::FramePool* pool;
  camera::Camera* const* camera;  // null without a camera row
  [[nodiscard]] camera::FramePool* get() const noexcept {
    if (pool != nullptr) return pool;
    return camera != nullptr && *camera != nullptr ? &(*camera)->frames() : nullptr;
  }
};

}  // namespace sen3bot::firmware
