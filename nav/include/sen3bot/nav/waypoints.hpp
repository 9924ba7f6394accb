#pragma once
// Waypoints for the global planner, until the supervisory planner computes them: a text file
// with one "x y" pair (map frame, metres) per line; '#' starts a comment, blank lines are
// skipped. Read once at start-up.
#include <string>
#include <string_view>
#include <vector>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/nav/geometry.hpp"

namespace sen3bot::nav {

Result<std::vector<Point2D>> parse_waypoints(std::string_view text, std::string_view source);
Result<std::vector<Point2D>> load_waypoints(const std::string& path);

}  // namespace sen3bot::nav
