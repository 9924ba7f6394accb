#pragma once
// One whole firmware on a simulated board in lockstep time until its mission ends or the run's
// limit: what an experiment's worker runs per seed (experiment dol, experiment crowd).
#include <cstdio>
#include <memory>
#include <string>

#include "firmware.hpp"
#include "sen3bot/sim/sim_board.hpp"

namespace sen3bot::sim {

// Builds the board and the firmware (its log to /dev/null), starts them, and runs the scheduler
// in `slice`s until the mission finishes or config.duration_s (600 s when not set) has passed,
// calling on_slice(fw, board, sim_s) after each slice; then shuts both down and calls
// on_end(fw, board, sim_s). Returns "" or why the run could not run (on_end is then not called).
// true_people: the firmware's people row relays the board's true people instead of sensing them
// (perfect perception; the configuration must have no detector row).
template <class OnSlice, class OnEnd>
std::string run_lockstep_mission(const firmware::FirmwareConfig& config, const SimulationConfig& world, hal::Nanos slice,
                                 OnSlice on_slice, OnEnd on_end, bool true_people = false) {
  Result<std::unique_ptr<SimBoard>> created = SimBoard::create(world, true);
  if (!created) return created.error().c_str();
  SimBoard& board = **created;
  std::FILE* quiet = std::fopen("/dev/null", "w");
  if (quiet == nullptr) return "cannot open /dev/null";
  std::string error;
  {
    firmware::Firmware fw(config, board, quiet);
    if (true_people) {
      board.publish_true_people();
      fw.use_people_source(&board.true_people());
    }
    board.referee().watch_estimate(&fw.pose_estimate());
    Status status = board.start();
    if (status) status = fw.init();
    double sim_s = 0;
    if (status) {
      tasks::Scheduler& scheduler = fw.scheduler();
      hal::SimClock& clock = *board.lockstep_clock();
      const double limit_s = config.duration_s > 0 ? config.duration_s : 600.0;
      while (!fw.mission()->finished() && sim_s < limit_s) {
        status = scheduler.run_lockstep(clock, slice);
        if (!status) break;
        sim_s = hal::to_seconds(clock.now() - scheduler.start_time_ns());
        on_slice(fw, board, sim_s);
      }
    }
    fw.shutdown();
    board.stop();
    if (status) on_end(fw, board, sim_s);
    else error = status.error().c_str();
  }
  std::fclose(quiet);
  return error;
}

}  // namespace sen3bot::sim
