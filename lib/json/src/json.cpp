#include "sen3bot/json/json.hpp"

#include <charconv>
#include <cstdarg>
#include <cstdio>
#include <cmath>
#include <limits>

namespace sen3bot::json {
namespace {

// Length of the well-formed UTF-8 sequence at s (RFC 3629: no overlongs, no surrogates,
// nothing above U+10FFFF), or 0 when it is not one.
std::size_t utf8_length(const unsigned char* s, std::size_t avail) noexcept {
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

int hex_digit(char c) noexcept {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

// Four hex digits at s (already known to be there), or -1.
long hex4(const char* s) noexcept {
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

// Whether two string bodies (either possibly escaped) unescape to the same bytes.
bool same_string(std::string_view a, bool a_escaped, std::string_view b, bool b_escaped) noexcept {
  if (!a_escaped && !b_escaped) return a == b;
  std::size_t i = 0, j = 0;
  char ca[4], cb[4];
  std::size_t na = 0, nb = 0, ia = 0, ib = 0;
  for (;;) {
    if (ia == na) {
      if (i == a.size()) {
        na = 0;
      } else {
        na = a_escaped ? next_char(a, i, ca) : (ca[0] = a[i++], 1);
      }
      ia = 0;
    }
    if (ib == nb) {
      if (j == b.size()) {
        nb = 0;
      } else {
        nb = b_escaped ? next_char(b, j, cb) : (cb[0] = b[j++], 1);
      }
      ib = 0;
    }
    if (na == 0 || nb == 0) return na == 0 && nb == 0;
    if (ca[ia++] != cb[ib++]) return false;
  }
}

}  // namespace

std::string_view to_string(Type type) noexcept {
  switch (type) {
    case Type::null: return "null";
    case Type::boolean: return "boolean";
    case Type::number: return "number";
    case Type::string: return "string";
    case Type::array: return "array";
    case Type::object: return "object";
  }
  return "null";
}

// ---- reader ----

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

// ---- values ----

const Token& Value::token() const noexcept { return doc_->token(index_); }
Type Value::type() const noexcept { return token().type; }
std::size_t Value::offset() const noexcept {
  if (!valid()) return 0;
  return token().type == Type::string ? token().start - 1 : token().start;
}

std::string_view Value::json_text() const noexcept {
  if (!valid()) return {};
  const Token& t = token();
  if (t.type == Type::string) return doc_->text().substr(t.start - 1, t.end - t.start + 2);
  return doc_->text().substr(t.start, t.end - t.start);
}

Value Value::find(std::string_view key) const noexcept {
  if (!is(Type::object)) return {};
  const std::uint32_t end = token().next;
  for (std::uint32_t i = index_ + 1; i < end; i = doc_->token(i + 1).next) {
    if (Value(doc_, i).string_equals(key)) return {doc_, i + 1};
  }
  return {};
}

std::size_t Value::size() const noexcept {
  if (!is(Type::array) && !is(Type::object)) return 0;
  const bool object = type() == Type::object;
  std::size_t n = 0;
  for (std::uint32_t i = index_ + 1; i < token().next; i = doc_->token(object ? i + 1 : i).next) ++n;
  return n;
}

Value::Range<Value::ItemIterator> Value::items() const noexcept {
  if (!is(Type::array)) return {ItemIterator(nullptr, 0), ItemIterator(nullptr, 0)};
  return {ItemIterator(doc_, index_ + 1), ItemIterator(doc_, token().next)};
}

Value::Range<Value::MemberIterator> Value::members() const noexcept {
  if (!is(Type::object)) return {MemberIterator(nullptr, 0), MemberIterator(nullptr, 0)};
  return {MemberIterator(doc_, index_ + 1), MemberIterator(doc_, token().next)};
}

Value::ItemIterator& Value::ItemIterator::operator++() noexcept {
  index_ = doc_->token(index_).next;
  return *this;
}

Value::Member Value::MemberIterator::operator*() const noexcept { return {Value(doc_, index_), Value(doc_, index_ + 1)}; }

Value::MemberIterator& Value::MemberIterator::operator++() noexcept {
  index_ = doc_->token(index_ + 1).next;
  return *this;
}

namespace {
Error type_error(const Value& v, Type want) noexcept {
  if (!v.valid()) return Error::format(Errc::invalid_argument, "missing value, %s expected", to_string(want).data());
  return Error::format(Errc::invalid_argument, "byte %zu: %s expected, got %s", v.offset(), to_string(want).data(),
                       to_string(v.type()).data());
}
}  // namespace

Result<bool> Value::boolean() const noexcept {
  if (!is(Type::boolean)) return type_error(*this, Type::boolean);
  return json_text() == "true";
}

Result<double> Value::number() const noexcept {
  if (!is(Type::number)) return type_error(*this, Type::number);
  const std::string_view t = json_text();
  double v = 0;
  std::from_chars(t.data(), t.data() + t.size(), v);  // checked by the parser
  return v;
}

Result<std::uint32_t> Value::uint32() const noexcept {
  if (!is(Type::number)) return type_error(*this, Type::number);
  const std::string_view t = json_text();
  bool digits_only = true;
  for (char c : t) digits_only = digits_only && c >= '0' && c <= '9';
  if (digits_only) {
    std::uint32_t v = 0;
    const auto r = std::from_chars(t.data(), t.data() + t.size(), v);
    if (r.ec == std::errc() && r.ptr == t.data() + t.size()) return v;
    return Error::format(Errc::invalid_argument, "byte %zu: %.*s is above the uint32 range", offset(),
                         static_cast<int>(t.size() < 40 ? t.size() : 40), t.data());
  }
  const double v = *number();
  if (v != std::floor(v))
    return Error::format(Errc::invalid_argument, "byte %zu: %.*s is not an integer", offset(),
                         static_cast<int>(t.size() < 40 ? t.size() : 40), t.data());
  if (v < 0 || v > 4294967295.0)
    return Error::format(Errc::invalid_argument, "byte %zu: %.*s is outside the uint32 range", offset(),
                         static_cast<int>(t.size() < 40 ? t.size() : 40), t.data());
  return static_cast<std::uint32_t>(v);
}

Result<std::size_t> Value::string(std::span<char> buf) const noexcept {
  if (!is(Type::string)) return type_error(*this, Type::string);
  const Token& t = token();
  const std::string_view body = doc_->text().substr(t.start, t.end - t.start);
  std::size_t n = 0;
  const auto too_long = [&] {
    return Error::format(Errc::capacity, "byte %zu: string longer than %zu bytes", offset(), buf.size());
  };
  if (!t.escaped) {
    if (body.size() > buf.size()) return too_long();
    for (char c : body) buf[n++] = c;
    return n;
  }
  char ch[4];
  for (std::size_t i = 0; i < body.size();) {
    const std::size_t k = next_char(body, i, ch);
    if (n + k > buf.size()) return too_long();
    for (std::size_t j = 0; j < k; ++j) buf[n++] = ch[j];
  }
  return n;
}

bool Value::string_equals(std::string_view text) const noexcept {
  if (!is(Type::string)) return false;
  const Token& t = token();
  return same_string(doc_->text().substr(t.start, t.end - t.start), t.escaped, text, false);
}

Status validate(std::string_view text) noexcept {
  StaticDocument<256> doc(Limits{32, text.size()});
  return doc.parse(text);
}

// ---- writer ----

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

Writer& Writer::uint32(std::uint32_t value) noexcept {
  if (!before_value()) return *this;
  char buf[16];
  const auto r = std::to_chars(buf, buf + sizeof buf, value);
  put(std::string_view(buf, static_cast<std::size_t>(r.ptr - buf)));
  if (depth_ == 0) done_ = true;
  return *this;
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
