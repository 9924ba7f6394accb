#pragma once
// A finished case of `sen3bot-sim sim` as a report figure: gathers what the firmware, its
// mission and the simulated board kept, and draws it with nav/figure (over lib/figure).
#include <string>

#include "config.hpp"
#include "firmware.hpp"
#include "sen3bot/sim/referee.hpp"
#include "sen3bot/nav_figure/case_figure.hpp"
#include "sen3bot/sim/sim_board.hpp"

namespace sen3bot::sim {

// "goal reached in 15.2 s, 0 contacts, 1 recovery, 2 replans, min clearance 0.14 m"
[[nodiscard]] std::string result_line(const firmware::MissionReport& mission, std::size_t goal_count,
                                      const RefereeReport& truth);

// After the run (the scheduler and the board stopped). Moves the board's world back in time to
// trace the people.
[[nodiscard]] figure::CaseFigure case_figure(std::string title, std::string description,
                                             const firmware::FirmwareConfig& config, const firmware::Firmware& fw,
                                             SimBoard& board);

}  // namespace sen3bot::sim
