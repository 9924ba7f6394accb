#include "sen3bot/vda5050/vehicle.hpp"

#include <cmath>
#include <cstdio>
#include <numbers>

namespace sen3bot::vda5050 {
namespace {

// Text longer than a field's capacity is cut rather than dropped: it is only ever a
// description or a reference value in a report.
template <std::size_t N>
void put(FixedString<N>& field, std::string_view text) noexcept {
  (void)field.assign(text.substr(0, std::min(text.size(), N)));
}

bool terminal(ActionStatus status) noexcept {
  return status == ActionStatus::finished || status == ActionStatus::failed;
}

struct Number {
  char text[16] = {};
  explicit Number(std::uint32_t value) noexcept { std::snprintf(text, sizeof text, "%u", value); }
  [[nodiscard]] std::string_view view() const noexcept { return text; }
};

}  // namespace

std::string_view to_string(HoldReason reason) noexcept {
  switch (reason) {
    case HoldReason::none: return "none";
    case HoldReason::no_order: return "no order";
    case HoldReason::paused: return "paused";
    case HoldReason::decision_point: return "decision point";
    case HoldReason::cancelled: return "cancelled";
    case HoldReason::blocking_action: return "blocking action";
  }
  return "none";
}

Vehicle::Vehicle(const VehicleConfig& config) noexcept : config_(config) {}

// --- orders (Figure 8) ------------------------------------------------------------------------

bool Vehicle::receive_order(const Order& order, const Pose& now) noexcept {
  pose_ = now;
  if (!validate(order)) return false;                                     // (1)
  const Node& first = order.nodes[0];
  if (!has_order_ || order.order_id != order_id_) {                       // (2) new
    if (executing())                                                      // (3)
      return reject(order, "orderError", "another order is still running or waiting for an update",
                    "orderId", order_id_.view());
    if (!check_capabilities(order, 0)) return false;
    if (!close_to(*first.position, now))                                  // (4)
      return reject(order, "noRouteError", "the first node is not within its deviation range",
                    "nodeId", first.node_id.view());
    return accept(order, Acceptance::new_order);
  }
  if (order.order_update_id < order_update_id_)                           // (5)
    return reject(order, "orderUpdateError", "orderUpdateId is lower than the current one");
  if (order.order_update_id == order_update_id_) return false;            // (6) a resend
  if (executing()) {                                                      // (3)
    // (7) The decision point: the last released node still ahead, else the last node passed.
    Id id = last_node_id_;
    std::uint32_t sequence_id = last_node_sequence_id_;
    for (const NodeState& node : nodes_) {
      if (!node.released) break;
      id = node.node_id;
      sequence_id = node.sequence_id;
    }
    if (first.node_id != id || first.sequence_id != sequence_id)
      return reject(order, "orderUpdateError", "the first node is not the decision point", "nodeId",
                    first.node_id.view());
  } else if (first.node_id != last_node_id_ || first.sequence_id != last_node_sequence_id_) {  // (8)
    return reject(order, "orderUpdateError", "the first node is not the last node passed", "nodeId",
                  first.node_id.view());
  }
  if (!check_capabilities(order, 1)) return false;  // the stitching node's content is not taken
  return accept(order, Acceptance::continuation);
}

bool Vehicle::reject(const Order& order, std::string_view type, std::string_view description,
                     std::string_view key, std::string_view value) noexcept {
  const Number update_id(order.order_update_id);
  if (key.empty()) {
    add_error(type, description, ErrorSource::order_message,
              {{"orderId", order.order_id.view()}, {"orderUpdateId", update_id.view()}});
  } else {
    add_error(type, description, ErrorSource::order_message,
              {{"orderId", order.order_id.view()}, {"orderUpdateId", update_id.view()}, {key, value}});
  }
  refresh_target();
  return false;
}

// The checks the vehicle relies on; the codec has already checked JSON types and ranges.
bool Vehicle::validate(const Order& order) noexcept {
  constexpr std::string_view kType = "validationError";
  if (!order.header.serial_number.empty() && !config_.serial_number.empty() &&
      order.header.serial_number != config_.serial_number)
    return reject(order, kType, "the order is for another vehicle", "serialNumber",
                  order.header.serial_number.view());
  if (order.order_id.empty()) return reject(order, kType, "orderId is empty", "orderId", "");
  if (order.nodes.empty()) return reject(order, kType, "an order needs at least one node", "nodes", "0");
  if (order.edges.size() + 1 != order.nodes.size())
    return reject(order, kType, "an order needs one edge less than nodes", "edges", "");
  if (!order.nodes[0].released)
    return reject(order, kType, "the first node is not released", "nodeId", order.nodes[0].node_id.view());
  for (std::size_t i = 0; i < order.edges.size(); ++i) {
    const Edge& edge = order.edges[i];
    const Node& from = order.nodes[i];
    const Node& to = order.nodes[i + 1];
    if (edge.start_node_id != from.node_id || edge.end_node_id != to.node_id)
      return reject(order, kType, "the edge does not join its neighbouring nodes", "edgeId", edge.edge_id.view());
    if (!(from.sequence_id < edge.sequence_id && edge.sequence_id < to.sequence_id))
      return reject(order, kType, "sequenceIds do not increase along the path", "edgeId", edge.edge_id.view());
    // Base first, then horizon; an edge is released only between released nodes.
    if (to.released && !from.released)
      return reject(order, kType, "a released node follows the horizon", "nodeId", to.node_id.view());
    if (edge.released != to.released)
      return reject(order, kType, "an edge's release differs from its end node's", "edgeId", edge.edge_id.view());
  }
  // Action ids are unique within the order.
  auto each_action = [&order](auto&& visit) {
    for (const Node& node : order.nodes)
      for (const Action& action : node.actions)
        if (!visit(action)) return false;
    for (const Edge& edge : order.edges)
      for (const Action& action : edge.actions)
        if (!visit(action)) return false;
    return true;
  };
  const Action* duplicate = nullptr;
  each_action([&](const Action& a) {
    int seen = 0;
    each_action([&](const Action& b) {
      if (a.action_id == b.action_id) ++seen;
      return seen < 2;
    });
    if (seen >= 2) duplicate = &a;
    return duplicate == nullptr;
  });
  if (duplicate != nullptr)
    return reject(order, kType, "actionId used twice", "actionId", duplicate->action_id.view());
  return true;
}

// 6.6.4.2: actions the vehicle cannot run and nodes it cannot drive to (no position: the
// robot navigates freely, it follows no lines) reject the order. Nodes before first_node
// are not taken over and are not checked.
bool Vehicle::check_capabilities(const Order& order, std::size_t first_node) noexcept {
  constexpr std::string_view kType = "orderError";
  auto unsupported = [&](const Action& action, bool on_node) {
    const SupportedAction* supported = find_supported(action.action_type.view());
    if (supported != nullptr && (on_node ? supported->node : supported->edge)) return false;
    const Number update_id(order.order_update_id);
    add_error(kType, on_node ? "action type not supported on nodes" : "action type not supported on edges",
              ErrorSource::order_message,
              {{"orderId", order.order_id.view()}, {"orderUpdateId", update_id.view()},
               {"actionId", action.action_id.view()}, {"actionType", action.action_type.view()}});
    refresh_target();
    return true;
  };
  for (std::size_t i = first_node; i < order.nodes.size(); ++i) {
    const Node& node = order.nodes[i];
    if (!node.position)
      return reject(order, kType, "the node has no position", "nodeId", node.node_id.view());
    for (const Action& action : node.actions)
      if (unsupported(action, true)) return false;
  }
  for (const Edge& edge : order.edges)
    for (const Action& action : edge.actions)
      if (unsupported(action, false)) return false;
  return true;
}

// (3): node states left, or an order action not done. Instant actions do not count, so a
// factsheetRequest waiting for publication does not hold up a new order.
bool Vehicle::executing() const noexcept {
  if (!nodes_.empty()) return true;
  for (const Slot& slot : slots_)
    if (slot.owner != Owner::instant && !terminal(slot.status)) return true;
  return false;
}

bool Vehicle::close_to(const NodePosition& position, const Pose& pose) const noexcept {
  if (!pose.localized) return false;
  if (!position.map_id.empty() && !pose.map_id.empty() && position.map_id != pose.map_id) return false;
  const double deviation =
      position.allowed_deviation_xy > 0 ? position.allowed_deviation_xy : config_.default_deviation_xy;
  return std::hypot(pose.x - position.x, pose.y - position.y) <= deviation;
}

bool Vehicle::accept(const Order& order, Acceptance kind) noexcept {
  const bool fresh = kind == Acceptance::new_order;
  const std::size_t first_new = fresh ? 0 : 1;

  // Which held nodes, edges and action states stay: a new order keeps only the running
  // instant actions; an update keeps the base and drops the horizon (9).
  std::size_t kept_nodes = 0;
  std::size_t kept_edges = 0;
  if (!fresh) {
    for (const NodeState& node : nodes_) kept_nodes += node.released ? 1 : 0;
    for (const HeldEdge& edge : edges_) kept_edges += edge.released ? 1 : 0;
  }
  auto in_horizon = [this](const Slot& slot) {
    if (slot.owner == Owner::node) {
      for (const NodeState& node : nodes_)
        if (!node.released && node.sequence_id == slot.sequence_id) return true;
    } else if (slot.owner == Owner::edge) {
      for (const HeldEdge& edge : edges_)
        if (!edge.released && edge.sequence_id == slot.sequence_id) return true;
    }
    return false;
  };
  auto kept = [&](const Slot& slot) {
    return fresh ? (slot.owner == Owner::instant && !terminal(slot.status)) : !in_horizon(slot);
  };

  const std::size_t nodes_after = kept_nodes + order.nodes.size() - first_new;
  const std::size_t edges_after = kept_edges + order.edges.size();
  char limit[48];
  if (nodes_after > kMaxNodes) {
    std::snprintf(limit, sizeof limit, "%zu held, at most %zu", nodes_after, kMaxNodes);
    return reject(order, "orderError", "too many nodes to hold", "nodes", limit);
  }
  if (edges_after > kMaxEdges) {
    std::snprintf(limit, sizeof limit, "%zu held, at most %zu", edges_after, kMaxEdges);
    return reject(order, "orderError", "too many edges to hold", "edges", limit);
  }

  std::size_t incoming = 0;
  for (std::size_t i = first_new; i < order.nodes.size(); ++i) {
    for (const Action& action : order.nodes[i].actions) {
      const Slot* known = find_slot(action.action_id.view());
      if (known != nullptr && kept(*known))
        return reject(order, "orderError", "actionId already in use", "actionId", action.action_id.view());
      ++incoming;
    }
  }
  for (const Edge& edge : order.edges) {
    for (const Action& action : edge.actions) {
      const Slot* known = find_slot(action.action_id.view());
      if (known != nullptr && kept(*known))
        return reject(order, "orderError", "actionId already in use", "actionId", action.action_id.view());
      ++incoming;
    }
  }
  std::size_t staying = 0;
  std::size_t prunable = 0;  // finished states may go to make room for new ones
  for (const Slot& slot : slots_) {
    if (!kept(slot)) continue;
    ++staying;
    prunable += terminal(slot.status) ? 1 : 0;
  }
  if (staying - prunable + incoming > kMaxActionStates) {
    std::snprintf(limit, sizeof limit, "%zu held, at most %zu", staying - prunable + incoming, kMaxActionStates);
    return reject(order, "orderError", "too many actions to hold", "actionStates", limit);
  }

  // Taken over from here on; nothing below can fail.
  slots_.remove_if([&](const Slot& slot) { return !kept(slot); });
  (void)make_room(incoming);
  if (fresh) {
    nodes_.clear();
    edges_.clear();
    edge_entered_ = false;
    order_id_ = order.order_id;
  } else {
    nodes_.remove_if([](const NodeState& node) { return !node.released; });
    edges_.remove_if([](const HeldEdge& edge) { return !edge.released; });
  }
  order_update_id_ = order.order_update_id;
  zone_set_id_ = order.zone_set_id;
  has_order_ = true;
  cancelled_ = false;

  auto add_actions = [this](const StaticVector<Action, kMaxActions>& actions, Owner owner,
                            std::uint32_t sequence_id) {
    for (const Action& action : actions) {
      Slot slot;
      slot.action = action;
      slot.owner = owner;
      slot.sequence_id = sequence_id;
      const SupportedAction* supported = find_supported(action.action_type.view());
      slot.host_run = supported != nullptr && supported->host_run;
      (void)slots_.push_back(slot);
    }
  };
  for (std::size_t i = first_new; i < order.nodes.size(); ++i) {
    const Node& node = order.nodes[i];
    if (i > 0) {
      const Edge& edge = order.edges[i - 1];
      (void)edges_.push_back(HeldEdge{edge.edge_id, edge.sequence_id, edge.released, edge.max_speed});
      add_actions(edge.actions, Owner::edge, edge.sequence_id);
    }
    (void)nodes_.push_back(NodeState{node.node_id, node.sequence_id, node.released, node.position});
    add_actions(node.actions, Owner::node, node.sequence_id);
  }

  // The warnings of earlier rejections and instant actions stand until an order is taken (6.6.4).
  clear_errors(ErrorSource::order_message);
  clear_errors(ErrorSource::instant_action);
  clear_errors(ErrorSource::navigation);
  navigation_error_raised_ = false;
  state_changed_ = true;
  refresh_target();
  return true;
}

// --- instant actions ------------------------------------------------------------------------

void Vehicle::receive_instant_actions(const InstantActions& message) noexcept {
  for (const Action& action : message.actions) run_instant(action);
  run_actions();
  refresh_target();
}

void Vehicle::run_instant(const Action& action) noexcept {
  if (find_slot(action.action_id.view()) != nullptr) return;  // a resend: never run twice

  Slot slot;
  slot.action = action;
  slot.owner = Owner::instant;
  slot.triggered = true;
  const std::string_view type = action.action_type.view();
  if (type == "cancelOrder") slot.builtin = Builtin::cancel_order;
  else if (type == "startPause") slot.builtin = Builtin::start_pause;
  else if (type == "stopPause") slot.builtin = Builtin::stop_pause;
  else if (type == "factsheetRequest") slot.builtin = Builtin::factsheet_request;
  else if (type == "stateRequest") slot.builtin = Builtin::state_request;

  const SupportedAction* supported = find_supported(type);
  if (slot.builtin == Builtin::none && (supported == nullptr || !supported->instant)) {
    add_error("instantActionError", "action type not supported as an instant action",
              ErrorSource::instant_action,
              {{"actionId", action.action_id.view()}, {"actionType", type}});
    slot.status = ActionStatus::failed;
    put(slot.result, "not supported");
    if (make_room(1)) (void)slots_.push_back(slot);
    return;
  }
  if (!make_room(1)) {
    add_error("instantActionError", "no room for another action state", ErrorSource::instant_action,
              {{"actionId", action.action_id.view()}, {"actionType", type}});
    return;
  }
  state_changed_ = true;

  switch (slot.builtin) {
    case Builtin::cancel_order:
      if (cancelled_ || !executing()) {  // 6.6.3.2
        slot.status = ActionStatus::failed;
        put(slot.result, "no order to cancel");
        add_error("noOrderToCancel", "there is no order to cancel", ErrorSource::instant_action,
                  {{"actionId", action.action_id.view()}});
        break;
      }
      // Stop where we are: everything scheduled or running fails, the route goes, the ids
      // stay. The action finishes once update() sees the robot stand.
      for (Slot& other : slots_)
        if (other.owner != Owner::instant && !terminal(other.status))
          set_status(other, ActionStatus::failed, "order cancelled");
      nodes_.clear();
      edges_.clear();
      edge_entered_ = false;
      cancelled_ = true;
      slot.status = ActionStatus::running;
      break;
    case Builtin::start_pause:
      paused_ = true;
      slot.status = ActionStatus::running;  // FINISHED once the robot stands
      break;
    case Builtin::stop_pause:
      paused_ = false;
      for (Slot& other : slots_)
        if (other.builtin == Builtin::start_pause && other.status == ActionStatus::running)
          set_status(other, ActionStatus::failed, "ended by stopPause");
      slot.status = ActionStatus::finished;
      break;
    case Builtin::factsheet_request:
    case Builtin::state_request:
      slot.status = ActionStatus::running;  // FINISHED once the host has published
      break;
    case Builtin::none:
      slot.host_run = supported->host_run;
      start(slot);
      break;
  }
  (void)slots_.push_back(slot);
}

// --- progress -------------------------------------------------------------------------------

void Vehicle::update(const Progress& progress) noexcept {
  pose_ = progress.pose;
  finish_cancel_and_pause(progress.speed);
  // Several nodes may fall within reach in one step; each pass takes at most one.
  for (std::size_t pass = 0; pass <= kMaxNodes; ++pass) {
    run_actions();
    if (paused_ || cancelled_ || blocked_by_actions()) break;
    if (nodes_.empty() || !nodes_[0].released) break;  // the decision point: never the horizon
    if (edge_into_first_node() && !edge_entered_) {
      edge_entered_ = true;
      trigger(Owner::edge, edges_[0].sequence_id);
      run_actions();
      if (blocked_by_actions()) break;  // 6.10.2: the edge's blocking actions run first
    }
    if (!reached(nodes_[0], progress)) break;
    traverse_first_node();
  }
  if (progress.goal_failed && !nodes_.empty() && nodes_[0].sequence_id == progress.goal_sequence_id &&
      !navigation_error_raised_) {
    const Number sequence_id(nodes_[0].sequence_id);
    add_error("navigationError", "the navigation could not reach the node", ErrorSource::navigation,
              {{"nodeId", nodes_[0].node_id.view()}, {"sequenceId", sequence_id.view()}});
    navigation_error_raised_ = true;
  }
  refresh_target();
}

bool Vehicle::reached(const NodeState& node, const Progress& progress) const noexcept {
  if (progress.goal_reached && progress.goal_sequence_id == node.sequence_id) return true;
  if (!node.position || !close_to(*node.position, progress.pose)) return false;
  if (!node.position->theta) return true;
  const double deviation = node.position->allowed_deviation_theta > 0 ? node.position->allowed_deviation_theta
                                                                      : config_.default_deviation_theta;
  const double error = std::remainder(progress.pose.theta - *node.position->theta, 2 * std::numbers::pi);
  return std::fabs(error) <= deviation;
}

// 6.10.2: passing a node leaves the edge into it (its actions finish), sets lastNode and
// triggers the node's actions; the next edge is entered once the robot may drive on.
void Vehicle::traverse_first_node() noexcept {
  if (edge_into_first_node()) {
    for (Slot& slot : slots_)
      if (slot.owner == Owner::edge && slot.sequence_id == edges_[0].sequence_id && !terminal(slot.status))
        set_status(slot, ActionStatus::finished, "edge left");
    edges_.erase(edges_.begin());
  }
  const NodeState node = nodes_[0];
  nodes_.erase(nodes_.begin());
  last_node_id_ = node.node_id;
  last_node_sequence_id_ = node.sequence_id;
  last_node_position_ = node.position;
  edge_entered_ = false;
  trigger(Owner::node, node.sequence_id);
  clear_errors(ErrorSource::navigation);
  navigation_error_raised_ = false;
  state_changed_ = true;
}

void Vehicle::finish_cancel_and_pause(double speed) noexcept {
  if (std::fabs(speed) > config_.standstill_speed) return;
  for (Slot& slot : slots_) {
    if (slot.status != ActionStatus::running) continue;
    if (slot.builtin == Builtin::cancel_order) set_status(slot, ActionStatus::finished, "order cancelled");
    if (slot.builtin == Builtin::start_pause && paused_) set_status(slot, ActionStatus::finished, "paused");
  }
}

// --- actions (6.11, 6.12) ---------------------------------------------------------------------

void Vehicle::trigger(Owner owner, std::uint32_t sequence_id) noexcept {
  for (Slot& slot : slots_)
    if (slot.owner == owner && slot.sequence_id == sequence_id) slot.triggered = true;
}

void Vehicle::start(Slot& slot) noexcept {
  if (slot.host_run) set_status(slot, ActionStatus::initializing);
  else set_status(slot, ActionStatus::finished, "done");
}

// One node's or edge's actions in list order: NONE and SOFT ones start together; a HARD one
// waits for everything before it and holds back everything after it.
void Vehicle::run_group(Owner owner, std::uint32_t sequence_id) noexcept {
  bool earlier_open = false;
  for (Slot& slot : slots_) {
    if (slot.owner != owner || slot.sequence_id != sequence_id || !slot.triggered) continue;
    if (slot.action.blocking_type == BlockingType::hard) {
      if (earlier_open) return;
      if (slot.status == ActionStatus::waiting) start(slot);
      if (!terminal(slot.status)) return;
    } else if (slot.status == ActionStatus::waiting) {
      start(slot);
    }
    earlier_open = earlier_open || !terminal(slot.status);
  }
}

void Vehicle::run_actions() noexcept {
  for (std::size_t i = 0; i < slots_.size(); ++i) {
    const Slot& slot = slots_[i];
    if (slot.owner != Owner::instant && slot.triggered && slot.status == ActionStatus::waiting)
      run_group(slot.owner, slot.sequence_id);
  }
}

// SOFT and HARD actions keep the robot standing while they are triggered and not done.
bool Vehicle::blocked_by_actions() const noexcept {
  for (const Slot& slot : slots_)
    if (slot.triggered && slot.builtin == Builtin::none && !terminal(slot.status) &&
        slot.action.blocking_type != BlockingType::none)
      return true;
  return false;
}

Status Vehicle::report_action(std::string_view action_id, ActionStatus status,
                              std::string_view result_description) noexcept {
  Slot* slot = find_slot(action_id);
  if (slot == nullptr) return Error(Errc::invalid_argument, "unknown actionId");
  if (!slot->host_run) return Error(Errc::invalid_argument, "the action is not run by the host");
  if (terminal(slot->status)) return Error(Errc::invalid_argument, "the action is already done");
  if (slot->status == ActionStatus::waiting || status == ActionStatus::waiting)
    return Error(Errc::invalid_argument, "the action was not started");
  set_status(*slot, status, result_description);
  run_actions();
  refresh_target();
  return Status::success();
}

void Vehicle::factsheet_published() noexcept {
  for (Slot& slot : slots_)
    if (slot.builtin == Builtin::factsheet_request && slot.status == ActionStatus::running)
      set_status(slot, ActionStatus::finished, "factsheet published");
}

// A stateRequest finishes with the publication, so the next state shows it FINISHED.
void Vehicle::state_published() noexcept {
  state_changed_ = false;
  for (Slot& slot : slots_)
    if (slot.builtin == Builtin::state_request && slot.status == ActionStatus::running)
      set_status(slot, ActionStatus::finished, "state published");
}

bool Vehicle::factsheet_requested() const noexcept {
  for (const Slot& slot : slots_)
    if (slot.builtin == Builtin::factsheet_request && slot.status == ActionStatus::running) return true;
  return false;
}

const Action* Vehicle::action_to_start() const noexcept {
  for (const Slot& slot : slots_)
    if (slot.host_run && slot.status == ActionStatus::initializing) return &slot.action;
  return nullptr;
}

std::optional<ActionStatus> Vehicle::action_status(std::string_view action_id) const noexcept {
  const Slot* slot = find_slot(action_id);
  if (slot == nullptr) return std::nullopt;
  return slot->status;
}

const SupportedAction* Vehicle::find_supported(std::string_view type) const noexcept {
  for (const SupportedAction& supported : config_.actions)
    if (supported.action_type == type) return &supported;
  return nullptr;
}

Vehicle::Slot* Vehicle::find_slot(std::string_view action_id) noexcept {
  for (Slot& slot : slots_)
    if (slot.action.action_id == action_id) return &slot;
  return nullptr;
}

const Vehicle::Slot* Vehicle::find_slot(std::string_view action_id) const noexcept {
  for (const Slot& slot : slots_)
    if (slot.action.action_id == action_id) return &slot;
  return nullptr;
}

// Drops the oldest finished or failed states until `wanted` more fit.
bool Vehicle::make_room(std::size_t wanted) noexcept {
  while (slots_.size() + wanted > kMaxActionStates) {
    const Slot* oldest = nullptr;
    for (const Slot& slot : slots_) {
      if (terminal(slot.status)) {
        oldest = &slot;
        break;
      }
    }
    if (oldest == nullptr) return false;
    slots_.erase(oldest);
    state_changed_ = true;
  }
  return true;
}

void Vehicle::set_status(Slot& slot, ActionStatus status, std::string_view result) noexcept {
  if (slot.status == status && slot.result == result) return;
  slot.status = status;
  put(slot.result, result);
  state_changed_ = true;
}

// --- outputs --------------------------------------------------------------------------------

std::span<const NodeState> Vehicle::route() const noexcept {
  std::size_t released = 0;
  while (released < nodes_.size() && nodes_[released].released) ++released;
  return {nodes_.data(), released};
}

// 6.10.3, kept simple: a horizon is left and the robot is within new_base_request_distance
// (straight line) of the decision point.
void Vehicle::update_new_base_request() noexcept {
  bool horizon = false;
  std::optional<NodePosition> decision_point = last_node_position_;
  for (const NodeState& node : nodes_) {
    if (node.released) decision_point = node.position;
    else horizon = true;
  }
  bool request = false;
  if (horizon && decision_point && pose_.localized)
    request = std::hypot(pose_.x - decision_point->x, pose_.y - decision_point->y) <=
              config_.new_base_request_distance;
  if (request != new_base_request_) state_changed_ = true;
  new_base_request_ = request;
}

void Vehicle::refresh_target() noexcept {
  update_new_base_request();
  DriveTarget next;
  if (cancelled_) next.reason = HoldReason::cancelled;
  else if (paused_) next.reason = HoldReason::paused;
  else if (blocked_by_actions()) next.reason = HoldReason::blocking_action;
  else if (nodes_.empty()) next.reason = HoldReason::no_order;
  else if (!nodes_[0].released) next.reason = HoldReason::decision_point;
  else {
    const NodeState& node = nodes_[0];
    next.hold = false;
    next.reason = HoldReason::none;
    next.node_id = node.node_id;
    next.sequence_id = node.sequence_id;
    if (node.position) {
      next.x = node.position->x;
      next.y = node.position->y;
      next.theta = node.position->theta;
      next.map_id = node.position->map_id;
    }
    if (edge_into_first_node()) next.max_speed = edges_[0].max_speed;
  }
  if (next.hold != target_.hold || next.reason != target_.reason) state_changed_ = true;
  target_ = next;
}

void Vehicle::fill_state(State& state) const noexcept {
  state.header.manufacturer = config_.manufacturer;
  state.header.serial_number = config_.serial_number;
  put(state.header.version, config_.version == Version::v2_0_0 ? "2.0.0" : "2.1.0");
  state.order_id = order_id_;
  state.order_update_id = order_update_id_;
  state.zone_set_id = zone_set_id_;
  state.last_node_id = last_node_id_;
  state.last_node_sequence_id = last_node_sequence_id_;
  state.node_states = nodes_;
  state.edge_states.clear();
  for (const HeldEdge& edge : edges_)
    (void)state.edge_states.push_back(EdgeState{edge.edge_id, edge.sequence_id, edge.released});
  state.action_states.clear();
  for (const Slot& slot : slots_)
    (void)state.action_states.push_back(
        ActionState{slot.action.action_id, slot.action.action_type, slot.status, slot.result});
  state.errors = errors_;
  state.paused = paused_;
  state.new_base_request = new_base_request_;
}

// --- errors ---------------------------------------------------------------------------------

void Vehicle::add_error(std::string_view type, std::string_view description, ErrorSource source,
                        std::initializer_list<std::pair<std::string_view, std::string_view>> references) noexcept {
  if (errors_.full()) {
    errors_.erase(errors_.begin());
    error_sources_.erase(error_sources_.begin());
    ++dropped_errors_;
  }
  VehicleError error;
  put(error.error_type, type);
  put(error.description, description);
  error.level = ErrorLevel::warning;
  for (const auto& [key, value] : references) {
    ErrorReference reference;
    put(reference.key, key);
    put(reference.value, value);
    if (!error.references.push_back(reference)) break;
  }
  (void)errors_.push_back(error);
  (void)error_sources_.push_back(source);
  state_changed_ = true;
}

void Vehicle::report_rejected_message(const VehicleError& error) noexcept {
  if (errors_.full()) {
    errors_.erase(errors_.begin());
    error_sources_.erase(error_sources_.begin());
    ++dropped_errors_;
  }
  VehicleError warning = error;
  warning.level = ErrorLevel::warning;
  (void)errors_.push_back(warning);
  (void)error_sources_.push_back(ErrorSource::order_message);
  state_changed_ = true;
}

void Vehicle::clear_errors(ErrorSource source) noexcept {
  std::size_t i = 0;
  while (i < errors_.size()) {
    if (error_sources_[i] == source) {
      errors_.erase(errors_.begin() + static_cast<std::ptrdiff_t>(i));
      error_sources_.erase(error_sources_.begin() + static_cast<std::ptrdiff_t>(i));
      state_changed_ = true;
    } else {
      ++i;
    }
  }
}

}  // namespace sen3bot::vda5050
