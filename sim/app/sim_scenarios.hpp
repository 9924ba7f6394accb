#pragma once
// The named scenarios of `sen3bot-sim sim` (sim_scenarios.cpp), and a case's result with the
// report.json that gathers a scenario's (sim_report.cpp), for the command (cmd_sim.cpp).
#include <cstddef>
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "firmware.hpp"
#include "sen3bot/nav/sgp.hpp"
#include "sen3bot/nav_figure/case_figure.hpp"
#include "sen3bot/sim/referee.hpp"
#include "sen3bot/sim/simulation.hpp"
#include "sen3bot/tasks/scheduler.hpp"
#include "sen3bot/world/world.hpp"

namespace sen3bot::sim::scenario {


struct Kidnap {
  double time_s = -1.0;  // < 0: none
  msg::Pose2D to;
};

struct Case {
  const char* name;
  const char* description;
  std::vector<world::MoverScript> movers;
  Kidnap kidnap = {};
  // What happens to the CAN safety I/O node (needs sim.io_node and devices.io_node).
  std::vector<SimIoEvent> io_events = {};
};

struct Scenario {
  const char* name;
  const char* description;
  msg::Pose2D start;
  std::vector<msg::Point2D> goals;
  // The safe path, relative to the base configuration's folder: a curve file for the
  // supervisory planner, or a waypoint file; both "" keep the base configuration's.
  const char* safe_curve;
  const char* waypoints;
  std::vector<Case> cases;
  // People on: the simulated detector, the fusion, the cages and the online SGP; the report
  // adds replans_triggered, min_person_distance_m and cage_entries per case.
  bool people = false;
  // The thesis' supervised-planning test ran without a moving-obstacle layer; at 5 scans/s the
  // layer tracks a still box's faces, coming into view one after another, as a slow mover for
  // a few seconds and the robot waits behind it (docs/navigation.md).
  bool without_movers_layer = false;
};

// Every named scenario, in the order --list shows them.
std::vector<Scenario> all();

// The referee's person position errors, 1-6 m from the robot.
struct PersonErrors {
  std::size_t samples = 0;
  double median_m = 0;
  double p95_m = 0;
  std::uint64_t false_people = 0;
};

PersonErrors summarize(std::span<const float> errors, std::uint64_t false_people);

struct CaseResult {
  std::string name;
  std::string title;  // the figure's: "case 2/3: NAME"
  std::string description;
  firmware::MissionReport report;
  RefereeReport truth;
  std::vector<TimedPose> contacts;  // where and when each began
  double sim_time_s = 0;
  double wall_time_s = 0;
  msg::Pose2D final_pose;  // the estimate when the case ended
  bool kidnapped = false;
  std::vector<tasks::TaskStats> stats;
  // The safe path: the supervisory planner's (its runs and last result) or a file's.
  bool sgp = false;
  std::uint32_t sgp_runs = 0;
  nav::SgpResult sgp_result;
  double sgp_time_ms = 0;
  std::size_t safe_path_points = 0;
  // With people on.
  bool people = false;
  std::uint64_t replans_triggered = 0;
  std::uint64_t cage_entries = 0;            // the robot moved into a person's cage
  std::uint64_t cage_entries_by_person = 0;  // a person walked up to the robot
  std::uint64_t boxes_located = 0;
  PersonErrors person_errors;
  std::vector<figure::CageMark> cages;
  std::vector<msg::Point2D> planned;    // the last goal's safe path, before any re-plan
  std::vector<msg::Point2D> replanned;  // the last online re-plan's safe path
  // With safety I/O events (lockstep): the first event's effect on the true robot.
  bool safety_io = false;
  std::uint64_t io_trips = 0;
  double io_speed_at_event_m_s = 0;
  double io_stop_s = -1;  // from the first event to the robot standing (-1: it never stood)
  double io_stop_distance_m = 0;
  double io_held_s = 0;   // time the safety I/O held the robot (its stop reasons on)
};

// The mission's time: its reached goals' times added up.
double mission_time_s(const firmware::MissionReport& r);

// DIR/report.json: the scenario, the seed and each case.
bool write_json(const std::string& path, const Scenario& scenario, std::uint64_t seed, const std::vector<CaseResult>& results);

}  // namespace sen3bot::sim::scenario
