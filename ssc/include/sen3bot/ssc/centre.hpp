#pragma once
// The Sensors Synergy Centre's decision step (thesis §2.1.1-2.1.2, Fig. 2.6 and 2.7). The host
// feeds it the robots' VDA 5050 states and connection, the AGVs' poses and remaining routes
// (from the AGV coordination centre), the robots' people reports and AMR task requests; each
// step(now) returns what to do: robot orders (send / suspend / resume), advisories for the
// AGVs (CLEAR / SLOW / STOP), and an event log with a reason for every decision.
//
// One step, in order:
//   1. people tracks unseen for the timeout are dropped;
//   2. offline robots leave their coalition (and are replaced below when a robot is free);
//   3. finished AMR work ends; a charged robot waits at home;
//   4. low battery: a p = 0 charge task to the home station (leaving any coalition);
//   5. coalitions: one per area that is the first monitored area on some AGV's remaining
//      route; released when no AGV's route crosses it first any more (passed, rerouted, left);
//   6. sizes (Table 2.1, latched people state) and staffing by Fig. 2.7; extra robots released;
//   7. pending AMR requests go to a free robot;
//   8. idle robots resume suspended work, else go home (p = 2);
//   9. one advisory per AGV whenever its advice changes.
#include <memory>
#include <optional>
#include <span>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/ssc/allocation.hpp"
#include "sen3bot/ssc/coalition.hpp"
#include "sen3bot/ssc/people_map.hpp"
#include "sen3bot/ssc/site.hpp"

namespace sen3bot::ssc {

// --- inputs --------------------------------------------------------------------------------

// What the centre keeps of a robot's VDA 5050 state message.
struct RobotReport {
  RobotId robot = kNone;
  Nanos stamp = 0;
  Pose pose;
  double battery = 100;  // %
  bool charging = false;
  bool driving = false;
  // The task the robot's current (or last) order carries: the host names orders after task
  // ids. finished: every node traversed and every action finished or failed.
  TaskId order_task = 0;
  bool order_finished = false;
};

// An AGV as the AGV coordination centre sees it: pose and the nodes still ahead on its route.
struct AgvReport {
  AgvId agv = kNone;
  Name name;
  Pose pose;
  StaticVector<Point, kMaxRouteNodes> route;  // remaining node positions, in order
};

// Ordinary AMR work the AGV coordination centre asks for when no AGV is free.
struct AmrRequest {
  std::uint32_t request = 0;  // the requester's reference, echoed in the task
  std::uint8_t priority = 1;  // 1 urgent, 2 not
  Pose goal;
};

// --- outputs -------------------------------------------------------------------------------

enum class CommandKind : std::uint8_t {
  send,     // order the robot to task.goal for task
  suspend,  // cancel the robot's order for task; the centre keeps it to resume later
  resume,   // order the robot to task.goal again for a suspended task
};
std::string_view to_string(CommandKind kind) noexcept;

struct RobotCommand {
  CommandKind kind = CommandKind::send;
  RobotId robot = kNone;
  Task task;
  Reason reason;
};

enum class Advice : std::uint8_t { clear, slow, stop };
std::string_view to_string(Advice advice) noexcept;  // "CLEAR", "SLOW", "STOP"

struct Advisory {
  AgvId agv = kNone;
  Advice advice = Advice::clear;
  double speed_factor = 1;  // of the AGV's planned speed
  AreaId area = kNone;      // the area the advice is about (kNone: none)
  std::uint16_t people = 0;
  std::uint16_t dynamic = 0;
  double distance = 0;  // m along the route to the area
  Reason reason;
};

enum class EventType : std::uint8_t {
  allocation,  // a robot joins a coalition
  coalition,   // a coalition starts, changes size, is short of robots
  release,     // a robot leaves a coalition, or a coalition ends
  advisory,    // an AGV's advice changed
  suspension,  // a robot's AMR task was suspended
  resumption,  // ... and resumed
  charge,      // low battery: to the charging station
  home,        // idle: home pose
  swap,        // a nearer p = 1 robot passed over for a farther p = 2 one
  task,        // AMR work requested, assigned, finished
  connection,  // a robot went online or offline
};
std::string_view to_string(EventType type) noexcept;

struct Event {
  EventType type = EventType::task;
  Nanos time = 0;
  StaticVector<RobotId, 4> robots;
  AgvId agv = kNone;
  AreaId area = kNone;
  TaskId task = 0;
  Reason reason;
};

// Room for one step's output with every robot and AGV changing at once (a robot gets at most a
// suspend, an order and their events in a step; an AGV an advisory and coalition events).
inline constexpr std::size_t kMaxCommands = 4 * kMaxRobots;
inline constexpr std::size_t kMaxEvents = 4 * (kMaxRobots + kMaxAgvs);

struct Decisions {
  Nanos time = 0;
  StaticVector<RobotCommand, kMaxCommands> commands;
  StaticVector<Advisory, kMaxAgvs> advisories;
  StaticVector<Event, kMaxEvents> events;
  std::uint32_t dropped = 0;  // commands or events that did not fit (never expected)
};

struct CentreConfig {
  PeopleMapConfig people;
  AllocationConfig allocation;
  StandingConfig standing;
  double slow_distance = 12;     // m along the route: people in an area nearer than this slow the AGV
  double stop_distance = 3;      // m: a dynamic person in an area nearer than this stops it
  double slow_speed_factor = 0.3;
};

class Centre {
 public:
  // The site must validate; robots are the site's (each has a home). Allocated once, here.
  static Result<std::unique_ptr<Centre>> create(const Site& site, const CentreConfig& config = {});

  // --- inputs (each may be called any number of times between steps) ---
  Status update_robot(const RobotReport& report);
  // From the VDA 5050 connection topic. Robots start offline.
  Status set_online(RobotId robot, bool online, Nanos now);
  Status update_agv(const AgvReport& report);
  void remove_agv(AgvId agv);  // it left the plant's coordination (or its order ended)
  void add_people(const PeopleReport& report) { people_.update(report); }
  // Queues ordinary AMR work (priority 1 or 2); it goes to a free robot at the next step.
  Result<TaskId> submit_amr_task(const AmrRequest& request, Nanos now);

  // --- the decision step ---
  // The result stays valid until the next call. now must not go backwards.
  const Decisions& step(Nanos now);

  // --- views ---
  [[nodiscard]] const Site& site() const noexcept { return site_; }
  [[nodiscard]] const PeopleMap& people() const noexcept { return people_; }
  [[nodiscard]] std::span<const Coalition> coalitions() const noexcept { return coalitions_.as_span(); }
  [[nodiscard]] const Coalition* coalition_at(AreaId area) const noexcept;
  [[nodiscard]] const RobotTasks* tasks(RobotId robot) const noexcept;
  [[nodiscard]] std::optional<Advisory> advice(AgvId agv) const noexcept;
  [[nodiscard]] std::size_t pending_requests() const noexcept { return pending_.size(); }

 private:
  struct RobotSlot {
    RobotId id = kNone;
    Name name;
    Pose home;
    AreaId overlooks = kNone;
    bool online = false;
    bool reported = false;
    RobotReport last;
    RobotTasks tasks;
  };
  struct AgvSlot {
    AgvId id = kNone;
    Name name;
    Pose pose;
    StaticVector<Point, kMaxRouteNodes + 1> path;  // pose, then the remaining route
    Crossings crossings;                           // monitored areas on the path, in order
    bool advised = false;
    Advisory last;
  };
  struct Pending {
    TaskId task = 0;
    AmrRequest request;
  };

  Centre(const Site& site, const CentreConfig& config);

  void drop_offline_members();
  void progress_tasks();
  void battery_rule();
  void update_coalitions();
  void staff_coalitions();
  void assign_requests();
  void idle_rule();
  void advise();

  RobotSlot* robot(RobotId id) noexcept;
  AgvSlot* agv(AgvId id) noexcept;
  const char* area_name(AreaId id) const noexcept;
  const char* agv_name(AgvId id) const noexcept;
  Coalition* coalition_of(RobotId robot) noexcept;
  bool usable(const RobotSlot& r) const noexcept;  // online, reported, battery not low
  Pose sentry_pose(const Coalition& c, const RobotSlot& r) const noexcept;

  // Starts task on r, suspending its AMR work (or requeueing it when its stack is full), and
  // orders the robot there unless send is false (a low robot already on its charger).
  void take(RobotSlot& r, const Task& task, const char* why, bool send = true);
  // r leaves a coalition or finished work: it resumes suspended work, else is left idle (the
  // idle rule sends it home after this step's AMR requests had their chance).
  void rest(RobotSlot& r, const char* why);
  void go_home(RobotSlot& r, const char* why);
  void remove_member(Coalition& c, RobotId robot);

  void command(CommandKind kind, const RobotSlot& r, const Task& task, const Reason& reason);
  Event& event(EventType type, AgvId agv = kNone, AreaId area = kNone);
  TaskId next_task_id() noexcept { return next_task_++; }

  Site site_;
  CentreConfig config_;
  PeopleMap people_;
  StaticVector<RobotSlot, kMaxRobots> robots_;
  StaticVector<AgvSlot, kMaxAgvs> agvs_;
  StaticVector<Coalition, kMaxAreas> coalitions_;
  StaticVector<Pending, 32> pending_;
  StaticVector<Event, 2 * kMaxRobots + 32> inbox_;  // events of the input calls (connections, requests), reported at the next step
  Decisions out_;
  Nanos now_ = 0;
  TaskId next_task_ = 1;
  Event scratch_;  // where an event goes when the output is full
};

}  // namespace sen3bot::ssc
