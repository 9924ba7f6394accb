#include "laser_task.hpp"

#include <new>

#include "adapters.hpp"
#include "sen3bot/hal/serial.hpp"
#include "task_table.hpp"
#include "wiring.hpp"

namespace sen3bot::firmware {

LaserTask::LaserTask(const lms200::Lms200Config& config, hal::Board& board, tasks::Topic<msg::ScanMessage>& topic)
    : config_(config), board_(board), topic_(topic), backoff_(config.restart_delay_ms) {}

// The device and the scans live in the arena and are trivially destructible: nothing to run
// here, and the arena may be gone already.
LaserTask::~LaserTask() = default;

Status LaserTask::init(std::pmr::memory_resource& arena) {
  if (!lms200::valid_variant(config_.variant))
    return Error::format(Errc::config, "lms200: variant %u/%u is not one the LMS200 has", config_.variant.angle_deg,
                         config_.variant.resolution_cdeg);
  if (!lms200::baud_mode(config_.baud)) return Error::format(Errc::config, "lms200: unsupported baud %u", config_.baud);
  if (!lms200::valid_measuring_mode(static_cast<std::uint8_t>(config_.measuring_mode)))
    return Error(Errc::config, "lms200: unknown measuring mode");
  try {
    device_memory_ = arena.allocate(sizeof(lms200::Lms200Device), alignof(lms200::Lms200Device));
    scan_ = new (arena.allocate(sizeof(lms200::LaserScan), alignof(lms200::LaserScan))) lms200::LaserScan();
    message_ = new (arena.allocate(sizeof(msg::ScanMessage), alignof(msg::ScanMessage))) msg::ScanMessage();
  } catch (const std::bad_alloc&) {
    return Error::format(Errc::capacity, "lms200: task arena too small (needs %zu bytes)", kArenaBytes);
  }
  try_open(board_.clock().now());
  return Status::success();
}

void LaserTask::try_open(hal::Nanos now_ns) {
  Result<hal::Link> opened = board_.open_link("laser", hal::LinkRequest{config_.port, config_.baud});
  if (!opened) {
    open_error_ = opened.error();
    missing_.store(true, std::memory_order_relaxed);
    backoff_.failed(now_ns);
    return;
  }
  open_error_.reset();
  missing_.store(false, std::memory_order_relaxed);
  backoff_.succeeded();
  link_ = std::move(*opened);
  device_ = new (device_memory_) lms200::Lms200Device(config_, *link_.stream, link_.baud_control);
}

void LaserTask::step(const tasks::StepContext& context) {
  if (scan_ == nullptr) return;
  const hal::Nanos now = context.start_ns;
  if (device_ == nullptr) {
    if (backoff_.due(now)) try_open(now);
    if (device_ == nullptr) return;
  }
  if (!started_) {
    device_->start(now);
    started_ = true;
  }
  // A vanished USB adapter: reopen the same port now and then; the device restarts itself.
  // The reopened stream replaces the old one under the device (same object, new descriptor).
  if (device_->phase() == lms200::Lms200Device::Phase::error_wait &&
      device_->last_error().code() == Errc::disconnected && backoff_.due(now)) {
    backoff_.failed(now);  // the next try waits longer, unless the device streams again first
    if (auto* serial = dynamic_cast<hal::SerialPort*>(link_.stream.get())) (void)serial->reopen();
  }
  device_->step(now);
  if (device_->phase() == lms200::Lms200Device::Phase::streaming) backoff_.succeeded();
  missing_.store(device_->phase() == lms200::Lms200Device::Phase::error_wait &&
                     device_->last_error().code() == Errc::disconnected,
                 std::memory_order_relaxed);
  if (device_->take_new_scan(*scan_)) {
    to_nav_scan(*scan_, *message_);
    topic_.publish(*message_, now);
  }
}

void LaserTask::shutdown() {
  if (device_ == nullptr || !started_ || link_.baud_control == nullptr) return;
  hal::Clock& clock = board_.clock();
  const hal::Nanos give_up = clock.now() + hal::seconds(2);
  device_->request_stop(clock.now());
  while (device_->phase() != lms200::Lms200Device::Phase::stopped && clock.now() < give_up) {
    device_->step(clock.now());
    clock.sleep_until(clock.now() + hal::millis(1));
  }
}

Status make_laser(Wiring& w) {
  if (!w.config.devices.has_laser) return w.absent("needs devices.laser");
  const lms200::Lms200Config& laser = w.config.devices.laser;
  w.takes("LMS200 telegrams on " + laser.port + " at " + std::to_string(laser.baud) +
          " baud (lms200::Scan, adapters.cpp)");
  w.sends("LMS200 requests: the mode, the variant, the baud rate, continuous output");
  w.make<LaserTask>(laser, w.board, w.writes(&Topics::scan));
  return Status::success();
}

}  // namespace sen3bot::firmware
