// Fuzz target: a box file must give frames or an error that says why, never a crash; every
// frame it accepts holds at most 16 boxes with ordered corners and a confidence in [0, 1].
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "box_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  auto frames = sen3bot::firmware::parse_box_file(text, "fuzz.jsonl");
  if (!frames) {
    if (frames.error().message().empty()) __builtin_trap();
    return 0;
  }
  for (const auto& f : *frames) {
    if (f.detections.count > sen3bot::msg::PersonDetections::kMax) __builtin_trap();
    for (std::size_t i = 0; i < f.detections.count; ++i) {
      const auto& b = f.detections.boxes[i];
      if (!(b.u0 <= b.u1 && b.v0 <= b.v1 && b.confidence >= 0.0f && b.confidence <= 1.0f)) __builtin_trap();
    }
  }
  return 0;
}
