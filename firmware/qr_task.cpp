#include "qr_task.hpp"

#include <algorithm>
#include <cmath>

namespace sen3bot::firmware {

Status QrTask::init(std::pmr::memory_resource& arena) {
  (void)arena;  // the reader's grey image is OpenCV's, sized here once
  frames_ = source_.get();
  if (frames_ == nullptr) return Error::format(Errc::config, "qr task: the tag reader needs a camera");
  if (!(config_.rate_hz > 0.0 && config_.rate_hz <= 30.0))
    return Error::format(Errc::config, "qr task: rate_hz must be in (0, 30]");
  if (Status s = projection_.set(config_.camera); !s) return s;
  if (Status s = qr_.init(frames_->width_px(), frames_->height_px()); !s) return s;
  reader_.emplace(*frames_);
  return Status::success();
}

bool QrTask::region(cobot::PixelRect& roi) const noexcept {
  tasks::Sample<msg::People> people;
  tasks::Sample<msg::PoseEstimate> pose;
  if (!topics_.people.read(people) || !topics_.pose.read(pose) || !pose.value.valid) return false;
  const msg::Pose2D laser = msg::compose(pose.value.pose, config_.laser_mount);
  const double c = std::cos(laser.theta_rad), s = std::sin(laser.theta_rad);
  // The calibration's pixels may differ from the frame's (a camera streaming a smaller size).
  const double sx = static_cast<double>(frames_->width_px()) / projection_.width_px();
  const double sy = static_cast<double>(frames_->height_px()) / projection_.height_px();
  double u0 = 1e9, v0 = 1e9, u1 = -1e9, v1 = -1e9;
  bool any = false;
  for (std::size_t i = 0; i < people.value.count && i < msg::People::kMax; ++i) {
    const msg::TrackedPerson& p = people.value.items[i];
    if (p.hidden) continue;  // out of the camera's view: no tag of theirs to find
    const double dx = p.x_m - laser.x_m, dy = p.y_m - laser.y_m;
    const double forward = c * dx + s * dy, left = -s * dx + c * dy;
    if (forward < 0.1 || std::hypot(forward, left) > config_.reach_m) continue;
    double u = 0, v = 0;
    if (!projection_.project_point(forward, left, config_.band_height_m - config_.laser_height_m, u, v)) continue;
    // Room for the band all round the leg, its tilt, and the track's error: three tags wide.
    const double half = 1.5 * config_.tag_side_m * projection_.focal_x_px() / forward + 0.5 * p.width_m * projection_.focal_x_px() / forward;
    u0 = std::min(u0, (u - half) * sx);
    u1 = std::max(u1, (u + half) * sx);
    v0 = std::min(v0, (v - half) * sy);
    v1 = std::max(v1, (v + half) * sy);
    any = true;
  }
  if (!any) return false;
  roi.u_px = static_cast<std::int32_t>(std::floor(u0));
  roi.v_px = static_cast<std::int32_t>(std::floor(v0));
  roi.width_px = static_cast<std::int32_t>(std::ceil(u1 - u0));
  roi.height_px = static_cast<std::int32_t>(std::ceil(v1 - v0));
  return true;
}

void QrTask::step(const tasks::StepContext& context) {
  if (last_ns_ >= 0 && static_cast<double>(context.start_ns - last_ns_) < 1e9 / config_.rate_hz) return;
  camera::FrameHandle frame = reader_->newer();
  if (!frame) return;
  last_ns_ = context.start_ns;
  cobot::PixelRect roi;
  if (config_.whole_frame) {
    qr_.read(frame.ref(), out_);
  } else if (region(roi)) {
    qr_.read(frame.ref(), roi, out_);
  } else {
    ++no_people_;
    return;
  }
  ++searched_;
  out_.frames_searched = searched_;
  out_.tags_read = qr_.tags_read();
  topics_.tags.publish(out_, context.start_ns);
}

}  // namespace sen3bot::firmware
