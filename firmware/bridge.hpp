#pragma once
// The driver shims: the devices' own messages in, navigation's messages out, and the safety
// filter's command back to the base. A few assignments per cycle; nothing allocated.
#include "sen3bot/lms200/scan.hpp"
#include "sen3bot/msg/messages.hpp"
#include "sen3bot/nav/scan.hpp"
#include "sen3bot/p2os/types.hpp"
#include "sen3bot/tasks/task.hpp"
#include "sen3bot/tasks/topic.hpp"

namespace sen3bot::firmware {

struct BridgeTopics {
  const tasks::Topic<lms200::LaserScan>& laser;
  const tasks::Topic<p2os::BaseState>& base;
  const tasks::Topic<msg::VelocityCommand>& command;  // the safety filter's output
  tasks::Topic<msg::ScanMessage>& scan;
  tasks::Topic<msg::Odometry>& odometry;
  tasks::Topic<msg::BaseFlags>& base_flags;
  tasks::Topic<p2os::BaseSetpoint>& setpoint;
};

// LMS200 scan -> navigation scan. "Over maximum" (no echo) becomes range_max, which clears
// without marking; any other invalid value (dazzle, overflow, weak signal) becomes NaN, which
// navigation ignores: an unreadable beam must not clear an obstacle.
void to_nav_scan(const lms200::LaserScan& in, msg::ScanMessage& out) noexcept;
msg::Odometry to_nav_odometry(const p2os::BaseState& in) noexcept;

class BridgeTask final : public tasks::Task {
 public:
  explicit BridgeTask(const BridgeTopics& topics) : topics_(topics) {}
  Status init(std::pmr::memory_resource&) override { return Status::success(); }
  void step(const tasks::StepContext& context) override;

 private:
  BridgeTopics topics_;
  std::uint64_t laser_seq_ = 0;
  std::uint64_t base_seq_ = 0;
  std::uint64_t command_seq_ = 0;
  tasks::Sample<lms200::LaserScan> laser_;
  msg::ScanMessage scan_;
};

}  // namespace sen3bot::firmware
