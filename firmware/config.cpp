#include "config.hpp"

#include <yaml-cpp/yaml.h>

#include "sen3bot/mem/byte_size.hpp"

#include <cctype>
#include <cmath>
#include <fstream>
#include <initializer_list>
#include <sstream>
#include <stdexcept>

namespace sen3bot::firmware {

namespace {

// Thrown inside the loader only; load_config() turns it into an Error.
struct ConfigError : std::runtime_error {
  using std::runtime_error::runtime_error;
};

std::string where(const YAML::Node& node) {
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
  void allow_only(std::initializer_list<std::string_view> keys) const {
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
    std::int64_t v = 0;
    if (!YAML::convert<std::int64_t>::decode(n, v))
      fail(key, "expected an integer, got '" + n.Scalar() + "'", n);
    if (v < min || v > max)
      fail(key, "value " + std::to_string(v) + " is outside [" + std::to_string(min) + ", " + std::to_string(max) + "]", n);
    return v;
  }

  [[nodiscard]] double number(const std::string& key, double min, double max) const {
    const YAML::Node n = scalar(key);
    double v = 0;
    if (!YAML::convert<double>::decode(n, v) || !std::isfinite(v))
      fail(key, "expected a number, got '" + n.Scalar() + "'", n);
    if (v < min || v > max) {
      std::ostringstream msg;
      msg << "value " << v << " is outside [" << min << ", " << max << "]";
      fail(key, msg.str(), n);
    }
    return v;
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

  YAML::Node node_;
  std::string file_;
  std::string path_;
};

FirmwareConfig read(const Reader& top, const std::string& source) {
  FirmwareConfig c;
  c.source_path = source;
  top.allow_only({"robot", "run", "realtime", "threads", "tasks"});

  const Reader robot = top.child("robot");
  robot.allow_only({"name"});
  c.robot_name = robot.text("name");

  const Reader run = top.child("run");
  run.allow_only({"clock", "duration_s"});
  const std::string clock = run.text("clock");
  if (clock == "lockstep") {
    c.clock = ClockMode::lockstep;
  } else if (clock == "realtime") {
    c.clock = ClockMode::realtime;
  } else {
    run.fail("clock", "expected 'lockstep' or 'realtime', got '" + clock + "'", YAML::Node());
  }
  c.duration_s = run.number("duration_s", 0.0, 1e7);

  if (top.has("realtime")) {
    const Reader rt = top.child("realtime");
    rt.allow_only({"lock_memory", "prefault_stack_bytes"});
    if (rt.has("lock_memory")) c.lock_memory = rt.boolean("lock_memory");
    if (rt.has("prefault_stack_bytes")) c.prefault_stack_bytes = rt.bytes("prefault_stack_bytes");
  }

  if (top.has("threads")) {
    top.child("threads").for_each_entry([&](const std::string& name, const Reader& t) {
      t.allow_only({"cpu", "realtime"});
      ThreadConfig tc;
      if (t.has("cpu")) tc.cpu = static_cast<int>(t.integer("cpu", -1, 1023));
      if (t.has("realtime")) tc.realtime = t.boolean("realtime");
      c.threads[name] = tc;
    });
  }

  top.child("tasks").for_each_entry([&](const std::string& name, const Reader& t) {
    TaskConfig tc;
    if (name == "health") {
      t.allow_only({"arena_bytes", "stall_periods"});
      if (t.has("stall_periods")) c.health_stall_periods = static_cast<int>(t.integer("stall_periods", 1, 1000));
    } else if (name == "telemetry") {
      t.allow_only({"arena_bytes", "status_period_s"});
      if (t.has("status_period_s"))
        c.telemetry_status_period_ms = static_cast<std::int64_t>(std::llround(t.number("status_period_s", 0.0, 86400.0) * 1000.0));
    } else {
      t.allow_only({"arena_bytes"});
    }
    tc.arena_bytes = t.bytes("arena_bytes");
    c.tasks[name] = tc;
  });
  return c;
}

}  // namespace

Result<FirmwareConfig> parse_config(std::string_view yaml_text, const std::string& source_name) {
  try {
    const YAML::Node root = YAML::Load(std::string(yaml_text));
    if (!root.IsDefined() || root.IsNull()) return Error::format(Errc::config, "%s: the file is empty", source_name.c_str());
    return read(Reader(root, source_name, ""), source_name);
  } catch (const ConfigError& e) {
    return Error(Errc::config, e.what());
  } catch (const YAML::Exception& e) {
    return Error::format(Errc::config, "%s: not valid YAML: %s", source_name.c_str(), e.what());
  }
}

Result<FirmwareConfig> load_config(const std::string& path) {
  // A configuration is a few kilobytes; anything far larger is the wrong file.
  constexpr std::size_t kMaxConfigBytes = 1 << 20;
  std::ifstream in(path, std::ios::binary);
  if (!in) return Error::format(Errc::not_found, "%s: cannot open the configuration file", path.c_str());
  std::string text(kMaxConfigBytes + 1, '\0');
  in.read(text.data(), static_cast<std::streamsize>(text.size()));
  text.resize(static_cast<std::size_t>(in.gcount()));
  if (text.size() > kMaxConfigBytes)
    return Error::format(Errc::config, "%s: larger than %zu bytes; not a configuration file", path.c_str(), kMaxConfigBytes);
  return parse_config(text, path);
}

}  // namespace sen3bot::firmware
