// The Foxglove encoders (view/core): each message read back with json::Document and
// its values checked, each validated against the schema the server advertises for it, the
// JSON writer's base64 and 64-bit integers, overflow, and no allocation while writing.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <cstdint>
#include <limits>
#include <random>
#include <string>
#include <string_view>
#include <vector>

#include "alloc_counter.hpp"
#include "sen3bot/view/foxglove.hpp"
#include "sen3bot/json/json.hpp"

namespace sen3bot::view {
namespace {

using mem::testing::AllocationScope;

constexpr std::array<Schema, kSchemaCount> kAllSchemas = {Schema::grid,         Schema::laser_scan,
                                                         Schema::frame_transform, Schema::poses_in_frame,
                                                         Schema::scene_update,    Schema::compressed_image,
                                                         Schema::task_stats,      Schema::mission};

// A reference decoder, deliberately unlike the encoder: bit by bit, padding checked.
bool decode_base64(std::string_view text, std::vector<std::uint8_t>& out) {
  out.clear();
  if (text.size() % 4 != 0) return false;
  const std::string_view alphabet = "ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
  std::uint32_t bits = 0;
  int count = 0;
  std::size_t pad = 0;
  for (std::size_t i = 0; i < text.size(); ++i) {
    if (text[i] == '=') {
      if (i + 2 < text.size()) return false;
      ++pad;
      continue;
    }
    if (pad) return false;
    const std::size_t v = alphabet.find(text[i]);
    if (v == std::string_view::npos) return false;
    bits = (bits << 6) | static_cast<std::uint32_t>(v);
    count += 6;
    if (count >= 8) {
      count -= 8;
      out.push_back(static_cast<std::uint8_t>(bits >> count));
      bits &= (1u << count) - 1;
    }
  }
  return bits == 0;  // the unused bits of the last character are zero
}

std::string string_of(json::Value v) {
  std::string s(v.json_text().size(), '\0');
  auto n = v.string(std::span<char>(s.data(), s.size()));
  if (!n) return "<not a string>";
  s.resize(*n);
  return s;
}

double number_of(json::Value v) {
  auto n = v.number();
  return n ? *n : std::numeric_limits<double>::quiet_NaN();
}

std::vector<std::string> keys_of(json::Value object) {
  std::vector<std::string> keys;
  for (json::Value::Member m : object.members()) keys.push_back(string_of(m.key));
  return keys;
}

// A small JSON Schema checker for the keywords the advertised schemas use: type (a name or a
// list), properties, required, items, minimum, maximum. Reports the first mismatch as a path.
bool type_matches(json::Value value, std::string_view type) {
  if (type == "integer") return value.is(json::Type::number) && std::floor(number_of(value)) == number_of(value);
  if (type == "number") return value.is(json::Type::number);
  if (type == "string") return value.is(json::Type::string);
  if (type == "boolean") return value.is(json::Type::boolean);
  if (type == "object") return value.is(json::Type::object);
  if (type == "array") return value.is(json::Type::array);
  if (type == "null") return value.is(json::Type::null);
  return false;
}

std::string validate(json::Value schema, json::Value value, const std::string& path) {
  if (!schema.is(json::Type::object)) return path + ": the schema is not an object";
  for (json::Value::Member m : schema.members()) {
    const std::string k = string_of(m.key);
    if (k != "type" && k != "title" && k != "properties" && k != "required" && k != "items" && k != "minimum" &&
        k != "maximum" && k != "contentEncoding")
      return path + ": unexpected keyword " + k;
  }
  if (json::Value type = schema.find("type"); type.valid()) {
    bool ok = false;
    if (type.is(json::Type::string)) {
      ok = type_matches(value, string_of(type));
    } else {
      for (json::Value t : type.items()) ok = ok || type_matches(value, string_of(t));
    }
    if (!ok)
      return path + ": type " + std::string(json::to_string(value.type())) + " not " + std::string(type.json_text());
  }
  if (json::Value min = schema.find("minimum"); min.valid() && number_of(value) < number_of(min))
    return path + ": below the minimum";
  if (json::Value max = schema.find("maximum"); max.valid() && number_of(value) > number_of(max))
    return path + ": above the maximum";
  if (value.is(json::Type::object)) {
    json::Value props = schema.find("properties");
    for (json::Value r : schema.find("required").items())
      if (!value.find(string_of(r)).valid()) return path + ": missing " + string_of(r);
    for (json::Value::Member m : value.members()) {
      const std::string k = string_of(m.key);
      json::Value sub = props.find(k);
      if (!sub.valid()) return path + ": member " + k + " not in the schema";
      if (std::string e = validate(sub, m.value, path + "." + k); !e.empty()) return e;
    }
  }
  if (value.is(json::Type::array)) {
    json::Value items = schema.find("items");
    std::size_t i = 0;
    for (json::Value v : value.items()) {
      if (!items.valid()) return path + ": array without items";
      if (std::string e = validate(items, v, path + "[" + std::to_string(i++) + "]"); !e.empty()) return e;
    }
  }
  return {};
}

// Parses a writer's output and keeps it (the document views into it).
class Parsed {
 public:
  explicit Parsed(const json::Writer& out) {
    auto text = out.finish();
    EXPECT_TRUE(text) << (text ? "" : text.error().c_str());
    if (!text) return;
    text_ = std::string(*text);
    Status st = doc_.parse(text_);
    EXPECT_TRUE(st) << (st ? "" : st.error().c_str());
  }
  json::Value root() const { return doc_.root(); }
  const std::string& text() const { return text_; }

 private:
  std::string text_;
  json::StaticDocument<65536> doc_{json::Limits{32, 4 * 1024 * 1024}};
};

// Checks the message against its advertised schema and returns the first error, if any.
std::string check_schema(Schema schema, const Parsed& message) {
  json::StaticDocument<4096> doc;
  Status st = doc.parse(json_schema(schema));
  if (!st) return std::string("schema does not parse: ") + st.error().c_str();
  return validate(doc.root(), message.root(), std::string(schema_name(schema)));
}

void expect_time(json::Value t, std::uint32_t sec, std::uint32_t nsec) {
  ASSERT_TRUE(t.is(json::Type::object));
  EXPECT_EQ(keys_of(t), (std::vector<std::string>{"sec", "nsec"}));
  EXPECT_EQ(*t.find("sec").uint32(), sec);
  EXPECT_EQ(*t.find("nsec").uint32(), nsec);
}

void expect_yaw(json::Value q, double yaw) {
  EXPECT_EQ(number_of(q.find("x")), 0.0);
  EXPECT_EQ(number_of(q.find("y")), 0.0);
  EXPECT_DOUBLE_EQ(number_of(q.find("z")), std::sin(yaw / 2));
  EXPECT_DOUBLE_EQ(number_of(q.find("w")), std::cos(yaw / 2));
}

void expect_pose(json::Value pose, double x, double y, double z, double yaw) {
  ASSERT_TRUE(pose.is(json::Type::object));
  EXPECT_EQ(keys_of(pose), (std::vector<std::string>{"position", "orientation"}));
  EXPECT_DOUBLE_EQ(number_of(pose.find("position").find("x")), x);
  EXPECT_DOUBLE_EQ(number_of(pose.find("position").find("y")), y);
  EXPECT_DOUBLE_EQ(number_of(pose.find("position").find("z")), z);
  expect_yaw(pose.find("orientation"), yaw);
}

std::vector<std::uint8_t> random_bytes(std::mt19937& rng, std::size_t n) {
  std::vector<std::uint8_t> bytes(n);
  for (auto& b : bytes) b = static_cast<std::uint8_t>(rng());
  return bytes;
}

// ---- the JSON writer's additions ----

std::string base64_text(std::span<const std::uint8_t> bytes) {
  std::vector<char> buf(bytes.size() * 2 + 16);
  json::Writer w(buf);
  w.base64(bytes);
  auto text = w.finish();
  EXPECT_TRUE(text);
  return text ? std::string(*text) : std::string();
}

TEST(JsonWriterBase64, MatchesTheRfcVectors) {
  const std::string_view input = "foobar";
  const std::array<std::string_view, 7> expected = {"\"\"",         "\"Zg==\"",     "\"Zm8=\"",    "\"Zm9v\"",
                                                    "\"Zm9vYg==\"", "\"Zm9vYmE=\"", "\"Zm9vYmFy\""};
  for (std::size_t n = 0; n <= input.size(); ++n) {
    const auto* data = reinterpret_cast<const std::uint8_t*>(input.data());
    EXPECT_EQ(base64_text(std::span<const std::uint8_t>(data, n)), expected[n]) << n;
  }
}

TEST(JsonWriterBase64, DecodesBackToTheInput) {
  std::mt19937 rng(20240611);
  std::vector<std::size_t> lengths = {0, 1, 2, 3, 4, 5};
  for (int i = 0; i < 200; ++i) lengths.push_back(rng() % 700);
  lengths.push_back(65536 + 1);
  for (std::size_t n : lengths) {
    const std::vector<std::uint8_t> bytes = random_bytes(rng, n);
    std::vector<char> buf(n * 2 + 64);
    json::Writer w(buf);
    w.begin_object().key("data").base64(bytes).end_object();
    auto text = w.finish();
    ASSERT_TRUE(text) << n;
    json::StaticDocument<8> doc(json::Limits{32, buf.size()});
    ASSERT_TRUE(doc.parse(*text)) << n;
    const std::string encoded = string_of(doc.root().find("data"));
    EXPECT_EQ(encoded.size(), (n + 2) / 3 * 4);
    std::vector<std::uint8_t> decoded;
    ASSERT_TRUE(decode_base64(encoded, decoded)) << n;
    EXPECT_EQ(decoded, bytes) << n;
  }
}

TEST(JsonWriterBase64, EveryByteValueAtEveryPosition) {
  std::vector<std::uint8_t> bytes;
  for (int k = 0; k < 3; ++k)
    for (int v = 0; v < 256; ++v) bytes.push_back(static_cast<std::uint8_t>(v));
  for (std::size_t skip = 0; skip < 3; ++skip) {
    const std::span<const std::uint8_t> part = std::span<const std::uint8_t>(bytes).subspan(skip);
    const std::string text = base64_text(part);
    ASSERT_GE(text.size(), 2u);
    std::vector<std::uint8_t> decoded;
    ASSERT_TRUE(decode_base64(std::string_view(text).substr(1, text.size() - 2), decoded));
    EXPECT_TRUE(std::equal(decoded.begin(), decoded.end(), part.begin(), part.end()));
  }
}

TEST(JsonWriterBase64, OverflowIsReportedNotTruncated) {
  const std::array<std::uint8_t, 5> bytes = {1, 2, 3, 4, 5};
  const std::size_t full = 2 + 8 + 2;  // [ "...." ]
  for (std::size_t size = 0; size <= full; ++size) {
    std::vector<char> buf(size);
    json::Writer w(buf);
    w.begin_array().base64(bytes).end_array();
    auto text = w.finish();
    if (size < full) {
      ASSERT_FALSE(text) << size;
      EXPECT_EQ(text.error().code(), Errc::capacity);
    } else {
      ASSERT_TRUE(text);
      EXPECT_EQ(*text, "[\"AQIDBAU=\"]");
    }
  }
}

TEST(JsonWriterBase64, CommasBetweenElements) {
  const std::array<std::uint8_t, 1> a = {0xFF};
  std::array<char, 64> buf;
  json::Writer w(buf);
  w.begin_array().base64(a).base64({}).uint32(7).base64(a).end_array();
  auto text = w.finish();
  ASSERT_TRUE(text);
  EXPECT_EQ(*text, "[\"/w==\",\"\",7,\"/w==\"]");
}

TEST(JsonWriterIntegers, SixtyFourBitExtremes) {
  std::array<char, 128> buf;
  json::Writer w(buf);
  w.begin_array()
      .int64(std::numeric_limits<std::int64_t>::min())
      .int64(-1)
      .int64(0)
      .int64(std::numeric_limits<std::int64_t>::max())
      .uint64(std::numeric_limits<std::uint64_t>::max())
      .end_array();
  auto text = w.finish();
  ASSERT_TRUE(text);
  EXPECT_EQ(*text, "[-9223372036854775808,-1,0,9223372036854775807,18446744073709551615]");
  json::StaticDocument<8> doc;
  EXPECT_TRUE(doc.parse(*text));
}

TEST(JsonWriterIntegers, MembersAndOverflow) {
  std::array<char, 24> buf;
  json::Writer w(buf);
  w.begin_object().member_int64("a", -5).member_uint64("b", 6).end_object();
  auto text = w.finish();
  ASSERT_TRUE(text);
  EXPECT_EQ(*text, "{\"a\":-5,\"b\":6}");
  std::array<char, 10> small;
  json::Writer o(small);
  o.begin_array().uint64(std::numeric_limits<std::uint64_t>::max()).end_array();
  ASSERT_FALSE(o.finish());
  EXPECT_EQ(o.finish().error().code(), Errc::capacity);
}

TEST(JsonWriterFloat32, ShortestAndRejectsNan) {
  std::array<char, 64> buf;
  json::Writer w(buf);
  w.begin_array().float32(1.23f).float32(0.0f).float32(-4.5f).end_array();
  auto text = w.finish();
  ASSERT_TRUE(text);
  EXPECT_EQ(*text, "[1.23,0,-4.5]");
  json::Writer n(buf);
  n.float32(std::numeric_limits<float>::quiet_NaN());
  ASSERT_FALSE(n.finish());
  EXPECT_EQ(n.finish().error().code(), Errc::invalid_argument);
}

// ---- the messages ----

// Buffers and inputs shared by the message tests (static: the allocation test reuses them).
struct Fixture {
  std::array<std::uint8_t, 12> cells = {0, 100, 255, 0, 1, 2, 3, 4, 5, 6, 7, 8};  // 4 x 3
  GridView grid{cells, 4, 3, 0.05, {-1.5, 2.25}, "occupancy"};
  std::array<float, 6> ranges = {0.5f, 0.0f, 7.99f, 8.0f, std::numeric_limits<float>::quiet_NaN(), 0.25f};
  std::array<Pose2, 3> poses = {Pose2{0, 0, 0}, Pose2{1, 0.5, 1.0}, Pose2{2, 1, -3.0}};
  std::array<std::uint8_t, 7> jpeg = {0xFF, 0xD8, 0xFF, 0xE0, 0x00, 0xFF, 0xD9};
  std::array<Point2, 4> square = {Point2{0, 0}, Point2{1, 0}, Point2{1, 1}, Point2{0, 1}};
  std::array<Line, 1> lines = {Line{LineType::loop, square, 0.05, {1, 0, 0, 1}}};
  std::array<Cylinder, 1> cylinders = {Cylinder{{2, 3}, 0.6, 1.7, {0, 0, 1, 0.5}}};
  std::array<Arrow, 1> arrows = {Arrow{{2, 3}, 0.5, 1.0, {0, 1, 0, 1}}};
  std::array<Text, 1> texts = {Text{{2, 3.5}, "person 7", 14, {1, 1, 1, 1}}};
  std::array<Entity, 2> entities = {Entity{"person/7", "map", 500'000'000, lines, cylinders, arrows, texts},
                                    Entity{"mover/2", "map", 0, {}, cylinders, arrows, {}}};
};
Fixture fx;

constexpr hal::Nanos kStamp = 1'717'171'717'123'456'789;

using WriteFn = void (*)(json::Writer&);
void write_grid_fx(json::Writer& w) { write_grid(w, kStamp, "map", fx.grid); }
void write_scan_fx(json::Writer& w) { write_laser_scan(w, kStamp, "laser", fx.ranges, -1.5, 0.5, 0.25, 8.0); }
void write_tf_fx(json::Writer& w) { write_frame_transform(w, kStamp, "map", "odom", Pose2{1.5, -2.0, 0.75}); }
void write_poses_fx(json::Writer& w) { write_poses_in_frame(w, kStamp, "map", fx.poses); }
void write_image_fx(json::Writer& w) { write_compressed_image(w, kStamp, "camera", fx.jpeg, "jpeg"); }
void write_scene_fx(json::Writer& w) { write_scene_update(w, kStamp, true, fx.entities); }

struct Case {
  Schema schema;
  WriteFn write;
};
constexpr std::array<Case, 6> kCases = {Case{Schema::grid, write_grid_fx}, Case{Schema::laser_scan, write_scan_fx},
                                        Case{Schema::frame_transform, write_tf_fx},
                                        Case{Schema::poses_in_frame, write_poses_fx},
                                        Case{Schema::compressed_image, write_image_fx},
                                        Case{Schema::scene_update, write_scene_fx}};

std::array<char, 1 << 16> g_buf;

TEST(Foxglove, TimesFromNanoseconds) {
  const std::array<std::pair<hal::Nanos, std::pair<std::uint32_t, std::uint32_t>>, 6> cases = {{
      {0, {0, 0}},
      {1'500'000'123, {1, 500'000'123}},
      {999'999'999, {0, 999'999'999}},
      {-1, {0, 0}},
      {std::numeric_limits<hal::Nanos>::min(), {0, 0}},
      {std::numeric_limits<hal::Nanos>::max(), {4'294'967'295u, 999'999'999}},
  }};
  for (const auto& [ns, want] : cases) {
    json::Writer w(g_buf);
    write_frame_transform(w, ns, "odom", "base_link", Pose2{});
    Parsed p(w);
    expect_time(p.root().find("timestamp"), want.first, want.second);
  }
}

TEST(Foxglove, FrameTransformQuaternionFromYaw) {
  for (double yaw : {0.0, 0.3, -1.2, M_PI / 2, M_PI, -M_PI, 3.0}) {
    json::Writer w(g_buf);
    write_frame_transform(w, kStamp, "map", "odom", Pose2{1.5, -2.0, yaw});
    Parsed p(w);
    const json::Value r = p.root();
    EXPECT_EQ(string_of(r.find("parent_frame_id")), "map");
    EXPECT_EQ(string_of(r.find("child_frame_id")), "odom");
    EXPECT_EQ(number_of(r.find("translation").find("x")), 1.5);
    EXPECT_EQ(number_of(r.find("translation").find("y")), -2.0);
    EXPECT_EQ(number_of(r.find("translation").find("z")), 0.0);
    const json::Value q = r.find("rotation");
    expect_yaw(q, yaw);
    const double z = number_of(q.find("z")), wq = number_of(q.find("w"));
    EXPECT_NEAR(z * z + wq * wq, 1.0, 1e-12);
    EXPECT_NEAR(std::atan2(2 * wq * z, 1 - 2 * z * z), std::remainder(yaw, 2 * M_PI), 1e-9);
  }
}

TEST(Foxglove, Grid) {
  json::Writer w(g_buf);
  write_grid_fx(w);
  Parsed p(w);
  const json::Value r = p.root();
  expect_time(r.find("timestamp"), 1'717'171'717u, 123'456'789u);
  EXPECT_EQ(string_of(r.find("frame_id")), "map");
  expect_pose(r.find("pose"), -1.5, 2.25, 0.0, 0.0);
  EXPECT_EQ(*r.find("column_count").uint32(), 4u);
  EXPECT_EQ(*r.find("row_stride").uint32(), 4u);
  EXPECT_EQ(*r.find("cell_stride").uint32(), 1u);
  EXPECT_EQ(number_of(r.find("cell_size").find("x")), 0.05);
  EXPECT_EQ(number_of(r.find("cell_size").find("y")), 0.05);
  const json::Value fields = r.find("fields");
  ASSERT_EQ(fields.size(), 1u);
  const json::Value f = *fields.items().begin();
  EXPECT_EQ(keys_of(f), (std::vector<std::string>{"name", "offset", "type"}));
  EXPECT_EQ(string_of(f.find("name")), "occupancy");
  EXPECT_EQ(*f.find("offset").uint32(), 0u);
  EXPECT_EQ(*f.find("type").uint32(), 1u);
  std::vector<std::uint8_t> data;
  ASSERT_TRUE(decode_base64(string_of(r.find("data")), data));
  EXPECT_EQ(data, std::vector<std::uint8_t>(fx.cells.begin(), fx.cells.end()));
}

TEST(Foxglove, GridWritesWholeRowsOnly) {
  GridView g = fx.grid;
  g.cells = std::span<const std::uint8_t>(fx.cells).first(10);  // 2.5 rows of 4
  json::Writer w(g_buf);
  write_grid(w, kStamp, "map", g);
  Parsed p(w);
  std::vector<std::uint8_t> data;
  ASSERT_TRUE(decode_base64(string_of(p.root().find("data")), data));
  EXPECT_EQ(data.size(), 8u);
  g.columns = 0;
  json::Writer e(g_buf);
  write_grid(e, kStamp, "map", g);
  Parsed q(e);
  EXPECT_EQ(string_of(q.root().find("data")), "");
}

TEST(Foxglove, LaserScanNoReturnIsZero) {
  json::Writer w(g_buf);
  write_scan_fx(w);
  Parsed p(w);
  const json::Value r = p.root();
  EXPECT_EQ(string_of(r.find("frame_id")), "laser");
  expect_pose(r.find("pose"), 0, 0, 0, 0);
  EXPECT_EQ(number_of(r.find("start_angle")), -1.5);
  EXPECT_DOUBLE_EQ(number_of(r.find("end_angle")), -1.5 + 5 * 0.5);
  std::vector<double> ranges;
  for (json::Value v : r.find("ranges").items()) ranges.push_back(number_of(v));
  // 0.5 in range, 0 below the minimum, 7.99 in, 8.0 at the maximum (excluded), NaN, the minimum itself.
  const std::vector<double> want = {0.5, 0.0, static_cast<double>(7.99f), 0.0, 0.0, 0.25};
  ASSERT_EQ(ranges.size(), want.size());
  for (std::size_t i = 0; i < want.size(); ++i)
    EXPECT_FLOAT_EQ(static_cast<float>(ranges[i]), static_cast<float>(want[i])) << i;
  EXPECT_NE(p.text().find("\"ranges\":[0.5,0,7.99,0,0,0.25]"), std::string::npos) << p.text();
  EXPECT_TRUE(r.find("intensities").is(json::Type::array));
  EXPECT_EQ(r.find("intensities").size(), 0u);
}

TEST(Foxglove, LaserScanEmpty) {
  json::Writer w(g_buf);
  write_laser_scan(w, kStamp, "laser", {}, 0.25, 0.01, 0.0, 1.0);
  Parsed p(w);
  EXPECT_EQ(number_of(p.root().find("end_angle")), 0.25);
  EXPECT_EQ(p.root().find("ranges").size(), 0u);
  EXPECT_EQ(check_schema(Schema::laser_scan, p), "");
}

TEST(Foxglove, PosesInFrame) {
  json::Writer w(g_buf);
  write_poses_fx(w);
  Parsed p(w);
  const json::Value r = p.root();
  EXPECT_EQ(string_of(r.find("frame_id")), "map");
  ASSERT_EQ(r.find("poses").size(), fx.poses.size());
  std::size_t i = 0;
  for (json::Value pose : r.find("poses").items()) {
    expect_pose(pose, fx.poses[i].x_m, fx.poses[i].y_m, 0.0, fx.poses[i].theta_rad);
    ++i;
  }
}

TEST(Foxglove, CompressedImage) {
  json::Writer w(g_buf);
  write_image_fx(w);
  Parsed p(w);
  const json::Value r = p.root();
  EXPECT_EQ(string_of(r.find("frame_id")), "camera");
  EXPECT_EQ(string_of(r.find("format")), "jpeg");
  std::vector<std::uint8_t> data;
  ASSERT_TRUE(decode_base64(string_of(r.find("data")), data));
  EXPECT_EQ(data, std::vector<std::uint8_t>(fx.jpeg.begin(), fx.jpeg.end()));
}

const std::vector<std::string> kEntityKeys = {"timestamp", "frame_id", "id",        "lifetime", "frame_locked",
                                              "metadata",  "arrows",   "cubes",     "spheres",  "cylinders",
                                              "lines",     "triangles", "texts",    "models"};

TEST(Foxglove, SceneUpdateDeleteAllAndEntities) {
  json::Writer w(g_buf);
  write_scene_fx(w);
  Parsed p(w);
  const json::Value r = p.root();
  EXPECT_EQ(keys_of(r), (std::vector<std::string>{"deletions", "entities"}));
  ASSERT_EQ(r.find("deletions").size(), 1u);
  const json::Value d = *r.find("deletions").items().begin();
  EXPECT_EQ(*d.find("type").uint32(), 1u);
  EXPECT_EQ(string_of(d.find("id")), "");
  expect_time(d.find("timestamp"), 1'717'171'717u, 123'456'789u);

  ASSERT_EQ(r.find("entities").size(), 2u);
  const json::Value person = *r.find("entities").items().begin();
  EXPECT_EQ(keys_of(person), kEntityKeys);
  EXPECT_EQ(string_of(person.find("id")), "person/7");
  EXPECT_EQ(string_of(person.find("frame_id")), "map");
  expect_time(person.find("lifetime"), 0, 500'000'000);
  EXPECT_FALSE(*person.find("frame_locked").boolean());
  for (const char* unused : {"metadata", "cubes", "spheres", "triangles", "models"}) {
    EXPECT_TRUE(person.find(unused).is(json::Type::array)) << unused;
    EXPECT_EQ(person.find(unused).size(), 0u) << unused;
  }
  for (const char* used : {"arrows", "cylinders", "lines", "texts"}) EXPECT_EQ(person.find(used).size(), 1u) << used;

  const json::Value line = *person.find("lines").items().begin();
  EXPECT_EQ(*line.find("type").uint32(), 1u);  // LINE_LOOP
  expect_pose(line.find("pose"), 0, 0, 0, 0);
  EXPECT_EQ(number_of(line.find("thickness")), 0.05);
  EXPECT_FALSE(*line.find("scale_invariant").boolean());
  ASSERT_EQ(line.find("points").size(), 4u);
  std::size_t i = 0;
  for (json::Value pt : line.find("points").items()) {
    EXPECT_EQ(number_of(pt.find("x")), fx.square[i].x_m);
    EXPECT_EQ(number_of(pt.find("y")), fx.square[i].y_m);
    EXPECT_EQ(number_of(pt.find("z")), 0.0);
    ++i;
  }
  EXPECT_EQ(number_of(line.find("color").find("r")), 1.0);
  EXPECT_EQ(line.find("colors").size(), 0u);
  EXPECT_EQ(line.find("indices").size(), 0u);

  const json::Value cyl = *person.find("cylinders").items().begin();
  expect_pose(cyl.find("pose"), 2, 3, 0.85, 0);
  EXPECT_EQ(number_of(cyl.find("size").find("x")), 0.6);
  EXPECT_EQ(number_of(cyl.find("size").find("y")), 0.6);
  EXPECT_EQ(number_of(cyl.find("size").find("z")), 1.7);
  EXPECT_EQ(number_of(cyl.find("bottom_scale")), 1.0);
  EXPECT_EQ(number_of(cyl.find("top_scale")), 1.0);
  EXPECT_EQ(number_of(cyl.find("color").find("a")), 0.5);

  const json::Value arrow = *person.find("arrows").items().begin();
  expect_pose(arrow.find("pose"), 2, 3, 0, 0.5);
  EXPECT_DOUBLE_EQ(number_of(arrow.find("shaft_length")), 0.8);
  EXPECT_DOUBLE_EQ(number_of(arrow.find("head_length")), 0.2);
  EXPECT_GT(number_of(arrow.find("head_diameter")), number_of(arrow.find("shaft_diameter")));
  EXPECT_GT(number_of(arrow.find("shaft_diameter")), 0.0);

  const json::Value text = *person.find("texts").items().begin();
  expect_pose(text.find("pose"), 2, 3.5, 0, 0);
  EXPECT_TRUE(*text.find("billboard").boolean());
  EXPECT_TRUE(*text.find("scale_invariant").boolean());
  EXPECT_EQ(number_of(text.find("font_size")), 14.0);
  EXPECT_EQ(string_of(text.find("text")), "person 7");

  json::Value mover;
  for (json::Value e : r.find("entities").items()) mover = e;
  EXPECT_EQ(keys_of(mover), kEntityKeys);
  EXPECT_EQ(string_of(mover.find("id")), "mover/2");
  expect_time(mover.find("lifetime"), 0, 0);
  EXPECT_EQ(mover.find("lines").size(), 0u);
  EXPECT_EQ(mover.find("texts").size(), 0u);
}

TEST(Foxglove, SceneUpdateWithoutDeleteAll) {
  json::Writer w(g_buf);
  write_scene_update(w, kStamp, false, {});
  Parsed p(w);
  EXPECT_EQ(p.text(), "{\"deletions\":[],\"entities\":[]}");
  EXPECT_EQ(check_schema(Schema::scene_update, p), "");
}

// ---- the schemas ----

TEST(Schemas, NamesAreDistinct) {
  for (std::size_t a = 0; a < kAllSchemas.size(); ++a) {
    EXPECT_FALSE(schema_name(kAllSchemas[a]).empty());
    for (std::size_t b = a + 1; b < kAllSchemas.size(); ++b)
      EXPECT_NE(schema_name(kAllSchemas[a]), schema_name(kAllSchemas[b]));
  }
  EXPECT_EQ(schema_name(Schema::grid), "foxglove.Grid");
  EXPECT_EQ(schema_name(Schema::scene_update), "foxglove.SceneUpdate");
  EXPECT_EQ(schema_name(Schema::mission), "sen3bot.Mission");
}

TEST(Schemas, EachParsesAsAnObjectSchema) {
  for (Schema s : kAllSchemas) {
    json::StaticDocument<4096> doc;
    const Status st = doc.parse(json_schema(s));
    ASSERT_TRUE(st) << schema_name(s) << ": " << (st ? "" : st.error().c_str());
    const json::Value r = doc.root();
    EXPECT_EQ(string_of(r.find("type")), "object") << schema_name(s);
    EXPECT_EQ(string_of(r.find("title")), schema_name(s));
    // Every property is required and every required name is a property.
    std::vector<std::string> required;
    for (json::Value v : r.find("required").items()) required.push_back(string_of(v));
    EXPECT_EQ(required, keys_of(r.find("properties"))) << schema_name(s);
  }
}

TEST(Schemas, RequiredIsExactlyWhatTheWritersEmit) {
  for (const Case& c : kCases) {
    json::Writer w(g_buf);
    c.write(w);
    Parsed p(w);
    json::StaticDocument<4096> doc;
    ASSERT_TRUE(doc.parse(json_schema(c.schema)));
    std::vector<std::string> required;
    for (json::Value v : doc.root().find("required").items()) required.push_back(string_of(v));
    EXPECT_EQ(required, keys_of(p.root())) << schema_name(c.schema);
  }
}

TEST(Schemas, EveryMessageValidates) {
  for (const Case& c : kCases) {
    json::Writer w(g_buf);
    c.write(w);
    Parsed p(w);
    EXPECT_EQ(check_schema(c.schema, p), "") << p.text();
  }
}

TEST(Schemas, TheCheckerCatchesMismatches) {
  // A negative control: the validator used above does reject wrong messages.
  // A frame transform without rotation, with a negative second, with a string coordinate, with an extra member.
  const std::string head = R"({"timestamp":{"sec":1,"nsec":2},"parent_frame_id":"a","child_frame_id":"b",)";
  const std::string rotation = R"(,"rotation":{"x":0,"y":0,"z":0,"w":1})";
  const std::array<std::string, 4> bad = {
      head + R"("translation":{"x":0,"y":0,"z":0}})",
      R"({"timestamp":{"sec":-1,"nsec":2},"parent_frame_id":"a","child_frame_id":"b",)"
      R"("translation":{"x":0,"y":0,"z":0})" + rotation + "}",
      head + R"("translation":{"x":0,"y":0,"z":"0"})" + rotation + "}",
      head + R"("translation":{"x":0,"y":0,"z":0})" + rotation + R"(,"extra":1})",
  };
  json::StaticDocument<512> schema;
  ASSERT_TRUE(schema.parse(json_schema(Schema::frame_transform)));
  for (const std::string& text : bad) {
    json::StaticDocument<256> doc;
    ASSERT_TRUE(doc.parse(text));
    EXPECT_NE(validate(schema.root(), doc.root(), "m"), "") << text;
  }
}

TEST(Schemas, MissionFollowsTheDocumentedFields) {
  json::StaticDocument<1024> schema;
  ASSERT_TRUE(schema.parse(json_schema(Schema::mission)));
  const std::vector<std::string> fields = {"timestamp", "state", "goals_reached", "goals_total", "goal", "pose",
                                           "localized", "lost",  "v",             "w",           "controller",
                                           "safety",    "separation"};
  EXPECT_EQ(keys_of(schema.root().find("properties")), fields);
  const std::string_view example = R"({"timestamp":{"sec":5,"nsec":0},"state":"driving","goals_reached":1,)"
                                   R"("goals_total":3,"goal":{"x":2.5,"y":2.0},"pose":{"x":1,"y":2,"theta":0.1},)"
                                   R"("localized":true,"lost":false,"v":0.31,"w":-0.05,"controller":"following",)"
                                   R"("safety":["slow_zone","separation"],"separation":{"cap":0.21,"gap":0.64,"approach":1.1}})";
  json::StaticDocument<256> doc;
  ASSERT_TRUE(doc.parse(example));
  EXPECT_EQ(validate(schema.root(), doc.root(), "mission"), "");
  std::string no_goal(example);
  no_goal.replace(no_goal.find("{\"x\":2.5,\"y\":2.0}"), 17, "null");
  ASSERT_TRUE(doc.parse(no_goal));
  EXPECT_EQ(validate(schema.root(), doc.root(), "mission"), "");
  std::string no_limit(example);
  no_limit.replace(no_limit.find("{\"cap\""), 38, "null");
  ASSERT_TRUE(doc.parse(no_limit)) << no_limit;
  EXPECT_EQ(validate(schema.root(), doc.root(), "mission"), "");
  std::string bad_safety(example);
  bad_safety.replace(bad_safety.find("\"slow_zone\""), 11, "1");
  ASSERT_TRUE(doc.parse(bad_safety));
  EXPECT_NE(validate(schema.root(), doc.root(), "mission"), "");
  std::string no_gap(example);
  no_gap.replace(no_gap.find(",\"gap\":0.64"), 11, "");
  ASSERT_TRUE(doc.parse(no_gap)) << no_gap;
  EXPECT_NE(validate(schema.root(), doc.root(), "mission"), "");
}

TEST(Schemas, TaskStatsFollowsTheDocumentedFields) {
  json::StaticDocument<1024> schema;
  ASSERT_TRUE(schema.parse(json_schema(Schema::task_stats)));
  const json::Value props = schema.root().find("properties");
  EXPECT_EQ(keys_of(props), (std::vector<std::string>{"timestamp", "uptime_s", "tasks", "view"}));
  EXPECT_EQ(keys_of(props.find("tasks").find("items").find("properties")),
            (std::vector<std::string>{"name", "thread", "period_us", "budget_us", "runs", "overruns", "slips", "skips",
                                      "exec_mean_us", "exec_max_us", "cpu_mean_us", "cpu_max_us", "jitter_p99_us"}));
  EXPECT_EQ(keys_of(props.find("view").find("properties")),
            (std::vector<std::string>{"clients", "sent", "dropped", "rejected"}));
  const std::string_view example =
      R"({"timestamp":{"sec":5,"nsec":7},"uptime_s":12.5,"tasks":[{"name":"control","thread":"rt","period_us":10000,)"
      R"("budget_us":2000,"runs":1250,"overruns":0,"slips":1,"skips":0,"exec_mean_us":210.5,"exec_max_us":900,)"
      R"("cpu_mean_us":200.1,"cpu_max_us":850.2,"jitter_p99_us":35.0}],)"
      R"("view":{"clients":1,"sent":1234,"dropped":5,"rejected":0}})";
  json::StaticDocument<256> doc;
  ASSERT_TRUE(doc.parse(example));
  EXPECT_EQ(validate(schema.root(), doc.root(), "stats"), "");
}

// ---- failure and memory ----

TEST(Foxglove, OverflowFailsWithoutTruncatedText) {
  for (const Case& c : kCases) {
    json::Writer full(g_buf);
    c.write(full);
    auto text = full.finish();
    ASSERT_TRUE(text) << schema_name(c.schema);
    const std::size_t need = text->size();
    std::vector<char> buf(need);
    for (std::size_t size = 0; size < need; ++size) {
      json::Writer w(std::span<char>(buf.data(), size));
      c.write(w);
      auto r = w.finish();
      ASSERT_FALSE(r) << schema_name(c.schema) << " in " << size << " of " << need << " bytes";
      EXPECT_EQ(r.error().code(), Errc::capacity);
      EXPECT_LE(w.size(), size);
    }
    json::Writer exact(std::span<char>(buf.data(), need));
    c.write(exact);
    ASSERT_TRUE(exact.finish());
    EXPECT_EQ(*exact.finish(), *text);
  }
}

TEST(Foxglove, WritersAllocateNothing) {
  std::array<std::uint8_t, 4096> big{};
  for (std::size_t i = 0; i < big.size(); ++i) big[i] = static_cast<std::uint8_t>(i * 37);
  const GridView grid{big, 64, 64, 0.1, {0, 0}, "cost"};
  std::size_t bytes = 0;
  AllocationScope scope;
  for (int round = 0; round < 100; ++round) {
    for (const Case& c : kCases) {
      json::Writer w(g_buf);
      c.write(w);
      bytes += w.size();
    }
    json::Writer w(g_buf);
    write_grid(w, kStamp, "map", grid);
    bytes += w.size();
    (void)json_schema(Schema::mission);
  }
  EXPECT_EQ(scope.allocations(), 0u);
  EXPECT_EQ(scope.malloc_calls(), 0u);
  EXPECT_GT(bytes, 0u);
}

}  // namespace
}  // namespace sen3bot::view
