// Paths as JSON lines (path_file.hpp), read with the strict fixed-memory JSON reader.
#include "sen3bot/cobot/path_file.hpp"

#include <array>
#include <cmath>
#include <cstdio>
#include <fstream>
#include <sstream>

#include "sen3bot/cobot/operations.hpp"
#include "sen3bot/json/json.hpp"

namespace sen3bot::cobot {

namespace {

namespace json = sen3bot::json;

// A point is three tokens ([, x, y); the object and its other members need a few more.
constexpr std::size_t kTokens = 3 * kMaxPathPoints + 16;
constexpr std::size_t kMaxLineBytes = 256 * 1024;  // 1024 points at full precision fit many times
constexpr std::size_t kMaxNameBytes = 256;
constexpr double kMaxPathCoordinateM = 1e5;

Result<std::string> string_member(json::Value v, const char* key) {
  if (!v.is(json::Type::string)) return Error::format(Errc::invalid_argument, "byte %zu: \"%s\": expected a string", v.offset(), key);
  std::array<char, kMaxNameBytes + 1> buf{};
  Result<std::size_t> n = v.string(buf);
  if (!n || *n > kMaxNameBytes)
    return Error::format(Errc::invalid_argument, "byte %zu: \"%s\": longer than %zu bytes", v.offset(), key, kMaxNameBytes);
  return std::string(buf.data(), *n);
}

}  // namespace

Result<PathRecord> parse_path_line(std::string_view line) {
  if (line.size() > kMaxLineBytes)
    return Error::format(Errc::capacity, "line longer than %zu bytes", kMaxLineBytes);
  std::vector<json::Token> tokens(kTokens);
  json::Document doc(tokens, json::Limits{4, kMaxLineBytes});
  if (Status s = doc.parse(line); !s) {
    if (s.error().code() == Errc::capacity && doc.token_count() >= tokens.size() - 1)
      return Error::format(Errc::capacity, "more than %zu points", kMaxPathPoints);
    return s.error();
  }
  const json::Value root = doc.root();
  if (!root.is(json::Type::object)) return Error(Errc::invalid_argument, "expected a JSON object");
  PathRecord record;
  bool have_points = false;
  for (const json::Value::Member m : root.members()) {
    if (m.key.string_equals("name")) {
      Result<std::string> s = string_member(m.value, "name");
      if (!s) return s.error();
      record.name = std::move(*s);
    } else if (m.key.string_equals("operation")) {
      Result<std::string> s = string_member(m.value, "operation");
      if (!s) return s.error();
      record.operation = std::move(*s);
    } else if (m.key.string_equals("points")) {
      if (!m.value.is(json::Type::array))
        return Error::format(Errc::invalid_argument, "byte %zu: \"points\": expected an array of [x, y]", m.value.offset());
      if (m.value.size() > kMaxPathPoints)
        return Error::format(Errc::capacity, "byte %zu: \"points\": more than %zu points", m.value.offset(), kMaxPathPoints);
      record.xy.reserve(2 * m.value.size());
      for (const json::Value p : m.value.items()) {
        if (!p.is(json::Type::array) || p.size() != 2)
          return Error::format(Errc::invalid_argument, "byte %zu: \"points\": expected [x, y]", p.offset());
        for (const json::Value c : p.items()) {
          Result<double> v = c.number();
          if (!v || !std::isfinite(*v) || std::fabs(*v) > kMaxPathCoordinateM)
            return Error::format(Errc::invalid_argument, "byte %zu: \"points\": expected a coordinate in metres",
                                 c.offset());
          record.xy.push_back(static_cast<float>(*v));
        }
      }
      have_points = true;
    } else {
      return Error::format(Errc::invalid_argument, "byte %zu: unknown member (expected name, operation, points)",
                           m.key.offset());
    }
  }
  if (!have_points) return Error(Errc::invalid_argument, "no \"points\"");
  return record;
}

Result<std::vector<PathRecord>> parse_paths(std::string_view text, std::string_view source) {
  std::vector<PathRecord> records;
  std::size_t line_number = 0;
  while (!text.empty()) {
    const std::size_t end = text.find('\n');
    std::string_view line = text.substr(0, end);
    text = end == std::string_view::npos ? std::string_view() : text.substr(end + 1);
    ++line_number;
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.find_first_not_of(" \t") == std::string_view::npos) continue;
    Result<PathRecord> r = parse_path_line(line);
    if (!r)
      return Error::format(r.error().code(), "%.*s: line %zu: %s", static_cast<int>(source.size()), source.data(),
                           line_number, r.error().c_str());
    records.push_back(std::move(*r));
  }
  return records;
}

Result<std::vector<PathRecord>> load_paths(const std::string& path) {
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error::format(Errc::not_found, "%s: cannot open", path.c_str());
  std::ostringstream text;
  text << in.rdbuf();
  return parse_paths(text.str(), path);
}

std::string path_line(const PathRecord& record) {
  std::string line;
  json::StringSink sink(line);
  json::Writer w(sink);
  w.begin_object().member("name", record.name);
  if (!record.operation.empty()) w.member("operation", record.operation);
  w.key("points").begin_array();
  for (std::size_t i = 0; i + 1 < record.xy.size(); i += 2) {
    w.begin_array()
        .fixed_or_null(static_cast<double>(record.xy[i]), 3)
        .fixed_or_null(static_cast<double>(record.xy[i + 1]), 3)
        .end_array();
  }
  w.end_array().end_object();
  return line;
}

}  // namespace sen3bot::cobot
