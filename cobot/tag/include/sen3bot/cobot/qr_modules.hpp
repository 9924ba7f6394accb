#pragma once
// Decoding a small QR symbol from its modules (ISO/IEC 18004, versions 1 and 2).
//
// Debian's OpenCV is built without its QR decoding library (quirc), so its detector finds a
// code's corners but reads nothing. The reader samples the code's modules itself and decodes
// them here. Only versions 1 and 2 (21 and 25 modules a side: one Reed-Solomon block, no
// version information) are read: the tags are version 2, and a bigger code is no tag.
//
// Steps: the format information (error correction level, mask; BCH(15,5), up to 3 wrong bits
// of either copy corrected), the mask removed, the codewords read in the standard zig-zag
// order around the function patterns, Reed-Solomon correction over GF(256) (as many wrong
// codewords as half the error correction codewords), then the segments: numeric,
// alphanumeric and byte (an ECI designator is skipped). Pure: no allocation, no OpenCV.
#include <array>
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

namespace sen3bot::cobot {

inline constexpr int kQrVersion1Modules = 21;
inline constexpr int kQrVersion2Modules = 25;

enum class QrDecodeFailure : std::uint8_t {
  size,            // not 21 or 25 modules a side
  format,          // neither copy of the format information is within 3 bits of a valid one
  too_many_errors, // more wrong codewords than the error correction can mend
  data,            // the segments do not parse (unknown mode, a count past the data, Kanji)
};
inline constexpr std::size_t kQrDecodeFailures = 4;
[[nodiscard]] const char* to_string(QrDecodeFailure failure) noexcept;

struct QrText {
  static constexpr std::size_t kCapacity = 80;  // version 2's most: 77 digits
  std::array<char, kCapacity + 1> chars{};      // NUL-terminated
  std::size_t length = 0;
  char level = 'L';                             // error correction level: L, M, Q or H
  std::uint8_t corrected = 0;                   // codewords Reed-Solomon mended
  [[nodiscard]] std::string_view text() const noexcept { return {chars.data(), length}; }
};

// modules: side * side, row by row from the top left as the code is meant to be read, nonzero
// for a dark module. False with the reason when it cannot be read.
[[nodiscard]] bool decode_qr_modules(std::span<const std::uint8_t> modules, int side, QrText& out,
                                     QrDecodeFailure& failure) noexcept;

// True for a module of a function pattern (finders, separators, timing, format, alignment):
// where a version 1 or 2 symbol holds no data.
[[nodiscard]] bool qr_function_module(int side, int row, int column) noexcept;

}  // namespace sen3bot::cobot
