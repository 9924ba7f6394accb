// The steady-state rule, proved on the real task table running the simulated mission: after
// init() and a warm-up, the tasks run at least 10 000 times in all, the slowest of them at
// least 100 times, and the process allocates nothing. A task added to the table is covered
// automatically, and the test fails if it does not run (the supervisory planner, computing a
// goal's waypoints, among them); the camera's row is the one the
// simulated robot cannot run yet (it has no camera).
#include <gtest/gtest.h>

#include <array>
#include <atomic>
#include <cstdio>
#include <memory>
#include <string>
#include <thread>
#include <vector>

#include "alloc_counter.hpp"
#include "ws_client.hpp"
#include "config.hpp"
#include "firmware.hpp"
#include "sen3bot/vda5050/codec.hpp"
#include "sen3bot/vda5050/extensions.hpp"
#include "sim_rig.hpp"
#include "task_table.hpp"

namespace sen3bot::firmware {
namespace {

constexpr std::uint64_t kSteadyStateTicks = 10'000;  // task runs in all
constexpr std::uint64_t kSlowestTaskRuns = 100;

TEST(ZeroAllocation, EveryTaskOfTheTableRunsTenThousandTicksWithoutAllocating) {
  testing::SimRig rig = testing::load_sim_rig();
  ASSERT_NE(rig.board, nullptr);
  FirmwareConfig* config = &rig.config;
  config->telemetry_status_period_ms = 1'000;  // exercise the status path often
  // The moving-obstacle layer and the DWA's time-aware check too (config/sim.yaml leaves them
  // off): the worker walking across is detected, tracked and painted meanwhile.
  config->navigation.dynamic_obstacles.enabled = true;
  config->navigation.dwa.mover_prediction = true;
  // The crossing gate with its lanes, and making way (both off by default): the proof covers
  // every step the controller can take.
  config->navigation.crossings.enabled = true;
  config->navigation.make_way.enabled = true;
  // The supervisory planner computes each goal's waypoints (config/sim.yaml gives a file).
  config->navigation.waypoints_path.clear();
  config->navigation.safe_curve_path = SEN3BOT_SOURCE_DIR "/config/maps/lab_curve.yaml";
  // People: the simulated detector's frames through the gate, the fusion and the cages.
  rig.world.detector.enabled = true;
  // The safety I/O's faults in the window: an e-stop, a silent node and a node that reboots,
  // each followed by a reset.
  using What = sim::SimIoEvent::What;
  rig.world.io_node.events = {
      {15.0, What::inputs, 0x00}, {16.0, What::inputs, 0x01}, {17.0, What::inputs, 0x03}, {17.2, What::inputs, 0x01},
      {25.0, What::silent, 0},    {26.0, What::talking, 0},   {28.0, What::inputs, 0x03}, {28.2, What::inputs, 0x01},
      {35.0, What::reboot, 0},    {37.0, What::inputs, 0x03}, {37.2, What::inputs, 0x01}};
  rig.make_board();
  config->navigation.people_enabled = true;
  config->navigation.people_detector = "sim";
  config->tasks["detector"].arena_bytes = 4 * 1024;
  config->tasks["people"].arena_bytes = 64 * 1024;
  // The live view with its own server in its arena, and a viewer subscribed to every channel
  // that reads all the while: encoding, the hand-off and the sending allocate nothing either.
  config->view.enabled = true;
  config->view.task.server.port = 0;
  config->tasks["view"].arena_bytes = 4 * 1024 * 1024;
  hal::SimClock& clock = rig.clock();

  std::FILE* sink = std::fopen("/dev/null", "w");
  ASSERT_NE(sink, nullptr);
  Firmware fw(*config, *rig.board, sink);
  ASSERT_TRUE(fw.init());
  tasks::Scheduler& scheduler = fw.scheduler();
  ASSERT_NE(fw.view(), nullptr);
  view::Server& server = *fw.view()->server();
  auto viewer = std::make_unique<testing::WsClient>();
  ASSERT_NE(viewer->connect("127.0.0.1", server.port()).find(" 101 "), std::string::npos);
  ASSERT_NE(viewer->read().payload.find("serverInfo"), std::string_view::npos);
  ASSERT_NE(viewer->read().payload.find("advertise"), std::string_view::npos);
  std::string subscribe = R"({"op":"subscribe","subscriptions":[)";
  for (std::size_t i = 0; i < server.board().channel_count(); ++i)
    subscribe += (i ? "," : "") + std::string(R"({"id":)") + std::to_string(i) + R"(,"channelId":)" + std::to_string(i) + "}";
  viewer->send_text(subscribe + "]}");
  std::atomic<bool> stop_viewer{false};
  std::atomic<std::uint64_t> viewer_frames{0};
  std::thread viewing([&] {
    while (!stop_viewer.load())
      if (viewer->read(100).opcode == 2) ++viewer_frames;
  });
  // Every row but the camera's and the on-board detector's (the simulated robot has no camera
  // yet, and OpenCV's search, on its own thread, allocates; docs/people.md) and the fleet's,
  // which takes the mission's place when the robot has one (counted in the test below), and the
  // collaborative mode's three (counted in their own test), and map building's (whose graph
  // solves allocate inside Eigen; its steps are counted in tests/sim/online_mapping_test.cpp).
  ASSERT_EQ(scheduler.task_count(), kTaskTable.size() - 7);

  // Warm-up: first-use work (stdio buffers, lazily sized state) happens here.
  ASSERT_TRUE(scheduler.run_lockstep(clock, hal::seconds(5)));
  ASSERT_NE(fw.planner(), nullptr);
  const std::uint32_t sgp_runs_before = fw.planner()->sgp_runs();
  std::vector<std::uint64_t> runs_before;
  for (std::size_t i = 0; i < scheduler.task_count(); ++i) runs_before.push_back(scheduler.stats(i).runs);

  // Long enough for the slowest task of the table to run kSlowestTaskRuns times; the mission
  // drives through the whole window (its goals take longer).
  std::int64_t longest_period_us = 0;
  for (const auto& row : kTaskTable) longest_period_us = std::max(longest_period_us, row.period_us);
  const hal::Nanos window = hal::micros(longest_period_us) * static_cast<hal::Nanos>(kSlowestTaskRuns);

  const std::uint64_t sent_before = server.counters().sent;
  mem::testing::AllocationScope scope;
  const Status ran = scheduler.run_lockstep(clock, window);
  const std::uint64_t allocations = scope.allocations();
  const std::uint64_t malloc_calls = scope.malloc_calls();
  stop_viewer = true;
  viewing.join();
  ASSERT_TRUE(ran);

  EXPECT_EQ(allocations, 0u) << "operator new called in steady state";
  EXPECT_EQ(malloc_calls, 0u) << "malloc called in steady state";
  EXPECT_GT(server.counters().sent, sent_before) << "the viewer was sent nothing in the window";
  EXPECT_GT(viewer_frames.load(), 0u);
  std::uint64_t total_runs = 0;
  for (std::size_t i = 0; i < scheduler.task_count(); ++i) {
    const tasks::TaskStats s = scheduler.stats(i);
    EXPECT_GE(s.runs - runs_before[i], kSlowestTaskRuns) << s.name;
    total_runs += s.runs - runs_before[i];
  }
  EXPECT_GE(total_runs, kSteadyStateTicks);
  // The window covered real driving, not an idle robot.
  const MissionTask* mission = fw.mission();
  ASSERT_NE(mission, nullptr);
  EXPECT_GE(mission->report().goals_reached, 1u);
  // A goal came inside the window, and the supervisory planner ran for it.
  EXPECT_GT(fw.planner()->sgp_runs(), sgp_runs_before);
  EXPECT_TRUE(fw.planner()->sgp_result().on_curve);
  // The worker was seen, placed and caged meanwhile.
  ASSERT_NE(fw.people_task(), nullptr);
  EXPECT_GT(fw.people_task()->frames_fused(), 0u);
  EXPECT_GT(fw.people_task()->fusion().count(nav::BoxVerdict::located), 0u);
  // The e-stop chain held the robot three times, and the node was set up again after its reboot.
  ASSERT_NE(fw.safety(), nullptr);
  EXPECT_EQ(fw.safety()->latch()->trips(), 3u);
  EXPECT_FALSE(fw.safety()->latch()->held());
  EXPECT_EQ(fw.can_io()->master().count(canopen::IoNodeEvent::boot_up), 2u);
  EXPECT_EQ(fw.can_io()->master().count(canopen::IoNodeEvent::heartbeat_lost), 1u);
  fw.shutdown();
  std::fclose(sink);
}

// The robot's VDA 5050 messages as a master control writes them (tests/sim/fleet_test.cpp).
std::string fleet_header(int header_id) {
  return "\"headerId\":" + std::to_string(header_id) +
         ",\"timestamp\":\"2026-12-03T10:00:00.00Z\",\"version\":\"2.1.0\",\"manufacturer\":\"Sen3Bot\",\"serialNumber\":\"r1\"";
}

// From the robot's start in the lab, (2.5, 2.0), north to (2.9, 4.25), joined by edges e<i>.
std::string fleet_order(int header_id, const char* order_id) {
  struct Node {
    const char* id;
    double x, y;
  };
  const Node nodes[] = {{"n0", 2.5, 2.0}, {"n1", 2.85, 3.5}, {"n2", 2.9, 4.25}};
  std::string text = "{" + fleet_header(header_id) + ",\"orderId\":\"" + order_id + "\",\"orderUpdateId\":0,\"nodes\":[";
  char buffer[256];
  for (int i = 0; i < 3; ++i) {
    std::snprintf(buffer, sizeof buffer,
                  "%s{\"nodeId\":\"%s\",\"sequenceId\":%d,\"released\":true,\"nodePosition\":{\"x\":%.3f,\"y\":%.3f,"
                  "\"mapId\":\"lab\",\"allowedDeviationXY\":0.3},\"actions\":[]}",
                  i ? "," : "", nodes[i].id, 2 * i, nodes[i].x, nodes[i].y);
    text += buffer;
  }
  text += "],\"edges\":[";
  for (int i = 0; i < 2; ++i) {
    std::snprintf(buffer, sizeof buffer,
                  "%s{\"edgeId\":\"e%d\",\"sequenceId\":%d,\"released\":true,\"startNodeId\":\"%s\",\"endNodeId\":\"%s\","
                  "\"actions\":[]}",
                  i ? "," : "", i, 2 * i + 1, nodes[i].id, nodes[i + 1].id);
    text += buffer;
  }
  return text + "]}";
}

std::string fleet_instant(int header_id, const char* action_id, const char* type) {
  return "{" + fleet_header(header_id) + ",\"actions\":[{\"actionId\":\"" + action_id + "\",\"actionType\":\"" + type +
         "\",\"blockingType\":\"HARD\"}]}";
}

// A formation command as the centre's codec writes it.
std::string fleet_formation(std::uint32_t header_id, const char* serial, double v, double w) {
  vda5050::FormationCommand m;
  m.header_id = header_id;
  (void)m.timestamp.assign("2026-12-03T10:00:00.00Z");
  (void)m.manufacturer.assign("Sen3Bot");
  (void)m.serial_number.assign(serial);
  m.v = v;
  m.omega = w;
  m.hold_s = 0.5;
  std::array<char, 512> out{};
  auto text = vda5050::encode_formation(m, out);
  EXPECT_TRUE(text.ok());
  return text.ok() ? std::string(*text) : std::string();
}

// A master control on the site's broker. Everything it uses in the counted window (topics,
// message texts, receive buffers, the state it decodes into) is made beforehand.
class Master {
 public:
  explicit Master(sim::SimBoard& board) {
    hal::PubSubOptions options;
    options.client_id = "master";
    options.subscriptions = {{kPrefix + std::string("#"), 1}, {"sen3bot/v1/people/Sen3Bot/r1", 0}};
    options.inbound_slots = 512;
    options.max_payload = kPayload;
    auto client = board.site_broker().connect(options);
    EXPECT_TRUE(client.ok());
    if (client.ok()) client_ = std::move(client.value());
  }
  [[nodiscard]] bool connected() const { return client_ != nullptr; }
  void send(const std::string& topic, const std::string& json) {
    const Status sent = client_->publish(topic, {reinterpret_cast<const std::uint8_t*>(json.data()), json.size()}, 0, false);
    if (!sent) ++send_failures;
  }
  // Reads what the robot published; the newest state is decoded.
  void drain() {
    for (;;) {
      auto message = client_->receive(topic_, payload_);
      if (!message.ok()) {
        ++bad;
        return;
      }
      if (!message.value()) return;
      const std::string_view topic(topic_.data(), message.value()->topic_size);
      const std::string_view text(reinterpret_cast<const char*>(payload_.data()), message.value()->payload_size);
      ++messages;
      if (!topic.ends_with("/state")) continue;
      ++states;
      if (vda5050::decode_state(text, vda5050::Version::v2_1_0, *state_, *scratch_).ok()) {
        have_state = true;
      } else {
        ++bad;
      }
    }
  }
  [[nodiscard]] const vda5050::State& state() const { return *state_; }
  [[nodiscard]] bool action_finished(std::string_view action_id) const {
    if (!have_state) return false;
    for (const vda5050::ActionState& a : state_->action_states)
      if (a.action_id == action_id) return a.status == vda5050::ActionStatus::finished;
    return false;
  }

  static constexpr const char* kPrefix = "uagv/v2/Sen3Bot/r1/";
  static constexpr std::size_t kPayload = 32 * 1024;
  const std::string order_topic = kPrefix + std::string("order");
  const std::string instant_topic = kPrefix + std::string("instantActions");
  std::uint64_t messages = 0, states = 0, bad = 0, send_failures = 0;
  bool have_state = false;

 private:
  std::unique_ptr<hal::PubSub> client_;
  std::vector<char> topic_ = std::vector<char>(256);
  std::vector<std::uint8_t> payload_ = std::vector<std::uint8_t>(kPayload);
  std::unique_ptr<vda5050::DecodeScratch> scratch_ = std::make_unique<vda5050::DecodeScratch>();
  std::unique_ptr<vda5050::State> state_ = std::make_unique<vda5050::State>();
};

TEST(ZeroAllocation, TheFirmwareWithTheFleetTaskTakesAnOrderInstantActionsAndFormationCommandsWithoutAllocating) {
  testing::SimRig rig = testing::load_sim_rig();
  ASSERT_NE(rig.board, nullptr);
  FirmwareConfig* config = &rig.config;
  config->telemetry_status_period_ms = 1'000;
  config->navigation.dynamic_obstacles.enabled = true;
  config->navigation.dwa.mover_prediction = true;
  // People: the fleet task sends them on its Sen3Bot topic.
  rig.world.detector.enabled = true;
  rig.make_board();
  config->navigation.people_enabled = true;
  config->navigation.people_detector = "sim";
  config->tasks["detector"].arena_bytes = 4 * 1024;
  config->tasks["people"].arena_bytes = 64 * 1024;
  // The fleet gives the goals instead of the mission (tests/sim/fleet_test.cpp).
  config->navigation.mission.goal_count = 0;
  config->tasks.erase("mission");
  config->tasks["fleet"] = TaskConfig{FleetTask::arena_bytes_needed() + 64 * 1024};
  config->has_fleet = true;
  config->fleet.broker = "sim";
  config->fleet.serial_number = "r1";
  config->fleet.map_id = "lab";
  hal::SimClock& clock = rig.clock();

  std::FILE* sink = std::fopen("/dev/null", "w");
  ASSERT_NE(sink, nullptr);
  Firmware fw(*config, *rig.board, sink);
  Master master(*rig.board);
  ASSERT_TRUE(master.connected());
  ASSERT_TRUE(fw.init());
  tasks::Scheduler& scheduler = fw.scheduler();
  // Every row but the camera's, the on-board detector's, the mission's and the collaborative
  // mode's three.
  ASSERT_EQ(scheduler.task_count(), kTaskTable.size() - 8);  // and no view
  ASSERT_NE(fw.fleet(), nullptr);

  // What master control sends in the window, written now.
  const std::string malformed = "{\"headerId\": 1, this is not JSON";
  const std::string order_text = fleet_order(2, "o1");
  const std::string pause = fleet_instant(1, "pause-1", "startPause");
  const std::string resume = fleet_instant(2, "pause-2", "stopPause");
  const std::string cancel = fleet_instant(3, "cancel-1", "cancelOrder");
  // Then the centre's formation controller drives the robot for 2 s at 10 Hz; one of its
  // commands is for another robot.
  const std::string formation_topic = vda5050::formation_topic("Sen3Bot", "r1");
  std::vector<std::string> formation_texts;
  for (std::uint32_t i = 1; i <= 20; ++i) formation_texts.push_back(fleet_formation(i, i == 10 ? "r2" : "r1", 0.1, 0.2));

  // Warm-up: the robot comes online (connection, factsheet, states) and master control reads it.
  const hal::Nanos chunk = hal::millis(10);
  for (hal::Nanos t = 0; t < hal::seconds(5); t += chunk) {
    ASSERT_TRUE(scheduler.run_lockstep(clock, chunk));
    master.drain();
  }
  ASSERT_TRUE(master.have_state);
  std::vector<std::uint64_t> runs_before;
  for (std::size_t i = 0; i < scheduler.task_count(); ++i) runs_before.push_back(scheduler.stats(i).runs);
  const FleetCounters before = fw.fleet()->counters();

  // As long as the test above; the order, the pause and the cancel come early in it.
  std::int64_t longest_period_us = 0;
  for (const auto& row : kTaskTable) longest_period_us = std::max(longest_period_us, row.period_us);
  const hal::Nanos window = hal::micros(longest_period_us) * static_cast<hal::Nanos>(kSlowestTaskRuns);

  enum class Step { order, driving, paused, resumed, past_n1, cancelled, formation, done };
  Step step = Step::order;
  bool was_paused_standing = false;
  hal::Nanos paused_at = 0;
  std::size_t formation_sent = 0;
  hal::Nanos formation_at = 0;
  bool formation_drove = false;
  bool ran = true;

  mem::testing::AllocationScope scope;
  for (hal::Nanos t = 0; t < window && ran; t += chunk) {
    ran = scheduler.run_lockstep(clock, chunk).ok();
    master.drain();
    const vda5050::State& s = master.state();
    switch (step) {
      case Step::order:
        master.send(master.order_topic, malformed);  // refused, reported; nothing else changes
        master.send(master.order_topic, order_text);
        step = Step::driving;
        break;
      case Step::driving:
        if (s.order_id == "o1" && s.driving) {
          master.send(master.instant_topic, pause);
          step = Step::paused;
        }
        break;
      case Step::paused:
        if (s.paused && !s.driving && !was_paused_standing) {
          was_paused_standing = true;
          paused_at = t;
        }
        if (was_paused_standing && t - paused_at >= hal::seconds(2)) {
          master.send(master.instant_topic, resume);
          step = Step::resumed;
        }
        break;
      case Step::resumed:
        if (!s.paused && s.driving) step = Step::past_n1;
        break;
      case Step::past_n1:
        if (s.last_node_id == "n1") {
          master.send(master.instant_topic, cancel);
          step = Step::cancelled;
        }
        break;
      case Step::cancelled:
        if (master.action_finished("cancel-1")) step = Step::formation;
        break;
      case Step::formation: {
        if (formation_sent < formation_texts.size() && t - formation_at >= hal::millis(100)) {
          master.send(formation_topic, formation_texts[formation_sent++]);
          formation_at = t;
        }
        tasks::Sample<msg::ControllerStatus> status;
        if (fw.controller_status().read(status) && status.value.formation) formation_drove = true;
        if (formation_sent == formation_texts.size() && t - formation_at >= hal::seconds(1)) step = Step::done;
        break;
      }
      case Step::done:
        break;
    }
  }
  const std::uint64_t allocations = scope.allocations();
  const std::uint64_t malloc_calls = scope.malloc_calls();
  ASSERT_TRUE(ran);

  EXPECT_EQ(allocations, 0u) << "operator new called in steady state";
  EXPECT_EQ(malloc_calls, 0u) << "malloc called in steady state";
  std::uint64_t total_runs = 0;
  for (std::size_t i = 0; i < scheduler.task_count(); ++i) {
    const tasks::TaskStats s = scheduler.stats(i);
    EXPECT_GE(s.runs - runs_before[i], kSlowestTaskRuns) << s.name;
    total_runs += s.runs - runs_before[i];
  }
  EXPECT_GE(total_runs, kSteadyStateTicks);
  // The whole exchange happened inside the window: order, pause, resume, cancel, formation.
  EXPECT_EQ(step, Step::done);
  EXPECT_TRUE(formation_drove);
  EXPECT_TRUE(was_paused_standing);
  const FleetCounters& after = fw.fleet()->counters();
  EXPECT_EQ(after.orders_received - before.orders_received, 2u);
  EXPECT_EQ(after.orders_accepted - before.orders_accepted, 1u);
  EXPECT_EQ(after.orders_rejected - before.orders_rejected, 1u);
  EXPECT_EQ(after.instant_actions_received - before.instant_actions_received, 3u);
  EXPECT_EQ(after.formation_received - before.formation_received, 20u);
  EXPECT_EQ(after.formation_rejected - before.formation_rejected, 1u);
  EXPECT_GT(after.goals_sent, before.goals_sent);
  // A state at least every second, and on the events.
  EXPECT_GE(after.states_published - before.states_published,
            static_cast<std::uint64_t>(window / hal::seconds(1)));
  EXPECT_GT(after.visualizations_published, before.visualizations_published);
  EXPECT_GT(after.people_published, before.people_published);
  EXPECT_EQ(after.publish_failures, 0u);
  EXPECT_GE(master.states, after.states_published - before.states_published);
  EXPECT_EQ(master.bad, 0u);
  EXPECT_EQ(master.send_failures, 0u);
  EXPECT_TRUE(master.state().node_states.empty());
  fw.shutdown();
  std::fclose(sink);
}

// The collaborative mode's control row: a waiting robot, an operator's request (the tags a QR
// row would read, published here: the reader itself is OpenCV's, on its own thread), follow-me
// goals to the planner and the worker's path recorded, all inside the counted window.
TEST(ZeroAllocation, TheCollaborativeModeTakesARequestFollowsAndRecordsWithoutAllocating) {
  testing::SimRig rig = testing::load_sim_rig();
  ASSERT_NE(rig.board, nullptr);
  FirmwareConfig* config = &rig.config;
  config->telemetry_status_period_ms = 1'000;  // the status lines' first-use buffers in the warm-up
  // An operator standing 0.9 m in front of the waiting robot (start (2.5, 2.0) facing north),
  // who sets off at t = 16 s along the work area and turns east.
  world::MoverScript op;
  op.timeline = {{2.5, 3.05}, {2.5, 3.05}, {2.5, 3.9}, {4.0, 3.9}};
  op.times_s = {0.0, 16.0, 18.5, 22.5};
  op.path = {op.timeline.front()};
  op.size_m = 0.45;
  op.person = true;
  rig.world.movers = {op};
  rig.world.detector.enabled = true;
  rig.make_board();
  config->navigation.people_enabled = true;
  config->navigation.people_detector = "sim";
  config->navigation.dynamic_obstacles.enabled = true;
  config->tasks["detector"].arena_bytes = 4 * 1024;
  config->tasks["people"].arena_bytes = 64 * 1024;
  config->navigation.mission.goal_count = 1;  // its post: where it starts
  config->navigation.mission.goals[0] = {2.5, 2.0};
  config->cobot.enabled = true;
  config->cobot.site_path = SEN3BOT_SOURCE_DIR "/config/cobot/lab_site.yaml";
  ASSERT_TRUE(config->cobot.task.trigger.operators.push_back(42));
  config->tasks["cobot"].arena_bytes = 64 * 1024;
  hal::SimClock& clock = rig.clock();

  std::FILE* sink = std::fopen("/dev/null", "w");
  ASSERT_NE(sink, nullptr);
  Firmware fw(*config, *rig.board, sink);
  ASSERT_TRUE(fw.init());
  tasks::Scheduler& scheduler = fw.scheduler();
  ASSERT_NE(fw.cobot(), nullptr);
  ASSERT_TRUE(scheduler.run_lockstep(clock, hal::seconds(5)));  // warm-up: waiting, the operator tracked

  // The tags as the QR row publishes them, 5 frames a second: the front 8.0-10.4 s, the back
  // 11.0-13.4 s. The frames are written before the window.
  struct Shown {
    double from_s, to_s;
    msg::TagSide side;
  };
  const std::array<Shown, 2> shown = {{{8.0, 10.4, msg::TagSide::front}, {11.0, 13.4, msg::TagSide::back}}};
  msg::TagFrame frame;
  mem::testing::AllocationScope scope;
  bool ran = true;
  for (int k = 0; k < 5 * 20 && ran; ++k) {  // 5 s .. 25 s
    ran = static_cast<bool>(scheduler.run_lockstep(clock, hal::millis(200)));
    const double t_s = hal::to_seconds(clock.now() - scheduler.start_time_ns());
    frame.count = 0;
    for (const Shown& sh : shown)
      if (t_s >= sh.from_s && t_s <= sh.to_s) {
        frame.tags[0] = msg::TagSighting{42, sh.side, 727.0f, 300.0f, 120.0f};
        frame.count = 1;
      }
    ++frame.frame_sequence;
    frame.capture_ns = clock.now();
    fw.tags_topic().publish(frame, clock.now());
  }
  const std::uint64_t allocations = scope.allocations();
  const std::uint64_t malloc_calls = scope.malloc_calls();
  ASSERT_TRUE(ran);
  EXPECT_EQ(allocations, 0u) << "operator new called in steady state";
  EXPECT_EQ(malloc_calls, 0u) << "malloc called in steady state";
  // The window covered the request, following and recording, not an idle robot.
  const CobotTask& cobot = *fw.cobot();
  EXPECT_EQ(cobot.counters().toggles_on, 1u);
  EXPECT_EQ(cobot.trigger().rejections_total(), 0u);
  EXPECT_GT(cobot.counters().follow_goals, 0u);
  EXPECT_GT(cobot.recorder().size(), 10u);
  tasks::Sample<msg::CobotState> state;
  ASSERT_TRUE(fw.cobot_state().read(state));
  EXPECT_EQ(state.value.mode, msg::CobotMode::collaborative);
  fw.shutdown();
  std::fclose(sink);
}

TEST(ZeroAllocation, TheCounterSeesAllocations) {
  // Guards the guard: if the replacement functions were not linked in, the test above would
  // pass vacuously.
  mem::testing::AllocationScope scope;
  auto* p = new int(7);
  std::vector<int> v(100);
  void* raw = std::malloc(64);
  asm volatile("" : : "g"(p), "g"(v.data()), "g"(raw) : "memory");  // keep all three
  const std::uint64_t allocations = scope.allocations();
  const std::uint64_t malloc_calls = scope.malloc_calls();
  delete p;
  std::free(raw);
  EXPECT_EQ(allocations, 2u);
  if (mem::testing::counts_malloc()) {
    EXPECT_EQ(malloc_calls, 3u);
  }
}

}  // namespace
}  // namespace sen3bot::firmware
