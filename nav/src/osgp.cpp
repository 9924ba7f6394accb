#include "sen3bot/nav/osgp.hpp"

#include <algorithm>
#include <cmath>
#include <limits>

namespace sen3bot::nav {

const char* to_string(OsgpOutcome outcome) noexcept {
  switch (outcome) {
    case OsgpOutcome::on_path: return "on_path";
    case OsgpOutcome::deviated_no_person: return "deviated_no_person";
    case OsgpOutcome::waiting: return "waiting";
    case OsgpOutcome::triggered: return "triggered";
    case OsgpOutcome::cooling_down: return "cooling_down";
  }
  return "unknown";
}

double distance_to_path(Point2D p, std::span<const Point2D> path) noexcept {
  double best = std::numeric_limits<double>::infinity();
  if (path.size() == 1) return std::hypot(p.x_m - path[0].x_m, p.y_m - path[0].y_m);
  for (std::size_t i = 1; i < path.size(); ++i) {
    const Point2D a = path[i - 1];
    const Point2D b = path[i];
    const double dx = b.x_m - a.x_m;
    const double dy = b.y_m - a.y_m;
    const double len2 = dx * dx + dy * dy;
    const double t = len2 > 0.0 ? std::clamp(((p.x_m - a.x_m) * dx + (p.y_m - a.y_m) * dy) / len2, 0.0, 1.0) : 0.0;
    best = std::min(best, std::hypot(p.x_m - (a.x_m + t * dx), p.y_m - (a.y_m + t * dy)));
  }
  return best;
}

OsgpOutcome OsgpTrigger::update(const Pose2D& robot, std::span<const Point2D> safe_path, Point2D goal,
                                const msg::People& people, hal::Nanos now_ns) noexcept {
  OsgpOutcome outcome = OsgpOutcome::on_path;
  bool deviated = false;
  if (!safe_path.empty()) {
    const Point2D at{robot.x_m, robot.y_m};
    const Point2D approach[2] = {safe_path.back(), goal};
    deviated = std::min(distance_to_path(at, safe_path), distance_to_path(at, approach)) > config_.deviation_m;
  }
  // The last time someone was seen near is remembered here: a person being passed leaves the
  // camera's view, and their track expires, before the deviation shows.
  for (std::size_t i = 0; i < std::min<std::size_t>(people.count, msg::People::kMax); ++i) {
    const msg::TrackedPerson& p = people.items[i];
    if (std::hypot(p.x_m - robot.x_m, p.y_m - robot.y_m) <= config_.trigger_distance_m)
      last_near_ns_ = std::max(last_near_ns_, p.last_seen_ns);
  }
  const bool person_near =
      last_near_ns_ >= 0 && static_cast<double>(now_ns - last_near_ns_) <= config_.person_timeout_s * 1e9;
  if (!deviated) {
    armed_ns_ = -1;
  } else if (!person_near) {
    armed_ns_ = -1;
    outcome = OsgpOutcome::deviated_no_person;
  } else if (last_trigger_ns_ >= 0 && static_cast<double>(now_ns - last_trigger_ns_) < config_.cooldown_s * 1e9) {
    outcome = OsgpOutcome::cooling_down;
  } else {
    if (armed_ns_ < 0) armed_ns_ = now_ns;
    if (static_cast<double>(now_ns - armed_ns_) >= config_.delay_s * 1e9) {
      outcome = OsgpOutcome::triggered;
      last_trigger_ns_ = now_ns;
      armed_ns_ = -1;
    } else {
      outcome = OsgpOutcome::waiting;
    }
  }
  ++counts_[static_cast<std::size_t>(outcome)];
  return outcome;
}

}  // namespace sen3bot::nav
