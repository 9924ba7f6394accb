#include "sen3bot/formation/examples.hpp"

#include <numbers>

namespace sen3bot::formation {

namespace {

constexpr double s = kExampleScale;

ControllerConfig base(TaskKind task, std::size_t robots) noexcept {
  ControllerConfig c;
  c.task = task;
  c.robots = robots;
  c.radius_m = 0.3;
  c.offset_m = 0.1;
  c.workspace = {-1.4 * s, -0.8 * s, 1.4 * s, 0.8 * s};
  return c;
}

}  // namespace

Example example(int number) noexcept {
  Example e;
  switch (number) {
    case 2:
      e.number = 2;
      e.title = "three robots patrol an ellipse in formation";
      e.config = base(TaskKind::patrol, 3);
      e.config.curve = nav::SafeCurve::ellipse({0.0, 0.0}, 1.0 * s, 0.5 * s, 0.0);
      e.config.curve_start = {0.0, 0.5 * s};
      e.starts[0] = {-0.5 * s, 0.5 * s, std::numbers::pi};
      e.starts[1] = {0.0, 0.5 * s, std::numbers::pi / 2.0};
      e.starts[2] = {0.5 * s, 0.5 * s, 1.5 * std::numbers::pi};
      e.duration_s = 120.0;
      return e;
    case 3:
      e.number = 3;
      e.title = "a leader patrols a circle, two followers keep 1.25 m from it";
      e.config = base(TaskKind::leader, 3);
      e.config.curve = nav::SafeCurve::circle({0.3 * s, 0.0}, 0.26 * s);
      e.config.curve_start = {0.56 * s, 0.0};
      // Behind the leader at 30 degrees either side, 0.5 m (scaled) from it.
      e.config.offsets[1] = {-0.5 * s * 0.8660254037844386, -0.5 * s * 0.5};
      e.config.offsets[2] = {-0.5 * s * 0.8660254037844386, 0.5 * s * 0.5};
      e.starts[0] = {-0.5 * s, 0.0, 0.0};
      e.starts[1] = {-1.0 * s, -0.6 * s, 0.0};
      e.starts[2] = {-1.0 * s, 0.6 * s, 0.0};
      e.duration_s = 120.0;
      return e;
    default:
      e.number = 1;
      e.title = "four robots to their targets";
      e.config = base(TaskKind::targets, 4);
      e.config.targets[0] = {-1.0 * s, -0.5 * s};
      e.config.targets[1] = {1.0 * s, 0.5 * s};
      e.config.targets[2] = {-1.0 * s, 0.5 * s};
      e.config.targets[3] = {1.0 * s, -0.5 * s};
      e.starts[0] = {-1.2 * s, 0.0, 0.0};
      e.starts[1] = {-0.4 * s, 0.0, std::numbers::pi / 2.0};
      e.starts[2] = {0.4 * s, 0.0, std::numbers::pi};
      e.starts[3] = {1.2 * s, 0.0, 1.5 * std::numbers::pi};
      e.duration_s = 90.0;
      return e;
  }
}

}  // namespace sen3bot::formation
