#include "sen3bot/lms200/task.hpp"

#include <new>

namespace sen3bot::lms200 {

Lms200Task::Lms200Task(const Lms200Config& config, tasks::Topic<LaserScan>& topic) : config_(config), topic_(topic) {}

Lms200Task::Lms200Task(const Lms200Config& config, hal::ByteStream& stream, LineControl* line,
                       tasks::Topic<LaserScan>& topic)
    : config_(config), topic_(topic), external_stream_(&stream), external_line_(line) {}

// The device and the scan live in the arena and are trivially destructible: nothing to run
// here, and the arena may be gone already.
Lms200Task::~Lms200Task() = default;

Status Lms200Task::init(std::pmr::memory_resource& arena) {
  if (!valid_variant(config_.variant))
    return Error::format(Errc::config, "lms200: variant %u/%u is not one the LMS200 has", config_.variant.angle_deg,
                         config_.variant.resolution_cdeg);
  if (!baud_mode(config_.baud)) return Error::format(Errc::config, "lms200: unsupported baud %u", config_.baud);
  if (!valid_measuring_mode(static_cast<std::uint8_t>(config_.measuring_mode)))
    return Error(Errc::config, "lms200: unknown measuring mode");
  hal::ByteStream* stream = external_stream_;
  LineControl* line = external_line_;
  if (stream == nullptr) {
    Result<std::unique_ptr<hal::ByteStream>> opened = hal::open_byte_stream(config_.port, config_.baud);
    if (!opened) return opened.error();
    owned_stream_ = std::move(*opened);
    if (auto* serial = dynamic_cast<hal::SerialPort*>(owned_stream_.get())) {
      owned_line_ = std::make_unique<SerialLineControl>(*serial);
      line = owned_line_.get();
    }
    stream = owned_stream_.get();
  }
  try {
    void* device_memory = arena.allocate(sizeof(Lms200Device), alignof(Lms200Device));
    device_ = new (device_memory) Lms200Device(config_, *stream, line);
    void* scan_memory = arena.allocate(sizeof(LaserScan), alignof(LaserScan));
    scan_ = new (scan_memory) LaserScan();
  } catch (const std::bad_alloc&) {
    return Error::format(Errc::capacity, "lms200: task arena too small (needs %zu bytes)", kArenaBytes);
  }
  arena_ = &arena;
  return Status::success();
}

void Lms200Task::step(const tasks::StepContext& context) {
  if (device_ == nullptr) return;
  const hal::Nanos now = context.start_ns;
  if (!started_) {
    device_->start(now);
    started_ = true;
  }
  // A vanished USB adapter: reopen the same path now and then; the device restarts itself.
  if (device_->phase() == Lms200Device::Phase::error_wait && device_->last_error().code() == Errc::disconnected &&
      owned_stream_ != nullptr && now >= next_reopen_ns_) {
    next_reopen_ns_ = now + hal::millis(config_.restart_delay_ms);
    if (auto* serial = dynamic_cast<hal::SerialPort*>(owned_stream_.get())) (void)serial->reopen();
  }
  device_->step(now);
  if (device_->take_new_scan(*scan_)) topic_.publish(*scan_, now);
}

void Lms200Task::shutdown() {
  if (device_ == nullptr || owned_stream_ == nullptr || !started_) return;
  hal::PosixClock clock;
  const hal::Nanos give_up = clock.now() + hal::seconds(2);
  device_->request_stop(clock.now());
  while (device_->phase() != Lms200Device::Phase::stopped && clock.now() < give_up) {
    device_->step(clock.now());
    clock.sleep_until(clock.now() + hal::millis(1));
  }
}

}  // namespace sen3bot::lms200
