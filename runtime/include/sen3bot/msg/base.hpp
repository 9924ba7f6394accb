#pragma once
// The mobile base's state: wheel odometry and its e-stop and motor flags.
#include <type_traits>

#include "sen3bot/hal/clock.hpp"

namespace sen3bot::msg {

// Wheel odometry: pose in the odometry frame and body velocities.
struct Odometry {
  double x_m = 0.0;
  double y_m = 0.0;
  double theta_rad = 0.0;
  double v_m_s = 0.0;
  double w_rad_s = 0.0;
  hal::Nanos stamp_ns = 0;
  bool valid = false;
};
static_assert(std::is_trivially_copyable_v<Odometry>);

struct BaseFlags {
  bool estop = false;
  bool motors_enabled = false;
  double battery_v = 0.0;  // 0: not reported
};
static_assert(std::is_trivially_copyable_v<BaseFlags>);

}  // namespace sen3bot::msg
