#pragma once
// Bus messages of the mobile base: what navigation/safety ask for (BaseSetpoint) and what
// the base reports every SIP (BaseState). Fixed-size and trivially copyable.
#include <cstdint>
#include <type_traits>

#include "sen3bot/hal/clock.hpp"

namespace sen3bot::p2os {

// Velocity command in the robot frame. The driver stops the robot if no fresh setpoint
// (a new Topic sequence) arrives within P2osConfig::command_timeout_ms.
struct BaseSetpoint {
  double v_m_s = 0;          // forward, + ahead
  double omega_rad_s = 0;    // yaw rate, + counter-clockwise
  bool enable_motors = true;  // false: the driver sends ENABLE 0 and zero velocity
};

enum class LinkState : std::uint8_t {
  disconnected,  // no stream, or the stream failed (reopen pending)
  syncing,       // handshake in progress (SYNC0..2, OPEN)
  connected,     // SIPs arriving
  closing,       // clean shutdown in progress
  closed,        // shut down on request
};

const char* to_string(LinkState state) noexcept;

struct BaseState {
  // Odometry in the controller's frame (starts where the controller's odometry is), unwrapped
  // across the 15-bit counter wrap.
  double x_m = 0;
  double y_m = 0;
  double theta_rad = 0;     // (-pi, pi]
  double v_m_s = 0;         // (left + right) / 2
  double omega_rad_s = 0;   // from ROTVEL when sent, else from the wheel speeds
  double left_wheel_m_s = 0;
  double right_wheel_m_s = 0;
  double distance_m = 0;    // path length travelled since connect (|d| summed per SIP)
  double battery_v = 0;
  std::int32_t left_encoder_ticks = 0;  // from ENCODERpac, when requested
  std::int32_t right_encoder_ticks = 0;
  hal::Nanos sip_stamp_ns = 0;      // when the last SIP was parsed
  std::uint64_t sip_count = 0;      // SIPs since the driver started
  std::uint64_t bad_checksums = 0;  // frames dropped for a wrong checksum
  std::uint64_t link_losses = 0;    // times the SIP stream stopped while connected
  std::uint64_t reconnects = 0;     // successful connects after the first
  std::uint64_t command_timeouts = 0;  // times the planner went quiet and the driver stopped
  std::uint16_t flags_raw = 0;        // SIP FLAGS
  std::uint16_t stall_bumpers_raw = 0;
  std::uint8_t front_bumpers = 0;   // bit i = front bumper segment i hit
  std::uint8_t rear_bumpers = 0;
  bool left_stall = false;
  bool right_stall = false;
  bool estop = false;               // FLAGS bit 5 (STOP button / e-stop)
  bool motors_enabled = false;      // FLAGS bit 0
  bool moving = false;              // SIP type 0x33
  bool encoders_valid = false;
  bool command_timed_out = false;   // currently stopped for lack of setpoints
  LinkState link = LinkState::disconnected;
};

static_assert(std::is_trivially_copyable_v<BaseSetpoint>);
static_assert(std::is_trivially_copyable_v<BaseState>);

}  // namespace sen3bot::p2os
