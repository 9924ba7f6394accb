// The reader: one pass over the text into the document's token array.
#include "sen3bot/json/json.hpp"

#include <charconv>
#include <cmath>
#include <cstdarg>
#include <cstdio>
#include <limits>

#include "string_body.hpp"

namespace sen3bot::json {

using detail::hex4;
using detail::same_string;
using detail::utf8_length;

class Document::Parser {
 public:
  Parser(Document& doc, std::string_view text) noexcept : d_(doc), s_(text) {}

  Status run() noexcept {
    if (s_.size() > d_.limits_.max_bytes)
      return Error::format(Errc::capacity, "byte %zu: input longer than the %zu-byte limit", d_.limits_.max_bytes,
                           d_.limits_.max_bytes);
    const std::size_t max_depth = d_.limits_.max_depth < kDepthCeiling ? d_.limits_.max_depth : kDepthCeiling;
    skip_ws();
    if (pos_ == s_.size()) return fail("empty input");
    for (;;) {
      // A value starts here.
      skip_ws();
      if (pos_ == s_.size()) return fail("unexpected end of input, a value expected");
      const char c = s_[pos_];
      if (c == '{' || c == '[') {
        const bool object = c == '{';
        if (depth_ == max_depth) return fail_fmt(Errc::capacity, "nesting deeper than %zu levels", max_depth);
        auto t = add(object ? Type::object : Type::array);
        if (!t) return t.error();
        stack_[depth_++] = *t;
        ++pos_;
        skip_ws();
        if (pos_ < s_.size() && s_[pos_] == (object ? '}' : ']')) {
          close();
        } else if (object) {
          if (Status st = member_name(); !st) return st;
          continue;
        } else {
          continue;
        }
      } else if (c == '"') {
        if (Status st = string(); !st) return st;
      } else if (c == '-' || (c >= '0' && c <= '9')) {
        if (Status st = number(); !st) return st;
      } else if (c == 't' || c == 'f' || c == 'n') {
        if (Status st = literal(); !st) return st;
      } else {
        return unexpected("a value expected");
      }
      // After a value: close containers or move to the next element.
      for (;;) {
        if (depth_ == 0) {
          skip_ws();
          if (pos_ != s_.size()) return unexpected("trailing data after the value");
          d_.count_ = count_;
          return {};
        }
        skip_ws();
        const bool object = d_.tokens_[stack_[depth_ - 1]].type == Type::object;
        if (pos_ == s_.size()) return fail(object ? "unexpected end of input, ',' or '}' expected"
                                                  : "unexpected end of input, ',' or ']' expected");
        const char n = s_[pos_];
        if (n == ',') {
          ++pos_;
          if (object) {
            skip_ws();
            if (Status st = member_name(); !st) return st;
          }
          break;
        }
        if (n == (object ? '}' : ']')) {
          if (object) {
            if (Status st = check_duplicates(stack_[depth_ - 1]); !st) return st;
          }
          close();
          continue;
        }
        return unexpected(object ? "',' or '}' expected" : "',' or ']' expected");
      }
    }
  }

 private:
  Status fail(const char* reason) const noexcept {
    return Error::format(Errc::protocol, "byte %zu: %s", pos_, reason);
  }
  [[gnu::format(printf, 3, 4)]] Status fail_fmt(Errc code, const char* fmt, ...) const noexcept {
    char reason[160];
    va_list args;
    va_start(args, fmt);
    std::vsnprintf(reason, sizeof reason, fmt, args);
    va_end(args);
    return Error::format(code, "byte %zu: %s", pos_, reason);
  }
  Status unexpected(const char* what) const noexcept {
    const auto b = static_cast<unsigned char>(s_[pos_]);
    if (b >= 0x20 && b < 0x7F) return fail_fmt(Errc::protocol, "unexpected '%c', %s", b, what);
    return fail_fmt(Errc::protocol, "unexpected byte 0x%02x, %s", b, what);
  }

  void skip_ws() noexcept {
    while (pos_ < s_.size() && (s_[pos_] == ' ' || s_[pos_] == '\t' || s_[pos_] == '\n' || s_[pos_] == '\r')) ++pos_;
  }

  Result<std::uint32_t> add(Type type) noexcept {
    if (count_ == d_.tokens_.size())
      return fail_fmt(Errc::capacity, "more than %zu tokens", d_.tokens_.size()).error();
    Token& t = d_.tokens_[count_];
    t = Token{};
    t.type = type;
    t.start = static_cast<std::uint32_t>(pos_);
    t.end = static_cast<std::uint32_t>(pos_);
    t.next = count_ + 1;
    return count_++;
  }

  void close() noexcept {
    Token& t = d_.tokens_[stack_[--depth_]];
    ++pos_;
    t.end = static_cast<std::uint32_t>(pos_);
    t.next = count_;
  }

  Status member_name() noexcept {
    if (pos_ == s_.size()) return fail("unexpected end of input, a member name expected");
    if (s_[pos_] != '"') return unexpected("a member name (string) expected");
    if (Status st = string(); !st) return st;
    skip_ws();
    if (pos_ == s_.size()) return fail("unexpected end of input, ':' expected");
    if (s_[pos_] != ':') return unexpected("':' expected");
    ++pos_;
    return {};
  }

  Status string() noexcept {
    auto t = add(Type::string);
    if (!t) return t.error();
    ++pos_;
    const std::size_t start = pos_;
    bool escaped = false;
    const auto* u = reinterpret_cast<const unsigned char*>(s_.data());
    for (;;) {
      if (pos_ == s_.size()) return fail("unterminated string");
      const unsigned char c = u[pos_];
      if (c == '"') break;
      if (c < 0x20) return fail_fmt(Errc::protocol, "control character 0x%02x in a string", c);
      if (c == '\\') {
        escaped = true;
        if (Status st = escape(); !st) return st;
        continue;
      }
      if (c >= 0x80) {
        const std::size_t n = utf8_length(u + pos_, s_.size() - pos_);
        if (n == 0) return fail("invalid UTF-8 in a string");
        pos_ += n;
        continue;
      }
      ++pos_;
    }
    Token& tok = d_.tokens_[*t];
    tok.start = static_cast<std::uint32_t>(start);
    tok.end = static_cast<std::uint32_t>(pos_);
    tok.escaped = escaped;
    ++pos_;
    return {};
  }

  Status escape() noexcept {
    if (pos_ + 1 >= s_.size()) return fail("unterminated escape");
    const char e = s_[pos_ + 1];
    if (e == '"' || e == '\\' || e == '/' || e == 'b' || e == 'f' || e == 'n' || e == 'r' || e == 't') {
      pos_ += 2;
      return {};
    }
    if (e != 'u') return fail_fmt(Errc::protocol, "invalid escape '\\%c'", e >= 0x20 && e < 0x7F ? e : '?');
    if (pos_ + 6 > s_.size() || hex4(s_.data() + pos_ + 2) < 0) return fail("\\u needs four hex digits");
    const long cp = hex4(s_.data() + pos_ + 2);
    if (cp >= 0xDC00 && cp <= 0xDFFF) return fail("unpaired low surrogate in \\u escape");
    if (cp >= 0xD800 && cp <= 0xDBFF) {
      const std::size_t low = pos_ + 6;
      if (low + 6 > s_.size() || s_[low] != '\\' || s_[low + 1] != 'u') return fail("unpaired high surrogate in \\u escape");
      const long lo = hex4(s_.data() + low + 2);
      if (lo < 0xDC00 || lo > 0xDFFF) return fail("unpaired high surrogate in \\u escape");
      pos_ += 12;
      return {};
    }
    pos_ += 6;
    return {};
  }

  Status number() noexcept {
    auto t = add(Type::number);
    if (!t) return t.error();
    const std::size_t start = pos_;
    const auto digit = [&] { return pos_ < s_.size() && s_[pos_] >= '0' && s_[pos_] <= '9'; };
    if (s_[pos_] == '-') ++pos_;
    if (!digit()) return fail("a digit expected in a number");
    if (s_[pos_] == '0') {
      ++pos_;
      if (digit()) return fail("leading zero in a number");
    } else {
      while (digit()) ++pos_;
    }
    if (pos_ < s_.size() && s_[pos_] == '.') {
      ++pos_;
      if (!digit()) return fail("a digit expected after the decimal point");
      while (digit()) ++pos_;
    }
    if (pos_ < s_.size() && (s_[pos_] == 'e' || s_[pos_] == 'E')) {
      ++pos_;
      if (pos_ < s_.size() && (s_[pos_] == '+' || s_[pos_] == '-')) ++pos_;
      if (!digit()) return fail("a digit expected in the exponent");
      while (digit()) ++pos_;
    }
    double v = 0;
    const auto r = std::from_chars(s_.data() + start, s_.data() + pos_, v);
    if (r.ec == std::errc::result_out_of_range || (r.ec == std::errc() && !std::isfinite(v))) {
      const std::size_t at = pos_;
      pos_ = start;
      Status st = fail("number out of range for a double");
      pos_ = at;
      return st;
    }
    if (r.ec != std::errc() || r.ptr != s_.data() + pos_) return fail("malformed number");
    Token& tok = d_.tokens_[*t];
    tok.start = static_cast<std::uint32_t>(start);
    tok.end = static_cast<std::uint32_t>(pos_);
    return {};
  }

  Status literal() noexcept {
    const std::string_view rest = s_.substr(pos_);
    Type type = Type::null;
    std::size_t n = 0;
    if (rest.starts_with("true")) {
      type = Type::boolean;
      n = 4;
    } else if (rest.starts_with("false")) {
      type = Type::boolean;
      n = 5;
    } else if (rest.starts_with("null")) {
      n = 4;
    } else {
      return unexpected("a value expected");
    }
    auto t = add(type);
    if (!t) return t.error();
    pos_ += n;
    d_.tokens_[*t].end = static_cast<std::uint32_t>(pos_);
    return {};
  }

  // Member names of the object at token `obj` (just closed but for its `next`) are unique.
  Status check_duplicates(std::uint32_t obj) const noexcept {
    const auto& tk = d_.tokens_;
    const auto body = [&](std::uint32_t i) { return s_.substr(tk[i].start, tk[i].end - tk[i].start); };
    for (std::uint32_t a = obj + 1; a < count_; a = tk[a + 1].next) {
      for (std::uint32_t b = tk[a + 1].next; b < count_; b = tk[b + 1].next) {
        if (!tk[a].escaped && !tk[b].escaped && tk[a].end - tk[a].start != tk[b].end - tk[b].start) continue;
        if (same_string(body(a), tk[a].escaped, body(b), tk[b].escaped)) {
          const std::string_view name = body(b);
          return Error::format(Errc::protocol, "byte %u: duplicate member name \"%.*s\"", tk[b].start - 1,
                               static_cast<int>(name.size() < 64 ? name.size() : 64), name.data());
        }
      }
    }
    return {};
  }

  Document& d_;
  std::string_view s_;
  std::size_t pos_ = 0;
  std::uint32_t count_ = 0;
  std::size_t depth_ = 0;
  std::array<std::uint32_t, kDepthCeiling> stack_{};
};

Document::Document(std::span<Token> tokens, Limits limits) noexcept : tokens_(tokens), limits_(limits) {
  // Offsets are 32-bit.
  if (limits_.max_bytes > std::numeric_limits<std::uint32_t>::max() - 1)
    limits_.max_bytes = std::numeric_limits<std::uint32_t>::max() - 1;
  if (tokens_.size() > std::numeric_limits<std::uint32_t>::max() - 1)
    tokens_ = tokens_.first(std::numeric_limits<std::uint32_t>::max() - 1);
}

Status Document::parse(std::string_view text) noexcept {
  text_ = text;
  count_ = 0;
  Parser parser(*this, text);
  Status st = parser.run();
  if (!st) count_ = 0;
  return st;
}

Status validate(std::string_view text) noexcept {
  StaticDocument<256> doc(Limits{32, text.size()});
  return doc.parse(text);
}

}  // namespace sen3bot::json
