#pragma once
// The robot as a VDA 5050 vehicle in the plant's fleet (docs/fleet.md). On the background
// thread, each cycle: take what the broker delivered (orders, instant actions), decode and
// check it, hand it to the vehicle's order state machine (vda5050::Vehicle), drive the
// navigation to the vehicle's next released node (msg::NavGoal), and publish the state on
// every event and at least every state_period_s, the visualization and the robot's people at
// their rates, and on every new broker session the retained ONLINE connection message and the
// factsheet. The broker's last will says CONNECTIONBROKEN. The centre's formation commands
// (sen3bot/v1/formation/MANUFACTURER/SERIAL) are checked and handed to the controller as
// msg::FormationCommand, stamped with the time they were taken.
//
// The link is the board's publish/subscribe link: MQTT on the robot, the site's in-process
// broker in simulation. Its network side runs on a thread of its own, so nothing here blocks;
// a lost broker leaves the current order running (VDA 5050 section 6.2) while the link
// reconnects with backoff and the state goes out again on the new session.
#include <array>
#include <cstdint>
#include <memory>
#include <memory_resource>
#include <optional>
#include <span>
#include <string>

#include "sen3bot/hal/board.hpp"
#include "sen3bot/msg/messages.hpp"
#include "sen3bot/tasks/task.hpp"
#include "sen3bot/tasks/topic.hpp"
#include "sen3bot/vda5050/codec.hpp"
#include "sen3bot/vda5050/vehicle.hpp"

namespace sen3bot::firmware {

struct FleetConfig {
  std::string broker;  // mqtt://HOST[:PORT], mqtts://HOST[:PORT], or "sim"
  std::string interface_name = "uagv";
  vda5050::Version version = vda5050::Version::v2_1_0;
  std::string manufacturer = "Sen3Bot";
  std::string serial_number;  // also the MQTT client id and, on the site's broker, the user
  std::string map_id = "map";
  std::string username;       // empty: none
  std::string password_file;  // its first line is the password, kept out of the configuration
  std::string ca_file;        // mqtts: the site CA
  std::string cert_file;      // optional client certificate
  std::string key_file;
  int keepalive_s = 15;
  double state_period_s = 1.0;           // VDA 5050 asks for at most 30 s between states
  double visualization_period_s = 0.5;   // 0: not sent
  double people_period_s = 0.2;          // 0: not sent
  double deviation_xy_m = 0.5;           // a node counts as traversed within this, when it sets 0
  double battery_empty_v = 11.0;         // the base's voltage read as 0 % and 100 %
  double battery_full_v = 12.7;
  // A formation command faster than these is refused: the robot's own limits (the firmware
  // sets them from the DWA's and the base driver's).
  double formation_max_v_m_s = 0.5;
  double formation_max_w_rad_s = 1.2;
};

// Errc::config naming the key.
Status check(const FleetConfig& config);

struct FleetTopics {
  const tasks::Topic<msg::PoseEstimate>& pose;
  const tasks::Topic<msg::Odometry>& odometry;
  const tasks::Topic<msg::BaseFlags>& base;
  const tasks::Topic<msg::ControllerStatus>& controller;
  const tasks::Topic<msg::PathMessage>& path;
  const tasks::Topic<msg::SafetyOutput>& safety;
  const tasks::Topic<msg::People>& people;
  tasks::Topic<msg::NavGoal>& goal;
  // Null: the formation topic is not subscribed.
  tasks::Topic<msg::FormationCommand>* formation = nullptr;
};

// What the task has done, for reports and tests; readable after the scheduler stopped.
struct FleetCounters {
  std::uint64_t orders_received = 0;
  std::uint64_t orders_accepted = 0;
  std::uint64_t orders_rejected = 0;      // by the codec or the vehicle
  std::uint64_t instant_actions_received = 0;
  std::uint64_t messages_rejected = 0;    // malformed, wrong version, wrong vehicle, out of order
  std::uint64_t messages_ignored = 0;     // on a topic we do not read
  std::uint64_t states_published = 0;
  std::uint64_t visualizations_published = 0;
  std::uint64_t people_published = 0;
  std::uint64_t publish_failures = 0;     // the link's queue was full or refused
  std::uint64_t sessions = 0;             // broker sessions seen
  std::uint64_t formation_received = 0;
  std::uint64_t formation_rejected = 0;   // malformed, another robot's, out of order, beyond the limits
  std::uint32_t goals_sent = 0;
};

class FleetTask final : public tasks::Task {
 public:
  static constexpr std::size_t kMaxMessagesPerStep = 8;
  static constexpr std::size_t kOutBytes = 64 * 1024;

  FleetTask(const FleetConfig& config, hal::Board& board, const FleetTopics& topics);
  ~FleetTask() override;

  // Opens the link (its last will set, its order and instant-action topics and, with a
  // formation topic on the bus, its formation topic subscribed) and builds the vehicle and the
  // message buffers in the arena.
  Status init(std::pmr::memory_resource& arena) override;
  void step(const tasks::StepContext& context) override;
  // Publishes OFFLINE and closes the link cleanly (no last will).
  void shutdown() override;

  [[nodiscard]] const FleetCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] const vda5050::Vehicle* vehicle() const noexcept { return vehicle_; }
  [[nodiscard]] const hal::PubSub* link() const noexcept { return link_.get(); }
  // The memory init() takes from the arena.
  static std::size_t arena_bytes_needed() noexcept;

 private:
  struct Buffers;

  void on_session(hal::Nanos now);
  void take_messages(const vda5050::Pose& pose, hal::Nanos now);
  void handle(std::string_view topic, std::string_view payload, const vda5050::Pose& pose, hal::Nanos now);
  void handle_formation(std::string_view payload, hal::Nanos now);
  bool check_header(const vda5050::Header& header, std::uint32_t& last_header_id, std::string_view topic_name);
  void drive();
  void publish_state(hal::Nanos now);
  void publish_connection(vda5050::ConnectionState state);
  void publish_factsheet();
  void publish_visualization();
  void publish_people();
  void publish(const std::string& topic, std::string_view payload, int qos, bool retain);
  void stamp(vda5050::Header& header, std::uint32_t& counter);
  [[nodiscard]] vda5050::Pose current_pose() const;
  [[nodiscard]] std::optional<vda5050::AgvPosition> position() const;
  [[nodiscard]] std::optional<vda5050::Velocity> velocity() const;

  FleetConfig config_;
  hal::Board& board_;
  FleetTopics topics_;
  std::unique_ptr<hal::PubSub> link_;
  vda5050::Vehicle* vehicle_ = nullptr;  // in the arena
  Buffers* buffers_ = nullptr;           // in the arena
  std::string topic_order_, topic_instant_, topic_state_, topic_connection_, topic_visualization_,
      topic_factsheet_, topic_people_, topic_formation_;
  std::uint32_t session_ = 0;
  std::uint32_t state_header_ = 0, connection_header_ = 0, visualization_header_ = 0, factsheet_header_ = 0,
      people_header_ = 0;
  std::uint32_t last_order_header_ = 0, last_instant_header_ = 0;
  bool seen_order_header_ = false, seen_instant_header_ = false;
  std::uint32_t last_formation_header_ = 0;
  bool seen_formation_header_ = false;
  hal::Nanos last_state_ns_ = -1;
  hal::Nanos last_visualization_ns_ = -1;
  hal::Nanos last_people_ns_ = -1;
  bool was_driving_ = false;
  std::uint32_t goal_sequence_ = 0;  // the vehicle's target the current goal is for
  bool goal_hold_ = true;
  msg::NavGoal goal_;
  std::uint32_t first_plan_for_goal_ = 0;  // 0: no plan for the current goal yet
  msg::SafetyOutput safety_;
  FleetCounters counters_;
};

}  // namespace sen3bot::firmware
