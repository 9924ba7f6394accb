#pragma once
// The robot's safety I/O as a scheduler task: a CANopen (CiA 401) digital I/O node on a CAN
// bus, mastered by canopen::IoNodeMaster. Each cycle it takes the node's frames, publishes the
// e-stop chain, the bumpers and the reset button as msg::SafetyIo for the safety task (which
// runs next on the same thread), and drives the status light and the buzzer from what the
// robot is doing. The bus comes from the board (SocketCAN on the robot, the simulated node in
// simulation).
//
// Wiring, as configured under devices.io_node: the e-stop chain on one input, active-low by
// default (a closed chain reads high, so a cut wire reads as pressed); an optional reset
// button; up to eight bumpers; one output per light mode and one for the buzzer.
#include <array>
#include <cstdint>
#include <memory>
#include <memory_resource>
#include <string>

#include "sen3bot/canopen/io_node.hpp"
#include "sen3bot/hal/board.hpp"
#include "sen3bot/msg/messages.hpp"
#include "sen3bot/tasks/task.hpp"
#include "sen3bot/tasks/topic.hpp"

namespace sen3bot::firmware {

struct CanIoConfig {
  std::string interface;         // "can0", or "sim" for the simulated node
  canopen::IoNodeConfig master;  // node id, heartbeat and timings
  std::uint8_t estop_input = 1;  // 1..8
  bool estop_active_low = true;
  std::uint8_t reset_input = 0;  // 0: none (a reset must then come from elsewhere)
  std::uint8_t bumper_inputs = 0;  // bit i = input i + 1 is a bumper
  bool bumpers_active_low = false;
  // Output number (1..8, 0: none) per light mode, indexed by msg::LightMode.
  std::array<std::uint8_t, 5> light_outputs{0, 1, 2, 3, 4};
  std::uint8_t buzzer_output = 0;  // 0: none
  double buzzer_period_s = 1.0;    // in fault the buzzer sounds for half of each period
  // A velocity command newer than this that moves the robot shows as driving.
  double driving_hold_s = 0.5;
  bool reset_at_start = false;  // the safety task's latch (SafetyLatch)
};

// Errc::config naming the key when inputs or outputs are out of range or used twice.
Status check(const CanIoConfig& config);

// The light mode for what the robot is doing: fault while a safety stop from the I/O holds it
// (or the base's own e-stop), else driving when the newest command moves it, else wait4col
// when the collaborative mode asks for it, else idle.
msg::LightMode light_mode(std::uint32_t safety_reasons, bool moving, bool wait4col) noexcept;

// The eight output levels for a light mode and the buzzer phase.
std::uint8_t output_levels(const CanIoConfig& config, msg::LightMode mode, bool buzzer_on) noexcept;

struct CanIoTopics {
  const tasks::Topic<msg::SafetyOutput>& safety;      // the reasons a safety stop holds
  const tasks::Topic<msg::VelocityCommand>& command;  // what goes to the base
  tasks::Topic<msg::SafetyIo>& io;
  const tasks::Topic<msg::OperatingMode>* mode = nullptr;  // the collaborative mode's wait4col
};

class CanIoTask final : public tasks::Task {
 public:
  static constexpr std::size_t kMaxFramesPerStep = 64;  // a 10 ms cycle at 1 Mbit/s carries ~80

  CanIoTask(const CanIoConfig& config, hal::Board& board, const CanIoTopics& topics);
  ~CanIoTask() override;

  // Opens the bus and keeps only the node's frames. A bus that cannot be opened is an error:
  // the robot must not run without its e-stop chain.
  Status init(std::pmr::memory_resource& arena) override;
  // Never allocates or blocks: frames in, SafetyIo out, outputs and the master's frames sent.
  void step(const tasks::StepContext& context) override;

  [[nodiscard]] const canopen::IoNodeMaster& master() const noexcept { return master_; }
  [[nodiscard]] msg::LightMode light() const noexcept { return light_; }
  [[nodiscard]] std::uint64_t bus_errors() const noexcept { return bus_errors_; }
  [[nodiscard]] std::uint64_t send_drops() const noexcept { return send_drops_; }
  [[nodiscard]] const hal::CanBus* bus() const noexcept { return bus_.get(); }

 private:
  CanIoConfig config_;
  hal::Board& board_;
  CanIoTopics topics_;
  std::unique_ptr<hal::CanBus> bus_;
  canopen::IoNodeMaster master_;
  msg::SafetyIo io_;
  bool reset_level_ = false;
  msg::LightMode light_ = msg::LightMode::off;
  std::uint64_t bus_errors_ = 0;  // receive or send failures
  std::uint64_t send_drops_ = 0;  // frames the bus had no room for
};

}  // namespace sen3bot::firmware
