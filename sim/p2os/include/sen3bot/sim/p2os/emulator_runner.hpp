#pragma once
// Thin real-time runners for the emulator: a thread stepping it every couple of
// milliseconds over a pseudo-terminal master (the driver opens the slave like a serial
// port) or over TCP connections (one client at a time, like MobileSim on port 8101).
#include <atomic>
#include <cstdint>
#include <memory>
#include <mutex>
#include <string>
#include <string_view>
#include <thread>

#include "sen3bot/hal/pty.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/hal/tcp.hpp"
#include "sen3bot/sim/p2os/emulator.hpp"

namespace sen3bot::p2os {

class EmulatorRunner {
 public:
  virtual ~EmulatorRunner();
  EmulatorRunner(const EmulatorRunner&) = delete;
  EmulatorRunner& operator=(const EmulatorRunner&) = delete;

  // Runs f(P2osEmulator&) with the emulator thread held off (fault injection, inspection).
  template <typename F>
  auto with_emulator(F&& f) {
    std::lock_guard lock(mutex_);
    return f(emulator_);
  }
  // Stops the thread; idempotent.
  void stop();

 protected:
  explicit EmulatorRunner(const EmulatorConfig& config) : emulator_(config) {}
  void start_thread();
  // One pass of the loop (called with the mutex held); returns the fd to wait on or -1.
  virtual int serve(hal::Nanos now_ns) = 0;

  std::mutex mutex_;
  P2osEmulator emulator_;

 private:
  std::atomic<bool> stop_{false};
  std::thread thread_;
};

struct PtyRunnerOptions {
  // Behave like a UART: while the client's line rate (read through the master) differs from
  // the robot's HOST rate, bytes in both directions arrive garbled. Off by default: on a pty
  // the rate is meaningless and clients switching with HOSTBAUD should simply carry on.
  bool enforce_baud = false;
};

class PtyEmulatorRunner final : public EmulatorRunner {
 public:
  // Opens a pty, optionally links `link_path` -> its slave, and starts serving.
  static Result<std::unique_ptr<PtyEmulatorRunner>> start(const EmulatorConfig& config,
                                                          std::string_view link_path = {},
                                                          PtyRunnerOptions options = {});
  ~PtyEmulatorRunner() override;
  [[nodiscard]] const std::string& slave_path() const { return slave_path_; }
  // The device vanishes: the master is closed; the client's reads fail from then on.
  // (CLOSE cannot close a pty: the session ends and SIPs stop, but the line stays up, as a
  // serial port does, and the next SYNC0 starts a handshake.)
  void close_device();

 private:
  PtyEmulatorRunner(const EmulatorConfig& config, std::unique_ptr<hal::PtyPair> pty, PtyRunnerOptions options);
  int serve(hal::Nanos now_ns) override;
  std::unique_ptr<hal::PtyPair> pty_;
  PtyRunnerOptions options_;
  std::string slave_path_;
};

class TcpEmulatorRunner final : public EmulatorRunner {
 public:
  // Listens on bind_address:port (port 0 picks a free one). Each new client starts a fresh
  // session (sync-wait, odometry zeroed), as the simulators do. A second client waits until
  // the first leaves, or takes over once the first has sent nothing for the watchdog time.
  // CLOSE ends the session and the connection.
  static Result<std::unique_ptr<TcpEmulatorRunner>> start(const EmulatorConfig& config, std::uint16_t port,
                                                          std::string_view bind_address = "127.0.0.1");
  ~TcpEmulatorRunner() override;
  [[nodiscard]] std::uint16_t port() const { return port_; }
  [[nodiscard]] std::uint64_t clients_served() const { return clients_.load(); }
  // Connections the runner closed after the client's CLOSE.
  [[nodiscard]] std::uint64_t connections_closed() const { return closes_.load(); }
  // Drops the current client's connection (the peer reads EOF).
  void drop_client();

 private:
  TcpEmulatorRunner(const EmulatorConfig& config, std::unique_ptr<hal::TcpListener> listener);
  int serve(hal::Nanos now_ns) override;
  std::unique_ptr<hal::TcpListener> listener_;
  std::unique_ptr<hal::TcpStream> client_;
  std::uint16_t port_;
  hal::Nanos silent_client_ns_;
  hal::Nanos client_since_ns_ = 0;
  std::atomic<std::uint64_t> clients_{0};
  std::atomic<std::uint64_t> closes_{0};
};

}  // namespace sen3bot::p2os
