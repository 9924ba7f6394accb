#include "sen3bot/ssc/allocation.hpp"

#include <algorithm>

namespace sen3bot::ssc {

std::string_view to_string(TaskKind kind) noexcept {
  switch (kind) {
    case TaskKind::monitor: return "monitor";
    case TaskKind::charge: return "charge";
    case TaskKind::home: return "home";
    case TaskKind::amr: return "amr";
  }
  return "?";
}

RobotTasks::Started RobotTasks::start(const Task& task) noexcept {
  Started out;
  if (is(TaskKind::amr)) {
    if (!suspended_.push_back(*current_)) return out;
    out.suspended = current_;
  }
  current_ = task;
  out.ok = true;
  return out;
}

std::optional<Task> RobotTasks::resume() noexcept {
  if (suspended_.empty()) return std::nullopt;
  current_ = suspended_.back();
  suspended_.pop_back();
  return current_;
}

Selection select_robots(std::span<const Candidate> robots, std::span<const Point> area, std::size_t n,
                        const AllocationConfig& config) {
  struct Ranked {
    double distance;
    const Candidate* robot;
  };
  StaticVector<Ranked, kMaxRobots> ranked;
  for (const Candidate& c : robots) {
    if (!c.available || c.priority == kHighest || c.priority > kLowest) continue;
    if (!ranked.push_back({distance_to(area, c.position), &c})) break;
  }
  std::stable_sort(ranked.begin(), ranked.end(), [](const Ranked& a, const Ranked& b) { return a.distance < b.distance; });

  Selection out;
  StaticVector<Ranked, kMaxRobots> chosen;
  for (const Ranked& r : ranked) {
    if (chosen.size() < n) {
      (void)chosen.push_back(r);
      continue;
    }
    if (r.robot->priority != kLowest) continue;
    // Full: a p = 2 robot replaces the farthest p = 1 robot taken so far (Fig. 2.7).
    auto victim = chosen.end();
    for (auto it = chosen.begin(); it != chosen.end(); ++it)
      if (it->robot->priority == 1) victim = it;
    if (victim == chosen.end()) break;  // every one taken is p = 2 already: nothing to gain
    if (r.distance - victim->distance > config.max_swap_extra_distance) continue;
    (void)out.swaps.push_back({r.robot->robot, victim->robot->robot});
    chosen.erase(victim);
    (void)chosen.push_back(r);
  }
  for (const Ranked& r : chosen) (void)out.robots.push_back(r.robot->robot);
  return out;
}

RobotId select_for_task(std::span<const Candidate> robots, Point goal) {
  RobotId best = kNone;
  double best_distance = INFINITY;
  for (const Candidate& c : robots) {
    if (!c.available) continue;
    const double d = distance(c.position, goal);
    if (d < best_distance) {
      best = c.robot;
      best_distance = d;
    }
  }
  return best;
}

StandingAction standing_rule(const RobotTasks& tasks, double battery_percent, const StandingConfig& config) noexcept {
  if (tasks.is(TaskKind::charge)) return battery_percent >= config.charged ? StandingAction::charged : StandingAction::none;
  if (battery_percent < config.low_battery) return StandingAction::charge;
  if (tasks.current()) return StandingAction::none;
  return tasks.suspended().empty() ? StandingAction::go_home : StandingAction::resume;
}

}  // namespace sen3bot::ssc
