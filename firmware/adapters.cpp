#include "adapters.hpp"

#include <cmath>
#include <limits>

#include "sen3bot/lms200/protocol.hpp"

namespace sen3bot::firmware {

namespace {
// The LMS200 cannot measure closer than a few centimetres (its window and the mirror).
constexpr float kLaserRangeMinM = 0.02f;
}  // namespace

void to_nav_scan(const lms200::LaserScan& in, msg::ScanMessage& out) noexcept {
  const std::size_t count = std::min<std::size_t>(in.count, msg::ScanMessage::kMaxBeams);
  out.count = static_cast<std::uint16_t>(count);
  out.angle_min_rad = in.angle_min_rad;
  out.increment_rad = in.angle_increment_rad;
  out.range_min_m = kLaserRangeMinM;
  out.range_max_m = in.range_max_m;
  out.stamp_ns = in.stamp_ns;
  for (std::size_t i = 0; i < count; ++i) {
    if (in.valid(i)) {
      out.ranges_m[i] = in.ranges_m[i];
    } else if (in.invalid_reason[i] == static_cast<std::uint8_t>(lms200::InvalidReason::over_maximum)) {
      out.ranges_m[i] = in.range_max_m;
    } else {
      out.ranges_m[i] = std::numeric_limits<float>::quiet_NaN();
    }
  }
}

msg::Odometry to_nav_odometry(const p2os::BaseState& in) noexcept {
  msg::Odometry odom;
  odom.x_m = in.x_m;
  odom.y_m = in.y_m;
  odom.theta_rad = in.theta_rad;
  odom.v_m_s = in.v_m_s;
  odom.w_rad_s = in.omega_rad_s;
  odom.stamp_ns = in.sip_stamp_ns;
  odom.valid = in.link == p2os::LinkState::connected && in.sip_count > 0;
  return odom;
}

msg::BaseFlags to_base_flags(const p2os::BaseState& in) noexcept {
  return msg::BaseFlags{in.estop, in.motors_enabled, in.battery_v};
}

void to_person_detections(const detector::Detections& in, msg::PersonDetections& out) noexcept {
  static_assert(detector::Detections::kMax == msg::PersonDetections::kMax);
  out.count = in.count;
  for (std::size_t i = 0; i < in.count && i < out.boxes.size(); ++i) {
    const detector::Box& b = in.boxes[i];
    out.boxes[i] = {b.u0, b.v0, b.u1, b.v1, b.confidence, b.class_id};
  }
  out.source = in.source;
  out.sequence = in.sequence;
  out.capture_ns = in.capture_ns;
}

}  // namespace sen3bot::firmware
