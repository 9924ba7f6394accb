#pragma once
// Driver and emulator in lockstep: one MemoryPipe, one simulated line, one simulated time
// line advanced in fixed steps. Deterministic, so timing assertions are exact.
#include <cmath>
#include <functional>
#include <memory>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/memory_stream.hpp"
#include "sen3bot/lms200/device.hpp"
#include "sen3bot/sim/lms200/emulator.hpp"

namespace sen3bot::lms200::testing {

// An 8 m x 6 m room with a 1 m box centred at (6, 3); the sensor at the centre facing +x.
inline WallWorld test_world() { return WallWorld::room_with_box(8.0, 6.0, 6.0, 3.0, 1.0); }

struct Rig {
  Rig(const EmulatorOptions& emulator_options, const Lms200Config& driver_config, hal::Nanos step_length_ns = hal::millis(1))
      : world(test_world()),
        line(emulator_options.initial_baud),
        emulator(emulator_options, pipe.b(), world, &line),
        device(driver_config, pipe.a(), &line),
        step_ns(step_length_ns) {}

  void step() {
    emulator.step(now);
    device.step(now);
    now += step_ns;
  }
  void run_for(hal::Nanos duration) {
    const hal::Nanos end = now + duration;
    while (now < end) step();
  }
  // Steps until pred() or the time limit; returns pred().
  bool run_until(const std::function<bool()>& pred, hal::Nanos limit) {
    const hal::Nanos end = now + limit;
    while (!pred() && now < end) step();
    return pred();
  }
  bool until_streaming(hal::Nanos limit = hal::seconds(10)) {
    return run_until([this] { return device.phase() == Lms200Device::Phase::streaming; }, limit);
  }

  hal::MemoryPipe pipe{16384, "lms200-driver", "lms200-emulator"};
  WallWorld world;
  SimulatedLine line;
  Lms200Emulator emulator;
  Lms200Device device;
  hal::Nanos step_ns;
  hal::Nanos now = 0;
};

// The range the emulator sends for beam i, quantised to the units as it does, or NaN when
// the scanner would report a code.
inline float expected_range_m(const WallWorld& world, const LaserScan& scan, std::size_t i) {
  const SensorPose p = world.sensor_pose();
  const double r = world.cast(p.x_m, p.y_m, p.theta_rad + static_cast<double>(scan.angle_min_rad) +
                                                 static_cast<double>(i) * static_cast<double>(scan.angle_increment_rad));
  const double unit = scan.units == 1 ? 0.001 : 0.01;
  const double max_units = 8182.0;
  const double q = std::round(r / unit);
  if (!std::isfinite(r) || q > max_units) return std::nanf("");
  return static_cast<float>(q * unit);
}

}  // namespace sen3bot::lms200::testing
