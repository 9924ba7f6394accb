#pragma once
// Running a firmware over its board: the `run` command of both binaries. In lockstep when the
// board's clock only moves when told to (a simulated board), else in real time with one OS
// thread per task group, until SIGINT/SIGTERM, the configured duration or the mission's end.
#include <signal.h>

#include <cstdio>
#include <string>

#include "config.hpp"
#include "firmware.hpp"
#include "sen3bot/hal/board.hpp"

namespace sen3bot::firmware {

struct RunOptions {
  std::string config_path;
  bool have_duration = false;
  double duration_s = 0;
  bool have_clock = false;
  ClockMode clock = ClockMode::lockstep;
};

// `run --config FILE [--duration S] [--clock lockstep|realtime]`; 0, or 2 after printing why.
int parse_run_options(int argc, char** argv, const char* program, RunOptions& options, std::FILE* err);
void apply(const RunOptions& options, FirmwareConfig& config);

// Locks memory (real time), prints the banner and the memory budgets, runs, and prints the
// mission report and the task statistics. `fw` is initialised. Returns the exit status: 0, 1
// on a run-time failure, 3 when the mission ran to its end and failed.
int run_firmware(Firmware& fw, hal::Board& board, const FirmwareConfig& config, std::FILE* out, std::FILE* err);

// SIGINT/SIGTERM stay blocked (pending) from the start of `run` until the run loop is ready for
// them, so a stop request during start-up is never lost nor kills the process.
class StopSignalsBlocked {
 public:
  StopSignalsBlocked();
  ~StopSignalsBlocked();
  StopSignalsBlocked(const StopSignalsBlocked&) = delete;
  StopSignalsBlocked& operator=(const StopSignalsBlocked&) = delete;
  // SIGINT and SIGTERM, for sigtimedwait().
  [[nodiscard]] const sigset_t& signals() const noexcept { return set_; }

 private:
  sigset_t set_;
  sigset_t previous_;
};

}  // namespace sen3bot::firmware
