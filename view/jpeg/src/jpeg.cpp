#include "sen3bot/view/jpeg.hpp"

#include <algorithm>
#include <bit>
#include <cmath>
#include <cstring>

namespace sen3bot::view {
namespace {

// The zigzag scan (T.81 figure 5): the natural index of the k-th coefficient sent.
constexpr std::uint8_t kZigzag[64] = {
    0,  1,  8,  16, 9,  2,  3,  10, 17, 24, 32, 25, 18, 11, 4,  5,  12, 19, 26, 33, 40, 48,
    41, 34, 27, 20, 13, 6,  7,  14, 21, 28, 35, 42, 49, 56, 57, 50, 43, 36, 29, 22, 15, 23,
    30, 37, 44, 51, 58, 59, 52, 45, 38, 31, 39, 46, 53, 60, 61, 54, 47, 55, 62, 63};

// Annex K tables K.1 (luminance) and K.2 (chrominance), natural order.
constexpr std::uint8_t kBaseQuant[2][64] = {
    {16, 11, 10, 16, 24,  40,  51,  61,  12, 12, 14, 19, 26,  58,  60,  55,  14, 13, 16, 24,  40,  57,
     69, 56, 14, 17, 22,  29,  51,  87,  80, 62, 18, 22, 37,  56,  68,  109, 103, 77, 24, 35, 55,  64,
     81, 104, 113, 92, 49, 64, 78,  87,  103, 121, 120, 101, 72, 92, 95, 98, 112, 100, 103, 99},
    {17, 18, 24, 47, 99, 99, 99, 99, 18, 21, 26, 66, 99, 99, 99, 99, 24, 26, 56, 99, 99, 99,
     99, 99, 47, 66, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99,
     99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99, 99}};

// Annex K.3: codes per length 1..16 and the symbols by increasing code length. For the AC
// tables only the symbols with codes shorter than 16 bits are listed: the rest (every other
// run/size symbol) take the 16-bit codes in increasing symbol order.
struct HuffmanSpec {
  std::uint8_t bits[16];
  std::uint8_t short_symbols[48];
  std::uint8_t short_count;
};
constexpr HuffmanSpec kDcSpec[2] = {
    {{0, 1, 5, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0, 0, 0}, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}, 12},
    {{0, 3, 1, 1, 1, 1, 1, 1, 1, 1, 1, 0, 0, 0, 0, 0}, {0, 1, 2, 3, 4, 5, 6, 7, 8, 9, 10, 11}, 12}};
constexpr HuffmanSpec kAcSpec[2] = {
    {{0, 2, 1, 3, 3, 2, 4, 3, 5, 5, 4, 4, 0, 0, 1, 125},
     {0x01, 0x02, 0x03, 0x00, 0x04, 0x11, 0x05, 0x12, 0x21, 0x31, 0x41, 0x06, 0x13, 0x51, 0x61, 0x07,
      0x22, 0x71, 0x14, 0x32, 0x81, 0x91, 0xa1, 0x08, 0x23, 0x42, 0xb1, 0xc1, 0x15, 0x52, 0xd1, 0xf0,
      0x24, 0x33, 0x62, 0x72, 0x82},
     37},
    {{0, 2, 1, 2, 4, 4, 3, 4, 7, 5, 4, 4, 0, 1, 2, 119},
     {0x00, 0x01, 0x02, 0x03, 0x11, 0x04, 0x05, 0x21, 0x31, 0x06, 0x12, 0x41, 0x51, 0x07, 0x61,
      0x71, 0x13, 0x22, 0x32, 0x81, 0x08, 0x14, 0x42, 0x91, 0xa1, 0xb1, 0xc1, 0x09, 0x23, 0x33,
      0x52, 0xf0, 0x15, 0x62, 0x72, 0xd1, 0x0a, 0x16, 0x24, 0x34, 0xe1, 0x25, 0xf1},
     43}};

// The full symbol list of a spec, in code order; the count.
std::size_t expand_symbols(const HuffmanSpec& spec, bool ac, std::uint8_t (&symbols)[256]) noexcept {
  std::size_t n = 0;
  for (std::size_t i = 0; i < spec.short_count; ++i) symbols[n++] = spec.short_symbols[i];
  if (!ac) return n;
  for (unsigned run = 0; run < 16; ++run) {
    for (unsigned size = 1; size <= 10; ++size) {
      const auto symbol = static_cast<std::uint8_t>(run << 4 | size);
      if (std::find(spec.short_symbols, spec.short_symbols + spec.short_count, symbol) ==
          spec.short_symbols + spec.short_count)
        symbols[n++] = symbol;
    }
  }
  return n;
}

// Annex C: canonical codes, consecutive within a length, doubling at each longer length.
void build_codes(const HuffmanSpec& spec, const std::uint8_t* symbols, JpegEncoder::HuffmanCodes& codes) noexcept {
  unsigned code = 0;
  std::size_t k = 0;
  for (unsigned length = 1; length <= 16; ++length) {
    for (unsigned i = 0; i < spec.bits[length - 1]; ++i, ++k) {
      codes.code[symbols[k]] = static_cast<std::uint16_t>(code++);
      codes.length[symbols[k]] = static_cast<std::uint8_t>(length);
    }
    code <<= 1;
  }
}

// The float AAN DCT's k-th output is the true coefficient times 8 * s[k] per dimension
// (s[0] = 1, s[k] = sqrt(2) cos(k pi / 16)), so the quantiser's divisor absorbs it.
float aan_scale(unsigned k) noexcept {
  return k == 0 ? 1.0f : static_cast<float>(std::sqrt(2.0) * std::cos(k * 3.14159265358979323846 / 16.0));
}

// One 8-point forward DCT (the Arai-Agui-Nakajima factorisation), in place, `step` apart.
inline void fdct8(float* d, std::size_t step) noexcept {
  const float s07 = d[0] + d[7 * step], d07 = d[0] - d[7 * step];
  const float s16 = d[step] + d[6 * step], d16 = d[step] - d[6 * step];
  const float s25 = d[2 * step] + d[5 * step], d25 = d[2 * step] - d[5 * step];
  const float s34 = d[3 * step] + d[4 * step], d34 = d[3 * step] - d[4 * step];

  const float e0 = s07 + s34, e3 = s07 - s34;
  const float e1 = s16 + s25, e2 = s16 - s25;
  d[0] = e0 + e1;
  d[4 * step] = e0 - e1;
  const float m = (e2 + e3) * 0.707106781f;
  d[2 * step] = e3 + m;
  d[6 * step] = e3 - m;

  const float o0 = d34 + d25, o1 = d25 + d16, o2 = d16 + d07;
  const float r = (o0 - o2) * 0.382683433f;
  const float a = 0.541196100f * o0 + r;
  const float b = 1.306562965f * o2 + r;
  const float c = o1 * 0.707106781f;
  const float p = d07 + c, q = d07 - c;
  d[5 * step] = q + a;
  d[3 * step] = q - a;
  d[step] = p + b;
  d[7 * step] = p - b;
}

// The entropy-coded segment's writer: a 64-bit accumulator drained in whole bytes, each 0xFF
// followed by a stuffed 0x00. Past the end of `out` it stops writing and remembers the overflow.
class BitWriter {
 public:
  BitWriter(std::uint8_t* out, std::size_t size, std::size_t pos) noexcept : out_(out), size_(size), pos_(pos) {}

  // count <= 32; the accumulator holds at most 31 bits between calls.
  void put(std::uint32_t value, unsigned count) noexcept {
    acc_ = (acc_ << count) | value;
    bits_ += count;
    if (bits_ >= 32) drain32();
  }

  // Pads the last byte with 1 bits (T.81 F.1.2.3) and writes what is left.
  void flush() noexcept {
    const unsigned pad = (8 - bits_ % 8) % 8;
    acc_ = (acc_ << pad) | ((1u << pad) - 1);
    bits_ += pad;
    while (bits_ >= 8) {
      bits_ -= 8;
      emit(static_cast<std::uint8_t>(acc_ >> bits_));
    }
  }

  void raw(std::uint8_t byte) noexcept {
    if (pos_ < size_)
      out_[pos_++] = byte;
    else
      overflow_ = true;
  }

  [[nodiscard]] bool overflow() const noexcept { return overflow_; }
  [[nodiscard]] std::size_t position() const noexcept { return pos_; }

 private:
  void emit(std::uint8_t byte) noexcept {
    raw(byte);
    if (byte == 0xFF) raw(0x00);
  }

  void drain32() noexcept {
    bits_ -= 32;
    const auto word = static_cast<std::uint32_t>(acc_ >> bits_);
    // No 0xFF byte in the word and room for it: the common case, four plain stores.
    const std::uint32_t inverted = ~word;
    const bool has_ff = ((inverted - 0x01010101u) & ~inverted & 0x80808080u) != 0;
    if (!has_ff && size_ - pos_ >= 4) {
      out_[pos_] = static_cast<std::uint8_t>(word >> 24);
      out_[pos_ + 1] = static_cast<std::uint8_t>(word >> 16);
      out_[pos_ + 2] = static_cast<std::uint8_t>(word >> 8);
      out_[pos_ + 3] = static_cast<std::uint8_t>(word);
      pos_ += 4;
      return;
    }
    for (int shift = 24; shift >= 0; shift -= 8) emit(static_cast<std::uint8_t>(word >> shift));
  }

  std::uint8_t* out_;
  std::size_t size_;
  std::size_t pos_;
  std::uint64_t acc_ = 0;
  unsigned bits_ = 0;
  bool overflow_ = false;
};

// The magnitude category of a coefficient (T.81 F.1.2.1) and its appended bits.
inline unsigned category(int v) noexcept {
  return static_cast<unsigned>(std::bit_width(static_cast<unsigned>(v < 0 ? -v : v)));
}
inline std::uint32_t magnitude_bits(int v, unsigned cat) noexcept {
  return static_cast<std::uint32_t>(v < 0 ? v - 1 : v) & ((1u << cat) - 1);
}

struct Tables {
  const float* scale;
  const JpegEncoder::HuffmanCodes* dc;
  const JpegEncoder::HuffmanCodes* ac;
};

// Transforms, quantises and entropy-codes one level-shifted block (natural order; clobbered).
void encode_block(float* block, const Tables& t, int& previous_dc, BitWriter& w) noexcept {
  for (std::size_t row = 0; row < 8; ++row) fdct8(block + row * 8, 1);
  for (std::size_t col = 0; col < 8; ++col) fdct8(block + col, 8);

  int natural[64];
  for (std::size_t i = 0; i < 64; ++i) {
    const float v = block[i] * t.scale[i];
    natural[i] = static_cast<int>(v + (v >= 0.0f ? 0.5f : -0.5f));
  }

  const int dc = natural[0];
  const int diff = dc - previous_dc;
  previous_dc = dc;
  const unsigned dc_cat = category(diff);
  w.put(static_cast<std::uint32_t>(t.dc->code[dc_cat]) << dc_cat | magnitude_bits(diff, dc_cat),
        t.dc->length[dc_cat] + dc_cat);

  // Bit k set when the k-th coefficient in zigzag order is not zero: runs come from the gaps.
  std::uint64_t nonzero = 0;
  for (unsigned k = 1; k < 64; ++k) nonzero |= static_cast<std::uint64_t>(natural[kZigzag[k]] != 0) << k;
  unsigned last = 0;
  while (nonzero != 0) {
    const auto k = static_cast<unsigned>(std::countr_zero(nonzero));
    nonzero &= nonzero - 1;
    unsigned run = k - last - 1;
    last = k;
    for (; run >= 16; run -= 16) w.put(t.ac->code[0xF0], t.ac->length[0xF0]);
    const int v = natural[kZigzag[k]];
    const unsigned cat = category(v);
    const unsigned symbol = run << 4 | cat;
    w.put(static_cast<std::uint32_t>(t.ac->code[symbol]) << cat | magnitude_bits(v, cat), t.ac->length[symbol] + cat);
  }
  if (last != 63) w.put(t.ac->code[0x00], t.ac->length[0x00]);
}

// Where the encoded pixels come from: the source and the box size.
struct Source {
  const std::uint8_t* pixels;
  std::size_t stride;
  std::uint32_t width, height;    // the source's
  std::uint32_t out_w, out_h;     // the encoded image's
  std::uint32_t factor;
};

// Copies an n x n square of encoded pixels at (x0, y0) into `stage` (n * n * Ch bytes,
// row-major), repeating the last row and column past the encoded image's edge.
template <unsigned Ch>
void fetch(const Source& s, std::uint32_t x0, std::uint32_t y0, unsigned n, std::uint8_t* stage) noexcept {
  if (s.factor == 1) {
    for (unsigned r = 0; r < n; ++r) {
      const std::uint32_t y = std::min(y0 + r, s.out_h - 1);
      const std::uint8_t* row = s.pixels + y * s.stride;
      std::uint8_t* dst = stage + r * n * Ch;
      if (x0 + n <= s.out_w) {
        std::memcpy(dst, row + static_cast<std::size_t>(x0) * Ch, n * Ch);
        continue;
      }
      for (unsigned c = 0; c < n; ++c) {
        const std::uint32_t x = std::min(x0 + c, s.out_w - 1);
        for (unsigned k = 0; k < Ch; ++k) dst[c * Ch + k] = row[static_cast<std::size_t>(x) * Ch + k];
      }
    }
    return;
  }
  const std::uint32_t f = s.factor;
  const std::uint32_t area = f * f;
  const bool inside_x = (x0 + n) * f <= s.width;  // no box of this square crosses the right edge
  for (unsigned r = 0; r < n; ++r) {
    const std::uint32_t y = std::min(y0 + r, s.out_h - 1);
    std::uint32_t sums[16][Ch] = {};
    for (std::uint32_t j = 0; j < f; ++j) {
      const std::uint8_t* row = s.pixels + std::min(y * f + j, s.height - 1) * s.stride;
      if (inside_x) {
        const std::uint8_t* px = row + static_cast<std::size_t>(x0) * f * Ch;
        for (unsigned c = 0; c < n; ++c)
          for (std::uint32_t i = 0; i < f; ++i, px += Ch)
            for (unsigned k = 0; k < Ch; ++k) sums[c][k] += px[k];
        continue;
      }
      for (unsigned c = 0; c < n; ++c) {
        const std::uint32_t x = std::min(x0 + c, s.out_w - 1);
        for (std::uint32_t i = 0; i < f; ++i) {
          const std::size_t sx = std::min(x * f + i, s.width - 1);
          for (unsigned k = 0; k < Ch; ++k) sums[c][k] += row[sx * Ch + k];
        }
      }
    }
    for (unsigned c = 0; c < n; ++c)
      for (unsigned k = 0; k < Ch; ++k)
        stage[(r * n + c) * Ch + k] = static_cast<std::uint8_t>((sums[c][k] + area / 2) / area);
  }
}

void put16(std::uint8_t* p, std::size_t value) noexcept {
  p[0] = static_cast<std::uint8_t>(value >> 8);
  p[1] = static_cast<std::uint8_t>(value);
}

constexpr std::uint8_t kApp0[] = {0xFF, 0xE0, 0, 16, 'J', 'F', 'I', 'F', 0, 1, 1, 0, 0, 1, 0, 1, 0, 0};
// SOI + APP0 + DQT (2 tables) + DHT (4 tables) + SOF0 (3 components) + SOS (3) + EOI.
constexpr std::size_t kHeaderBound = 2 + sizeof kApp0 + (4 + 2 * 65) + (4 + 2 * (17 + 12 + 17 + 162)) + 19 + 14 + 2;
// Bits of one block at worst: DC (11-bit code + 11 bits) and 63 ACs (16-bit code + 10 bits),
// then every byte stuffed.
constexpr std::size_t kBlockBound = 2 * ((11 + 11 + 63 * (16 + 10) + 7) / 8);

}  // namespace

JpegEncoder::JpegEncoder(JpegOptions options) noexcept : options_(options) {
  options_.quality = std::clamp(options_.quality, 1, 100);
  const int q = options_.quality;
  const int percent = q < 50 ? 5000 / q : 200 - 2 * q;  // the IJG scaling
  for (std::size_t t = 0; t < 2; ++t) {
    for (std::size_t i = 0; i < 64; ++i) {
      const int value = (kBaseQuant[t][i] * percent + 50) / 100;
      quant_[t][i] = static_cast<std::uint8_t>(std::clamp(value, 1, 255));  // baseline: 8-bit entries
      scale_[t][i] = 1.0f / (static_cast<float>(quant_[t][i]) * aan_scale(static_cast<unsigned>(i / 8)) *
                             aan_scale(static_cast<unsigned>(i % 8)) * 8.0f);
    }
    std::uint8_t symbols[256];
    expand_symbols(kDcSpec[t], false, symbols);
    build_codes(kDcSpec[t], symbols, dc_[t]);
    expand_symbols(kAcSpec[t], true, symbols);
    build_codes(kAcSpec[t], symbols, ac_[t]);
  }
}

std::uint32_t JpegEncoder::scale_factor(std::uint32_t width) const noexcept {
  if (options_.max_width == 0 || width <= options_.max_width) return 1;
  return static_cast<std::uint32_t>((static_cast<std::uint64_t>(width) + options_.max_width - 1) / options_.max_width);
}

std::size_t JpegEncoder::max_encoded_size(std::uint32_t width, std::uint32_t height, PixelLayout layout) noexcept {
  const std::size_t mcu = layout == PixelLayout::gray8 ? 8 : 16;
  const std::size_t blocks_per_mcu = layout == PixelLayout::gray8 ? 1 : 6;
  const std::size_t mcus = ((width + mcu - 1) / mcu) * ((height + mcu - 1) / mcu);
  return kHeaderBound + mcus * blocks_per_mcu * kBlockBound;
}

Result<std::size_t> JpegEncoder::encode(const Image& in, std::span<std::uint8_t> out) const noexcept {
  const bool colour = in.layout == PixelLayout::bgr8;
  const unsigned channels = colour ? 3 : 1;
  if (in.pixels == nullptr) return Error(Errc::invalid_argument, "jpeg: no pixels");
  if (in.width == 0 || in.height == 0) return Error(Errc::invalid_argument, "jpeg: empty image");
  if (in.stride_bytes < static_cast<std::size_t>(in.width) * channels)
    return Error(Errc::invalid_argument, "jpeg: stride shorter than a row");
  const std::uint32_t factor = scale_factor(in.width);
  const Source src{in.pixels,
                   in.stride_bytes,
                   in.width,
                   in.height,
                   (in.width - 1) / factor + 1,
                   (in.height - 1) / factor + 1,
                   factor};
  if (src.out_w > kMaxDimension || src.out_h > kMaxDimension)
    return Error::format(Errc::invalid_argument, "jpeg: %ux%u exceeds 65535", src.out_w, src.out_h);

  // The headers are fixed in size, so one check covers them: SOI, APP0, DQT, SOF0, DHT (per
  // table set a DC table of 12 symbols and an AC table of 162), SOS.
  const std::size_t components = colour ? 3 : 1;
  const std::size_t tables = colour ? 2 : 1;
  const std::size_t header_size = 2 + sizeof kApp0 + (4 + 65 * tables) + (10 + 3 * components) +
                                  (4 + tables * (17 + 12 + 17 + 162)) + (8 + 2 * components);
  if (out.size() < header_size + 2) return Error(Errc::capacity, "jpeg: output buffer too small");
  std::uint8_t* p = out.data();
  *p++ = 0xFF;
  *p++ = 0xD8;  // SOI
  std::memcpy(p, kApp0, sizeof kApp0);
  p += sizeof kApp0;

  *p++ = 0xFF;
  *p++ = 0xDB;  // DQT, 8-bit entries in zigzag order
  put16(p, 2 + 65 * tables);
  p += 2;
  for (std::size_t t = 0; t < tables; ++t) {
    *p++ = static_cast<std::uint8_t>(t);
    for (std::size_t k = 0; k < 64; ++k) *p++ = quant_[t][kZigzag[k]];
  }

  *p++ = 0xFF;
  *p++ = 0xC0;  // SOF0
  put16(p, 8 + 3 * components);
  p += 2;
  *p++ = 8;
  put16(p, src.out_h);
  p += 2;
  put16(p, src.out_w);
  p += 2;
  *p++ = static_cast<std::uint8_t>(components);
  for (std::size_t c = 0; c < components; ++c) {
    *p++ = static_cast<std::uint8_t>(c + 1);
    *p++ = colour && c == 0 ? 0x22 : 0x11;  // luma 2 x 2 blocks per MCU when colour
    *p++ = c == 0 ? 0 : 1;
  }

  *p++ = 0xFF;
  *p++ = 0xC4;  // DHT
  const std::size_t dht_length_at = static_cast<std::size_t>(p - out.data());
  p += 2;
  for (std::size_t t = 0; t < tables; ++t) {
    for (int ac = 0; ac < 2; ++ac) {
      const HuffmanSpec& spec = ac ? kAcSpec[t] : kDcSpec[t];
      *p++ = static_cast<std::uint8_t>(ac << 4 | static_cast<int>(t));
      std::memcpy(p, spec.bits, 16);
      p += 16;
      std::uint8_t symbols[256];
      const std::size_t n = expand_symbols(spec, ac != 0, symbols);
      std::memcpy(p, symbols, n);
      p += n;
    }
  }
  put16(out.data() + dht_length_at, static_cast<std::size_t>(p - out.data()) - dht_length_at);

  *p++ = 0xFF;
  *p++ = 0xDA;  // SOS: all components, Ss 0, Se 63, Ah/Al 0
  put16(p, 6 + 2 * components);
  p += 2;
  *p++ = static_cast<std::uint8_t>(components);
  for (std::size_t c = 0; c < components; ++c) {
    *p++ = static_cast<std::uint8_t>(c + 1);
    *p++ = c == 0 ? 0x00 : 0x11;
  }
  *p++ = 0;
  *p++ = 63;
  *p++ = 0;

  // Leave room for EOI so the check after the scan covers the whole file.
  BitWriter w(out.data(), out.size() - 2, static_cast<std::size_t>(p - out.data()));
  const Tables luma{scale_[0], &dc_[0], &ac_[0]};
  const Tables chroma{scale_[1], &dc_[1], &ac_[1]};
  int dc_y = 0, dc_cb = 0, dc_cr = 0;

  if (!colour) {
    std::uint8_t stage[64];
    alignas(32) float block[64];
    for (std::uint32_t y0 = 0; y0 < src.out_h; y0 += 8) {
      for (std::uint32_t x0 = 0; x0 < src.out_w; x0 += 8) {
        fetch<1>(src, x0, y0, 8, stage);
        for (std::size_t i = 0; i < 64; ++i) block[i] = static_cast<float>(stage[i]) - 128.0f;
        encode_block(block, luma, dc_y, w);
      }
      if (w.overflow()) return Error(Errc::capacity, "jpeg: output buffer too small");
    }
  } else {
    std::uint8_t stage[16 * 16 * 3];
    alignas(32) float y[4][64];
    alignas(32) float cb[64];
    alignas(32) float cr[64];
    for (std::uint32_t y0 = 0; y0 < src.out_h; y0 += 16) {
      for (std::uint32_t x0 = 0; x0 < src.out_w; x0 += 16) {
        fetch<3>(src, x0, y0, 16, stage);
        // JFIF's YCbCr (BT.601, full range), level-shifted by -128 for the DCT.
        for (std::size_t r = 0; r < 16; ++r) {
          const std::uint8_t* px = stage + r * 48;
          float* yrow = y[(r / 8) * 2] + (r % 8) * 8;
          for (std::size_t c = 0; c < 16; ++c) {
            const float b = px[c * 3], g = px[c * 3 + 1], rd = px[c * 3 + 2];
            yrow[(c / 8) * 56 + c] = 0.299f * rd + 0.587f * g + 0.114f * b - 128.0f;
          }
        }
        for (std::size_t r = 0; r < 8; ++r) {
          const std::uint8_t* top = stage + 2 * r * 48;
          const std::uint8_t* bottom = top + 48;
          for (std::size_t c = 0; c < 8; ++c) {
            const std::size_t i = 6 * c;
            // The mean of the 2 x 2 pixels (the transform is linear, so averaging first is exact).
            const float b = 0.25f * static_cast<float>(top[i] + top[i + 3] + bottom[i] + bottom[i + 3]);
            const float g = 0.25f * static_cast<float>(top[i + 1] + top[i + 4] + bottom[i + 1] + bottom[i + 4]);
            const float rd = 0.25f * static_cast<float>(top[i + 2] + top[i + 5] + bottom[i + 2] + bottom[i + 5]);
            cb[r * 8 + c] = -0.168736f * rd - 0.331264f * g + 0.5f * b;
            cr[r * 8 + c] = 0.5f * rd - 0.418688f * g - 0.081312f * b;
          }
        }
        for (auto& block : y) encode_block(block, luma, dc_y, w);
        encode_block(cb, chroma, dc_cb, w);
        encode_block(cr, chroma, dc_cr, w);
      }
      if (w.overflow()) return Error(Errc::capacity, "jpeg: output buffer too small");
    }
  }
  w.flush();
  if (w.overflow()) return Error(Errc::capacity, "jpeg: output buffer too small");
  std::size_t size = w.position();
  out[size++] = 0xFF;
  out[size++] = 0xD9;  // EOI
  return size;
}

}  // namespace sen3bot::view
