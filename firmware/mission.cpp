#include "mission.hpp"

#include <cmath>

#include "task_table.hpp"
#include "wiring.hpp"

namespace sen3bot::firmware {

const char* to_string(MissionState state) noexcept {
  switch (state) {
    case MissionState::waiting: return "waiting";
    case MissionState::driving: return "driving";
    case MissionState::complete: return "complete";
    case MissionState::failed: return "failed";
  }
  return "?";
}

Status MissionTask::init(std::pmr::memory_resource&) {
  if (config_.goal_count == 0 || config_.goal_count > MissionConfig::kMaxGoals)
    return Error::format(Errc::config, "mission: needs 1 to %zu goals, got %zu", MissionConfig::kMaxGoals,
                         config_.goal_count);
  return Status::success();
}

void MissionTask::start_goal(std::size_t index, hal::Nanos now_ns) {
  goal_index_ = index;
  goal_start_ns_ = now_ns;
  first_plan_for_goal_ = 0;
  const msg::Point2D g = config_.goals[index];
  topics_.goal.publish(msg::NavGoal{g.x_m, g.y_m, ++goal_id_, true}, now_ns);
  report_.state = MissionState::driving;
}

void MissionTask::step(const tasks::StepContext& context) {
  const hal::Nanos now = context.start_ns;
  if (start_ns_ < 0) start_ns_ = now;
  if (finished()) return;

  tasks::Sample<msg::PoseEstimate> pose;
  const bool have_pose = topics_.pose.read(pose) && pose.value.valid;
  if (have_pose) {
    if (have_last_pose_ && report_.state == MissionState::driving)
      report_.path_length_m += std::hypot(pose.value.pose.x_m - last_pose_.x_m, pose.value.pose.y_m - last_pose_.y_m);
    last_pose_ = pose.value.pose;
    have_last_pose_ = true;
  }
  tasks::Sample<msg::SafetyOutput> safety;
  if (topics_.safety.read(safety) && safety.sequence != safety_seq_) {
    safety_seq_ = safety.sequence;
    if ((safety.value.reasons & ~msg::kSafetyReverseCapped) != msg::kSafetyNone) ++report_.safety_limited_steps;
    if ((safety.value.reasons & msg::kSafetySeparation) != 0) {
      ++report_.separation_limited_steps;
      if (safety.value.separation_cap_m_s < report_.separation_min_cap_m_s) {
        report_.separation_min_cap_m_s = safety.value.separation_cap_m_s;
        report_.separation_gap_at_min_m = safety.value.separation_gap_m;
      }
    }
  }

  if (report_.state == MissionState::waiting) {
    if (have_pose && now - start_ns_ >= static_cast<hal::Nanos>(config_.start_delay_s * 1e9)) start_goal(0, now);
    return;
  }

  tasks::Sample<msg::PathMessage> path;
  if (topics_.path.read(path) && path.value.goal_id == goal_id_ && path.value.plan_id != last_plan_id_) {
    last_plan_id_ = path.value.plan_id;
    ++report_.plans;
    if (path.value.status != msg::PlanStatus::ok) ++report_.plan_failures;
    if (first_plan_for_goal_ == 0) {
      first_plan_for_goal_ = path.value.plan_id;
      first_plans_[goal_index_] = path.value;
    }
  }
  tasks::Sample<msg::ControllerStatus> controller;
  if (!topics_.controller.read(controller)) return;
  report_.recoveries = controller.value.recoveries.total();
  const bool on_this_goal = first_plan_for_goal_ != 0 && controller.value.plan_id >= first_plan_for_goal_;
  const double elapsed_s = static_cast<double>(now - goal_start_ns_) * 1e-9;
  if (on_this_goal && controller.value.status == msg::DwaStatus::reached) {
    report_.goal_time_s[goal_index_] = elapsed_s;
    ++report_.goals_reached;
    if (goal_index_ + 1 < config_.goal_count) {
      start_goal(goal_index_ + 1, now);
    } else {
      topics_.goal.publish(msg::NavGoal{0, 0, ++goal_id_, false}, now);
      report_.state = MissionState::complete;
      finished_.store(true, std::memory_order_release);
    }
  } else if ((on_this_goal && controller.value.status == msg::DwaStatus::failed) || elapsed_s > config_.goal_timeout_s) {
    topics_.goal.publish(msg::NavGoal{0, 0, ++goal_id_, false}, now);
    report_.state = MissionState::failed;
    finished_.store(true, std::memory_order_release);
  }
}

void MissionTask::print_report(std::FILE* out) const {
  const MissionReport& r = report_;
  std::fprintf(out, "mission %s: %zu of %zu goals reached\n", to_string(r.state), r.goals_reached, config_.goal_count);
  for (std::size_t i = 0; i < config_.goal_count; ++i) {
    const msg::Point2D g = config_.goals[i];
    if (i < r.goals_reached)
      std::fprintf(out, "  goal %zu (%.2f, %.2f) m: reached in %.1f s\n", i + 1, g.x_m, g.y_m, r.goal_time_s[i]);
    else
      std::fprintf(out, "  goal %zu (%.2f, %.2f) m: not reached\n", i + 1, g.x_m, g.y_m);
  }
  std::fprintf(out, "  driven %.2f m, %u plans (%u failed), %u recoveries, %llu safety-limited steps\n",
               r.path_length_m, r.plans, r.plan_failures, r.recoveries,
               static_cast<unsigned long long>(r.safety_limited_steps));
  if (r.separation_limited_steps > 0)
    std::fprintf(out, "  speed and separation: %llu steps slowed, down to %.2f m/s at %.2f m from a cage\n",
                 static_cast<unsigned long long>(r.separation_limited_steps), r.separation_min_cap_m_s,
                 r.separation_gap_at_min_m);
}

Status make_mission(Wiring& w) {
  if (!w.config.navigation.enabled) return w.absent("needs a navigation section");
  if (w.config.has_fleet) return w.absent("the fleet gives the goals: no mission");
  // With the collaborative mode the mission's goals are the cooperative ones: the cobot row
  // passes them on.
  tasks::Topic<msg::NavGoal>& goals =
      w.config.cobot.enabled ? w.writes(&Topics::cooperative_goal) : w.writes(&Topics::goal);
  w.make<MissionTask>(w.config.navigation.mission,
                      MissionTopics{goals, w.reads(&Topics::controller_status), w.reads(&Topics::path),
                                    w.reads(&Topics::pose), w.reads(&Topics::safety_output)});
  return Status::success();
}

}  // namespace sen3bot::firmware
