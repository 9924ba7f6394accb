#pragma once
// Follow-me: in collaborative mode the robot walks behind its operator along the way they
// walked, keeping distance_m between them measured along that way, and never leaves the
// type-2 area it collaborates in (shrunk by its own radius).
//
// The operator's way is a breadcrumb trail: their position is added whenever it is more than
// min_step_m from the newest crumb; when the trail is full its oldest crumb goes. The trail
// starts at the robot (start()), so the first stretch leads from where the robot stood to
// where the operator was. Each cycle the trail, ended by the operator's current position, is
// one polyline; the target is the point on it distance_m before its end, the heading that of
// the polyline there. Pure: no clock, no I/O; the trail's memory is taken in init().
#include <cstddef>
#include <cstdint>
#include <memory_resource>
#include <span>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/msg/geometry.hpp"

namespace sen3bot::cobot {

struct FollowConfig {
  std::size_t trail_capacity = 256;  // crumbs (25 m of trail at min_step_m)
  double min_step_m = 0.1;           // a crumb when the operator is farther than this from the last
  double distance_m = 1.0;           // behind the operator, along the trail
  double stop_speed_m_s = 0.1;       // slower than this for stop_after_s: the operator has stopped
  double stop_after_s = 1.0;
  double lost_s = 1.0;               // not seen for longer: the operator is lost
  double robot_radius_m = 0.3;       // the area is shrunk by this
  double on_trail_m = 0.3;           // the robot this near the trail is on it: gaps along the trail
  double arrive_m = 0.05;            // at the area's border, closer than this to the last crumb: stand
};

enum class FollowHold : std::uint8_t {
  none,              // going
  close_enough,      // within distance_m of the operator, along the trail or straight
  operator_stopped,  // slower than stop_speed_m_s for stop_after_s
  operator_lost,     // not seen for lost_s
  area_border,       // the target would leave the shrunk area: the last crumb inside it instead
};
[[nodiscard]] const char* to_string(FollowHold hold) noexcept;

struct FollowInput {
  hal::Nanos now_ns = 0;
  bool operator_seen = false;  // the people tracker has the operator this cycle
  msg::Point2D operator_at;    // map frame
  double operator_vx_m_s = 0.0;
  double operator_vy_m_s = 0.0;
  msg::Pose2D robot;                      // map frame
  std::span<const msg::Point2D> area;     // the type-2 area (simple polygon); empty: no way to go
};

struct FollowCommand {
  bool go = false;              // drive to target; false: stand where it is
  msg::Point2D target;          // the robot's own position when standing
  double heading_rad = 0.0;     // along the trail at the target (the robot's heading when standing)
  FollowHold reason = FollowHold::none;
  double gap_m = 0.0;           // robot to operator along the trail, or straight when off it
};

class FollowMe {
 public:
  // Errors: a capacity under 2, a distance, step, radius or time not positive.
  Status init(const FollowConfig& config, std::pmr::memory_resource& resource);
  // Starts a trail for a new operator: the robot's position, then the operator's.
  void start(hal::Nanos now_ns, const msg::Pose2D& robot, msg::Point2D operator_at) noexcept;
  FollowCommand update(const FollowInput& input) noexcept;

  [[nodiscard]] std::size_t trail_size() const noexcept { return size_; }
  [[nodiscard]] msg::Point2D trail_point(std::size_t i) const noexcept {  // 0: the oldest
    return trail_[(head_ + i) % trail_.size()];
  }

 private:
  void add(msg::Point2D p) noexcept;
  // The polyline's vertices: the crumbs, then the operator (index size_).
  [[nodiscard]] msg::Point2D vertex(std::size_t i) const noexcept { return i < size_ ? trail_point(i) : operator_; }
  // Where on the polyline arc length s lies, and the direction of its segment there.
  void point_at(double s_m, msg::Point2D& at, double& heading_rad) const noexcept;

  FollowConfig config_;
  std::span<msg::Point2D> trail_;
  std::size_t head_ = 0;
  std::size_t size_ = 0;
  msg::Point2D operator_;
  hal::Nanos seen_ns_ = 0;    // the operator's last sighting
  hal::Nanos moving_ns_ = 0;  // the last time the operator was faster than stop_speed_m_s
};

}  // namespace sen3bot::cobot
