#pragma once
// The `sim` section of a configuration file: the simulated robot's world (ground-truth map,
// start pose, people and boxes, noise, the laser's status byte). The firmware's loader accepts
// the section as the board's and leaves it to this reader.
#include <string>
#include <string_view>

#include "config.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/nav/geometry.hpp"
#include "sen3bot/sim/simulation.hpp"

namespace sen3bot::sim {

inline constexpr std::string_view kSimSection = "sim";

// Fails when the document has no `sim` section, naming the file. `laser_mount` comes from the
// robot section, so the simulated scanner sits where the firmware believes it is.
Result<SimulationConfig> parse_sim_config(std::string_view yaml_text, const std::string& source_name,
                                          const nav::Pose2D& laser_mount);

// A configuration file as the simulator reads it: the firmware's part (the `sim` section left
// to the board) and the simulated robot from that section.
struct SimulatedRobot {
  firmware::FirmwareConfig firmware;
  SimulationConfig world;
};
Result<SimulatedRobot> load_simulated_robot(const std::string& path);

}  // namespace sen3bot::sim
