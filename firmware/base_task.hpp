#pragma once
// The Pioneer base as a scheduler task: the safety filter's VelocityCommand in, the P2OS
// driver stepped, Odometry and BaseFlags out after every SIP (and on link changes). The link
// comes from the board and is reopened through it after a failure.
#include <atomic>
#include <memory_resource>
#include <optional>

#include "reopen_backoff.hpp"
#include "sen3bot/hal/board.hpp"
#include "sen3bot/msg/messages.hpp"
#include "sen3bot/p2os/driver.hpp"
#include "sen3bot/p2os/types.hpp"
#include "sen3bot/tasks/task.hpp"
#include "sen3bot/tasks/topic.hpp"

namespace sen3bot::firmware {

struct BaseTopics {
  const tasks::Topic<msg::VelocityCommand>& command;  // the safety filter's output
  tasks::Topic<msg::Odometry>& odometry;
  tasks::Topic<msg::BaseFlags>& flags;
  tasks::Topic<msg::Sonar>* sonar = nullptr;  // the ring's readings, as SIPs bring them
};

class BaseTask final : public tasks::Task {
 public:
  BaseTask(const p2os::P2osConfig& config, hal::Board& board, const BaseTopics& topics);
  ~BaseTask() override;

  // Builds the driver in `arena` and opens the link; a missing device is reported through
  // device_missing() and retried in step() with backoff (reopen_delay_ms doubling to 5 s).
  Status init(std::pmr::memory_resource& arena) override;
  // Does not allocate or block in steady state. Reopening a failed link allocates a new stream
  // object and, for TCP, may block up to reopen_connect_timeout_ms; it happens at most once per
  // backoff delay. Only fresh commands reach the driver: if the safety task goes quiet, the
  // driver's own command timeout stops the robot.
  void step(const tasks::StepContext& context) override;
  // Zero velocity, ENABLE 0, CLOSE; waits up to one second for them to go out.
  void shutdown() override;

  [[nodiscard]] bool device_missing() const noexcept override { return missing_.load(std::memory_order_relaxed); }

  [[nodiscard]] const p2os::P2osDriver* driver() const noexcept { return driver_; }
  [[nodiscard]] const std::optional<Error>& last_open_error() const noexcept { return open_error_; }

 private:
  void try_open(int connect_timeout_ms, hal::Nanos now_ns);
  void publish(hal::Nanos now_ns);

  p2os::P2osConfig config_;
  hal::Board& board_;
  BaseTopics topics_;
  std::pmr::memory_resource* arena_ = nullptr;
  p2os::P2osDriver* driver_ = nullptr;
  hal::Link link_;
  std::optional<Error> open_error_;
  ReopenBackoff backoff_;
  std::atomic<bool> missing_{false};
  std::uint64_t last_command_sequence_ = 0;
  p2os::LinkState last_published_link_ = p2os::LinkState::disconnected;
  msg::Sonar sonar_;
};

}  // namespace sen3bot::firmware
