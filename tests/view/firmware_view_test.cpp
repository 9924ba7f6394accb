// The live view inside the whole firmware on the simulated robot: what its channels carry is
// the firmware's own state, and a viewer that stops reading costs no task a period.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cmath>
#include <cstdio>
#include <cstring>
#include <map>
#include <memory>
#include <algorithm>
#include <string>
#include <thread>
#include <vector>

#include "firmware.hpp"
#include "sen3bot/vda5050/json.hpp"
#include "sen3bot/view/session.hpp"
#include "sim_rig.hpp"
#include "ws_client.hpp"

namespace sen3bot::firmware {
namespace {

using testing::WsClient;
namespace json = vda5050::json;

// Subscribes to every advertised channel (subscription id = channel id); returns the topics.
std::vector<std::string> subscribe_all(WsClient& c, int port) {
  EXPECT_NE(c.connect("127.0.0.1", port).find(" 101 "), std::string::npos);
  EXPECT_NE(c.read().payload.find("serverInfo"), std::string_view::npos);
  const std::string advertise(c.read().payload);
  std::vector<json::Token> tokens(4096);
  json::Document doc(tokens, json::Limits{32, 1 << 20});
  EXPECT_TRUE(doc.parse(advertise));
  std::vector<std::string> topics;
  std::string sub = R"({"op":"subscribe","subscriptions":[)";
  for (json::Value ch : doc.root().find("channels").items()) {
    char topic[64];
    const auto n = ch.find("topic").string(topic);
    topics.emplace_back(topic, n ? *n : 0);
    const std::uint32_t id = *ch.find("id").uint32();
    sub += (topics.size() > 1 ? "," : "") + std::string(R"({"id":)") + std::to_string(id) + R"(,"channelId":)" +
           std::to_string(id) + "}";
  }
  c.send_text(sub + "]}");
  return topics;
}

FirmwareConfig with_view(FirmwareConfig config) {
  config.view.enabled = true;
  config.view.task.server.port = 0;
  config.tasks["view"].arena_bytes = 4 * 1024 * 1024;
  return config;
}

TEST(ViewFirmware, TheChannelsCarryTheFirmwaresOwnState) {
  testing::SimRig rig = testing::load_sim_rig();
  ASSERT_NE(rig.board, nullptr);
  FirmwareConfig config = with_view(rig.config);
  // The mission every view step, so its last message is at most one step old.
  config.view.task.period_s[static_cast<std::size_t>(ViewChannel::mission)] = 0.05;
  std::FILE* sink = std::fopen("/dev/null", "w");
  Firmware fw(config, *rig.board, sink);
  ASSERT_TRUE(fw.init());
  auto viewer = std::make_unique<WsClient>();
  const std::vector<std::string> topics = subscribe_all(*viewer, fw.view()->server()->port());
  for (const char* t : {"/map", "/costmap/global", "/costmap/local", "/scan", "/tf", "/plan", "/safe_path", "/path/driven",
                        "/dwa", "/people", "/stats", "/mission"})
    EXPECT_NE(std::find(topics.begin(), topics.end(), t), topics.end()) << t;
  ASSERT_TRUE(fw.scheduler().run_lockstep(rig.clock(), hal::seconds(20)));
  // The run has stopped: the newest message of each channel is what the firmware last published.
  std::map<std::string, std::string> last;
  for (;;) {
    const WsClient::Frame f = viewer->read(1500);
    if (f.opcode < 0) break;
    if (f.opcode != 2 || f.payload.size() < view::kFrameHeader) continue;
    std::uint32_t id = 0;
    std::memcpy(&id, f.payload.data() + 1, 4);
    ASSERT_LT(id, topics.size());
    const std::string payload(f.payload.substr(view::kFrameHeader));
    if (topics[id] == "/tf") last["/tf " + payload.substr(payload.find("child_frame_id"), 30)] = payload;
    else last[topics[id]] = payload;
  }
  std::vector<json::Token> tokens(8192);
  json::Document doc(tokens, json::Limits{32, 4 << 20});
  // The map: the occupancy map's size and resolution.
  ASSERT_TRUE(doc.parse(last["/map"]));
  EXPECT_EQ(*doc.root().find("column_count").uint32(), static_cast<std::uint32_t>(fw.map().width()));
  EXPECT_NEAR(*doc.root().find("cell_size").find("x").number(), fw.map().resolution_m(), 1e-9);
  char data_text[8];
  EXPECT_FALSE(doc.root().find("data").string(data_text));  // the cells are there (far more than 8 bytes)
  // The pose: map -> odom -> base_link is the estimate.
  double x = 0, y = 0, th = 0;
  for (const char* child : {"odom", "base_link"}) {
    std::string key;
    for (const auto& [k, v] : last)
      if (k.starts_with("/tf") && k.find(std::string("\"") + child + "\"") != std::string::npos) key = k;
    ASSERT_FALSE(key.empty()) << child;
    ASSERT_TRUE(doc.parse(last[key]));
    const double tx = *doc.root().find("translation").find("x").number();
    const double ty = *doc.root().find("translation").find("y").number();
    const double qz = *doc.root().find("rotation").find("z").number();
    const double qw = *doc.root().find("rotation").find("w").number();
    const double a = 2.0 * std::atan2(qz, qw);
    x += std::cos(th) * tx - std::sin(th) * ty;
    y += std::sin(th) * tx + std::cos(th) * ty;
    th += a;
  }
  tasks::Sample<msg::PoseEstimate> estimate;
  ASSERT_TRUE(fw.pose_estimate().read(estimate));
  EXPECT_NEAR(x, estimate.value.pose.x_m, 0.05);
  EXPECT_NEAR(y, estimate.value.pose.y_m, 0.05);
  // The mission and the scan.
  ASSERT_TRUE(doc.parse(last["/mission"]));
  EXPECT_TRUE(doc.root().find("state").string_equals(to_string(fw.mission()->report().state))) << last["/mission"];
  EXPECT_NEAR(*doc.root().find("pose").find("x").number(), estimate.value.pose.x_m, 0.05);
  ASSERT_TRUE(doc.parse(last["/scan"]));
  tasks::Sample<msg::ScanMessage> scan;
  ASSERT_TRUE(fw.scan().read(scan));
  EXPECT_EQ(doc.root().find("ranges").size(), scan.value.count);
  ASSERT_TRUE(doc.parse(last["/stats"]));
  EXPECT_EQ(doc.root().find("tasks").size(), fw.scheduler().task_count());
  EXPECT_EQ(*doc.root().find("view").find("clients").uint32(), 1u);
  fw.shutdown();
  std::fclose(sink);
}

TEST(ViewRealTime, AViewerThatStopsReadingCostsNoTaskAPeriod) {
  testing::SimRig rig = testing::load_sim_rig();
  ASSERT_NE(rig.board, nullptr);
  rig.make_board(false);
  FirmwareConfig config = with_view(rig.config);
  config.clock = ClockMode::realtime;
  // Every channel as often as the view row runs: the most a stalled viewer could be sent.
  config.view.task.period_s.fill(0.05);
  std::FILE* sink = std::fopen("/dev/null", "w");
  Firmware fw(config, *rig.board, sink);
  ASSERT_TRUE(rig.board->start());
  ASSERT_TRUE(fw.init());
  const int port = fw.view()->server()->port();
  auto stalled = std::make_unique<WsClient>();
  stalled->small_receive_buffer();
  subscribe_all(*stalled, port);  // and never reads again
  auto reading = std::make_unique<WsClient>();
  subscribe_all(*reading, port);
  std::atomic<bool> stop{false};
  std::atomic<std::uint64_t> frames{0};
  std::thread reader([&] {
    while (!stop.load())
      if (reading->read(100).opcode == 2) ++frames;
  });
  tasks::Scheduler& scheduler = fw.scheduler();
  ASSERT_TRUE(scheduler.start());
  std::this_thread::sleep_for(std::chrono::seconds(2));  // start-up: the drivers connect
  std::vector<tasks::TaskStats> before;
  for (std::size_t i = 0; i < scheduler.task_count(); ++i) before.push_back(scheduler.stats(i));
  const std::uint64_t frames_before = frames.load();
  std::this_thread::sleep_for(std::chrono::seconds(6));
  std::vector<tasks::TaskStats> after;
  for (std::size_t i = 0; i < scheduler.task_count(); ++i) after.push_back(scheduler.stats(i));
  const bool priorities_granted = scheduler.warning_count() == 0;
  const std::uint64_t frames_read = frames.load() - frames_before;
  stop = true;
  reader.join();
  fw.shutdown();
  rig.board->stop();
  std::fclose(sink);
  // With real-time priorities every row keeps its periods whatever the load; without them (a
  // machine that refuses SCHED_FIFO) the other processes' load shows as misses with or without a
  // viewer, so only the view row's own are counted then.
  const bool priorities = priorities_granted;
  for (std::size_t i = 0; i < after.size(); ++i) {
    EXPECT_GT(after[i].runs, before[i].runs) << after[i].name;
    const bool view_row = after[i].name == "view";
    if (!priorities && !view_row) continue;
    EXPECT_EQ(after[i].slips - before[i].slips, 0u) << after[i].name << " started a period late";
    EXPECT_EQ(after[i].skips - before[i].skips, 0u) << after[i].name << " missed a period";
    if (view_row) {
      EXPECT_LT(after[i].exec_max_ns, after[i].period_us * 1000) << "the view row waited";
    }
  }
  if (!priorities) std::printf("no real-time priorities here: only the view row's periods were checked\n");
  // The reading viewer got about every channel's messages meanwhile (20 a second each).
  EXPECT_GT(frames_read, 6u * 20u * 5u);
}

}  // namespace
}  // namespace sen3bot::firmware
