#pragma once
// A box file: person-detector frames recorded or written by hand, one JSON object per line,
//     {"t_s": 0.10, "boxes": [[u0, v0, u1, v1, confidence, class], ...]}
// (tools/detector_replay.py sends them; `sen3bot fuse` fuses them with a scan capture). Blank
// lines and lines starting with '#' are skipped. Errors name the file and the line.
#include <string>
#include <string_view>
#include <vector>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/msg/people.hpp"

namespace sen3bot::firmware {

struct BoxFrame {
  double t_s = 0;
  msg::PersonDetections detections;  // boxes and count only
};

Result<std::vector<BoxFrame>> parse_box_file(std::string_view text, const std::string& name);
Result<std::vector<BoxFrame>> load_box_file(const std::string& path);

}  // namespace sen3bot::firmware
