// The live view's JPEG encoder per frame: 640 x 480 colour at quality 70 (the camera channel's
// case), 320 x 240 grey, and 1280 x 720 colour halved to 640 wide.
#include <benchmark/benchmark.h>

#include <cmath>
#include <cstdint>
#include <vector>

#include "sen3bot/view/jpeg.hpp"

namespace {

using sen3bot::view::Image;
using sen3bot::view::JpegEncoder;
using sen3bot::view::JpegOptions;
using sen3bot::view::PixelLayout;

// Gradients, texture and a few edges: roughly a camera frame's cost to code.
std::vector<std::uint8_t> scene(std::uint32_t w, std::uint32_t h, unsigned channels) {
  std::vector<std::uint8_t> pixels(static_cast<std::size_t>(w) * h * channels);
  std::uint32_t noise = 1;
  for (std::uint32_t y = 0; y < h; ++y) {
    for (std::uint32_t x = 0; x < w; ++x) {
      for (unsigned k = 0; k < channels; ++k) {
        noise = noise * 1664525u + 1013904223u;
        double v = 128 + 60 * std::sin(0.05 * x + 0.7 * k) * std::cos(0.04 * y) + ((noise >> 28) & 7);
        if ((x / 80 + y / 60) % 3 == 0) v = 0.5 * v + 90;
        pixels[(static_cast<std::size_t>(y) * w + x) * channels + k] = static_cast<std::uint8_t>(v);
      }
    }
  }
  return pixels;
}

void encode(benchmark::State& state, std::uint32_t w, std::uint32_t h, PixelLayout layout, JpegOptions options) {
  const unsigned channels = layout == PixelLayout::bgr8 ? 3 : 1;
  const auto pixels = scene(w, h, channels);
  const Image image{pixels.data(), w, h, static_cast<std::size_t>(w) * channels, layout};
  const JpegEncoder encoder(options);
  std::vector<std::uint8_t> out(JpegEncoder::max_encoded_size(w, h, layout));
  std::size_t bytes = 0;
  for (auto _ : state) {
    auto size = encoder.encode(image, out);
    if (!size.ok()) {
      state.SkipWithError(size.error().c_str());
      break;
    }
    bytes = *size;
    benchmark::DoNotOptimize(out.data());
  }
  state.counters["jpeg_bytes"] = static_cast<double>(bytes);
}

void BM_Colour640x480Q70(benchmark::State& state) { encode(state, 640, 480, PixelLayout::bgr8, {.quality = 70}); }
void BM_Grey320x240Q70(benchmark::State& state) { encode(state, 320, 240, PixelLayout::gray8, {.quality = 70}); }
void BM_Colour1280x720To640Q70(benchmark::State& state) {
  encode(state, 1280, 720, PixelLayout::bgr8, {.quality = 70, .max_width = 640});
}
BENCHMARK(BM_Colour640x480Q70)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Grey320x240Q70)->Unit(benchmark::kMillisecond);
BENCHMARK(BM_Colour1280x720To640Q70)->Unit(benchmark::kMillisecond);

}  // namespace

BENCHMARK_MAIN();
