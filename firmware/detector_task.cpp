#include "detector_task.hpp"

#include "adapters.hpp"

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

}  // namespace sen3bot::firmware
