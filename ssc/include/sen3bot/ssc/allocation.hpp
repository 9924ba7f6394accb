#pragma once
// Robot allocation, thesis §2.1.2 and Fig. 2.7. Every robot task has a priority p in
// {0, 1, 2}, 0 highest: monitoring a 1.1 area and going to charge are p = 0, ordinary AMR work
// is p = 1 or 2 by urgency, idle (going home) is p = 2. To staff a coalition the robots are
// sorted by distance to the area and taken only from p = 1 or 2 work; a p = 1 robot taken is
// replaced by a farther p = 2 robot when there is one. A robot taken from AMR work suspends it
// and resumes it when released.
#include <cmath>
#include <optional>
#include <span>
#include <string_view>

#include "sen3bot/ssc/site.hpp"

namespace sen3bot::ssc {

inline constexpr std::uint8_t kHighest = 0;
inline constexpr std::uint8_t kLowest = 2;

enum class TaskKind : std::uint8_t {
  monitor,  // stand sentry at an area for a coalition
  charge,   // to the home charging station on low battery (p = 0)
  home,     // idle: to the home pose, or waiting there (p = 2)
  amr,      // ordinary AMR work asked for by the AGV coordination centre (p = 1 or 2)
};
std::string_view to_string(TaskKind kind) noexcept;

struct Task {
  TaskId id = 0;
  TaskKind kind = TaskKind::home;
  std::uint8_t priority = kLowest;
  Pose goal;
  AreaId area = kNone;          // monitor: the area watched
  std::uint32_t request = 0;    // amr: the requester's reference
};

// A robot's current task and the AMR tasks it was taken from, most recent on top.
inline constexpr std::size_t kMaxSuspended = 4;
class RobotTasks {
 public:
  [[nodiscard]] const std::optional<Task>& current() const noexcept { return current_; }
  // The priority an allocation compares against: the current task's, p = 2 with no task.
  [[nodiscard]] std::uint8_t priority() const noexcept { return current_ ? current_->priority : kLowest; }
  [[nodiscard]] std::span<const Task> suspended() const noexcept { return suspended_.as_span(); }
  [[nodiscard]] bool is(TaskKind kind) const noexcept { return current_ && current_->kind == kind; }
  // Whether starting a new task would need a free slot on the suspended stack and has none.
  [[nodiscard]] bool stack_full_for_new_task() const noexcept { return is(TaskKind::amr) && suspended_.full(); }

  // Starts task. A current AMR task is suspended (pushed) and returned so the caller can tell
  // the robot; any other current task (home, a finished monitor) is simply replaced. Not ok,
  // and nothing changed, when the stack would overflow: check stack_full_for_new_task.
  struct Started {
    bool ok = false;
    std::optional<Task> suspended;
  };
  Started start(const Task& task) noexcept;
  // Ends the current task; the caller then resumes the top of the stack or sends it home.
  void finish() noexcept { current_.reset(); }
  // Pops the most recently suspended task and makes it current.
  std::optional<Task> resume() noexcept;

 private:
  std::optional<Task> current_;
  StaticVector<Task, kMaxSuspended> suspended_;
};

// What the selection knows of a robot. available = false leaves it out whatever its priority
// (offline, no pose yet, already in a coalition, low battery, suspended stack full).
struct Candidate {
  RobotId robot = kNone;
  Point position;
  std::uint8_t priority = kLowest;  // of its current task
  bool available = true;
};

struct AllocationConfig {
  // A p = 1 robot is given up for a p = 2 robot at most this much farther (m). The thesis
  // sets no bound; a site may cap the detour.
  double max_swap_extra_distance = INFINITY;
};

struct Swap {
  RobotId taken = kNone;        // the farther p = 2 robot
  RobotId passed_over = kNone;  // the nearer p = 1 robot it replaced
};

struct Selection {
  StaticVector<RobotId, kMaxRobots> robots;  // nearest first among those kept
  StaticVector<Swap, kMaxRobots> swaps;
};

// Fig. 2.7: up to n robots for the area, nearest first, never from p = 0 work, preferring
// p = 2 to p = 1. Fewer than n when not enough robots qualify.
[[nodiscard]] Selection select_robots(std::span<const Candidate> robots, std::span<const Point> area, std::size_t n,
                                      const AllocationConfig& config = {});

// For an AMR task: the nearest available robot (kNone if none). The caller marks as available
// the robots whose work the task may take over: idle or going home, or AMR work of a strictly
// lower priority (a larger p) than the new task; never monitoring or charging robots.
[[nodiscard]] RobotId select_for_task(std::span<const Candidate> robots, Point goal);

// The standing rules every step applies to each online robot.
struct StandingConfig {
  double low_battery = 20;  // % : below it, charge at the home station (p = 0)
  double charged = 80;      // % : a charging robot is available again from here
};
enum class StandingAction : std::uint8_t {
  none,
  charge,        // battery low: start a p = 0 charge task
  charged,       // charge task over: the robot waits at home (p = 2)
  resume,        // idle with suspended work: resume it
  go_home,       // idle: p = 2 task to the home pose
};
[[nodiscard]] StandingAction standing_rule(const RobotTasks& tasks, double battery_percent, const StandingConfig& config) noexcept;

}  // namespace sen3bot::ssc
