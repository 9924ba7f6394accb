#include "string_body.hpp"

namespace sen3bot::json::detail {

std::size_t next_char(std::string_view s, std::size_t& i, char out[4]) noexcept {
  if (s[i] != '\\') {
    out[0] = s[i++];
    return 1;
  }
  const char e = s[i + 1];
  i += 2;
  switch (e) {
    case 'b': out[0] = '\b'; return 1;
    case 'f': out[0] = '\f'; return 1;
    case 'n': out[0] = '\n'; return 1;
    case 'r': out[0] = '\r'; return 1;
    case 't': out[0] = '\t'; return 1;
    case 'u': break;
    default: out[0] = e; return 1;  // " \ /
  }
  unsigned long cp = static_cast<unsigned long>(hex4(s.data() + i));
  i += 4;
  if (cp >= 0xD800 && cp <= 0xDBFF) {  // the parser checked the low half follows
    const unsigned long low = static_cast<unsigned long>(hex4(s.data() + i + 2));
    i += 6;
    cp = 0x10000 + ((cp - 0xD800) << 10) + (low - 0xDC00);
  }
  const auto byte = [](unsigned long v) { return static_cast<char>(static_cast<unsigned char>(v)); };
  if (cp < 0x80) {
    out[0] = byte(cp);
    return 1;
  }
  if (cp < 0x800) {
    out[0] = byte(0xC0 | (cp >> 6));
    out[1] = byte(0x80 | (cp & 0x3F));
    return 2;
  }
  if (cp < 0x10000) {
    out[0] = byte(0xE0 | (cp >> 12));
    out[1] = byte(0x80 | ((cp >> 6) & 0x3F));
    out[2] = byte(0x80 | (cp & 0x3F));
    return 3;
  }
  out[0] = byte(0xF0 | (cp >> 18));
  out[1] = byte(0x80 | ((cp >> 12) & 0x3F));
  out[2] = byte(0x80 | ((cp >> 6) & 0x3F));
  out[3] = byte(0x80 | (cp & 0x3F));
  return 4;
}

namespace {

// The unescaped bytes of a string body, one at a time.
class Bytes {
 public:
  Bytes(std::string_view s, bool escaped) noexcept : s_(s), escaped_(escaped) {}

  // The next byte into b; false past the end.
  bool next(char& b) noexcept {
    if (taken_ == size_) {
      if (i_ == s_.size()) return false;
      size_ = escaped_ ? next_char(s_, i_, char_) : (char_[0] = s_[i_++], 1);
      taken_ = 0;
    }
    b = char_[taken_++];
    return true;
  }

 private:
  std::string_view s_;
  bool escaped_;
  std::size_t i_ = 0;
  char char_[4];  // the current character's bytes
  std::size_t size_ = 0, taken_ = 0;
};

}  // namespace

bool same_string(std::string_view a, bool a_escaped, std::string_view b, bool b_escaped) noexcept {
  if (!a_escaped && !b_escaped) return a == b;
  Bytes x(a, a_escaped), y(b, b_escaped);
  for (;;) {
    char ca, cb;
    const bool more_a = x.next(ca), more_b = y.next(cb);
    if (!more_a || !more_b) return more_a == more_b;
    if (ca != cb) return false;
  }
}

}  // namespace sen3bot::json::detail
