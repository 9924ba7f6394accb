#include "vision_task.hpp"

#include "adapters.hpp"

namespace sen3bot::firmware {

Status VisionTask::init(std::pmr::memory_resource& arena) {
  (void)arena;  // the detector's images are OpenCV matrices, sized here once
  frames_ = source_.get();
  if (frames_ == nullptr) return Error::format(Errc::config, "vision task: the on-board detector needs the camera");
  if (!(config_.rate_hz > 0.0 && config_.rate_hz <= 30.0))
    return Error::format(Errc::config, "vision task: rate_hz must be in (0, 30]");
  if (Status s = hog_.init(config_.hog, frames_->width_px(), frames_->height_px()); !s) return s;
  reader_.emplace(*frames_);
  return Status::success();
}

void VisionTask::step(const tasks::StepContext& context) {
  if (last_ns_ >= 0 && static_cast<double>(context.start_ns - last_ns_) < 1e9 / config_.rate_hz) return;
  camera::FrameHandle frame = reader_->newer();
  if (!frame) return;
  last_ns_ = context.start_ns;
  const camera::FrameRef& f = frame.ref();
  const detector::ImageView view{f.data, f.width_px, f.height_px, f.stride_bytes,
                                 static_cast<std::uint8_t>(camera::bytes_per_pixel(f.format))};
  if (Status s = hog_.detect(view, out_); !s) {
    ++errors_;  // a frame of another size than the pool's: the camera was reconfigured
    return;
  }
  ++searched_;
  // The boxes in the calibration's pixels, where the fusion projects the laser.
  const float sx = static_cast<float>(config_.calibration_width_px) / static_cast<float>(f.width_px);
  const float sy = static_cast<float>(config_.calibration_height_px) / static_cast<float>(f.height_px);
  for (std::size_t i = 0; i < out_.count; ++i) {
    detector::Box& b = out_.boxes[i];
    b.u0 *= sx;
    b.u1 *= sx;
    b.v0 *= sy;
    b.v1 *= sy;
  }
  out_.source = kSource;
  out_.sequence = static_cast<std::uint32_t>(searched_);
  // The frame's last RTP packet's arrival: the camera's own encoding delay (tens of
  // milliseconds) is inside the fusion's match window.
  out_.capture_ns = f.last_packet_ns;
  to_person_detections(out_, message_);
  topic_.publish(message_, context.start_ns);
}

}  // namespace sen3bot::firmware
