// Fuzz target: the safe curve file must give a curve or an error that says why, never a crash;
// a curve it accepts is checked against an ellipse and planned on without trouble.
#include <cstddef>
#include <cstdint>
#include <memory_resource>
#include <string_view>

#include "safe_curve.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto curve = sen3bot::firmware::parse_safe_curve(text, "fuzz.yaml");
  if (!curve) {
    if (curve.error().message().empty()) __builtin_trap();  // every error says why
    return 0;
  }
  using namespace sen3bot::nav;
  const Ellipse rock = Ellipse::from_axes(1.0, 1.0, 0.5, 0.2, 0.3);
  const CurveBounds bounds = curve->has_bounds ? curve->bounds : CurveBounds{-5.0, -5.0, 5.0, 5.0};
  std::pmr::monotonic_buffer_resource arena;
  SgpConfig config;
  config.max_steps = 500;
  SupervisoryPlanner planner;
  if (!planner.init(config, arena)) __builtin_trap();
  if (planner.set_site(curve->curve, bounds, std::span(&rock, 1))) (void)planner.plan({-1.0, -1.0}, {3.0, 2.0});
  return 0;
}
