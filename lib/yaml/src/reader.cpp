#include "sen3bot/yaml/reader.hpp"

#include <cmath>
#include <sstream>

#include "sen3bot/mem/byte_size.hpp"

namespace sen3bot::yaml {

namespace {

// " (line L, column C)" of a node, or "" where it has no place (a node made up by the caller).
std::string where(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  if (mark.line < 0) return "";
  return " (line " + std::to_string(mark.line + 1) + ", column " + std::to_string(mark.column + 1) + ")";
}

template <typename Fail>
std::int64_t integer_of(const YAML::Node& n, std::int64_t min, std::int64_t max, Fail&& fail_with) {
  std::int64_t v = 0;
  if (!YAML::convert<std::int64_t>::decode(n, v)) fail_with("expected an integer, got '" + n.Scalar() + "'");
  if (v < min || v > max)
    fail_with("value " + std::to_string(v) + " is outside [" + std::to_string(min) + ", " + std::to_string(max) + "]");
  return v;
}

template <typename Fail>
double number_of(const YAML::Node& n, double min, double max, Fail&& fail_with) {
  double v = 0;
  if (!YAML::convert<double>::decode(n, v) || !std::isfinite(v)) fail_with("expected a number, got '" + n.Scalar() + "'");
  if (v < min || v > max) {
    std::ostringstream msg;
    msg << "value " << v << " is outside [" << min << ", " << max << "]";
    fail_with(msg.str());
  }
  return v;
}

}  // namespace

void Reader::fail(const std::string& key, const std::string& problem, const YAML::Node& at) const {
  throw ReadError(file_ + ": " + full(key) + ": " + problem + where(at));
}

void Reader::fail(const std::string& key, const std::string& problem) const {
  const YAML::Node value = node_.IsMap() ? node_[key] : YAML::Node();
  fail(key, problem, value.IsDefined() ? value : node_);
}

void Reader::fail_here(const std::string& problem) const {
  throw ReadError(file_ + ": " + (path_.empty() ? std::string("(top level)") : path_) + ": " + problem + where(node_));
}

void Reader::require_map() const {
  if (!node_.IsMap()) fail_here("expected a mapping of keys");
}

void Reader::allow_only(std::span<const std::string_view> keys) const {
  require_map();
  for (const auto& kv : node_) {
    const std::string name = kv.first.as<std::string>();
    bool known = false;
    for (std::string_view k : keys) known = known || k == name;
    if (!known) {
      std::string list;
      for (std::string_view k : keys) list += (list.empty() ? "" : ", ") + std::string(k);
      fail(name, "unknown key (expected one of: " + list + ")", kv.first);
    }
  }
}

Reader Reader::child(const std::string& key) const {
  const YAML::Node n = node_[key];
  if (!n.IsDefined() || n.IsNull()) fail(key, "missing", node_);
  return Reader(n, file_, full(key));
}

YAML::Node Reader::scalar(const std::string& key) const {
  const YAML::Node n = node_[key];
  if (!n.IsDefined() || n.IsNull()) fail(key, "missing", node_);
  if (!n.IsScalar()) fail(key, "expected a single value", n);
  return n;
}

std::string Reader::text(const std::string& key) const { return scalar(key).Scalar(); }

std::int64_t Reader::integer(const std::string& key, std::int64_t min, std::int64_t max) const {
  const YAML::Node n = scalar(key);
  return integer_of(n, min, max, [&](const std::string& problem) { fail(key, problem, n); });
}

double Reader::number(const std::string& key, double min, double max) const {
  const YAML::Node n = scalar(key);
  return number_of(n, min, max, [&](const std::string& problem) { fail(key, problem, n); });
}

bool Reader::boolean(const std::string& key) const {
  const YAML::Node n = scalar(key);
  bool v = false;
  if (!YAML::convert<bool>::decode(n, v)) fail(key, "expected true or false, got '" + n.Scalar() + "'", n);
  return v;
}

std::size_t Reader::choice(const std::string& key, std::initializer_list<std::string_view> options) const {
  const YAML::Node n = scalar(key);
  std::string list;
  std::size_t index = 0;
  for (std::string_view option : options) {
    if (option == n.Scalar()) return index;
    list += (index == 0 ? "" : index + 1 == options.size() ? " or " : ", ") + std::string(option);
    ++index;
  }
  fail(key, "expected " + list + ", got '" + n.Scalar() + "'", n);
}

std::size_t Reader::bytes(const std::string& key) const {
  const YAML::Node n = scalar(key);
  Result<std::size_t> r = mem::parse_byte_size(n.Scalar());
  if (!r) fail(key, std::string(r.error().message()), n);
  return *r;
}

std::string Reader::text_here() const {
  if (!node_.IsScalar()) fail_here("expected a single value");
  return node_.Scalar();
}

std::int64_t Reader::integer_here(std::int64_t min, std::int64_t max) const {
  if (!node_.IsScalar()) fail_here("expected a single value");
  return integer_of(node_, min, max, [&](const std::string& problem) { fail_here(problem); });
}

double Reader::number_here(double min, double max) const {
  if (!node_.IsScalar()) fail_here("expected a single value");
  return number_of(node_, min, max, [&](const std::string& problem) { fail_here(problem); });
}

std::vector<Reader> Reader::sequence(const std::string& key) const {
  const YAML::Node n = node_[key];
  if (!n.IsDefined() || n.IsNull()) fail(key, "missing", node_);
  if (!n.IsSequence()) fail(key, "expected a list", n);
  return Reader(n, file_, full(key)).sequence_here();
}

std::vector<Reader> Reader::sequence_here() const {
  if (!node_.IsSequence()) fail_here("expected a list");
  std::vector<Reader> items;
  for (std::size_t i = 0; i < node_.size(); ++i) items.emplace_back(node_[i], file_, path_ + "[" + std::to_string(i) + "]");
  return items;
}

std::vector<double> Reader::numbers_here(std::string_view form, std::size_t min_count, std::size_t max_count,
                                         double limit) const {
  if (!node_.IsSequence() || node_.size() < min_count || node_.size() > max_count)
    fail_here("expected " + std::string(form));
  std::vector<double> values;
  for (const Reader& item : sequence_here()) values.push_back(item.number_here(-limit, limit));
  return values;
}

geometry::Point2D Reader::point(double limit) const {
  const std::vector<double> v = numbers_here("[x, y]", 2, 2, limit);
  return {v[0], v[1]};
}

std::string relative_to(const std::string& file, const std::string& path) {
  if (path.empty() || path.front() == '/') return path;
  const std::size_t slash = file.find_last_of('/');
  return slash == std::string::npos ? path : file.substr(0, slash + 1) + path;
}

}  // namespace sen3bot::yaml
