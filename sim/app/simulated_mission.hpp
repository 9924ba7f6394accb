#pragma once
// One whole firmware on a simulated board until its mission ends or the run's limit: what an
// experiment's worker runs per seed (experiment dol, experiment crowd). In lockstep time as fast
// as the CPU allows, or in real time over ptys (the world on its own thread), as
// `run --clock realtime` runs.
#include <chrono>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>

#include "firmware.hpp"
#include "sen3bot/sim/sim_board.hpp"

namespace sen3bot::sim {

struct MissionRunOptions {
  hal::Nanos slice = hal::millis(50);  // on_slice's period (simulated time; wall time in real time)
  // The firmware's people row relays the board's true people instead of sensing them (perfect
  // perception; the configuration must have no detector row).
  bool true_people = false;
  bool realtime = false;
};

// Builds the board and the firmware (its log to /dev/null), starts them, and runs until the
// mission finishes or config.duration_s (600 s when not set) has passed, calling
// on_slice(fw, board, sim_s) after each slice, with the world held still between two of its
// steps (sim_s: the world's time); then shuts both down and calls on_end(fw, board, sim_s).
// Returns "" or why the run could not run (on_end is then not called).
template <class OnSlice, class OnEnd>
std::string run_simulated_mission(firmware::FirmwareConfig config, const SimulationConfig& world,
                                  const MissionRunOptions& options, OnSlice on_slice, OnEnd on_end) {
  config.clock = options.realtime ? firmware::ClockMode::realtime : firmware::ClockMode::lockstep;
  Result<std::unique_ptr<SimBoard>> created = SimBoard::create(world, !options.realtime);
  if (!created) return created.error().c_str();
  SimBoard& board = **created;
  std::FILE* quiet = std::fopen("/dev/null", "w");
  if (quiet == nullptr) return "cannot open /dev/null";
  std::string error;
  {
    firmware::Firmware fw(config, board, quiet);
    if (options.true_people) {
      board.publish_true_people();
      fw.use_people_source(&board.true_people());
    }
    board.referee().watch_estimate(&fw.pose_estimate());
    Status status = board.start();
    if (status) status = fw.init();
    double sim_s = 0;
    const double limit_s = config.duration_s > 0 ? config.duration_s : 600.0;
    tasks::Scheduler& scheduler = fw.scheduler();
    if (status && options.realtime) {
      status = scheduler.start();
      auto next = std::chrono::steady_clock::now();
      while (status && !fw.mission()->finished() && sim_s < limit_s) {
        next += std::chrono::nanoseconds(options.slice);
        std::this_thread::sleep_until(next);
        board.with_world([&](Simulation& s) {
          sim_s = hal::to_seconds(s.truth().stamp_ns);
          on_slice(fw, board, sim_s);
        });
      }
    } else if (status) {
      hal::SimClock& clock = *board.lockstep_clock();
      while (!fw.mission()->finished() && sim_s < limit_s) {
        status = scheduler.run_lockstep(clock, options.slice);
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
