#pragma once
// Runs an Lms200Emulator in real time on the master side of a pseudo-terminal, on its own
// thread. The client's real baud is read from the pty master at every step, so a client at
// the wrong rate receives garbage, as on a wire.
#include <atomic>
#include <functional>
#include <memory>
#include <mutex>
#include <string>
#include <thread>

#include "sen3bot/hal/pty.hpp"
#include "sen3bot/sim/lms200/emulator.hpp"

namespace sen3bot::lms200 {

class Lms200PtyRunner {
 public:
  // `world` must outlive the runner.
  static Result<std::unique_ptr<Lms200PtyRunner>> open(const EmulatorOptions& options, RangeSource& world);
  ~Lms200PtyRunner();
  Lms200PtyRunner(const Lms200PtyRunner&) = delete;
  Lms200PtyRunner& operator=(const Lms200PtyRunner&) = delete;

  [[nodiscard]] std::string_view slave_path() const { return pty_->slave_path(); }
  Status link(std::string_view link_path) { return pty_->link_slave(link_path); }

  void start();
  void stop();
  // Runs `fn` on the emulator between two steps (change faults, read counters).
  void with_emulator(const std::function<void(Lms200Emulator&)>& fn);

 private:
  class PtyClientLine final : public ClientLine {
   public:
    explicit PtyClientLine(hal::PtyPair& pty) : pty_(pty) {}
    Result<std::uint32_t> client_baud() override { return pty_.slave_baud(); }

   private:
    hal::PtyPair& pty_;
  };

  Lms200PtyRunner(std::unique_ptr<hal::PtyPair> pty, const EmulatorOptions& options, RangeSource& world);
  void run();

  std::unique_ptr<hal::PtyPair> pty_;
  PtyClientLine client_line_;
  Lms200Emulator emulator_;
  std::mutex mutex_;
  std::atomic<bool> running_{false};
  std::thread thread_;
};

}  // namespace sen3bot::lms200
