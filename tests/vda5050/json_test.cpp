// The JSON reader refuses what RFC 8259 refuses (with the byte offset and the reason) and what
// exceeds its limits; the writer escapes, keeps UTF-8, round-trips doubles, prints fixed
// decimals as printf does, writes to every sink alike and reports overflow.
#include "sen3bot/json/json.hpp"

#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdio>
#include <limits>
#include <string>
#include <vector>

#include "sen3bot/vda5050/types.hpp"

namespace sen3bot::json {
namespace {

struct Parsed {
  StaticDocument<64> doc;
  Status status;
  explicit Parsed(std::string_view text, Limits limits = {}) : doc(limits), status(doc.parse(text)) {}
};

// The error message of parsing text, or "" when it parses.
std::string error_of(std::string_view text, Limits limits = {}) {
  Parsed p(text, limits);
  return p.status ? std::string() : std::string(p.status.error().message());
}

TEST(JsonReader, ParsesNestedValues) {
  Parsed p(R"( {"a": [1, -2.5e3, true, false, null], "b": {"c": "d"}, "e": ""} )");
  ASSERT_TRUE(p.status) << p.status.error().c_str();
  Value root = p.doc.root();
  ASSERT_TRUE(root.is(Type::object));
  EXPECT_EQ(root.size(), 3u);
  Value a = root.find("a");
  ASSERT_TRUE(a.is(Type::array));
  EXPECT_EQ(a.size(), 5u);
  std::array<Type, 5> types{Type::number, Type::number, Type::boolean, Type::boolean, Type::null};
  std::size_t i = 0;
  for (Value v : a.items()) EXPECT_EQ(v.type(), types[i++]);
  EXPECT_EQ(i, 5u);
  EXPECT_EQ(*a.items().begin().operator*().uint32(), 1u);
  EXPECT_FALSE(root.find("b").find("x").valid());
  EXPECT_TRUE(root.find("b").find("c").string_equals("d"));
  std::size_t members = 0;
  for (Value::Member m : root.members()) {
    EXPECT_TRUE(m.key.is(Type::string));
    ++members;
  }
  EXPECT_EQ(members, 3u);
  EXPECT_FALSE(root.find("missing").valid());
  EXPECT_FALSE(root.find("a").find("x").valid());  // not an object
}

TEST(JsonReader, NumbersAndRanges) {
  Parsed p(R"([0, 4294967295, 4294967296, -1, 1.5, 1e2, 1.0, -0, 0.1, 1.7976931348623157e308])");
  ASSERT_TRUE(p.status);
  std::array<Value, 10> v;
  std::size_t i = 0;
  for (Value x : p.doc.root().items()) v[i++] = x;
  EXPECT_EQ(*v[0].uint32(), 0u);
  EXPECT_EQ(*v[1].uint32(), 4294967295u);
  EXPECT_FALSE(v[2].uint32());
  EXPECT_NE(v[2].uint32().error().message().find("uint32"), std::string_view::npos);
  EXPECT_FALSE(v[3].uint32());
  EXPECT_FALSE(v[4].uint32());
  EXPECT_EQ(*v[5].uint32(), 100u);
  EXPECT_EQ(*v[6].uint32(), 1u);
  EXPECT_EQ(*v[7].uint32(), 0u);
  EXPECT_EQ(*v[8].number(), 0.1);
  EXPECT_EQ(*v[9].number(), std::numeric_limits<double>::max());
  EXPECT_FALSE(v[8].boolean());
  EXPECT_FALSE(v[8].string(std::span<char>()));
}

TEST(JsonReader, StringsUnescape) {
  Parsed p(R"(["a\"b\\c\/d\b\f\n\r\t", "\u00e9\u20ac\ud83d\ude00", "caf\u00e9", "\u0000"])");
  ASSERT_TRUE(p.status) << p.status.error().c_str();
  std::array<Value, 4> v;
  std::size_t i = 0;
  for (Value x : p.doc.root().items()) v[i++] = x;
  char buf[32];
  EXPECT_EQ(std::string(buf, *v[0].string(buf)), "a\"b\\c/d\b\f\n\r\t");
  EXPECT_EQ(std::string(buf, *v[1].string(buf)), "\xc3\xa9\xe2\x82\xac\xf0\x9f\x98\x80");
  EXPECT_TRUE(v[2].string_equals("caf\xc3\xa9"));
  EXPECT_FALSE(v[2].string_equals("cafe"));
  EXPECT_EQ(*v[3].string(buf), 1u);
  EXPECT_EQ(buf[0], '\0');
  // Too small a buffer is an error, not a cut.
  char small[3];
  auto r = v[0].string(small);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code(), Errc::capacity);
  vda5050::FixedString<4> fs;
  EXPECT_FALSE(v[0].string_to(fs));
  EXPECT_TRUE(v[2].string_to(fs).ok() == false);  // "café" is 5 bytes
  vda5050::FixedString<5> fs5;
  EXPECT_TRUE(v[2].string_to(fs5));
  EXPECT_EQ(fs5.view(), "caf\xc3\xa9");
}

TEST(JsonReader, EscapedKeysFindAndCollide) {
  Parsed p(R"({"k\u0065y": 1})");
  ASSERT_TRUE(p.status);
  EXPECT_TRUE(p.doc.root().find("key").valid());
  EXPECT_EQ(error_of(R"({"key": 1, "k\u0065y": 2})"), "byte 11: duplicate member name \"k\\u0065y\"");
}

TEST(JsonReader, MalformedInputSaysWhereAndWhy) {
  struct Case {
    std::string_view text;
    std::string_view error;
  };
  const Case cases[] = {
      {"", "byte 0: empty input"},
      {"   ", "byte 3: empty input"},
      {"{} x", "byte 3: unexpected 'x', trailing data after the value"},
      {"[1,]", "byte 3: unexpected ']', a value expected"},
      {"[1 2]", "byte 3: unexpected '2', ',' or ']' expected"},
      {"{\"a\" 1}", "byte 5: unexpected '1', ':' expected"},
      {"{\"a\":1,}", "byte 7: unexpected '}', a member name (string) expected"},
      {"{1:2}", "byte 1: unexpected '1', a member name (string) expected"},
      {"[\"a\\x\"]", "byte 3: invalid escape '\\x'"},
      {"[\"\\u12\"]", "byte 2: \\u needs four hex digits"},
      {"[\"\\ud800\"]", "byte 2: unpaired high surrogate in \\u escape"},
      {"[\"\\udc00\"]", "byte 2: unpaired low surrogate in \\u escape"},
      {"[\"a\nb\"]", "byte 3: control character 0x0a in a string"},
      {"[\"\xc3\x28\"]", "byte 2: invalid UTF-8 in a string"},
      {"[\"\xc0\xaf\"]", "byte 2: invalid UTF-8 in a string"},          // overlong '/'
      {"[\"\xed\xa0\x80\"]", "byte 2: invalid UTF-8 in a string"},      // encoded surrogate
      {"[\"\xf4\x90\x80\x80\"]", "byte 2: invalid UTF-8 in a string"},  // above U+10FFFF
      {"[\"abc", "byte 5: unterminated string"},
      {"[01]", "byte 2: leading zero in a number"},
      {"[1.]", "byte 3: a digit expected after the decimal point"},
      {"[1e]", "byte 3: a digit expected in the exponent"},
      {"[-]", "byte 2: a digit expected in a number"},
      {"[+1]", "byte 1: unexpected '+', a value expected"},
      {"[1e400]", "byte 1: number out of range for a double"},
      {"[tru]", "byte 1: unexpected 't', a value expected"},
      {"[NaN]", "byte 1: unexpected 'N', a value expected"},
      {"[1", "byte 2: unexpected end of input, ',' or ']' expected"},
      {"{\"a\":1", "byte 6: unexpected end of input, ',' or '}' expected"},
      {"\xef\xbb\xbf{}", "byte 0: unexpected byte 0xef, a value expected"},
      {"{\"a\":1,\"a\":2}", "byte 7: duplicate member name \"a\""},
  };
  for (const Case& c : cases) EXPECT_EQ(error_of(c.text), c.error) << c.text;
}

TEST(JsonReader, LimitsAreErrors) {
  EXPECT_EQ(error_of("[[[[1]]]]", Limits{3, 1024}), "byte 3: nesting deeper than 3 levels");
  EXPECT_EQ(error_of("[[[1]]]", Limits{3, 1024}), "");
  EXPECT_EQ(error_of("[1, 2, 3]", Limits{32, 8}), "byte 8: input longer than the 8-byte limit");
  Token tokens[3];
  Document doc(tokens);
  Status st = doc.parse("[1, 2, 3]");
  ASSERT_FALSE(st);
  EXPECT_EQ(st.error().code(), Errc::capacity);
  EXPECT_EQ(st.error().message(), "byte 7: more than 3 tokens");
  EXPECT_FALSE(doc.root().valid());
  EXPECT_TRUE(doc.parse("[1, 2]"));
  // Deep nesting past the ceiling stops at the ceiling, whatever the limit.
  std::string deep(200, '[');
  deep += std::string(200, ']');
  StaticDocument<512> big(Limits{1000, 4096});
  Status deep_st = big.parse(deep);
  ASSERT_FALSE(deep_st);
  EXPECT_EQ(deep_st.error().message(), "byte 64: nesting deeper than 64 levels");
}

TEST(JsonReader, ScalarRootAndJsonText) {
  Parsed p(" \"x\" ");
  ASSERT_TRUE(p.status);
  EXPECT_EQ(p.doc.root().json_text(), "\"x\"");
  Parsed q(R"({"v": {"a": [1, 2]}})");
  ASSERT_TRUE(q.status);
  EXPECT_EQ(q.doc.root().find("v").json_text(), R"({"a": [1, 2]})");
}

TEST(JsonWriter, WritesObjectsArraysAndEscapes) {
  std::array<char, 256> buf;
  Writer w(buf);
  w.begin_object()
      .member("s", "q\"b\\s\n\x01\xc3\xa9")
      .member_uint32("u", 4294967295u)
      .member_number("d", 0.1)
      .member_bool("t", true)
      .key("a")
      .begin_array()
      .number(-0.0)
      .number(1e300)
      .null()
      .begin_object()
      .end_object()
      .end_array()
      .end_object();
  auto r = w.finish();
  ASSERT_TRUE(r) << r.error().c_str();
  EXPECT_EQ(*r, R"({"s":"q\"b\\s\n\u0001)"
                "\xc3\xa9"
                R"(","u":4294967295,"d":0.1,"t":true,"a":[-0,1e+300,null,{}]})");
  // Reads back.
  StaticDocument<32> doc;
  ASSERT_TRUE(doc.parse(*r));
  char s[32];
  EXPECT_EQ(std::string(s, *doc.root().find("s").string(s)), "q\"b\\s\n\x01\xc3\xa9");
}

TEST(JsonWriter, DoublesRoundTrip) {
  const double values[] = {0.1, 1.0 / 3.0, -2.5e-310, 1.7976931348623157e308, 123456789.123456789, 3.14159265359, 5e-324};
  for (double v : values) {
    std::array<char, 64> buf;
    Writer w(buf);
    w.number(v);
    auto text = w.finish();
    ASSERT_TRUE(text);
    StaticDocument<4> doc;
    ASSERT_TRUE(doc.parse(*text)) << *text;
    EXPECT_EQ(*doc.root().number(), v) << *text;
  }
}

TEST(JsonWriter, OverflowIsReportedNotTruncated) {
  std::array<char, 10> buf;
  Writer w(buf);
  w.begin_object().member("key", "a long value").end_object();
  auto r = w.finish();
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code(), Errc::capacity);
  EXPECT_EQ(r.error().message(), "JSON output exceeds the 10-byte buffer");
}

TEST(JsonWriter, MisuseAndUnrepresentableValues) {
  std::array<char, 64> buf;
  {
    Writer w(buf);
    w.begin_array().number(std::nan("")).end_array();
    EXPECT_EQ(w.finish().error().code(), Errc::invalid_argument);
  }
  {
    Writer w(buf);
    w.begin_object().uint32(1).end_object();  // a value without a key
    EXPECT_FALSE(w.finish());
  }
  {
    Writer w(buf);
    w.begin_array().key("k");
    EXPECT_FALSE(w.finish());
  }
  {
    Writer w(buf);
    w.begin_array();
    EXPECT_EQ(w.finish().error().message(), "JSON writer: the value is incomplete");
  }
  {
    Writer w(buf);
    w.begin_array().end_object();
    EXPECT_FALSE(w.finish());
  }
  {
    Writer w(buf);
    w.begin_array().raw("{\"a\":1}").raw("[1,]").end_array();
    EXPECT_FALSE(w.finish());
  }
  {
    Writer w(buf);
    w.begin_array().raw(" {\"a\": [true]} ").end_array();
    EXPECT_EQ(*w.finish(), "[ {\"a\": [true]} ]");
  }
  {
    Writer w(buf);
    w.uint32(1).uint32(2);
    EXPECT_FALSE(w.finish());
  }
}

TEST(JsonWriter, EscapesEveryControlCharacter) {
  std::string text;
  for (int c = 0; c < 0x20; ++c) text += static_cast<char>(c);
  text += "\"\\/\x7f";
  std::array<char, 256> buf;
  Writer w(buf);
  w.string(text);
  auto r = w.finish();
  ASSERT_TRUE(r);
  EXPECT_EQ(*r,
            "\"\\u0000\\u0001\\u0002\\u0003\\u0004\\u0005\\u0006\\u0007\\b\\t\\n\\u000b\\f\\r\\u000e\\u000f"
            "\\u0010\\u0011\\u0012\\u0013\\u0014\\u0015\\u0016\\u0017\\u0018\\u0019\\u001a\\u001b\\u001c\\u001d"
            "\\u001e\\u001f\\\"\\\\/\x7f\"");
  StaticDocument<4> doc;
  ASSERT_TRUE(doc.parse(*r));
  char back[64];
  EXPECT_EQ(std::string(back, *doc.root().string(back)), text);
}

TEST(JsonWriter, KeepsUtf8AndReplacesInvalidBytes) {
  std::array<char, 128> buf;
  {
    // Two-, three- and four-byte sequences come out byte for byte.
    Writer w(buf);
    w.begin_object().member("caf\xc3\xa9", "\xe2\x82\xac \xf0\x9f\xa4\x96").end_object();
    EXPECT_EQ(*w.finish(), "{\"caf\xc3\xa9\":\"\xe2\x82\xac \xf0\x9f\xa4\x96\"}");
  }
  {
    // A stray continuation byte, a Latin-1 byte, a truncated sequence, an overlong form and an
    // encoded surrogate: each byte that starts no valid sequence becomes U+FFFD.
    Writer w(buf);
    w.string("a\x80" "b\xe9" "c\xe2\x82" "d\xc0\xaf" "e\xed\xa0\x80");
    auto r = w.finish();
    ASSERT_TRUE(r);
    const std::string bad = "\xef\xbf\xbd";
    EXPECT_EQ(*r, "\"a" + bad + "b" + bad + "c" + bad + bad + "d" + bad + bad + "e" + bad + bad + bad + "\"");
    StaticDocument<4> doc;
    EXPECT_TRUE(doc.parse(*r));
  }
}

TEST(JsonWriter, FixedAndGeneralMatchPrintf) {
  const double values[] = {0.0, -0.0, 0.0005, 0.0015, 2.675, -1.2345, 1e-7, -1e-7, -0.0004, 123456.789, 1e21, -3.99999, 0.125, 7.0};
  for (const int decimals : {0, 1, 2, 3, 4, 6}) {
    for (const double v : values) {
      std::array<char, 64> buf;
      Writer w(buf);
      w.fixed(v, decimals);
      char expected[64];
      std::snprintf(expected, sizeof expected, "%.*f", decimals, v);
      EXPECT_EQ(*w.finish(), std::string_view(expected)) << v << " with " << decimals;
    }
  }
  for (const int digits : {1, 3, 6, 17}) {
    for (const double v : {0.0, 1e-5, 0.0001, 123456.0, 1234567.0, -2.5e-300, 1e300, 0.1, 100.0}) {
      std::array<char, 64> buf;
      Writer w(buf);
      w.general(v, digits);
      char expected[64];
      std::snprintf(expected, sizeof expected, "%.*g", digits, v);
      EXPECT_EQ(*w.finish(), std::string_view(expected)) << v << " with " << digits;
    }
  }
  std::array<char, 64> buf;
  Writer w(buf);
  w.begin_array().fixed_or_null(std::nan(""), 3).fixed_or_null(HUGE_VAL, 3).fixed_or_null(1.5, 3).end_array();
  EXPECT_EQ(*w.finish(), "[null,null,1.500]");
  Writer bad(buf);
  bad.fixed(HUGE_VAL, 2);
  EXPECT_EQ(bad.finish().error().code(), Errc::invalid_argument);
}

TEST(JsonWriter, SpacedStyleAndLineBreaks) {
  std::string out;
  StringSink sink(out);
  Writer w(sink, Style::spaced);
  w.begin_object().line(2).member("name", "a").key("n").uint32(1).line(2).key("list").begin_array();
  w.line(4).begin_object().member_fixed("x", 1.0, 2).end_object();
  w.line(4).begin_object().member_fixed("x", 2.0, 2).end_object();
  w.line(2).end_array().key("empty").begin_array().end_array().line(0).end_object();
  ASSERT_TRUE(w.finish());
  EXPECT_EQ(out,
            "{\n  \"name\": \"a\", \"n\": 1,\n  \"list\": [\n    {\"x\": 1.00},\n    {\"x\": 2.00}\n  ], "
            "\"empty\": []\n}");
  EXPECT_EQ(w.size(), out.size());
}

TEST(JsonWriter, StringSinkGrowsAndFileSinkWrites) {
  std::vector<std::uint8_t> bytes(1000);
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<std::uint8_t>(i * 7);
  // The same document into a fixed buffer, a string and a file is the same text.
  const auto write = [&](Writer& w) {
    w.begin_object().member("s", std::string(3000, 'x')).key("b").base64(bytes).key("n").number(0.1).end_object();
  };
  std::array<char, 8192> buf;
  Writer fixed(buf);
  write(fixed);
  auto text = fixed.finish();
  ASSERT_TRUE(text);
  std::string out;
  StringSink string_sink(out);
  Writer to_string(string_sink);
  write(to_string);
  ASSERT_TRUE(to_string.finish());
  EXPECT_EQ(out, *text);
  std::FILE* f = std::tmpfile();
  ASSERT_NE(f, nullptr);
  FileSink file_sink(f);
  Writer to_file(file_sink);
  write(to_file);
  ASSERT_TRUE(to_file.finish());
  std::rewind(f);
  std::string read(text->size() + 1, '\0');
  read.resize(std::fread(read.data(), 1, read.size(), f));
  std::fclose(f);
  EXPECT_EQ(read, *text);
}

TEST(JsonWriter, FailedSinkWriteIsReported) {
  struct Full final : Sink {
    bool write(std::string_view) noexcept override { return false; }
  } full;
  Writer w(full);
  w.begin_array().end_array();
  auto r = w.finish();
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code(), Errc::io);
}

}  // namespace
}  // namespace sen3bot::json
