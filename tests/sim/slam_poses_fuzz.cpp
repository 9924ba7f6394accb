// Fuzzes the poses-file parser of `sen3bot-sim slam-check`: a file it accepts holds one finite
// pose per line it counted, nothing else.
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "slam_check.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  const auto poses = sen3bot::sim::slam_check::parse_poses(text, "fuzz.txt");
  if (!poses.ok()) return 0;
  if (poses->size() > size / 7 + 1) __builtin_trap();  // "i x y t" needs at least 7 bytes a line
  for (const auto& p : *poses)
    if (!std::isfinite(p.x_m) || !std::isfinite(p.y_m) || !std::isfinite(p.theta_rad)) __builtin_trap();
  return 0;
}
