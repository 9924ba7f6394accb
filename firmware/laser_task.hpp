#pragma once
// The LMS200 as a scheduler task: init() takes its memory from the task's arena and opens the
// link through the board; step() drives the device state machine and publishes each new scan
// as a navigation ScanMessage. An absent device is not an init error: like the base, the task
// reports it (device_missing()) and retries with backoff (restart_delay_ms doubling to 5 s).
// step() never allocates; it blocks only for the open() of a retry.
#include <atomic>
#include <memory_resource>
#include <optional>

#include "reopen_backoff.hpp"
#include "sen3bot/hal/board.hpp"
#include "sen3bot/lms200/device.hpp"
#include "sen3bot/lms200/scan.hpp"
#include "sen3bot/msg/messages.hpp"
#include "sen3bot/tasks/task.hpp"
#include "sen3bot/tasks/topic.hpp"

namespace sen3bot::firmware {

class LaserTask final : public tasks::Task {
 public:
  LaserTask(const lms200::Lms200Config& config, hal::Board& board, tasks::Topic<msg::ScanMessage>& topic);
  ~LaserTask() override;

  Status init(std::pmr::memory_resource& arena) override;
  void step(const tasks::StepContext& context) override;
  // Clean stop (20 25, back to 9600) when the line's rate can follow; bounded to ~2 s.
  void shutdown() override;

  [[nodiscard]] bool device_missing() const noexcept override { return missing_.load(std::memory_order_relaxed); }
  [[nodiscard]] const std::optional<Error>& last_open_error() const noexcept { return open_error_; }

  // Null until the link first opened.
  [[nodiscard]] const lms200::Lms200Device* device() const noexcept { return device_; }
  // Arena bytes init() needs, for sizing the task's budget.
  static constexpr std::size_t kArenaBytes =
      sizeof(lms200::Lms200Device) + sizeof(lms200::LaserScan) + sizeof(msg::ScanMessage) + 256;

 private:
  lms200::Lms200Config config_;
  hal::Board& board_;
  tasks::Topic<msg::ScanMessage>& topic_;
  void try_open(hal::Nanos now_ns);

  hal::Link link_;
  void* device_memory_ = nullptr;
  lms200::Lms200Device* device_ = nullptr;
  lms200::LaserScan* scan_ = nullptr;
  msg::ScanMessage* message_ = nullptr;
  ReopenBackoff backoff_;
  std::optional<Error> open_error_;
  std::atomic<bool> missing_{false};
  bool started_ = false;
};

}  // namespace sen3bot::firmware
