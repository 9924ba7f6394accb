#pragma once
// The thesis' three examples (§1.2.2), scaled by kExampleScale in position so that robots of a
// Pioneer's size fit: the thesis' workspace [-1.4, 1.4] x [-0.8, 0.8] m with robots of radius
// 0.3 m becomes [-3.5, 3.5] x [-2, 2] m for a 0.3 m body circle (which holds the Pioneer's
// 0.455 m x 0.381 m footprint about its axle) driven through a point P 0.1 m ahead of the axle.
// docs/formation.md says why the scale.
//   1: four robots to four targets;
//   2: three robots patrol an ellipse in formation;
//   3: a leader patrols a circle, two followers keep 0.5 m (scaled: 1.25 m) from it.
#include <array>
#include <cstddef>

#include "sen3bot/formation/controller.hpp"

namespace sen3bot::formation {

inline constexpr double kExampleScale = 2.5;
inline constexpr int kExampleCount = 3;

struct Example {
  int number = 0;                // 1, 2 or 3
  const char* title = "";
  ControllerConfig config;       // v_max / w_max: the Pioneer's defaults; override with the robot's
  std::array<Pose, kMaxRobots> starts{};
  double duration_s = 0.0;       // long enough to converge from the perturbed starts
};

// number 1..3; anything else gives example 1.
[[nodiscard]] Example example(int number) noexcept;

}  // namespace sen3bot::formation
