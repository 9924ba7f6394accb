#pragma once
// A plant AGV that speaks VDA 5050, for the fleet's simulations and tests: it takes orders
// (the vehicle's order state machine, vda5050::Vehicle, decides what it accepts), drives
// straight from node to node at its speed, reports its state, honours startPause/stopPause,
// and honours the people advisory the AGV coordination centre would pass on to it (CLEAR,
// SLOW with a speed factor, STOP; docs/fleet.md). It has no sensors of its own beyond a short
// range (sensor_range_m) within which it stops for a person by itself, as an AGV's own safety
// scanner would.
//
// Pure simulation: step() is called with the time; the link is a hal::PubSub (the site's
// in-process broker in lockstep, a real broker in real time).
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/pubsub.hpp"
#include "sen3bot/msg/geometry.hpp"
#include "sen3bot/vda5050/codec.hpp"
#include "sen3bot/vda5050/extensions.hpp"
#include "sen3bot/vda5050/vehicle.hpp"

namespace sen3bot::sim {

using Advice = vda5050::AdviceKind;

struct SimAgvConfig {
  std::string interface_name = "uagv";
  vda5050::Version version = vda5050::Version::v2_1_0;
  std::string manufacturer = "PlantAGV";
  std::string serial_number = "agv1";
  std::string map_id = "map";
  double x = 0, y = 0, theta = 0;  // start pose, map frame
  double speed_m_s = 1.0;          // cruise
  double accel_m_s2 = 0.5;         // and deceleration
  double state_period_s = 1.0;
  double sensor_range_m = 2.0;     // its own scanner stops it for a person this close ahead
  bool obey_advisory = true;
};

class SimAgv {
 public:
  // Subscribes the link to the AGV's order, instantActions and advisory topics: open the link
  // with subscriptions(config).
  SimAgv(const SimAgvConfig& config, std::unique_ptr<hal::PubSub> link);
  ~SimAgv();
  static std::vector<hal::PubSubSubscription> subscriptions(const SimAgvConfig& config);

  // Takes messages, moves for dt_s, publishes. unix_ns stamps the messages. people: the true
  // positions of the people around (for its own short-range scanner).
  void step(hal::Nanos now_ns, std::int64_t unix_ns, double dt_s, std::span<const msg::Point2D> people = {});

  [[nodiscard]] double x() const noexcept { return x_; }
  [[nodiscard]] double y() const noexcept { return y_; }
  [[nodiscard]] double theta() const noexcept { return theta_; }
  [[nodiscard]] double speed() const noexcept { return speed_; }
  [[nodiscard]] Advice advice() const noexcept { return advice_; }
  [[nodiscard]] double advised_factor() const noexcept { return factor_; }
  [[nodiscard]] bool stopped_by_own_sensor() const noexcept { return own_stop_; }
  [[nodiscard]] const vda5050::Vehicle& vehicle() const noexcept { return *vehicle_; }
  [[nodiscard]] std::uint64_t advisories() const noexcept { return advisories_; }
  [[nodiscard]] const SimAgvConfig& config() const noexcept { return config_; }

 private:
  struct Buffers;
  void take_messages();
  void publish_state(std::int64_t unix_ns);

  SimAgvConfig config_;
  std::unique_ptr<hal::PubSub> link_;
  std::unique_ptr<Buffers> buffers_;
  std::unique_ptr<vda5050::Vehicle> vehicle_;
  std::string topic_order_, topic_instant_, topic_state_, topic_connection_, topic_advisory_;
  double x_, y_, theta_;
  double speed_ = 0;
  Advice advice_ = Advice::clear;
  double factor_ = 1.0;
  bool own_stop_ = false;
  std::uint32_t state_header_ = 0;
  std::uint32_t connection_header_ = 0;
  std::uint32_t session_ = 0;
  hal::Nanos last_state_ns_ = -1;
  bool was_driving_ = false;
  std::uint64_t advisories_ = 0;
};

}  // namespace sen3bot::sim
