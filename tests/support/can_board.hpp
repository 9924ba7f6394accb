#pragma once
// A board with one CAN bus and nothing else: the firmware's station handed out as "test", the
// CANopen I/O node's emulator on the other, stepped by the caller. For the CAN I/O task's tests
// and benchmark.
#include <array>
#include <memory>
#include <optional>
#include <string_view>

#include "sen3bot/canopen/io_node_emulator.hpp"
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

}  // namespace sen3bot::testing
