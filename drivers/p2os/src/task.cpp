#include "sen3bot/p2os/task.hpp"

#include <new>

#include "sen3bot/hal/serial.hpp"
#include "sen3bot/hal/tcp.hpp"

namespace sen3bot::p2os {

namespace {

// A serial port that also lets the driver change its rate.
class SerialLink final : public hal::ByteStream, public BaudControl {
 public:
  explicit SerialLink(std::unique_ptr<hal::SerialPort> port) : port_(std::move(port)) {}
  Result<std::size_t> read(std::span<std::uint8_t> out) override { return port_->read(out); }
  Result<std::size_t> write(std::span<const std::uint8_t> data) override { return port_->write(data); }
  [[nodiscard]] int poll_fd() const override { return port_->poll_fd(); }
  [[nodiscard]] std::string_view name() const override { return port_->name(); }
  Status set_baud(std::uint32_t baud) override { return port_->set_baud(baud); }

 private:
  std::unique_ptr<hal::SerialPort> port_;
};

}  // namespace

Result<OpenedLink> open_p2os_link(const P2osConfig& config) {
  OpenedLink link;
  if (hal::is_tcp_url(config.port)) {
    Result<std::unique_ptr<hal::ByteStream>> stream = hal::open_byte_stream(config.port, 0, config.connect_timeout_ms);
    if (!stream) return stream.error();
    link.stream = std::move(*stream);
    return link;
  }
  Result<std::unique_ptr<hal::SerialPort>> port = hal::SerialPort::open(config.port, config.baud);
  if (!port) return port.error();
  auto serial = std::make_unique<SerialLink>(std::move(*port));
  link.baud_control = serial.get();
  link.baud = config.baud;
  link.stream = std::move(serial);
  return link;
}

P2osTask::P2osTask(const P2osConfig& config, hal::Clock& clock, tasks::Topic<BaseSetpoint>& setpoint_topic,
                   tasks::Topic<BaseState>& state_topic, LinkOpener opener)
    : config_(config),
      reopen_config_(config),
      clock_(clock),
      setpoint_topic_(setpoint_topic),
      state_topic_(state_topic),
      opener_(std::move(opener)) {
  reopen_config_.connect_timeout_ms = config.reopen_connect_timeout_ms;
}

P2osTask::~P2osTask() {
  if (driver_ != nullptr) {
    driver_->detach();
    driver_->~P2osDriver();
    arena_->deallocate(driver_, sizeof(P2osDriver), alignof(P2osDriver));
  }
}

Status P2osTask::init(std::pmr::memory_resource& arena) {
  if (driver_ != nullptr) return Error(Errc::invalid_argument, "p2os task: init called twice");
  try {
    void* memory = arena.allocate(sizeof(P2osDriver), alignof(P2osDriver));
    driver_ = new (memory) P2osDriver(config_);
    arena_ = &arena;
  } catch (const std::bad_alloc&) {
    return Error::format(Errc::capacity, "p2os task: the driver needs %zu bytes of arena", sizeof(P2osDriver));
  }
  try_open(config_, clock_.now());
  return Status::success();
}

void P2osTask::try_open(const P2osConfig& config, hal::Nanos now_ns) {
  Result<OpenedLink> opened = opener_(config);
  if (!opened) {
    open_error_ = opened.error();
    next_open_ns_ = now_ns + hal::millis(config_.reopen_delay_ms);
    return;
  }
  open_error_.reset();
  link_ = std::move(*opened);
  driver_->attach(*link_.stream, now_ns, link_.baud_control, link_.baud);
}

void P2osTask::step(const tasks::StepContext& context) {
  if (driver_ == nullptr) return;
  const hal::Nanos now_ns = context.start_ns;
  tasks::Sample<BaseSetpoint> sample;
  if (setpoint_topic_.read(sample) && sample.sequence != last_setpoint_sequence_) {
    last_setpoint_sequence_ = sample.sequence;
    driver_->set_setpoint(sample.value, now_ns);
  }
  if (!driver_->attached() && !driver_->closed()) {
    if (link_.stream) {
      // The stream failed: drop it and try again after the reopen delay.
      open_error_ = driver_->stream_error();
      link_ = OpenedLink{};
      next_open_ns_ = now_ns + hal::millis(config_.reopen_delay_ms);
    }
    if (now_ns >= next_open_ns_) try_open(reopen_config_, now_ns);
  }
  driver_->step(now_ns);
  const BaseState& state = driver_->state();
  if (driver_->take_new_sip() || state.link != last_published_link_) {
    state_topic_.publish(state, now_ns);
    last_published_link_ = state.link;
  }
}

void P2osTask::shutdown() {
  if (driver_ == nullptr || !driver_->attached()) return;
  driver_->request_close(clock_.now());
  const hal::Nanos give_up_ns = clock_.now() + hal::seconds(1);
  while (!driver_->closed() && driver_->attached() && clock_.now() < give_up_ns) {
    driver_->step(clock_.now());
    clock_.sleep_until(clock_.now() + hal::millis(2));
  }
  state_topic_.publish(driver_->state(), clock_.now());
}

}  // namespace sen3bot::p2os
