#pragma once
// The centre's formation service on the site's broker: the I/O shell around
// formation::Controller. It reads each team robot's VDA 5050 visualization
// (uagv/v2/MANUFACTURER/SERIAL/visualization: agvPosition and velocity, every 0.1 s or so),
// steps the controller every period on the newest poses and sends each robot its (v, omega) as
// a Sen3Bot formation command (sen3bot/v1/formation/MANUFACTURER/SERIAL) with a hold time: the
// robot drives it at most that long after it arrives, then stops, so a centre that falls silent
// leaves the team standing.
//
// The controller is centralised: it steers only on a whole picture. When any robot's pose is
// missing or older than the pose timeout, every robot is told to stop until all are fresh
// again (and the controller restarts from there). Each pose is predicted forward from its
// timestamp to the step by the velocity the robot reported with it, to make up for the
// link's latency, and on by the command's own latency (lookahead_s) with the last commands.
//
// Fixed memory: every buffer is sized in create(); step() allocates nothing.
#include <array>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <vector>

#include "sen3bot/formation/controller.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/pubsub.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/vda5050/types.hpp"

namespace sen3bot::formation {

// One robot of the team; robot i here is the controller's robot i.
struct TeamMember {
  std::string manufacturer = "Sen3Bot";
  std::string serial_number;
};

struct FormationServiceConfig {
  std::string interface_name = "uagv";
  vda5050::Version version = vda5050::Version::v2_1_0;
  std::vector<TeamMember> team;   // config.controller.robots of them
  ControllerConfig controller;
  double period_s = 0.1;          // a controller step and a command per robot this often
  double pose_timeout_s = 0.5;    // an older pose (by its message's timestamp) is stale
  double hold_s = 0.5;            // the commands' hold (0 < hold <= 2 s)
  // The link's latency from a command leaving to the robot acting on it (the robot's fleet and
  // controller rows, 0.1 s each, half a period each on average, and the base's cycle): the
  // poses are predicted this far ahead with the last commands, so the barriers act in time.
  double lookahead_s = 0.15;
  std::size_t max_payload = 64 * 1024;  // the link's max_payload: a receive needs room for its largest message
};

struct FormationCounters {
  std::uint64_t poses = 0;          // visualization messages taken with a position
  std::uint64_t rejected = 0;       // did not decode, or a header naming another robot than the topic
  std::uint64_t unpositioned = 0;   // decoded, with no initialised position
  std::uint64_t out_of_order = 0;   // older than the pose already held
  std::uint64_t unknown = 0;        // on a topic of no team robot
  std::uint64_t controller_steps = 0;
  std::uint64_t stale_steps = 0;    // periods with a pose missing or stale: the team told to stop
  std::uint64_t commands_sent = 0;
  std::uint64_t publish_failures = 0;
};

// What one call of step() did.
enum class StepOutcome : std::uint8_t {
  idle,       // not yet a period since the last one
  commanded,  // the controller stepped; its commands went out
  stopped,    // a pose missing or stale: stop went out to every robot
};

class FormationService {
 public:
  // Errc::config naming the field for a team that does not match the controller, a bad
  // period, timeout or hold, or a controller configuration it refuses.
  static Result<std::unique_ptr<FormationService>> create(const FormationServiceConfig& config, std::unique_ptr<hal::PubSub> link);
  // The link's subscriptions: each team robot's visualization topic.
  static Result<std::vector<hal::PubSubSubscription>> subscriptions(const FormationServiceConfig& config);
  ~FormationService();

  // Takes every message waiting; once a period (from the first call) steps the controller at
  // `now` and publishes. unix_ns: the site's wall clock, for the freshness of the poses and
  // the commands' timestamps. Never allocates.
  StepOutcome step(hal::Nanos now, std::int64_t unix_ns);
  // Tells every robot to stop now (a program on its way out: the team stands at once rather
  // than at the end of its hold). The next step() starts the controller afresh.
  void stop_team(std::int64_t unix_ns);
  // Sends what is queued (up to timeout_s) and disconnects cleanly.
  void close(double timeout_s) noexcept { link_->close(timeout_s); }

  [[nodiscard]] const FormationCounters& counters() const noexcept { return counters_; }
  [[nodiscard]] const Controller& controller() const noexcept { return *controller_; }
  [[nodiscard]] const hal::PubSub& link() const noexcept { return *link_; }
  [[nodiscard]] std::size_t robots() const noexcept { return robots_.size(); }
  // The poses the last controller step used (predicted to its time) and the commands sent
  // with the last step of either kind.
  [[nodiscard]] std::span<const Pose> poses() const noexcept { return {poses_.data(), robots_.size()}; }
  [[nodiscard]] std::span<const Unicycle> commands() const noexcept { return {commands_.data(), robots_.size()}; }
  // Each robot's newest pose as received (its message's unix time, 0 when none yet).
  [[nodiscard]] std::int64_t pose_stamp_unix_ns(std::size_t robot) const noexcept { return robots_[robot].stamp_unix_ns; }
  [[nodiscard]] std::uint32_t last_header_id(std::size_t robot) const noexcept { return robots_[robot].header_id; }

 private:
  struct Buffers;
  struct Robot {
    std::string visualization_topic;
    std::string command_topic;
    bool have_pose = false;
    Pose pose;
    double v = 0.0;       // reported with the pose
    double omega = 0.0;
    std::int64_t stamp_unix_ns = 0;
    std::uint32_t header_id = 0;  // the last command's
  };
  FormationService(const FormationServiceConfig& config, std::unique_ptr<hal::PubSub> link);

  void take_messages();
  void on_visualization(std::size_t robot, std::string_view text);
  void send(std::size_t robot, Unicycle command, std::int64_t unix_ns);

  FormationServiceConfig config_;
  std::unique_ptr<hal::PubSub> link_;
  std::unique_ptr<Controller> controller_;
  std::unique_ptr<Buffers> buffers_;
  std::vector<Robot> robots_;
  std::array<Pose, kMaxRobots> poses_{};
  std::array<Unicycle, kMaxRobots> commands_{};
  hal::Nanos period_ns_ = 0;
  hal::Nanos next_ns_ = 0;
  bool started_ = false;   // step() has been called
  bool running_ = false;   // the controller was reset on a whole picture and steps on
  FormationCounters counters_;
};

}  // namespace sen3bot::formation
