#pragma once
// The CPU budget of the robot computer, as one table. Every periodic piece of the firmware is
// a row here: what runs, how often, how long it may take, how urgent it is, and on which
// thread. The scheduler's statistics are reported against these numbers, and the docs and
// tests take theirs from here.
#include <array>
#include <string_view>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/tasks/scheduler.hpp"
#include "sen3bot/tasks/utilization.hpp"

namespace sen3bot::firmware {

class Wiring;
// A row's factory: takes its topics and devices from the Wiring and makes the row's task, or
// says why this configuration runs none (wiring.hpp). Each is defined beside its task.
using RowFactory = Status (*)(Wiring&);
Status make_laser(Wiring&);         // laser_task.cpp
Status make_can_io(Wiring&);        // can_io_task.cpp
Status make_safety(Wiring&);        // nav_rows.cpp: navigation's rows
Status make_base(Wiring&);          // base_task.cpp
Status make_detector(Wiring&);      // detector_task.cpp
Status make_localization(Wiring&);  // nav_rows.cpp
Status make_people(Wiring&);        // nav_rows.cpp
Status make_controller(Wiring&);    // nav_rows.cpp
Status make_cobot(Wiring&);         // cobot_task.cpp
Status make_health(Wiring&);        // firmware.cpp
Status make_planner(Wiring&);       // nav_rows.cpp
Status make_mission(Wiring&);       // mission.cpp
Status make_fleet(Wiring&);         // fleet_task.cpp
Status make_telemetry(Wiring&);     // firmware.cpp
Status make_camera(Wiring&);        // row_module.cpp: the rows in modules
Status make_vision(Wiring&);        // row_module.cpp
Status make_qr(Wiring&);            // row_module.cpp
Status make_recognition(Wiring&);   // row_module.cpp
Status make_view(Wiring&);          // view_task.cpp
Status make_mapping(Wiring&);       // mapping_task.cpp

struct Row {
  tasks::TaskSpec spec;
  RowFactory make;
};

// Threads: "io" runs the reflex path from the laser to the wheels, "control" localization and
// the local planner, "background" whatever may block (planning, logs, files, network),
// "camera" the RTSP client and the decoder (a 720p H.264 frame takes milliseconds to decode,
// and a camera can fall silent: neither may hold up anything else). Within
// a thread, due rows run highest priority first, so each thread's rows are ordered by the data
// flow: on "io" a scan is read, checked by the safety filter and answered by the base in the
// same cycle (the CAN I/O node's e-stop chain too), and a person detector's datagrams are taken in; on "control" localization feeds
// the people's fusion and the controller. A row runs when its task is configured: the
// devices under `devices`, localization, planners, safety and the mission under `navigation`,
// the detector and the people under `navigation.people`, the collaborative mode's under
// `cobot` (qr with a camera, recognition with cobot.recognition), the view under `view`; the rest always. Budgets are for the Pi 3; the camera's allows one
// 15 fps stream decoded at up to 1280 x 720; the controller's a worst DWA cycle among movers
// (docs/navigation.md, benchmarks).
inline constexpr auto kRows = std::to_array<Row>({
    //  name           period_us  budget_us  prio thread        factory
    {{"laser",        5'000,     500,       75,  "io"},        make_laser},
    // Before safety: the e-stop chain read in a cycle stops the base in that cycle.
    {{"can_io",       10'000,    300,       74,  "io"},        make_can_io},
    {{"safety",       10'000,    1'000,     73,  "io"},        make_safety},
    {{"base",         10'000,    500,       72,  "io"},        make_base},
    {{"detector",     20'000,    300,       71,  "io"},        make_detector},
    {{"localization", 50'000,    15'000,    66,  "control"},   make_localization},
    {{"people",       100'000,   2'000,     65,  "control"},   make_people},
    {{"controller",   100'000,   20'000,    64,  "control"},   make_controller},
    // After the people: the collaborative mode reads this cycle's tracks.
    {{"cobot",        100'000,   1'000,     63,  "control"},   make_cobot},
    {{"health",       100'000,   500,       60,  "control"},   make_health},
    {{"planner",      500'000,   30'000,    10,  "background"}, make_planner},
    {{"mission",      100'000,   500,       5,   "background"}, make_mission},
    // Decoding a full order takes ~1 ms on a Pi 3 (benchmarks); the network is the link's thread.
    {{"fleet",        100'000,   5'000,     4,   "background"}, make_fleet},
    {{"telemetry",    100'000,   5'000,     0,   "background"}, make_telemetry},
    {{"camera",       20'000,    12'000,    0,   "camera"},    make_camera},
    // After the camera: its init() reads the camera's frame pool.
    {{"vision",       500'000,   300'000,   0,   "vision"},    make_vision},
    // The collaborative mode's OpenCV work, off the real-time threads: reading the operators'
    // tags near the people within reach, and recognising a worker's operation from their path.
    {{"qr",           200'000,   120'000,   1,   "cobot"},     make_qr},
    {{"recognition",  1'000'000, 50'000,    0,   "cobot"},     make_recognition},
    // The live view (docs/view.md), on the planner's and the mission's thread, whose state it
    // reads; last, so that its init() finds the camera row's frames. A step with the map and the
    // global costmap is its longest.
    {{"view",         50'000,    5'000,     0,   "background"}, make_view},
    // Map building (docs/mapping.md): the wheels' poses every period, five scans a second, on a
    // thread of its own, whose loop searches and graph solves come in bursts as submaps finish.
    // Budget: a scan's matching and its share of the loop searches, about 5 ms on the host,
    // ten times that on a Pi 3.
    {{"mapping",      50'000,    30'000,    0,   "mapping"},   make_mapping},
});

// The rows' timing alone, as the scheduler and the reports take it.
inline constexpr auto kTaskTable = [] {
  std::array<tasks::TaskSpec, kRows.size()> specs{};
  for (std::size_t i = 0; i < kRows.size(); ++i) specs[i] = kRows[i].spec;
  return specs;
}();
static_assert(tasks::threads_fit(kTaskTable), "a thread's budgets claim more than tasks::kMaxThreadUtilization");

constexpr const tasks::TaskSpec& row(std::string_view name) {
  for (const tasks::TaskSpec& spec : kTaskTable)
    if (spec.name == name) return spec;
  throw "no such row";  // a compile error where used in a constant expression
}

// The longest time from a scan being decoded (or a command being published) to the base
// driver writing the velocity it asks for: the safety row's release is at most one safety
// period away, and the base row follows it in the same cycle, or one base period later when
// the two grids are out of phase. The safety filter adds it to the scan's age when it sizes
// its stop zone; tests/sim/latency_test.cpp measures it on the wire.
inline constexpr hal::Nanos kSenseToActBudgetNs =
    hal::micros(row("safety").period_us + row("base").period_us + row("safety").budget_us + row("base").budget_us);

}  // namespace sen3bot::firmware
