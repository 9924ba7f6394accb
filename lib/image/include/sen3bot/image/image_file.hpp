#pragma once
// Images in and out of bytes and files with libjpeg-turbo and libpng directly: the camera's
// JPEG frames, `sen3bot detect --image`, saved frames and figures. OpenCV's image codecs module
// would bring GDAL, HDF5 and X11 into the robot binary for the same two formats.
#include <cstdint>
#include <span>
#include <string>
#include <vector>

#include "sen3bot/hal/result.hpp"

namespace sen3bot::image {

// Larger images are refused before any pixel memory is taken: a corrupt or hostile header can
// claim 65535 x 65535 (12 GiB in BGR), which a Pi cannot hold. An 8K frame is 33 Mpx.
inline constexpr std::uint64_t kMaxPixels = std::uint64_t{1} << 26;

// Row-major pixels, rows packed (stride = width x channels): 1 channel grey, 3 BGR, 4 BGRA.
struct Image {
  std::uint32_t width_px = 0;
  std::uint32_t height_px = 0;
  std::uint8_t channels = 0;
  std::vector<std::uint8_t> pixels;
};

// Decodes a baseline or progressive JPEG into grey (channels 1) or BGR (3), as OpenCV's
// imdecode does with the same library: integer DCT, fancy upsampling, the EXIF orientation
// applied, and the rows after a truncated stream's end repeating the last one decoded. The
// pixel buffer is reused when the size is unchanged.
Status decode_jpeg(std::span<const std::uint8_t> jpeg, int channels, Image& out);

// Reads a JPEG or PNG file (told apart by their signatures) into grey (1) or BGR (3).
Status read_image(const std::string& path, int channels, Image& out);

// Writes 8-bit pixels (1 grey, 3 BGR, 4 BGRA; rows stride_bytes apart) as PNG, with the
// settings OpenCV's imwrite uses by default (sub filter, fastest zlib level, RLE strategy).
Status write_png(const std::string& path, const std::uint8_t* pixels, std::uint32_t width_px,
                 std::uint32_t height_px, std::size_t stride_bytes, int channels);

}  // namespace sen3bot::image
