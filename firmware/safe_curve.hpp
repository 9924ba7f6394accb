#pragma once
// A site's safe curve for the supervisory planner, from its own YAML file (docs/navigation.md,
// "The safe curve file"):
//
//   shape: line | circle | ellipse | polynomial
//   through: [[x, y], [x, y]]                 # line: two distinct points
//   centre: [x, y]                            # circle, ellipse
//   radius_m: R                               # circle
//   semi_major_m: A, semi_minor_m: B, angle_deg: T   # ellipse (T of the major axis)
//   terms: [[i, j, c], ...]                   # polynomial: c x^i y^j, i + j <= 4
//   bounds: [[x0, y0], [x1, y1]]              # optional: the part of the site it serves
//
// Unknown keys, a key of another shape, degenerate shapes and non-finite numbers are errors
// naming the file, the key and the line.
#include <string>
#include <string_view>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/nav/sgp.hpp"

namespace sen3bot::firmware {

struct SiteCurve {
  nav::SafeCurve curve;
  nav::CurveBounds bounds;
  bool has_bounds = false;  // without: the map's extent (the user of the curve decides)
  std::string shape;        // as written
};

Result<SiteCurve> parse_safe_curve(std::string_view text, const std::string& source);
Result<SiteCurve> load_safe_curve(const std::string& path);

}  // namespace sen3bot::firmware
