// The view row alone: the channels a configuration serves, the camera's frames as JPEG, and the
// `view` section of the configuration.
#include <gtest/gtest.h>

#include <cstring>
#include <memory>
#include <memory_resource>
#include <string>
#include <vector>

#include "config.hpp"
#include "sen3bot/camera/frame_pool.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/mem/budget_arena.hpp"
#include "sen3bot/nav/nav_tasks.hpp"
#include "sen3bot/json/json.hpp"
#include "sen3bot/view/session.hpp"
#include "view_task.hpp"

namespace sen3bot::firmware {
namespace {

namespace json = sen3bot::json;

std::vector<std::uint8_t> base64_decode(std::string_view text) {
  auto value = [](char c) -> int {
    if (c >= 'A' && c <= 'Z') return c - 'A';
    if (c >= 'a' && c <= 'z') return c - 'a' + 26;
    if (c >= '0' && c <= '9') return c - '0' + 52;
    return c == '+' ? 62 : c == '/' ? 63 : -1;
  };
  std::vector<std::uint8_t> out;
  unsigned bits = 0;
  int count = 0;
  for (char c : text) {
    const int v = value(c);
    if (v < 0) break;
    bits = (bits << 6) | static_cast<unsigned>(v);
    count += 6;
    if (count >= 8) {
      count -= 8;
      out.push_back(static_cast<std::uint8_t>((bits >> count) & 0xff));
    }
  }
  return out;
}

TEST(ViewTask, ServesOnlyTheChannelsItHasSourcesForAndIsAskedFor) {
  ViewTaskConfig config;
  std::array<view::ChannelSpec, kViewChannels> specs{};
  // A robot with a laser and nothing else: the scan and the statistics.
  std::size_t n = ViewTask::channel_specs(config, {0, false, true, false}, specs);
  ASSERT_EQ(n, 2u);
  EXPECT_EQ(specs[0].topic, "/scan");
  EXPECT_EQ(specs[1].topic, "/stats");
  // Navigation: the grids are sized from the map.
  n = ViewTask::channel_specs(config, {160 * 190, true, true, false}, specs);
  EXPECT_EQ(n, kViewChannels - 1);  // no camera
  EXPECT_EQ(specs[0].topic, "/map");
  EXPECT_GT(specs[0].capacity_bytes, (160u * 190u + 2) / 3 * 4);
  // A channel with period 0 is off.
  config.period_s[static_cast<std::size_t>(ViewChannel::scan)] = 0;
  n = ViewTask::channel_specs(config, {0, false, true, true}, specs);
  ASSERT_EQ(n, 2u);
  EXPECT_EQ(specs[0].topic, "/camera/image");
  EXPECT_EQ(specs[1].topic, "/stats");
}

TEST(ViewTask, SendsTheCamerasNewestFrameAsJpegOncePerFrame) {
  auto pool = camera::FramePool::create(4, 640, 480, camera::PixelFormat::bgr8);
  ASSERT_TRUE(pool);
  hal::SimClock clock(hal::seconds(1));
  tasks::Scheduler scheduler(clock);
  ViewTaskConfig config;
  config.server.port = 0;
  ViewSources sources{.scheduler = scheduler, .clock = clock, .frames = FrameSource{pool->get()}};
  mem::BudgetArena arena("view", 2 * 1024 * 1024);  // outlives the task, as the firmware's arenas do
  ViewTask task(config, sources);
  ASSERT_TRUE(mem::try_init(arena, [&] { return task.init(arena); }));
  view::Server& server = *task.server();
  std::size_t camera = server.board().channel_count();
  for (std::size_t i = 0; i < server.board().channel_count(); ++i)
    if (server.board().spec(i).topic == "/camera/image") camera = i;
  ASSERT_LT(camera, server.board().channel_count());

  // No frame yet: nothing to send.
  task.step({clock.now(), clock.now(), 0});
  EXPECT_EQ(server.board().published(camera), 0u);
  // A 640 x 480 frame: red left half, blue right half.
  const int slot = (*pool)->begin_write();
  ASSERT_GE(slot, 0);
  std::span<std::uint8_t> pixels = (*pool)->slot_pixels(slot);
  for (std::size_t y = 0; y < 480; ++y)
    for (std::size_t x = 0; x < 640; ++x) {
      std::uint8_t* p = pixels.data() + (y * 640 + x) * 3;
      p[0] = x < 320 ? 0 : 255;  // B
      p[1] = 0;
      p[2] = x < 320 ? 255 : 0;  // R
    }
  (*pool)->publish(slot, 640, 480, 0, clock.now(), clock.now());
  clock.advance_to(clock.now() + hal::seconds(1));
  task.step({clock.now(), clock.now(), 1});
  ASSERT_EQ(server.board().published(camera), 1u);
  const view::Publication& pub = server.board().take(camera);
  const std::string text(pub.payload(0).data(), pub.payload(0).size());
  std::vector<json::Token> tokens(256);
  json::Document doc(tokens, json::Limits{16, 1 << 20});
  ASSERT_TRUE(doc.parse(text));
  EXPECT_TRUE(doc.root().find("format").string_equals("jpeg"));
  std::vector<char> data(text.size());
  const auto size = doc.root().find("data").string(data);
  ASSERT_TRUE(size);
  const std::vector<std::uint8_t> jpeg = base64_decode({data.data(), *size});
  ASSERT_GT(jpeg.size(), 100u);
  EXPECT_EQ(jpeg[0], 0xFF);  // SOI
  EXPECT_EQ(jpeg[1], 0xD8);
  EXPECT_EQ(jpeg[jpeg.size() - 2], 0xFF);  // EOI
  EXPECT_EQ(jpeg[jpeg.size() - 1], 0xD9);
  // SOF0's size: 640 wide shrunk to at most 320.
  std::size_t sof = 2;
  while (sof + 8 < jpeg.size() && !(jpeg[sof] == 0xFF && jpeg[sof + 1] == 0xC0)) ++sof;
  ASSERT_LT(sof + 8, jpeg.size());
  EXPECT_EQ((jpeg[sof + 5] << 8) | jpeg[sof + 6], 240);
  EXPECT_EQ((jpeg[sof + 7] << 8) | jpeg[sof + 8], 320);
  // The same frame again: not sent twice.
  clock.advance_to(clock.now() + hal::seconds(1));
  task.step({clock.now(), clock.now(), 2});
  EXPECT_EQ(server.board().published(camera), 1u);
  task.shutdown();
}

// The people channel marks a hidden person (kept out of the sensors' view): the label says so
// and the cage and body are grey.
TEST(ViewTask, APersonKeptHiddenIsLabelledAndGreyed) {
  hal::SimClock clock(hal::seconds(1));
  tasks::Scheduler scheduler(clock);
  const nav::OccupancyMap map(40, 40, 0.1, 0.0, 0.0);
  tasks::Topic<msg::PoseEstimate> pose;
  tasks::Topic<msg::NavGoal> goal;
  tasks::Topic<msg::ScanMessage> scan;
  tasks::Topic<msg::PathMessage> path;
  tasks::Topic<msg::People> people;
  nav::PlannerTask planner(nav::PlannerTaskConfig{}, map, {}, {goal, pose, scan, path});  // only there: not run
  ViewTaskConfig config;
  config.server.port = 0;
  config.period_s.fill(0.0);
  config.period_s[static_cast<std::size_t>(ViewChannel::people)] = 0.2;
  ViewSources sources{.scheduler = scheduler, .clock = clock, .map = &map, .pose = &pose, .people = &people, .planner = &planner};
  mem::BudgetArena arena("view", 2 * 1024 * 1024);
  ViewTask task(config, sources);
  ASSERT_TRUE(mem::try_init(arena, [&] { return task.init(arena); }));
  view::Server& server = *task.server();
  ASSERT_EQ(server.board().channel_count(), 1u);
  ASSERT_EQ(server.board().spec(0).topic, "/people");

  msg::People list;
  list.count = 2;
  list.stamp_ns = clock.now();
  list.items[0] = {.id = 3, .x_m = 1.0, .y_m = 2.0, .width_m = 0.4, .cage_radius_m = 0.7};
  list.items[1] = {.id = 4, .x_m = 2.0, .y_m = 1.0, .width_m = 0.4, .cage_radius_m = 1.1};
  list.items[1].hidden = true;
  list.items[1].position_sigma_m = 0.6;
  people.publish(list, clock.now());
  task.step({clock.now(), clock.now(), 0});
  ASSERT_EQ(server.board().published(0), 1u);
  const view::Publication& pub = server.board().take(0);
  const std::string text(pub.payload(0).data(), pub.payload(0).size());
  std::vector<json::Token> tokens(4096);
  json::Document doc(tokens, json::Limits{32, 1 << 20});
  ASSERT_TRUE(doc.parse(text)) << text;
  std::size_t seen = 0;
  for (const json::Value entity : doc.root().find("entities").items()) {
    std::array<char, 64> id{};
    const auto id_size = entity.find("id").string(id);
    ASSERT_TRUE(id_size);
    const std::string name(id.data(), *id_size);
    const json::Value label = *entity.find("texts").items().begin();
    std::array<char, 64> words{};
    const auto size = label.find("text").string(words);
    ASSERT_TRUE(size);
    const double cage_red = *(*entity.find("lines").items().begin()).find("color").find("r").number();
    if (name == "person/3") {
      EXPECT_EQ(std::string(words.data(), *size), "person 3");
      EXPECT_DOUBLE_EQ(cage_red, 0.9);
      ++seen;
    } else if (name == "person/4") {
      EXPECT_EQ(std::string(words.data(), *size), "person 4 hidden");
      EXPECT_DOUBLE_EQ(cage_red, 0.5);
      ++seen;
    }
  }
  EXPECT_EQ(seen, 2u);
  task.shutdown();
}

Result<FirmwareConfig> parse_view(const std::string& view) {
  return parse_config(std::string(R"(
robot: { name: test-bot }
run: { clock: lockstep, duration_s: 1 }
tasks: { health: { arena_bytes: 4KiB }, view: { arena_bytes: 1MiB } }
view:
)") + view,
                      "robot.yaml");
}

TEST(ViewConfig, ReadsEveryKeyAndRefusesAnOpenAddressWithoutAToken) {
  Result<FirmwareConfig> r = parse_view(R"(
  address: 0.0.0.0
  port: 9000
  token: abc-123
  max_clients: 2
  channels: { map: 10, scan: 0 }
  camera: { max_width_px: 160, quality: 80 }
)");
  ASSERT_TRUE(r) << r.error().c_str();
  const ViewSection& v = r->view;
  EXPECT_TRUE(v.enabled);
  EXPECT_EQ(v.task.server.address, "0.0.0.0");
  EXPECT_EQ(v.task.server.port, 9000);
  EXPECT_EQ(v.task.server.token, "abc-123");
  EXPECT_EQ(v.task.server.max_clients, 2u);
  EXPECT_EQ(v.task.period_s[static_cast<std::size_t>(ViewChannel::map)], 10.0);
  EXPECT_EQ(v.task.period_s[static_cast<std::size_t>(ViewChannel::scan)], 0.0);
  EXPECT_EQ(v.task.period_s[static_cast<std::size_t>(ViewChannel::tf)], 0.1);  // default kept
  EXPECT_EQ(v.task.camera_max_width_px, 160u);
  EXPECT_EQ(v.task.camera_quality, 80);

  auto message = [](const std::string& view) {
    Result<FirmwareConfig> bad = parse_view(view);
    return bad ? std::string() : std::string(bad.error().c_str());
  };
  EXPECT_NE(message("  address: 0.0.0.0\n").find("token"), std::string::npos);
  EXPECT_NE(message("  channels: { maps: 1 }\n").find("unknown key"), std::string::npos);
  EXPECT_NE(message("  max_clients: 99\n").find("max_clients"), std::string::npos);
  EXPECT_NE(message("  token: a\n  token_file: /x\n").find("not both"), std::string::npos);
  EXPECT_NE(message("  token_file: /no/such/token\n").find("cannot read"), std::string::npos);
  EXPECT_NE(message("  wat: 1\n").find("unknown key"), std::string::npos);
  // Off: nothing is checked further and the row does not run.
  Result<FirmwareConfig> off = parse_view("  enabled: false\n  address: 0.0.0.0\n");
  ASSERT_TRUE(off);
  EXPECT_FALSE(off->view.enabled);
}

}  // namespace
}  // namespace sen3bot::firmware
