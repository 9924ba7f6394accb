#pragma once
// The mission: hand the navigation its goals one after another, watch the controller reach
// them, and keep the numbers a run is judged by (time per goal, plans, recoveries, safety stops,
// the estimated path). What really happened is for a referee outside the firmware to judge.
#include <array>
#include <atomic>
#include <cstdint>
#include <cstdio>
#include <limits>

#include "sen3bot/msg/messages.hpp"
#include "sen3bot/tasks/task.hpp"
#include "sen3bot/tasks/topic.hpp"

namespace sen3bot::firmware {

struct MissionConfig {
  static constexpr std::size_t kMaxGoals = 16;
  std::array<msg::Point2D, kMaxGoals> goals{};  // map frame, visited in order
  std::size_t goal_count = 0;
  double start_delay_s = 2.0;     // let the drivers connect and localization settle first
  double goal_timeout_s = 120.0;  // a goal not reached by then fails the mission
};

enum class MissionState : std::uint8_t { waiting, driving, complete, failed };
const char* to_string(MissionState state) noexcept;

struct MissionTopics {
  tasks::Topic<msg::NavGoal>& goal;
  const tasks::Topic<msg::ControllerStatus>& controller;
  const tasks::Topic<msg::PathMessage>& path;
  const tasks::Topic<msg::PoseEstimate>& pose;
  const tasks::Topic<msg::SafetyOutput>& safety;
};

struct MissionReport {
  MissionState state = MissionState::waiting;
  std::size_t goals_reached = 0;
  std::array<double, MissionConfig::kMaxGoals> goal_time_s{};  // from the goal's start
  std::uint32_t plans = 0;
  std::uint32_t plan_failures = 0;
  std::uint64_t safety_limited_steps = 0;  // steps where safety lowered the requested speed
  // Speed and separation: steps it lowered the speed, and the tightest it set (+inf: never).
  std::uint64_t separation_limited_steps = 0;
  double separation_min_cap_m_s = std::numeric_limits<double>::infinity();
  double separation_gap_at_min_m = std::numeric_limits<double>::infinity();
  std::uint32_t recoveries = 0;
  double path_length_m = 0;                // estimated pose, summed while driving
};

class MissionTask final : public tasks::Task {
 public:
  MissionTask(const MissionConfig& config, const MissionTopics& topics) : config_(config), topics_(topics) {}
  Status init(std::pmr::memory_resource&) override;
  void step(const tasks::StepContext& context) override;

  // Readable from any thread: the run ends when the mission is over.
  [[nodiscard]] bool finished() const noexcept { return finished_.load(std::memory_order_acquire); }
  // Call after the scheduler stopped.
  [[nodiscard]] const MissionReport& report() const noexcept { return report_; }
  // The goal being driven to; null before the first and after the last. Same thread, or
  // after the scheduler stopped.
  [[nodiscard]] const msg::Point2D* current_goal() const noexcept {
    return report_.state == MissionState::driving && goal_index_ < config_.goal_count ? &config_.goals[goal_index_] : nullptr;
  }
  void print_report(std::FILE* out) const;

  // The first plan made for each goal: what a report draws.
  [[nodiscard]] const msg::PathMessage& first_plan(std::size_t goal) const noexcept { return first_plans_[goal]; }

 private:
  void start_goal(std::size_t index, hal::Nanos now_ns);

  MissionConfig config_;
  MissionTopics topics_;
  MissionReport report_;
  std::atomic<bool> finished_{false};
  std::size_t goal_index_ = 0;
  std::uint32_t goal_id_ = 0;
  hal::Nanos start_ns_ = -1;
  hal::Nanos goal_start_ns_ = 0;
  std::uint32_t last_plan_id_ = 0;
  bool have_last_pose_ = false;
  msg::Pose2D last_pose_;
  std::uint32_t first_plan_for_goal_ = 0;
  std::array<msg::PathMessage, MissionConfig::kMaxGoals> first_plans_{};
  std::uint64_t safety_seq_ = 0;
};

}  // namespace sen3bot::firmware
