#include "sen3bot/sim/p2os/emulator_runner.hpp"

#include <poll.h>

#include <algorithm>
#include <array>

#include "sen3bot/hal/clock.hpp"

namespace sen3bot::p2os {

namespace {
// The loop wakes at least this often to send SIPs on time (SipCycle is 100 ms).
constexpr int kLoopPeriodMs = 2;

// What a UART at the wrong rate delivers: garbage in both directions.
class MismatchedRate final : public hal::ByteStream {
 public:
  explicit MismatchedRate(hal::ByteStream& inner) : inner_(inner) {}
  Result<std::size_t> read(std::span<std::uint8_t> out) override {
    Result<std::size_t> got = inner_.read(out);
    if (got)
      for (std::size_t i = 0; i < *got; ++i) out[i] = garble(out[i]);
    return got;
  }
  Result<std::size_t> write(std::span<const std::uint8_t> data) override {
    std::array<std::uint8_t, 256> chunk;
    const std::size_t n = std::min(chunk.size(), data.size());
    for (std::size_t i = 0; i < n; ++i) chunk[i] = garble(data[i]);
    return inner_.write(std::span<const std::uint8_t>(chunk.data(), n));
  }
  [[nodiscard]] std::string_view name() const override { return inner_.name(); }

 private:
  static std::uint8_t garble(std::uint8_t b) { return static_cast<std::uint8_t>((b << 3) | (b >> 5)) ^ 0xA5; }
  hal::ByteStream& inner_;
};

}  // namespace

EmulatorRunner::~EmulatorRunner() { stop(); }

void EmulatorRunner::start_thread() {
  thread_ = std::thread([this] {
    hal::PosixClock clock;
    while (!stop_.load(std::memory_order_acquire)) {
      int fd = -1;
      {
        std::lock_guard lock(mutex_);
        fd = serve(clock.now());
      }
      if (fd >= 0) {
        pollfd p{fd, POLLIN, 0};
        (void)::poll(&p, 1, kLoopPeriodMs);
        // A hung-up fd polls ready at once; pace the loop anyway so it never spins.
        if (p.revents & (POLLHUP | POLLERR | POLLNVAL)) clock.sleep_until(clock.now() + hal::millis(kLoopPeriodMs));
      } else {
        clock.sleep_until(clock.now() + hal::millis(kLoopPeriodMs));
      }
    }
  });
}

void EmulatorRunner::stop() {
  stop_.store(true, std::memory_order_release);
  if (thread_.joinable()) thread_.join();
}

Result<std::unique_ptr<PtyEmulatorRunner>> PtyEmulatorRunner::start(const EmulatorConfig& config,
                                                                   std::string_view link_path,
                                                                   PtyRunnerOptions options) {
  Result<std::unique_ptr<hal::PtyPair>> pty = hal::PtyPair::open();
  if (!pty) return pty.error();
  if (!link_path.empty()) {
    if (Status s = (*pty)->link_slave(link_path); !s) return s.error();
  }
  std::unique_ptr<PtyEmulatorRunner> runner(new PtyEmulatorRunner(config, std::move(*pty), options));
  runner->start_thread();
  return runner;
}

PtyEmulatorRunner::PtyEmulatorRunner(const EmulatorConfig& config, std::unique_ptr<hal::PtyPair> pty,
                                     PtyRunnerOptions options)
    : EmulatorRunner(config), pty_(std::move(pty)), options_(options), slave_path_(pty_->slave_path()) {}

PtyEmulatorRunner::~PtyEmulatorRunner() { stop(); }

void PtyEmulatorRunner::close_device() {
  std::lock_guard lock(mutex_);
  pty_.reset();
}

int PtyEmulatorRunner::serve(hal::Nanos now_ns) {
  if (!pty_) return -1;
  // A pty master reads EIO while no client holds the slave; the robot carries on regardless.
  if (options_.enforce_baud) {
    const Result<std::uint32_t> client_baud = pty_->slave_baud();
    if (client_baud && *client_baud != emulator_.host_baud()) {
      MismatchedRate garbled(*pty_);
      (void)emulator_.step(garbled, now_ns);
      return pty_->poll_fd();
    }
  }
  (void)emulator_.step(*pty_, now_ns);
  return pty_->poll_fd();
}

Result<std::unique_ptr<TcpEmulatorRunner>> TcpEmulatorRunner::start(const EmulatorConfig& config, std::uint16_t port,
                                                                   std::string_view bind_address) {
  Result<std::unique_ptr<hal::TcpListener>> listener = hal::TcpListener::listen(bind_address, port);
  if (!listener) return listener.error();
  std::unique_ptr<TcpEmulatorRunner> runner(new TcpEmulatorRunner(config, std::move(*listener)));
  runner->start_thread();
  return runner;
}

TcpEmulatorRunner::TcpEmulatorRunner(const EmulatorConfig& config, std::unique_ptr<hal::TcpListener> listener)
    : EmulatorRunner(config),
      listener_(std::move(listener)),
      port_(listener_->port()),
      silent_client_ns_(hal::millis(config.watchdog_ms)) {}

TcpEmulatorRunner::~TcpEmulatorRunner() { stop(); }

void TcpEmulatorRunner::drop_client() {
  std::lock_guard lock(mutex_);
  client_.reset();
}

int TcpEmulatorRunner::serve(hal::Nanos now_ns) {
  // A client that vanished without closing (host down, cable out) holds the connection until
  // keep-alive notices. Once it has been silent for the watchdog time, a waiting client takes
  // over at once, on a new session.
  const bool silent = client_ && now_ns - std::max(emulator_.last_packet_ns(), client_since_ns_) > silent_client_ns_;
  if (!client_ || silent) {
    Result<std::unique_ptr<hal::TcpStream>> accepted = listener_->accept();
    if (accepted && *accepted) {
      client_ = std::move(*accepted);
      client_since_ns_ = now_ns;
      clients_.fetch_add(1);
      emulator_.reset_session();
    }
  }
  if (!client_) return listener_->poll_fd();
  if (Status s = emulator_.step(*client_, now_ns); !s) {
    client_.reset();  // the client left; the next one starts a new session
    return listener_->poll_fd();
  }
  if (emulator_.take_session_closed()) {
    // CLOSE ends the connection, as AMRISim does: the client reads EOF instead of waiting on
    // a silent socket.
    client_.reset();
    closes_.fetch_add(1);
    return listener_->poll_fd();
  }
  return client_->poll_fd();
}

}  // namespace sen3bot::p2os
