#pragma once
// A strict RFC 8259 JSON reader and a JSON writer, both in fixed memory.
//
// The reader tokenises a whole message into a caller-supplied token array in one pass and
// keeps views into the text (which must outlive the document). Everything the RFC forbids is
// an error with the byte offset and the reason, and so are the limits that keep it bounded:
// duplicate member names, nesting deeper than the limit, more tokens than the array holds,
// input longer than the size limit, numbers a double cannot hold. Nothing is allocated.
//
// The writer inserts commas itself and writes either into a caller's fixed buffer (nothing is
// allocated: the robot's real-time paths) or to a Sink (a std::string or a FILE*: commands and
// reports). An overflow, a failed write, a NaN or an unbalanced structure is reported by
// finish() instead of yielding truncated text.
//
// Strings are escaped as RFC 8259 asks: \" \\ \b \f \n \r \t, the other control characters
// as \u00XX; every other byte is copied unchanged, so UTF-8 stays as it is. A byte that does not
// belong to a valid UTF-8 sequence is written as U+FFFD (the output is always valid UTF-8, and
// text from a device or a file still comes out instead of failing the whole document).
#include <array>
#include <cstddef>
#include <cstdint>
#include <cstdio>
#include <span>
#include <string>
#include <string_view>

#include "sen3bot/hal/result.hpp"

namespace sen3bot::json {

enum class Type : std::uint8_t { null, boolean, number, string, array, object };
std::string_view to_string(Type type) noexcept;  // "null", "boolean", ...

// One value (or member name) of a parsed document. Containers are followed by their
// children; `next` is the index just past the subtree, so siblings are a hop apart.
struct Token {
  std::uint32_t start = 0;  // first byte of the value (strings: after the opening quote)
  std::uint32_t end = 0;    // one past the last byte (strings: before the closing quote)
  std::uint32_t next = 0;
  Type type = Type::null;
  bool escaped = false;     // a string with backslash escapes (unescape before use)
};

struct Limits {
  std::size_t max_depth = 32;          // nested arrays/objects
  std::size_t max_bytes = 256 * 1024;  // whole input
};
inline constexpr std::size_t kDepthCeiling = 64;  // Limits::max_depth is clamped to this

class Document;

// A view of one value in a document; a default or missing one is !valid().
class Value {
 public:
  Value() = default;
  Value(const Document* doc, std::uint32_t index) noexcept : doc_(doc), index_(index) {}

  [[nodiscard]] bool valid() const noexcept { return doc_ != nullptr; }
  [[nodiscard]] Type type() const noexcept;
  [[nodiscard]] bool is(Type t) const noexcept { return valid() && type() == t; }
  [[nodiscard]] std::size_t offset() const noexcept;  // byte offset in the text
  // The value's JSON text as it appears in the input (strings with their quotes).
  [[nodiscard]] std::string_view json_text() const noexcept;

  // Object member by (unescaped) name; !valid() when absent or this is not an object.
  [[nodiscard]] Value find(std::string_view key) const noexcept;
  // Elements of an array or members of an object.
  [[nodiscard]] std::size_t size() const noexcept;

  // Arrays: for (Value v : value.items()). Objects: for (Member m : value.members()).
  class ItemIterator;
  class MemberIterator;
  struct Member;
  template <typename It>
  struct Range {
    It first, last;
    It begin() const noexcept { return first; }
    It end() const noexcept { return last; }
  };
  [[nodiscard]] Range<ItemIterator> items() const noexcept;
  [[nodiscard]] Range<MemberIterator> members() const noexcept;

  // Typed access; a type mismatch or range violation is Errc::invalid_argument with the offset.
  [[nodiscard]] Result<bool> boolean() const noexcept;
  [[nodiscard]] Result<double> number() const noexcept;
  // An integral number in [0, 2^32 - 1] (written as an integer, or with a zero fraction).
  [[nodiscard]] Result<std::uint32_t> uint32() const noexcept;
  // The unescaped string into buf; Errc::capacity when it does not fit. Returns its length.
  [[nodiscard]] Result<std::size_t> string(std::span<char> buf) const noexcept;
  // The unescaped string into anything with `bool assign(std::string_view)` (a FixedString).
  template <typename S>
  [[nodiscard]] Status string_to(S& out) const noexcept {
    std::array<char, S::kCapacity + 1> buf;  // +1: tells "fits" from "too long"
    auto n = string(buf);
    if (!n) return n.error();
    if (!out.assign(std::string_view(buf.data(), *n)))
      return Error::format(Errc::capacity, "string at byte %zu longer than %zu bytes", offset(), S::kCapacity);
    return {};
  }
  // Compares the unescaped string with text without copying it.
  [[nodiscard]] bool string_equals(std::string_view text) const noexcept;

  [[nodiscard]] std::uint32_t index() const noexcept { return index_; }
  [[nodiscard]] const Token& token() const noexcept;

 private:
  const Document* doc_ = nullptr;
  std::uint32_t index_ = 0;
};

struct Value::Member {
  Value key;  // a string
  Value value;
};

class Value::ItemIterator {
 public:
  ItemIterator(const Document* doc, std::uint32_t index) noexcept : doc_(doc), index_(index) {}
  Value operator*() const noexcept { return {doc_, index_}; }
  ItemIterator& operator++() noexcept;
  bool operator==(const ItemIterator& other) const noexcept { return index_ == other.index_; }

 private:
  const Document* doc_;
  std::uint32_t index_;
};

class Value::MemberIterator {
 public:
  MemberIterator(const Document* doc, std::uint32_t index) noexcept : doc_(doc), index_(index) {}
  Member operator*() const noexcept;
  MemberIterator& operator++() noexcept;
  bool operator==(const MemberIterator& other) const noexcept { return index_ == other.index_; }

 private:
  const Document* doc_;
  std::uint32_t index_;
};

// Parses into a token array it does not own. parse() may be called again with new text.
class Document {
 public:
  explicit Document(std::span<Token> tokens, Limits limits = {}) noexcept;

  // Errc::protocol for malformed JSON, Errc::capacity for a limit; the message gives the
  // byte offset and the reason. After an error root() is !valid().
  Status parse(std::string_view text) noexcept;

  [[nodiscard]] Value root() const noexcept { return count_ ? Value(this, 0) : Value(); }
  [[nodiscard]] std::string_view text() const noexcept { return text_; }
  [[nodiscard]] std::size_t token_count() const noexcept { return count_; }
  [[nodiscard]] std::size_t token_capacity() const noexcept { return tokens_.size(); }
  [[nodiscard]] const Token& token(std::uint32_t i) const noexcept { return tokens_[i]; }
  [[nodiscard]] const Limits& limits() const noexcept { return limits_; }

 private:
  class Parser;
  std::span<Token> tokens_;
  Limits limits_;
  std::string_view text_;
  std::uint32_t count_ = 0;
};

// A document with its own token array (keep large ones static or in a long-lived object).
template <std::size_t N>
class StaticDocument : public Document {
 public:
  explicit StaticDocument(Limits limits = {}) noexcept : Document(std::span<Token>(), limits) {
    static_cast<Document&>(*this) = Document(std::span<Token>(storage_), limits);
  }
  StaticDocument(const StaticDocument&) = delete;
  StaticDocument& operator=(const StaticDocument&) = delete;

 private:
  std::array<Token, N> storage_{};
};

// Checks that text is one complete JSON value (used for action parameter values given as
// JSON text). At most 256 tokens; a bigger value is Errc::capacity.
Status validate(std::string_view text) noexcept;

// Where a Writer's text goes when it is not a fixed buffer.
class Sink {
 public:
  // Appends text; false when it could not be written (the writer then fails with Errc::io).
  virtual bool write(std::string_view text) noexcept = 0;

 protected:
  ~Sink() = default;
};

// Appends to a std::string (allocates: not for the real-time paths).
class StringSink final : public Sink {
 public:
  explicit StringSink(std::string& out) noexcept : out_(out) {}
  bool write(std::string_view text) noexcept override {
    out_.append(text);
    return true;
  }

 private:
  std::string& out_;
};

// Writes to a stdio stream; a short write fails the writer.
class FileSink final : public Sink {
 public:
  explicit FileSink(std::FILE* file) noexcept : file_(file) {}
  bool write(std::string_view text) noexcept override {
    return std::fwrite(text.data(), 1, text.size(), file_) == text.size();
  }

 private:
  std::FILE* file_;
};

// The whitespace between tokens. compact: {"a":1,"b":[1,2]}. spaced: {"a": 1, "b": [1, 2]},
// the form the simulator's reports have always printed. line() adds line breaks to either.
enum class Style : std::uint8_t { compact, spaced };

class Writer {
 public:
  explicit Writer(std::span<char> buffer, Style style = Style::compact) noexcept : buffer_(buffer), style_(style) {}
  explicit Writer(Sink& sink, Style style = Style::compact) noexcept : sink_(&sink), style_(style) {}

  Writer& begin_object() noexcept;
  Writer& end_object() noexcept;
  Writer& begin_array() noexcept;
  Writer& end_array() noexcept;
  Writer& key(std::string_view name) noexcept;  // inside an object, before each value
  Writer& string(std::string_view text) noexcept;  // escaped; invalid UTF-8 bytes as U+FFFD
  Writer& number(double value) noexcept;  // shortest text that reads back the same double
  // Fixed notation with `decimals` digits after the point (printf's "%.*f"; decimals <= 17).
  Writer& fixed(double value, int decimals) noexcept;
  // fixed(), or null when the value is NaN or infinite (JSON has neither).
  Writer& fixed_or_null(double value, int decimals) noexcept;
  // `digits` significant digits, fixed or exponent form, trailing zeros dropped (printf's
  // "%.*g"; 1 <= digits <= 17).
  Writer& general(double value, int digits) noexcept;
  Writer& uint32(std::uint32_t value) noexcept;
  Writer& int64(std::int64_t value) noexcept;
  Writer& uint64(std::uint64_t value) noexcept;
  // Shortest text that reads back the same float (fewer digits than the float as a double).
  Writer& float32(float value) noexcept;
  // A string of the bytes in standard base64 (RFC 4648 section 4, padded).
  Writer& base64(std::span<const std::uint8_t> bytes) noexcept;
  Writer& boolean(bool value) noexcept;
  Writer& null() noexcept;
  Writer& raw(std::string_view json) noexcept;  // a complete JSON value, validated first

  // The next separator (after a comma, after an opening bracket or before a closing one) is a
  // line break and `indent` spaces instead of the style's space or nothing.
  Writer& line(std::size_t indent) noexcept;

  // Shorthands for a member: key(name) then the value.
  Writer& member(std::string_view name, std::string_view text) noexcept { return key(name).string(text); }
  Writer& member_number(std::string_view name, double value) noexcept { return key(name).number(value); }
  Writer& member_fixed(std::string_view name, double value, int decimals) noexcept {
    return key(name).fixed(value, decimals);
  }
  Writer& member_uint32(std::string_view name, std::uint32_t value) noexcept { return key(name).uint32(value); }
  Writer& member_int64(std::string_view name, std::int64_t value) noexcept { return key(name).int64(value); }
  Writer& member_uint64(std::string_view name, std::uint64_t value) noexcept { return key(name).uint64(value); }
  Writer& member_bool(std::string_view name, bool value) noexcept { return key(name).boolean(value); }

  // The text written (empty when writing to a sink), or the first error (Errc::capacity on
  // overflow, Errc::io when the sink failed, invalid_argument on misuse, NaN/infinity or an
  // unclosed container).
  [[nodiscard]] Result<std::string_view> finish() const noexcept;
  [[nodiscard]] bool failed() const noexcept { return failed_; }
  [[nodiscard]] std::size_t size() const noexcept { return size_; }  // bytes written so far

 private:
  bool before_value() noexcept;
  void separator(bool after_comma) noexcept;
  void put(std::string_view text) noexcept;
  void put(char c) noexcept;
  void fail(Error error) noexcept;
  void escaped(std::string_view text) noexcept;
  template <typename T>
  Writer& integer(T value) noexcept;
  Writer& open(char c, bool object) noexcept;
  Writer& close(char c, bool object) noexcept;

  std::span<char> buffer_;
  Sink* sink_ = nullptr;
  std::size_t size_ = 0;
  bool failed_ = false;
  Style style_ = Style::compact;
  Error error_;
  // Per open container: is it an object, has it a first element yet. Bit i = depth i.
  std::uint64_t object_bits_ = 0;
  std::uint64_t nonempty_bits_ = 0;
  std::size_t depth_ = 0;
  std::size_t line_indent_ = 0;
  bool line_pending_ = false;
  bool after_key_ = false;
  bool done_ = false;  // a complete top-level value was written
};

}  // namespace sen3bot::json
