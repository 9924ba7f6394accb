#include "sen3bot/cobot/qr_reader.hpp"

#include <algorithm>
#include <cmath>
#include <cstdio>
#include <string>
#include <vector>

#include <opencv2/core.hpp>
#include <opencv2/imgproc.hpp>
#include <opencv2/objdetect.hpp>

#include "sen3bot/image/image_file.hpp"
#include "sen3bot/cobot/qr_modules.hpp"
#include "sen3bot/cobot/tag_symbol.hpp"

namespace sen3bot::cobot {

namespace {

constexpr std::uint32_t kMinFramePx = 64;
constexpr std::uint32_t kMaxFramePx = 8192;
// Corners of the codes found per search; the detector seldom finds more.
constexpr std::size_t kReservedCodes = 16;

// The centre and mean side length of a code from its four corners.
void place(const cv::Point2f* corners, float offset_u, float offset_v, msg::TagSighting& sighting) noexcept {
  float u = 0.0f;
  float v = 0.0f;
  float sides = 0.0f;
  for (int i = 0; i < 4; ++i) {
    u += corners[i].x;
    v += corners[i].y;
    const cv::Point2f edge = corners[(i + 1) % 4] - corners[i];
    sides += std::sqrt(edge.x * edge.x + edge.y * edge.y);
  }
  sighting.u_px = u / 4.0f + offset_u;
  sighting.v_px = v / 4.0f + offset_v;
  sighting.size_px = sides / 4.0f;
}

// The grey level at a point, bilinear (the module's centre seldom falls on a pixel's); false
// outside the image.
bool level_at(const cv::Mat& grey, const cv::Matx33d& h, double column, double row, float& level) {
  const cv::Vec3d p = h * cv::Vec3d(column, row, 1.0);
  if (!(p[2] > 0.0)) return false;
  const double x = p[0] / p[2];
  const double y = p[1] / p[2];
  if (!(x >= 0.0 && y >= 0.0 && x < grey.cols - 1 && y < grey.rows - 1)) return false;
  const int x0 = static_cast<int>(x);
  const int y0 = static_cast<int>(y);
  const float fx = static_cast<float>(x - x0);
  const float fy = static_cast<float>(y - y0);
  const std::uint8_t* row0 = grey.ptr<std::uint8_t>(y0) + x0;
  const std::uint8_t* row1 = grey.ptr<std::uint8_t>(y0 + 1) + x0;
  level = (1 - fy) * ((1 - fx) * row0[0] + fx * row0[1]) + fy * ((1 - fx) * row1[0] + fx * row1[1]);
  return true;
}

// Version 2's alignment pattern (dark centre, light ring, dark ring) near where the corners put
// it, searched a module and a half around in quarter modules: OpenCV extrapolates the corner
// without a finder, and under perspective that corner is the least sure. The homography is then
// taken from the three finders' corners and the pattern's centre. False when no clear pattern.
bool refine_with_alignment(const cv::Mat& grey, const cv::Point2f* to, cv::Matx33d& h) {
  constexpr double kCentre = kQrVersion2Modules - 6.5;  // module 18's centre
  double best_score = 0.0;
  double best_dc = 0.0;
  double best_dr = 0.0;
  for (double dr = -1.5; dr <= 1.5; dr += 0.25) {
    for (double dc = -1.5; dc <= 1.5; dc += 0.25) {
      float centre = 0.0f;
      if (!level_at(grey, h, kCentre + dc, kCentre + dr, centre)) return false;
      float light = 0.0f;
      float dark = centre;
      for (int i = -2; i <= 2; ++i) {
        for (int j = -2; j <= 2; ++j) {
          if (i == 0 && j == 0) continue;
          float v = 0.0f;
          if (!level_at(grey, h, kCentre + dc + j, kCentre + dr + i, v)) return false;
          if (std::abs(i) == 2 || std::abs(j) == 2) {
            dark += v;
          } else {
            light += v;
          }
        }
      }
      const double score = light / 8.0 - dark / 17.0;
      if (score > best_score) {
        best_score = score;
        best_dc = dc;
        best_dr = dr;
      }
    }
  }
  constexpr double kMinContrast = 20.0;  // grey levels between the light ring and the dark parts
  if (best_score < kMinContrast) return false;
  const cv::Vec3d p = h * cv::Vec3d(kCentre + best_dc, kCentre + best_dr, 1.0);
  const float n = static_cast<float>(kQrVersion2Modules);
  const cv::Point2f from[4] = {{0.0f, 0.0f}, {n, 0.0f}, {0.0f, n},
                               {static_cast<float>(kCentre), static_cast<float>(kCentre)}};
  const cv::Point2f image[4] = {to[0], to[1], to[3],
                                {static_cast<float>(p[0] / p[2]), static_cast<float>(p[1] / p[2])}};
  h = cv::getPerspectiveTransform(from, image);
  return true;
}

// Samples the modules through h and decodes them.
bool sample(const cv::Mat& grey, const cv::Matx33d& h, int side, std::array<std::uint8_t, 625>& modules,
            QrText& text, QrDecodeFailure& failure) {
  std::array<float, 625> level{};
  for (int r = 0; r < side; ++r) {
    for (int c = 0; c < side; ++c) {
      if (!level_at(grey, h, c + 0.5, r + 0.5, level[static_cast<std::size_t>(r * side + c)])) {
        failure = QrDecodeFailure::format;
        return false;
      }
    }
  }
  // The threshold halfway between the finders' dark cores and their light rings.
  float dark_sum = 0.0f;
  float light_sum = 0.0f;
  int light_count = 0;
  for (const auto& [r0, c0] : {std::pair{0, 0}, std::pair{0, side - 7}, std::pair{side - 7, 0}}) {
    for (int r = 2; r <= 4; ++r) {
      for (int c = 2; c <= 4; ++c) dark_sum += level[static_cast<std::size_t>((r0 + r) * side + c0 + c)];
    }
    for (int i = 1; i <= 5; ++i) {
      light_sum += level[static_cast<std::size_t>((r0 + 1) * side + c0 + i)] +
                   level[static_cast<std::size_t>((r0 + 5) * side + c0 + i)];
      light_count += 2;
    }
  }
  const float threshold = 0.5f * (dark_sum / 27.0f + light_sum / static_cast<float>(light_count));
  for (std::size_t i = 0; i < static_cast<std::size_t>(side * side); ++i) modules[i] = level[i] < threshold ? 1 : 0;
  return decode_qr_modules({modules.data(), static_cast<std::size_t>(side * side)}, side, text, failure);
}

// Samples a code's modules through the homography from its corners (as OpenCV gives them: the
// top-left finder's outer corner first, then clockwise) and decodes them, trying both sizes the
// decoder reads and each corner first (OpenCV's order is not promised for a turned code).
bool sample_and_decode(const cv::Mat& grey, const cv::Point2f* corners, std::array<std::uint8_t, 625>& modules,
                       QrText& text, QrDecodeFailure& failure) {
  failure = QrDecodeFailure::format;
  for (const int side : {kQrVersion2Modules, kQrVersion1Modules}) {
    const float n = static_cast<float>(side);
    const cv::Point2f square[4] = {{0.0f, 0.0f}, {n, 0.0f}, {n, n}, {0.0f, n}};
    for (int first = 0; first < 4; ++first) {
      const cv::Point2f to[4] = {corners[first], corners[(first + 1) % 4], corners[(first + 2) % 4],
                                 corners[(first + 3) % 4]};
      cv::Matx33d h = cv::getPerspectiveTransform(square, to);
      QrDecodeFailure why = QrDecodeFailure::format;
      if (sample(grey, h, side, modules, text, why)) return true;
      // Past the format check, the size and the first corner were right: mend the far corner.
      if (why != QrDecodeFailure::format) {
        failure = why;
        if (side == kQrVersion2Modules && refine_with_alignment(grey, to, h) &&
            sample(grey, h, side, modules, text, why)) {
          return true;
        }
        return false;
      }
    }
  }
  return false;
}

}  // namespace

struct QrReader::Impl {
  cv::QRCodeDetector detector;
  cv::Mat grey;  // the whole frame's size; a search uses the ROI's part of it
  std::vector<cv::Point2f> corners;
  std::array<std::uint8_t, 625> modules{};
};

QrReader::QrReader() = default;
QrReader::~QrReader() = default;

std::uint64_t QrReader::undecoded_total() const noexcept {
  std::uint64_t total = 0;
  for (const std::uint64_t n : undecoded_) total += n;
  return total;
}

std::uint64_t QrReader::refused_total() const noexcept {
  std::uint64_t total = 0;
  for (const std::uint64_t n : refused_) total += n;
  return total;
}

Status QrReader::init(std::uint32_t width_px, std::uint32_t height_px, const QrReaderConfig& config) {
  if (width_px < kMinFramePx || height_px < kMinFramePx || width_px > kMaxFramePx || height_px > kMaxFramePx ||
      config.min_roi_px < 32 || !(config.smoothing_sigma_px >= 0.0 && config.smoothing_sigma_px <= 5.0)) {
    return Error::format(Errc::config,
                         "qr reader: frames of %ux%u (each side %u..%u px), min_roi_px %d (>= 32), smoothing_sigma_px "
                         "%.2f (0..5)",
                         width_px, height_px, kMinFramePx, kMaxFramePx, config.min_roi_px, config.smoothing_sigma_px);
  }
  try {
    auto impl = std::make_unique<Impl>();
    impl->grey.create(static_cast<int>(height_px), static_cast<int>(width_px), CV_8UC1);
    impl->corners.reserve(4 * kReservedCodes);
    impl_ = std::move(impl);
  } catch (const std::exception& e) {
    return Error::format(Errc::capacity, "qr reader: %s", e.what());
  }
  config_ = config;
  width_px_ = width_px;
  height_px_ = height_px;
  frames_ = tags_read_ = overflow_ = bad_frames_ = errors_ = 0;
  refused_.fill(0);
  undecoded_.fill(0);
  return Status::success();
}

std::size_t QrReader::read(const camera::FrameRef& frame, msg::TagFrame& out) noexcept {
  return read(frame, PixelRect{0, 0, static_cast<std::int32_t>(width_px_), static_cast<std::int32_t>(height_px_)}, out);
}

std::size_t QrReader::read(const camera::FrameRef& frame, const PixelRect& roi, msg::TagFrame& out) noexcept {
  out.count = 0;
  out.frame_sequence = frame.sequence;
  out.capture_ns = frame.last_packet_ns;
  const std::size_t bpp = camera::bytes_per_pixel(frame.format);
  if (!impl_ || frame.data == nullptr || frame.width_px != width_px_ || frame.height_px != height_px_ ||
      frame.stride_bytes < static_cast<std::uint64_t>(frame.width_px) * bpp) {
    ++bad_frames_;
    return 0;
  }
  // The ROI, widened to the detector's working size where the frame allows, then cut to the frame.
  const std::int64_t frame_w = width_px_;
  const std::int64_t frame_h = height_px_;
  std::int64_t u0 = roi.u_px;
  std::int64_t v0 = roi.v_px;
  std::int64_t u1 = u0 + std::max<std::int64_t>(roi.width_px, 0);
  std::int64_t v1 = v0 + std::max<std::int64_t>(roi.height_px, 0);
  if (u1 <= 0 || v1 <= 0 || u0 >= frame_w || v0 >= frame_h || u1 <= u0 || v1 <= v0) return 0;
  const auto widen = [](std::int64_t& lo, std::int64_t& hi, std::int64_t min_size, std::int64_t limit) {
    if (hi - lo >= min_size) return;
    const std::int64_t grow = min_size - (hi - lo);
    lo -= grow / 2;
    hi += grow - grow / 2;
    if (lo < 0) {
      hi -= lo;
      lo = 0;
    }
    if (hi > limit) {
      lo -= hi - limit;
      hi = limit;
    }
  };
  widen(u0, u1, config_.min_roi_px, frame_w);
  widen(v0, v1, config_.min_roi_px, frame_h);
  u0 = std::clamp<std::int64_t>(u0, 0, frame_w);
  v0 = std::clamp<std::int64_t>(v0, 0, frame_h);
  u1 = std::clamp<std::int64_t>(u1, 0, frame_w);
  v1 = std::clamp<std::int64_t>(v1, 0, frame_h);
  const cv::Rect area(static_cast<int>(u0), static_cast<int>(v0), static_cast<int>(u1 - u0), static_cast<int>(v1 - v0));
  ++frames_;
  Impl& m = *impl_;
  try {
    // A view of the caller's pixels: OpenCV does not write through it.
    const cv::Mat whole(static_cast<int>(height_px_), static_cast<int>(width_px_),
                        frame.format == camera::PixelFormat::bgr8 ? CV_8UC3 : CV_8UC1,
                        const_cast<std::uint8_t*>(frame.data), frame.stride_bytes);
    cv::Mat grey = m.grey(area);
    if (frame.format == camera::PixelFormat::bgr8) {
      cv::cvtColor(whole(area), grey, cv::COLOR_BGR2GRAY);
    } else {
      whole(area).copyTo(grey);
    }
    // OpenCV's finder search thresholds against the local mean less 2 grey levels: sensor noise
    // on the white paper would break the finders' 1:1:3:1:1 runs, so it is smoothed first.
    if (config_.smoothing_sigma_px > 0.0) cv::GaussianBlur(grey, grey, cv::Size(0, 0), config_.smoothing_sigma_px);
    m.corners.clear();
    // OpenCV finds the codes' corners; it cannot decode them (Debian builds it without quirc).
    const bool found = config_.search == QrReaderConfig::Search::every_code ? m.detector.detectMulti(grey, m.corners)
                                                                            : m.detector.detect(grey, m.corners);
    const std::size_t codes = found ? m.corners.size() / 4 : 0;
    for (std::size_t c = 0; c < codes; ++c) {
      QrText text;
      QrDecodeFailure failure = QrDecodeFailure::format;
      if (!sample_and_decode(grey, &m.corners[4 * c], m.modules, text, failure)) {
        ++undecoded_[static_cast<std::size_t>(failure)];
        continue;
      }
      Tag tag;
      TagRefusal why = TagRefusal::foreign;
      if (!check_tag(text.text(), tag, why)) {
        ++refused_[static_cast<std::size_t>(why)];
        continue;
      }
      if (out.count >= msg::TagFrame::kMax) {
        ++overflow_;
        continue;
      }
      msg::TagSighting& sighting = out.tags[out.count++];
      sighting.operator_id = tag.operator_id;
      sighting.side = tag.side;
      place(&m.corners[4 * c], static_cast<float>(u0), static_cast<float>(v0), sighting);
      ++tags_read_;
    }
  } catch (const std::exception&) {
    // cv::Exception or bad_alloc: this frame reads nothing; the next is tried afresh.
    ++errors_;
    out.count = 0;
  }
  return out.count;
}

namespace detail {

Status tag_symbol(const Tag& tag, cv::Mat& modules) {
  Result<TagPayload> payload = encode_tag(tag);
  if (!payload) return payload.error();
  try {
    cv::QRCodeEncoder::Params params;
    params.correction_level = cv::QRCodeEncoder::CORRECT_LEVEL_H;
    params.mode = cv::QRCodeEncoder::MODE_ALPHANUMERIC;
    params.version = kTagQrVersion;
    cv::Mat encoded;
    cv::QRCodeEncoder::create(params)->encode(payload->c_str(), encoded);
    // OpenCV's encoder may add a white margin of its own: the symbol is what lies between the
    // outermost dark modules (the finder patterns' corners).
    cv::Mat dark;
    if (!encoded.empty()) cv::compare(encoded, 128, dark, cv::CMP_LT);
    const cv::Rect box = dark.empty() ? cv::Rect() : cv::boundingRect(dark);
    if (box.width != kTagQrModules || box.height != kTagQrModules) {
      return Error::format(Errc::io, "tag: the QR encoder gave a %dx%d symbol for %s, expected %dx%d", box.width,
                           box.height, payload->c_str(), kTagQrModules, kTagQrModules);
    }
    encoded(box).copyTo(modules);
  } catch (const cv::Exception& e) {
    return Error::format(Errc::io, "tag: the QR encoder failed: %s", e.what());
  }
  return Status::success();
}

}  // namespace detail

Status write_tag_png(const Tag& tag, const std::string& path, int module_px) {
  constexpr int kMinModulePx = 2;
  constexpr int kMaxModulePx = 200;
  constexpr int kQuietModules = 4;  // ISO/IEC 18004's quiet zone
  if (module_px < kMinModulePx || module_px > kMaxModulePx) {
    return Error::format(Errc::invalid_argument, "tag png: module_px %d is outside %d..%d", module_px, kMinModulePx,
                         kMaxModulePx);
  }
  cv::Mat symbol;
  if (Status s = detail::tag_symbol(tag, symbol); !s) return s;
  try {
    cv::Mat code;
    cv::resize(symbol, code, cv::Size(), module_px, module_px, cv::INTER_NEAREST);
    const int quiet_px = kQuietModules * module_px;
    const int side_px = code.cols + 2 * quiet_px;
    char caption[48];
    std::snprintf(caption, sizeof caption, "operator %u %s", tag.operator_id, side_name(tag.side));
    // The caption as wide as about two thirds of the code, under it in the quiet zone's height.
    const int font = cv::FONT_HERSHEY_SIMPLEX;
    int baseline = 0;
    const cv::Size unit = cv::getTextSize(caption, font, 1.0, 1, &baseline);
    const double scale = 0.66 * code.cols / unit.width;
    const int thickness = std::max(1, static_cast<int>(std::lround(scale * 2.0)));
    const cv::Size text = cv::getTextSize(caption, font, scale, thickness, &baseline);
    const int caption_px = text.height + baseline + quiet_px;
    cv::Mat page(side_px + caption_px, side_px, CV_8UC1, cv::Scalar(255));
    code.copyTo(page(cv::Rect(quiet_px, quiet_px, code.cols, code.rows)));
    cv::putText(page, caption, cv::Point((side_px - text.width) / 2, side_px + text.height), font, scale,
                cv::Scalar(0), thickness, cv::LINE_AA);
    if (Status s = image::write_png(path, page.data, static_cast<std::uint32_t>(page.cols),
                                     static_cast<std::uint32_t>(page.rows), page.step, 1);
        !s) {
      return Error::format(Errc::io, "tag png: %s", s.error().c_str());
    }
  } catch (const cv::Exception& e) {
    return Error::format(Errc::io, "tag png: %s: %s", path.c_str(), e.what());
  }
  return Status::success();
}

}  // namespace sen3bot::cobot
