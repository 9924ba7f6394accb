#include "sen3bot/sim/cobot/tag_scene.hpp"

#include <algorithm>
#include <cmath>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/objdetect.hpp>

#include "sen3bot/cobot/qr_reader.hpp"
#include "sen3bot/cobot/tag_symbol.hpp"

namespace sen3bot::cobot {

namespace {

constexpr double kPi = 3.14159265358979323846;
constexpr int kQuietModules = 4;
constexpr int kSourcePxPerModule = 6;  // the tag image warped onto the frame
// Printed paper under plant lighting: white is not 255 nor black 0.
constexpr double kPaperWhite = 215.0;
constexpr double kInkBlack = 28.0;
constexpr std::size_t kCachedTags = 8;
// An operator's legs: the tag is on one leg's surface, the other leg beside it.
constexpr double kLegWidthM = 0.14;
constexpr double kLegSpacingM = 0.22;
constexpr double kHipAboveFloorM = 0.9;
constexpr double kTorsoWidthM = 0.42;
constexpr double kTorsoTopAboveFloorM = 1.5;
// The plant's own code on the wall: left of where operators stand, at the laser's height.
constexpr double kWallCodeLeftM = 0.5;

struct CachedTag {
  Tag tag;
  bool used = false;
  cv::Mat image;  // BGR, symbol and quiet zone, kSourcePxPerModule a module
};

}  // namespace

struct TagSceneRenderer::Impl {
  nav::CameraProjection projection;
  SceneOptions options;
  cv::RNG rng;
  cv::Mat background;  // BGR
  cv::Mat frame;       // BGR
  cv::Mat noise;       // CV_16SC3
  cv::Mat wide;        // CV_16SC3
  cv::Mat motion_kernel;
  cv::Mat shaded;
  std::array<CachedTag, kCachedTags> cache{};
  std::size_t next_slot = 0;

  // The tag's code image, encoded once per payload while it stays among the recent ones.
  const cv::Mat* image(const Tag& tag) {
    for (CachedTag& c : cache) {
      if (c.used && c.tag.operator_id == tag.operator_id && c.tag.side == tag.side) return &c.image;
    }
    cv::Mat symbol;
    if (!detail::tag_symbol(tag, symbol)) return nullptr;
    CachedTag& slot = cache[next_slot];
    next_slot = (next_slot + 1) % cache.size();
    cv::Mat padded;
    cv::copyMakeBorder(symbol, padded, kQuietModules, kQuietModules, kQuietModules, kQuietModules,
                       cv::BORDER_CONSTANT, cv::Scalar(255));
    cv::Mat big;
    cv::resize(padded, big, cv::Size(), kSourcePxPerModule, kSourcePxPerModule, cv::INTER_NEAREST);
    big.convertTo(big, CV_8U, (kPaperWhite - kInkBlack) / 255.0, kInkBlack);
    cv::cvtColor(big, slot.image, cv::COLOR_GRAY2BGR);
    slot.tag = tag;
    slot.used = true;
    return &slot.image;
  }

  // A point in the laser's frame to pixels; false behind the camera.
  bool pixel(double forward_m, double left_m, double up_m, cv::Point2f& p) const noexcept {
    double u = 0.0;
    double v = 0.0;
    if (!projection.project_point(forward_m, left_m, up_m, u, v)) return false;
    p = cv::Point2f(static_cast<float>(u), static_cast<float>(v));
    return true;
  }

  // A vertical rectangle facing along (normal_x, normal_y): centre, half widths. Corners from
  // the top left as the camera sees it (clockwise). False when a corner is behind the camera.
  bool quad(double cx, double cy, double cz, double right_x, double right_y, double half_w, double up_lo,
            double up_hi, std::array<cv::Point2f, 4>& out) const noexcept {
    return pixel(cx - right_x * half_w, cy - right_y * half_w, cz + up_hi, out[0]) &&
           pixel(cx + right_x * half_w, cy + right_y * half_w, cz + up_hi, out[1]) &&
           pixel(cx + right_x * half_w, cy + right_y * half_w, cz + up_lo, out[2]) &&
           pixel(cx - right_x * half_w, cy - right_y * half_w, cz + up_lo, out[3]);
  }

  void fill(const std::array<cv::Point2f, 4>& corners, const cv::Scalar& colour) {
    std::array<cv::Point, 4> points;
    for (std::size_t i = 0; i < 4; ++i) points[i] = cv::Point(cvRound(corners[i].x), cvRound(corners[i].y));
    cv::fillConvexPoly(frame, points.data(), 4, colour, cv::LINE_AA);
  }

  void draw_background();
  void draw_line(double f0, double l0, double f1, double l1, double up, const cv::Scalar& colour, int thickness);
  bool draw_tag(const SceneTag& tag);
  // The tag's outline with its quiet zone (top left first, clockwise as the camera sees it).
  bool tag_corners(const SceneTag& tag, std::array<cv::Point2f, 4>& corners) const noexcept;
  // The direction from the tag to the camera (near enough the laser's origin), turned by the
  // tag's facing, is its normal; its right edge, as the camera sees it, is the normal turned a
  // quarter counter-clockwise.
  static double normal_rad(const SceneTag& t) noexcept { return std::atan2(-t.left_m, -t.forward_m) + t.facing_rad; }
  void warp(const cv::Mat& source, const std::array<cv::Point2f, 4>& corners);
};

void TagSceneRenderer::Impl::draw_line(double f0, double l0, double f1, double l1, double up, const cv::Scalar& colour,
                                       int thickness) {
  cv::Point2f a;
  cv::Point2f b;
  if (!pixel(f0, l0, up, a) || !pixel(f1, l1, up, b)) return;
  cv::line(frame, cv::Point(cvRound(a.x), cvRound(a.y)), cv::Point(cvRound(b.x), cvRound(b.y)), colour, thickness,
           cv::LINE_AA);
}

void TagSceneRenderer::Impl::draw_background() {
  // Drawn into `frame`, then kept as the background.
  const double wall = options.wall_distance_m;
  const double floor_up = -options.laser_height_m;
  constexpr double kNearM = 0.15;   // the floor seen nearest the robot (the image's bottom is farther)
  constexpr double kHalfWidthM = 8.0;
  const auto jitter = [&](double base, double spread) { return base + rng.uniform(-spread, spread); };
  // A grey of `base` tinted per channel, drawn in a fixed order (see the shelves' boxes below).
  const auto shade = [&](double base, double spread, double tint) {
    const double third = jitter(0, tint);
    const double second = jitter(0, tint);
    const double first = jitter(0, tint);
    return cv::Scalar::all(jitter(base, spread)) + cv::Scalar(first, second, third);
  };
  frame.setTo(shade(160, 25, 8));  // the wall
  std::array<cv::Point2f, 4> floor{};
  if (pixel(wall, kHalfWidthM, floor_up, floor[0]) && pixel(wall, -kHalfWidthM, floor_up, floor[1]) &&
      pixel(kNearM, -kHalfWidthM, floor_up, floor[2]) && pixel(kNearM, kHalfWidthM, floor_up, floor[3])) {
    fill(floor, shade(105, 20, 6));
  }
  // Floor tiles, 0.6 m.
  const cv::Scalar seam(80, 84, 86);
  for (double f = 0.6; f < wall; f += 0.6) draw_line(f, -kHalfWidthM, f, kHalfWidthM, floor_up, seam, 1);
  for (double l = -kHalfWidthM; l <= kHalfWidthM; l += 0.6) draw_line(kNearM, l, wall, l, floor_up, seam, 1);
  // A yellow safety stripe across the floor somewhere between the operator and the wall.
  const double stripe = rng.uniform(1.6, std::max(1.7, wall - 0.5));
  for (double w = 0.0; w < 0.08; w += 0.01) {
    draw_line(stripe + w, -kHalfWidthM, stripe + w, kHalfWidthM, floor_up, cv::Scalar(30, 190, 215), 2);
  }
  // Wall panels (1.2 m), a skirting board, shelves with boxes on them.
  for (double l = -kHalfWidthM; l <= kHalfWidthM; l += 1.2) {
    cv::Point2f a;
    cv::Point2f b;
    if (pixel(wall, l, floor_up, a) && pixel(wall, l, floor_up + 3.0, b)) {
      cv::line(frame, a, b, cv::Scalar(120, 128, 130), 2, cv::LINE_AA);
    }
  }
  draw_line(wall, -kHalfWidthM, wall, kHalfWidthM, floor_up + 0.12, cv::Scalar(60, 60, 62), 3);
  for (int box = 0; box < 14; ++box) {
    const double l = rng.uniform(-3.0, 3.0);
    const double w = rng.uniform(0.15, 0.6);
    const double lo = floor_up + rng.uniform(0.0, 1.2);
    const double h = rng.uniform(0.1, 0.5);
    std::array<cv::Point2f, 4> corners{};
    if (quad(wall - 0.05, l, 0.0, 0.0, -1.0, w / 2, lo, lo + h, corners)) {
      // Drawn in a fixed order (a function's arguments are evaluated in an order each compiler
      // chooses: GCC's last to first is kept, so the scenes stay as they were).
      const int red = rng.uniform(30, 200);
      const int green = rng.uniform(30, 200);
      const int blue = rng.uniform(30, 200);
      fill(corners, cv::Scalar(blue, green, red));
    }
  }
  if (!options.wall_code.empty()) {
    cv::QRCodeEncoder::Params params;
    params.correction_level = cv::QRCodeEncoder::CORRECT_LEVEL_M;
    cv::Mat code;
    cv::QRCodeEncoder::create(params)->encode(options.wall_code, code);
    if (!code.empty()) {
      cv::Mat padded;
      cv::copyMakeBorder(code, padded, 2, 2, 2, 2, cv::BORDER_CONSTANT, cv::Scalar(255));
      cv::Mat big;
      cv::resize(padded, big, cv::Size(), kSourcePxPerModule, kSourcePxPerModule, cv::INTER_NEAREST);
      big.convertTo(big, CV_8U, (kPaperWhite - kInkBlack) / 255.0, kInkBlack);
      cv::Mat source;
      cv::cvtColor(big, source, cv::COLOR_GRAY2BGR);
      std::array<cv::Point2f, 4> corners{};
      const double half = options.wall_code_side_m / 2;
      if (quad(wall - 0.06, kWallCodeLeftM, 0.0, 0.0, -1.0, half, -half, half, corners)) warp(source, corners);
    }
  }
  // Uneven light (a coarse random gain field) and the sensor's fixed-pattern texture.
  cv::Mat coarse(6, 10, CV_32FC1);
  rng.fill(coarse, cv::RNG::UNIFORM, 0.8, 1.15);
  cv::Mat light;
  cv::resize(coarse, light, frame.size(), 0, 0, cv::INTER_CUBIC);
  cv::Mat light3;
  cv::cvtColor(light, light3, cv::COLOR_GRAY2BGR);
  cv::Mat lit;
  frame.convertTo(lit, CV_32FC3);
  cv::multiply(lit, light3, lit);
  cv::Mat texture(frame.size(), CV_32FC3);
  rng.fill(texture, cv::RNG::NORMAL, 0.0, 5.0);
  cv::GaussianBlur(texture, texture, cv::Size(0, 0), 1.2);
  lit += texture;
  lit.convertTo(background, CV_8UC3);
}

void TagSceneRenderer::Impl::warp(const cv::Mat& source, const std::array<cv::Point2f, 4>& corners) {
  const cv::Rect bounds = cv::boundingRect(std::vector<cv::Point2f>(corners.begin(), corners.end())) &
                          cv::Rect(0, 0, frame.cols, frame.rows);
  if (bounds.width <= 0 || bounds.height <= 0) return;
  const float w = static_cast<float>(source.cols);
  const float h = static_cast<float>(source.rows);
  const std::array<cv::Point2f, 4> from = {cv::Point2f(0, 0), cv::Point2f(w, 0), cv::Point2f(w, h), cv::Point2f(0, h)};
  std::array<cv::Point2f, 4> to{};
  for (std::size_t i = 0; i < 4; ++i) to[i] = corners[i] - cv::Point2f(static_cast<float>(bounds.x), static_cast<float>(bounds.y));
  const cv::Mat homography = cv::getPerspectiveTransform(from.data(), to.data());
  // Transparent border: only the tag's own pixels change.
  cv::Mat target = frame(bounds);
  cv::warpPerspective(source, target, homography, bounds.size(), cv::INTER_LINEAR, cv::BORDER_TRANSPARENT);
}

bool TagSceneRenderer::Impl::tag_corners(const SceneTag& t, std::array<cv::Point2f, 4>& corners) const noexcept {
  const double half = t.side_m / 2.0 * (kTagQrModules + 2 * kQuietModules) / kTagQrModules;
  const double normal = normal_rad(t);
  return quad(t.forward_m, t.left_m, t.up_m, -std::sin(normal), std::cos(normal), half, -half, half, corners);
}

bool TagSceneRenderer::Impl::draw_tag(const SceneTag& t) {
  const double normal = normal_rad(t);
  const double right_x = -std::sin(normal);
  const double right_y = std::cos(normal);
  const double facing = std::remainder(t.facing_rad, 2.0 * kPi);
  const double cos_facing = std::cos(facing);
  if (options.body) {
    // The operator's colours follow their id, so a front and back tag draw the same person.
    const std::uint32_t h = t.tag.operator_id * 2654435761u;
    const cv::Scalar trousers(35 + (h & 0x1F), 35 + ((h >> 5) & 0x1F), 40 + ((h >> 10) & 0x1F));
    const double floor_up = -options.laser_height_m;
    const double hip_up = floor_up + kHipAboveFloorM;
    // Behind the tag (away from the camera) by half a leg.
    const double cx = t.forward_m + std::cos(normal) * -0.5 * kLegWidthM;
    const double cy = t.left_m + std::sin(normal) * -0.5 * kLegWidthM;
    std::array<cv::Point2f, 4> corners{};
    const double other = (h & 0x100) != 0 ? kLegSpacingM : -kLegSpacingM;
    if (quad(cx + right_x * other, cy + right_y * other, 0.0, right_x, right_y, kLegWidthM / 2, floor_up, hip_up,
             corners)) {
      fill(corners, trousers * 0.85);
    }
    if (quad(cx + right_x * other / 2, cy + right_y * other / 2, 0.0, right_x, right_y, kTorsoWidthM / 2, hip_up - 0.1,
             floor_up + kTorsoTopAboveFloorM, corners)) {
      fill(corners, cv::Scalar(60 + ((h >> 15) & 0x3F), 50 + ((h >> 21) & 0x3F), 45 + ((h >> 26) & 0x1F)));
    }
    if (quad(cx, cy, 0.0, right_x, right_y, kLegWidthM / 2, floor_up, hip_up, corners)) fill(corners, trousers);
  }
  if (!(cos_facing > 0.0)) return true;  // its back to the camera: the leg hides it
  const cv::Mat* code = image(t.tag);
  if (code == nullptr) return false;
  std::array<cv::Point2f, 4> corners{};
  if (!tag_corners(t, corners)) return true;
  // Lambertian-ish: a tag turned from the light (near the camera) is darker.
  const double shade = 0.55 + 0.45 * cos_facing;
  if (std::abs(facing) > kReadableFacingRad) {
    fill(corners, cv::Scalar::all(kPaperWhite * shade));
    return true;
  }
  code->convertTo(shaded, CV_8UC3, shade);
  warp(shaded, corners);
  return true;
}

TagSceneRenderer::TagSceneRenderer() = default;
TagSceneRenderer::~TagSceneRenderer() = default;

Status TagSceneRenderer::init(const nav::CameraCalibration& calibration, std::uint64_t seed,
                              const SceneOptions& options) {
  impl_.reset();
  if (!(options.laser_height_m > 0.0) || !(options.wall_distance_m > 1.0) || !(options.defocus_sigma_px >= 0.0) ||
      !(options.motion_blur_px >= 0.0 && options.motion_blur_px <= 64.0) || !(options.noise_sigma >= 0.0) ||
      !(options.gain > 0.0) || !std::isfinite(options.offset) || !(options.wall_code_side_m > 0.0)) {
    return Error::format(Errc::config, "tag scene: laser_height_m > 0, wall_distance_m > 1, defocus_sigma_px >= 0, "
                                       "0 <= motion_blur_px <= 64, noise_sigma >= 0, gain > 0, wall_code_side_m > 0");
  }
  auto impl = std::make_unique<Impl>();
  if (Status s = impl->projection.set(calibration); !s) return s;
  impl->options = options;
  impl->rng = cv::RNG(seed == 0 ? 0x5EED : seed);  // cv::RNG treats 0 as its own default
  try {
    const cv::Size size(calibration.width_px, calibration.height_px);
    impl->frame.create(size, CV_8UC3);
    impl->noise.create(size, CV_16SC3);
    impl->wide.create(size, CV_16SC3);
    const int motion = static_cast<int>(std::lround(options.motion_blur_px));
    if (motion >= 2) impl->motion_kernel = cv::Mat::ones(1, motion, CV_32FC1) / static_cast<float>(motion);
    impl->draw_background();
  } catch (const cv::Exception& e) {
    return Error::format(Errc::capacity, "tag scene: %s", e.what());
  }
  width_px_ = static_cast<std::uint32_t>(calibration.width_px);
  height_px_ = static_cast<std::uint32_t>(calibration.height_px);
  impl_ = std::move(impl);
  return Status::success();
}

bool TagSceneRenderer::centre_px(const SceneTag& tag, double& u_px, double& v_px) const noexcept {
  return impl_ && impl_->projection.project_point(tag.forward_m, tag.left_m, tag.up_m, u_px, v_px);
}

bool TagSceneRenderer::in_view(const SceneTag& tag) const noexcept {
  std::array<cv::Point2f, 4> corners{};
  if (!impl_ || !impl_->tag_corners(tag, corners)) return false;
  for (const cv::Point2f& p : corners) {
    if (!(p.x >= 0.0f && p.y >= 0.0f && p.x <= static_cast<float>(width_px_ - 1) &&
          p.y <= static_cast<float>(height_px_ - 1))) {
      return false;
    }
  }
  return true;
}

bool TagSceneRenderer::render(std::span<const SceneTag> tags, std::span<std::uint8_t> pixels,
                              std::uint32_t stride_bytes, camera::PixelFormat format) {
  const std::uint64_t row_bytes = static_cast<std::uint64_t>(width_px_) * camera::bytes_per_pixel(format);
  if (!impl_ || tags.size() > kMaxTags || stride_bytes < row_bytes ||
      pixels.size() < static_cast<std::uint64_t>(stride_bytes) * (height_px_ - 1) + row_bytes) {
    return false;
  }
  for (const SceneTag& t : tags) {
    if (t.tag.operator_id == 0 || t.tag.operator_id > kMaxOperatorId || !(t.side_m > 0.0)) return false;
  }
  Impl& m = *impl_;
  try {
    m.background.copyTo(m.frame);
    // Farthest first, so nearer operators cover them.
    // An insertion sort of at most kMaxTags: std::sort on part of the array trips GCC 12's
    // bounds warning under the sanitizers.
    const std::size_t n = std::min(tags.size(), kMaxTags);
    std::array<std::size_t, kMaxTags> order{};
    for (std::size_t i = 0; i < n; ++i) order[i] = i;
    const auto range = [&](std::size_t i) { return std::hypot(tags[i].forward_m, tags[i].left_m); };
    for (std::size_t i = 1; i < n; ++i)
      for (std::size_t j = i; j > 0 && range(order[j - 1]) < range(order[j]); --j) std::swap(order[j - 1], order[j]);
    for (std::size_t k = 0; k < n; ++k) {
      if (!m.draw_tag(tags[order[k]])) return false;
    }
    const SceneOptions& o = m.options;
    if (o.gain != 1.0 || o.offset != 0.0) m.frame.convertTo(m.frame, CV_8UC3, o.gain, o.offset);
    if (!m.motion_kernel.empty()) cv::filter2D(m.frame, m.frame, -1, m.motion_kernel);
    if (o.defocus_sigma_px > 0.0) cv::GaussianBlur(m.frame, m.frame, cv::Size(0, 0), o.defocus_sigma_px);
    if (o.noise_sigma > 0.0) {
      m.rng.fill(m.noise, cv::RNG::NORMAL, 0.0, o.noise_sigma);
      m.frame.convertTo(m.wide, CV_16SC3);
      m.wide += m.noise;
      m.wide.convertTo(m.frame, CV_8UC3);
    }
    cv::Mat out(static_cast<int>(height_px_), static_cast<int>(width_px_),
                format == camera::PixelFormat::bgr8 ? CV_8UC3 : CV_8UC1, pixels.data(), stride_bytes);
    if (format == camera::PixelFormat::bgr8) {
      m.frame.copyTo(out);
    } else {
      cv::cvtColor(m.frame, out, cv::COLOR_BGR2GRAY);
    }
  } catch (const cv::Exception&) {
    return false;
  }
  return true;
}

}  // namespace sen3bot::cobot
