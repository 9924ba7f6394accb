#pragma once
// A configuration file loaded the way sen3bot-sim loads it: the firmware's part, the `sim`
// section, and the simulated board built from it. For tests of the whole firmware on the
// simulated robot.
#include <gtest/gtest.h>

#include <memory>
#include <string>

#include "config.hpp"
#include "sen3bot/sim/sim_board.hpp"
#include "sen3bot/sim/sim_config.hpp"

namespace sen3bot::testing {

struct SimRig {
  firmware::FirmwareConfig config;
  sim::SimulationConfig world;
  std::unique_ptr<sim::SimBoard> board;

  // Builds (or rebuilds, after a test changed `world`) the board.
  void make_board(bool lockstep = true) {
    Result<std::unique_ptr<sim::SimBoard>> created = sim::SimBoard::create(world, lockstep);
    ASSERT_TRUE(created) << created.error().c_str();
    board = std::move(*created);
  }
  [[nodiscard]] hal::SimClock& clock() { return *board->lockstep_clock(); }
};

inline SimRig load_sim_rig(const std::string& path = SEN3BOT_SOURCE_DIR "/config/sim.yaml") {
  SimRig rig;
  Result<sim::SimulatedRobot> loaded = sim::load_simulated_robot(path);
  EXPECT_TRUE(loaded) << loaded.error().c_str();
  if (!loaded) return rig;
  rig.config = std::move(loaded->firmware);
  rig.world = std::move(loaded->world);
  rig.make_board();
  return rig;
}

}  // namespace sen3bot::testing
