#pragma once
// The collaborative mode (Sen3CoBot) as a row of the task table, on the control thread after
// the people: where the robot stands on the site (its areas), whether it is idle, the tags the
// QR row read and the person who shows them go through the trigger (cobot/trigger.hpp) and the
// mode (cobot/mode.hpp); in collaborative mode follow-me (cobot/follow.hpp) gives the planner
// its goals and the operator's path is recorded (cobot/path_recorder.hpp) for the operation
// recogniser.
//
// Goals: with this row the mission's (or the fleet's) goals are the cooperative goals; this
// row passes them on to the planner, holds the robot in wait4col, replaces them with follow-me
// targets while collaborative, and on the way back drives to where the robot waited before
// handing the cooperative goals on again.
//
// Memory: the trail and the path in its arena, at init(); nothing after.
#include <array>
#include <cstdint>
#include <memory_resource>

#include "sen3bot/cobot/follow.hpp"
#include "sen3bot/cobot/mode.hpp"
#include "sen3bot/cobot/path_recorder.hpp"
#include "sen3bot/cobot/trigger.hpp"
#include "sen3bot/msg/messages.hpp"
#include "sen3bot/nav/map.hpp"
#include "sen3bot/nav/people.hpp"
#include "sen3bot/tasks/task.hpp"
#include "sen3bot/tasks/topic.hpp"

namespace sen3bot::firmware {

// One of the site's areas as the robot needs it.
struct CobotArea {
  static constexpr std::size_t kMaxVertices = 16;
  cobot::AreaType type = cobot::AreaType::none;
  std::array<msg::Point2D, kMaxVertices> outline{};
  std::size_t vertices = 0;
};

struct CobotTaskConfig {
  static constexpr std::size_t kMaxAreas = 16;
  cobot::TriggerConfig trigger;
  cobot::ModeConfig mode;
  cobot::FollowConfig follow;
  cobot::PathConfig path;
  std::array<CobotArea, kMaxAreas> areas{};
  std::size_t area_count = 0;
  double reach_m = 2.5;              // people farther from the laser are not the operator
  double front_half_angle_rad = 0.6; // nor people further off the laser's axis
  double in_way_m = 1.0;             // another person this near the operator is in the way
  // So is anything the laser sees there that is neither the operator nor the map (someone the
  // camera has not made a person of yet, half hidden behind the operator): this many returns.
  double operator_body_m = 0.35;     // returns this near the operator's centre are theirs
  double map_margin_m = 0.15;        // returns this near an occupied map cell are the map's
  std::size_t foreign_returns = 3;
  // The operator's distance (the trigger's D_f window) is from the laser to the nearest point
  // of their body in the newest scan.
  double idle_speed_m_s = 0.02;      // slower: standing
  double goal_step_m = 0.25;         // a follow-me goal is sent again when its target moved this far
  double band_height_m = 0.35;       // where the tags are worn, for telling whose they are
  double laser_height_m = 0.3;
  msg::SensorMount laser_mount;
  nav::CameraCalibration camera;
};

struct CobotTopics {
  const tasks::Topic<msg::People>& people;
  const tasks::Topic<msg::PoseEstimate>& pose;
  const tasks::Topic<msg::Odometry>& odometry;
  const tasks::Topic<msg::ScanMessage>& scan;
  const tasks::Topic<msg::TagFrame>& tags;
  const tasks::Topic<msg::NavGoal>& cooperative_goal;  // the mission's or the fleet's
  const tasks::Topic<msg::PathMessage>& path;
  const tasks::Topic<msg::ControllerStatus>& controller;
  tasks::Topic<msg::NavGoal>& goal;  // to the planner
  tasks::Topic<msg::CobotState>& state;
  tasks::Topic<msg::OperatingMode>& light;
  tasks::Topic<msg::WorkerPath>& worker_path;
};

// What a report or test reads after a run (the scheduler stopped).
struct CobotCounters {
  std::uint32_t toggles_on = 0;
  std::uint32_t toggles_off = 0;
  std::uint32_t wait4col_entries = 0;
  std::uint32_t aborts = 0;
  std::uint32_t follow_goals = 0;   // follow-me targets sent to the planner
  std::uint32_t border_holds = 0;   // cycles held at the area's border
  std::uint32_t reassociations = 0; // the operator's track ended and a new one near them was taken
  std::uint32_t laser_in_way = 0;   // cycles something unmapped stood by the would-be operator
};

class CobotTask final : public tasks::Task {
 public:
  // map: the static map (kept by reference), or null to take every return for something.
  CobotTask(const CobotTaskConfig& config, const CobotTopics& topics, const nav::OccupancyMap* map = nullptr)
      : config_(config), topics_(topics), map_(map) {}
  Status init(std::pmr::memory_resource& arena) override;
  void step(const tasks::StepContext& context) override;

  [[nodiscard]] const cobot::CollaborationTrigger& trigger() const noexcept { return trigger_; }
  [[nodiscard]] const cobot::CollaborationMode& mode() const noexcept { return mode_; }
  [[nodiscard]] const cobot::PathRecorder& recorder() const noexcept { return recorder_; }
  [[nodiscard]] const CobotCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] const cobot::FollowCommand& last_follow() const noexcept { return follow_cmd_; }

 private:
  // The area type where the robot stands (type 1 wins an overlap) and the type-2 area's index.
  cobot::AreaType area_at(msg::Point2D p, int& sub_critical) const noexcept;
  // Picks the would-be operator among the people in front of the laser; fills the trigger's
  // person inputs. tags: this cycle's frame or null.
  void look(const msg::People& people, const msg::Pose2D& laser, const msg::TagFrame* tags,
            cobot::TriggerInput& in) noexcept;
  const msg::TrackedPerson* find(const msg::People& people, std::uint32_t id) const noexcept;
  // Returns of the newest scan within in_way_m of the operator that are neither theirs nor the map's.
  [[nodiscard]] std::size_t foreign_returns(const msg::Pose2D& laser, msg::Point2D operator_at) const noexcept;
  [[nodiscard]] bool on_map(double x_m, double y_m) const noexcept;
  void send(const msg::NavGoal& goal, hal::Nanos now_ns) noexcept;
  void follow(const msg::People& people, const msg::Pose2D& robot, hal::Nanos now_ns) noexcept;

  CobotTaskConfig config_;
  CobotTopics topics_;
  const nav::OccupancyMap* map_;
  cobot::CollaborationTrigger trigger_;
  cobot::CollaborationMode mode_;
  cobot::FollowMe follow_;
  cobot::PathRecorder recorder_;
  nav::CameraProjection projection_;
  CobotCounters counters_;
  cobot::FollowCommand follow_cmd_;

  std::uint64_t tags_seq_ = 0;
  std::uint64_t coop_seq_ = 0;
  std::uint64_t scan_seq_ = 0;
  msg::NavGoal coop_goal_;        // the newest cooperative goal
  msg::NavGoal sent_;             // what the planner has now
  bool sent_any_ = false;
  std::uint32_t own_ids_ = 0x40000000;  // this row's goals: apart from the mission's and fleet's
  msg::Point2D post_;             // where the robot waited before collaborating
  bool returning_ = false;        // driving back to post_
  std::uint32_t candidate_ = 0;   // the track showing the tags
  std::uint32_t operator_track_ = 0;
  msg::Point2D operator_at_;
  int area_index_ = -1;           // the type-2 area collaborated in
  tasks::Sample<msg::ScanMessage> scan_sample_;  // this cycle's newest scan
  const msg::ScanMessage* scan_ = nullptr;        // it, when there is one
  msg::WorkerPath path_out_;
  msg::CobotState state_;
};

}  // namespace sen3bot::firmware
