#pragma once
// The firmware's pieces of reading its configuration, over the YAML reader
// (sen3bot/yaml/reader.hpp): poses, seconds as milliseconds, the file's text. The firmware's
// loader and a board that owns a section of the same file (the simulator's `sim`) both read
// through this.
#include <cmath>
#include <cstdint>
#include <numbers>
#include <string>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/nav/geometry.hpp"
#include "sen3bot/yaml/reader.hpp"

namespace sen3bot::firmware::config {

using Reader = yaml::Reader;
using ConfigError = yaml::ReadError;
using yaml::parse;
using yaml::relative_to;

// {x_m, y_m, theta_deg}; a missing key is 0.
inline nav::Pose2D read_pose(const Reader& r) {
  r.allow_only({"x_m", "y_m", "theta_deg"});
  nav::Pose2D p;
  if (r.has("x_m")) p.x_m = r.number("x_m", -1e4, 1e4);
  if (r.has("y_m")) p.y_m = r.number("y_m", -1e4, 1e4);
  if (r.has("theta_deg")) p.theta_rad = r.number("theta_deg", -360.0, 360.0) * std::numbers::pi / 180.0;
  return p;
}

inline std::int64_t millis(const Reader& r, const std::string& key, std::int64_t min_ms, std::int64_t max_ms) {
  return static_cast<std::int64_t>(std::llround(r.number(key, static_cast<double>(min_ms) / 1000.0,
                                                          static_cast<double>(max_ms) / 1000.0) * 1000.0));
}

// The text of a configuration file, refused when it is far larger than one can be.
Result<std::string> read_text(const std::string& path);

}  // namespace sen3bot::firmware::config
