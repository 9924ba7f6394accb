// The VDA 5050 codec: the spec's examples decode, what is encoded decodes to the same values,
// and every rejection rule gives the errorType and the references the vehicle reports.
#include "sen3bot/vda5050/codec.hpp"

#include <gtest/gtest.h>

#include <cmath>
#include <memory>
#include <string>
#include <vector>

namespace sen3bot::vda5050 {
namespace {

// Orders and states are large: the tests keep them on the heap, the robot in static storage.
struct Codec : ::testing::Test {
  std::unique_ptr<DecodeScratch> scratch = std::make_unique<DecodeScratch>();
  std::unique_ptr<Order> order = std::make_unique<Order>();
  std::vector<char> buffer = std::vector<char>(256 * 1024);

  Decoded order_of(const std::string& text, Version v = Version::v2_1_0) { return decode_order(text, v, *order, *scratch); }
};

std::string header(std::string_view version = "2.1.0", int header_id = 7) {
  return "\"headerId\":" + std::to_string(header_id) + ",\"timestamp\":\"2017-04-15T11:40:03.12Z\",\"version\":\"" +
         std::string(version) + "\",\"manufacturer\":\"KIT\",\"serialNumber\":\"0001\"";
}

struct N {
  std::string id;
  long long seq;
  bool released = true;
  std::string extra = "";  // more members, with a leading comma
};
struct E {
  std::string id;
  long long seq;
  bool released;
  std::string start, end;
  std::string extra = "";
};

std::string order_json(const std::vector<N>& nodes, const std::vector<E>& edges, std::string_view version = "2.1.0",
                       std::string top_extra = "") {
  std::string s = "{" + header(version) + ",\"orderId\":\"1234\",\"orderUpdateId\":0" + top_extra + ",\"nodes\":[";
  for (std::size_t i = 0; i < nodes.size(); ++i) {
    const N& n = nodes[i];
    s += (i ? "," : "") + std::string("{\"nodeId\":\"") + n.id + "\",\"sequenceId\":" + std::to_string(n.seq) +
         ",\"released\":" + (n.released ? "true" : "false") + ",\"actions\":[]" + n.extra + "}";
  }
  s += "],\"edges\":[";
  for (std::size_t i = 0; i < edges.size(); ++i) {
    const E& e = edges[i];
    s += (i ? "," : "") + std::string("{\"edgeId\":\"") + e.id + "\",\"sequenceId\":" + std::to_string(e.seq) +
         ",\"released\":" + (e.released ? "true" : "false") + ",\"startNodeId\":\"" + e.start + "\",\"endNodeId\":\"" +
         e.end + "\",\"actions\":[]" + e.extra + "}";
  }
  return s + "]}";
}

// Figure 5 of the spec (pseudocode there): base f-d-g, horizon b-h.
std::string figure5(std::string_view version = "2.1.0") {
  return order_json({{"f", 0}, {"d", 2}, {"g", 4}, {"b", 6, false}, {"h", 8, false}},
                    {{"e1", 1, true, "f", "d"}, {"e3", 3, true, "d", "g"}, {"e8", 5, false, "g", "b"},
                     {"e9", 7, false, "b", "h"}},
                    version);
}

void expect_rejected(const Decoded& d, std::string_view type, std::string_view field) {
  ASSERT_FALSE(d.ok());
  EXPECT_EQ(d.error().error_type.view(), type) << d.error().description.view();
  EXPECT_EQ(d.reference("field"), field) << d.error().description.view();
  EXPECT_EQ(d.error().level, ErrorLevel::warning);
}

TEST(Timestamps, Iso8601ReadsAsUnixTime) {
  constexpr std::int64_t kJan2026 = 1'767'225'600'000'000'000;  // 2026-01-01T00:00:00Z
  std::int64_t t = 0;
  ASSERT_TRUE(parse_iso8601(iso8601(kJan2026 + 12'340'000'000).view(), t));
  EXPECT_EQ(t, kJan2026 + 12'340'000'000);
  ASSERT_TRUE(parse_iso8601("1970-01-01T00:00:01.5Z", t));
  EXPECT_EQ(t, 1'500'000'000);
  ASSERT_TRUE(parse_iso8601("2026-01-01T01:00:00+01:00", t));
  EXPECT_EQ(t, kJan2026);
  EXPECT_FALSE(parse_iso8601("2026-01-01 00:00:00Z", t));
  EXPECT_FALSE(parse_iso8601("2026-01-01T00:00:00", t));
  EXPECT_FALSE(parse_iso8601("2026-13-01T00:00:00Z", t));
  EXPECT_FALSE(parse_iso8601("", t));
  EXPECT_FALSE(parse_iso8601("9999-12-31T23:59:59Z", t));  // beyond 64-bit nanoseconds
}

TEST_F(Codec, SpecFigure5OrderDecodes) {
  for (Version v : {Version::v2_0_0, Version::v2_1_0}) {
    auto d = order_of(figure5(v == Version::v2_0_0 ? "2.0.0" : "2.1.0"), v);
    ASSERT_TRUE(d) << d.error().description.view();
    EXPECT_EQ(order->order_id, "1234");
    ASSERT_EQ(order->nodes.size(), 5u);
    ASSERT_EQ(order->edges.size(), 4u);
    EXPECT_EQ(order->nodes[2].node_id, "g");
    EXPECT_FALSE(order->nodes[3].released);
    EXPECT_EQ(order->edges[2].start_node_id, "g");
    EXPECT_EQ(order->header.header_id, 7u);
    EXPECT_EQ(order->header.timestamp, "2017-04-15T11:40:03.12Z");
  }
}

TEST_F(Codec, SpecFigure6UpdateDecodes) {
  auto d = order_of(order_json({{"g", 4}, {"b", 6}, {"h", 8}, {"i", 10, false}},
                               {{"e8", 5, true, "g", "b"}, {"e9", 7, true, "b", "h"}, {"e10", 9, false, "h", "i"}}));
  ASSERT_TRUE(d) << d.error().description.view();
  EXPECT_EQ(order->nodes.size(), 4u);
}

TEST_F(Codec, SpecParameterExampleKeepsTypes) {
  // Section 7.2's actionParameters.
  auto d = order_of(order_json(
      {{"a", 0, true,
        R"(,"actions":[{"actionType":"someAction","actionId":"x1","blockingType":"HARD","actionParameters":[)"
        R"({"key":"stationType", "value": "floor"},{"key":"weight", "value": 8.5},{"key": "loadType", "value": "pallet_eu"},)"
        R"({"key":"flags","value":{"a":[1,true]}},{"key":"ok","value":false}]}])"}},
      {}));
  // "actions" appears twice in that node: a duplicate member is malformed JSON.
  expect_rejected(d, kValidationError, "");
  EXPECT_NE(d.error().description.view().find("duplicate member name \"actions\""), std::string_view::npos);

  std::string text = order_json({{"a", 0}}, {});
  text.replace(text.find("\"actions\":[]"), 12,
               R"("actions":[{"actionType":"someAction","actionId":"x1","blockingType":"HARD","actionParameters":[)"
               R"({"key":"stationType", "value": "floor"},{"key":"weight", "value": 8.5},{"key": "loadType", "value": "pallet_eu"},)"
               R"({"key":"flags","value":{"a":[1,true]}},{"key":"ok","value":false}]}])");
  d = order_of(text);
  ASSERT_TRUE(d) << d.error().description.view();
  const Action& a = order->nodes[0].actions[0];
  EXPECT_EQ(a.blocking_type, BlockingType::hard);
  ASSERT_EQ(a.parameters.size(), 5u);
  EXPECT_EQ(a.parameters[0].value, "floor");
  EXPECT_EQ(a.parameters[0].value_type, ParameterType::string);
  EXPECT_EQ(a.parameters[1].value, "8.5");
  EXPECT_EQ(a.parameters[1].value_type, ParameterType::number);
  EXPECT_EQ(a.parameters[3].value, R"({"a":[1,true]})");
  EXPECT_EQ(a.parameters[3].value_type, ParameterType::object);
  EXPECT_EQ(a.parameters[4].value_type, ParameterType::boolean);
}

Order& sample_order(Order& o) {
  (void)o.header.timestamp.assign("2024-01-02T03:04:05.67Z");
  (void)o.header.manufacturer.assign("ACME");
  (void)o.header.serial_number.assign("0001");
  o.header.header_id = 42;
  (void)o.order_id.assign("order-\"7\"\\");
  o.order_update_id = 4294967295u;
  (void)o.zone_set_id.assign("zones");
  for (int i = 0; i < 3; ++i) {
    (void)o.nodes.emplace_back();
    Node& n = o.nodes.back();
    (void)n.node_id.assign("n" + std::to_string(i));
    n.sequence_id = static_cast<std::uint32_t>(2 * i);
    n.released = i < 2;
    if (i != 1) {
      n.position.emplace();
      n.position->x = 1.0 / 3.0 + i;
      n.position->y = -2.5e-3;
      if (i == 0) n.position->theta = 3.14159265359;
      n.position->allowed_deviation_xy = 0.1;
      (void)n.position->map_id.assign("lab");
    }
  }
  for (int i = 0; i < 2; ++i) {
    (void)o.edges.emplace_back();
    Edge& e = o.edges.back();
    (void)e.edge_id.assign("e" + std::to_string(i));
    e.sequence_id = static_cast<std::uint32_t>(2 * i + 1);
    e.released = i == 0;
    e.start_node_id = o.nodes[static_cast<std::size_t>(i)].node_id;
    e.end_node_id = o.nodes[static_cast<std::size_t>(i) + 1].node_id;
    if (i == 0) {
      e.max_speed = 0.6;
      e.orientation = -1.5;
      e.max_rotation_speed = 1.0;
    }
  }
  Action a;
  (void)a.action_type.assign("beep");
  (void)a.action_id.assign("a1");
  (void)a.action_description.assign("caf\xc3\xa9\n");
  a.blocking_type = BlockingType::soft;
  ActionParameter p;
  (void)p.key.assign("n");
  (void)p.value.assign("8.5");
  p.value_type = ParameterType::number;
  (void)a.parameters.push_back(p);
  (void)p.value.assign("8.5");
  p.value_type = ParameterType::string;
  (void)a.parameters.push_back(p);
  (void)p.value.assign("[1,{\"b\":null}]");
  p.value_type = ParameterType::array;
  (void)a.parameters.push_back(p);
  (void)o.edges[0].actions.push_back(a);
  (void)a.action_id.assign("a2");
  a.parameters.clear();
  (void)o.nodes[2].actions.push_back(a);
  return o;
}

TEST_F(Codec, OrderRoundTrips) {
  for (Version v : {Version::v2_0_0, Version::v2_1_0}) {
    auto in = std::make_unique<Order>();
    sample_order(*in);
    auto text = encode_order(*in, v, buffer);
    ASSERT_TRUE(text) << text.error().c_str();
    const std::string first(*text);
    auto d = order_of(first, v);
    ASSERT_TRUE(d) << d.error().description.view() << "\n" << first;
    EXPECT_EQ(order->header.version, to_string(v));
    EXPECT_EQ(order->order_id, in->order_id);
    EXPECT_EQ(order->order_update_id, 4294967295u);
    EXPECT_EQ(order->nodes[0].position->x, 1.0 / 3.0);
    EXPECT_EQ(*order->nodes[0].position->theta, 3.14159265359);
    EXPECT_FALSE(order->nodes[1].position.has_value());
    EXPECT_EQ(*order->edges[0].max_speed, 0.6);
    EXPECT_EQ(order->edges[0].actions[0].action_description, in->edges[0].actions[0].action_description);
    EXPECT_EQ(order->edges[0].actions[0].parameters[2].value, "[1,{\"b\":null}]");
    auto again = encode_order(*order, v, buffer);
    ASSERT_TRUE(again);
    EXPECT_EQ(*again, first);
  }
}

TEST_F(Codec, InstantActionsRoundTripAndTheOldArrayName) {
  InstantActions in;
  (void)in.header.timestamp.assign("2024-01-02T03:04:05Z");
  Action a;
  (void)a.action_type.assign("cancelOrder");
  (void)a.action_id.assign("c1");
  (void)in.actions.push_back(a);
  auto text = encode_instant_actions(in, Version::v2_0_0, buffer);
  ASSERT_TRUE(text);
  EXPECT_NE(text->find("\"actions\":[{"), std::string_view::npos);
  InstantActions out;
  ASSERT_TRUE(decode_instant_actions(*text, Version::v2_0_0, out, *scratch));
  EXPECT_EQ(out.actions[0].action_type, "cancelOrder");

  const std::string old = "{" + header("2.0.0") + R"(,"instantActions":[{"actionType":"startPause","actionId":"p","blockingType":"HARD"}]})";
  ASSERT_TRUE(decode_instant_actions(old, Version::v2_0_0, out, *scratch));
  EXPECT_EQ(out.actions[0].action_type, "startPause");
  const std::string old21 = "{" + header("2.1.0") + R"(,"instantActions":[]})";
  auto d = decode_instant_actions(old21, Version::v2_1_0, out, *scratch);
  expect_rejected(d, kValidationError, "actions");
  EXPECT_EQ(d.reference("topic"), "instantActions");

  const std::string twice = "{" + header() +
                            R"(,"actions":[{"actionType":"a","actionId":"p","blockingType":"HARD"},)"
                            R"({"actionType":"b","actionId":"p","blockingType":"NONE"}]})";
  d = decode_instant_actions(twice, Version::v2_1_0, out, *scratch);
  expect_rejected(d, kValidationError, "actions[1]");
  EXPECT_EQ(d.reference("actionId"), "p");
}

State& sample_state(State& s) {
  (void)s.header.timestamp.assign("2024-01-02T03:04:05Z");
  (void)s.header.manufacturer.assign("ACME");
  (void)s.header.serial_number.assign("0001");
  (void)s.order_id.assign("o1");
  s.order_update_id = 3;
  (void)s.last_node_id.assign("n0");
  s.last_node_sequence_id = 0;
  (void)s.node_states.emplace_back();
  (void)s.node_states.back().node_id.assign("n1");
  s.node_states.back().sequence_id = 2;
  s.node_states.back().released = true;
  s.node_states.back().position.emplace();
  (void)s.node_states.back().position->map_id.assign("lab");
  (void)s.edge_states.emplace_back();
  (void)s.edge_states.back().edge_id.assign("e0");
  s.edge_states.back().sequence_id = 1;
  s.agv_position = AgvPosition{true, 0.9, 0.05, 4.0, 7.0, -3.0, {}};
  (void)s.agv_position->map_id.assign("lab");
  s.velocity = Velocity{0.3, 0, 0.1};
  s.driving = true;
  s.distance_since_last_node = 1.25;
  (void)s.action_states.emplace_back();
  (void)s.action_states.back().action_id.assign("a1");
  (void)s.action_states.back().action_type.assign("beep");
  s.action_states.back().status = ActionStatus::running;
  s.battery.battery_charge = 87.5;
  s.battery.battery_voltage = 12.6;
  (void)s.errors.emplace_back();
  (void)s.errors.back().error_type.assign("validationError");
  (void)s.errors.back().description.assign("nodes: required field missing");
  ErrorReference r;
  (void)r.key.assign("headerId");
  (void)r.value.assign("3");
  (void)s.errors.back().references.push_back(r);
  s.e_stop = EStop::autoack;
  (void)s.maps.emplace_back();
  (void)s.maps.back().map_id.assign("lab");
  (void)s.maps.back().map_version.assign("3");
  return s;
}

TEST_F(Codec, StateRoundTripsAndMapsAreOnly21) {
  auto in = std::make_unique<State>();
  sample_state(*in);
  auto out = std::make_unique<State>();
  for (Version v : {Version::v2_0_0, Version::v2_1_0}) {
    auto text = encode_state(*in, v, buffer);
    ASSERT_TRUE(text) << text.error().c_str();
    EXPECT_EQ(text->find("\"maps\"") != std::string_view::npos, v == Version::v2_1_0);
    const std::string first(*text);
    auto d = decode_state(first, v, *out, *scratch);
    ASSERT_TRUE(d) << d.error().description.view();
    EXPECT_EQ(out->agv_position->theta, -3.0);
    EXPECT_EQ(*out->agv_position->localization_score, 0.9);
    EXPECT_EQ(out->battery.battery_charge, 87.5);
    EXPECT_EQ(out->errors[0].references[0].value, "3");
    EXPECT_EQ(out->e_stop, EStop::autoack);
    EXPECT_EQ(out->maps.size(), v == Version::v2_1_0 ? 1u : 0u);
    auto again = encode_state(*out, v, buffer);
    ASSERT_TRUE(again);
    EXPECT_EQ(*again, first);
  }
  // A 2.1 state's maps are an unknown member to a 2.0 reader.
  std::string s21(*encode_state(*in, Version::v2_1_0, buffer));
  s21.replace(s21.find("2.1.0"), 5, "2.0.0");
  ASSERT_TRUE(decode_state(s21, Version::v2_0_0, *out, *scratch));
  EXPECT_TRUE(out->maps.empty());
}

TEST_F(Codec, StateRejections) {
  auto in = std::make_unique<State>();
  sample_state(*in);
  auto out = std::make_unique<State>();
  std::string text(*encode_state(*in, Version::v2_1_0, buffer));
  std::string bad = text;
  bad.replace(bad.find("\"RUNNING\""), 9, "\"SLEEPING\"");
  auto d = decode_state(bad, Version::v2_1_0, *out, *scratch);
  expect_rejected(d, kValidationError, "actionStates[0].actionStatus");
  EXPECT_EQ(d.reference("actionId"), "a1");
  EXPECT_EQ(d.reference("orderId"), "o1");
  bad = text;
  bad.replace(bad.find(",\"safetyState\""), std::string::npos, "}");
  expect_rejected(decode_state(bad, Version::v2_1_0, *out, *scratch), kValidationError, "safetyState");
  bad = text;
  bad.replace(bad.find("\"localizationScore\":0.9"), 23, "\"localizationScore\":1.5");
  expect_rejected(decode_state(bad, Version::v2_1_0, *out, *scratch), kValidationError, "agvPosition.localizationScore");
}

TEST_F(Codec, ConnectionAndVisualization) {
  Connection c;
  (void)c.header.timestamp.assign("2017-04-15T11:40:03.12Z");
  (void)c.header.manufacturer.assign("KIT");
  (void)c.header.serial_number.assign("0001");
  c.state = ConnectionState::connection_broken;
  auto text = encode_connection(c, Version::v2_0_0, buffer);
  ASSERT_TRUE(text);
  EXPECT_EQ(*text,
            R"({"headerId":0,"timestamp":"2017-04-15T11:40:03.12Z","version":"2.0.0","manufacturer":"KIT",)"
            R"("serialNumber":"0001","connectionState":"CONNECTIONBROKEN"})");
  Connection back;
  ASSERT_TRUE(decode_connection(*text, Version::v2_0_0, back, *scratch));
  EXPECT_EQ(back.state, ConnectionState::connection_broken);
  EXPECT_EQ(back.header.manufacturer, "KIT");
  expect_rejected(decode_connection(*text, Version::v2_1_0, back, *scratch), kValidationError, "version");
  // An empty timestamp is refused on the way in, as the encoder refuses it on the way out.
  const std::string no_time = R"({"headerId":1,"timestamp":"","version":"2.0.0","manufacturer":"KIT",)"
                              R"("serialNumber":"0001","connectionState":"ONLINE"})";
  expect_rejected(decode_connection(no_time, Version::v2_0_0, back, *scratch), kValidationError, "timestamp");

  Visualization v;
  v.header = c.header;
  v.agv_position = AgvPosition{true, {}, {}, 1, 2, 0.5, {}};
  (void)v.agv_position->map_id.assign("lab");
  text = encode_visualization(v, Version::v2_1_0, buffer);
  ASSERT_TRUE(text);
  EXPECT_NE(text->find(R"("agvPosition":{"x":1,"y":2,"theta":0.5,"mapId":"lab","positionInitialized":true})"),
            std::string_view::npos);
  EXPECT_EQ(text->find("velocity"), std::string_view::npos);
}

// The centre reads the robots' poses from their visualization messages.
TEST_F(Codec, VisualizationRoundTripsAndIsChecked) {
  Visualization v;
  v.header.header_id = 42;
  (void)v.header.timestamp.assign("2017-04-15T11:40:03.12Z");
  (void)v.header.manufacturer.assign("Sen3Bot");
  (void)v.header.serial_number.assign("r1");
  v.agv_position = AgvPosition{true, 0.75, 0.05, 3.25, -1.5, -2.5, {}};
  (void)v.agv_position->map_id.assign("plant");
  v.velocity = Velocity{0.4, 0.0, -0.25};
  Visualization back;
  for (Version version : {Version::v2_0_0, Version::v2_1_0}) {
    auto text = encode_visualization(v, version, buffer);
    ASSERT_TRUE(text) << text.error().c_str();
    const std::string first(*text);
    auto d = decode_visualization(first, version, back, *scratch);
    ASSERT_TRUE(d) << d.error().description.view();
    EXPECT_EQ(back.header.header_id, 42u);
    EXPECT_EQ(back.header.version, to_string(version));
    EXPECT_EQ(back.header.serial_number, "r1");
    ASSERT_TRUE(back.agv_position.has_value());
    EXPECT_TRUE(back.agv_position->position_initialized);
    EXPECT_EQ(back.agv_position->x, 3.25);
    EXPECT_EQ(back.agv_position->y, -1.5);
    EXPECT_EQ(back.agv_position->theta, -2.5);
    EXPECT_EQ(*back.agv_position->localization_score, 0.75);
    EXPECT_EQ(*back.agv_position->deviation_range, 0.05);
    EXPECT_EQ(back.agv_position->map_id, "plant");
    ASSERT_TRUE(back.velocity.has_value());
    EXPECT_EQ(back.velocity->vx, 0.4);
    EXPECT_EQ(back.velocity->omega, -0.25);
    auto again = encode_visualization(back, version, buffer);
    ASSERT_TRUE(again);
    EXPECT_EQ(*again, first);
  }
  // Position and velocity are optional; a decode forgets the previous message's.
  Visualization bare;
  bare.header = v.header;
  std::string text(*encode_visualization(bare, Version::v2_1_0, buffer));
  ASSERT_TRUE(decode_visualization(text, Version::v2_1_0, back, *scratch));
  EXPECT_FALSE(back.agv_position.has_value());
  EXPECT_FALSE(back.velocity.has_value());

  const std::string full(*encode_visualization(v, Version::v2_1_0, buffer));
  expect_rejected(decode_visualization(full, Version::v2_0_0, back, *scratch), kValidationError, "version");
  std::string bad = full;
  bad.replace(bad.find("\"headerId\":42,"), 14, "");
  expect_rejected(decode_visualization(bad, Version::v2_1_0, back, *scratch), kValidationError, "headerId");
  bad = full;
  bad.replace(bad.find("\"mapId\":\"plant\","), 16, "");
  expect_rejected(decode_visualization(bad, Version::v2_1_0, back, *scratch), kValidationError, "agvPosition.mapId");
  bad = full;
  bad.replace(bad.find("\"x\":3.25"), 8, "\"x\":\"3\"");
  expect_rejected(decode_visualization(bad, Version::v2_1_0, back, *scratch), kValidationError, "agvPosition.x");
  bad = full;
  bad.replace(bad.find("\"localizationScore\":0.75"), 24, "\"localizationScore\":2");
  expect_rejected(decode_visualization(bad, Version::v2_1_0, back, *scratch), kValidationError,
                  "agvPosition.localizationScore");
  bad = full;
  bad.replace(bad.find("\"omega\":-0.25"), 13, "\"omega\":true");
  expect_rejected(decode_visualization(bad, Version::v2_1_0, back, *scratch), kValidationError, "velocity.omega");
  bad = full;
  bad.replace(bad.find("{\"vx\""), 1, "[");
  EXPECT_FALSE(decode_visualization(bad, Version::v2_1_0, back, *scratch));
  expect_rejected(decode_visualization("[1]", Version::v2_1_0, back, *scratch), kValidationError, "");
}

TEST_F(Codec, VersionMustMatchTheSite) {
  EXPECT_TRUE(order_of(figure5("2.1.0"), Version::v2_1_0));
  EXPECT_TRUE(order_of(figure5("2.1.7"), Version::v2_1_0));
  EXPECT_TRUE(order_of(figure5("2.0.3"), Version::v2_0_0));
  for (std::string_view v : {"2.0.0", "1.1.0", "3.1.0", "2.1", "2.1.x", "v2.1.0", "2.10.0", "2.1.0 "}) {
    auto d = order_of(figure5(v), Version::v2_1_0);
    expect_rejected(d, kValidationError, "version");
    EXPECT_EQ(d.reference("headerId"), "7");
  }
  expect_rejected(order_of(figure5("2.1.0"), Version::v2_0_0), kValidationError, "version");
}

TEST_F(Codec, SchemaViolations) {
  struct Case {
    std::string text;
    std::string_view field;
    std::string_view id_key;
    std::string_view id;
  };
  const std::vector<N> one{{"a", 0}};
  const std::vector<Case> cases{
      {"[1]", "", "", ""},
      {"{\"headerId\":1", "", "", ""},
      {order_json({{"a", 0, true, ",\"released\":1"}}, {}), "", "", ""},  // duplicate member
      {"{" + header() + R"(,"orderId":"1","nodes":[],"edges":[]})", "orderUpdateId", "", ""},
      {"{" + header() + R"(,"orderId":1,"orderUpdateId":0,"nodes":[],"edges":[]})", "orderId", "", ""},
      {"{" + header() + R"(,"orderId":"1","orderUpdateId":-1,"nodes":[],"edges":[]})", "orderUpdateId", "", ""},
      {"{" + header() + R"(,"orderId":"1","orderUpdateId":1.5,"nodes":[],"edges":[]})", "orderUpdateId", "", ""},
      {"{" + header() + R"(,"orderId":"1","orderUpdateId":0,"nodes":{},"edges":[]})", "nodes", "", ""},
      {R"({"headerId":4294967296,"timestamp":"t","version":"2.1.0","manufacturer":"m","serialNumber":"s"})", "headerId", "", ""},
      {order_json({{"a", 0}, {"b", 4294967296}}, {{"e", 1, true, "a", "b"}}), "nodes[1].sequenceId", "nodeId", "b"},
      {order_json({{"a", 0, true, ",\"nodePosition\":{\"x\":1,\"y\":2,\"theta\":4,\"mapId\":\"m\"}"}}, {}),
       "nodes[0].nodePosition.theta", "nodeId", "a"},
      {order_json({{"a", 0, true, ",\"nodePosition\":{\"x\":1,\"y\":2}"}}, {}), "nodes[0].nodePosition.mapId", "nodeId", "a"},
      {order_json({{"a", 0, true, ",\"nodePosition\":{\"x\":1,\"y\":2,\"mapId\":\"m\",\"allowedDeviationXY\":-1}"}}, {}),
       "nodes[0].nodePosition.allowedDeviationXY", "nodeId", "a"},
      {order_json({{"a", 0}, {"b", 2}}, {{"e", 1, true, "a", "b", ",\"orientation\":-3.2"}}), "edges[0].orientation", "edgeId", "e"},
      {order_json({{"a", 0}, {"b", 2}}, {{"e", 1, true, "a", "b", ",\"maxSpeed\":\"fast\""}}), "edges[0].maxSpeed", "edgeId", "e"},
      {order_json({{"a", 0}, {"b", 2}},
                  {{"e", 1, true, "a", "b", R"(,"trajectory":{"degree":0,"knotVector":[],"controlPoints":[]})"}}),
       "edges[0].trajectory.degree", "edgeId", "e"},
      {order_json({{"a", 0}, {"b", 2}},
                  {{"e", 1, true, "a", "b", R"(,"trajectory":{"degree":1,"knotVector":[0,1.5],"controlPoints":[]})"}}),
       "edges[0].trajectory.knotVector[1]", "edgeId", "e"},
      {order_json({{"a", 0}, {"b", 2}}, {{"e", 1, true, "a", "b", R"(,"corridor":{"leftWidth":-1,"rightWidth":1})"}}),
       "edges[0].corridor.leftWidth", "edgeId", "e"},
      {order_json({{"a", 0}, {"b", 2}},
                  {{"e", 1, true, "a", "b", R"(,"corridor":{"leftWidth":1,"rightWidth":1,"corridorRefPoint":"EDGE"})"}}),
       "edges[0].corridor.corridorRefPoint", "edgeId", "e"},
  };
  for (const Case& c : cases) {
    auto d = order_of(c.text);
    expect_rejected(d, kValidationError, c.field);
    if (!c.id_key.empty()) {
      EXPECT_EQ(d.reference(c.id_key), c.id) << c.text;
    }
    // The topic comes last, when there is room for it.
    if (d.error().references.size() < kMaxErrorReferences) {
      EXPECT_EQ(d.reference("topic"), "order");
    }
  }
  // Reasons read as sentences.
  auto d = order_of("{" + header() + R"(,"orderId":"1","nodes":[],"edges":[]})");
  EXPECT_EQ(d.error().description.view(), "orderUpdateId: required field missing");
  EXPECT_EQ(d.reference("headerId"), "7");
  d = order_of("[1,]");
  EXPECT_EQ(d.error().description.view(), "malformed JSON: byte 3: unexpected ']', a value expected");
}

TEST_F(Codec, ActionViolations) {
  std::string text = order_json({{"a", 0}}, {});
  const auto with_action = [&](std::string_view action) {
    std::string t = text;
    t.replace(t.find("\"actions\":[]"), 12, "\"actions\":[" + std::string(action) + "]");
    return t;
  };
  auto d = order_of(with_action(R"({"actionType":"beep","actionId":"b1","blockingType":"MEDIUM"})"));
  expect_rejected(d, kValidationError, "nodes[0].actions[0].blockingType");
  EXPECT_EQ(d.reference("actionId"), "b1");
  EXPECT_EQ(d.reference("orderId"), "1234");
  d = order_of(with_action(R"({"actionType":"beep","actionId":"b1"})"));
  expect_rejected(d, kValidationError, "nodes[0].actions[0].blockingType");
  d = order_of(with_action(R"({"actionType":"beep","actionId":"b1","blockingType":"NONE","actionParameters":[{"key":"k","value":null}]})"));
  expect_rejected(d, kValidationError, "nodes[0].actions[0].actionParameters[0].value");
  d = order_of(with_action(R"({"actionType":"beep","actionId":"b1","blockingType":"NONE","actionParameters":[{"value":1}]})"));
  expect_rejected(d, kValidationError, "nodes[0].actions[0].actionParameters[0].key");
  // The same actionId on a node and an edge.
  text = order_json({{"a", 0}, {"b", 2}}, {{"e", 1, true, "a", "b"}});
  text.replace(text.find("\"actions\":[]"), 12, R"("actions":[{"actionType":"x","actionId":"dup","blockingType":"NONE"}])");
  text.replace(text.rfind("\"actions\":[]"), 12, R"("actions":[{"actionType":"y","actionId":"dup","blockingType":"NONE"}])");
  d = order_of(text);
  expect_rejected(d, kValidationError, "edges[0].actions[0]");
  EXPECT_EQ(d.reference("actionId"), "dup");
}

TEST_F(Codec, GraphRules) {
  struct Case {
    std::string text;
    std::string_view field;
    std::string_view id_key;
    std::string_view id;
  };
  const std::vector<Case> cases{
      {order_json({}, {}), "nodes", "", ""},
      {order_json({{"a", 0}, {"b", 2}}, {}), "edges", "", ""},
      {order_json({{"a", 0}}, {{"e", 1, true, "a", "a"}}), "edges", "", ""},
      {order_json({{"a", 0}, {"b", 2}}, {{"e", 1, true, "b", "b"}}), "edges[0].startNodeId", "edgeId", "e"},
      {order_json({{"a", 0}, {"b", 2}}, {{"e", 1, true, "a", "c"}}), "edges[0].endNodeId", "edgeId", "e"},
      {order_json({{"a", 0}, {"b", 2}}, {{"e", 0, true, "a", "b"}}), "edges[0].sequenceId", "edgeId", "e"},
      {order_json({{"a", 4}, {"b", 2}}, {{"e", 5, true, "a", "b"}}), "nodes[1].sequenceId", "nodeId", "b"},
      {order_json({{"a", 0}, {"b", 2, false}, {"c", 4}}, {{"e", 1, false, "a", "b"}, {"f", 3, false, "b", "c"}}),
       "nodes[2].released", "nodeId", "c"},
      {order_json({{"a", 0}, {"b", 2, false}}, {{"e", 1, true, "a", "b"}}), "edges[0].released", "edgeId", "e"},
      {order_json({{"a", 0, false}, {"b", 2, false}}, {{"e", 1, true, "a", "b"}}), "edges[0].released", "edgeId", "e"},
      {order_json({{"a", 0}, {"b", 2}, {"c", 4}}, {{"e", 1, false, "a", "b"}, {"f", 3, true, "b", "c"}}),
       "nodes[1].released", "nodeId", "b"},
  };
  for (const Case& c : cases) {
    auto d = order_of(c.text);
    expect_rejected(d, kValidationError, c.field);
    if (!c.id_key.empty()) {
      EXPECT_EQ(d.reference(c.id_key), c.id) << c.text;
    }
    EXPECT_EQ(d.reference("orderId"), "1234");
  }
  // A horizon-only order (first node released, nothing else) and a single node are fine.
  EXPECT_TRUE(order_of(order_json({{"a", 0}, {"b", 2, false}}, {{"e", 1, false, "a", "b"}})));
  EXPECT_TRUE(order_of(order_json({{"a", 0}}, {})));
}

TEST_F(Codec, CapacityIsAnOrderErrorNamingTheField) {
  std::vector<N> nodes;
  std::vector<E> edges;
  for (int i = 0; i < 33; ++i) {
    nodes.push_back({"n" + std::to_string(i), 2 * i});
    if (i) edges.push_back({"e" + std::to_string(i), 2 * i - 1, true, "n" + std::to_string(i - 1), "n" + std::to_string(i)});
  }
  expect_rejected(order_of(order_json(nodes, edges)), kOrderError, "nodes");
  nodes.pop_back();
  edges.pop_back();
  EXPECT_TRUE(order_of(order_json(nodes, edges)));

  const std::string long_id(65, 'x');
  auto d = order_of(order_json({{long_id, 0}}, {}));
  expect_rejected(d, kOrderError, "nodes[0].nodeId");
  EXPECT_EQ(d.error().description.view(), "nodes[0].nodeId: longer than the 64 bytes this vehicle holds");
  EXPECT_TRUE(order_of(order_json({{std::string(64, 'x'), 0}}, {})));

  std::string actions = "\"actions\":[";
  for (int i = 0; i < 9; ++i)
    actions += std::string(i ? "," : "") + R"({"actionType":"t","actionId":"a)" + std::to_string(i) + R"(","blockingType":"NONE"})";
  std::string text = order_json({{"a", 0}}, {});
  text.replace(text.find("\"actions\":[]"), 12, actions + "]");
  expect_rejected(order_of(text), kOrderError, "nodes[0].actions");

  text = order_json({{"a", 0}}, {});
  text.replace(text.find("\"actions\":[]"), 12,
               R"("actions":[{"actionType":"t","actionId":"p","blockingType":"NONE","actionParameters":[{"key":"k","value":[)" +
                   std::string(200, '1') + "]}]}]");
  d = order_of(text);
  expect_rejected(d, kOrderError, "nodes[0].actions[0].actionParameters[0].value");
  EXPECT_EQ(d.reference("actionId"), "p");

  // More tokens than the decoder holds: still an orderError.
  std::string huge = "{" + header() + ",\"junk\":[";
  for (std::size_t i = 0; i < kDecodeTokens; ++i) huge += i ? ",0" : "0";
  huge += "]}";
  d = order_of(huge);
  EXPECT_EQ(d.error().error_type.view(), kOrderError);
}

TEST_F(Codec, UnknownMembersAndCorridorsByVersion) {
  const std::string corridor = R"(,"corridor":{"leftWidth":0.5,"rightWidth":0.25,"corridorRefPoint":"CONTOUR"})";
  auto text = order_json({{"a", 0, true, ",\"vendorExtension\":{\"x\":[1]}"}, {"b", 2}}, {{"e", 1, true, "a", "b", corridor}},
                         "2.1.0", ",\"somethingNew\":true");
  ASSERT_TRUE(order_of(text));
  EXPECT_TRUE(order->edges[0].has_corridor);
  // In 2.0 a corridor is just an unknown member: not checked, not flagged.
  text = order_json({{"a", 0}, {"b", 2}}, {{"e", 1, true, "a", "b", R"(,"corridor":{"leftWidth":-1})"}}, "2.0.0");
  ASSERT_TRUE(order_of(text, Version::v2_0_0));
  EXPECT_FALSE(order->edges[0].has_corridor);
  text = order_json({{"a", 0}, {"b", 2}},
                    {{"e", 1, true, "a", "b",
                      R"(,"trajectory":{"degree":1,"knotVector":[0,0,1,1],"controlPoints":[{"x":0,"y":0},{"x":1,"y":1,"weight":1}]})"}});
  ASSERT_TRUE(order_of(text));
  EXPECT_TRUE(order->edges[0].has_trajectory);
}

TEST_F(Codec, EncoderErrors) {
  auto in = std::make_unique<Order>();
  sample_order(*in);
  std::vector<char> small(100);
  auto r = encode_order(*in, Version::v2_1_0, small);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code(), Errc::capacity);
  in->nodes[0].position->x = std::nan("");
  r = encode_order(*in, Version::v2_1_0, buffer);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code(), Errc::invalid_argument);
  sample_order(*(in = std::make_unique<Order>()));
  (void)in->header.version.assign("2.0.0");
  r = encode_order(*in, Version::v2_1_0, buffer);
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().message(), "header.version 2.0.0 is not 2.1.0");
  in->header.version = Id();
  in->header.timestamp = Id();
  EXPECT_FALSE(encode_order(*in, Version::v2_1_0, buffer));
  sample_order(*(in = std::make_unique<Order>()));
  (void)in->edges[0].actions[0].parameters[0].value.assign("eight");  // typed as a number
  EXPECT_FALSE(encode_order(*in, Version::v2_1_0, buffer));
}

TEST_F(Codec, Factsheet) {
  FactsheetInfo f = sen3bot_factsheet();
  (void)f.header.timestamp.assign("2024-01-02T03:04:05Z");
  (void)f.header.manufacturer.assign("ACME");
  (void)f.header.serial_number.assign("0001");
  for (Version v : {Version::v2_0_0, Version::v2_1_0}) {
    auto text = encode_factsheet(f, v, buffer);
    ASSERT_TRUE(text) << text.error().c_str();
    json::StaticDocument<1024> doc;
    ASSERT_TRUE(doc.parse(*text));
    json::Value root = doc.root();
    EXPECT_EQ(*root.find("physicalParameters").find("speedMax").number(), 1.2);
    EXPECT_EQ(*root.find("physicalParameters").find("length").number(), 0.455);
    EXPECT_EQ(*root.find("physicalParameters").find("width").number(), 0.381);
    EXPECT_EQ(*root.find("protocolLimits").find("maxArrayLens").find("order.nodes").uint32(), kMaxNodes);
    EXPECT_EQ(root.find("protocolFeatures").find("agvActions").size(), 5u);
    EXPECT_EQ(root.find("vehicleConfig").valid(), v == Version::v2_1_0);
    EXPECT_TRUE(root.find("typeSpecification").find("agvKinematic").string_equals("DIFF"));
  }
}

TEST(Topic, BuildsAndChecksLevels) {
  char buf[64];
  auto t = make_topic(buf, "uagv", Version::v2_1_0, "ACME", "0001", "state");
  ASSERT_TRUE(t);
  EXPECT_EQ(*t, "uagv/v2/ACME/0001/state");
  EXPECT_EQ(*make_topic(buf, "uagv", Version::v2_0_0, "KIT", "A-z_0.9:x", "order"), "uagv/v2/KIT/A-z_0.9:x/order");
  EXPECT_FALSE(make_topic(buf, "uagv", Version::v2_1_0, "ACME", "00/1", "state"));
  EXPECT_FALSE(make_topic(buf, "uagv", Version::v2_1_0, "ACME", "00 1", "state"));
  EXPECT_FALSE(make_topic(buf, "uagv", Version::v2_1_0, "ACME", "", "state"));
  EXPECT_FALSE(make_topic(buf, "uagv", Version::v2_1_0, "AC/ME", "0001", "state"));
  EXPECT_FALSE(make_topic(buf, "uagv", Version::v2_1_0, "AC$ME", "0001", "state"));
  EXPECT_FALSE(make_topic(buf, "ua#gv", Version::v2_1_0, "ACME", "0001", "state"));
  EXPECT_FALSE(make_topic(buf, "uagv", Version::v2_1_0, "ACME", "0001", "status"));
  char tiny[10];
  auto r = make_topic(tiny, "uagv", Version::v2_1_0, "ACME", "0001", "state");
  ASSERT_FALSE(r);
  EXPECT_EQ(r.error().code(), Errc::capacity);
}

}  // namespace
}  // namespace sen3bot::vda5050
