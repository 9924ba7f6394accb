#pragma once
// The camera as a row of the task table, on its own non-real-time thread: each step does the
// RTSP/RTP I/O that is ready, depacketizes and decodes what arrived into the fixed frame pool.
// Readers take the newest frame from frames() without blocking.
#include <memory>
#include <memory_resource>

#include "sen3bot/camera/camera.hpp"
#include "sen3bot/hal/board.hpp"
#include "sen3bot/tasks/task.hpp"

namespace sen3bot::firmware {

class CameraTask final : public tasks::Task {
 public:
  CameraTask(const camera::CameraConfig& config, hal::Board& board) : config_(config), board_(board) {}

  // Builds the client, the decoder's converter and the frame pool (slots x the largest frame,
  // from the configuration: the camera's memory, sized once here). Connecting happens in step().
  Status init(std::pmr::memory_resource& arena) override;
  void step(const tasks::StepContext& context) override;
  // TEARDOWN.
  void shutdown() override;

  // Null before init().
  [[nodiscard]] camera::Camera* camera() noexcept { return camera_.get(); }

 private:
  camera::CameraConfig config_;
  hal::Board& board_;
  std::unique_ptr<camera::Camera> camera_;
};

}  // namespace sen3bot::firmware
