#pragma once
// The Sensors Synergy Centre as a program on the site's broker: the I/O shell around
// ssc::Centre. It reads every vehicle's VDA 5050 state and connection (uagv/v2/+/+/...: the
// site's robots by serial number, every other vehicle is a plant AGV whose remaining route is
// its state's nodeStates) and the robots' people reports; feeds the centre; and carries out its
// decisions: VDA 5050 orders and cancelOrder to the robots, the advisory for each AGV on
// sen3bot/v1/advisory/MANUFACTURER/SERIAL (docs/fleet/advisory.schema.json; retained, QoS 1)
// for the plant's AGV coordination centre, and, where the site allows it, startPause /
// stopPause straight to the AGV. Every decision goes to the event log (JSON lines) with its
// reason.
//
// Nothing here keeps state the broker cannot give back: a restarted centre rebuilds the
// robots and AGVs from the retained connection messages and their next states, and decides
// afresh from there.
#include <cstdio>
#include <map>
#include <memory>
#include <string>
#include <vector>

#include "sen3bot/hal/pubsub.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/ssc/centre.hpp"
#include "sen3bot/ssc/site_file.hpp"
#include "sen3bot/vda5050/codec.hpp"
#include "sen3bot/vda5050/extensions.hpp"

namespace sen3bot::ssc {

struct ServiceCounters {
  std::uint64_t states = 0;
  std::uint64_t people_reports = 0;
  std::uint64_t rejected = 0;       // messages that did not decode (logged once per sender)
  std::uint64_t orders_sent = 0;
  std::uint64_t cancels_sent = 0;
  std::uint64_t advisories_sent = 0;
  std::uint64_t pauses_sent = 0;
  std::uint64_t unknown_agvs = 0;   // AGVs beyond the centre's capacity
};

class Service {
 public:
  // event_log: where the JSON lines go (may be null).
  static Result<std::unique_ptr<Service>> create(const SiteFile& site, std::unique_ptr<hal::PubSub> link, std::FILE* event_log);
  static std::vector<hal::PubSubSubscription> subscriptions(const ServiceConfig& config);
  ~Service();

  // Takes every message waiting, steps the centre at `now`, publishes its decisions.
  void step(hal::Nanos now, std::int64_t unix_ns);
  // Sends what is queued (up to timeout_s) and disconnects cleanly.
  void close(double timeout_s) noexcept { link_->close(timeout_s); }

  [[nodiscard]] const Centre& centre() const noexcept { return *centre_; }
  [[nodiscard]] const ServiceCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] const hal::PubSub& link() const noexcept { return *link_; }
  // The latency from a people report's timestamp to each advisory it caused (s): the newest
  // report before the advisory. For the load benchmark; bounded to the newest 100000.
  [[nodiscard]] const std::vector<double>& advisory_latencies() const noexcept { return latencies_; }
  [[nodiscard]] const std::vector<std::string>& event_lines() const noexcept { return events_; }

 private:
  struct Buffers;
  struct AgvEntry {
    std::string manufacturer;
    std::string serial;
    AgvId id = kNone;
    Advice last_advice = Advice::clear;
    hal::Nanos last_sent = -1;
    bool paused_by_us = false;
    std::uint32_t instant_header = 0;
  };
  Service(const SiteFile& site, std::unique_ptr<hal::PubSub> link, std::FILE* event_log);

  void take_messages(hal::Nanos now);
  void on_state(std::string_view manufacturer, std::string_view serial, std::string_view text, hal::Nanos now);
  void on_connection(std::string_view manufacturer, std::string_view serial, std::string_view text, hal::Nanos now);
  void on_people(std::string_view text, hal::Nanos now);
  void carry_out(const Decisions& decisions, std::int64_t unix_ns);
  void send_order(RobotId robot, const Task& task, std::int64_t unix_ns);
  void send_cancel(RobotId robot, std::int64_t unix_ns);
  void send_advisory(AgvEntry& agv, const Advisory& advisory, std::int64_t unix_ns, hal::Nanos now);
  void send_pause(AgvEntry& agv, bool pause, std::int64_t unix_ns);
  void log(const Event& event, std::int64_t unix_ns);
  void publish(const std::string& topic, std::string_view payload, int qos, bool retain);
  [[nodiscard]] RobotId robot_id(std::string_view serial) const noexcept;
  AgvEntry* agv_entry(std::string_view manufacturer, std::string_view serial, bool create);

  SiteFile site_;
  std::unique_ptr<hal::PubSub> link_;
  std::FILE* event_log_;
  std::unique_ptr<Centre> centre_;
  std::unique_ptr<Buffers> buffers_;
  std::vector<AgvEntry> agvs_;
  std::vector<std::uint32_t> order_headers_;    // per robot
  std::vector<std::uint32_t> instant_headers_;  // per robot
  std::vector<std::uint32_t> order_counts_;     // per robot: orders sent, for unique order ids
  std::vector<std::int64_t> robot_people_stamp_;  // per robot: unix ns of its newest people report
  std::vector<Pose> robot_poses_;                 // per robot: from its newest state
  std::int64_t newest_people_unix_ns_ = 0;
  std::uint32_t advisory_header_ = 0;
  ServiceCounters counters_;
  std::vector<double> latencies_;
  std::vector<std::string> events_;
};

}  // namespace sen3bot::ssc
