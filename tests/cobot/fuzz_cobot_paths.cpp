// Fuzz target: a paths file's text is paths or an error naming a line, never a crash; what was
// read writes back to lines that read the same (to the millimetre the writer keeps).
#include <cmath>
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "sen3bot/cobot/operations.hpp"
#include "sen3bot/cobot/path_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sen3bot::cobot;
  const std::string_view text(reinterpret_cast<const char*>(data), size);
  sen3bot::Result<std::vector<PathRecord>> paths = parse_paths(text, "fuzz");
  if (!paths) {
    if (std::string_view(paths.error().c_str()).find("fuzz: line ") != 0) __builtin_trap();
    return 0;
  }
  for (const PathRecord& p : *paths) {
    if (p.points() > kMaxPathPoints || p.xy.size() % 2 != 0) __builtin_trap();
    // Names read back are valid UTF-8 (the reader checks), so the line reads back whole.
    sen3bot::Result<PathRecord> again = parse_path_line(path_line(p));
    if (!again) __builtin_trap();
    if (again->xy.size() != p.xy.size()) __builtin_trap();
    for (std::size_t i = 0; i < p.xy.size(); ++i)
      if (std::fabs(again->xy[i] - p.xy[i]) > 0.0006f * (1.0f + std::fabs(p.xy[i]) * 1e-3f)) __builtin_trap();
  }
  return 0;
}
