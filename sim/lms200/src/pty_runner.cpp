#include "sen3bot/sim/lms200/pty_runner.hpp"

#include <poll.h>

namespace sen3bot::lms200 {

Result<std::unique_ptr<Lms200PtyRunner>> Lms200PtyRunner::open(const EmulatorOptions& options, RangeSource& world) {
  Result<std::unique_ptr<hal::PtyPair>> pty = hal::PtyPair::open();
  if (!pty) return pty.error();
  return std::unique_ptr<Lms200PtyRunner>(new Lms200PtyRunner(std::move(*pty), options, world));
}

Lms200PtyRunner::Lms200PtyRunner(std::unique_ptr<hal::PtyPair> pty, const EmulatorOptions& options,
                                 RangeSource& world)
    : pty_(std::move(pty)), client_line_(*pty_), emulator_(options, *pty_, world, &client_line_) {}

Lms200PtyRunner::~Lms200PtyRunner() { stop(); }

void Lms200PtyRunner::start() {
  if (running_.exchange(true)) return;
  thread_ = std::thread([this] { run(); });
}

void Lms200PtyRunner::stop() {
  running_.store(false);
  if (thread_.joinable()) thread_.join();
}

void Lms200PtyRunner::with_emulator(const std::function<void(Lms200Emulator&)>& fn) {
  std::lock_guard lock(mutex_);
  fn(emulator_);
}

void Lms200PtyRunner::run() {
  hal::PosixClock clock;
  while (running_.load(std::memory_order_relaxed)) {
    {
      std::lock_guard lock(mutex_);
      emulator_.step(clock.now());
    }
    // Wake on input at once, otherwise every 500 us: 25 bytes per write at 500 kbaud, and
    // few enough wake-ups that a loaded machine (or qemu) still keeps up.
    pollfd p{pty_->poll_fd(), POLLIN, 0};
    timespec wait{0, 500'000};
    ::ppoll(&p, 1, &wait, nullptr);
    if (p.revents & (POLLHUP | POLLERR)) clock.sleep_until(clock.now() + hal::millis(1));
  }
}

}  // namespace sen3bot::lms200
