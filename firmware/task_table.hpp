#pragma once
// The CPU budget of the robot computer, as one table. Every periodic piece of the firmware is
// a row here: what runs, how often, how long it may take, how urgent it is, and on which
// thread. The scheduler's statistics are reported against these numbers.
#include <array>

#include "sen3bot/tasks/scheduler.hpp"

namespace sen3bot::firmware {

// Threads: "control" runs the real-time control loop tasks, "io" the device links,
// "background" whatever may block (writing logs, files, network).
inline constexpr std::array kTaskTable = {
    //                 name         period_us  budget_us  priority  thread
    tasks::TaskSpec{"health",       100'000,   500,       60,       "control"},
    tasks::TaskSpec{"telemetry",    100'000,   5'000,     0,        "background"},
};

}  // namespace sen3bot::firmware
