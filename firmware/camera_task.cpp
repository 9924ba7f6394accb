#include "camera_task.hpp"

namespace sen3bot::firmware {

Status CameraTask::init(std::pmr::memory_resource&) {
  if (camera_ != nullptr) return Error(Errc::invalid_argument, "camera task: init called twice");
  Result<std::unique_ptr<camera::Camera>> created = camera::Camera::create(config_, board_.clock());
  if (!created) return Error::format(created.error().code(), "camera: %s", created.error().c_str());
  camera_ = std::move(*created);
  if (camera_out_ != nullptr) *camera_out_ = camera_.get();
  return Status::success();
}

void CameraTask::step(const tasks::StepContext& context) {
  if (camera_ == nullptr || failure_reported_) return;
  camera_->step(context.start_ns);
  if (camera_->failed()) {
    failure_reported_ = true;
    // Once, off the steady state: status() copies the reason under the camera's mutex.
    const camera::CameraStatus status = camera_->status();
    bus_.events.post(context.start_ns, tasks::Severity::error, "camera", "gave up: %s", status.last_error.c_str());
  }
}

void CameraTask::shutdown() {
  if (camera_ != nullptr) camera_->close(board_.clock().now());
}

}  // namespace sen3bot::firmware
