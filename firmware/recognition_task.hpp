#pragma once
// Operation recognition as a row of the task table, on the non-real-time "cobot" thread: at
// most rate_hz times a second, when the worker's path (the cobot row's recorder) has grown, it
// classifies the path (cobot/recognizer.hpp: OpenCV's MLP) and publishes one probability per
// configured operation, and the reference trajectory of the most probable one for the planner
// (docs/cobot/recognition.md).
//
// Memory: the model and its matrices are loaded at init(); OpenCV may allocate in classify(),
// which is why this runs on a thread of its own and never on the io or control threads.
#include <array>
#include <cstdint>
#include <memory>
#include <memory_resource>
#include <string>

#include "sen3bot/cobot/operations.hpp"
#include "sen3bot/cobot/recognizer.hpp"
#include "sen3bot/msg/messages.hpp"
#include "sen3bot/tasks/task.hpp"
#include "sen3bot/tasks/topic.hpp"

namespace sen3bot::firmware {

struct RecognitionTaskConfig {
  std::string operations_path;
  std::string model_path;
  double rate_hz = 1.0;
  std::size_t min_points = 10;  // a shorter path is not classified yet
};

struct RecognitionTopics {
  const tasks::Topic<msg::WorkerPath>& path;
  tasks::Topic<msg::OperationEstimate>& estimate;
  tasks::Topic<msg::PathMessage>& reference;  // the most probable operation's, when it changes
};

class RecognitionTask final : public tasks::Task {
 public:
  RecognitionTask(const RecognitionTaskConfig& config, const RecognitionTopics& topics)
      : config_(config), topics_(topics) {}
  Status init(std::pmr::memory_resource& arena) override;
  void step(const tasks::StepContext& context) override;

  [[nodiscard]] std::uint64_t classified() const noexcept { return classified_; }
  [[nodiscard]] std::uint64_t errors() const noexcept { return errors_; }
  [[nodiscard]] const cobot::OperationsConfig& operations() const noexcept { return operations_; }

 private:
  RecognitionTaskConfig config_;
  RecognitionTopics topics_;
  cobot::OperationsConfig operations_;
  std::unique_ptr<cobot::OperationRecognizer> recognizer_;
  tasks::Sample<msg::WorkerPath> path_;
  std::uint32_t classified_version_ = 0;
  std::array<float, msg::OperationEstimate::kMaxOperations> probability_{};
  msg::OperationEstimate estimate_;
  msg::PathMessage reference_;
  int reference_of_ = -1;
  hal::Nanos last_ns_ = -1;
  std::uint64_t classified_ = 0;
  std::uint64_t errors_ = 0;
};

}  // namespace sen3bot::firmware
