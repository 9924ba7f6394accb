#include "detector_task.hpp"

#include "adapters.hpp"
#include "task_table.hpp"
#include "wiring.hpp"

namespace sen3bot::firmware {

Status DetectorTask::init(std::pmr::memory_resource& arena) {
  (void)arena;
  Result<std::unique_ptr<hal::DatagramPort>> port = board_.open_datagram("detector", config_.address);
  if (!port) return port.error();
  port_ = std::move(*port);
  return Status::success();
}

void DetectorTask::step(const tasks::StepContext& context) {
  for (int i = 0; i < config_.max_per_cycle; ++i) {
    Result<std::optional<std::size_t>> got = port_->receive(buffer_);
    if (!got) {
      receive_errors_.fetch_add(1, std::memory_order_relaxed);
      continue;
    }
    if (!got->has_value()) return;
    const std::span<const std::uint8_t> bytes(buffer_.data(), **got);
    if (!gate_.accept(bytes, context.start_ns, board_.clock().unix_now_ns(), frame_)) continue;
    to_person_detections(frame_, message_);
    topic_.publish(message_, context.start_ns);
  }
}

Status make_detector(Wiring& w) {
  const NavigationSection& n = w.config.navigation;
  if (!n.enabled || !n.people_enabled) return w.absent("needs navigation.people");
  if (w.shared.external_people != nullptr) return w.absent("the people come from the simulator: no detector");
  if (n.people_detector == "onboard") return w.absent("navigation.people.detector: onboard (the vision row)");
  const nav::CameraCalibration camera;
  DetectorTaskConfig detector;
  detector.address = n.people_detector;
  detector.gate.max_age_s = n.detection_max_age_s;
  detector.gate.width_px = static_cast<std::uint16_t>(camera.width_px);
  detector.gate.height_px = static_cast<std::uint16_t>(camera.height_px);
  w.takes("person detector datagrams on " + n.people_detector + " (detector::Detections, adapters.cpp)");
  w.make<DetectorTask>(detector, w.board, w.writes(&Topics::detections));
  return Status::success();
}

}  // namespace sen3bot::firmware
