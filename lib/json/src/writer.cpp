// The writer: commas, whitespace and nesting, escaped strings and the values' text.
#include "sen3bot/json/json.hpp"

#include <charconv>
#include <cmath>

#include "string_body.hpp"

namespace sen3bot::json {

using detail::utf8_length;

void Writer::fail(Error error) noexcept {
  if (failed_) return;
  failed_ = true;
  error_ = error;
}

void Writer::put(char c) noexcept {
  if (failed_) return;
  if (sink_ != nullptr) {
    put(std::string_view(&c, 1));
    return;
  }
  if (size_ == buffer_.size()) {
    fail(Error::format(Errc::capacity, "JSON output exceeds the %zu-byte buffer", buffer_.size()));
    return;
  }
  buffer_[size_++] = c;
}

void Writer::put(std::string_view text) noexcept {
  if (failed_) return;
  if (sink_ != nullptr) {
    if (!sink_->write(text)) {
      fail(Error::format(Errc::io, "JSON writer: writing %zu bytes after byte %zu failed", text.size(), size_));
      return;
    }
    size_ += text.size();
    return;
  }
  if (text.size() > buffer_.size() - size_) {
    fail(Error::format(Errc::capacity, "JSON output exceeds the %zu-byte buffer", buffer_.size()));
    return;
  }
  for (char c : text) buffer_[size_++] = c;
}

bool Writer::before_value() noexcept {
  if (failed_) return false;
  if (depth_ == 0) {
    if (done_) {
      fail(Error(Errc::invalid_argument, "JSON writer: a second top-level value"));
      return false;
    }
    return true;
  }
  const std::uint64_t bit = std::uint64_t{1} << (depth_ - 1);
  if (object_bits_ & bit) {
    if (!after_key_) {
      fail(Error(Errc::invalid_argument, "JSON writer: an object member without a key"));
      return false;
    }
    after_key_ = false;
    return true;
  }
  const bool comma = (nonempty_bits_ & bit) != 0;
  if (comma) put(',');
  separator(comma);
  nonempty_bits_ |= bit;
  return !failed_;
}

void Writer::separator(bool after_comma) noexcept {
  if (line_pending_) {
    line_pending_ = false;
    put('\n');
    static constexpr std::string_view kSpaces = "                                ";
    for (std::size_t left = line_indent_; left > 0;) {
      const std::size_t n = left < kSpaces.size() ? left : kSpaces.size();
      put(kSpaces.substr(0, n));
      left -= n;
    }
  } else if (after_comma && style_ == Style::spaced) {
    put(' ');
  }
}

Writer& Writer::line(std::size_t indent) noexcept {
  line_pending_ = true;
  line_indent_ = indent;
  return *this;
}

Writer& Writer::open(char c, bool object) noexcept {
  if (!before_value()) return *this;
  if (depth_ == 64) {
    fail(Error(Errc::capacity, "JSON writer: nesting deeper than 64 levels"));
    return *this;
  }
  put(c);
  const std::uint64_t bit = std::uint64_t{1} << depth_;
  if (object) {
    object_bits_ |= bit;
  } else {
    object_bits_ &= ~bit;
  }
  nonempty_bits_ &= ~bit;
  ++depth_;
  return *this;
}

Writer& Writer::close(char c, bool object) noexcept {
  if (failed_) return *this;
  if (depth_ == 0 || ((object_bits_ >> (depth_ - 1)) & 1) != (object ? 1u : 0u) || after_key_) {
    fail(Error(Errc::invalid_argument, "JSON writer: unbalanced close"));
    return *this;
  }
  --depth_;
  if (line_pending_) separator(false);
  put(c);
  if (depth_ == 0) done_ = true;
  return *this;
}

Writer& Writer::begin_object() noexcept { return open('{', true); }
Writer& Writer::end_object() noexcept { return close('}', true); }
Writer& Writer::begin_array() noexcept { return open('[', false); }
Writer& Writer::end_array() noexcept { return close(']', false); }

Writer& Writer::key(std::string_view name) noexcept {
  if (failed_) return *this;
  const std::uint64_t bit = depth_ ? std::uint64_t{1} << (depth_ - 1) : 0;
  if (depth_ == 0 || !(object_bits_ & bit) || after_key_) {
    fail(Error(Errc::invalid_argument, "JSON writer: a key outside an object"));
    return *this;
  }
  const bool comma = (nonempty_bits_ & bit) != 0;
  if (comma) put(',');
  separator(comma);
  nonempty_bits_ |= bit;
  escaped(name);
  put(style_ == Style::spaced ? std::string_view(": ") : std::string_view(":"));
  after_key_ = true;
  return *this;
}

Writer& Writer::string(std::string_view text) noexcept {
  if (!before_value()) return *this;
  escaped(text);
  if (depth_ == 0) done_ = true;
  return *this;
}

void Writer::escaped(std::string_view text) noexcept {
  put('"');
  const auto* u = reinterpret_cast<const unsigned char*>(text.data());
  static constexpr char kHex[] = "0123456789abcdef";
  for (std::size_t i = 0; i < text.size() && !failed_;) {
    const unsigned char c = u[i];
    if (c == '"' || c == '\\') {
      put('\\');
      put(static_cast<char>(c));
      ++i;
    } else if (c < 0x20) {
      switch (c) {
        case '\b': put("\\b"); break;
        case '\f': put("\\f"); break;
        case '\n': put("\\n"); break;
        case '\r': put("\\r"); break;
        case '\t': put("\\t"); break;
        default: {
          const char esc[6] = {'\\', 'u', '0', '0', kHex[c >> 4], kHex[c & 0xF]};
          put(std::string_view(esc, 6));
        }
      }
      ++i;
    } else if (c < 0x80) {
      put(static_cast<char>(c));
      ++i;
    } else {
      const std::size_t n = utf8_length(u + i, text.size() - i);
      if (n == 0) {
        put("\xef\xbf\xbd");  // U+FFFD for the byte that starts no valid sequence
        ++i;
        continue;
      }
      put(text.substr(i, n));
      i += n;
    }
  }
  put('"');
}

Writer& Writer::number(double value) noexcept {
  if (!std::isfinite(value)) {
    fail(Error(Errc::invalid_argument, "JSON writer: NaN or infinity has no JSON form"));
    return *this;
  }
  if (!before_value()) return *this;
  char buf[40];
  const auto r = std::to_chars(buf, buf + sizeof buf, value);  // shortest round-trip form
  put(std::string_view(buf, static_cast<std::size_t>(r.ptr - buf)));
  if (depth_ == 0) done_ = true;
  return *this;
}

Writer& Writer::fixed(double value, int decimals) noexcept {
  if (!std::isfinite(value)) {
    fail(Error(Errc::invalid_argument, "JSON writer: NaN or infinity has no JSON form"));
    return *this;
  }
  if (decimals < 0 || decimals > 17) {
    fail(Error::format(Errc::invalid_argument, "JSON writer: %d decimals (0..17)", decimals));
    return *this;
  }
  if (!before_value()) return *this;
  char buf[348];  // the largest double in fixed notation with 17 decimals
  const auto r = std::to_chars(buf, buf + sizeof buf, value, std::chars_format::fixed, decimals);
  put(std::string_view(buf, static_cast<std::size_t>(r.ptr - buf)));
  if (depth_ == 0) done_ = true;
  return *this;
}

Writer& Writer::general(double value, int digits) noexcept {
  if (!std::isfinite(value)) {
    fail(Error(Errc::invalid_argument, "JSON writer: NaN or infinity has no JSON form"));
    return *this;
  }
  if (digits < 1 || digits > 17) {
    fail(Error::format(Errc::invalid_argument, "JSON writer: %d significant digits (1..17)", digits));
    return *this;
  }
  if (!before_value()) return *this;
  char buf[40];
  const auto r = std::to_chars(buf, buf + sizeof buf, value, std::chars_format::general, digits);
  put(std::string_view(buf, static_cast<std::size_t>(r.ptr - buf)));
  if (depth_ == 0) done_ = true;
  return *this;
}

Writer& Writer::fixed_or_null(double value, int decimals) noexcept {
  return std::isfinite(value) ? fixed(value, decimals) : null();
}

template <typename T>
Writer& Writer::integer(T value) noexcept {
  if (!before_value()) return *this;
  char buf[24];
  const auto r = std::to_chars(buf, buf + sizeof buf, value);
  put(std::string_view(buf, static_cast<std::size_t>(r.ptr - buf)));
  if (depth_ == 0) done_ = true;
  return *this;
}

Writer& Writer::uint32(std::uint32_t value) noexcept { return integer(value); }
Writer& Writer::int64(std::int64_t value) noexcept { return integer(value); }
Writer& Writer::uint64(std::uint64_t value) noexcept { return integer(value); }

Writer& Writer::float32(float value) noexcept {
  if (!std::isfinite(value)) {
    fail(Error(Errc::invalid_argument, "JSON writer: NaN or infinity has no JSON form"));
    return *this;
  }
  if (!before_value()) return *this;
  char buf[32];
  const auto r = std::to_chars(buf, buf + sizeof buf, value);
  put(std::string_view(buf, static_cast<std::size_t>(r.ptr - buf)));
  if (depth_ == 0) done_ = true;
  return *this;
}

Writer& Writer::base64(std::span<const std::uint8_t> bytes) noexcept {
  if (!before_value()) return *this;
  static constexpr char kAlphabet[] = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  const std::size_t n = bytes.size();
  const std::size_t whole = n / 3 * 3;
  // Checked once up front (the quotes included), so the loop writes without checks.
  const std::size_t need = 2 + (n + 2) / 3 * 4;
  if (sink_ != nullptr) {
    // In pieces through a small buffer: the same encoding, written as it goes.
    std::array<char, 256> chunk;
    std::size_t used = 0;
    const auto emit = [&](char c) {
      chunk[used++] = c;
      if (used == chunk.size()) {
        put(std::string_view(chunk.data(), used));
        used = 0;
      }
    };
    emit('"');
    for (std::size_t i = 0; i < n; i += 3) {
      const std::size_t left = n - i;
      const std::uint32_t v = (std::uint32_t{bytes[i]} << 16) | (left > 1 ? std::uint32_t{bytes[i + 1]} << 8 : 0u) |
                              (left > 2 ? bytes[i + 2] : 0u);
      emit(kAlphabet[v >> 18]);
      emit(kAlphabet[(v >> 12) & 0x3F]);
      emit(left > 1 ? kAlphabet[(v >> 6) & 0x3F] : '=');
      emit(left > 2 ? kAlphabet[v & 0x3F] : '=');
    }
    emit('"');
    put(std::string_view(chunk.data(), used));
    if (depth_ == 0) done_ = true;
    return *this;
  }
  if (need > buffer_.size() - size_) {
    fail(Error::format(Errc::capacity, "JSON output exceeds the %zu-byte buffer", buffer_.size()));
    return *this;
  }
  char* out = buffer_.data() + size_;
  *out++ = '"';
  const std::uint8_t* in = bytes.data();
  for (std::size_t i = 0; i < whole; i += 3) {
    const std::uint32_t v = (std::uint32_t{in[i]} << 16) | (std::uint32_t{in[i + 1]} << 8) | in[i + 2];
    out[0] = kAlphabet[v >> 18];
    out[1] = kAlphabet[(v >> 12) & 0x3F];
    out[2] = kAlphabet[(v >> 6) & 0x3F];
    out[3] = kAlphabet[v & 0x3F];
    out += 4;
  }
  if (const std::size_t tail = n - whole; tail != 0) {
    const std::uint32_t v = (std::uint32_t{in[whole]} << 16) | (tail == 2 ? std::uint32_t{in[whole + 1]} << 8 : 0u);
    out[0] = kAlphabet[v >> 18];
    out[1] = kAlphabet[(v >> 12) & 0x3F];
    out[2] = tail == 2 ? kAlphabet[(v >> 6) & 0x3F] : '=';
    out[3] = '=';
    out += 4;
  }
  *out++ = '"';
  size_ = static_cast<std::size_t>(out - buffer_.data());
  if (depth_ == 0) done_ = true;
  return *this;
}

Writer& Writer::boolean(bool value) noexcept {
  if (!before_value()) return *this;
  put(value ? "true" : "false");
  if (depth_ == 0) done_ = true;
  return *this;
}

Writer& Writer::null() noexcept {
  if (!before_value()) return *this;
  put("null");
  if (depth_ == 0) done_ = true;
  return *this;
}

Writer& Writer::raw(std::string_view json) noexcept {
  if (failed_) return *this;
  if (Status st = validate(json); !st) {
    fail(Error::format(Errc::invalid_argument, "JSON writer: raw value is not JSON: %s", st.error().c_str()));
    return *this;
  }
  if (!before_value()) return *this;
  put(json);
  if (depth_ == 0) done_ = true;
  return *this;
}

Result<std::string_view> Writer::finish() const noexcept {
  if (failed_) return error_;
  if (depth_ != 0 || !done_) return Error(Errc::invalid_argument, "JSON writer: the value is incomplete");
  if (sink_ != nullptr) return std::string_view();
  return std::string_view(buffer_.data(), size_);
}

}  // namespace sen3bot::json
