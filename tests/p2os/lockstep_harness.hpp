#pragma once
// Driver and emulator over an in-memory pipe on one simulated time line: exact, repeatable
// timing for state-machine tests.
#include <cmath>
#include <functional>
#include <numbers>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/memory_stream.hpp"
#include "sen3bot/p2os/driver.hpp"
#include "sen3bot/sim/p2os/emulator.hpp"

namespace sen3bot::p2os::test {

inline EmulatorConfig fast_emulator_config() {
  EmulatorConfig c;
  // Brisk accelerations keep simulated manoeuvres short.
  c.trans_accel_mm_s2 = 1500;
  c.trans_decel_mm_s2 = 1500;
  c.rot_accel_deg_s2 = 400;
  c.rot_decel_deg_s2 = 400;
  c.trans_vel_max_mm_s = 1500;
  c.rot_vel_max_deg_s = 300;
  return c;
}

struct Lockstep {
  static constexpr hal::Nanos kStepNs = hal::millis(2);

  explicit Lockstep(const P2osConfig& driver_config = {}, const EmulatorConfig& emulator_config = fast_emulator_config())
      : emulator(emulator_config), driver(driver_config) {
    driver.attach(pipe.a(), now_ns);
  }

  // One tick: emulator, then driver, then time moves on.
  void tick() {
    (void)emulator.step(pipe.b(), now_ns);
    if (planner) planner(now_ns);
    driver.step(now_ns);
    now_ns += kStepNs;
  }
  void run_for(hal::Nanos duration_ns) {
    const hal::Nanos end = now_ns + duration_ns;
    while (now_ns < end) tick();
  }
  bool run_until(const std::function<bool()>& done, hal::Nanos max_ns) {
    const hal::Nanos end = now_ns + max_ns;
    while (now_ns < end) {
      tick();
      if (done()) return true;
    }
    return false;
  }
  bool connect(hal::Nanos max_ns = hal::seconds(5)) {
    return run_until([&] { return driver.state().link == LinkState::connected; }, max_ns);
  }
  // Publishes a setpoint every 50 ms, as a planner would.
  void hold(double v_m_s, double omega_rad_s, bool enable = true) {
    planner = [this, v_m_s, omega_rad_s, enable, next = hal::Nanos{0}](hal::Nanos t) mutable {
      if (t >= next) {
        driver.set_setpoint(BaseSetpoint{v_m_s, omega_rad_s, enable}, t);
        next = t + hal::millis(50);
      }
    };
  }

  hal::MemoryPipe pipe{16384, "driver", "robot"};
  P2osEmulator emulator;
  P2osDriver driver;
  hal::Nanos now_ns = hal::seconds(1);
  std::function<void(hal::Nanos)> planner;
};

// Closed-loop "drive a square on odometry": returns the list of setpoints over time through
// the callback the harness already has. Works on any driver state source.
class SquareDriver {
 public:
  // decel_m_s2 / rot_decel_rad_s2: the braking profile, no harder than the robot can brake.
  SquareDriver(double side_m, double v_m_s, double omega_rad_s, double decel_m_s2 = 1.0, double rot_decel_rad_s2 = 3.0)
      : side_m_(side_m), v_(v_m_s), w_(omega_rad_s), decel_(decel_m_s2), rot_decel_(rot_decel_rad_s2) {}

  // Given the latest state, the setpoint to use now; done() once four sides are driven.
  BaseSetpoint next(const BaseState& s) {
    if (!started_) {
      started_ = true;
      start_x_ = s.x_m;
      start_y_ = s.y_m;
      heading_ = s.theta_rad;
    }
    if (side_ >= 4) return BaseSetpoint{0, 0, true};
    if (turning_) {
      const double error = std::remainder(heading_ - s.theta_rad, 2 * std::numbers::pi);
      if (std::fabs(error) < 0.02 && std::fabs(s.omega_rad_s) < 0.1) {
        turning_ = false;
        start_x_ = s.x_m;
        start_y_ = s.y_m;
        return BaseSetpoint{0, 0, true};
      }
      const double w = std::min({w_, std::sqrt(2 * rot_decel_ * std::fabs(error)), std::fabs(error) * 6.0});
      return BaseSetpoint{0, std::copysign(w, error), true};
    }
    const double travelled = std::hypot(s.x_m - start_x_, s.y_m - start_y_);
    const double remaining = side_m_ - travelled;
    if (remaining <= 0.01) {
      side_ += 1;
      turning_ = true;
      heading_ = std::remainder(heading_ + std::numbers::pi / 2, 2 * std::numbers::pi);
      return BaseSetpoint{0, 0, true};
    }
    const double error = std::remainder(heading_ - s.theta_rad, 2 * std::numbers::pi);
    return BaseSetpoint{std::min(v_, std::max(0.1, std::sqrt(2 * decel_ * remaining))), error * 2.0, true};
  }
  [[nodiscard]] bool done() const { return side_ >= 4; }

 private:
  double side_m_, v_, w_, decel_, rot_decel_;
  bool started_ = false;
  bool turning_ = false;
  int side_ = 0;
  double start_x_ = 0, start_y_ = 0, heading_ = 0;
};

}  // namespace sen3bot::p2os::test
