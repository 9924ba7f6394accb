#include "sen3bot/figure/canvas.hpp"

#include <algorithm>
#include <cmath>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>

#include "sen3bot/image/image_file.hpp"

namespace sen3bot::figure {

namespace {

constexpr int kShift = 4;  // fractional bits of the coordinates handed to OpenCV
constexpr double kOne = 1 << kShift;
constexpr int kFont = cv::FONT_HERSHEY_SIMPLEX;

cv::Point fixed(Px p) { return {static_cast<int>(std::lround(p.x * kOne)), static_cast<int>(std::lround(p.y * kOne))}; }
cv::Scalar bgr(Rgb c) { return {static_cast<double>(c.b), static_cast<double>(c.g), static_cast<double>(c.r)}; }

// A header over the canvas' pixels for OpenCV to draw into; nothing is copied.
cv::Mat as_mat(std::vector<std::uint8_t>& bgr, int width, int height) { return {height, width, CV_8UC3, bgr.data()}; }

std::vector<cv::Point> fixed(std::span<const Px> points) {
  std::vector<cv::Point> out;
  out.reserve(points.size());
  for (const Px& p : points) out.push_back(fixed(p));
  return out;
}

}  // namespace

Canvas::Canvas(int width, int height, Rgb background)
    : width_(std::max(width, 1)), height_(std::max(height, 1)), background_(background),
      bgr_(static_cast<std::size_t>(width_) * static_cast<std::size_t>(height_) * 3) {
  for (std::size_t i = 0; i < bgr_.size(); i += 3) {
    bgr_[i] = background.b;
    bgr_[i + 1] = background.g;
    bgr_[i + 2] = background.r;
  }
}

Rgb Canvas::at(int x, int y) const noexcept {
  const std::size_t i = (static_cast<std::size_t>(y) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(x)) * 3;
  return {bgr_[i + 2], bgr_[i + 1], bgr_[i]};
}

void Canvas::fill_rect(int x, int y, int w, int h, Rgb colour) {
  const int x0 = std::max(x, 0), y0 = std::max(y, 0);
  const int x1 = std::min(x + w, width_), y1 = std::min(y + h, height_);
  for (int row = y0; row < y1; ++row)
    for (int col = x0; col < x1; ++col) {
      const std::size_t i = (static_cast<std::size_t>(row) * static_cast<std::size_t>(width_) + static_cast<std::size_t>(col)) * 3;
      bgr_[i] = colour.b;
      bgr_[i + 1] = colour.g;
      bgr_[i + 2] = colour.r;
    }
}

void Canvas::line(Px a, Px b, Rgb colour, int thickness) {
  cv::Mat image = as_mat(bgr_, width_, height_);
  cv::line(image, fixed(a), fixed(b), bgr(colour), thickness, cv::LINE_AA, kShift);
}

void Canvas::polyline(std::span<const Px> points, Rgb colour, int thickness) {
  if (points.size() < 2) return;
  cv::Mat image = as_mat(bgr_, width_, height_);
  const std::vector<cv::Point> pts = fixed(points);
  cv::polylines(image, pts, false, bgr(colour), thickness, cv::LINE_AA, kShift);
}

void Canvas::dashed_polyline(std::span<const Px> points, Rgb colour, int thickness, double dash_px, double gap_px) {
  const double period = dash_px + gap_px;
  if (points.size() < 2 || dash_px <= 0 || period <= 0) return;
  double phase = 0;  // distance into the current period at the segment's start
  for (std::size_t i = 1; i < points.size(); ++i) {
    const Px a = points[i - 1], b = points[i];
    const double length = std::hypot(b.x - a.x, b.y - a.y);
    double s = 0;
    while (s < length) {
      const double in_period = std::fmod(phase + s, period);
      const double step = in_period < dash_px ? dash_px - in_period : period - in_period;
      const double end = std::min(length, s + step);
      if (in_period < dash_px && length > 0) {
        const Px p{a.x + (b.x - a.x) * s / length, a.y + (b.y - a.y) * s / length};
        const Px q{a.x + (b.x - a.x) * end / length, a.y + (b.y - a.y) * end / length};
        line(p, q, colour, thickness);
      }
      s = std::max(end, s + 1e-9);  // always forward, even where rounding eats a sliver
    }
    phase = std::fmod(phase + length, period);
  }
}

void Canvas::fill_polygon(std::span<const Px> points, Rgb colour) {
  if (points.size() < 3) return;
  cv::Mat image = as_mat(bgr_, width_, height_);
  const std::vector<std::vector<cv::Point>> polygons{fixed(points)};
  cv::fillPoly(image, polygons, bgr(colour), cv::LINE_AA, kShift);
}

void Canvas::outline_polygon(std::span<const Px> points, Rgb colour, int thickness) {
  if (points.size() < 2) return;
  cv::Mat image = as_mat(bgr_, width_, height_);
  const std::vector<cv::Point> pts = fixed(points);
  cv::polylines(image, pts, true, bgr(colour), thickness, cv::LINE_AA, kShift);
}

void Canvas::disc(Px centre, double radius_px, Rgb colour) {
  cv::Mat image = as_mat(bgr_, width_, height_);
  cv::circle(image, fixed(centre), static_cast<int>(std::lround(radius_px * kOne)), bgr(colour), cv::FILLED, cv::LINE_AA,
             kShift);
}

void Canvas::ring(Px centre, double radius_px, Rgb colour, int thickness) {
  cv::Mat image = as_mat(bgr_, width_, height_);
  cv::circle(image, fixed(centre), static_cast<int>(std::lround(radius_px * kOne)), bgr(colour), thickness, cv::LINE_AA,
             kShift);
}

void Canvas::text(Px at, std::string_view s, Rgb colour, double size, int thickness, bool halo) {
  cv::Mat image = as_mat(bgr_, width_, height_);
  const std::string str(s);
  const cv::Point origin(static_cast<int>(std::lround(at.x)), static_cast<int>(std::lround(at.y)));
  if (halo) cv::putText(image, str, origin, kFont, size, bgr(background_), thickness + 3, cv::LINE_AA);
  cv::putText(image, str, origin, kFont, size, bgr(colour), thickness, cv::LINE_AA);
}

int Canvas::text_width(std::string_view s, double size, int thickness) {
  int baseline = 0;
  return cv::getTextSize(std::string(s), kFont, size, thickness, &baseline).width;
}

int Canvas::text_height(double size, int thickness) {
  int baseline = 0;
  return cv::getTextSize("H", kFont, size, thickness, &baseline).height;
}

bool Canvas::write_png(const std::string& path) const {
  return image::write_png(path, bgr_.data(), static_cast<std::uint32_t>(width_), static_cast<std::uint32_t>(height_),
                           static_cast<std::size_t>(width_) * 3, 3)
      .ok();
}

}  // namespace sen3bot::figure
