#include "cobot_task.hpp"

#include <cmath>

#include "sen3bot/cobot/polygon.hpp"
#include "sen3bot/ssc/site_file.hpp"
#include "sen3bot/geometry/point_math.hpp"
#include "task_table.hpp"
#include "wiring.hpp"

namespace sen3bot::firmware {

namespace {

constexpr std::uint32_t kOwnGoalIds = 0x40000000;
// A follow-me target's reached within the controller's tolerance; the operator's track may
// end and start again (they turned, someone crossed): a track this near where they were is them.
constexpr double kReassociateM = 0.8;
constexpr std::int8_t kOccupied = 65;  // the fusion's background threshold (nav::FusionConfig)

bool is_critical(cobot::AreaType t) noexcept {
  return t == cobot::AreaType::critical_1_1 || t == cobot::AreaType::critical_1_2;
}


}  // namespace

Status CobotTask::init(std::pmr::memory_resource& arena) {
  if (Status s = trigger_.init(config_.trigger); !s) return s;
  if (Status s = mode_.init(config_.mode); !s) return s;
  if (Status s = follow_.init(config_.follow, arena); !s) return s;
  if (Status s = recorder_.init(config_.path, arena); !s) return s;
  if (Status s = projection_.set(config_.camera); !s) return s;
  return Status::success();
}

cobot::AreaType CobotTask::area_at(msg::Point2D p, int& sub_critical) const noexcept {
  sub_critical = -1;
  cobot::AreaType critical = cobot::AreaType::none;
  bool not_monitored = false;
  for (std::size_t i = 0; i < config_.area_count; ++i) {
    const CobotArea& a = config_.areas[i];
    if (!cobot::inside_polygon(std::span(a.outline.data(), a.vertices), p)) continue;
    if (is_critical(a.type)) critical = a.type;
    else if (a.type == cobot::AreaType::sub_critical_2 && sub_critical < 0) sub_critical = static_cast<int>(i);
    else if (a.type == cobot::AreaType::not_monitored_3) not_monitored = true;
  }
  if (critical != cobot::AreaType::none) {
    sub_critical = -1;
    return critical;
  }
  if (sub_critical >= 0) return cobot::AreaType::sub_critical_2;
  return not_monitored ? cobot::AreaType::not_monitored_3 : cobot::AreaType::none;
}

const msg::TrackedPerson* CobotTask::find(const msg::People& people, std::uint32_t id) const noexcept {
  for (std::size_t i = 0; i < people.count && i < msg::People::kMax; ++i)
    if (people.items[i].id == id) return &people.items[i];
  return nullptr;
}

void CobotTask::look(const msg::People& people, const msg::Pose2D& laser, const msg::TagFrame* tags,
                     cobot::TriggerInput& in) noexcept {
  const double c = std::cos(laser.theta_rad), s = std::sin(laser.theta_rad);
  struct Front {
    const msg::TrackedPerson* person;
    double forward, left, range;
  };
  std::array<Front, msg::People::kMax> front{};
  std::size_t n = 0;
  for (std::size_t i = 0; i < people.count && i < msg::People::kMax; ++i) {
    const msg::TrackedPerson& p = people.items[i];
    if (p.hidden) continue;  // out of the sensors' view: no one to ask for the robot
    const double dx = p.x_m - laser.x_m, dy = p.y_m - laser.y_m;
    const double forward = c * dx + s * dy, left = -s * dx + c * dy;
    const double range = std::hypot(forward, left);
    if (forward < 0.1 || range > config_.reach_m || std::fabs(std::atan2(left, forward)) > config_.front_half_angle_rad)
      continue;
    front[n++] = {&p, forward, left, range};
  }
  const Front* chosen = nullptr;
  if (tags != nullptr && tags->count > 0) {
    // Whose tags: the person whose leg band projects nearest the tags in the image.
    double best = 1e18;
    for (std::size_t k = 0; k < n; ++k) {
      double u = 0, v = 0;
      if (!projection_.project_point(front[k].forward, front[k].left, config_.band_height_m - config_.laser_height_m, u, v))
        continue;
      const double reach_px = projection_.focal_x_px() * (front[k].person->width_m + 0.2) / front[k].forward;
      for (std::size_t t = 0; t < tags->count && t < msg::TagFrame::kMax; ++t) {
        const double du = std::fabs(u - tags->tags[t].u_px);
        if (du < reach_px && du < best) {
          best = du;
          chosen = &front[k];
        }
      }
    }
  }
  if (chosen == nullptr)
    for (std::size_t k = 0; k < n; ++k)
      if (front[k].person->id == candidate_) chosen = &front[k];
  if (chosen == nullptr)
    for (std::size_t k = 0; k < n; ++k)
      if (chosen == nullptr || front[k].range < chosen->range) chosen = &front[k];
  in.operator_present = chosen != nullptr;
  in.operator_distance_m = 0.0;
  in.operator_speed_m_s = chosen != nullptr ? std::hypot(chosen->person->vx_m_s, chosen->person->vy_m_s) : 0.0;
  if (chosen != nullptr) {
    // To the nearest point of their body in this scan: the track's centre lags a walker and
    // is an estimate behind the legs the laser sees.
    msg::Point2D body;
    if (scan_ != nullptr &&
        recorder_.nearest_return(scan_->view(), laser, {chosen->person->x_m, chosen->person->y_m}, chosen->person->width_m, body))
      in.operator_distance_m = std::hypot(body.x_m - laser.x_m, body.y_m - laser.y_m);
    else
      in.operator_distance_m = std::max(0.0, chosen->range - chosen->person->width_m / 2);
  }
  in.others_in_way = 0;
  candidate_ = chosen != nullptr ? chosen->person->id : 0;
  if (chosen == nullptr) return;
  const msg::Point2D at{chosen->person->x_m, chosen->person->y_m};
  for (std::size_t k = 0; k < n; ++k) {
    if (&front[k] == chosen) continue;
    const msg::Point2D other{front[k].person->x_m, front[k].person->y_m};
    if (front[k].range < chosen->range || geometry::distance(other, at) < config_.in_way_m) ++in.others_in_way;
  }
  if (in.others_in_way == 0 && foreign_returns(laser, at) >= config_.foreign_returns) {
    ++in.others_in_way;
    ++counters_.laser_in_way;
  }
}

bool CobotTask::on_map(double x_m, double y_m) const noexcept {
  if (map_ == nullptr) return false;
  int col = 0, row = 0;
  if (!map_->world_to_cell(x_m, y_m, col, row)) return true;  // off the map: a wall's far side
  const int reach = static_cast<int>(std::ceil(config_.map_margin_m / map_->resolution_m()));
  for (int dr = -reach; dr <= reach; ++dr)
    for (int dc = -reach; dc <= reach; ++dc) {
      const int c = col + dc, r = row + dr;
      if (dr * dr + dc * dc <= reach * reach && c >= 0 && r >= 0 && c < map_->width() && r < map_->height() &&
          map_->at(c, r) >= kOccupied)
        return true;
    }
  return false;
}

std::size_t CobotTask::foreign_returns(const msg::Pose2D& laser, msg::Point2D operator_at) const noexcept {
  if (scan_ == nullptr) return 0;
  const msg::ScanView scan = scan_->view();
  std::size_t count = 0;
  for (std::size_t i = 0; i < scan.ranges_m.size(); ++i) {
    const float r = scan.ranges_m[i];
    if (!(r > scan.range_min_m && r < scan.range_max_m)) continue;
    const double a = laser.theta_rad + scan.angle_min_rad + static_cast<double>(i) * scan.increment_rad;
    const msg::Point2D p{laser.x_m + r * std::cos(a), laser.y_m + r * std::sin(a)};
    const double d = geometry::distance(p, operator_at);
    if (d <= config_.operator_body_m || d > config_.in_way_m || on_map(p.x_m, p.y_m)) continue;
    ++count;
  }
  return count;
}

void CobotTask::send(const msg::NavGoal& goal, hal::Nanos now_ns) noexcept {
  sent_ = goal;
  sent_any_ = true;
  topics_.goal.publish(goal, now_ns);
}

void CobotTask::follow(const msg::People& people, const msg::Pose2D& robot, hal::Nanos now_ns) noexcept {
  // A hidden track is a guess of where the operator went: not followed, and not seen.
  const msg::TrackedPerson* p = find(people, operator_track_);
  if (p != nullptr && p->hidden) p = nullptr;
  if (p == nullptr) {
    const msg::TrackedPerson* nearest = nullptr;
    for (std::size_t i = 0; i < people.count && i < msg::People::kMax; ++i) {
      const msg::TrackedPerson& q = people.items[i];
      if (!q.hidden && geometry::distance({q.x_m, q.y_m}, operator_at_) < kReassociateM &&
          (nearest == nullptr || geometry::distance({q.x_m, q.y_m}, operator_at_) < geometry::distance({nearest->x_m, nearest->y_m}, operator_at_)))
        nearest = &q;
    }
    if (nearest != nullptr) {
      operator_track_ = nearest->id;
      ++counters_.reassociations;
      p = nearest;
    }
  }
  if (p != nullptr) operator_at_ = {p->x_m, p->y_m};
  cobot::FollowInput in;
  in.now_ns = now_ns;
  in.operator_seen = p != nullptr;
  in.operator_at = operator_at_;
  in.operator_vx_m_s = p != nullptr ? p->vx_m_s : 0.0;
  in.operator_vy_m_s = p != nullptr ? p->vy_m_s : 0.0;
  in.robot = robot;
  if (area_index_ >= 0) {
    const CobotArea& a = config_.areas[static_cast<std::size_t>(area_index_)];
    in.area = std::span(a.outline.data(), a.vertices);
  }
  follow_cmd_ = follow_.update(in);
  if (follow_cmd_.reason == cobot::FollowHold::area_border) ++counters_.border_holds;
  if (follow_cmd_.go) {
    const bool own_active = sent_any_ && sent_.active && sent_.id >= kOwnGoalIds;
    if (!own_active || geometry::distance({sent_.x_m, sent_.y_m}, follow_cmd_.target) > config_.goal_step_m) {
      send({follow_cmd_.target.x_m, follow_cmd_.target.y_m, ++own_ids_, true, true}, now_ns);
      ++counters_.follow_goals;
    }
  } else if (sent_any_ && sent_.active) {
    send({robot.x_m, robot.y_m, ++own_ids_, false}, now_ns);
  }

  // The worker's path, from each new scan.
  if (p == nullptr || scan_ == nullptr || scan_sample_.sequence == scan_seq_) return;
  scan_seq_ = scan_sample_.sequence;
  const msg::Pose2D laser = msg::compose(robot, config_.laser_mount);
  if (recorder_.add_scan(scan_->view(), laser, operator_at_, p->width_m)) {
    recorder_.fill(path_out_);
    topics_.worker_path.publish(path_out_, now_ns);
  }
}

void CobotTask::step(const tasks::StepContext& context) {
  const hal::Nanos now = context.start_ns;
  tasks::Sample<msg::PoseEstimate> pose;
  if (!topics_.pose.read(pose) || !pose.value.valid) return;
  const msg::Pose2D robot = pose.value.pose;
  const msg::Pose2D laser = msg::compose(robot, config_.laser_mount);

  tasks::Sample<msg::NavGoal> coop;
  const bool new_coop = topics_.cooperative_goal.read(coop) && coop.sequence != coop_seq_;
  if (new_coop) {
    coop_seq_ = coop.sequence;
    coop_goal_ = coop.value;
  }

  // Idle: standing, with no goal or the goal of the moment reached.
  tasks::Sample<msg::Odometry> odometry;
  const bool standing = topics_.odometry.read(odometry) && std::fabs(odometry.value.v_m_s) < config_.idle_speed_m_s &&
                        std::fabs(odometry.value.w_rad_s) < 5 * config_.idle_speed_m_s;
  tasks::Sample<msg::PathMessage> path;
  tasks::Sample<msg::ControllerStatus> controller;
  const bool reached = topics_.path.read(path) && topics_.controller.read(controller) && sent_any_ &&
                       path.value.goal_id == sent_.id && controller.value.status == msg::DwaStatus::reached &&
                       controller.value.plan_id == path.value.plan_id;
  if (returning_ && reached) {
    returning_ = false;
    if (coop_goal_.active) send(coop_goal_, now);  // the cooperative task goes on
  }
  const msg::NavGoal& current = sent_any_ ? sent_ : coop_goal_;
  const bool idle = standing && !returning_ && (!current.active || reached) && !(new_coop && coop_goal_.active);

  tasks::Sample<msg::People> people;
  if (!topics_.people.read(people)) people.value.count = 0;
  scan_ = topics_.scan.read(scan_sample_) ? &scan_sample_.value : nullptr;
  tasks::Sample<msg::TagFrame> tags;
  const bool new_tags = topics_.tags.read(tags) && tags.sequence != tags_seq_;
  if (new_tags) tags_seq_ = tags.sequence;

  int sub_critical = -1;
  const cobot::AreaType area = area_at({robot.x_m, robot.y_m}, sub_critical);

  cobot::TriggerInput tin;
  tin.now_ns = now;
  tin.frame = new_tags ? &tags.value : nullptr;
  tin.armed = mode_.accepts_requests();
  look(people.value, laser, tin.frame, tin);
  const cobot::TriggerOutput trig = trigger_.update(tin);

  cobot::ModeInput min;
  min.now_ns = now;
  min.area = area;
  min.idle = idle;
  min.trigger_events = std::span(trig.events.data(), trig.events.size());
  const cobot::ModeOutput m = mode_.update(min);
  for (const cobot::ModeEvent& e : m.events) {
    switch (e.kind) {
      case cobot::ModeEventKind::entered_wait4col:
        ++counters_.wait4col_entries;
        post_ = {robot.x_m, robot.y_m};
        break;
      case cobot::ModeEventKind::toggled_on: {
        ++counters_.toggles_on;
        operator_track_ = candidate_;
        const msg::TrackedPerson* p = find(people.value, operator_track_);
        operator_at_ = p != nullptr ? msg::Point2D{p->x_m, p->y_m} : msg::Point2D{laser.x_m, laser.y_m};
        area_index_ = sub_critical;
        follow_.start(now, robot, operator_at_);
        recorder_.reset(operator_track_);
        break;
      }
      case cobot::ModeEventKind::toggled_off: ++counters_.toggles_off; break;
      case cobot::ModeEventKind::aborted: ++counters_.aborts; break;
      default: break;
    }
  }
  if (m.resume) {
    operator_track_ = 0;
    returning_ = true;
    send({post_.x_m, post_.y_m, ++own_ids_, true, true}, now);
  }

  if (m.mode == msg::CobotMode::collaborative) {
    follow(people.value, robot, now);
  } else if (!returning_ && coop_seq_ != 0 &&
             (!sent_any_ || sent_.id != coop_goal_.id || sent_.active != coop_goal_.active)) {
    // Cooperative or waiting: the cooperative goals go to the planner as they come.
    send(coop_goal_, now);
  }

  state_.mode = m.mode;
  state_.operator_id = m.operator_id;
  state_.operator_track = m.mode == msg::CobotMode::collaborative ? operator_track_ : 0;
  state_.toggles = counters_.toggles_on + counters_.toggles_off;
  state_.rejections = trigger_.rejections_total() + mode_.refusals(cobot::ModeRefusal::not_the_operator);
  state_.stamp_ns = now;
  topics_.state.publish(state_, now);
  topics_.light.publish(msg::OperatingMode{m.mode == msg::CobotMode::wait4col}, now);
}

Status make_cobot(Wiring& w) {
  const CobotSection& k = w.config.cobot;
  if (!k.enabled) return w.absent("needs a cobot section");
  if (!w.config.navigation.enabled) return w.absent("needs a navigation section");
  Result<ssc::SiteFile> site = ssc::load_site(k.site_path);
  if (!site) return Error::format(site.error().code(), "%s: cobot.site: %s", w.file(), site.error().c_str());
  CobotTaskConfig task = k.task;
  task.laser_mount = w.shared.laser_mount;
  task.camera = nav::CameraCalibration{};
  task.area_count = 0;
  for (const ssc::Area& a : site->site.areas) {
    if (task.area_count == CobotTaskConfig::kMaxAreas)
      return Error::format(Errc::config, "%s: cobot.site: more than %zu areas", w.file(), CobotTaskConfig::kMaxAreas);
    CobotArea& area = task.areas[task.area_count++];
    switch (a.type) {
      case ssc::AreaType::blind_intersection: area.type = cobot::AreaType::critical_1_1; break;
      case ssc::AreaType::transition: area.type = cobot::AreaType::critical_1_2; break;
      case ssc::AreaType::workstation: area.type = cobot::AreaType::sub_critical_2; break;
      case ssc::AreaType::not_monitored: area.type = cobot::AreaType::not_monitored_3; break;
    }
    if (a.outline.size() > CobotArea::kMaxVertices)
      return Error::format(Errc::config, "%s: cobot.site: an area of more than %zu corners", w.file(),
                           CobotArea::kMaxVertices);
    for (const ssc::Point& p : a.outline) area.outline[area.vertices++] = p;
  }
  w.make<CobotTask>(task,
                    CobotTopics{w.reads(&Topics::people), w.reads(&Topics::pose), w.reads(&Topics::odometry),
                                w.reads(&Topics::scan), w.reads(&Topics::tags), w.reads(&Topics::cooperative_goal),
                                w.reads(&Topics::path), w.reads(&Topics::controller_status), w.writes(&Topics::goal),
                                w.writes(&Topics::cobot_state), w.writes(&Topics::operating_mode),
                                w.writes(&Topics::worker_path)},
                    &w.shared.map);
  return Status::success();
}

}  // namespace sen3bot::firmware
