#include "report_figure.hpp"

#include <cmath>
#include <cstdio>

#include "sen3bot/nav_figure/sgp_layer.hpp"

namespace sen3bot::sim {

using firmware::MissionReport;
using firmware::MissionState;

namespace {
constexpr double kTraceStepS = 0.1;       // people's tracks: a point per 100 ms
constexpr double kFootprintSpacingM = 1.0;  // the robot drawn about every metre
constexpr double kPersonNearM = 2.5;
}  // namespace

std::string result_line(const MissionReport& r, std::size_t goal_count, const RefereeReport& truth) {
  double time_s = 0;
  for (std::size_t g = 0; g < r.goals_reached; ++g) time_s += r.goal_time_s[g];
  char goals[96];
  if (goal_count == 1 && r.state == MissionState::complete)
    std::snprintf(goals, sizeof goals, "goal reached in %.1f s", time_s);
  else if (goal_count == 1)
    std::snprintf(goals, sizeof goals, "goal not reached (%s)", to_string(r.state));
  else
    std::snprintf(goals, sizeof goals, "%zu of %zu goals reached in %.1f s", r.goals_reached, goal_count, time_s);
  char contacts[64];
  if (truth.contacts == 0)
    std::snprintf(contacts, sizeof contacts, "0 contacts");
  else
    std::snprintf(contacts, sizeof contacts, "%llu contact%s (%llu by the robot)",
                  static_cast<unsigned long long>(truth.contacts), truth.contacts == 1 ? "" : "s",
                  static_cast<unsigned long long>(truth.moving_contacts));
  const unsigned replans = r.plans > 0 ? r.plans - 1 : 0;
  char line[256];
  int n = std::snprintf(line, sizeof line, "%s, %s, %u recover%s, %u replan%s, min clearance %.2f m", goals, contacts,
                        r.recoveries, r.recoveries == 1 ? "y" : "ies", replans, replans == 1 ? "" : "s",
                        truth.min_clearance_m);
  if (truth.relocalization_s >= 0 && n > 0 && static_cast<std::size_t>(n) < sizeof line)
    std::snprintf(line + n, sizeof line - static_cast<std::size_t>(n), ", relocalised in %.1f s", truth.relocalization_s);
  return line;
}

figure::CaseFigure case_figure(std::string title, std::string description, const firmware::FirmwareConfig& config,
                               const firmware::Firmware& fw, SimBoard& board) {
  const firmware::MissionTask& mission = *fw.mission();
  const firmware::MissionConfig& goals = config.navigation.mission;
  const Referee& referee = board.referee();
  const SimulationConfig& sim = board.simulation().config();
  figure::CaseFigure f;
  f.title = std::move(title);
  f.description = std::move(description);
  f.result = result_line(mission.report(), goals.goal_count, referee.report());
  f.passed = mission.report().state == MissionState::complete && referee.report().moving_contacts == 0;
  f.map = &fw.map();
  f.waypoints.assign(fw.safe_path().begin(), fw.safe_path().end());
  if (const nav::SupervisoryPlanner* sgp = fw.planner() ? fw.planner()->sgp() : nullptr)
    figure::add_sgp_layer(f, *sgp, fw.planner()->sgp_result().direction, 0.0);
  for (std::size_t g = 0; g <= mission.report().goals_reached && g < goals.goal_count; ++g) {
    const msg::PathMessage& plan = mission.first_plan(g);
    if (plan.count < 2) continue;
    std::vector<msg::Point2D>& points = f.plans.emplace_back();
    for (std::size_t i = 0; i < plan.count; ++i) points.push_back({plan.points[i].x_m, plan.points[i].y_m});
  }
  f.driven.assign(referee.track().begin(), referee.track().end());
  f.estimated.assign(referee.estimate_track().begin(), referee.estimate_track().end());
  f.footprint = sim.footprint;
  std::vector<figure::RobotAt> poses;
  for (const TimedPose& p : referee.poses()) poses.push_back({p.t_s, p.pose});
  f.robot = figure::robot_instants(poses, kFootprintSpacingM);
  for (const TimedPose& c : referee.contact_poses()) f.contacts.push_back({{c.pose.x_m, c.pose.y_m}, c.t_s, c.moving});
  f.start = sim.start_pose;
  f.goals.assign(goals.goals.begin(), goals.goals.begin() + static_cast<std::ptrdiff_t>(goals.goal_count));

  // The world is a function of time: replay it over the run to see where each mover was.
  world::World& world = board.simulation().world();
  const double t0 = poses.empty() ? 0 : poses.front().t_s, t1 = poses.empty() ? 0 : poses.back().t_s;
  for (std::size_t i = 0; i < sim.movers.size() && i < world.mover_count(); ++i) {
    const world::MoverScript& script = sim.movers[i];
    figure::MoverTrack& m = f.movers.emplace_back();
    m.size_m = script.size_m;
    m.person = script.person;
    m.square = script.shape == world::MoverShape::square;
    m.appear_s = script.appear_time_s;
    for (double t = t0; t <= t1; t += kTraceStepS) {
      world.set_time(t);
      if (world.mover_visible(i)) m.path.push_back(world.mover_position(i));
    }
    if (!m.person) continue;
    // A person is drawn when the robot is, if near enough to matter to it.
    for (const figure::RobotAt& r : f.robot) {
      world.set_time(r.t_s);
      const msg::Point2D p = world.mover_position(i);
      if (world.mover_visible(i) && std::hypot(p.x_m - r.pose.x_m, p.y_m - r.pose.y_m) <= kPersonNearM)
        m.marks.push_back({r.t_s, p});
    }
  }
  world.set_time(t1);
  // The crowd's walkers, moved by their model rather than a script: from the referee's record.
  const std::size_t first_walker = board.simulation().first_crowd_mover();
  for (std::size_t i = first_walker; i < world.mover_count(); ++i) {
    figure::MoverTrack& m = f.movers.emplace_back();
    m.size_m = world.mover_script(i).size_m;
    m.person = true;
    std::size_t next_robot = 0;
    for (const PersonAt& p : referee.person_path()) {
      if (p.mover != i) continue;
      m.path.push_back(p.at);
      for (; next_robot < f.robot.size() && f.robot[next_robot].t_s <= p.t_s + 1e-9; ++next_robot) {
        const msg::Pose2D& r = f.robot[next_robot].pose;
        if (std::abs(f.robot[next_robot].t_s - p.t_s) < 1e-6 && std::hypot(p.at.x_m - r.x_m, p.at.y_m - r.y_m) <= kPersonNearM)
          m.marks.push_back({p.t_s, p.at});
      }
    }
    if (m.path.empty()) f.movers.pop_back();
  }
  return f;
}

}  // namespace sen3bot::sim
