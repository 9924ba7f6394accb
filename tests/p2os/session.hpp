#pragma once
// The scripted session behind tests/data/captures/p2os_session.s3bcap: connect, enable,
// drive and turn, stop, request encoders, shut down cleanly. The same step schedule drives
// the recording (with the emulator on the other end) and the replay (with the capture).
#include <functional>

#include "sen3bot/hal/byte_stream.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/p2os/driver.hpp"

namespace sen3bot::p2os::test {

inline constexpr hal::Nanos kSessionStepNs = hal::millis(2);

inline P2osConfig session_driver_config() {
  P2osConfig c;
  c.request_encoders = true;
  return c;
}

// Runs the driver side of the session on `clock`; `peer` runs the robot side each tick
// (empty for a replay). Returns the driver's final state.
inline BaseState run_session(hal::ByteStream& link, hal::SimClock& clock, const std::function<void()>& peer) {
  P2osDriver driver(session_driver_config());
  driver.attach(link, clock.now());
  const hal::Nanos start = clock.now();
  bool close_requested = false;
  hal::Nanos closed_at = 0;
  while (clock.now() - start < hal::seconds(10)) {
    const hal::Nanos t = clock.now() - start;
    if (peer) peer();
    if (t < hal::millis(2500)) {
      driver.set_setpoint(BaseSetpoint{0.3, 0.35, true}, clock.now());
    } else if (t < hal::millis(3200)) {
      driver.set_setpoint(BaseSetpoint{0, 0, true}, clock.now());
    } else if (!close_requested) {
      driver.request_close(clock.now());
      close_requested = true;
    }
    driver.step(clock.now());
    if (driver.closed() && closed_at == 0) closed_at = clock.now();
    if (closed_at != 0 && clock.now() - closed_at > hal::millis(100)) break;
    clock.advance_by(kSessionStepNs);
  }
  return driver.state();
}

}  // namespace sen3bot::p2os::test
