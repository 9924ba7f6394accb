#pragma once
// A board with one CAN bus and nothing else: the firmware's station handed out as "test", the
// CANopen I/O node's emulator on the other, stepped by the caller. For the CAN I/O task's tests
// and benchmark.
#include <array>
#include <memory>
#include <optional>
#include <string_view>

#include "can_io_task.hpp"
#include "sen3bot/sim/canopen/io_node_emulator.hpp"
#include "sen3bot/hal/board.hpp"
#include "sen3bot/hal/can.hpp"
#include "sen3bot/hal/clock.hpp"

namespace sen3bot::testing {

class CanBoard final : public hal::Board {
 public:
  CanBoard() {
    firmware_ = *bus.attach("firmware");
    node_ = *bus.attach("node");
  }
  [[nodiscard]] std::string_view name() const override { return "can-test"; }
  [[nodiscard]] hal::Clock& clock() override { return clock_; }
  Result<hal::Link> open_link(std::string_view, const hal::LinkRequest&) override {
    return Error(Errc::not_found, "no links");
  }
  Result<std::unique_ptr<hal::CanBus>> open_can(std::string_view, std::string_view interface) override {
    if (interface != "test") return Error(Errc::not_found, "no such CAN interface");
    return std::unique_ptr<hal::CanBus>(std::make_unique<hal::CanBusRef>(*firmware_));
  }
  // The node's side of one 5 ms step.
  void step_node(canopen::IoNodeEmulator& emulator, hal::Nanos now) {
    for (;;) {
      Result<std::optional<hal::CanFrame>> f = node_->receive();
      if (!f || !f->has_value()) break;
      emulator.on_frame(**f, now);
    }
    std::array<hal::CanFrame, 4> out;
    const std::size_t n = emulator.poll(now, out);
    for (std::size_t i = 0; i < n; ++i) (void)node_->send(out[i]);
  }
  hal::MemoryCanBus bus;

 private:
  hal::MemoryCanNode* firmware_ = nullptr;
  hal::MemoryCanNode* node_ = nullptr;
  hal::SimClock clock_;
};

// The firmware's CAN I/O task on a CanBoard, wired as config/sim.yaml wires the node (the
// chain on input 1, reset on 2, bumpers on 3 and 4, buzzer on output 5), the node powered up
// with its chain closed. The task is built, not initialised.
struct CanIoRig {
  static constexpr hal::Nanos kCycleNs = hal::millis(10);

  firmware::CanIoConfig config;
  CanBoard board;
  tasks::Topic<msg::SafetyOutput> safety;
  tasks::Topic<msg::VelocityCommand> command;
  tasks::Topic<msg::OperatingMode> mode;
  tasks::Topic<msg::SafetyIo> io;
  canopen::IoNodeEmulator node{canopen::IoNodeEmulatorConfig{}};
  std::unique_ptr<firmware::CanIoTask> task;
  hal::Nanos now = 0;
  std::uint64_t cycle = 0;

  CanIoRig() {
    config.interface = "test";
    config.reset_input = 2;
    config.bumper_inputs = 0x0C;
    config.buzzer_output = 5;
    task = std::make_unique<firmware::CanIoTask>(config, board, firmware::CanIoTopics{safety, command, io, &mode});
    node.set_inputs(0x01);
    node.power_up(0);
  }
  // One 10 ms cycle: the node's two 5 ms steps, then the task (unless with_task is false).
  void cycle_once(bool with_task = true) {
    board.step_node(node, now);
    board.step_node(node, now + kCycleNs / 2);
    if (with_task) task->step(tasks::StepContext{now, now, cycle++});
    now += kCycleNs;
  }
  void run(hal::Nanos duration) {
    for (const hal::Nanos end = now + duration; now < end;) cycle_once();
  }
};

}  // namespace sen3bot::testing
