#pragma once
// The fleet scenarios of `sen3bot-sim fleet-sim` (cmd_fleet.cpp): the source's three, the plant's
// AGVs and their orders, the scenario's own checks, the report's pieces and the site figure,
// shared by the lockstep run (cmd_fleet.cpp) and the real-time one (fleet_realtime.cpp).
#include <cstdio>
#include <memory>
#include <string>
#include <string_view>
#include <vector>

#include "config.hpp"
#include "firmware.hpp"
#include "sen3bot/json/json.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/sim/agv.hpp"
#include "sen3bot/sim/sim_board.hpp"
#include "sen3bot/ssc/service.hpp"
#include "sen3bot/world/world.hpp"

namespace sen3bot::sim::fleet {

inline constexpr double kPi = 3.14159265358979323846;
inline constexpr hal::Nanos kSliceNs = hal::millis(10);
inline constexpr double kAgvStepS = 0.05;
inline constexpr double kCentreStepS = 0.05;  // as the centre's program steps
inline constexpr std::int64_t kEpochUnixNs = hal::SimClock::kEpochUnixNs;

struct AgvPlan {
  const char* serial;
  std::vector<msg::Point2D> route;
  double speed_m_s;
  double order_s;  // when the plant's master control sends its order
};

struct FleetScenario {
  const char* name;
  const char* description;
  std::vector<const char*> robots;  // serial numbers of the site's robots that take part
  std::vector<AgvPlan> agvs;
  std::vector<world::MoverScript> people;
  double duration_s;
};

std::vector<FleetScenario> scenarios();

struct RobotRun {
  std::string serial;
  firmware::FirmwareConfig config;
  std::unique_ptr<SimBoard> board;
  std::unique_ptr<firmware::Firmware> fw;
  std::vector<msg::Point2D> trail;
};

struct AgvSample {
  double t_s;
  double x, y, speed;
  Advice advice;
};

struct Snapshot {
  double t_s = -1;
  std::string label;
  std::vector<msg::Pose2D> robots;
  std::vector<msg::Pose2D> agvs;
  std::vector<msg::Point2D> people;
};

struct LatestState {
  bool known = false;
  double t_s = 0;  // when it arrived, scenario time
  double x = 0, y = 0, theta = 0, speed = 0;
};

// The members both fleet reports open with: the scenario, its failures, the closest AGV-person
// distance and the first times (null: never).
struct ReportHead {
  std::string_view scenario;
  bool realtime = false;
  const std::vector<std::string>* failures = nullptr;
  double min_agv_person_m = 0;
  double first_advice_s = -1, own_sensor_s = 0, lead_s = 0, unadvised_sensor_s = -1;
  bool never_in_range = false;
};

bool write_text(const std::string& path, const std::string& text);
// The site at one moment: the map, the areas, the robots' trails and poses, the AGVs with their
// routes, the people; axes in metres, a legend and a title.
bool draw_site(const std::string& path, const std::string& title, const nav::OccupancyMap& map, const ssc::SiteFile& site,
               const std::vector<RobotRun>& robots, const std::vector<AgvPlan>& plans, const Snapshot& shot);
// The plant's master control's order for one AGV: its route as a VDA 5050 order ("" when it
// does not encode).
std::string plant_order_text(const AgvPlan& plan, const ssc::SiteFile& site, std::int64_t unix_ns);
std::string plant_topic(const AgvPlan& plan, const char* leaf);
// The AGV as it would have driven without the centre: its route at its speed from its order.
msg::Pose2D unadvised_pose(const AgvPlan& plan, double t_s);
int fail(std::FILE* err, const std::string& message, int code = 2);
// The scenario's own checks, the same in lockstep and in real time: no AGV within 1 m of a
// person, and what the scenario is about (net-1: the advice beats the AGV's scanner; net-2: both
// robots at the blind intersection; net-3: a robot released and sent on).
std::vector<std::string> scenario_failures(const FleetScenario& scenario, const std::vector<std::string>& events,
                                           double first_advice_s, double own_sensor_s, double unadvised_sensor_s,
                                           double min_agv_person_m);
void write_report_head(json::Writer& w, const ReportHead& h);
// The centre's event lines (JSON objects), one a line.
void write_timeline(json::Writer& w, const std::vector<std::string>& events);
void write_agv_samples(json::Writer& w, const FleetScenario& scenario, const std::vector<std::vector<AgvSample>>& samples);

// --realtime: the same scenario as separate programs (robots, AGVs, the centre) on a Mosquitto
// started here, paced by the wall clock (fleet_realtime.cpp).
int fleet_realtime(const FleetScenario& scenario, const ssc::SiteFile& site, const std::string& site_path,
                   const std::string& config_path, const nav::OccupancyMap& map, const std::string& report_dir,
                   std::FILE* out, std::FILE* err);

}  // namespace sen3bot::sim::fleet
