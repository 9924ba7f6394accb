#pragma once
// The VDA 5050 vehicle's order state machine (sections 6.6 to 6.12): it accepts or rejects
// orders and order updates (Figure 8), runs instant actions, traverses nodes as the pose comes
// in, runs node and edge actions by their blocking types, and reports what the state message
// needs. Pure code: no I/O, no clock, no heap. The firmware task feeds it decoded messages and
// the navigation's progress, drives to target(), and publishes when state_changed().
#include <cstddef>
#include <cstdint>
#include <initializer_list>
#include <optional>
#include <span>
#include <string_view>
#include <utility>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/vda5050/types.hpp"

namespace sen3bot::vda5050 {

inline constexpr std::size_t kMaxSupportedActions = 16;

// An action type the vehicle can run besides the built-in instant actions (cancelOrder,
// startPause, stopPause, factsheetRequest, stateRequest, always supported).
struct SupportedAction {
  Id action_type;
  bool instant = false;  // allowed in instantActions
  bool node = false;     // allowed on nodes
  bool edge = false;     // allowed on edges
  // false: the vehicle finishes the action as soon as it is triggered (a marker, a no-op).
  // true: the host runs it: it is offered by action_to_start() and the host reports progress.
  bool host_run = false;
};

struct VehicleConfig {
  Id manufacturer;
  Id serial_number;
  Version version = Version::v2_1_0;
  double default_deviation_xy = 0.5;       // m, when a node's allowedDeviationXY is 0
  double default_deviation_theta = 0.35;   // rad, when a node's allowedDeviationTheta is 0
  double standstill_speed = 0.02;          // m/s (and rad/s): at or below it the robot stands
  double new_base_request_distance = 3.0;  // m to the decision point with a horizon left
  StaticVector<SupportedAction, kMaxSupportedActions> actions;
};

// The estimated pose. Nodes are only traversed (and a new order's start only reached) while
// the robot is localized on the node's map.
struct Pose {
  double x = 0;
  double y = 0;
  double theta = 0;  // rad
  Id map_id;
  bool localized = false;
};

struct Progress {
  Pose pose;
  double speed = 0;  // m/s, the larger of |linear| and |angular| (rad/s) is fine
  // The navigation's verdict on the goal it was given: target().sequence_id copied back, so a
  // late report about an older goal is ignored.
  bool goal_reached = false;
  bool goal_failed = false;
  std::uint32_t goal_sequence_id = 0;
};

enum class HoldReason : std::uint8_t {
  none,             // driving to the target
  no_order,         // no order, or the order's base is done and nothing is left
  paused,           // startPause
  decision_point,   // at the last released node, waiting for an order update
  cancelled,        // cancelOrder
  blocking_action,  // a SOFT or HARD action is running or queued
};
std::string_view to_string(HoldReason reason) noexcept;

// Where to drive next: the next released node. hold means stand still (reason says why).
struct DriveTarget {
  bool hold = true;
  HoldReason reason = HoldReason::no_order;
  Id node_id;
  std::uint32_t sequence_id = 0;
  double x = 0;
  double y = 0;
  std::optional<double> theta;
  std::optional<double> max_speed;  // the edge leading to the node, when it sets one
  Id map_id;
};

class Vehicle {
 public:
  explicit Vehicle(const VehicleConfig& config) noexcept;
  Vehicle(const Vehicle&) = delete;
  Vehicle& operator=(const Vehicle&) = delete;

  // --- inputs -----------------------------------------------------------------------------
  // Figure 8. Returns true when the order (or update) was taken over; a rejection adds a
  // warning to errors() and leaves the current order as it was. An ignored duplicate
  // (same orderId and orderUpdateId) returns false without an error.
  bool receive_order(const Order& order, const Pose& now) noexcept;
  void receive_instant_actions(const InstantActions& message) noexcept;
  // A message the codec refused (malformed, a schema violation, a field we cannot hold): its
  // error is reported as a warning until a new order is accepted (section 6.6.4); the current
  // order goes on untouched.
  void report_rejected_message(const VehicleError& error) noexcept;
  void update(const Progress& progress) noexcept;
  // The host's report on an action it runs (host_run): RUNNING, PAUSED, FINISHED or FAILED.
  // invalid_argument for an unknown id, an action not run by the host, or one already done.
  Status report_action(std::string_view action_id, ActionStatus status,
                       std::string_view result_description = {}) noexcept;
  // The host published the factsheet / a state message: factsheetRequest and stateRequest
  // actions finish, and the state-changed flag (for state_published) is cleared.
  void factsheet_published() noexcept;
  void state_published() noexcept;

  // --- outputs ----------------------------------------------------------------------------
  [[nodiscard]] const DriveTarget& target() const noexcept { return target_; }
  // The released nodes still to traverse, the target first: the global planner's via points.
  [[nodiscard]] std::span<const NodeState> route() const noexcept;
  // An event that calls for a state message happened since the last state_published().
  [[nodiscard]] bool state_changed() const noexcept { return state_changed_; }
  // A factsheetRequest waits for the host to publish the factsheet.
  [[nodiscard]] bool factsheet_requested() const noexcept;
  // The first host-run action triggered but not yet reported on (INITIALIZING), or null.
  // The host starts it and calls report_action before asking again.
  [[nodiscard]] const Action* action_to_start() const noexcept;
  [[nodiscard]] std::optional<ActionStatus> action_status(std::string_view action_id) const noexcept;
  // Fills header.manufacturer/serial_number/version, order_id, order_update_id, zone_set_id,
  // last_node_id, last_node_sequence_id, node_states, edge_states, action_states, errors,
  // paused and new_base_request. Everything else is the host's.
  void fill_state(State& state) const noexcept;

  [[nodiscard]] bool paused() const noexcept { return paused_; }
  [[nodiscard]] bool new_base_request() const noexcept { return new_base_request_; }
  [[nodiscard]] std::string_view order_id() const noexcept { return order_id_.view(); }
  [[nodiscard]] std::uint32_t order_update_id() const noexcept { return order_update_id_; }
  [[nodiscard]] std::string_view last_node_id() const noexcept { return last_node_id_.view(); }
  [[nodiscard]] std::uint32_t last_node_sequence_id() const noexcept { return last_node_sequence_id_; }
  [[nodiscard]] std::span<const NodeState> node_states() const noexcept { return nodes_.as_span(); }
  [[nodiscard]] std::size_t edge_state_count() const noexcept { return edges_.size(); }
  [[nodiscard]] std::span<const VehicleError> errors() const noexcept { return errors_.as_span(); }
  // Errors pushed out of the full list (oldest first) since start-up.
  [[nodiscard]] std::uint32_t dropped_errors() const noexcept { return dropped_errors_; }

 private:
  enum class Owner : std::uint8_t { instant, node, edge };
  enum class Builtin : std::uint8_t { none, cancel_order, start_pause, stop_pause, factsheet_request, state_request };
  enum class ErrorSource : std::uint8_t { order_message, instant_action, navigation };

  struct Slot {
    Action action;
    ActionStatus status = ActionStatus::waiting;
    Text result;
    Owner owner = Owner::instant;
    std::uint32_t sequence_id = 0;  // of the node or edge it belongs to
    bool triggered = false;         // its node was traversed / its edge entered
    bool host_run = false;
    Builtin builtin = Builtin::none;
  };

  struct HeldEdge {
    Id edge_id;
    std::uint32_t sequence_id = 0;
    bool released = false;
    std::optional<double> max_speed;
  };

  // What an accepted order changes: computed first, so a rejection touches nothing.
  enum class Acceptance : std::uint8_t { new_order, continuation };

  bool reject(const Order& order, std::string_view type, std::string_view description,
              std::string_view key = {}, std::string_view value = {}) noexcept;
  bool validate(const Order& order) noexcept;
  bool check_capabilities(const Order& order, std::size_t first_node) noexcept;
  bool executing() const noexcept;
  bool close_to(const NodePosition& position, const Pose& pose) const noexcept;
  bool accept(const Order& order, Acceptance kind) noexcept;
  void run_instant(const Action& action) noexcept;

  const SupportedAction* find_supported(std::string_view type) const noexcept;
  Slot* find_slot(std::string_view action_id) noexcept;
  const Slot* find_slot(std::string_view action_id) const noexcept;
  bool make_room(std::size_t wanted) noexcept;
  void set_status(Slot& slot, ActionStatus status, std::string_view result = {}) noexcept;
  void start(Slot& slot) noexcept;
  void run_group(Owner owner, std::uint32_t sequence_id) noexcept;
  void run_actions() noexcept;
  bool blocked_by_actions() const noexcept;
  void trigger(Owner owner, std::uint32_t sequence_id) noexcept;
  bool edge_into_first_node() const noexcept { return !edges_.empty() && edges_.size() == nodes_.size(); }
  bool reached(const NodeState& node, const Progress& progress) const noexcept;
  void traverse_first_node() noexcept;
  void finish_cancel_and_pause(double speed) noexcept;
  void update_new_base_request() noexcept;
  void refresh_target() noexcept;

  void add_error(std::string_view type, std::string_view description, ErrorSource source,
                 std::initializer_list<std::pair<std::string_view, std::string_view>> references) noexcept;
  void clear_errors(ErrorSource source) noexcept;

  VehicleConfig config_;

  Id order_id_;
  std::uint32_t order_update_id_ = 0;
  Id zone_set_id_;
  Id last_node_id_;
  std::uint32_t last_node_sequence_id_ = 0;
  std::optional<NodePosition> last_node_position_;
  bool has_order_ = false;
  Pose pose_;  // the latest pose seen (for newBaseRequest)  // an order was accepted since start-up (orderId is meaningful)

  StaticVector<NodeState, kMaxNodes> nodes_;  // not yet traversed: base, then horizon
  StaticVector<HeldEdge, kMaxEdges> edges_;   // not yet left; edges_[0] leads into nodes_[0]
                                              // when the counts are equal
  bool edge_entered_ = false;                 // edges_[0]'s actions were triggered
  StaticVector<Slot, kMaxActionStates> slots_;

  StaticVector<VehicleError, kMaxErrors> errors_;
  StaticVector<ErrorSource, kMaxErrors> error_sources_;
  std::uint32_t dropped_errors_ = 0;
  bool navigation_error_raised_ = false;

  bool paused_ = false;
  bool cancelled_ = false;
  bool new_base_request_ = false;
  bool state_changed_ = false;
  DriveTarget target_;
};

}  // namespace sen3bot::vda5050
