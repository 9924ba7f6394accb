// The YAML reader: values within their limits, and every mistake named by file, dotted key,
// problem, line and column.
#include "sen3bot/yaml/reader.hpp"

#include <gtest/gtest.h>

#include <string>
#include <vector>

namespace sen3bot::yaml {
namespace {

struct Values {
  std::string name;
  std::int64_t count = 0;
  double speed = 0.0;
  bool enabled = false;
  std::size_t arena = 0;
  geometry::Point2D goal;
  std::vector<double> pose;
  std::vector<std::string> tags;
  std::size_t mode = 0;
};

// The shape of every reader in the tree: allowed keys, then each value with its limits.
Values read_values(const Reader& top) {
  top.allow_only({"name", "count", "limits", "goal", "pose", "tags", "mode"});
  Values v;
  v.name = top.text("name");
  v.count = top.integer("count", 1, 10);
  const Reader limits = top.child("limits");
  limits.allow_only({"speed_m_s", "enabled", "arena_bytes"});
  v.speed = limits.number("speed_m_s", 0.0, 2.0);
  if (limits.has("enabled")) v.enabled = limits.boolean("enabled");
  if (limits.has("arena_bytes")) v.arena = limits.bytes("arena_bytes");
  v.goal = top.child("goal").point(100.0);
  if (top.has("pose")) v.pose = top.child("pose").numbers_here("[x, y] or [x, y, theta_deg]", 2, 3);
  if (top.has("tags"))
    for (const Reader& t : top.sequence("tags")) v.tags.push_back(t.text_here());
  if (top.has("mode")) v.mode = top.choice("mode", {"fast", "careful", "off"});
  return v;
}

const std::string kGood =
    "name: r1\n"
    "count: 3\n"
    "limits: {speed_m_s: 0.5, enabled: true, arena_bytes: 64KiB}\n"
    "goal: [4, -2.5]\n"
    "pose: [1, 2, 90]\n"
    "tags: [a, b]\n"
    "mode: careful\n";

Result<Values> parse_values(const std::string& text) { return parse<Values>(text, "v.yaml", read_values); }

TEST(YamlReader, ReadsEveryKindOfValue) {
  const Result<Values> v = parse_values(kGood);
  ASSERT_TRUE(v.ok()) << v.error().c_str();
  EXPECT_EQ(v->name, "r1");
  EXPECT_EQ(v->count, 3);
  EXPECT_DOUBLE_EQ(v->speed, 0.5);
  EXPECT_TRUE(v->enabled);
  EXPECT_EQ(v->arena, 64u * 1024u);
  EXPECT_DOUBLE_EQ(v->goal.x_m, 4.0);
  EXPECT_DOUBLE_EQ(v->goal.y_m, -2.5);
  EXPECT_EQ(v->pose, (std::vector<double>{1, 2, 90}));
  EXPECT_EQ(v->tags, (std::vector<std::string>{"a", "b"}));
  EXPECT_EQ(v->mode, 1u);
}

TEST(YamlReader, AListOfTwoOrThreeNumbers) {
  std::string text = kGood;
  text.replace(text.find("[1, 2, 90]"), 10, "[1, 2]");
  const Result<Values> v = parse_values(text);
  ASSERT_TRUE(v.ok()) << v.error().c_str();
  EXPECT_EQ(v->pose, (std::vector<double>{1, 2}));
}

struct Mistake {
  std::string from;  // text in kGood
  std::string to;    // what it becomes
  std::string message;
};

TEST(YamlReader, MistakesNameFileKeyLineAndColumn) {
  const Mistake mistakes[] = {
      // An unknown key names the allowed ones.
      {"speed_m_s:", "speed:",
       "v.yaml: limits.speed: unknown key (expected one of: speed_m_s, enabled, arena_bytes) (line 3, column 10)"},
      {"count: 3\n", "count: 3\ncolour: red\n",
       "v.yaml: colour: unknown key (expected one of: name, count, limits, goal, pose, tags, mode) (line 3, column 1)"},
      // A missing key: at the mapping that lacks it.
      {"count: 3\n", "", "v.yaml: count: missing (line 1, column 1)"},
      {"{speed_m_s: 0.5, ", "{", "v.yaml: limits.speed_m_s: missing (line 3, column 9)"},
      // Out of range.
      {"count: 3", "count: 11", "v.yaml: count: value 11 is outside [1, 10] (line 2, column 8)"},
      {"speed_m_s: 0.5", "speed_m_s: 2.5", "v.yaml: limits.speed_m_s: value 2.5 is outside [0, 2] (line 3, column 21)"},
      {"[4, -2.5]", "[400, -2.5]", "v.yaml: goal[0]: value 400 is outside [-100, 100] (line 4, column 8)"},
      // Not a number, not a single value, not one of the choices.
      {"count: 3", "count: three", "v.yaml: count: expected an integer, got 'three' (line 2, column 8)"},
      {"count: 3", "count: 2.5", "v.yaml: count: expected an integer, got '2.5' (line 2, column 8)"},
      {"speed_m_s: 0.5", "speed_m_s: .nan", "v.yaml: limits.speed_m_s: expected a number, got '.nan' (line 3, column 21)"},
      {"count: 3", "count: [3]", "v.yaml: count: expected a single value (line 2, column 8)"},
      {"enabled: true", "enabled: maybe", "v.yaml: limits.enabled: expected true or false, got 'maybe' (line 3, column 35)"},
      {"64KiB", "64KB",
       "v.yaml: limits.arena_bytes: byte size '64KB': unknown unit 'KB' (use B, KiB, MiB or GiB) (line 3, column 54)"},
      {"mode: careful", "mode: slow", "v.yaml: mode: expected fast, careful or off, got 'slow' (line 7, column 7)"},
      // A bad list.
      {"[4, -2.5]", "[4]", "v.yaml: goal: expected [x, y] (line 4, column 7)"},
      {"goal: [4, -2.5]", "goal: 4", "v.yaml: goal: expected [x, y] (line 4, column 7)"},
      {"[4, -2.5]", "[4, x]", "v.yaml: goal[1]: expected a number, got 'x' (line 4, column 11)"},
      {"[1, 2, 90]", "[1, 2, 90, 4]", "v.yaml: pose: expected [x, y] or [x, y, theta_deg] (line 5, column 7)"},
      {"tags: [a, b]", "tags: a", "v.yaml: tags: expected a list (line 6, column 7)"},
      {"tags: [a, b]", "tags: [a, [b]]", "v.yaml: tags[1]: expected a single value (line 6, column 11)"},
  };
  for (const Mistake& m : mistakes) {
    std::string text = kGood;
    const std::size_t at = text.find(m.from);
    ASSERT_NE(at, std::string::npos) << m.from;
    text.replace(at, m.from.size(), m.to);
    const Result<Values> v = parse_values(text);
    ASSERT_FALSE(v.ok()) << "accepted: " << text;
    EXPECT_EQ(v.error().code(), Errc::config);
    EXPECT_EQ(std::string(v.error().c_str()), m.message);
  }
}

TEST(YamlReader, TheFileItself) {
  const Result<Values> empty = parse_values("");
  ASSERT_FALSE(empty.ok());
  EXPECT_STREQ(empty.error().c_str(), "v.yaml: the file is empty");
  const Result<Values> list = parse_values("- 1\n- 2\n");
  ASSERT_FALSE(list.ok());
  EXPECT_STREQ(list.error().c_str(), "v.yaml: (top level): expected a mapping of keys (line 1, column 1)");
  const Result<Values> broken = parse_values("name: [r1\n");
  ASSERT_FALSE(broken.ok());
  EXPECT_EQ(std::string(broken.error().c_str()).rfind("v.yaml: not valid YAML: ", 0), 0u) << broken.error().c_str();
}

TEST(YamlReader, ARuleBetweenKeysNamesTheKey) {
  const Result<int> r = parse<int>("a: 1\nb: 2\n", "v.yaml", [](const Reader& top) -> int {
    top.fail("b", "must be below a");
  });
  ASSERT_FALSE(r.ok());
  EXPECT_STREQ(r.error().c_str(), "v.yaml: b: must be below a (line 2, column 4)");
  const Result<int> nowhere = parse<int>("a: 1\n", "v.yaml", [](const Reader& top) -> int {
    top.fail("a", "is odd", YAML::Node());
  });
  ASSERT_FALSE(nowhere.ok());
  EXPECT_STREQ(nowhere.error().c_str(), "v.yaml: a: is odd");
}

TEST(YamlReader, EntriesAndRelativePaths) {
  std::vector<std::string> seen;
  const Result<int> r = parse<int>("threads: {io: 1, control: 2}\n", "v.yaml", [&](const Reader& top) {
    top.child("threads").for_each_entry([&](const std::string& name, const Reader& value) {
      seen.push_back(name + "=" + std::to_string(value.integer_here(0, 9)));
    });
    return 0;
  });
  ASSERT_TRUE(r.ok()) << r.error().c_str();
  EXPECT_EQ(seen, (std::vector<std::string>{"io=1", "control=2"}));
  EXPECT_EQ(relative_to("config/robot.yaml", "maps/lab.yaml"), "config/maps/lab.yaml");
  EXPECT_EQ(relative_to("robot.yaml", "lab.yaml"), "lab.yaml");
  EXPECT_EQ(relative_to("config/robot.yaml", "/srv/lab.yaml"), "/srv/lab.yaml");
}

}  // namespace
}  // namespace sen3bot::yaml
