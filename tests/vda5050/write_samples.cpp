// write_samples DIR: writes one representative message of every encoded type, for 2.0.0 and
// 2.1.0, as DIR/<version>/<topic>.json, and Sen3Bot's own messages as DIR/sen3bot/<topic>.json
// (when that folder exists), for validate_schemas.py to check against the schemas.
#include <array>
#include <cstdio>
#include <filesystem>
#include <string>

#include "sen3bot/vda5050/codec.hpp"
#include "sen3bot/vda5050/extensions.hpp"

namespace {

using namespace sen3bot::vda5050;

Header header(std::uint32_t id) {
  Header h;
  h.header_id = id;
  (void)h.timestamp.assign("2024-05-06T07:08:09.10Z");
  (void)h.manufacturer.assign("ACME");
  (void)h.serial_number.assign("0001");
  return h;
}

Action action(const char* type, const char* id, BlockingType blocking) {
  Action a;
  (void)a.action_type.assign(type);
  (void)a.action_id.assign(id);
  a.blocking_type = blocking;
  return a;
}

ActionParameter parameter(const char* key, const char* value, ParameterType type) {
  ActionParameter p;
  (void)p.key.assign(key);
  (void)p.value.assign(value);
  p.value_type = type;
  return p;
}

void fill_order(Order& o) {
  o.header = header(1);
  (void)o.order_id.assign("order-1");
  o.order_update_id = 2;
  (void)o.zone_set_id.assign("lab-zones");
  const char* ids[] = {"n0", "n1", "n2"};
  for (std::size_t i = 0; i < 3; ++i) {
    (void)o.nodes.emplace_back();
    Node& n = o.nodes.back();
    (void)n.node_id.assign(ids[i]);
    n.sequence_id = static_cast<std::uint32_t>(2 * i);
    n.released = i < 2;
    n.position.emplace();
    n.position->x = 4.0 - static_cast<double>(i);
    n.position->y = 7.0 - 2.5 * static_cast<double>(i);
    n.position->theta = -1.5707963267948966;
    n.position->allowed_deviation_xy = 0.2;
    n.position->allowed_deviation_theta = 0.3;
    (void)n.position->map_id.assign("lab");
  }
  for (std::size_t i = 0; i < 2; ++i) {
    (void)o.edges.emplace_back();
    Edge& e = o.edges.back();
    (void)e.edge_id.assign(i ? "e1" : "e0");
    e.sequence_id = static_cast<std::uint32_t>(2 * i + 1);
    e.released = i == 0;
    e.start_node_id = o.nodes[i].node_id;
    e.end_node_id = o.nodes[i + 1].node_id;
    e.max_speed = 0.6;
    e.max_rotation_speed = 1.0;
    e.orientation = 0.0;
  }
  Action beep = action("beep", "a-beep", BlockingType::none);
  (void)beep.action_description.assign("sound the buzzer");
  (void)beep.parameters.push_back(parameter("duration", "0.5", ParameterType::number));
  (void)beep.parameters.push_back(parameter("tone", "high", ParameterType::string));
  (void)beep.parameters.push_back(parameter("loud", "true", ParameterType::boolean));
  (void)beep.parameters.push_back(parameter("pattern", "[1,0,1]", ParameterType::array));
  (void)beep.parameters.push_back(parameter("extra", "{\"a\":1}", ParameterType::object));
  (void)o.nodes[1].actions.push_back(beep);
  (void)o.edges[0].actions.push_back(action("warnPeople", "a-warn", BlockingType::soft));
}

void fill_state(State& s) {
  s.header = header(3);
  (void)s.order_id.assign("order-1");
  s.order_update_id = 2;
  (void)s.zone_set_id.assign("lab-zones");
  (void)s.last_node_id.assign("n0");
  s.last_node_sequence_id = 0;
  (void)s.node_states.emplace_back();
  (void)s.node_states.back().node_id.assign("n1");
  s.node_states.back().sequence_id = 2;
  s.node_states.back().released = true;
  s.node_states.back().position.emplace();
  s.node_states.back().position->x = 3;
  s.node_states.back().position->y = 4.5;
  s.node_states.back().position->theta = 0.25;
  (void)s.node_states.back().position->map_id.assign("lab");
  (void)s.edge_states.emplace_back();
  (void)s.edge_states.back().edge_id.assign("e0");
  s.edge_states.back().sequence_id = 1;
  s.edge_states.back().released = true;
  s.agv_position.emplace();
  s.agv_position->position_initialized = true;
  s.agv_position->localization_score = 0.93;
  s.agv_position->deviation_range = 0.05;
  s.agv_position->x = 3.9;
  s.agv_position->y = 6.8;
  s.agv_position->theta = -1.55;
  (void)s.agv_position->map_id.assign("lab");
  s.velocity = Velocity{0.4, 0, 0.05};
  s.driving = true;
  s.distance_since_last_node = 0.31;
  const ActionStatus statuses[] = {ActionStatus::waiting, ActionStatus::running, ActionStatus::finished};
  const char* ids[] = {"a-beep", "a-warn", "a-init"};
  for (std::size_t i = 0; i < 3; ++i) {
    (void)s.action_states.emplace_back();
    ActionState& a = s.action_states.back();
    (void)a.action_id.assign(ids[i]);
    (void)a.action_type.assign("beep");
    a.status = statuses[i];
    if (i == 2) (void)a.result_description.assign("done");
  }
  s.battery.battery_charge = 81.5;
  s.battery.battery_voltage = 12.4;
  s.battery.charging = false;
  s.operating_mode = OperatingMode::automatic;
  (void)s.errors.emplace_back();
  VehicleError& e = s.errors.back();
  (void)e.error_type.assign("orderError");
  (void)e.description.assign("nodes[0].nodeId: longer than the 64 bytes this vehicle holds");
  ErrorReference r;
  (void)r.key.assign("orderId");
  (void)r.value.assign("order-0");
  (void)e.references.push_back(r);
  s.e_stop = EStop::none;
  s.field_violation = false;
  (void)s.maps.emplace_back();
  (void)s.maps.back().map_id.assign("lab");
  (void)s.maps.back().map_version.assign("3");
  (void)s.maps.back().map_description.assign("8 x 9.5 m lab");
}

bool save(const std::string& path, sen3bot::Result<std::string_view> text) {
  if (!text) {
    std::fprintf(stderr, "write_samples: %s: %s\n", path.c_str(), text.error().c_str());
    return false;
  }
  std::FILE* f = std::fopen(path.c_str(), "wb");
  if (!f) {
    std::perror(path.c_str());
    return false;
  }
  const bool ok = std::fwrite(text->data(), 1, text->size(), f) == text->size();
  return std::fclose(f) == 0 && ok;
}

}  // namespace

int main(int argc, char** argv) {
  if (argc != 2) {
    std::fprintf(stderr, "usage: write_samples DIR (DIR/2.0.0 and DIR/2.1.0 must exist; DIR/sen3bot may)\n");
    return 2;
  }
  static Order order;
  static State state;
  static std::array<char, 1 << 18> buf;
  fill_order(order);
  fill_state(state);
  InstantActions instant;
  instant.header = header(2);
  (void)instant.actions.push_back(action("cancelOrder", "i-cancel", BlockingType::hard));
  (void)instant.actions.push_back(action("stateRequest", "i-state", BlockingType::none));
  Connection connection;
  connection.header = header(4);
  connection.state = ConnectionState::online;
  Visualization visualization;
  visualization.header = header(5);
  visualization.agv_position = state.agv_position;
  visualization.velocity = state.velocity;
  FactsheetInfo factsheet = sen3bot_factsheet();
  factsheet.header = header(6);
  bool ok = true;
  for (Version v : {Version::v2_0_0, Version::v2_1_0}) {
    const std::string dir = std::string(argv[1]) + "/" + std::string(to_string(v)) + "/";
    ok = save(dir + "order.json", encode_order(order, v, buf)) && ok;
    ok = save(dir + "instantActions.json", encode_instant_actions(instant, v, buf)) && ok;
    ok = save(dir + "state.json", encode_state(state, v, buf)) && ok;
    ok = save(dir + "connection.json", encode_connection(connection, v, buf)) && ok;
    ok = save(dir + "visualization.json", encode_visualization(visualization, v, buf)) && ok;
    ok = save(dir + "factsheet.json", encode_factsheet(factsheet, v, buf)) && ok;
  }
  const std::string own = std::string(argv[1]) + "/sen3bot/";
  if (std::filesystem::is_directory(own)) {
    PeopleMessage people;
    people.header_id = 8;
    people.timestamp = header(0).timestamp;
    (void)people.manufacturer.assign("Sen3Bot");
    (void)people.serial_number.assign("r1");
    (void)people.map_id.assign("lab");
    people.robot_valid = true;
    people.robot_x = 2.5;
    people.robot_y = 2.0;
    people.robot_theta = 1.5;
    (void)people.people.push_back(PersonReport{3, 4.0, 5.5, 0.4, -0.2, 0.5, 1.0, true, 0.1, 14});
    (void)people.people.push_back(PersonReport{5, 1.0, 6.0, 0.0, 0.0, 0.4, 1.2, false, 4.5, 0, true, 0.7});
    AdvisoryMessage advisory;
    advisory.header_id = 9;
    advisory.timestamp = header(0).timestamp;
    (void)advisory.agv_manufacturer.assign("PlantAGV");
    (void)advisory.agv_serial_number.assign("agv1");
    advisory.advice = AdviceKind::slow;
    advisory.speed_factor = 0.3;
    (void)advisory.area_id.assign("cross-1");
    (void)advisory.area_type.assign("1.1");
    advisory.people = 1;
    advisory.distance_to_area_m = 7.5;
    (void)advisory.reason.assign("1 person in 1.1 area cross-1");
    FormationCommand formation;
    formation.header_id = 10;
    formation.timestamp = header(0).timestamp;
    (void)formation.manufacturer.assign("Sen3Bot");
    (void)formation.serial_number.assign("r2");
    formation.v = 0.3;
    formation.omega = -0.2;
    formation.hold_s = 0.5;
    ok = save(own + "people.json", encode_people(people, buf)) && ok;
    ok = save(own + "advisory.json", encode_advisory(advisory, buf)) && ok;
    ok = save(own + "formation.json", encode_formation(formation, buf)) && ok;
  }
  return ok ? 0 : 1;
}
