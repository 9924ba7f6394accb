#pragma once
// A JSON string's body as the reader keeps it, the bytes between the quotes with the escapes
// still in: the UTF-8 rule the reader and the writer share, the \u escape's digits, and undoing
// the escapes (for the values and the reader's duplicate-name check).
#include <cstddef>
#include <string_view>

namespace sen3bot::json::detail {

// Length of the well-formed UTF-8 sequence at s (RFC 3629: no overlongs, no surrogates,
// nothing above U+10FFFF), or 0 when it is not one.
inline std::size_t utf8_length(const unsigned char* s, std::size_t avail) noexcept {
  const unsigned char c = s[0];
  if (c < 0x80) return 1;
  const auto cont = [&](std::size_t i, unsigned char lo = 0x80, unsigned char hi = 0xBF) {
    return i < avail && s[i] >= lo && s[i] <= hi;
  };
  if (c >= 0xC2 && c <= 0xDF) return cont(1) ? 2 : 0;
  if (c == 0xE0) return cont(1, 0xA0) && cont(2) ? 3 : 0;
  if ((c >= 0xE1 && c <= 0xEC) || c == 0xEE || c == 0xEF) return cont(1) && cont(2) ? 3 : 0;
  if (c == 0xED) return cont(1, 0x80, 0x9F) && cont(2) ? 3 : 0;
  if (c == 0xF0) return cont(1, 0x90) && cont(2) && cont(3) ? 4 : 0;
  if (c >= 0xF1 && c <= 0xF3) return cont(1) && cont(2) && cont(3) ? 4 : 0;
  if (c == 0xF4) return cont(1, 0x80, 0x8F) && cont(2) && cont(3) ? 4 : 0;
  return 0;
}

inline int hex_digit(char c) noexcept {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// Four hex digits at s (already known to be there), or -1.
inline long hex4(const char* s) noexcept {
  long v = 0;
  for (int i = 0; i < 4; ++i) {
    const int d = hex_digit(s[i]);
    if (d < 0) return -1;
    v = v * 16 + d;
  }
  return v;
}

// Decodes one character of a validated string body at s[i], advancing i; writes its UTF-8
// bytes to out and returns how many.
std::size_t next_char(std::string_view s, std::size_t& i, char out[4]) noexcept;

// Whether two string bodies (either possibly escaped) unescape to the same bytes.
bool same_string(std::string_view a, bool a_escaped, std::string_view b, bool b_escaped) noexcept;

}  // namespace sen3bot::json::detail
