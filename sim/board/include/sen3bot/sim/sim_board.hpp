#pragma once
// The simulated board, as software-in-the-loop simulators do it: the firmware composes against
// hal::Board exactly as on the robot, and this board answers with the simulated robot. Links
// whose port is "sim" reach the emulators (in-memory pipes in lockstep, real ptys in real
// time); any other port is opened on the host as the robot computer would, so a real device can
// join a simulated run. The world steps on its own 5 ms grid: in lockstep as the firmware's
// clock advances past each step, in real time on the board's own thread. The referee watches
// every step.
#include <atomic>
#include <memory>
#include <mutex>
#include <span>
#include <string_view>
#include <thread>
#include <vector>

#include "sen3bot/sim/canopen/io_node_emulator.hpp"
#include "sen3bot/hal/board.hpp"
#include "sen3bot/msg/people.hpp"
#include "sen3bot/sim/referee.hpp"
#include "sen3bot/sim/simulation.hpp"
#include "sen3bot/tasks/topic.hpp"

namespace sen3bot::sim {

// A discrete line a scenario drives (the e-stop) or reads (the light).
class SimLine final : public hal::DigitalInput, public hal::DigitalOutput {
 public:
  Result<bool> read() override { return state_.load(std::memory_order_acquire); }
  Status write(bool on) override {
    state_.store(on, std::memory_order_release);
    return Status::success();
  }
  [[nodiscard]] bool state() const noexcept { return state_.load(std::memory_order_acquire); }

 private:
  std::atomic<bool> state_{false};
};

// Sees every byte a driver writes to a simulated link, stamped with the board's clock, on the
// writing thread: what went out on the wire, and when.
class WireTap {
 public:
  virtual ~WireTap() = default;
  virtual void on_write(std::string_view link, std::span<const std::uint8_t> bytes, hal::Nanos now_ns) = 0;
};

class SimBoard final : public hal::Board, private hal::SimClock::Listener {
 public:
  static constexpr hal::Nanos kStepNs = hal::millis(5);
  // In real time the world thread stands for physics and the devices' own processors, which no
  // load on the robot's computer delays: it runs above every task of the firmware's table.
  static constexpr int kWorldPriority = 90;

  // Builds the world and the emulators (LinkKind from `lockstep`). Allocates; before the run.
  static Result<std::unique_ptr<SimBoard>> create(const SimulationConfig& config, bool lockstep);
  ~SimBoard() override;

  [[nodiscard]] std::string_view name() const override { return "sim"; }
  [[nodiscard]] hal::Clock& clock() override;
  [[nodiscard]] hal::SimClock* lockstep_clock() noexcept override { return lockstep_ ? &sim_clock_ : nullptr; }
  Result<hal::Link> open_link(std::string_view link, const hal::LinkRequest& request) override;
  // "detector" at "sim": the simulated person detector; any other address opens on the host.
  Result<std::unique_ptr<hal::DatagramPort>> open_datagram(std::string_view name, std::string_view address) override;
  // "io_node" at "sim": the simulated CAN I/O node's bus (once); any other interface opens on
  // the host.
  Result<std::unique_ptr<hal::CanBus>> open_can(std::string_view name, std::string_view interface) override;
  // "fleet" at "sim": a client of the site's in-process broker; mqtt:// and mqtts:// open a
  // real MQTT client on the host.
  Result<std::unique_ptr<hal::PubSub>> open_pubsub(std::string_view name, const hal::PubSubOptions& options) override;
  [[nodiscard]] hal::DigitalInput* input(std::string_view name) noexcept override {
    return name == "estop" ? &estop_ : nullptr;
  }
  [[nodiscard]] hal::DigitalOutput* output(std::string_view name) noexcept override {
    return name == "light" ? &light_ : nullptr;
  }
  Status start() override;
  void stop() noexcept override;

  [[nodiscard]] Simulation& simulation() noexcept { return *simulation_; }
  // f(simulation) between two of the world's steps: in real time the world's thread waits for
  // it (keep it short); in lockstep at once, as nothing else steps the world.
  template <class F>
  void with_world(F&& f) {
    const std::lock_guard<std::mutex> hold(world_mutex_);
    f(*simulation_);
  }
  [[nodiscard]] Referee& referee() noexcept { return referee_; }
  [[nodiscard]] SimDetector& detector() noexcept { return *detector_; }
  [[nodiscard]] SimLine& estop() noexcept { return estop_; }
  [[nodiscard]] SimLine& light() noexcept { return light_; }
  // The CAN I/O node and its bus (sim.io_node); null without one. Lockstep: touch between
  // slices only (the world's thread steps them in real time).
  [[nodiscard]] canopen::IoNodeEmulator* io_node() noexcept { return io_node_.get(); }
  [[nodiscard]] hal::MemoryCanBus& can_bus() noexcept { return can_bus_; }
  // The in-process broker "sim" clients join: the board's own, unless a site with several
  // robots shares one (set before the firmware opens its link; it must outlive the link).
  [[nodiscard]] hal::MemoryBroker& site_broker() noexcept { return shared_broker_ != nullptr ? *shared_broker_ : own_broker_; }
  void set_site_broker(hal::MemoryBroker* broker) noexcept { shared_broker_ = broker; }
  // The true people: the world's person movers present, hidden or not, the msg::People::kMax
  // nearest the robot, in the map frame, published every world step once publish_true_people()
  // was called (before start()). What a perfect perception would report, for
  // Firmware::use_people_source(); a walking person (>= 0.2 m/s) is dynamic.
  void publish_true_people() noexcept { publish_true_people_ = true; }
  [[nodiscard]] const tasks::Topic<msg::People>& true_people() const noexcept { return true_people_; }
  // Lockstep links only; set before the links are opened. Null: no tap.
  void set_wire_tap(WireTap* tap) noexcept { tap_ = tap; }

 private:
  SimBoard(std::unique_ptr<Simulation> simulation, bool lockstep);
  void before_advance(hal::Nanos now_ns, hal::Nanos to_ns) override;
  void step(hal::Nanos now_ns) noexcept;
  void step_io_node(hal::Nanos now_ns) noexcept;
  void step_true_people(hal::Nanos now_ns) noexcept;
  void thread_main(std::atomic<int>& started);

  std::unique_ptr<Simulation> simulation_;
  bool lockstep_;
  hal::SimClock sim_clock_;
  hal::PosixClock posix_clock_;
  hal::PosixBoard host_;
  Referee referee_;
  SimLine estop_;
  SimLine light_;
  WireTap* tap_ = nullptr;
  std::mutex world_mutex_;  // real time: held by each world step and by with_world()
  bool publish_true_people_ = false;
  tasks::Topic<msg::People> true_people_;
  msg::People true_people_message_;
  std::unique_ptr<SimDetector> detector_;
  hal::MemoryCanBus can_bus_{4};
  hal::MemoryCanNode* can_firmware_ = nullptr;  // the firmware's station, handed out once
  hal::MemoryCanNode* can_node_ = nullptr;      // the I/O node's
  bool can_handed_out_ = false;
  std::unique_ptr<canopen::IoNodeEmulator> io_node_;
  hal::MemoryBroker own_broker_;
  hal::MemoryBroker* shared_broker_ = nullptr;
  std::size_t next_io_event_ = 0;
  hal::Nanos next_step_ns_ = 0;
  std::thread thread_;
  std::atomic<bool> running_{false};
};

}  // namespace sen3bot::sim
