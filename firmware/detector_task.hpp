#pragma once
// The remote person detector's channel as a scheduler task (io thread): each cycle it takes
// the waiting datagrams (a bounded number) from the board's "detector" port, passes them
// through the gate (drivers/detector) and publishes each accepted frame's boxes. The port
// is opened at init(); the receive path never blocks or allocates.
#include <array>
#include <atomic>
#include <memory>
#include <memory_resource>
#include <string>

#include "sen3bot/detector/protocol.hpp"
#include "sen3bot/hal/board.hpp"
#include "sen3bot/msg/people.hpp"
#include "sen3bot/tasks/task.hpp"
#include "sen3bot/tasks/topic.hpp"

namespace sen3bot::firmware {

struct DetectorTaskConfig {
  std::string address = "udp://0.0.0.0:5600";  // or "sim" on the simulated robot
  detector::GateConfig gate;
  int max_per_cycle = 8;  // datagrams taken per cycle; more wait for the next
};

class DetectorTask final : public tasks::Task {
 public:
  DetectorTask(const DetectorTaskConfig& config, hal::Board& board, tasks::Topic<msg::PersonDetections>& topic)
      : config_(config), board_(board), topic_(topic), gate_(config.gate) {}
  Status init(std::pmr::memory_resource& arena) override;
  void step(const tasks::StepContext& context) override;

  [[nodiscard]] const detector::DetectionGate& gate() const noexcept { return gate_; }
  [[nodiscard]] std::uint64_t receive_errors() const noexcept { return receive_errors_.load(std::memory_order_relaxed); }

 private:
  DetectorTaskConfig config_;
  hal::Board& board_;
  tasks::Topic<msg::PersonDetections>& topic_;
  std::unique_ptr<hal::DatagramPort> port_;
  detector::DetectionGate gate_;
  std::array<std::uint8_t, detector::kMaxDatagramBytes + 1> buffer_{};  // one more: a longer one is refused
  detector::Detections frame_;
  msg::PersonDetections message_;
  std::atomic<std::uint64_t> receive_errors_{0};
};

}  // namespace sen3bot::firmware
