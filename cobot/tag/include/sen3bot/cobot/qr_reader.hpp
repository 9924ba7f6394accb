#pragma once
// Reading operators' tags in camera frames, and writing the printable tags. OpenCV's QR code
// detector finds the codes' corners; the modules are sampled here and decoded by
// decode_qr_modules (qr_modules.hpp), since Debian's OpenCV cannot decode.
//
// Cost: a 1280 x 720 frame takes milliseconds to tens of milliseconds (docs/cobot/tags.md has
// the measured numbers), and OpenCV allocates its own scratch on every call, so read() runs on
// a background (non-real-time) thread row, as the HOG people detector does. Its own buffers
// (the grey image) are allocated once, at init().
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <string>

#include "sen3bot/camera/frame_pool.hpp"
#include "sen3bot/cobot/qr_modules.hpp"
#include "sen3bot/cobot/tag.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/msg/cobot.hpp"

namespace sen3bot::cobot {

// A rectangle of a frame's pixels: columns u_px .. u_px + width_px - 1, rows v_px ..
// v_px + height_px - 1. Parts outside the frame are cut off.
struct PixelRect {
  std::int32_t u_px = 0;
  std::int32_t v_px = 0;
  std::int32_t width_px = 0;
  std::int32_t height_px = 0;
};

struct QrReaderConfig {
  // How OpenCV searches a frame for codes: every code in it (detectMulti), or the one it finds
  // first (detect). Measured on the simulated frames (docs/cobot/tags.md), first_code is both
  // faster and far more reliable (98-100 % against 80-91 % within 0.5-1 m); it reads one
  // operator per frame, the one the trigger wants, standing in front of the robot.
  enum class Search : std::uint8_t { every_code, first_code };
  Search search = Search::first_code;
  // An ROI narrower or shorter than this is widened around its centre: OpenCV enlarges small
  // images to about 512 px before searching, so a smaller ROI costs the same and sees less.
  std::int32_t min_roi_px = 512;
  // Gaussian smoothing of the grey image before the search (0: none); see qr_reader.cpp.
  double smoothing_sigma_px = 1.0;
};

class QrReader {
 public:
  QrReader();
  ~QrReader();
  QrReader(const QrReader&) = delete;
  QrReader& operator=(const QrReader&) = delete;

  // For frames of width x height (both 64..8192): allocates the grey image. May be called
  // again for another frame size; the counters start again.
  Status init(std::uint32_t width_px, std::uint32_t height_px, const QrReaderConfig& config = {});

  // The tags in a whole frame (bgr8 or gray8). Fills out.tags[0..count) with each tag's
  // operator, side, centre and mean side length in the frame's pixels (at most
  // TagFrame::kMax; more are counted as overflow), out.frame_sequence = frame.sequence and
  // out.capture_ns = frame.last_packet_ns (the arrival of the frame's last packet: the
  // nearest to when the picture was taken). Returns out.count. A frame of another size than
  // init's, a frame without pixels or a reader not initialised reads nothing and counts a
  // bad frame. Codes that are not tags are counted by their refusal. Never throws.
  std::size_t read(const camera::FrameRef& frame, msg::TagFrame& out) noexcept;
  // The same in a part of the frame only (where an operator's knees can be): cheaper when the
  // part is small. Positions are still in the whole frame's pixels. An ROI wholly outside the
  // frame reads nothing (and is not a bad frame).
  std::size_t read(const camera::FrameRef& frame, const PixelRect& roi, msg::TagFrame& out) noexcept;

  // --- counters, since init ------------------------------------------------------------------
  [[nodiscard]] std::uint64_t frames() const noexcept { return frames_; }          // read() calls that searched
  [[nodiscard]] std::uint64_t tags_read() const noexcept { return tags_read_; }    // tags put in a TagFrame
  [[nodiscard]] std::uint64_t refused(TagRefusal why) const noexcept {            // codes that were not tags
    return refused_[static_cast<std::size_t>(why)];
  }
  [[nodiscard]] std::uint64_t refused_total() const noexcept;
  // Codes found but not read, by why (QrDecodeFailure): too blurred, too oblique, too big.
  [[nodiscard]] std::uint64_t undecoded(QrDecodeFailure why) const noexcept {
    return undecoded_[static_cast<std::size_t>(why)];
  }
  [[nodiscard]] std::uint64_t undecoded_total() const noexcept;
  [[nodiscard]] std::uint64_t overflow() const noexcept { return overflow_; }      // tags beyond TagFrame::kMax
  [[nodiscard]] std::uint64_t bad_frames() const noexcept { return bad_frames_; }  // wrong size/format, not initialised
  [[nodiscard]] std::uint64_t errors() const noexcept { return errors_; }          // OpenCV failed (an exception)
  [[nodiscard]] const QrReaderConfig& config() const noexcept { return config_; }

 private:
  struct Impl;
  std::unique_ptr<Impl> impl_;
  QrReaderConfig config_;
  std::uint32_t width_px_ = 0;
  std::uint32_t height_px_ = 0;
  std::uint64_t frames_ = 0;
  std::uint64_t tags_read_ = 0;
  std::array<std::uint64_t, kTagRefusals> refused_{};
  std::array<std::uint64_t, kQrDecodeFailures> undecoded_{};
  std::uint64_t overflow_ = 0;
  std::uint64_t bad_frames_ = 0;
  std::uint64_t errors_ = 0;
};

// Writes a printable tag as PNG: the code at module_px pixels a module (2..200), its 4-module
// white quiet zone, and a caption under it ("operator 42 FRONT") for the people handing tags
// out. At 300 dpi, module_px 47 prints the code (without the quiet zone) 10 cm wide.
// Errc::invalid_argument for a bad tag or module size, Errc::io when the file cannot be written.
Status write_tag_png(const Tag& tag, const std::string& path, int module_px);

// The tags' QR symbol: version 2 (25 x 25 modules) at error correction level H (30 % of the
// code may be lost), the payload in alphanumeric mode.
inline constexpr int kTagQrVersion = 2;
inline constexpr int kTagQrModules = 25;

// The module size at which a 10 cm code prints at 300 dpi (docs/cobot/tags.md).
inline constexpr int kPrintModulePx = 47;

}  // namespace sen3bot::cobot
