#pragma once
// Reading a YAML configuration with messages that name the file, the key and the problem. The
// firmware's loader and a board that owns a section of the same file (the simulator's `sim`)
// both read through this. Loading allocates and throws ConfigError; the loaders catch it and
// return an Error.
#include <yaml-cpp/yaml.h>

#include <cmath>
#include <cstdint>
#include <initializer_list>
#include <numbers>
#include <span>
#include <sstream>
#include <stdexcept>
#include <string>
#include <string_view>
#include <vector>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/mem/byte_size.hpp"
#include "sen3bot/nav/geometry.hpp"

namespace sen3bot::firmware::config {

// Thrown inside the loader only; load_config() turns it into an Error.
struct ConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

inline std::string where(const YAML::Node& node) {
  const YAML::Mark mark = node.Mark();
  if (mark.line < 0) return "";
  return " (line " + std::to_string(mark.line + 1) + ", column " + std::to_string(mark.column + 1) + ")";
}

// A node plus its dotted key path, so every message can say exactly which key is wrong.
class Reader {
 public:
  Reader(YAML::Node node, std::string file, std::string path)
      : node_(std::move(node)), file_(std::move(file)), path_(std::move(path)) {}

  [[noreturn]] void fail(const std::string& key, const std::string& problem, const YAML::Node& at) const {
    throw ConfigError(file_ + ": " + full(key) + ": " + problem + where(at));
  }
  [[noreturn]] void fail_here(const std::string& problem) const {
    throw ConfigError(file_ + ": " + (path_.empty() ? std::string("(top level)") : path_) + ": " + problem + where(node_));
  }

  [[nodiscard]] bool has(const std::string& key) const { return node_[key].IsDefined() && !node_[key].IsNull(); }

  void require_map() const {
    if (!node_.IsMap()) fail_here("expected a mapping of keys");
  }

  // Unknown keys are errors: a misspelt key must not silently fall back to a default.
  void allow_only(std::initializer_list<std::string_view> keys) const { allow_only(std::span(keys.begin(), keys.size())); }
  void allow_only(std::span<const std::string_view> keys) const {
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

  [[nodiscard]] Reader child(const std::string& key) const {
    const YAML::Node n = node_[key];
    if (!n.IsDefined() || n.IsNull()) fail(key, "missing", node_);
    return Reader(n, file_, full(key));
  }

  [[nodiscard]] std::string text(const std::string& key) const {
    const YAML::Node n = scalar(key);
    return n.Scalar();
  }

  [[nodiscard]] std::int64_t integer(const std::string& key, std::int64_t min, std::int64_t max) const {
    const YAML::Node n = scalar(key);
    return integer_of(n, min, max, [&](const std::string& problem) { fail(key, problem, n); });
  }
  [[nodiscard]] double number(const std::string& key, double min, double max) const {
    const YAML::Node n = scalar(key);
    return number_of(n, min, max, [&](const std::string& problem) { fail(key, problem, n); });
  }
  // This node itself (an element of a list).
  [[nodiscard]] std::int64_t integer_here(std::int64_t min, std::int64_t max) const {
    if (!node_.IsScalar()) fail_here("expected a single value");
    return integer_of(node_, min, max, [&](const std::string& problem) { fail_here(problem); });
  }
  [[nodiscard]] double number_here(double min, double max) const {
    if (!node_.IsScalar()) fail_here("expected a single value");
    return number_of(node_, min, max, [&](const std::string& problem) { fail_here(problem); });
  }

  [[nodiscard]] bool boolean(const std::string& key) const {
    const YAML::Node n = scalar(key);
    bool v = false;
    if (!YAML::convert<bool>::decode(n, v)) fail(key, "expected true or false, got '" + n.Scalar() + "'", n);
    return v;
  }

  [[nodiscard]] std::size_t bytes(const std::string& key) const {
    const YAML::Node n = scalar(key);
    Result<std::size_t> r = mem::parse_byte_size(n.Scalar());
    if (!r) fail(key, std::string(r.error().message()), n);
    return *r;
  }

  // Elements of a sequence under `key`, each as a Reader named key[i].
  [[nodiscard]] std::vector<Reader> sequence(const std::string& key) const {
    const YAML::Node n = node_[key];
    if (!n.IsDefined() || n.IsNull()) fail(key, "missing", node_);
    if (!n.IsSequence()) fail(key, "expected a list", n);
    std::vector<Reader> items;
    for (std::size_t i = 0; i < n.size(); ++i)
      items.emplace_back(n[i], file_, full(key) + "[" + std::to_string(i) + "]");
    return items;
  }

  // This node as a list, each element a Reader named path[i].
  [[nodiscard]] std::vector<Reader> sequence_here() const {
    if (!node_.IsSequence()) fail_here("expected a list");
    std::vector<Reader> items;
    for (std::size_t i = 0; i < node_.size(); ++i) items.emplace_back(node_[i], file_, path_ + "[" + std::to_string(i) + "]");
    return items;
  }

  // This node as a list of two numbers [x, y].
  [[nodiscard]] nav::Point2D point() const {
    if (!node_.IsSequence() || node_.size() != 2) fail_here("expected a point [x_m, y_m]");
    double v[2];
    for (std::size_t i = 0; i < 2; ++i)
      if (!YAML::convert<double>::decode(node_[i], v[i]) || !std::isfinite(v[i])) fail_here("expected two numbers");
    return {v[0], v[1]};
  }

  [[nodiscard]] const std::string& file() const { return file_; }

  template <typename F>
  void for_each_entry(F&& f) const {
    require_map();
    for (const auto& kv : node_) {
      const std::string name = kv.first.as<std::string>();
      f(name, Reader(kv.second, file_, full(name)));
    }
  }

 private:
  [[nodiscard]] std::string full(const std::string& key) const { return path_.empty() ? key : path_ + "." + key; }
  [[nodiscard]] YAML::Node scalar(const std::string& key) const {
    const YAML::Node n = node_[key];
    if (!n.IsDefined() || n.IsNull()) fail(key, "missing", node_);
    if (!n.IsScalar()) fail(key, "expected a single value", n);
    return n;
  }

  template <typename Fail>
  static std::int64_t integer_of(const YAML::Node& n, std::int64_t min, std::int64_t max, Fail&& fail_with) {
    std::int64_t v = 0;
    if (!YAML::convert<std::int64_t>::decode(n, v)) fail_with("expected an integer, got '" + n.Scalar() + "'");
    if (v < min || v > max)
      fail_with("value " + std::to_string(v) + " is outside [" + std::to_string(min) + ", " + std::to_string(max) + "]");
    return v;
  }
  template <typename Fail>
  static double number_of(const YAML::Node& n, double min, double max, Fail&& fail_with) {
    double v = 0;
    if (!YAML::convert<double>::decode(n, v) || !std::isfinite(v)) fail_with("expected a number, got '" + n.Scalar() + "'");
    if (v < min || v > max) {
      std::ostringstream msg;
      msg << "value " << v << " is outside [" << min << ", " << max << "]";
      fail_with(msg.str());
    }
    return v;
  }

  YAML::Node node_;
  std::string file_;
  std::string path_;
};

// {x_m, y_m, theta_deg}; a missing key is 0.
inline nav::Pose2D read_pose(const Reader& r) {
  r.allow_only({"x_m", "y_m", "theta_deg"});
  nav::Pose2D p;
  if (r.has("x_m")) p.x_m = r.number("x_m", -1e4, 1e4);
  if (r.has("y_m")) p.y_m = r.number("y_m", -1e4, 1e4);
  if (r.has("theta_deg")) p.theta_rad = r.number("theta_deg", -360.0, 360.0) * std::numbers::pi / 180.0;
  return p;
}

// A path relative to the configuration file's folder, as ROS map YAMLs do for their image.
inline std::string relative_to(const std::string& file, const std::string& path) {
  if (path.empty() || path.front() == '/') return path;
  const std::size_t slash = file.find_last_of('/');
  return slash == std::string::npos ? path : file.substr(0, slash + 1) + path;
}

inline std::int64_t millis(const Reader& r, const std::string& key, std::int64_t min_ms, std::int64_t max_ms) {
  return static_cast<std::int64_t>(std::llround(r.number(key, static_cast<double>(min_ms) / 1000.0,
                                                          static_cast<double>(max_ms) / 1000.0) * 1000.0));
}

// The text of a configuration file, refused when it is far larger than one can be.
Result<std::string> read_text(const std::string& path);

// Runs `read` on the document's root, turning ConfigError and YAML errors into an Error.
template <typename T, typename F>
Result<T> parse(std::string_view yaml_text, const std::string& source_name, F&& read) {
  try {
    const YAML::Node root = YAML::Load(std::string(yaml_text));
    if (!root.IsDefined() || root.IsNull()) return Error::format(Errc::config, "%s: the file is empty", source_name.c_str());
    return read(Reader(root, source_name, ""));
  } catch (const ConfigError& e) {
    return Error(Errc::config, e.what());
  } catch (const YAML::Exception& e) {
    return Error::format(Errc::config, "%s: not valid YAML: %s", source_name.c_str(), e.what());
  }
}

}  // namespace sen3bot::firmware::config
