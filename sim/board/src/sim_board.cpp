#include "sen3bot/sim/sim_board.hpp"

#include <array>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <thread>
#include <utility>

#include "sen3bot/hal/rt_setup.hpp"
#include "sen3bot/hal/serial.hpp"

namespace sen3bot::sim {

namespace {

// A driver's view of an in-memory link it does not own (the pipe belongs to the simulation),
// showing what it writes to the tap.
class BorrowedStream final : public hal::ByteStream {
 public:
  BorrowedStream(hal::ByteStream& stream, std::string_view link, WireTap* tap, hal::Clock& clock)
      : stream_(stream), link_(link), tap_(tap), clock_(clock) {}
  Result<std::size_t> read(std::span<std::uint8_t> out) override { return stream_.read(out); }
  Result<std::size_t> write(std::span<const std::uint8_t> data) override {
    Result<std::size_t> wrote = stream_.write(data);
    if (tap_ != nullptr && wrote && *wrote > 0) tap_->on_write(link_, data.first(*wrote), clock_.now());
    return wrote;
  }
  [[nodiscard]] int poll_fd() const override { return stream_.poll_fd(); }
  [[nodiscard]] std::string_view name() const override { return stream_.name(); }

 private:
  hal::ByteStream& stream_;
  std::string_view link_;
  WireTap* tap_;
  hal::Clock& clock_;
};

}  // namespace

Result<std::unique_ptr<SimBoard>> SimBoard::create(const SimulationConfig& config, bool lockstep) {
  SimulationConfig c = config;
  c.link = lockstep ? LinkKind::memory : LinkKind::pty;
  Result<std::unique_ptr<Simulation>> simulation = Simulation::create(c);
  if (!simulation) return simulation.error();
  return std::unique_ptr<SimBoard>(new SimBoard(std::move(*simulation), lockstep));
}

SimBoard::SimBoard(std::unique_ptr<Simulation> simulation, bool lockstep)
    : simulation_(std::move(simulation)), lockstep_(lockstep) {
  if (lockstep_) sim_clock_.set_listener(this);
  const SimulationConfig& c = simulation_->config();
  detector_ = std::make_unique<SimDetector>(c.detector, c.seed);
  if (c.io_node.enabled) {
    // Two stations: the firmware's and the node's; each queue holds far more than a 5 ms step.
    can_firmware_ = *can_bus_.attach("firmware");
    can_node_ = *can_bus_.attach("io-node");
    io_node_ = std::make_unique<canopen::IoNodeEmulator>(canopen::IoNodeEmulatorConfig{.node = c.io_node.node});
    io_node_->set_inputs(c.io_node.inputs);
    io_node_->power_up(0);
  }
}

SimBoard::~SimBoard() {
  stop();
  sim_clock_.set_listener(nullptr);
}

hal::Clock& SimBoard::clock() {
  if (lockstep_) return sim_clock_;
  return posix_clock_;
}

Result<hal::Link> SimBoard::open_link(std::string_view link, const hal::LinkRequest& request) {
  if (request.port != "sim") return host_.open_link(link, request);
  Simulation& sim = *simulation_;
  hal::Link opened;
  if (link == "base" || link == "laser") {
    const bool base = link == "base";
    if (lockstep_) {
      opened.stream = std::make_unique<BorrowedStream>(base ? *sim.base_driver_stream() : *sim.laser_driver_stream(),
                                                       base ? "base" : "laser", tap_, sim_clock_);
      if (!base) opened.baud_control = sim.laser_driver_line();
      opened.baud = request.baud;
      return opened;
    }
    const std::string path = base ? sim.base_device_path() : sim.laser_device_path();
    return host_.open_link(link, hal::LinkRequest{path, request.baud, request.connect_timeout_ms});
  }
  return Error::format(Errc::not_found, "sim board: no simulated device behind the '%.*s' link",
                       static_cast<int>(link.size()), link.data());
}

void SimBoard::step_io_node(hal::Nanos now_ns) noexcept {
  const std::vector<SimIoEvent>& events = simulation_->config().io_node.events;
  for (; next_io_event_ < events.size() && static_cast<hal::Nanos>(events[next_io_event_].at_s * 1e9) <= now_ns; ++next_io_event_) {
    const SimIoEvent& e = events[next_io_event_];
    switch (e.what) {
      case SimIoEvent::What::inputs: io_node_->set_inputs(e.inputs); break;
      case SimIoEvent::What::silent: io_node_->set_silent(true); break;
      case SimIoEvent::What::talking: io_node_->set_silent(false); break;
      case SimIoEvent::What::reboot: io_node_->reboot(now_ns); break;
      case SimIoEvent::What::bus_off: can_bus_.set_link_state(hal::CanLinkState::bus_off); break;
      case SimIoEvent::What::bus_on: can_bus_.set_link_state(hal::CanLinkState::active); break;
    }
  }
  for (;;) {
    Result<std::optional<hal::CanFrame>> frame = can_node_->receive();
    if (!frame || !frame->has_value()) break;
    io_node_->on_frame(**frame, now_ns);
  }
  std::array<hal::CanFrame, 4> out;
  const std::size_t n = io_node_->poll(now_ns, out);
  // A bus that is off takes nothing: what the node had to say is lost, as on a real bus.
  for (std::size_t i = 0; i < n; ++i) (void)can_node_->send(out[i]);
}

void SimBoard::step_true_people(hal::Nanos now_ns) noexcept {
  const world::World& w = simulation_->world();
  const nav::Pose2D robot = simulation_->truth().pose;
  // The nearest kMax, by insertion into a list kept sorted by distance.
  std::array<std::pair<double, std::size_t>, msg::People::kMax> nearest;
  std::size_t n = 0;
  for (std::size_t i = 0; i < w.mover_count(); ++i) {
    if (!w.mover_script(i).person || !w.mover_visible(i)) continue;
    const nav::Point2D p = w.mover_position(i);
    const double d = std::hypot(p.x_m - robot.x_m, p.y_m - robot.y_m);
    if (n == nearest.size() && d >= nearest[n - 1].first) continue;
    std::size_t k = n < nearest.size() ? n++ : n - 1;
    for (; k > 0 && nearest[k - 1].first > d; --k) nearest[k] = nearest[k - 1];
    nearest[k] = {d, i};
  }
  msg::People& out = true_people_message_;
  out.count = static_cast<std::uint8_t>(n);
  out.stamp_ns = now_ns;
  for (std::size_t k = 0; k < n; ++k) {
    const std::size_t i = nearest[k].second;
    const nav::Point2D p = w.mover_position(i);
    const nav::Point2D v = w.mover_velocity(i);
    msg::TrackedPerson& t = out.items[k];
    t = {};
    t.id = static_cast<std::uint32_t>(i + 1);
    t.x_m = p.x_m;
    t.y_m = p.y_m;
    t.vx_m_s = v.x_m;
    t.vy_m_s = v.y_m;
    t.width_m = w.mover_script(i).size_m;
    t.state = std::hypot(v.x_m, v.y_m) >= 0.2 ? msg::PersonState::dynamic_person : msg::PersonState::static_person;
    t.last_seen_ns = now_ns;
  }
  true_people_.publish(out, now_ns);
}

void SimBoard::step(hal::Nanos now_ns) noexcept {
  simulation_->step(now_ns);
  if (io_node_) step_io_node(now_ns);
  if (publish_true_people_) step_true_people(now_ns);
  referee_.observe(simulation_->truth());
  const SimulationConfig& c = simulation_->config();
  if (c.detector.enabled) {
    // The camera sits with the laser (the calibration relates the two): seen from the laser's true pose.
    const nav::Pose2D laser = msg::compose(simulation_->truth().pose, {c.laser_mount.x_m, c.laser_mount.y_m, c.laser_mount.theta_rad});
    const std::int64_t unix_ns = lockstep_ ? hal::SimClock::kEpochUnixNs + now_ns : posix_clock_.unix_now_ns();
    detector_->step(now_ns, unix_ns, simulation_->world(), laser);
  }
}

namespace {
// The board's detector as the firmware's port (the board keeps it).
class DetectorPort final : public hal::DatagramPort {
 public:
  explicit DetectorPort(SimDetector& detector) : detector_(detector) {}
  Result<std::optional<std::size_t>> receive(std::span<std::uint8_t> out) override { return detector_.receive(out); }

 private:
  SimDetector& detector_;
};
}  // namespace

Result<std::unique_ptr<hal::DatagramPort>> SimBoard::open_datagram(std::string_view name, std::string_view address) {
  if (address != "sim") return host_.open_datagram(name, address);
  if (name != "detector") return hal::Board::open_datagram(name, address);
  if (!simulation_->config().detector.enabled)
    return Error(Errc::config, "detector: the simulated robot has no person detector (sim.detector)");
  return std::unique_ptr<hal::DatagramPort>(std::make_unique<DetectorPort>(*detector_));
}

Result<std::unique_ptr<hal::CanBus>> SimBoard::open_can(std::string_view name, std::string_view interface) {
  if (interface != "sim") return host_.open_can(name, interface);
  if (name != "io_node" || !io_node_)
    return Error::format(Errc::config, "%.*s: the simulated robot has no CAN I/O node (sim.io_node)",
                         static_cast<int>(name.size()), name.data());
  if (can_handed_out_) return Error(Errc::capacity, "io_node: the simulated CAN I/O node's bus is already open");
  can_handed_out_ = true;
  return std::unique_ptr<hal::CanBus>(std::make_unique<hal::CanBusRef>(*can_firmware_));
}

Result<std::unique_ptr<hal::PubSub>> SimBoard::open_pubsub(std::string_view name, const hal::PubSubOptions& options) {
  if (options.url != "sim") return host_.open_pubsub(name, options);
  return site_broker().connect(options);
}

void SimBoard::before_advance(hal::Nanos, hal::Nanos to_ns) {
  while (next_step_ns_ <= to_ns) {
    step(next_step_ns_);
    next_step_ns_ += kStepNs;
  }
}

Status SimBoard::start() {
  if (lockstep_ || running_.load()) return Status::success();
  running_.store(true);
  std::atomic<int> started{0};  // 1 real-time, 2 best effort
  thread_ = std::thread([this, &started] { thread_main(started); });
  while (started.load() == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  return Status::success();
}

void SimBoard::stop() noexcept {
  if (!running_.exchange(false)) return;
  if (thread_.joinable()) thread_.join();
}

// Real time: the world steps on its grid from the moment the board starts (t = 0 for movers).
void SimBoard::thread_main(std::atomic<int>& started) {
  const Status fifo = hal::set_current_thread_fifo(kWorldPriority);
  if (!fifo)
    std::fprintf(stderr, "sen3bot-sim: warning: world thread: %s (the simulated world may lag behind under load)\n",
                 fifo.error().c_str());
  (void)hal::prefault_stack(64 * 1024);
  started.store(fifo ? 1 : 2);
  const hal::Nanos origin = posix_clock_.now();
  hal::Nanos next = origin;
  while (running_.load(std::memory_order_acquire)) {
    {
      const std::lock_guard<std::mutex> hold(world_mutex_);
      step(next - origin);
    }
    next += kStepNs;
    const hal::Nanos now = posix_clock_.now();
    if (next < now) next = now;  // fell behind: carry on from now rather than in a burst
    posix_clock_.sleep_until(next);
  }
}

}  // namespace sen3bot::sim
