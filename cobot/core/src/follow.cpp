#include "sen3bot/cobot/follow.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

#include "sen3bot/cobot/polygon.hpp"
#include "sen3bot/geometry/point_math.hpp"
#include "sen3bot/nav/arena.hpp"

namespace sen3bot::cobot {

const char* to_string(FollowHold hold) noexcept {
  switch (hold) {
    case FollowHold::none: return "none";
    case FollowHold::close_enough: return "close_enough";
    case FollowHold::operator_stopped: return "operator_stopped";
    case FollowHold::operator_lost: return "operator_lost";
    case FollowHold::area_border: return "area_border";
  }
  return "unknown";
}

Status FollowMe::init(const FollowConfig& config, std::pmr::memory_resource& resource) {
  if (config.trail_capacity < 2 || !(config.min_step_m > 0.0) || !(config.distance_m > 0.0) ||
      !(config.stop_speed_m_s >= 0.0) || !(config.stop_after_s > 0.0) || !(config.lost_s > 0.0) ||
      !(config.robot_radius_m >= 0.0) || !(config.on_trail_m >= 0.0) || !(config.arrive_m > 0.0)) {
    return Error::format(Errc::config, "cobot follow: trail_capacity >= 2; min_step_m, distance_m, stop_after_s, "
                                       "lost_s and arrive_m > 0; stop_speed_m_s, robot_radius_m, on_trail_m >= 0");
  }
  config_ = config;
  size_ = head_ = 0;
  return nav::guarded("cobot follow", [&]() -> Status {
    trail_ = nav::allocate_array<msg::Point2D>(resource, config.trail_capacity);
    return Status::success();
  });
}

void FollowMe::start(hal::Nanos now_ns, const msg::Pose2D& robot, msg::Point2D operator_at) noexcept {
  head_ = size_ = 0;
  add({robot.x_m, robot.y_m});
  add(operator_at);
  operator_ = operator_at;
  seen_ns_ = moving_ns_ = now_ns;
}

void FollowMe::add(msg::Point2D p) noexcept {
  if (trail_.empty()) return;
  if (size_ == trail_.size()) {
    head_ = (head_ + 1) % trail_.size();  // the oldest crumb goes
    --size_;
  }
  trail_[(head_ + size_) % trail_.size()] = p;
  ++size_;
}

void FollowMe::point_at(double s_m, msg::Point2D& at, double& heading_rad) const noexcept {
  double walked = 0.0;
  at = vertex(0);
  heading_rad = std::numeric_limits<double>::quiet_NaN();
  for (std::size_t i = 0; i < size_; ++i) {
    const msg::Point2D a = vertex(i);
    const msg::Point2D b = vertex(i + 1);
    const double len = geometry::distance(a, b);
    if (len <= 1e-9) continue;
    heading_rad = std::atan2(b.y_m - a.y_m, b.x_m - a.x_m);
    if (s_m <= walked + len) {
      const double t = std::clamp((s_m - walked) / len, 0.0, 1.0);
      at = {a.x_m + t * (b.x_m - a.x_m), a.y_m + t * (b.y_m - a.y_m)};
      return;
    }
    walked += len;
    at = b;
  }
}

FollowCommand FollowMe::update(const FollowInput& input) noexcept {
  if (input.operator_seen) {
    operator_ = input.operator_at;
    seen_ns_ = input.now_ns;
    if (std::hypot(input.operator_vx_m_s, input.operator_vy_m_s) >= config_.stop_speed_m_s) moving_ns_ = input.now_ns;
    if (size_ == 0 || geometry::distance(trail_point(size_ - 1), operator_) > config_.min_step_m) add(operator_);
  }
  const msg::Point2D robot{input.robot.x_m, input.robot.y_m};

  // The robot's place on the polyline: the nearest point of any segment, as arc length.
  double length = 0.0;
  double robot_s = 0.0;
  double robot_off = std::numeric_limits<double>::infinity();
  for (std::size_t i = 0; i < size_; ++i) {
    const msg::Point2D a = vertex(i);
    const msg::Point2D b = vertex(i + 1);
    const double len = geometry::distance(a, b);
    const double t = len > 1e-9
                         ? std::clamp(((robot.x_m - a.x_m) * (b.x_m - a.x_m) + (robot.y_m - a.y_m) * (b.y_m - a.y_m)) /
                                          (len * len),
                                      0.0, 1.0)
                         : 0.0;
    const double off = std::hypot(a.x_m + t * (b.x_m - a.x_m) - robot.x_m, a.y_m + t * (b.y_m - a.y_m) - robot.y_m);
    if (off < robot_off) {
      robot_off = off;
      robot_s = length + t * len;
    }
    length += len;
  }
  const double straight = geometry::distance(robot, operator_);
  const bool on_trail = robot_off <= config_.on_trail_m;

  FollowCommand cmd;
  cmd.gap_m = on_trail ? length - robot_s : straight;
  const auto hold = [&](FollowHold reason) {
    cmd.go = false;
    cmd.target = robot;
    cmd.heading_rad = input.robot.theta_rad;
    cmd.reason = reason;
    return cmd;
  };
  if (input.now_ns - seen_ns_ > hal::from_seconds(config_.lost_s)) return hold(FollowHold::operator_lost);
  if (input.now_ns - moving_ns_ > hal::from_seconds(config_.stop_after_s)) return hold(FollowHold::operator_stopped);
  if (cmd.gap_m <= config_.distance_m || straight <= config_.distance_m) return hold(FollowHold::close_enough);

  const double target_s = std::max(length - config_.distance_m, 0.0);
  msg::Point2D target;
  double heading = 0.0;
  point_at(target_s, target, heading);
  if (std::isnan(heading)) heading = input.robot.theta_rad;
  const double margin = config_.robot_radius_m;
  const auto inside = [&](msg::Point2D p) { return inside_by(input.area, p, margin); };

  // The way to the target: along the trail from the robot's place when on it (every crumb on
  // the way must be inside), straight when off it.
  std::size_t first_out = size_ + 1;  // none
  double walked = 0.0;
  std::size_t last_in = size_ + 1;
  for (std::size_t i = 1; i <= size_ && on_trail; ++i) {
    walked += geometry::distance(vertex(i - 1), vertex(i));
    if (walked <= robot_s) continue;
    if (walked >= target_s) break;
    if (!inside(vertex(i))) {
      first_out = i;
      break;
    }
    last_in = i;
  }
  if (first_out > size_ && inside(target)) {
    cmd.go = true;
    cmd.target = target;
    cmd.heading_rad = heading;
    cmd.reason = FollowHold::none;
    return cmd;
  }
  if (first_out <= size_ && inside(target)) {
    // The trail leaves the area and comes back: straight to the target when that way stays in.
    const double span = geometry::distance(robot, target);
    const int samples = static_cast<int>(std::ceil(span / config_.min_step_m));
    bool clear = true;
    for (int k = 1; k < samples && clear; ++k) {
      const double t = static_cast<double>(k) / samples;
      clear = inside({robot.x_m + t * (target.x_m - robot.x_m), robot.y_m + t * (target.y_m - robot.y_m)});
    }
    if (clear) {
      cmd.go = true;
      cmd.target = target;
      cmd.heading_rad = heading;
      cmd.reason = FollowHold::none;
      return cmd;
    }
  }
  if (!on_trail) {
    // Off the trail: the crumb nearest before the target that lies inside.
    double s = 0.0;
    for (std::size_t i = 1; i <= size_; ++i) {
      s += geometry::distance(vertex(i - 1), vertex(i));
      if (s >= target_s) break;
      if (inside(vertex(i))) last_in = i;
    }
  }
  if (last_in > size_) return hold(FollowHold::area_border);
  double s_in = 0.0;
  for (std::size_t i = 1; i <= last_in; ++i) s_in += geometry::distance(vertex(i - 1), vertex(i));
  msg::Point2D on_line;
  double border_heading = 0.0;
  point_at(s_in, on_line, border_heading);
  const msg::Point2D border = vertex(last_in);
  if (std::isnan(border_heading) || geometry::distance(robot, border) <= config_.arrive_m) return hold(FollowHold::area_border);
  cmd.go = true;
  cmd.target = border;
  cmd.heading_rad = border_heading;
  cmd.reason = FollowHold::area_border;
  return cmd;
}

}  // namespace sen3bot::cobot
