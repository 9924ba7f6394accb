#include "box_file.hpp"

#include <yaml-cpp/yaml.h>

#include <cmath>
#include <fstream>
#include <sstream>

namespace sen3bot::firmware {

namespace {

Result<BoxFrame> parse_line(const std::string& line, const std::string& name, int number) {
  // JSON is YAML's flow style: yaml-cpp reads each line.
  const YAML::Node node = YAML::Load(line);
  if (!node.IsMap() || !node["t_s"] || !node["boxes"] || !node["boxes"].IsSequence())
    return Error::format(Errc::protocol, "%s:%d: expected {\"t_s\": T, \"boxes\": [...]}", name.c_str(), number);
  BoxFrame frame;
  frame.t_s = node["t_s"].as<double>();
  if (!std::isfinite(frame.t_s) || std::abs(frame.t_s) > 1e9)
    return Error::format(Errc::protocol, "%s:%d: t_s must be a finite time in seconds", name.c_str(), number);
  if (node["boxes"].size() > msg::PersonDetections::kMax)
    return Error::format(Errc::protocol, "%s:%d: %zu boxes, at most %zu a frame", name.c_str(), number,
                         node["boxes"].size(), msg::PersonDetections::kMax);
  for (const YAML::Node& b : node["boxes"]) {
    if (!b.IsSequence() || b.size() != 6)
      return Error::format(Errc::protocol, "%s:%d: a box is [u0, v0, u1, v1, confidence, class]", name.c_str(), number);
    msg::PersonBox box;
    box.u0 = b[0].as<float>();
    box.v0 = b[1].as<float>();
    box.u1 = b[2].as<float>();
    box.v1 = b[3].as<float>();
    box.confidence = b[4].as<float>();
    const long cls = b[5].as<long>();
    const bool inside = box.u0 >= 0.0f && box.v0 >= 0.0f && box.u1 <= 65535.0f && box.v1 <= 65535.0f;
    if (!(box.u0 <= box.u1 && box.v0 <= box.v1) || !inside || !(box.confidence >= 0.0f && box.confidence <= 1.0f) ||
        cls < 0 || cls > 65535)
      return Error::format(Errc::protocol,
                           "%s:%d: a box needs 0 <= u0 <= u1 and 0 <= v0 <= v1 (pixels), confidence in [0, 1] and "
                           "class 0..65535",
                           name.c_str(), number);
    box.class_id = static_cast<std::uint16_t>(cls);
    frame.detections.boxes[frame.detections.count++] = box;
  }
  return frame;
}

}  // namespace

Result<std::vector<BoxFrame>> parse_box_file(std::string_view text, const std::string& name) {
  std::vector<BoxFrame> frames;
  std::istringstream lines{std::string(text)};
  std::string line;
  for (int number = 1; std::getline(lines, line); ++number) {
    const std::size_t start = line.find_first_not_of(" \t\r");
    if (start == std::string::npos || line[start] == '#') continue;
    try {
      Result<BoxFrame> frame = parse_line(line, name, number);
      if (!frame) return frame.error();
      frames.push_back(*frame);
    } catch (const YAML::Exception& e) {
      return Error::format(Errc::protocol, "%s:%d: %s", name.c_str(), number, e.what());
    }
  }
  return frames;
}

Result<std::vector<BoxFrame>> load_box_file(const std::string& path) {
  std::ifstream file(path);
  if (!file) return Error::format(Errc::not_found, "%s: cannot open it", path.c_str());
  std::ostringstream text;
  text << file.rdbuf();
  return parse_box_file(text.str(), path);
}

}  // namespace sen3bot::firmware
