#pragma once
// Reading a YAML file with messages that name the file, the dotted key and the problem, and
// where yaml-cpp knows it the line and column: "robot.yaml: navigation.goals[1][0]: expected a
// number, got 'x' (line 12, column 14)". Unknown keys are errors. Every YAML file of the
// project is read through this: the firmware's configuration (and the simulator's section of
// it), the safe curve, the fleet centre's site file, the operations file and the ROS map YAML.
// Reading allocates and throws ReadError; parse() catches it and returns an Error.
#include <yaml-cpp/yaml.h>

#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <limits>
#include <span>
#include <stdexcept>
#include <string>
#include <string_view>
#include <utility>
#include <vector>

#include "sen3bot/geometry/geometry.hpp"
#include "sen3bot/hal/result.hpp"

namespace sen3bot::yaml {

// Thrown inside a reader only; parse() turns it into an Error.
struct ReadError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

// A node plus its dotted key path, so every message can say exactly which key is wrong.
class Reader {
 public:
  Reader(YAML::Node node, std::string file, std::string path)
      : node_(std::move(node)), file_(std::move(file)), path_(std::move(path)) {}

  // `at` gives the line and column; YAML::Node() gives none (a rule between keys).
  [[noreturn]] void fail(const std::string& key, const std::string& problem, const YAML::Node& at) const;
  // At the key's value where it is given, else at this mapping.
  [[noreturn]] void fail(const std::string& key, const std::string& problem) const;
  [[noreturn]] void fail_here(const std::string& problem) const;

  [[nodiscard]] bool has(const std::string& key) const { return node_[key].IsDefined() && !node_[key].IsNull(); }

  void require_map() const;

  // Unknown keys are errors: a misspelt key must not silently fall back to a default.
  void allow_only(std::initializer_list<std::string_view> keys) const { allow_only(std::span(keys.begin(), keys.size())); }
  void allow_only(std::span<const std::string_view> keys) const;

  [[nodiscard]] Reader child(const std::string& key) const;

  [[nodiscard]] std::string text(const std::string& key) const;
  [[nodiscard]] std::int64_t integer(const std::string& key, std::int64_t min, std::int64_t max) const;
  [[nodiscard]] double number(const std::string& key, double min, double max) const;
  [[nodiscard]] bool boolean(const std::string& key) const;
  // The index of the key's text among `options` ("expected a, b or c, got 'x'" when none).
  [[nodiscard]] std::size_t choice(const std::string& key, std::initializer_list<std::string_view> options) const;
  // "4096", "64KiB", "1 MiB" (mem::parse_byte_size).
  [[nodiscard]] std::size_t bytes(const std::string& key) const;

  // This node itself (an element of a list).
  [[nodiscard]] std::string text_here() const;
  [[nodiscard]] std::int64_t integer_here(std::int64_t min, std::int64_t max) const;
  [[nodiscard]] double number_here(double min, double max) const;

  // Elements of a sequence under `key`, each as a Reader named key[i].
  [[nodiscard]] std::vector<Reader> sequence(const std::string& key) const;
  // This node as a list, each element a Reader named path[i].
  [[nodiscard]] std::vector<Reader> sequence_here() const;

  // This node as a list of min_count to max_count numbers, each within [-limit, limit], as a
  // pose [x, y(, theta_deg)] is written; `form` shows the list in the message when it is not one.
  [[nodiscard]] std::vector<double> numbers_here(std::string_view form, std::size_t min_count, std::size_t max_count,
                                                 double limit = std::numeric_limits<double>::max()) const;
  // This node as a point [x, y], each coordinate within [-limit, limit].
  [[nodiscard]] geometry::Point2D point(double limit = std::numeric_limits<double>::max()) const;

  [[nodiscard]] const std::string& file() const { return file_; }

  // Each key of this mapping with its value, named path.key.
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
  [[nodiscard]] YAML::Node scalar(const std::string& key) const;

  YAML::Node node_;
  std::string file_;
  std::string path_;
};

// A path relative to the folder of the file that names it, as ROS map YAMLs do for their image.
std::string relative_to(const std::string& file, const std::string& path);

// Runs `read` on the document's root, turning ReadError and YAML errors into an Error.
template <typename T, typename F>
Result<T> parse(std::string_view yaml_text, const std::string& source_name, F&& read) {
  try {
    const YAML::Node root = YAML::Load(std::string(yaml_text));
    if (!root.IsDefined() || root.IsNull()) return Error::format(Errc::config, "%s: the file is empty", source_name.c_str());
    return read(Reader(root, source_name, ""));
  } catch (const ReadError& e) {
    return Error(Errc::config, e.what());
  } catch (const YAML::Exception& e) {
    return Error::format(Errc::config, "%s: not valid YAML: %s", source_name.c_str(), e.what());
  }
}

}  // namespace sen3bot::yaml
