// Fuzz target: JPEG decoding (the camera's frames arrive from the network), EXIF orientation
// included, in colour and grey. A decoded image must hold exactly its pixels.
#include <cstddef>
#include <cstdint>
#include <span>

#include "sen3bot/image/image_file.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sen3bot::image;
  Image image;
  for (const int channels : {3, 1}) {
    if (!decode_jpeg(std::span(data, size), channels, image)) continue;
    const std::uint64_t pixels = static_cast<std::uint64_t>(image.width_px) * image.height_px;
    if (pixels == 0 || pixels > kMaxPixels || image.channels != channels ||
        image.pixels.size() != pixels * static_cast<std::uint64_t>(channels))
      __builtin_trap();
  }
  return 0;
}
