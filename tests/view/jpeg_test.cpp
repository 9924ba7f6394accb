// The fixed-memory JPEG encoder: its files decode with the system libjpeg (an independent
// decoder) to the right size, component count and colours, close to the source; the downscale,
// the capacity and argument errors, and no allocation per encode.
#include <gtest/gtest.h>

#include <algorithm>
#include <cmath>
#include <cstdint>
#include <cstdio>
#include <cstdlib>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/view/jpeg.hpp"

#ifdef SEN3BOT_HAVE_LIBJPEG
#include <csetjmp>
#include <jpeglib.h>
#endif

namespace sen3bot::view {
namespace {

using mem::testing::AllocationScope;

// Pixels in BGR or grey, with a stride that may exceed a row.
struct TestImage {
  std::vector<std::uint8_t> pixels;
  std::uint32_t width = 0, height = 0;
  std::size_t stride = 0;
  PixelLayout layout = PixelLayout::bgr8;

  [[nodiscard]] unsigned channels() const { return layout == PixelLayout::bgr8 ? 3 : 1; }
  [[nodiscard]] Image view() const { return {pixels.data(), width, height, stride, layout}; }
  std::uint8_t* at(std::uint32_t x, std::uint32_t y) { return pixels.data() + y * stride + x * channels(); }
};

// Smooth gradients with a few hard edges: a dark disc and a bright bar.
TestImage synthetic(std::uint32_t w, std::uint32_t h, PixelLayout layout, std::size_t padding = 0) {
  TestImage img{{}, w, h, 0, layout};
  img.stride = w * img.channels() + padding;
  img.pixels.assign(img.stride * h, 0xAB);  // padding bytes must not leak into the image
  for (std::uint32_t y = 0; y < h; ++y) {
    for (std::uint32_t x = 0; x < w; ++x) {
      const double u = w > 1 ? static_cast<double>(x) / (w - 1) : 0.5;
      const double v = h > 1 ? static_cast<double>(y) / (h - 1) : 0.5;
      double r = 40 + 170 * u, g = 60 + 140 * v, b = 128 + 80 * std::sin(6.0 * u + 3.0 * v);
      const double dx = u - 0.35, dy = v - 0.5;
      if (dx * dx + dy * dy < 0.04) r = 30, g = 40, b = 60;
      if (u > 0.7 && u < 0.8) r = 230, g = 220, b = 200;
      std::uint8_t* p = img.at(x, y);
      if (layout == PixelLayout::gray8) {
        p[0] = static_cast<std::uint8_t>(std::lround(0.299 * r + 0.587 * g + 0.114 * b));
      } else {
        p[0] = static_cast<std::uint8_t>(std::lround(b));
        p[1] = static_cast<std::uint8_t>(std::lround(g));
        p[2] = static_cast<std::uint8_t>(std::lround(r));
      }
    }
  }
  return img;
}

std::vector<std::uint8_t> encode_ok(const JpegEncoder& encoder, const TestImage& img) {
  std::vector<std::uint8_t> out(JpegEncoder::max_encoded_size(img.width, img.height, img.layout));
  auto size = encoder.encode(img.view(), out);
  EXPECT_TRUE(size.ok()) << (size.ok() ? "" : size.error().c_str());
  out.resize(size.ok() ? *size : 0);
  return out;
}

TEST(Jpeg, FileHasTheMarkersInOrder) {
  const JpegEncoder encoder;
  const auto file = encode_ok(encoder, synthetic(40, 30, PixelLayout::bgr8));
  ASSERT_GT(file.size(), 100u);
  EXPECT_EQ(file[0], 0xFF);
  EXPECT_EQ(file[1], 0xD8);  // SOI
  EXPECT_EQ(file[2], 0xFF);
  EXPECT_EQ(file[3], 0xE0);  // APP0 JFIF
  EXPECT_EQ(std::string(reinterpret_cast<const char*>(&file[6]), 4), "JFIF");
  EXPECT_EQ(file[file.size() - 2], 0xFF);
  EXPECT_EQ(file[file.size() - 1], 0xD9);  // EOI
  // SOF0 (baseline) present, SOF2 (progressive) not.
  bool sof0 = false, sof2 = false;
  for (std::size_t i = 0; i + 1 < file.size(); ++i) {
    sof0 |= file[i] == 0xFF && file[i + 1] == 0xC0;
    sof2 |= file[i] == 0xFF && file[i + 1] == 0xC2;
  }
  EXPECT_TRUE(sof0);
  EXPECT_FALSE(sof2);
  // Inside the entropy-coded data every 0xFF is followed by a stuffed 0x00 (no RST markers).
  std::size_t sos = 0;
  for (std::size_t i = 0; i + 1 < file.size(); ++i)
    if (file[i] == 0xFF && file[i + 1] == 0xDA) sos = i;
  ASSERT_GT(sos, 0u);
  const std::size_t data = sos + 2 + (file[sos + 2] << 8 | file[sos + 3]);
  for (std::size_t i = data; i + 2 < file.size(); ++i) {
    if (file[i] == 0xFF) {
      EXPECT_EQ(file[i + 1], 0x00) << "at " << i;
    }
  }
}

TEST(Jpeg, QualityIsClampedAndOptionsKept) {
  EXPECT_EQ(JpegEncoder({.quality = 0}).options().quality, 1);
  EXPECT_EQ(JpegEncoder({.quality = 150}).options().quality, 100);
  EXPECT_EQ(JpegEncoder({.quality = 70, .max_width = 320}).options().max_width, 320u);
  // Higher quality spends more bytes on the same picture.
  const auto img = synthetic(64, 48, PixelLayout::bgr8);
  std::size_t previous = 0;
  for (int q : {10, 50, 90, 100}) {
    const auto size = encode_ok(JpegEncoder({.quality = q}), img).size();
    EXPECT_GT(size, previous) << "quality " << q;
    previous = size;
  }
}

TEST(Jpeg, ScaleFactorIsTheSmallestThatFits) {
  const JpegEncoder none;
  EXPECT_EQ(none.scale_factor(4000), 1u);
  const JpegEncoder fit({.max_width = 320});
  EXPECT_EQ(fit.scale_factor(320), 1u);
  EXPECT_EQ(fit.scale_factor(321), 2u);
  EXPECT_EQ(fit.scale_factor(640), 2u);
  EXPECT_EQ(fit.scale_factor(641), 3u);
  EXPECT_EQ(fit.scale_factor(1280), 4u);
}

TEST(Jpeg, InvalidArguments) {
  const JpegEncoder encoder;
  std::vector<std::uint8_t> out(1 << 16);
  const auto img = synthetic(16, 16, PixelLayout::bgr8);
  auto expect_invalid = [&](Image in, const JpegEncoder& e) {
    auto r = e.encode(in, out);
    ASSERT_FALSE(r.ok());
    EXPECT_EQ(r.error().code(), Errc::invalid_argument) << r.error().c_str();
  };
  Image in = img.view();
  in.pixels = nullptr;
  expect_invalid(in, encoder);
  in = img.view();
  in.width = 0;
  expect_invalid(in, encoder);
  in = img.view();
  in.height = 0;
  expect_invalid(in, encoder);
  in = img.view();
  in.stride_bytes = 16 * 3 - 1;
  expect_invalid(in, encoder);

  // Above 65535 after scaling is refused; the same width scaled down is fine.
  std::vector<std::uint8_t> row(70'000, 100);
  const Image wide{row.data(), 70'000, 1, row.size(), PixelLayout::gray8};
  expect_invalid(wide, encoder);
  const Image tall{row.data(), 1, 70'000, 1, PixelLayout::gray8};
  expect_invalid(tall, encoder);
  EXPECT_TRUE(JpegEncoder({.max_width = 1000}).encode(wide, out).ok());
}

TEST(Jpeg, CapacityErrorNeverWritesPastTheSpan) {
  const JpegEncoder encoder({.quality = 90});
  for (auto layout : {PixelLayout::bgr8, PixelLayout::gray8}) {
    const auto img = synthetic(48, 40, layout);
    const auto full = encode_ok(encoder, img);
    ASSERT_FALSE(full.empty());
    constexpr std::size_t kGuard = 64;
    std::vector<std::uint8_t> buffer(full.size() + kGuard);
    for (std::size_t size = 0; size < full.size(); size += (size < 700 ? 1 : 7)) {
      std::fill(buffer.begin(), buffer.end(), 0x5A);
      auto r = encoder.encode(img.view(), std::span(buffer.data(), size));
      ASSERT_FALSE(r.ok()) << size;
      EXPECT_EQ(r.error().code(), Errc::capacity);
      for (std::size_t i = size; i < buffer.size(); ++i) ASSERT_EQ(buffer[i], 0x5A) << "size " << size << " byte " << i;
    }
    // Exactly enough is enough, and gives the same bytes.
    std::fill(buffer.begin(), buffer.end(), 0x5A);
    auto r = encoder.encode(img.view(), std::span(buffer.data(), full.size()));
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(*r, full.size());
    EXPECT_TRUE(std::equal(full.begin(), full.end(), buffer.begin()));
    for (std::size_t i = full.size(); i < buffer.size(); ++i) ASSERT_EQ(buffer[i], 0x5A);
  }
}

TEST(Jpeg, WorstCaseFitsTheBound) {
  // Noise at quality 100 is the most expensive picture there is to code.
  const JpegEncoder encoder({.quality = 100});
  for (auto layout : {PixelLayout::bgr8, PixelLayout::gray8}) {
    TestImage img = synthetic(67, 45, layout);
    std::uint32_t state = 12345;
    for (auto& p : img.pixels) {
      state = state * 1664525u + 1013904223u;
      p = static_cast<std::uint8_t>(state >> 24);
    }
    const std::size_t bound = JpegEncoder::max_encoded_size(img.width, img.height, layout);
    std::vector<std::uint8_t> out(bound);
    auto r = encoder.encode(img.view(), out);
    ASSERT_TRUE(r.ok());
    EXPECT_LE(*r, bound);
  }
}

TEST(Jpeg, NoAllocationPerEncode) {
  const JpegEncoder encoder({.quality = 70});
  const JpegEncoder scaled({.quality = 50, .max_width = 100});
  const auto colour = synthetic(320, 240, PixelLayout::bgr8);
  const auto grey = synthetic(161, 97, PixelLayout::gray8);
  std::vector<std::uint8_t> out(JpegEncoder::max_encoded_size(320, 240, PixelLayout::bgr8));
  std::vector<std::uint8_t> small(300);
  ASSERT_TRUE(encoder.encode(colour.view(), out).ok());  // warm-up

  std::size_t total = 0;
  AllocationScope scope;
  for (int i = 0; i < 5; ++i) {
    total += *encoder.encode(colour.view(), out);
    total += *encoder.encode(grey.view(), out);
    total += *scaled.encode(colour.view(), out);
    auto too_small = encoder.encode(colour.view(), small);
    auto invalid = encoder.encode(Image{}, out);
    total += too_small.ok() + invalid.ok();
  }
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(scope.malloc_calls(), 0u);
  EXPECT_GT(total, 0u);

  // The counter does see allocations (positive control).
  AllocationScope control;
  auto* leak_free = new std::vector<int>(10);
  delete leak_free;
  EXPECT_GT(control.allocations(), 0u);
}

#ifdef SEN3BOT_HAVE_LIBJPEG

TestImage solid(std::uint32_t w, std::uint32_t h, std::uint8_t b, std::uint8_t g, std::uint8_t r) {
  TestImage img{{}, w, h, w * 3u, PixelLayout::bgr8};
  img.pixels.resize(img.stride * h);
  for (std::size_t i = 0; i < img.pixels.size(); i += 3) {
    img.pixels[i] = b;
    img.pixels[i + 1] = g;
    img.pixels[i + 2] = r;
  }
  return img;
}

struct Decoded {
  bool ok = false;
  std::uint32_t width = 0, height = 0;
  int components = 0;
  bool jfif = false;
  bool progressive = false;
  std::vector<std::uint8_t> pixels;  // RGB or grey, tightly packed
  char message[JMSG_LENGTH_MAX] = {};
};

struct ErrorManager {
  jpeg_error_mgr base;
  std::jmp_buf jump;
};

[[noreturn]] void on_error(j_common_ptr cinfo) {
  std::longjmp(reinterpret_cast<ErrorManager*>(cinfo->err)->jump, 1);
}

// Only trivially destructible locals live between setjmp and longjmp; `result` is the caller's.
void decode_into(const std::vector<std::uint8_t>& file, Decoded& result) {
  jpeg_decompress_struct cinfo{};
  ErrorManager errors{};
  cinfo.err = jpeg_std_error(&errors.base);
  errors.base.error_exit = on_error;
  if (setjmp(errors.jump)) {
    errors.base.format_message(reinterpret_cast<j_common_ptr>(&cinfo), result.message);
    jpeg_destroy_decompress(&cinfo);
    result.ok = false;
    return;
  }
  jpeg_create_decompress(&cinfo);
  jpeg_mem_src(&cinfo, file.data(), static_cast<unsigned long>(file.size()));
  jpeg_read_header(&cinfo, TRUE);
  result.jfif = cinfo.saw_JFIF_marker != 0;
  result.progressive = cinfo.progressive_mode != 0;
  jpeg_start_decompress(&cinfo);
  result.width = cinfo.output_width;
  result.height = cinfo.output_height;
  result.components = cinfo.output_components;
  const std::size_t row =
      static_cast<std::size_t>(cinfo.output_width) * static_cast<std::size_t>(cinfo.output_components);
  result.pixels.resize(row * cinfo.output_height);
  while (cinfo.output_scanline < cinfo.output_height) {
    JSAMPROW line = result.pixels.data() + row * cinfo.output_scanline;
    jpeg_read_scanlines(&cinfo, &line, 1);
  }
  jpeg_finish_decompress(&cinfo);
  jpeg_destroy_decompress(&cinfo);
  result.ok = true;
}

Decoded decode(const std::vector<std::uint8_t>& file) {
  Decoded d;
  decode_into(file, d);
  return d;
}

// libjpeg's own encoding of the same picture (4:2:0, its float DCT): the reference for what
// quality a size and content allow.
void libjpeg_encode_into(const TestImage& img, int quality, std::vector<std::uint8_t>& rgb,
                         std::vector<std::uint8_t>& file, bool& ok) {
  jpeg_compress_struct cinfo{};
  ErrorManager errors{};
  cinfo.err = jpeg_std_error(&errors.base);
  errors.base.error_exit = on_error;
  unsigned char* buffer = nullptr;
  unsigned long size = 0;
  if (setjmp(errors.jump)) {
    jpeg_destroy_compress(&cinfo);
    std::free(buffer);
    ok = false;
    return;
  }
  jpeg_create_compress(&cinfo);
  jpeg_mem_dest(&cinfo, &buffer, &size);
  cinfo.image_width = img.width;
  cinfo.image_height = img.height;
  cinfo.input_components = static_cast<int>(img.channels());
  cinfo.in_color_space = img.channels() == 3 ? JCS_RGB : JCS_GRAYSCALE;
  jpeg_set_defaults(&cinfo);
  cinfo.dct_method = JDCT_FLOAT;
  jpeg_set_quality(&cinfo, quality, TRUE);
  jpeg_start_compress(&cinfo, TRUE);
  const std::size_t row = static_cast<std::size_t>(img.width) * img.channels();
  while (cinfo.next_scanline < cinfo.image_height) {
    JSAMPROW line = rgb.data() + row * cinfo.next_scanline;
    jpeg_write_scanlines(&cinfo, &line, 1);
  }
  jpeg_finish_compress(&cinfo);
  jpeg_destroy_compress(&cinfo);
  file.assign(buffer, buffer + size);
  std::free(buffer);
  ok = true;
}

std::vector<std::uint8_t> libjpeg_encode(const TestImage& img, int quality) {
  std::vector<std::uint8_t> packed;  // RGB or grey rows without padding
  for (std::uint32_t y = 0; y < img.height; ++y) {
    const std::uint8_t* s = img.pixels.data() + y * img.stride;
    for (std::uint32_t x = 0; x < img.width; ++x) {
      if (img.channels() == 1) {
        packed.push_back(s[x]);
      } else {
        packed.insert(packed.end(), {s[3 * x + 2], s[3 * x + 1], s[3 * x]});
      }
    }
  }
  std::vector<std::uint8_t> file;
  bool ok = false;
  libjpeg_encode_into(img, quality, packed, file, ok);
  EXPECT_TRUE(ok);
  return file;
}

// PSNR over every channel, the source's BGR compared with the decoded RGB.
double psnr(const TestImage& src, const Decoded& d) {
  const unsigned ch = src.channels();
  double sum = 0.0;
  for (std::uint32_t y = 0; y < src.height; ++y) {
    const std::uint8_t* s = src.pixels.data() + y * src.stride;
    const std::uint8_t* o = d.pixels.data() + static_cast<std::size_t>(y) * src.width * ch;
    for (std::uint32_t x = 0; x < src.width; ++x) {
      for (unsigned k = 0; k < ch; ++k) {
        const double e = double(s[x * ch + (ch == 3 ? 2 - k : 0)]) - double(o[x * ch + k]);
        sum += e * e;
      }
    }
  }
  const double mse = sum / (double(src.width) * src.height * ch);
  return mse == 0.0 ? 99.0 : 10.0 * std::log10(255.0 * 255.0 / mse);
}

TEST(JpegDecoded, ColourQualityAndSize) {
  const auto img = synthetic(320, 240, PixelLayout::bgr8);
  for (auto [quality, min_psnr] : {std::pair{90, 30.0}, std::pair{50, 26.0}}) {
    const auto file = encode_ok(JpegEncoder({.quality = quality}), img);
    const auto d = decode(file);
    ASSERT_TRUE(d.ok) << d.message;
    EXPECT_TRUE(d.jfif);
    EXPECT_FALSE(d.progressive);
    EXPECT_EQ(d.width, 320u);
    EXPECT_EQ(d.height, 240u);
    EXPECT_EQ(d.components, 3);
    const double p = psnr(img, d);
    // libjpeg (float DCT, same tables) on the same picture: about the same size and error.
    const auto reference = libjpeg_encode(img, quality);
    const auto r = decode(reference);
    ASSERT_TRUE(r.ok) << r.message;
    const double p_ref = psnr(img, r);
    std::printf("colour q%d: %zu bytes, PSNR %.2f dB (libjpeg: %zu bytes, %.2f dB)\n", quality, file.size(), p,
                reference.size(), p_ref);
    EXPECT_GT(p, min_psnr) << "quality " << quality;
    EXPECT_GT(p, p_ref - 0.5);
    EXPECT_LT(static_cast<double>(file.size()), 1.1 * static_cast<double>(reference.size()));
  }
}

TEST(JpegDecoded, GreyQualityAndSize) {
  const auto img = synthetic(320, 240, PixelLayout::gray8);
  for (auto [quality, min_psnr] : {std::pair{90, 30.0}, std::pair{50, 26.0}}) {
    const auto file = encode_ok(JpegEncoder({.quality = quality}), img);
    const auto d = decode(file);
    ASSERT_TRUE(d.ok) << d.message;
    EXPECT_EQ(d.width, 320u);
    EXPECT_EQ(d.height, 240u);
    EXPECT_EQ(d.components, 1);
    const double p = psnr(img, d);
    // libjpeg (float DCT, same tables) on the same picture: about the same size and error.
    const auto reference = libjpeg_encode(img, quality);
    const auto r = decode(reference);
    ASSERT_TRUE(r.ok) << r.message;
    const double p_ref = psnr(img, r);
    std::printf("grey q%d: %zu bytes, PSNR %.2f dB (libjpeg: %zu bytes, %.2f dB)\n", quality, file.size(), p,
                reference.size(), p_ref);
    EXPECT_GT(p, min_psnr) << "quality " << quality;
    EXPECT_GT(p, p_ref - 0.5);
    EXPECT_LT(static_cast<double>(file.size()), 1.1 * static_cast<double>(reference.size()));
  }
}

TEST(JpegDecoded, OddSizesAndPaddedStrides) {
  const JpegEncoder encoder({.quality = 90});
  for (auto layout : {PixelLayout::bgr8, PixelLayout::gray8}) {
    for (auto [w, h] : {std::pair{17u, 13u}, std::pair{1u, 1u}, std::pair{16u, 16u}, std::pair{8u, 8u},
                        std::pair{33u, 7u}, std::pair{2u, 31u}, std::pair{23u, 17u}}) {
      for (std::size_t padding : {std::size_t{0}, std::size_t{5}}) {
        const auto img = synthetic(w, h, layout, padding);
        const auto d = decode(encode_ok(encoder, img));
        ASSERT_TRUE(d.ok) << d.message << " " << w << "x" << h;
        EXPECT_EQ(d.width, w);
        EXPECT_EQ(d.height, h);
        EXPECT_EQ(d.components, layout == PixelLayout::bgr8 ? 3 : 1);
        // Tiny images are all edges, and 4:2:0 halves their colour: libjpeg's own encoding
        // of the same picture at the same quality is the yardstick.
        const auto reference = decode(libjpeg_encode(img, 90));
        ASSERT_TRUE(reference.ok) << reference.message;
        const double ours = psnr(img, d), theirs = psnr(img, reference);
        EXPECT_GT(ours, std::min(30.0, theirs - 1.0)) << w << "x" << h << " padding " << padding << " ours " << ours
                                                      << " libjpeg " << theirs;
      }
    }
  }
}

TEST(JpegDecoded, BgrOrderIsRight) {
  const JpegEncoder encoder({.quality = 90});
  struct Case {
    std::uint8_t b, g, r;
  };
  for (const Case c : {Case{0, 0, 255}, Case{0, 255, 0}, Case{255, 0, 0}, Case{40, 120, 200}}) {
    const auto img = solid(24, 20, c.b, c.g, c.r);
    const auto d = decode(encode_ok(encoder, img));
    ASSERT_TRUE(d.ok) << d.message;
    ASSERT_EQ(d.components, 3);
    for (std::size_t i = 0; i < d.pixels.size(); i += 3) {
      ASSERT_NEAR(d.pixels[i], c.r, 6) << i;  // decoded as RGB
      ASSERT_NEAR(d.pixels[i + 1], c.g, 6) << i;
      ASSERT_NEAR(d.pixels[i + 2], c.b, 6) << i;
    }
  }
}

TEST(JpegDecoded, DownscaleAveragesBoxes) {
  // A one-pixel checkerboard of black and white halved is flat mid grey.
  TestImage board{{}, 64, 48, 64 * 3, PixelLayout::bgr8};
  board.pixels.resize(board.stride * board.height);
  for (std::uint32_t y = 0; y < board.height; ++y)
    for (std::uint32_t x = 0; x < board.width; ++x)
      std::fill_n(board.at(x, y), 3, ((x + y) & 1) ? 255 : 0);
  const JpegEncoder half({.quality = 90, .max_width = 32});
  const auto d = decode(encode_ok(half, board));
  ASSERT_TRUE(d.ok) << d.message;
  EXPECT_EQ(d.width, 32u);
  EXPECT_EQ(d.height, 24u);
  for (auto v : d.pixels) ASSERT_NEAR(v, 128, 3);

  // A smooth picture scaled by 3 (641 wide into 320) matches its box means.
  const auto img = synthetic(641, 481, PixelLayout::bgr8);
  const JpegEncoder third({.quality = 90, .max_width = 320});
  ASSERT_EQ(third.scale_factor(641), 3u);
  const auto small = decode(encode_ok(third, img));
  ASSERT_TRUE(small.ok) << small.message;
  EXPECT_EQ(small.width, 214u);   // ceil(641 / 3)
  EXPECT_EQ(small.height, 161u);  // ceil(481 / 3)
  TestImage expected{{}, 214, 161, 214 * 3, PixelLayout::bgr8};
  expected.pixels.resize(expected.stride * expected.height);
  for (std::uint32_t y = 0; y < 161; ++y) {
    for (std::uint32_t x = 0; x < 214; ++x) {
      for (unsigned k = 0; k < 3; ++k) {
        unsigned sum = 0;
        for (std::uint32_t j = 0; j < 3; ++j)
          for (std::uint32_t i = 0; i < 3; ++i)
            sum += img.pixels[std::min(y * 3 + j, 480u) * img.stride + std::min(x * 3 + i, 640u) * 3 + k];
        expected.at(x, y)[k] = static_cast<std::uint8_t>((sum + 4) / 9);
      }
    }
  }
  EXPECT_GT(psnr(expected, small), 30.0);

  // Grey too, with the width already inside the limit on one side.
  const auto grey = synthetic(100, 60, PixelLayout::gray8);
  const auto g = decode(encode_ok(JpegEncoder({.max_width = 40}), grey));
  ASSERT_TRUE(g.ok) << g.message;
  EXPECT_EQ(g.width, 34u);
  EXPECT_EQ(g.height, 20u);
  EXPECT_EQ(g.components, 1);
}

#endif  // SEN3BOT_HAVE_LIBJPEG

}  // namespace
}  // namespace sen3bot::view
