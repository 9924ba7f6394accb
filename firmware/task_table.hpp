#pragma once
// The CPU budget of the robot computer, as one table. Every periodic piece of the firmware is
// a row here: what runs, how often, how long it may take, how urgent it is, and on which
// thread. The scheduler's statistics are reported against these numbers.
#include <array>

#include "sen3bot/tasks/scheduler.hpp"

namespace sen3bot::firmware {

// Threads: "control" runs the real-time control loop tasks, "io" the device links, "sim" the
// simulated robot (only with a `sim` section), "background" whatever may block (logs, files,
// network). A row runs when its task is configured: the devices under `devices`, the
// simulated robot under `sim`; the rest always.
inline constexpr std::array kTaskTable = {
    //                 name         period_us  budget_us  priority  thread
    tasks::TaskSpec{"sim",          5'000,     2'000,     50,       "sim"},
    tasks::TaskSpec{"base",         10'000,    500,       70,       "io"},
    tasks::TaskSpec{"laser",        5'000,     500,       70,       "io"},
    tasks::TaskSpec{"health",       100'000,   500,       60,       "control"},
    tasks::TaskSpec{"telemetry",    100'000,   5'000,     0,        "background"},
};

}  // namespace sen3bot::firmware
