#pragma once
// A scenario case's whole firmware over its simulated board (cmd_sim.cpp, cmd_cobot.cpp): the
// firmware's status lines sent nowhere, the start with the referee watching, and the stop when
// the case cannot go on.
#include <cstdio>
#include <string_view>

#include "firmware.hpp"
#include "sen3bot/sim/sim_board.hpp"

namespace sen3bot::sim {

// The firmware's log (the per-task status lines of `run`): /dev/null, or `out` should it not
// open; closed with this.
class QuietLog {
 public:
  explicit QuietLog(std::FILE* out) : out_(out), file_(std::fopen("/dev/null", "w")) {
    if (file_ == nullptr) file_ = out;
  }
  ~QuietLog() {
    if (file_ != out_) std::fclose(file_);
  }
  QuietLog(const QuietLog&) = delete;
  QuietLog& operator=(const QuietLog&) = delete;
  [[nodiscard]] std::FILE* file() const noexcept { return file_; }

 private:
  std::FILE* out_;
  std::FILE* file_;
};

// The referee watching the firmware's estimate and people; the board started, then the firmware.
inline Status start_case(firmware::Firmware& fw, SimBoard& board) {
  board.referee().watch_estimate(&fw.pose_estimate());
  board.referee().watch_people(&fw.people());
  if (Status s = board.start(); !s) return s;
  return fw.init();
}

// Says on err why the case stopped and shuts the firmware and the board down: exit status 1.
inline int stop_case(firmware::Firmware& fw, SimBoard& board, std::string_view name, const Error& e, std::FILE* err) {
  std::fprintf(err, "sen3bot-sim sim: %.*s: %s\n", static_cast<int>(name.size()), name.data(), e.c_str());
  fw.shutdown();
  board.stop();
  return 1;
}

}  // namespace sen3bot::sim
