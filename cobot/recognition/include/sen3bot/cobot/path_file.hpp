#pragma once
// Recorded worker paths as text, one JSON object per line (JSON lines):
//   {"name": "w17", "operation": "kitting", "points": [[1.62, 7.04], [1.70, 7.01], ...]}
// name: any string (may be empty); operation: the truth, optional; points: [x, y] pairs in the
// map frame (metres), at most kMaxPathPoints. Other members are refused, so a misspelt key is
// not silently ignored. Blank lines are skipped. `sen3bot recognize --paths` reads this and
// `sen3bot-sim experiment operations --save-paths` writes it.
#include <cstddef>
#include <string>
#include <string_view>
#include <vector>

#include "sen3bot/hal/result.hpp"

namespace sen3bot::cobot {

struct PathRecord {
  std::string name;
  std::string operation;  // empty: not given
  std::vector<float> xy;  // x0, y0, x1, y1, ...
  [[nodiscard]] std::size_t points() const noexcept { return xy.size() / 2; }
};

// One line (without its newline). Errors give the byte offset and the reason.
Result<PathRecord> parse_path_line(std::string_view line);
// A whole file's text; errors start with "line N: ". source names the text in messages.
Result<std::vector<PathRecord>> parse_paths(std::string_view text, std::string_view source);
Result<std::vector<PathRecord>> load_paths(const std::string& path);

// The record as one line (no newline), coordinates to the millimetre.
[[nodiscard]] std::string path_line(const PathRecord& record);

}  // namespace sen3bot::cobot
