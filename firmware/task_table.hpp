#pragma once
// The CPU budget of the robot computer, as one table. Every periodic piece of the firmware is
// a row here: what runs, how often, how long it may take, how urgent it is, and on which
// thread. The scheduler's statistics are reported against these numbers.
#include <array>

#include "sen3bot/tasks/scheduler.hpp"
#include "sen3bot/tasks/utilization.hpp"

namespace sen3bot::firmware {

// Threads: "control" runs the real-time control loop tasks, "io" the device links, "sim" the
// simulated robot (only with a `sim` section), "background" whatever may block (logs, files,
// network). A row runs when its task is configured: the devices (and the bridge between them
// and navigation) under `devices`, the simulated robot under `sim`, localization, planners,
// safety and the mission under `navigation`; the rest always. Budgets are for the Pi 3.
inline constexpr std::array kTaskTable = {
    //                 name         period_us  budget_us  priority  thread
    tasks::TaskSpec{"sim",          5'000,     2'000,     50,       "sim"},
    tasks::TaskSpec{"base",         10'000,    500,       70,       "io"},
    tasks::TaskSpec{"laser",        5'000,     500,       70,       "io"},
    tasks::TaskSpec{"bridge",       10'000,    200,       75,       "control"},
    tasks::TaskSpec{"safety",       50'000,    1'000,     72,       "control"},
    tasks::TaskSpec{"localization", 50'000,    15'000,    65,       "control"},
    tasks::TaskSpec{"controller",   100'000,   10'000,    62,       "control"},
    tasks::TaskSpec{"planner",      500'000,   30'000,    10,       "background"},
    tasks::TaskSpec{"mission",      100'000,   500,       5,        "background"},
    tasks::TaskSpec{"health",       100'000,   500,       60,       "control"},
    tasks::TaskSpec{"telemetry",    100'000,   5'000,     0,        "background"},
};
static_assert(tasks::threads_fit(kTaskTable), "a thread's budgets claim more than tasks::kMaxThreadUtilization");

}  // namespace sen3bot::firmware
