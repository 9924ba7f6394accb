#include "sen3bot/cobot/qr_modules.hpp"

#include <algorithm>

namespace sen3bot::cobot {

namespace {

// GF(256) with the QR code's field polynomial x^8 + x^4 + x^3 + x^2 + 1 (0x11D), generator 2.
struct Field {
  std::array<std::uint8_t, 512> exp{};
  std::array<std::uint8_t, 256> log{};
  constexpr Field() {
    unsigned x = 1;
    for (unsigned i = 0; i < 255; ++i) {
      exp[i] = static_cast<std::uint8_t>(x);
      log[x] = static_cast<std::uint8_t>(i);
      x <<= 1;
      if (x & 0x100) x ^= 0x11D;
    }
    for (unsigned i = 255; i < 512; ++i) exp[i] = exp[i - 255];
  }
  [[nodiscard]] constexpr std::uint8_t mul(std::uint8_t a, std::uint8_t b) const {
    return a == 0 || b == 0 ? 0 : exp[log[a] + log[b]];
  }
  [[nodiscard]] constexpr std::uint8_t div(std::uint8_t a, std::uint8_t b) const {  // b != 0
    return a == 0 ? 0 : exp[log[a] + 255 - log[b]];
  }
  [[nodiscard]] constexpr std::uint8_t pow2(int e) const { return exp[static_cast<std::size_t>(((e % 255) + 255) % 255)]; }
};
constexpr Field kField;

// Error correction codewords of the single block of versions 1 and 2, by level L, M, Q, H.
constexpr int kTotalCodewords[3] = {0, 26, 44};
constexpr int kEccCodewords[3][4] = {{0, 0, 0, 0}, {7, 10, 13, 17}, {10, 16, 22, 28}};
constexpr char kLevelNames[4] = {'L', 'M', 'Q', 'H'};
constexpr int kMaxCodewords = 44;
constexpr int kMaxEcc = 28;

// The format information's two bits for L, M, Q, H (the standard's odd order).
constexpr int kLevelBits[4] = {1, 0, 3, 2};
constexpr int kFormatMask = 0x5412;

constexpr int format_word(int level_bits, int mask) {
  const int data = (level_bits << 3) | mask;
  int rem = data;
  for (int i = 0; i < 10; ++i) rem = (rem << 1) ^ (((rem >> 9) & 1) * 0x537);
  return ((data << 10) | (rem & 0x3FF)) ^ kFormatMask;
}

int popcount15(int x) {
  int n = 0;
  for (; x != 0; x &= x - 1) ++n;
  return n;
}

bool masked(int mask, int row, int column) {
  const int r = row;
  const int c = column;
  switch (mask) {
    case 0: return (r + c) % 2 == 0;
    case 1: return r % 2 == 0;
    case 2: return c % 3 == 0;
    case 3: return (r + c) % 3 == 0;
    case 4: return (r / 2 + c / 3) % 2 == 0;
    case 5: return (r * c) % 2 + (r * c) % 3 == 0;
    case 6: return ((r * c) % 2 + (r * c) % 3) % 2 == 0;
    default: return ((r + c) % 2 + (r * c) % 3) % 2 == 0;
  }
}

// Corrects data in place (n codewords, the last ecc of them error correction); false when it
// cannot. Syndromes, Berlekamp-Massey, Chien search, Forney (first consecutive root alpha^0).
bool correct(std::uint8_t* data, int n, int ecc, std::uint8_t& corrected) {
  std::array<std::uint8_t, kMaxEcc> syndromes{};
  bool clean = true;
  for (int j = 0; j < ecc; ++j) {
    std::uint8_t s = 0;
    const std::uint8_t root = kField.pow2(j);
    for (int i = 0; i < n; ++i) s = static_cast<std::uint8_t>(kField.mul(s, root) ^ data[i]);
    syndromes[static_cast<std::size_t>(j)] = s;
    clean = clean && s == 0;
  }
  corrected = 0;
  if (clean) return true;
  // Berlekamp-Massey: the error locator lambda.
  std::array<std::uint8_t, kMaxEcc + 1> lambda{};
  std::array<std::uint8_t, kMaxEcc + 1> previous{};
  lambda[0] = previous[0] = 1;
  int errors = 0;
  int shift = 1;
  std::uint8_t previous_discrepancy = 1;
  for (int k = 0; k < ecc; ++k) {
    std::uint8_t d = syndromes[static_cast<std::size_t>(k)];
    for (int i = 1; i <= errors; ++i) {
      d ^= kField.mul(lambda[static_cast<std::size_t>(i)], syndromes[static_cast<std::size_t>(k - i)]);
    }
    if (d == 0) {
      ++shift;
      continue;
    }
    const std::uint8_t scale = kField.div(d, previous_discrepancy);
    std::array<std::uint8_t, kMaxEcc + 1> before = lambda;
    for (int i = 0; i + shift <= ecc; ++i) {
      lambda[static_cast<std::size_t>(i + shift)] ^= kField.mul(scale, previous[static_cast<std::size_t>(i)]);
    }
    if (2 * errors <= k) {
      errors = k + 1 - errors;
      previous = before;
      previous_discrepancy = d;
      shift = 1;
    } else {
      ++shift;
    }
  }
  if (2 * errors > ecc) return false;
  // Omega = S(x) lambda(x) mod x^ecc.
  std::array<std::uint8_t, kMaxEcc> omega{};
  for (int i = 0; i < ecc; ++i) {
    std::uint8_t v = 0;
    for (int j = 0; j <= i && j <= errors; ++j) {
      v ^= kField.mul(syndromes[static_cast<std::size_t>(i - j)], lambda[static_cast<std::size_t>(j)]);
    }
    omega[static_cast<std::size_t>(i)] = v;
  }
  int found = 0;
  for (int position = 0; position < n; ++position) {  // position: the power of x, from the end
    const std::uint8_t x_inverse = kField.pow2(-position);
    std::uint8_t value = 0;
    std::uint8_t power = 1;
    for (int i = 0; i <= errors; ++i) {
      value ^= kField.mul(lambda[static_cast<std::size_t>(i)], power);
      power = kField.mul(power, x_inverse);
    }
    if (value != 0) continue;
    // lambda'(x) keeps the odd terms; omega at x^-1.
    std::uint8_t derivative = 0;
    power = 1;
    const std::uint8_t x_inverse_sq = kField.mul(x_inverse, x_inverse);
    for (int i = 1; i <= errors; i += 2) {
      derivative ^= kField.mul(lambda[static_cast<std::size_t>(i)], power);
      power = kField.mul(power, x_inverse_sq);
    }
    std::uint8_t numerator = 0;
    power = 1;
    for (int i = 0; i < ecc; ++i) {
      numerator ^= kField.mul(omega[static_cast<std::size_t>(i)], power);
      power = kField.mul(power, x_inverse);
    }
    if (derivative == 0) return false;
    const std::uint8_t magnitude = kField.mul(kField.pow2(position), kField.div(numerator, derivative));
    data[n - 1 - position] ^= magnitude;
    ++found;
  }
  if (found != errors) return false;
  // The mended word must be a codeword.
  for (int j = 0; j < ecc; ++j) {
    std::uint8_t s = 0;
    const std::uint8_t root = kField.pow2(j);
    for (int i = 0; i < n; ++i) s = static_cast<std::uint8_t>(kField.mul(s, root) ^ data[i]);
    if (s != 0) return false;
  }
  corrected = static_cast<std::uint8_t>(found);
  return true;
}

class BitReader {
 public:
  BitReader(const std::uint8_t* data, int bytes) : data_(data), bits_(8 * bytes) {}
  [[nodiscard]] int left() const { return bits_ - at_; }
  int take(int n) {
    int v = 0;
    for (int i = 0; i < n; ++i, ++at_) v = (v << 1) | ((data_[at_ / 8] >> (7 - at_ % 8)) & 1);
    return v;
  }

 private:
  const std::uint8_t* data_;
  int bits_;
  int at_ = 0;
};

constexpr char kAlphanumeric[] = "0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZ $%*+-./:";

bool parse_segments(const std::uint8_t* data, int bytes, QrText& out) {
  BitReader bits(data, bytes);
  const auto put = [&out](char c) {
    if (out.length >= QrText::kCapacity) return false;
    out.chars[out.length++] = c;
    return true;
  };
  while (bits.left() >= 4) {
    const int mode = bits.take(4);
    if (mode == 0) break;  // terminator
    if (mode == 0x7) {     // ECI: the designator's first byte (0xxxxxxx); longer ones are not met here
      if (bits.left() < 8 || (bits.take(8) & 0x80) != 0) return false;
      continue;
    }
    if (mode == 0x1) {  // numeric: 10-bit count, 3 digits in 10 bits
      if (bits.left() < 10) return false;
      int count = bits.take(10);
      while (count > 0) {
        const int digits = count >= 3 ? 3 : count;
        const int width = digits == 3 ? 10 : (digits == 2 ? 7 : 4);
        if (bits.left() < width) return false;
        int value = bits.take(width);
        char group[3];
        for (int i = digits - 1; i >= 0; --i, value /= 10) group[i] = static_cast<char>('0' + value % 10);
        if (value != 0) return false;  // more than the digits allow (e.g. 1000 in 10 bits)
        for (int i = 0; i < digits; ++i) {
          if (!put(group[i])) return false;
        }
        count -= digits;
      }
    } else if (mode == 0x2) {  // alphanumeric: 9-bit count, pairs in 11 bits
      if (bits.left() < 9) return false;
      int count = bits.take(9);
      for (; count >= 2; count -= 2) {
        if (bits.left() < 11) return false;
        const int pair = bits.take(11);
        if (pair >= 45 * 45) return false;
        if (!put(kAlphanumeric[pair / 45]) || !put(kAlphanumeric[pair % 45])) return false;
      }
      if (count == 1) {
        if (bits.left() < 6) return false;
        const int single = bits.take(6);
        if (single >= 45 || !put(kAlphanumeric[single])) return false;
      }
    } else if (mode == 0x4) {  // byte: 8-bit count
      if (bits.left() < 8) return false;
      const int count = bits.take(8);
      for (int i = 0; i < count; ++i) {
        if (bits.left() < 8 || !put(static_cast<char>(bits.take(8)))) return false;
      }
    } else {
      return false;  // Kanji, structured append, FNC1: not in a tag, not read
    }
  }
  out.chars[out.length] = '\0';
  return true;
}

}  // namespace

const char* to_string(QrDecodeFailure failure) noexcept {
  switch (failure) {
    case QrDecodeFailure::size: return "size";
    case QrDecodeFailure::format: return "format";
    case QrDecodeFailure::too_many_errors: return "too_many_errors";
    case QrDecodeFailure::data: return "data";
  }
  return "unknown";
}

bool qr_function_module(int side, int row, int column) noexcept {
  const int far = side - 8;  // where the other finders' separators start
  if (row <= 8 && (column <= 8 || column >= far)) return true;  // finders, separators, format
  if (row >= far && column <= 8) return true;                    // the third finder, format, dark module
  if (row == 6 || column == 6) return true;                      // timing patterns
  if (side == kQrVersion2Modules) {
    const int centre = side - 7;  // version 2's one alignment pattern
    if (row >= centre - 2 && row <= centre + 2 && column >= centre - 2 && column <= centre + 2) return true;
  }
  return false;
}

bool decode_qr_modules(std::span<const std::uint8_t> modules, int side, QrText& out, QrDecodeFailure& failure) noexcept {
  out = QrText{};
  if ((side != kQrVersion1Modules && side != kQrVersion2Modules) ||
      modules.size() < static_cast<std::size_t>(side) * static_cast<std::size_t>(side)) {
    failure = QrDecodeFailure::size;
    return false;
  }
  const int version = (side - 17) / 4;
  const auto dark = [&](int row, int column) {
    return modules[static_cast<std::size_t>(row * side + column)] != 0 ? 1 : 0;
  };
  // Both copies of the format information, bit 0 first.
  int first = 0;
  int second = 0;
  for (int i = 0; i <= 5; ++i) first |= dark(i, 8) << i;
  first |= dark(7, 8) << 6;
  first |= dark(8, 8) << 7;
  first |= dark(8, 7) << 8;
  for (int i = 9; i < 15; ++i) first |= dark(8, 14 - i) << i;
  for (int i = 0; i < 8; ++i) second |= dark(8, side - 1 - i) << i;
  for (int i = 8; i < 15; ++i) second |= dark(side - 15 + i, 8) << i;
  int best_distance = 16;
  int level = 0;
  int mask = 0;
  for (int l = 0; l < 4; ++l) {
    for (int m = 0; m < 8; ++m) {
      const int word = format_word(kLevelBits[l], m);
      const int distance = std::min(popcount15(word ^ first), popcount15(word ^ second));
      if (distance < best_distance) {
        best_distance = distance;
        level = l;
        mask = m;
      }
    }
  }
  if (best_distance > 3) {
    failure = QrDecodeFailure::format;
    return false;
  }
  // The codewords, two columns at a time from the right, up then down, skipping column 6.
  std::array<std::uint8_t, kMaxCodewords> codewords{};
  const int total = kTotalCodewords[version];
  int bit = 0;
  for (int right = side - 1; right >= 1; right -= 2) {
    if (right == 6) right = 5;
    const bool upward = ((right + 1) & 2) == 0;
    for (int step = 0; step < side; ++step) {
      const int row = upward ? side - 1 - step : step;
      for (int j = 0; j < 2; ++j) {
        const int column = right - j;
        if (qr_function_module(side, row, column) || bit >= 8 * total) continue;
        const int value = dark(row, column) ^ (masked(mask, row, column) ? 1 : 0);
        codewords[static_cast<std::size_t>(bit / 8)] |= static_cast<std::uint8_t>(value << (7 - bit % 8));
        ++bit;
      }
    }
  }
  const int ecc = kEccCodewords[version][level];
  if (!correct(codewords.data(), total, ecc, out.corrected)) {
    failure = QrDecodeFailure::too_many_errors;
    return false;
  }
  out.level = kLevelNames[level];
  if (!parse_segments(codewords.data(), total - ecc, out)) {
    const char level_name = out.level;
    out = QrText{};
    out.level = level_name;
    failure = QrDecodeFailure::data;
    return false;
  }
  return true;
}

}  // namespace sen3bot::cobot
