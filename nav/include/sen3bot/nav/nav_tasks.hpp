#pragma once
// The navigation pieces as periodic tasks. Each takes a plain config struct and its topics in
// the constructor, sizes everything in init() from its arena, and never allocates in step().
//
// Data flow (topics in brackets):
//   laser driver [ScanMessage] ---+--> LocalizationTask --[PoseEstimate]--+
//   base driver  [Odometry]   ----+                                       |
//   mission      [NavGoal] ------> PlannerTask (global costmap + A*) <----+--[PathMessage]
//   PathMessage + PoseEstimate + Odometry + ScanMessage --> ControllerTask (local costmap with
//        the dynamic obstacle layer + DWA, or a fresh FormationCommand from the fleet)
//        --[VelocityCommand requested, MovingObstacles]-->
//        SafetyTask (+ ScanMessage, Odometry, BaseFlags, PoseEstimate, Sonar) --[VelocityCommand]-->
//        base driver
//
// The OccupancyMap given to LocalizationTask, PlannerTask and ControllerTask must outlive them.
#include <array>
#include <atomic>
#include <cstdint>
#include <span>

#include "sen3bot/msg/messages.hpp"
#include "sen3bot/nav/costmap.hpp"
#include "sen3bot/nav/crossings.hpp"
#include "sen3bot/nav/dynamic_obstacles.hpp"
#include "sen3bot/nav/global_planner.hpp"
#include "sen3bot/nav/local_planner.hpp"
#include "sen3bot/nav/localization.hpp"
#include "sen3bot/nav/odometry_history.hpp"
#include "sen3bot/nav/osgp.hpp"
#include "sen3bot/nav/people.hpp"
#include "sen3bot/nav/projected_scan.hpp"
#include "sen3bot/nav/safety.hpp"
#include "sen3bot/nav/sgp.hpp"
#include "sen3bot/tasks/task.hpp"
#include "sen3bot/tasks/topic.hpp"

namespace sen3bot::nav {

using msg::BaseFlags;
using msg::ControllerStatus;
using msg::NavGoal;
using msg::PathMessage;

// --- Localization ----------------------------------------------------------------------------

struct LocalizationTaskConfig {
  MclConfig mcl;
};

struct LocalizationTopics {
  const tasks::Topic<ScanMessage>& scan;
  const tasks::Topic<Odometry>& odometry;
  tasks::Topic<PoseEstimate>& pose;  // out
};

class LocalizationTask final : public tasks::Task {
 public:
  LocalizationTask(const LocalizationTaskConfig& config, const OccupancyMap& map, const LocalizationTopics& topics) noexcept
      : config_(config), map_(map), scan_(topics.scan), odom_(topics.odometry), estimate_(topics.pose) {}
  Status init(std::pmr::memory_resource& arena) override;
  void step(const tasks::StepContext& context) override;
  // Thread-safe: the next step spreads the particles over the whole map.
  void request_global_initialization() noexcept { global_request_.store(true, std::memory_order_relaxed); }
  [[nodiscard]] const MonteCarloLocalization& filter() const noexcept { return mcl_; }

 private:
  LocalizationTaskConfig config_;
  const OccupancyMap& map_;
  const tasks::Topic<ScanMessage>& scan_;
  const tasks::Topic<Odometry>& odom_;
  tasks::Topic<PoseEstimate>& estimate_;
  MonteCarloLocalization mcl_;
  std::atomic<bool> global_request_{false};
  std::uint64_t scan_seq_ = 0;
  tasks::Sample<ScanMessage> scan_sample_;
  ProjectedScan projected_;       // the newest scan, projected with config_.mcl.laser_mount
  OdometryHistory history_;       // to take each scan at the pose it was measured from
  Pose2D scan_pose_;              // the filter pose at the newest scan (published)
  hal::Nanos scan_stamp_ns_ = 0;
};

// --- Global planner ---------------------------------------------------------------------------

struct PlannerTaskConfig {
  GlobalPlannerConfig planner;
  StaticLayerConfig static_layer;
  ObstacleLayerConfig obstacle;
  InflationLayerConfig inflation;
  bool use_scan = true;          // mark laser obstacles in the global costmap (thesis case 2)
  double replan_period_s = 1.0;  // 0: plan only when the goal changes
  double waypoint_pass_m = 0.5;  // waypoints behind the nearest one within this are dropped
  // Plans keep the robot's centre at least this far from obstacles (0: planner.blocked_cost
  // as given). It becomes planner.blocked_cost through the inflation curve, so no plan leads
  // through a gap the local planner's padded footprint (half-width 0.19 + 0.05 m) cannot pass.
  double plan_clearance_m = 0.28;
  // Hysteresis: a periodic re-plan replaces the plan being followed only when that plan is
  // blocked now, the robot is farther than keep_off_plan_m from it, or the new plan costs less
  // than keep_cost_ratio times what is left of it. A new goal always gets a new plan.
  double keep_cost_ratio = 0.85;
  double keep_off_plan_m = 0.6;
  SensorMount laser_mount;
  // The supervisory planner: with it, each new goal's waypoints are its path from the robot's
  // position to where the curve passes closest to the goal (the given waypoints are not used).
  // The map's ellipses are fitted once, at init(), and the curve checked against them there.
  bool use_sgp = false;
  SgpConfig sgp;
  SafeCurve curve;
  CurveBounds curve_bounds;
  MapEllipsesConfig ellipses;  // max_map_cells and max_map_rows become the map's
  // The people's cages (people.hpp), with a People topic to read them from.
  bool use_people = false;
  PeopleLayerConfig people_layer;
  // Online SGP (osgp.hpp): with the SGP and people, a person near while the robot is off the
  // safe path re-runs the SGP from the robot's position.
  bool use_osgp = true;
  OsgpConfig osgp;
};

struct PlannerTopics {
  const tasks::Topic<NavGoal>& goal;
  const tasks::Topic<PoseEstimate>& pose;
  const tasks::Topic<ScanMessage>& scan;
  tasks::Topic<PathMessage>& path;  // out
  const tasks::Topic<msg::People>* people = nullptr;  // with PlannerTaskConfig::use_people
};

class PlannerTask final : public tasks::Task {
 public:
  PlannerTask(const PlannerTaskConfig& config, const OccupancyMap& map, std::span<const Point2D> waypoints,
              const PlannerTopics& topics) noexcept
      : config_(config), map_(map), waypoints_in_(waypoints), goal_(topics.goal), pose_(topics.pose), scan_(topics.scan),
        path_(topics.path), people_(topics.people), static_layer_(map, config.static_layer), obstacle_layer_(config.obstacle),
        people_layer_(people_copy_, config.people_layer), inflation_layer_(config.inflation) {}
  Status init(std::pmr::memory_resource& arena) override;
  void step(const tasks::StepContext& context) override;
  [[nodiscard]] const Costmap2D& costmap() const noexcept { return costmap_.costmap(); }
  [[nodiscard]] std::uint32_t plans() const noexcept { return plan_id_; }
  // Periodic re-plans that kept the current plan (hysteresis).
  [[nodiscard]] std::uint32_t plans_kept() const noexcept { return kept_; }
  // The waypoints the global planner follows: the file's, or the supervisory planner's for the
  // newest goal. Read them when the task is not running.
  [[nodiscard]] std::span<const Point2D> safe_path() const noexcept { return waypoints_.first(waypoint_count_); }
  // The supervisory planner (null without use_sgp), its runs and its last result.
  [[nodiscard]] const SupervisoryPlanner* sgp() const noexcept { return config_.use_sgp ? &sgp_ : nullptr; }
  [[nodiscard]] std::uint32_t sgp_runs() const noexcept { return sgp_runs_; }
  [[nodiscard]] const SgpResult& sgp_result() const noexcept { return sgp_result_; }
  [[nodiscard]] double sgp_time_ms() const noexcept { return sgp_time_ms_; }
  // The online SGP's trigger and its counts (null without the SGP and people).
  [[nodiscard]] const OsgpTrigger* osgp() const noexcept {
    return config_.use_sgp && config_.use_osgp && people_ != nullptr ? &osgp_ : nullptr;
  }

 private:
  void plan(const NavGoal& goal, const Pose2D& pose, hal::Nanos now_ns, bool new_goal) noexcept;
  // The supervisory planner's waypoints from pose to the goal, into waypoints_.
  void plan_safe_path(const NavGoal& goal, const Pose2D& pose) noexcept;
  // What following the published plan from the robot's position still costs on the current
  // costmap (planner units); infinity when it is blocked, or the robot is off it.
  [[nodiscard]] double remaining_cost(const Pose2D& pose) noexcept;

  PlannerTaskConfig config_;
  const OccupancyMap& map_;
  std::span<const Point2D> waypoints_in_;
  const tasks::Topic<NavGoal>& goal_;
  const tasks::Topic<PoseEstimate>& pose_;
  const tasks::Topic<ScanMessage>& scan_;
  tasks::Topic<PathMessage>& path_;
  const tasks::Topic<msg::People>* people_;
  msg::People people_copy_;  // the layer paints from this, copied before each update
  StaticLayer static_layer_;
  ObstacleLayer obstacle_layer_;
  PeopleLayer people_layer_;
  InflationLayer inflation_layer_;
  LayeredCostmap costmap_;
  GlobalPlanner planner_;
  MapEllipses ellipses_;
  SupervisoryPlanner sgp_;
  SgpResult sgp_result_;
  OsgpTrigger osgp_{config_.osgp};
  std::uint32_t sgp_runs_ = 0;
  double sgp_time_ms_ = 0.0;
  std::span<Point2D> waypoints_;
  std::size_t waypoint_count_ = 0;
  std::span<Point2D> open_waypoints_;  // the ones to plan through: not under a cage or obstacle
  std::span<GridCell> cells_;
  std::span<GridCell> kept_cells_;  // the published plan as a cell path, for remaining_cost()
  bool have_plan_ = false;          // message_ holds a usable plan for the active goal
  std::uint32_t kept_ = 0;
  std::size_t next_waypoint_ = 0;
  std::uint32_t plan_id_ = 0;
  std::uint32_t goal_id_ = 0;
  bool goal_active_ = false;
  hal::Nanos last_plan_ns_ = 0;
  std::uint64_t scan_seq_ = 0;
  tasks::Sample<ScanMessage> scan_sample_;
  ProjectedScan projected_;
  PathMessage message_;
};

// --- Local planner (controller) ---------------------------------------------------------------

struct ControllerTaskConfig {
  CostmapConfig local_costmap{.rolling = true, .width_m = 6.0, .height_m = 6.0, .resolution_m = 0.05};
  StaticLayerConfig static_layer;
  ObstacleLayerConfig obstacle;
  DynamicObstacleConfig dynamic_obstacles;
  InflationLayerConfig inflation;
  DwaConfig dwa;
  SensorMount laser_mount;
  double pose_timeout_s = 1.0;  // no fresh pose estimate: command zero
  bool use_people = false;      // the people's cages, from a People topic
  PeopleLayerConfig people_layer;
  // Walkers' crossings of the path planned in time, and their lanes (crossings.hpp): from the
  // movers and the people, when either is tracked.
  CrossingConfig crossings;
  LaneConfig lanes;
  MakeWayConfig make_way;  // moving out of a walker's way when the robot would stand in it
  double mover_keep_out_m = 0.0;  // added to a mover's radius (the cages' safety radius)
};

struct ControllerTopics {
  const tasks::Topic<PoseEstimate>& pose;
  const tasks::Topic<Odometry>& odometry;
  const tasks::Topic<ScanMessage>& scan;
  const tasks::Topic<PathMessage>& path;
  tasks::Topic<VelocityCommand>& request;            // out: what it asks the safety filter for
  tasks::Topic<ControllerStatus>& status;            // out
  tasks::Topic<msg::MovingObstacles>& movers;        // out: the dynamic obstacle layer's tracks
  const tasks::Topic<msg::People>* people = nullptr;
  const tasks::Topic<msg::FormationCommand>* formation = nullptr;  // a fleet's formation commands
  // The base's sonar ring, which clears the obstacle layer's marks behind the laser
  // (ObstacleLayerConfig::sonar_clearing).
  const tasks::Topic<msg::Sonar>* sonar = nullptr;
};

class ControllerTask final : public tasks::Task {
 public:
  ControllerTask(const ControllerTaskConfig& config, const OccupancyMap& map, const ControllerTopics& topics) noexcept
      : config_(config), map_(map), pose_(topics.pose), odom_(topics.odometry), scan_(topics.scan), path_(topics.path),
        command_(topics.request), status_(topics.status), movers_(topics.movers), people_(topics.people),
        formation_(topics.formation), sonar_(topics.sonar), static_layer_(map, config.static_layer), obstacle_layer_(config.obstacle),
        dynamic_layer_(config.dynamic_obstacles, &map, &obstacle_layer_), people_layer_(people_copy_, config.people_layer),
        inflation_layer_(config.inflation) {}
  Status init(std::pmr::memory_resource& arena) override;
  void step(const tasks::StepContext& context) override;
  [[nodiscard]] const Costmap2D& costmap() const noexcept { return costmap_.costmap(); }
  [[nodiscard]] const DwaPlanner& planner() const noexcept { return dwa_; }
  [[nodiscard]] const LaneMap& lanes() const noexcept { return lanes_; }
  // Before init: every `every_cycles` cycles the costmap goes out on `topic` (the live view's).
  void publish_costmap(tasks::Topic<msg::CostmapSnapshot>* topic, int every_cycles) noexcept {
    snapshot_topic_ = topic;
    snapshot_every_ = every_cycles < 1 ? 1 : every_cycles;
  }
  // Null when the configuration turns the layer off.
  [[nodiscard]] const DynamicObstacleLayer* dynamic_layer() const noexcept {
    return config_.dynamic_obstacles.enabled ? &dynamic_layer_ : nullptr;
  }

 private:
  // A formation command was read and is within its hold time at now.
  [[nodiscard]] bool formation_fresh(hal::Nanos now) const noexcept;

  ControllerTaskConfig config_;
  const OccupancyMap& map_;
  const tasks::Topic<PoseEstimate>& pose_;
  const tasks::Topic<Odometry>& odom_;
  const tasks::Topic<ScanMessage>& scan_;
  const tasks::Topic<PathMessage>& path_;
  tasks::Topic<VelocityCommand>& command_;
  tasks::Topic<ControllerStatus>& status_;
  tasks::Topic<msg::MovingObstacles>& movers_;
  const tasks::Topic<msg::People>* people_;
  // The centre's formation commands (null: none): while one is fresh it is the request.
  const tasks::Topic<msg::FormationCommand>* formation_;
  tasks::Sample<msg::FormationCommand> formation_sample_;
  msg::People people_copy_;  // the layer paints from this, copied before each update
  const tasks::Topic<msg::Sonar>* sonar_ = nullptr;
  tasks::Sample<msg::Sonar> sonar_sample_;
  StaticLayer static_layer_;
  ObstacleLayer obstacle_layer_;
  DynamicObstacleLayer dynamic_layer_;
  PeopleLayer people_layer_;
  InflationLayer inflation_layer_;
  LayeredCostmap costmap_;
  DwaPlanner dwa_;
  // The crossing gate and making way, on the DWA's command; the tracks they read, built each
  // cycle from the movers and the people.
  [[nodiscard]] bool crossings_on() const noexcept;
  [[nodiscard]] bool walkers_tracked() const noexcept;
  std::size_t collect_tracks(hal::Nanos now) noexcept;
  void gate(const Pose2D& pose, double v_m_s, hal::Nanos now, std::size_t tracks, VelocityCommand& command,
            ControllerStatus& status) noexcept;
  void make_way(const Pose2D& pose, double v_m_s, std::size_t tracks, VelocityCommand& command,
                ControllerStatus& status) noexcept;
  LaneMap lanes_;
  CrossingGate gate_;
  std::array<CrossingTrack, msg::MovingObstacles::kMax + msg::People::kMax> tracks_{};
  std::uint32_t crossing_waits_ = 0;
  std::uint32_t ways_made_ = 0;
  msg::MovingObstacles movers_message_;
  std::uint32_t plan_id_ = 0;
  std::uint64_t scan_seq_ = 0;
  tasks::Sample<ScanMessage> scan_sample_;
  ProjectedScan projected_;
  tasks::Sample<PathMessage> path_sample_;
  tasks::Topic<msg::CostmapSnapshot>* snapshot_topic_ = nullptr;
  int snapshot_every_ = 1;
  int snapshot_count_ = 0;
  msg::CostmapSnapshot snapshot_;
};

// The costmap into a snapshot, coarsened to fit (the view's, and its tests').
void snapshot_costmap(const Costmap2D& costmap, msg::CostmapSnapshot& out) noexcept;

// --- People -----------------------------------------------------------------------------------

struct PeopleTaskConfig {
  FusionConfig fusion;
  PersonTrackerConfig tracker;
  CameraCalibration camera;
  SensorMount laser_mount;
  // A frame waits this long for its scan (a scan arrives after the frame it matches at slow
  // baud rates); then it is fused with the nearest one it has, or counted out of the window.
  double frame_wait_s = 0.5;
  // The operator a collaborative robot follows is a trained person: their cage uses this
  // safety radius instead of the tracker's (< 0: no difference).
  double operator_safety_radius_m = -1.0;
};

// Camera-laser fusion on the bus: each detector frame is fused with the scan nearest it in
// time, placed from the pose the localization gave that scan; the tracks, predicted to the
// cycle, are published as People (the cages' source). Scans and frames wait in fixed rings.
struct PeopleTopics {
  const tasks::Topic<ScanMessage>& scan;
  const tasks::Topic<PoseEstimate>& pose;
  const tasks::Topic<msg::PersonDetections>& detections;
  tasks::Topic<msg::People>& people;  // out
  const tasks::Topic<msg::CobotState>* cobot = nullptr;  // whose operator it is
  // The base's sonar ring: weak evidence about people hidden behind the robot.
  const tasks::Topic<msg::Sonar>* sonar = nullptr;
};

class PeopleTask final : public tasks::Task {
 public:
  PeopleTask(const PeopleTaskConfig& config, const OccupancyMap& map, const PeopleTopics& topics) noexcept
      : config_(config), map_(map), scan_(topics.scan), pose_(topics.pose), detections_(topics.detections),
        people_(topics.people), cobot_(topics.cobot), sonar_(topics.sonar) {}
  Status init(std::pmr::memory_resource& arena) override;
  void step(const tasks::StepContext& context) override;
  [[nodiscard]] const PeopleFusion& fusion() const noexcept { return fusion_; }
  [[nodiscard]] const PersonTracker& tracker() const noexcept { return tracker_; }
  [[nodiscard]] std::uint64_t frames_fused() const noexcept { return frames_fused_; }
  [[nodiscard]] std::uint64_t laser_fixes() const noexcept { return laser_fixes_; }

 private:
  static constexpr std::size_t kScans = 4;
  static constexpr std::size_t kFrames = 4;
  struct PosedScan {
    ScanMessage scan;
    Pose2D pose;  // the robot's, at the scan
    bool posed = false;
    bool followed = false;  // the laser has followed the people out of view through it
  };
  void fuse(const msg::PersonDetections& frame, const PosedScan& scan) noexcept;
  void follow(PosedScan& scan) noexcept;

  PeopleTaskConfig config_;
  const OccupancyMap& map_;
  const tasks::Topic<ScanMessage>& scan_;
  const tasks::Topic<PoseEstimate>& pose_;
  const tasks::Topic<msg::PersonDetections>& detections_;
  tasks::Topic<msg::People>& people_;
  const tasks::Topic<msg::CobotState>* cobot_;
  const tasks::Topic<msg::Sonar>* sonar_ = nullptr;
  tasks::Sample<msg::Sonar> sonar_sample_;
  PeopleFusion fusion_;
  PersonTracker tracker_;
  std::span<PosedScan> scans_;             // ring, newest at scans_[(scan_next_ - 1) % kScans]
  std::size_t scan_next_ = 0;
  std::span<msg::PersonDetections> frames_;  // waiting for their scan, oldest first
  std::size_t frame_count_ = 0;
  tasks::Sample<ScanMessage> scan_sample_;
  tasks::Sample<msg::PersonDetections> frame_sample_;
  std::uint64_t scan_seq_ = 0;
  std::uint64_t frame_seq_ = 0;
  std::array<PersonFix, msg::PersonDetections::kMax> fixes_{};
  msg::People message_;
  std::uint64_t frames_fused_ = 0;
  std::uint64_t laser_fixes_ = 0;
  std::array<Point2D, msg::People::kMax> predicted_{};
  std::array<std::uint8_t, msg::People::kMax> followed_tracks_{};
  std::array<PersonFix, msg::People::kMax> follow_fixes_{};
};

// People known without sensing, in place of the fusion: each period the source's latest list
// is republished with the tracker's cages (half the width, at least min_width_m, plus the
// safety radius). A list older than expire_s is nobody. The source is the simulator's ground
// truth for the crowd benchmark's perfect-perception runs.
class PeopleRelayTask final : public tasks::Task {
 public:
  PeopleRelayTask(const PersonTrackerConfig& tracker, const tasks::Topic<msg::People>& source,
                  tasks::Topic<msg::People>& people) noexcept
      : tracker_(tracker), source_(source), people_(people) {}
  Status init(std::pmr::memory_resource& arena) override;
  void step(const tasks::StepContext& context) override;

 private:
  PersonTrackerConfig tracker_;
  const tasks::Topic<msg::People>& source_;
  tasks::Topic<msg::People>& people_;
  tasks::Sample<msg::People> sample_;
  msg::People message_;
};

// --- Safety -----------------------------------------------------------------------------------

struct SafetyTaskConfig {
  SafetyConfig safety;
  double command_timeout_s = 0.5;  // a requested command older than this counts as zero
  double movers_timeout_s = 0.5;   // tracked movers older than this are not used
  double people_timeout_s = 0.5;   // and tracked people
  bool require_base_flags = true;  // with no BaseFlags ever published, stop
  // The safety I/O (when the task is given its topic): older than this counts as lost.
  double io_timeout_s = 0.1;
  bool io_reset_at_start = false;  // SafetyLatch
};

struct SafetyTopics {
  const tasks::Topic<VelocityCommand>& request;
  const tasks::Topic<ScanMessage>& scan;
  const tasks::Topic<Odometry>& odometry;
  const tasks::Topic<BaseFlags>& base_flags;
  const tasks::Topic<PoseEstimate>& pose;
  const tasks::Topic<msg::MovingObstacles>& movers;
  tasks::Topic<VelocityCommand>& command;  // out: what the base drives
  tasks::Topic<SafetyOutput>& status;      // out
  const tasks::Topic<msg::People>* people = nullptr;
  const tasks::Topic<msg::SafetyIo>* io = nullptr;  // the safety I/O node's e-stop chain
  // The base's sonar ring, for reversing and turning on the spot.
  const tasks::Topic<msg::Sonar>* sonar = nullptr;
};

class SafetyTask final : public tasks::Task {
 public:
  SafetyTask(const SafetyTaskConfig& config, const SafetyTopics& topics) noexcept
      : config_(config), filter_(config.safety), latch_(config.io_reset_at_start), requested_(topics.request),
        scan_(topics.scan), odom_(topics.odometry), base_(topics.base_flags), pose_(topics.pose), movers_(topics.movers),
        people_(topics.people), io_(topics.io), command_(topics.command), status_(topics.status), sonar_(topics.sonar) {}
  Status init(std::pmr::memory_resource& arena) override;
  void step(const tasks::StepContext& context) override;
  [[nodiscard]] std::uint64_t stops() const noexcept { return stops_; }
  // Null without the safety I/O.
  [[nodiscard]] const SafetyLatch* latch() const noexcept { return io_ != nullptr ? &latch_ : nullptr; }

 private:
  SafetyTaskConfig config_;
  SafetyFilter filter_;
  SafetyLatch latch_;
  const tasks::Topic<VelocityCommand>& requested_;
  const tasks::Topic<ScanMessage>& scan_;
  const tasks::Topic<Odometry>& odom_;
  const tasks::Topic<BaseFlags>& base_;
  const tasks::Topic<PoseEstimate>& pose_;
  const tasks::Topic<msg::MovingObstacles>& movers_;
  const tasks::Topic<msg::People>* people_;  // null: no people layer
  const tasks::Topic<msg::SafetyIo>* io_;    // null: no safety I/O
  tasks::Topic<VelocityCommand>& command_;
  tasks::Topic<SafetyOutput>& status_;
  tasks::Sample<ScanMessage> scan_sample_;
  tasks::Sample<msg::MovingObstacles> movers_sample_;
  tasks::Sample<msg::People> people_sample_;
  const tasks::Topic<msg::Sonar>* sonar_ = nullptr;
  tasks::Sample<msg::Sonar> sonar_sample_;
  std::uint64_t scan_seq_ = 0;
  ProjectedScan projected_;  // projected once per scan, checked every step
  std::uint64_t stops_ = 0;  // steps where a non-zero request was cut to zero
};

}  // namespace sen3bot::nav
