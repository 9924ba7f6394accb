#include "recognition_task.hpp"

#include <algorithm>

namespace sen3bot::firmware {

Status RecognitionTask::init(std::pmr::memory_resource& arena) {
  (void)arena;  // the model is OpenCV's, loaded here once
  if (!(config_.rate_hz > 0.0 && config_.rate_hz <= 10.0))
    return Error(Errc::config, "recognition task: rate_hz must be in (0, 10]");
  Result<cobot::OperationsConfig> operations = cobot::load_operations(config_.operations_path);
  if (!operations) return operations.error();
  operations_ = std::move(*operations);
  if (operations_.operations.size() > msg::OperationEstimate::kMaxOperations)
    return Error::format(Errc::config, "recognition task: %s: at most %zu operations", config_.operations_path.c_str(),
                         msg::OperationEstimate::kMaxOperations);
  Result<std::unique_ptr<cobot::OperationRecognizer>> recognizer =
      cobot::OperationRecognizer::load(config_.model_path, operations_);
  if (!recognizer) return recognizer.error();
  recognizer_ = std::move(*recognizer);
  return Status::success();
}

void RecognitionTask::step(const tasks::StepContext& context) {
  if (last_ns_ >= 0 && static_cast<double>(context.start_ns - last_ns_) < 1e9 / config_.rate_hz) return;
  if (!topics_.path.read(path_) || path_.value.version == classified_version_ || path_.value.count < config_.min_points)
    return;
  last_ns_ = context.start_ns;
  classified_version_ = path_.value.version;
  const std::size_t n = operations_.operations.size();
  const std::size_t points = std::min<std::size_t>(path_.value.count, msg::WorkerPath::kMax);
  if (Status s = recognizer_->classify(std::span<const float>(path_.value.xy.data(), 2 * points), points,
                                       std::span<float>(probability_.data(), n));
      !s) {
    ++errors_;
    return;
  }
  ++classified_;
  estimate_.operations = static_cast<std::uint8_t>(n);
  std::copy_n(probability_.begin(), n, estimate_.probability.begin());
  estimate_.best = static_cast<std::int8_t>(std::max_element(probability_.begin(), probability_.begin() + n) -
                                            probability_.begin());
  estimate_.points = static_cast<std::uint16_t>(points);
  estimate_.path_version = path_.value.version;
  estimate_.stamp_ns = context.start_ns;
  topics_.estimate.publish(estimate_, context.start_ns);
  // The reference trajectory of the most probable operation, for the planner.
  if (estimate_.best != reference_of_) {
    reference_of_ = estimate_.best;
    const std::vector<msg::Point2D>& ref = operations_.operations[static_cast<std::size_t>(reference_of_)].reference;
    reference_ = msg::PathMessage{};
    reference_.plan_id = static_cast<std::uint32_t>(reference_of_) + 1;
    reference_.status = ref.empty() ? msg::PlanStatus::no_path : msg::PlanStatus::ok;
    for (const msg::Point2D& p : ref) {
      if (reference_.count == msg::PathMessage::kMaxPoints) break;
      reference_.points[reference_.count++] = {static_cast<float>(p.x_m), static_cast<float>(p.y_m)};
    }
    topics_.reference.publish(reference_, context.start_ns);
  }
}

}  // namespace sen3bot::firmware
