#include "sen3bot/nav/waypoints.hpp"

#include <cctype>
#include <charconv>
#include <cmath>
#include <fstream>
#include <iterator>

namespace sen3bot::nav {
namespace {

bool next_number(std::string_view& s, double& out) {
  while (!s.empty() && (std::isspace(static_cast<unsigned char>(s.front())) != 0 || s.front() == ',')) s.remove_prefix(1);
  if (s.empty()) return false;
  if (s.front() == '+') s.remove_prefix(1);
  const auto [ptr, ec] = std::from_chars(s.data(), s.data() + s.size(), out);
  if (ec != std::errc() || !std::isfinite(out)) return false;
  s.remove_prefix(static_cast<std::size_t>(ptr - s.data()));
  return true;
}

}  // namespace

Result<std::vector<Point2D>> parse_waypoints(std::string_view text, std::string_view source) {
  std::vector<Point2D> points;
  int line_number = 0;
  while (!text.empty()) {
    const std::size_t eol = text.find('\n');
    std::string_view line = text.substr(0, eol);
    text.remove_prefix(eol == std::string_view::npos ? text.size() : eol + 1);
    ++line_number;
    if (const std::size_t hash = line.find('#'); hash != std::string_view::npos) line = line.substr(0, hash);
    while (!line.empty() && std::isspace(static_cast<unsigned char>(line.back())) != 0) line.remove_suffix(1);
    while (!line.empty() && std::isspace(static_cast<unsigned char>(line.front())) != 0) line.remove_prefix(1);
    if (line.empty()) continue;
    Point2D p;
    if (!next_number(line, p.x_m) || !next_number(line, p.y_m)) {
      return Error::format(Errc::config, "%.*s:%d: expected two numbers 'x y'", static_cast<int>(source.size()),
                           source.data(), line_number);
    }
    while (!line.empty() && std::isspace(static_cast<unsigned char>(line.front())) != 0) line.remove_prefix(1);
    if (!line.empty()) {
      return Error::format(Errc::config, "%.*s:%d: unexpected text after 'x y'", static_cast<int>(source.size()),
                           source.data(), line_number);
    }
    points.push_back(p);
  }
  return points;
}

Result<std::vector<Point2D>> load_waypoints(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error::format(Errc::not_found, "%s: cannot open", path.c_str());
  const std::string text((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  return parse_waypoints(text, path);
}

}  // namespace sen3bot::nav
