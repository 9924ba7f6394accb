#pragma once
// A baseline JPEG encoder in fixed memory, for the live view's camera channel (docs/view.md).
// libjpeg allocates its pools per image; this one allocates nothing: the encoder object holds
// every table, encode() works in a few KiB of stack and writes into the caller's buffer.
//
// Output: a JFIF file, baseline sequential DCT (SOF0), one scan, the Huffman tables of
// ITU T.81 Annex K, quantisation tables of Annex K scaled by quality as the IJG library does.
// gray8 gives one component; bgr8 gives YCbCr 4:2:0 (chroma averaged over 2 x 2 pixels).
// Partial blocks at the right and bottom edges repeat the last column and row.
//
//   const JpegEncoder encoder({.quality = 70, .max_width = 640});  // once
//   auto size = encoder.encode(image, buffer);                      // per frame
#include <cstddef>
#include <cstdint>
#include <span>

#include "sen3bot/hal/result.hpp"

namespace sen3bot::view {

enum class PixelLayout : std::uint8_t { bgr8, gray8 };

// A frame in the caller's memory, rows top to bottom, stride_bytes apart.
struct Image {
  const std::uint8_t* pixels = nullptr;
  std::uint32_t width = 0;
  std::uint32_t height = 0;
  std::size_t stride_bytes = 0;  // at least width * bytes per pixel
  PixelLayout layout = PixelLayout::bgr8;
};

struct JpegOptions {
  int quality = 70;             // 1..100 (clamped), the IJG scale
  std::uint32_t max_width = 0;  // 0: full size; else shrink by the smallest integer factor that fits
};

class JpegEncoder {
 public:
  static constexpr std::uint32_t kMaxDimension = 65535;  // SOF0's 16-bit width and height

  explicit JpegEncoder(JpegOptions options = {}) noexcept;

  // Encodes `in` into `out`; the size written. Errc::invalid_argument for null pixels, a zero
  // size, a stride shorter than a row, or an encoded width or height above kMaxDimension;
  // Errc::capacity when `out` is too small (nothing past out.size() is ever written).
  Result<std::size_t> encode(const Image& in, std::span<std::uint8_t> out) const noexcept;

  // The downscale factor for a width: 1 without max_width, else ceil(width / max_width).
  // The encoded size is ceil(width / factor) x ceil(height / factor); each pixel is the mean of
  // a factor x factor box, and a box that runs past the edge repeats the last row or column.
  [[nodiscard]] std::uint32_t scale_factor(std::uint32_t width) const noexcept;

  // An upper bound on encode()'s output for an image that encodes to width x height.
  [[nodiscard]] static std::size_t max_encoded_size(std::uint32_t width, std::uint32_t height,
                                                    PixelLayout layout) noexcept;

  [[nodiscard]] const JpegOptions& options() const noexcept { return options_; }

  // A Huffman code per symbol (Annex C's code assignment), ready to shift into the stream.
  struct HuffmanCodes {
    std::uint16_t code[256] = {};
    std::uint8_t length[256] = {};  // 0: the symbol has no code
  };

 private:
  JpegOptions options_;
  std::uint8_t quant_[2][64] = {};  // luma, chroma; natural (row-major) order
  float scale_[2][64] = {};         // 1 / (quantiser * the float DCT's output scale), natural order
  HuffmanCodes dc_[2];
  HuffmanCodes ac_[2];
};

}  // namespace sen3bot::view
