#include "safe_curve.hpp"

#include <cmath>
#include <numbers>
#include <vector>

#include "config_reader.hpp"

namespace sen3bot::firmware {

namespace {

using config::Reader;

// Every number is a coordinate or a size on a site: kilometres are already a mistake.
constexpr double kMaxMetres = 1e4;

// A point [x, y] of this node, within 10 km of the origin.
nav::Point2D site_point(const Reader& r) {
  const nav::Point2D p = r.point();
  if (std::abs(p.x_m) > kMaxMetres || std::abs(p.y_m) > kMaxMetres) r.fail_here("a coordinate beyond 10 km");
  return p;
}

SiteCurve read_curve(const Reader& r) {
  r.require_map();
  SiteCurve c;
  c.shape = r.text("shape");
  if (c.shape == "line") {
    r.allow_only({"shape", "through", "bounds"});
    const std::vector<Reader> through = r.sequence("through");
    if (through.size() != 2) r.fail("through", "expected two points [[x, y], [x, y]]", YAML::Node());
    const nav::Point2D a = site_point(through[0]);
    const nav::Point2D b = site_point(through[1]);
    if (std::hypot(b.x_m - a.x_m, b.y_m - a.y_m) < 1e-3) r.fail("through", "the two points coincide", YAML::Node());
    c.curve = nav::SafeCurve::line(a, b);
  } else if (c.shape == "circle") {
    r.allow_only({"shape", "centre", "radius_m", "bounds"});
    c.curve = nav::SafeCurve::circle(site_point(r.child("centre")), r.number("radius_m", 0.05, kMaxMetres));
  } else if (c.shape == "ellipse") {
    r.allow_only({"shape", "centre", "semi_major_m", "semi_minor_m", "angle_deg", "bounds"});
    const double a = r.number("semi_major_m", 0.05, kMaxMetres);
    const double b = r.number("semi_minor_m", 0.05, kMaxMetres);
    if (b > a) r.fail("semi_minor_m", "is larger than semi_major_m", YAML::Node());
    const double angle = r.has("angle_deg") ? r.number("angle_deg", -360.0, 360.0) * std::numbers::pi / 180.0 : 0.0;
    c.curve = nav::SafeCurve::ellipse(site_point(r.child("centre")), a, b, angle);
  } else if (c.shape == "polynomial") {
    r.allow_only({"shape", "terms", "bounds"});
    const std::vector<Reader> terms = r.sequence("terms");
    if (terms.empty()) r.fail("terms", "expected at least one term [i, j, c]", YAML::Node());
    bool seen[nav::SafeCurve::kMaxDegree + 1][nav::SafeCurve::kMaxDegree + 1] = {};
    bool varies = false;
    for (const Reader& t : terms) {
      const std::vector<Reader> parts = t.sequence_here();
      if (parts.size() != 3) t.fail_here("expected [i, j, c]: the powers of x and y and the coefficient");
      const std::int64_t i = parts[0].integer_here(0, nav::SafeCurve::kMaxDegree);
      const std::int64_t j = parts[1].integer_here(0, nav::SafeCurve::kMaxDegree);
      const double value = parts[2].number_here(-1e12, 1e12);
      if (!nav::SafeCurve::valid_term(static_cast<int>(i), static_cast<int>(j)))
        t.fail_here("degree " + std::to_string(i + j) + " is above " + std::to_string(nav::SafeCurve::kMaxDegree));
      if (seen[i][j]) t.fail_here("the term x^" + std::to_string(i) + " y^" + std::to_string(j) + " is given twice");
      seen[i][j] = true;
      c.curve.set_coefficient(static_cast<int>(i), static_cast<int>(j), value);
      varies = varies || (i + j > 0 && value != 0.0);
    }
    if (!varies) r.fail("terms", "p is a constant: it has no curve", YAML::Node());
  } else {
    r.fail("shape", "expected line, circle, ellipse or polynomial, got '" + c.shape + "'", YAML::Node());
  }
  if (r.has("bounds")) {
    const std::vector<Reader> corners = r.sequence("bounds");
    if (corners.size() != 2) r.fail("bounds", "expected two corners [[x0, y0], [x1, y1]]", YAML::Node());
    const nav::Point2D lo = site_point(corners[0]);
    const nav::Point2D hi = site_point(corners[1]);
    if (!(hi.x_m > lo.x_m && hi.y_m > lo.y_m))
      r.fail("bounds", "the second corner must be above and right of the first", YAML::Node());
    c.bounds = {lo.x_m, lo.y_m, hi.x_m, hi.y_m};
    c.has_bounds = true;
  }
  return c;
}

}  // namespace

Result<SiteCurve> parse_safe_curve(std::string_view text, const std::string& source) {
  return config::parse<SiteCurve>(text, source, [](const Reader& r) { return read_curve(r); });
}

Result<SiteCurve> load_safe_curve(const std::string& path) {
  Result<std::string> text = config::read_text(path);
  if (!text) return text.error();
  return parse_safe_curve(*text, path);
}

}  // namespace sen3bot::firmware
