#pragma once
// The LMS200 as a scheduler task: init() opens the link through the board and takes its
// memory from the task's arena; step() drives the device state machine and publishes each new
// scan as a navigation ScanMessage. step() never allocates or blocks.
#include <memory_resource>

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

  // Null before init().
  [[nodiscard]] const lms200::Lms200Device* device() const noexcept { return device_; }
  // Arena bytes init() needs, for sizing the task's budget.
  static constexpr std::size_t kArenaBytes =
      sizeof(lms200::Lms200Device) + sizeof(lms200::LaserScan) + sizeof(msg::ScanMessage) + 256;

 private:
  lms200::Lms200Config config_;
  hal::Board& board_;
  tasks::Topic<msg::ScanMessage>& topic_;
  hal::Link link_;
  std::pmr::memory_resource* arena_ = nullptr;
  lms200::Lms200Device* device_ = nullptr;
  lms200::LaserScan* scan_ = nullptr;
  msg::ScanMessage* message_ = nullptr;
  hal::Nanos next_reopen_ns_ = 0;
  bool started_ = false;
};

}  // namespace sen3bot::firmware
