// The vehicle's order state machine: Figure 8's branches, node traversal, action blocking,
// instant actions and the state it reports.
#include "sen3bot/vda5050/vehicle.hpp"

#include <gtest/gtest.h>

#include <memory>
#include <string>
#include <vector>

namespace sen3bot::vda5050 {
namespace {

Id id(std::string_view text) {
  Id value;
  EXPECT_TRUE(value.assign(text));
  return value;
}

struct N {
  std::string node_id;
  std::uint32_t sequence_id = 0;
  bool released = true;
  double x = 0;
  double y = 0;
  std::optional<double> theta = std::nullopt;
  double deviation = 0;
};

// Orders are large; tests keep them on the heap. Edges join neighbours, "e<seq>".
std::unique_ptr<Order> make_order(std::string_view order_id, std::uint32_t update_id, const std::vector<N>& nodes) {
  auto order = std::make_unique<Order>();
  order->order_id = id(order_id);
  order->order_update_id = update_id;
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    Node node;
    node.node_id = id(nodes[i].node_id);
    node.sequence_id = nodes[i].sequence_id;
    node.released = nodes[i].released;
    node.position = NodePosition{nodes[i].x, nodes[i].y, nodes[i].theta, nodes[i].deviation, 0, id("map")};
    EXPECT_TRUE(order->nodes.push_back(node));
    if (i + 1 < nodes.size()) {
      Edge edge;
      edge.edge_id = id("e" + std::to_string(nodes[i].sequence_id + 1));
      edge.sequence_id = nodes[i].sequence_id + 1;
      edge.released = nodes[i + 1].released;
      edge.start_node_id = id(nodes[i].node_id);
      edge.end_node_id = id(nodes[i + 1].node_id);
      EXPECT_TRUE(order->edges.push_back(edge));
    }
  }
  return order;
}

Action action(std::string_view type, std::string_view action_id, BlockingType blocking = BlockingType::none) {
  Action a;
  a.action_type = id(type);
  a.action_id = id(action_id);
  a.blocking_type = blocking;
  return a;
}

InstantActions instant(std::initializer_list<Action> actions) {
  InstantActions message;
  for (const Action& a : actions) EXPECT_TRUE(message.actions.push_back(a));
  return message;
}

Pose at(double x, double y, double theta = 0) {
  Pose pose;
  pose.x = x;
  pose.y = y;
  pose.theta = theta;
  pose.map_id = id("map");
  pose.localized = true;
  return pose;
}

Progress moving(double x, double y, double speed = 0.5, double theta = 0) {
  Progress progress;
  progress.pose = at(x, y, theta);
  progress.speed = speed;
  return progress;
}
Progress standing(double x, double y) { return moving(x, y, 0.0); }

VehicleConfig config() {
  VehicleConfig c;
  c.manufacturer = id("sen3");
  c.serial_number = id("bot1");
  // beep: finished when triggered; pick: run by the host; signal: an instant action the host runs.
  EXPECT_TRUE(c.actions.push_back(SupportedAction{id("beep"), true, true, true, false}));
  EXPECT_TRUE(c.actions.push_back(SupportedAction{id("pick"), false, true, true, true}));
  EXPECT_TRUE(c.actions.push_back(SupportedAction{id("signal"), true, false, false, true}));
  return c;
}

class VehicleTest : public ::testing::Test {
 protected:
  std::unique_ptr<Vehicle> vehicle = std::make_unique<Vehicle>(config());
  std::unique_ptr<State> state = std::make_unique<State>();

  State& report() {
    *state = State{};
    vehicle->fill_state(*state);
    return *state;
  }
  std::vector<std::string> node_ids() {
    std::vector<std::string> ids;
    for (const NodeState& node : vehicle->node_states()) ids.emplace_back(node.node_id.view());
    return ids;
  }
  std::string status(std::string_view action_id) {
    const auto s = vehicle->action_status(action_id);
    return s ? std::string(to_string(*s)) : "none";
  }
  bool has_error(std::string_view type) {
    for (const VehicleError& e : vehicle->errors())
      if (e.error_type == type) return true;
    return false;
  }
  std::string reference(std::string_view type, std::string_view key) {
    for (const VehicleError& e : vehicle->errors())
      if (e.error_type == type)
        for (const ErrorReference& r : e.references)
          if (r.key == key) return std::string(r.value.view());
    return "none";
  }
  // a(0,0) - b(2,0) - c(4,0) released, d(6,0) - e(8,0) horizon.
  std::unique_ptr<Order> base_and_horizon(std::string_view order_id = "o1", std::uint32_t update_id = 0) {
    return make_order(order_id, update_id,
                      {{"a", 0, true, 0, 0}, {"b", 2, true, 2, 0}, {"c", 4, true, 4, 0},
                       {"d", 6, false, 6, 0}, {"e", 8, false, 8, 0}});
  }
  void drive_to(double x, double y) {
    vehicle->update(moving(x, y));
  }
};

// --- Figure 8 -------------------------------------------------------------------------------

TEST_F(VehicleTest, NewOrderAcceptedWhenIdleAndNearFirstNode) {
  EXPECT_TRUE(vehicle->target().hold);
  EXPECT_EQ(vehicle->target().reason, HoldReason::no_order);
  ASSERT_TRUE(vehicle->receive_order(*base_and_horizon(), at(0.2, 0.1)));
  EXPECT_TRUE(vehicle->state_changed());
  State& s = report();
  EXPECT_EQ(s.order_id, "o1");
  EXPECT_EQ(s.order_update_id, 0u);
  EXPECT_EQ(s.node_states.size(), 5u);
  EXPECT_EQ(s.edge_states.size(), 4u);
  EXPECT_EQ(s.header.serial_number, "bot1");
  EXPECT_TRUE(s.errors.empty());
  // The first node is where the robot stands: the first update passes it.
  EXPECT_FALSE(vehicle->target().hold);
  EXPECT_EQ(vehicle->target().node_id, "a");
  vehicle->update(standing(0.2, 0.1));
  EXPECT_EQ(vehicle->last_node_id(), "a");
  EXPECT_EQ(vehicle->target().node_id, "b");
  EXPECT_EQ(vehicle->route().size(), 2u);  // b, c: never the horizon
  EXPECT_EQ(report().edge_states.size(), 4u);
}

TEST_F(VehicleTest, NewOrderRejectedWhileExecuting) {
  ASSERT_TRUE(vehicle->receive_order(*base_and_horizon(), at(0, 0)));
  EXPECT_FALSE(vehicle->receive_order(*make_order("o2", 0, {{"x", 0, true, 0, 0}}), at(0, 0)));
  EXPECT_TRUE(has_error("orderError"));
  EXPECT_EQ(reference("orderError", "orderId"), "o2");
  EXPECT_EQ(vehicle->order_id(), "o1");
  EXPECT_EQ(node_ids().size(), 5u);
}

TEST_F(VehicleTest, NewOrderRejectedWhileOnlyWaitingForAnUpdate) {
  ASSERT_TRUE(vehicle->receive_order(*base_and_horizon(), at(0, 0)));
  drive_to(0, 0);
  drive_to(2, 0);
  drive_to(4, 0);
  EXPECT_EQ(vehicle->target().reason, HoldReason::decision_point);
  EXPECT_FALSE(vehicle->receive_order(*make_order("o2", 0, {{"c2", 0, true, 4, 0}}), at(4, 0)));
  EXPECT_TRUE(has_error("orderError"));
}

struct ReachCase {
  const char* name;
  Pose pose;
  double allowed_deviation;
  bool accepted;
};

TEST_F(VehicleTest, NewOrderStartMustBeWithinTheFirstNodesDeviation) {
  Pose other_map = at(0, 0);
  other_map.map_id = id("hall2");
  Pose lost = at(0, 0);
  lost.localized = false;
  const ReachCase cases[] = {
      {"on the node", at(0, 0), 0, true},
      {"inside the default 0.5 m", at(0.3, 0.3), 0, true},
      {"outside the default 0.5 m", at(0.4, 0.4), 0, false},
      {"inside the node's own 2 m", at(1.5, 0), 2.0, true},
      {"outside the node's own 2 m", at(2.5, 0), 2.0, false},
      {"another map", other_map, 0, false},
      {"not localized", lost, 0, false},
  };
  for (const ReachCase& c : cases) {
    SCOPED_TRACE(c.name);
    auto v = std::make_unique<Vehicle>(config());
    auto order = make_order("o1", 0, {{"a", 0, true, 0, 0, std::nullopt, c.allowed_deviation}, {"b", 2, true, 5, 0}});
    EXPECT_EQ(v->receive_order(*order, c.pose), c.accepted);
    bool no_route = false;
    for (const VehicleError& e : v->errors()) no_route = no_route || e.error_type == "noRouteError";
    EXPECT_EQ(no_route, !c.accepted);
    EXPECT_EQ(v->order_id(), c.accepted ? "o1" : "");
  }
}

TEST_F(VehicleTest, DeprecatedUpdateRejectedAndTheOldOrderKeepsRunning) {
  ASSERT_TRUE(vehicle->receive_order(*base_and_horizon("o1", 3), at(0, 0)));
  drive_to(0, 0);
  EXPECT_FALSE(vehicle->receive_order(*make_order("o1", 2, {{"c", 4, true, 4, 0}, {"d", 6, true, 6, 0}}), at(0, 0)));
  EXPECT_TRUE(has_error("orderUpdateError"));
  EXPECT_EQ(reference("orderUpdateError", "orderUpdateId"), "2");
  EXPECT_EQ(vehicle->order_update_id(), 3u);
  EXPECT_EQ(node_ids(), (std::vector<std::string>{"b", "c", "d", "e"}));
  drive_to(2, 0);
  EXPECT_EQ(vehicle->last_node_id(), "b");
  EXPECT_EQ(vehicle->target().node_id, "c");
}

TEST_F(VehicleTest, SameUpdateTwiceIsIgnored) {
  ASSERT_TRUE(vehicle->receive_order(*base_and_horizon(), at(0, 0)));
  drive_to(0, 0);
  vehicle->state_published();
  EXPECT_FALSE(vehicle->receive_order(*base_and_horizon(), at(0, 0)));
  EXPECT_TRUE(vehicle->errors().empty());
  EXPECT_FALSE(vehicle->state_changed());
  EXPECT_EQ(node_ids(), (std::vector<std::string>{"b", "c", "d", "e"}));
  EXPECT_EQ(vehicle->last_node_id(), "a");
}

TEST_F(VehicleTest, StitchingReplacesTheHorizonAndKeepsTheStitchingNode) {
  auto first = base_and_horizon();
  ASSERT_TRUE(first->nodes[2].actions.push_back(action("beep", "beep-c")));
  ASSERT_TRUE(first->nodes[3].actions.push_back(action("beep", "beep-d-old")));
  ASSERT_TRUE(vehicle->receive_order(*first, at(0, 0)));
  drive_to(0, 0);
  EXPECT_EQ(report().action_states.size(), 2u);

  // c again (moved, with an action of its own: both ignored), then a new base and horizon.
  auto update = make_order("o1", 1, {{"c", 4, true, 40, 40}, {"f", 6, true, 4, 2}, {"g", 8, false, 4, 4}});
  ASSERT_TRUE(update->nodes[0].actions.push_back(action("beep", "beep-c-again")));
  ASSERT_TRUE(update->nodes[1].actions.push_back(action("beep", "beep-f")));
  ASSERT_TRUE(vehicle->receive_order(*update, at(1, 0)));
  EXPECT_EQ(vehicle->order_update_id(), 1u);
  EXPECT_EQ(node_ids(), (std::vector<std::string>{"b", "c", "f", "g"}));
  State& s = report();
  ASSERT_EQ(s.edge_states.size(), 4u);
  EXPECT_EQ(s.edge_states[0].edge_id, "e1");
  EXPECT_EQ(s.edge_states[1].edge_id, "e3");
  EXPECT_EQ(s.edge_states[2].edge_id, "e5");
  EXPECT_TRUE(s.edge_states[2].released);
  EXPECT_FALSE(s.edge_states[3].released);
  EXPECT_EQ(s.node_states[1].position->x, 4.0);  // the first message's c
  EXPECT_EQ(status("beep-c"), "WAITING");
  EXPECT_EQ(status("beep-d-old"), "none");  // the horizon went with its actions
  EXPECT_EQ(status("beep-c-again"), "none");
  EXPECT_EQ(status("beep-f"), "WAITING");

  drive_to(2, 0);
  drive_to(4, 0);
  EXPECT_EQ(status("beep-c"), "FINISHED");
  EXPECT_EQ(vehicle->target().node_id, "f");
  drive_to(4, 2);
  EXPECT_EQ(vehicle->last_node_id(), "f");
  EXPECT_EQ(vehicle->last_node_sequence_id(), 6u);
  EXPECT_EQ(vehicle->target().reason, HoldReason::decision_point);
}

TEST_F(VehicleTest, StitchingOnceTheDecisionPointIsPassed) {
  ASSERT_TRUE(vehicle->receive_order(*base_and_horizon(), at(0, 0)));
  for (double x : {0.0, 2.0, 4.0}) drive_to(x, 0);
  EXPECT_EQ(vehicle->target().reason, HoldReason::decision_point);
  ASSERT_TRUE(vehicle->receive_order(*make_order("o1", 1, {{"c", 4, true, 4, 0}, {"d", 6, true, 6, 0}}), at(4, 0)));
  EXPECT_EQ(vehicle->target().node_id, "d");
  EXPECT_EQ(report().edge_states.size(), 1u);
  drive_to(6, 0);
  EXPECT_EQ(vehicle->last_node_id(), "d");
  EXPECT_EQ(vehicle->target().reason, HoldReason::no_order);
}

struct WrongStart {
  const char* name;
  const char* node_id;
  std::uint32_t sequence_id;
};

TEST_F(VehicleTest, UpdateNotStartingAtTheDecisionPointIsRejected) {
  const WrongStart cases[] = {
      {"another node", "b", 2},
      {"the decision point's id with another sequenceId", "c", 8},
      {"a horizon node", "d", 6},
  };
  ASSERT_TRUE(vehicle->receive_order(*base_and_horizon(), at(0, 0)));
  drive_to(0, 0);
  std::uint32_t update_id = 0;
  for (const WrongStart& c : cases) {
    SCOPED_TRACE(c.name);
    auto update = make_order("o1", ++update_id, {{c.node_id, c.sequence_id, true, 4, 0}, {"z", 20, true, 9, 9}});
    EXPECT_FALSE(vehicle->receive_order(*update, at(0, 0)));
    EXPECT_TRUE(has_error("orderUpdateError"));
    EXPECT_EQ(vehicle->order_update_id(), 0u);
    EXPECT_EQ(node_ids(), (std::vector<std::string>{"b", "c", "d", "e"}));
  }
}

TEST_F(VehicleTest, ContinuationOfACompletedOrder) {
  ASSERT_TRUE(vehicle->receive_order(*make_order("o1", 0, {{"a", 0, true, 0, 0}, {"b", 2, true, 2, 0}}), at(0, 0)));
  drive_to(0, 0);
  drive_to(2, 0);
  EXPECT_TRUE(vehicle->node_states().empty());
  EXPECT_EQ(vehicle->target().reason, HoldReason::no_order);

  // Not from the last node: rejected.
  EXPECT_FALSE(vehicle->receive_order(*make_order("o1", 1, {{"b", 4, true, 2, 0}, {"c", 6, true, 4, 0}}), at(2, 0)));
  EXPECT_TRUE(has_error("orderUpdateError"));
  // From lastNodeId / lastNodeSequenceId: taken, and the old warning goes.
  ASSERT_TRUE(vehicle->receive_order(*make_order("o1", 2, {{"b", 2, true, 2, 0}, {"c", 4, true, 4, 0}}), at(2, 0)));
  EXPECT_TRUE(vehicle->errors().empty());
  EXPECT_EQ(node_ids(), (std::vector<std::string>{"c"}));
  EXPECT_EQ(report().edge_states.size(), 1u);
  EXPECT_EQ(vehicle->target().node_id, "c");
  drive_to(4, 0);
  EXPECT_EQ(vehicle->last_node_sequence_id(), 4u);
}

TEST_F(VehicleTest, NewOrderAfterTheLastOneCompleted) {
  ASSERT_TRUE(vehicle->receive_order(*make_order("o1", 0, {{"a", 0, true, 0, 0}}), at(0, 0)));
  drive_to(0, 0);
  ASSERT_TRUE(vehicle->receive_order(*make_order("o2", 0, {{"q", 0, true, 0.1, 0}, {"r", 2, true, 3, 0}}), at(0, 0)));
  EXPECT_EQ(vehicle->order_id(), "o2");
  EXPECT_EQ(vehicle->last_node_id(), "a");  // until q is passed
  drive_to(0, 0);
  EXPECT_EQ(vehicle->last_node_id(), "q");
}

struct InvalidCase {
  const char* name;
  void (*spoil)(Order&);
  const char* reference_key;
};

TEST_F(VehicleTest, InvalidOrdersAreRejectedWithValidationError) {
  const InvalidCase cases[] = {
      {"no nodes", [](Order& o) { o.nodes.clear(); o.edges.clear(); }, "nodes"},
      {"an edge missing", [](Order& o) { o.edges.pop_back(); }, "edges"},
      {"first node not released", [](Order& o) { o.nodes[0].released = false; o.edges[0].released = false; }, "nodeId"},
      {"released after the horizon", [](Order& o) { o.nodes[4].released = true; }, "nodeId"},
      {"edge released into the horizon", [](Order& o) { o.edges[2].released = true; }, "edgeId"},
      {"edge with the wrong end", [](Order& o) { o.edges[1].end_node_id = id("x"); }, "edgeId"},
      {"sequenceIds going back", [](Order& o) { o.edges[1].sequence_id = 1; }, "edgeId"},
      {"an actionId twice", [](Order& o) {
         (void)o.nodes[1].actions.push_back(action("beep", "same"));
         (void)o.edges[2].actions.push_back(action("beep", "same"));
       }, "actionId"},
      {"empty orderId", [](Order& o) { o.order_id = Id{}; }, "orderId"},
      {"another vehicle's order", [](Order& o) { o.header.serial_number = id("bot2"); }, "serialNumber"},
  };
  for (const InvalidCase& c : cases) {
    SCOPED_TRACE(c.name);
    vehicle = std::make_unique<Vehicle>(config());
    auto order = base_and_horizon();
    c.spoil(*order);
    EXPECT_FALSE(vehicle->receive_order(*order, at(0, 0)));
    EXPECT_TRUE(has_error("validationError"));
    EXPECT_NE(reference("validationError", c.reference_key), "none");
    EXPECT_TRUE(vehicle->node_states().empty());
  }
}

TEST_F(VehicleTest, UnsupportedNodeOrEdgeActionRejectsTheOrder) {
  auto order = base_and_horizon();
  ASSERT_TRUE(order->nodes[1].actions.push_back(action("liftFork", "lift-1")));
  EXPECT_FALSE(vehicle->receive_order(*order, at(0, 0)));
  EXPECT_TRUE(has_error("orderError"));
  EXPECT_EQ(reference("orderError", "actionId"), "lift-1");
  EXPECT_EQ(reference("orderError", "actionType"), "liftFork");
  EXPECT_TRUE(vehicle->node_states().empty());

  // Instant-only types are not node actions; "signal" is instant-only here.
  vehicle = std::make_unique<Vehicle>(config());
  order = base_and_horizon();
  ASSERT_TRUE(order->edges[0].actions.push_back(action("cancelOrder", "c-1")));
  EXPECT_FALSE(vehicle->receive_order(*order, at(0, 0)));
  EXPECT_EQ(reference("orderError", "actionId"), "c-1");

  vehicle = std::make_unique<Vehicle>(config());
  order = base_and_horizon();
  ASSERT_TRUE(order->nodes[0].actions.push_back(action("signal", "s-1")));
  EXPECT_FALSE(vehicle->receive_order(*order, at(0, 0)));
  EXPECT_EQ(reference("orderError", "actionType"), "signal");
}

TEST_F(VehicleTest, NodeWithoutAPositionRejectsTheOrder) {
  auto order = base_and_horizon();
  order->nodes[2].position.reset();
  EXPECT_FALSE(vehicle->receive_order(*order, at(0, 0)));
  EXPECT_EQ(reference("orderError", "nodeId"), "c");
}

TEST_F(VehicleTest, RejectionWarningsStayUntilAnOrderIsAccepted) {
  ASSERT_TRUE(vehicle->receive_order(*base_and_horizon("o1", 5), at(0, 0)));
  EXPECT_FALSE(vehicle->receive_order(*base_and_horizon("o1", 4), at(0, 0)));
  EXPECT_FALSE(vehicle->receive_order(*make_order("o2", 0, {{"x", 0, true, 0, 0}}), at(0, 0)));
  for (double x : {0.0, 2.0}) drive_to(x, 0);
  EXPECT_TRUE(has_error("orderUpdateError"));
  EXPECT_TRUE(has_error("orderError"));
  EXPECT_EQ(report().errors.size(), 2u);
  ASSERT_TRUE(vehicle->receive_order(*make_order("o1", 6, {{"c", 4, true, 4, 0}}), at(2, 0)));
  EXPECT_TRUE(vehicle->errors().empty());
}

TEST_F(VehicleTest, OrderWhilePausedIsAccepted) {
  vehicle->receive_instant_actions(instant({action("startPause", "p1")}));
  ASSERT_TRUE(vehicle->receive_order(*base_and_horizon(), at(0, 0)));
  EXPECT_TRUE(vehicle->target().hold);
  EXPECT_EQ(vehicle->target().reason, HoldReason::paused);
  vehicle->update(standing(0, 0));
  EXPECT_EQ(vehicle->last_node_id(), "");  // no progress while paused
  vehicle->receive_instant_actions(instant({action("stopPause", "p2")}));
  vehicle->update(standing(0, 0));
  EXPECT_EQ(vehicle->last_node_id(), "a");
  EXPECT_FALSE(vehicle->target().hold);
}

// --- capacity -------------------------------------------------------------------------------

TEST_F(VehicleTest, UpdateThatWouldHoldTooManyNodesIsRejected) {
  std::vector<N> nodes;
  for (std::uint32_t i = 0; i < kMaxNodes; ++i) nodes.push_back({"n" + std::to_string(i), 2 * i, true, i * 1.0, 0});
  ASSERT_TRUE(vehicle->receive_order(*make_order("o1", 0, nodes), at(0, 0)));
  drive_to(0, 0);  // 31 nodes and 31 edges held
  std::vector<N> more{{"n31", 62, true, 31, 0}, {"n32", 64, true, 32, 0}, {"n33", 66, true, 33, 0}};
  EXPECT_FALSE(vehicle->receive_order(*make_order("o1", 1, more), at(0, 0)));
  EXPECT_TRUE(has_error("orderError"));
  EXPECT_NE(reference("orderError", "nodes"), "none");  // 31 + 2
  EXPECT_EQ(vehicle->node_states().size(), kMaxNodes - 1);
  drive_to(1, 0);  // one more passed: the nodes fit, the edges (30 + 2) do not
  EXPECT_FALSE(vehicle->receive_order(*make_order("o1", 1, more), at(1, 0)));
  EXPECT_NE(reference("orderError", "edges"), "none");
  drive_to(2, 0);
  EXPECT_TRUE(vehicle->receive_order(*make_order("o1", 1, more), at(2, 0)));
  EXPECT_EQ(vehicle->node_states().size(), kMaxNodes - 1);
  EXPECT_TRUE(vehicle->errors().empty());
}

TEST_F(VehicleTest, OrderWithTooManyActionsIsRejectedNamingActionStates) {
  std::vector<N> nodes;
  for (std::uint32_t i = 0; i < 9; ++i) nodes.push_back({"n" + std::to_string(i), 2 * i, true, i * 1.0, 0});
  auto order = make_order("o1", 0, nodes);
  std::size_t count = 0;
  for (Node& node : order->nodes)
    for (std::size_t k = 0; k < kMaxActions; ++k)
      ASSERT_TRUE(node.actions.push_back(action("beep", "b" + std::to_string(count++))));
  ASSERT_GT(count, kMaxActionStates);
  EXPECT_FALSE(vehicle->receive_order(*order, at(0, 0)));
  EXPECT_NE(reference("orderError", "actionStates"), "none");
  order->nodes[8].actions.clear();  // exactly 64
  EXPECT_TRUE(vehicle->receive_order(*order, at(0, 0)));
  EXPECT_EQ(report().action_states.size(), kMaxActionStates);
}

TEST_F(VehicleTest, FinishedActionStatesMakeRoomForAnUpdate) {
  std::vector<N> nodes{{"n0", 0, true, 0, 0}, {"n2", 2, true, 1, 0}};
  auto order = make_order("o1", 0, nodes);
  for (std::size_t k = 0; k < kMaxActions; ++k) ASSERT_TRUE(order->nodes[0].actions.push_back(action("beep", "a" + std::to_string(k))));
  ASSERT_TRUE(vehicle->receive_order(*order, at(0, 0)));
  drive_to(0, 0);
  drive_to(1, 0);
  std::uint32_t update_id = 0;
  std::uint32_t sequence_id = 2;
  double x = 1;
  // 20 updates of 8 actions each: far more than 64, the finished ones give way.
  for (int round = 0; round < 20; ++round) {
    auto next = make_order("o1", ++update_id, {{"n" + std::to_string(sequence_id), sequence_id, true, x, 0},
                                              {"n" + std::to_string(sequence_id + 2), sequence_id + 2, true, x + 1, 0}});
    for (std::size_t k = 0; k < kMaxActions; ++k)
      ASSERT_TRUE(next->nodes[1].actions.push_back(action("beep", "r" + std::to_string(round) + "-" + std::to_string(k))));
    ASSERT_TRUE(vehicle->receive_order(*next, at(x, 0))) << round;
    sequence_id += 2;
    x += 1;
    drive_to(x, 0);
    ASSERT_EQ(vehicle->last_node_sequence_id(), sequence_id);
  }
  EXPECT_LE(report().action_states.size(), kMaxActionStates);
  EXPECT_EQ(status("r19-7"), "FINISHED");
}

// --- traversal ------------------------------------------------------------------------------

TEST_F(VehicleTest, NodesAreTraversedWithinTheirDeviationAndTheRobotStopsAtTheDecisionPoint) {
  auto order = make_order("o1", 0, {{"a", 0, true, 0, 0}, {"b", 2, true, 2, 0, 1.57}, {"c", 4, true, 4, 0, std::nullopt, 1.0},
                                    {"d", 6, false, 6, 0}});
  order->edges[0].max_speed = 0.4;
  ASSERT_TRUE(vehicle->receive_order(*order, at(0, 0)));
  drive_to(0, 0);
  EXPECT_EQ(vehicle->target().node_id, "b");
  ASSERT_TRUE(vehicle->target().theta.has_value());
  EXPECT_DOUBLE_EQ(*vehicle->target().theta, 1.57);
  EXPECT_EQ(vehicle->target().max_speed, 0.4);
  ASSERT_EQ(vehicle->route().size(), 2u);
  EXPECT_EQ(vehicle->route()[1].node_id, "c");

  vehicle->update(moving(1.6, 0, 0.5, 1.57));  // 0.4 m short: within the default 0.5 m
  EXPECT_EQ(vehicle->last_node_id(), "b");
  vehicle = std::make_unique<Vehicle>(config());
  ASSERT_TRUE(vehicle->receive_order(*order, at(0, 0)));
  drive_to(0, 0);
  vehicle->update(moving(2.0, 0.1, 0.5, 0.0));  // in place but facing the wrong way
  EXPECT_EQ(vehicle->last_node_id(), "a");
  vehicle->update(moving(2.0, 0.1, 0.5, 1.4));  // within the default 0.35 rad
  EXPECT_EQ(vehicle->last_node_id(), "b");
  EXPECT_EQ(vehicle->last_node_sequence_id(), 2u);
  EXPECT_EQ(report().edge_states.size(), 2u);  // e3, e5: e1 was left
  EXPECT_FALSE(vehicle->target().max_speed.has_value());
  vehicle->update(moving(3.2, 0, 0.5));  // c allows 1 m
  EXPECT_EQ(vehicle->last_node_id(), "c");
  EXPECT_TRUE(vehicle->target().hold);
  EXPECT_EQ(vehicle->target().reason, HoldReason::decision_point);
  EXPECT_TRUE(vehicle->route().empty());
  EXPECT_EQ(node_ids(), (std::vector<std::string>{"d"}));
  EXPECT_TRUE(vehicle->new_base_request());
  EXPECT_TRUE(report().new_base_request);
  // Even standing on the horizon node, it is not passed.
  vehicle->update(standing(6, 0));
  EXPECT_EQ(vehicle->last_node_id(), "c");
}

TEST_F(VehicleTest, NewBaseRequestNearTheDecisionPointOnly) {
  auto order = make_order("o1", 0, {{"a", 0, true, 0, 0}, {"b", 2, true, 10, 0}, {"c", 4, false, 20, 0}});
  ASSERT_TRUE(vehicle->receive_order(*order, at(0, 0)));
  drive_to(0, 0);
  EXPECT_FALSE(vehicle->new_base_request());  // 10 m away
  drive_to(7.5, 0);
  EXPECT_TRUE(vehicle->new_base_request());  // within 3 m
  ASSERT_TRUE(vehicle->receive_order(*make_order("o1", 1, {{"b", 2, true, 10, 0}, {"c", 4, true, 20, 0}}), at(7.5, 0)));
  EXPECT_FALSE(vehicle->new_base_request());  // no horizon left
}

TEST_F(VehicleTest, SeveralNodesInReachPassInOneUpdate) {
  auto order = make_order("o1", 0, {{"a", 0, true, 0, 0}, {"b", 2, true, 0.1, 0}, {"c", 4, true, 0.2, 0}, {"d", 6, true, 5, 0}});
  ASSERT_TRUE(vehicle->receive_order(*order, at(0, 0)));
  drive_to(0.1, 0);
  EXPECT_EQ(vehicle->last_node_id(), "c");
  EXPECT_EQ(vehicle->target().node_id, "d");
}

TEST_F(VehicleTest, NavigationGoalReportsAreMatchedBySequenceId) {
  ASSERT_TRUE(vehicle->receive_order(*base_and_horizon(), at(0, 0)));
  drive_to(0, 0);
  Progress p = moving(1.0, 0.0);
  p.goal_reached = true;
  p.goal_sequence_id = 4;  // not the current goal
  vehicle->update(p);
  EXPECT_EQ(vehicle->last_node_id(), "a");
  p.goal_sequence_id = 2;
  p.goal_reached = false;
  p.goal_failed = true;
  vehicle->update(p);
  EXPECT_TRUE(has_error("navigationError"));
  EXPECT_EQ(reference("navigationError", "nodeId"), "b");
  p.goal_failed = false;
  p.goal_reached = true;  // the navigation's own tolerance counts
  vehicle->update(p);
  EXPECT_EQ(vehicle->last_node_id(), "b");
  EXPECT_FALSE(has_error("navigationError"));
}

// --- actions and blocking -------------------------------------------------------------------

TEST_F(VehicleTest, NodeActionsRunByTheirBlockingTypes) {
  auto order = make_order("o1", 0, {{"a", 0, true, 0, 0}, {"b", 2, true, 2, 0}, {"c", 4, true, 4, 0}});
  auto& b = order->nodes[1].actions;
  ASSERT_TRUE(b.push_back(action("pick", "none-1", BlockingType::none)));
  ASSERT_TRUE(b.push_back(action("pick", "soft-1", BlockingType::soft)));
  ASSERT_TRUE(b.push_back(action("pick", "hard-1", BlockingType::hard)));
  ASSERT_TRUE(b.push_back(action("beep", "none-2", BlockingType::none)));
  ASSERT_TRUE(vehicle->receive_order(*order, at(0, 0)));
  drive_to(0, 0);
  EXPECT_EQ(status("none-1"), "WAITING");
  drive_to(2, 0);
  EXPECT_EQ(status("none-1"), "INITIALIZING");
  EXPECT_EQ(status("soft-1"), "INITIALIZING");
  EXPECT_EQ(status("hard-1"), "WAITING");  // waits for the two before it
  EXPECT_EQ(status("none-2"), "WAITING");  // waits for the HARD one
  EXPECT_TRUE(vehicle->target().hold);
  EXPECT_EQ(vehicle->target().reason, HoldReason::blocking_action);
  ASSERT_NE(vehicle->action_to_start(), nullptr);
  EXPECT_EQ(vehicle->action_to_start()->action_id, "none-1");

  EXPECT_TRUE(vehicle->report_action("none-1", ActionStatus::running).ok());
  EXPECT_TRUE(vehicle->report_action("soft-1", ActionStatus::running).ok());
  EXPECT_EQ(vehicle->action_to_start(), nullptr);
  EXPECT_TRUE(vehicle->report_action("soft-1", ActionStatus::finished, "ok").ok());
  EXPECT_EQ(status("hard-1"), "WAITING");  // none-1 still runs
  EXPECT_TRUE(vehicle->report_action("none-1", ActionStatus::finished).ok());
  EXPECT_EQ(status("hard-1"), "INITIALIZING");
  EXPECT_TRUE(vehicle->target().hold);
  EXPECT_TRUE(vehicle->report_action("hard-1", ActionStatus::running).ok());
  EXPECT_TRUE(vehicle->report_action("hard-1", ActionStatus::failed, "no load").ok());
  EXPECT_EQ(status("none-2"), "FINISHED");
  EXPECT_FALSE(vehicle->target().hold);
  EXPECT_EQ(vehicle->target().node_id, "c");

  EXPECT_FALSE(vehicle->report_action("hard-1", ActionStatus::running).ok());  // already done
  EXPECT_FALSE(vehicle->report_action("none-2", ActionStatus::running).ok());  // not the host's
  EXPECT_FALSE(vehicle->report_action("nope", ActionStatus::running).ok());
}

TEST_F(VehicleTest, NonBlockingActionsLetTheRobotDriveOn) {
  auto order = make_order("o1", 0, {{"a", 0, true, 0, 0}, {"b", 2, true, 2, 0}, {"c", 4, true, 4, 0}});
  ASSERT_TRUE(order->nodes[1].actions.push_back(action("pick", "p", BlockingType::none)));
  ASSERT_TRUE(vehicle->receive_order(*order, at(0, 0)));
  drive_to(0, 0);
  drive_to(2, 0);
  EXPECT_EQ(status("p"), "INITIALIZING");
  EXPECT_FALSE(vehicle->target().hold);
  EXPECT_EQ(vehicle->target().node_id, "c");
}

TEST_F(VehicleTest, EdgeActionsRunWhileOnTheEdge) {
  auto order = make_order("o1", 0, {{"a", 0, true, 0, 0}, {"b", 2, true, 2, 0}, {"c", 4, true, 4, 0}});
  ASSERT_TRUE(order->edges[0].actions.push_back(action("pick", "edge-none", BlockingType::none)));
  ASSERT_TRUE(order->edges[1].actions.push_back(action("pick", "edge-soft", BlockingType::soft)));
  ASSERT_TRUE(vehicle->receive_order(*order, at(0, 0)));
  drive_to(0, 0);
  EXPECT_EQ(status("edge-none"), "INITIALIZING");  // entered with leaving a
  EXPECT_EQ(status("edge-soft"), "WAITING");
  EXPECT_TRUE(vehicle->report_action("edge-none", ActionStatus::running).ok());
  drive_to(2, 0);
  EXPECT_EQ(status("edge-none"), "FINISHED");  // the edge is left
  EXPECT_EQ(status("edge-soft"), "INITIALIZING");
  EXPECT_EQ(vehicle->target().reason, HoldReason::blocking_action);  // stands before the edge
  EXPECT_TRUE(vehicle->report_action("edge-soft", ActionStatus::finished).ok());
  EXPECT_EQ(vehicle->target().node_id, "c");
}

// --- instant actions ------------------------------------------------------------------------

TEST_F(VehicleTest, CancelOrderStopsFailsActionsAndFinishesOnceStanding) {
  auto order = base_and_horizon("o1", 2);
  ASSERT_TRUE(order->nodes[2].actions.push_back(action("beep", "later")));
  ASSERT_TRUE(order->nodes[1].actions.push_back(action("pick", "running", BlockingType::none)));
  ASSERT_TRUE(vehicle->receive_order(*order, at(0, 0)));
  drive_to(0, 0);
  drive_to(2, 0);
  ASSERT_TRUE(vehicle->report_action("running", ActionStatus::running).ok());
  vehicle->receive_instant_actions(instant({action("cancelOrder", "cancel-1")}));
  EXPECT_EQ(status("cancel-1"), "RUNNING");
  EXPECT_EQ(status("later"), "FAILED");
  EXPECT_EQ(status("running"), "FAILED");
  EXPECT_TRUE(vehicle->target().hold);
  EXPECT_EQ(vehicle->target().reason, HoldReason::cancelled);
  State& s = report();
  EXPECT_TRUE(s.node_states.empty());
  EXPECT_TRUE(s.edge_states.empty());
  EXPECT_EQ(s.order_id, "o1");
  EXPECT_EQ(s.order_update_id, 2u);
  EXPECT_EQ(s.last_node_id, "b");
  vehicle->update(moving(2.3, 0, 0.3));
  EXPECT_EQ(status("cancel-1"), "RUNNING");
  vehicle->update(standing(2.4, 0));
  EXPECT_EQ(status("cancel-1"), "FINISHED");

  // A second cancel: nothing left to cancel.
  vehicle->receive_instant_actions(instant({action("cancelOrder", "cancel-2")}));
  EXPECT_EQ(status("cancel-2"), "FAILED");
  EXPECT_EQ(reference("noOrderToCancel", "actionId"), "cancel-2");

  // 6.6.3.1: a new order from where the robot stands.
  ASSERT_TRUE(vehicle->receive_order(*make_order("o2", 0, {{"t", 0, true, 2.4, 0}, {"u", 2, true, 5, 0}}), at(2.4, 0)));
  EXPECT_FALSE(has_error("noOrderToCancel"));
  EXPECT_FALSE(vehicle->target().hold);
  EXPECT_EQ(status("cancel-1"), "none");  // finished states of the old order are cleared
}

TEST_F(VehicleTest, CancelOrderWithoutAnOrderFails) {
  vehicle->receive_instant_actions(instant({action("cancelOrder", "c1")}));
  EXPECT_EQ(status("c1"), "FAILED");
  ASSERT_TRUE(has_error("noOrderToCancel"));
  EXPECT_EQ(vehicle->errors()[0].level, ErrorLevel::warning);
  EXPECT_EQ(reference("noOrderToCancel", "actionId"), "c1");
  // Nor with a completed one.
  ASSERT_TRUE(vehicle->receive_order(*make_order("o1", 0, {{"a", 0, true, 0, 0}}), at(0, 0)));
  drive_to(0, 0);
  vehicle->receive_instant_actions(instant({action("cancelOrder", "c2")}));
  EXPECT_EQ(status("c2"), "FAILED");
  EXPECT_EQ(reference("noOrderToCancel", "actionId"), "c2");
}

TEST_F(VehicleTest, StartPauseAndStopPause) {
  ASSERT_TRUE(vehicle->receive_order(*base_and_horizon(), at(0, 0)));
  drive_to(0, 0);
  vehicle->state_published();
  vehicle->receive_instant_actions(instant({action("startPause", "p1")}));
  EXPECT_TRUE(vehicle->paused());
  EXPECT_TRUE(vehicle->state_changed());
  EXPECT_EQ(vehicle->target().reason, HoldReason::paused);
  EXPECT_EQ(status("p1"), "RUNNING");
  vehicle->update(moving(0.5, 0, 0.3));  // still braking
  EXPECT_EQ(status("p1"), "RUNNING");
  vehicle->update(standing(2, 0));  // standing on b: not passed while paused
  EXPECT_EQ(status("p1"), "FINISHED");
  EXPECT_EQ(vehicle->last_node_id(), "a");
  EXPECT_TRUE(report().paused);
  vehicle->receive_instant_actions(instant({action("stopPause", "p2")}));
  EXPECT_EQ(status("p2"), "FINISHED");
  EXPECT_FALSE(vehicle->paused());
  EXPECT_EQ(vehicle->target().node_id, "b");
  vehicle->update(standing(2, 0));
  EXPECT_EQ(vehicle->last_node_id(), "b");
}

TEST_F(VehicleTest, FactsheetAndStateRequestsFinishOncePublished) {
  vehicle->receive_instant_actions(instant({action("factsheetRequest", "f1"), action("stateRequest", "s1")}));
  EXPECT_TRUE(vehicle->factsheet_requested());
  EXPECT_TRUE(vehicle->state_changed());
  EXPECT_EQ(status("f1"), "RUNNING");
  EXPECT_EQ(status("s1"), "RUNNING");
  vehicle->factsheet_published();
  EXPECT_FALSE(vehicle->factsheet_requested());
  EXPECT_EQ(status("f1"), "FINISHED");
  vehicle->state_published();
  EXPECT_EQ(status("s1"), "FINISHED");
  EXPECT_TRUE(vehicle->state_changed());  // one more state shows it FINISHED
  vehicle->state_published();
  EXPECT_FALSE(vehicle->state_changed());
}

TEST_F(VehicleTest, UnsupportedInstantActionFailsWithAnError) {
  vehicle->receive_instant_actions(instant({action("liftFork", "l1"), action("pick", "l2")}));
  EXPECT_EQ(status("l1"), "FAILED");
  EXPECT_EQ(status("l2"), "FAILED");  // pick is not an instant action here
  EXPECT_EQ(reference("instantActionError", "actionType"), "liftFork");
  EXPECT_EQ(vehicle->errors().size(), 2u);
}

TEST_F(VehicleTest, HostRunInstantActionAndKnownIdsRunOnce) {
  vehicle->receive_instant_actions(instant({action("signal", "s1"), action("beep", "b1")}));
  EXPECT_EQ(status("s1"), "INITIALIZING");
  EXPECT_EQ(status("b1"), "FINISHED");
  ASSERT_NE(vehicle->action_to_start(), nullptr);
  EXPECT_TRUE(vehicle->report_action("s1", ActionStatus::finished).ok());
  vehicle->receive_instant_actions(instant({action("signal", "s1"), action("cancelOrder", "b1")}));
  EXPECT_EQ(status("s1"), "FINISHED");
  EXPECT_EQ(vehicle->action_to_start(), nullptr);
  EXPECT_EQ(report().action_states.size(), 2u);
  EXPECT_TRUE(vehicle->errors().empty());
}

TEST_F(VehicleTest, NewOrderClearsActionStatesButRunningInstantActions) {
  auto first = make_order("o1", 0, {{"a", 0, true, 0, 0}});
  ASSERT_TRUE(first->nodes[0].actions.push_back(action("beep", "old")));
  ASSERT_TRUE(vehicle->receive_order(*first, at(0, 0)));
  drive_to(0, 0);
  vehicle->receive_instant_actions(instant({action("signal", "s-running"), action("beep", "b-done"),
                                            action("factsheetRequest", "f-running")}));
  ASSERT_TRUE(vehicle->report_action("s-running", ActionStatus::running).ok());
  auto second = make_order("o2", 0, {{"z", 0, true, 0, 0}});
  ASSERT_TRUE(second->nodes[0].actions.push_back(action("beep", "new")));
  ASSERT_TRUE(vehicle->receive_order(*second, at(0, 0)));
  State& s = report();
  std::vector<std::string> ids;
  for (const ActionState& a : s.action_states) ids.emplace_back(a.action_id.view());
  EXPECT_EQ(ids, (std::vector<std::string>{"s-running", "f-running", "new"}));
}

TEST_F(VehicleTest, ActionIdAlreadyInUseRejectsTheOrder) {
  vehicle->receive_instant_actions(instant({action("signal", "busy")}));
  auto order = make_order("o1", 0, {{"a", 0, true, 0, 0}});
  ASSERT_TRUE(order->nodes[0].actions.push_back(action("beep", "busy")));
  EXPECT_FALSE(vehicle->receive_order(*order, at(0, 0)));
  EXPECT_EQ(reference("orderError", "actionId"), "busy");
}

TEST_F(VehicleTest, BlockingInstantActionHoldsTheRobot) {
  ASSERT_TRUE(vehicle->receive_order(*base_and_horizon(), at(0, 0)));
  drive_to(0, 0);
  vehicle->receive_instant_actions(instant({action("signal", "s", BlockingType::hard)}));
  EXPECT_EQ(vehicle->target().reason, HoldReason::blocking_action);
  EXPECT_TRUE(vehicle->report_action("s", ActionStatus::finished).ok());
  EXPECT_FALSE(vehicle->target().hold);
}

// --- errors and events ----------------------------------------------------------------------

TEST_F(VehicleTest, ErrorListIsBoundedAndDropsTheOldest) {
  for (std::size_t i = 0; i < kMaxErrors + 3; ++i)
    vehicle->receive_instant_actions(instant({action("liftFork", "l" + std::to_string(i))}));
  ASSERT_EQ(vehicle->errors().size(), kMaxErrors);
  EXPECT_EQ(vehicle->dropped_errors(), 3u);
  EXPECT_EQ(vehicle->errors()[0].references[0].value, "l3");
  EXPECT_EQ(report().errors.size(), kMaxErrors);
}

TEST_F(VehicleTest, StateChangedMarksTheEvents) {
  EXPECT_FALSE(vehicle->state_changed());
  ASSERT_TRUE(vehicle->receive_order(*base_and_horizon(), at(0, 0)));
  EXPECT_TRUE(vehicle->state_changed());  // order received
  vehicle->state_published();
  vehicle->update(moving(-1, 0));  // nowhere near
  EXPECT_FALSE(vehicle->state_changed());
  drive_to(0, 0);
  EXPECT_TRUE(vehicle->state_changed());  // node passed
  vehicle->state_published();
  drive_to(0.5, 0);
  EXPECT_FALSE(vehicle->state_changed());
  EXPECT_FALSE(vehicle->receive_order(*base_and_horizon("o2"), at(0, 0)));
  EXPECT_TRUE(vehicle->state_changed());  // error added
  vehicle->state_published();
  for (double x : {2.0, 4.0}) drive_to(x, 0);
  EXPECT_TRUE(vehicle->state_changed());  // nodes passed, holding at the decision point
}

}  // namespace
}  // namespace sen3bot::vda5050
