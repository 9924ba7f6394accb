// The values of a parsed document: their place in the text, their children and typed access.
#include "sen3bot/json/json.hpp"

#include <charconv>
#include <cmath>

#include "string_body.hpp"

namespace sen3bot::json {

using detail::next_char;
using detail::same_string;

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

}  // namespace sen3bot::json
