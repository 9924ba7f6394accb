// The fleet scenarios' shared pieces (fleet_scenario.hpp).
#include "fleet_scenario.hpp"

#include <algorithm>
#include <cmath>

#include "sen3bot/figure/canvas.hpp"

namespace sen3bot::sim::fleet {

namespace {

// A walker who leaves the site at vanish_s.
world::MoverScript walker(std::vector<world::Point2D> path, double speed, double start_s, double vanish_s) {
  world::MoverScript m = world::walking_person(std::move(path), speed, start_s);
  m.vanish_time_s = vanish_s;
  return m;
}

}  // namespace

std::vector<FleetScenario> scenarios() {
  return {
      {"net-1",
       "One AGV and one Sen3Bot: a worker comes down the cross aisle towards the AGV lane, hidden "
       "from the AGV by the racks; the robot at the intersection sees the worker and the centre "
       "advises the AGV before the AGV's own scanner could have seen the worker.",
       {"r1"},
       {{"agv1", {{1.5, 2.0}, {12.0, 2.0}, {22.5, 2.0}}, 0.8, 6.0}},
       {walker({{11.4, 9.0}, {11.4, 0.9}}, 0.8, 4.0, 26.0)},
       55.0},
      {"net-2",
       "A 1.1 area with a moving person: two robots go to the blind intersection and both stay "
       "while the AGV's route crosses it; the AGV is stopped until the person has left.",
       {"r1", "r2"},
       {{"agv1", {{1.5, 2.0}, {12.0, 2.0}, {22.5, 2.0}}, 0.6, 5.0}},
       {walker({{11.3, 3.1}, {11.3, 0.8}}, 0.5, 2.0, 70.0)},
       110.0},
      {"net-3",
       "A workstation behind racks treated as 1.2 with static people: two robots go, one is "
       "released (p = 2) once the people are known to be static, and is then sent to the next "
       "monitoring request on the AGV's route.",
       {"r1", "r3"},
       {{"agv1", {{23.0, 8.3}, {17.0, 8.3}, {11.8, 8.3}, {11.8, 11.5}}, 0.6, 20.0}},
       {world::standing_person(19.0, 11.1), world::standing_person(20.2, 11.1)},
       140.0},
  };
}

bool write_text(const std::string& path, const std::string& text) {
  std::FILE* f = std::fopen(path.c_str(), "w");
  if (f == nullptr) return false;
  const bool ok = std::fwrite(text.data(), 1, text.size(), f) == text.size();
  return std::fclose(f) == 0 && ok;
}

figure::Rgb area_colour(ssc::AreaType type) {
  switch (type) {
    case ssc::AreaType::blind_intersection: return {255, 200, 200};
    case ssc::AreaType::transition: return {255, 230, 180};
    case ssc::AreaType::workstation: return {210, 230, 255};
    case ssc::AreaType::not_monitored: return {230, 230, 230};
  }
  return {230, 230, 230};
}

// The site at one moment: the map, the areas, the robots' trails and poses, the AGVs with their
// routes, the people; axes in metres, a legend and a title.
bool draw_site(const std::string& path, const std::string& title, const nav::OccupancyMap& map, const ssc::SiteFile& site,
               const std::vector<RobotRun>& robots, const std::vector<AgvPlan>& plans, const Snapshot& shot) {
  const double px_per_m = 40;
  const double width_m = map.width() * map.resolution_m(), height_m = map.height() * map.resolution_m();
  const int left = 70, bottom_margin = 60, top = 70, legend_w = 230;
  const int w = left + static_cast<int>(width_m * px_per_m) + legend_w, h = top + static_cast<int>(height_m * px_per_m) + bottom_margin;
  figure::Canvas canvas(w, h, {255, 255, 255});
  figure::View view{map.origin_x_m(), map.origin_y_m(), px_per_m, static_cast<double>(left), static_cast<double>(h - bottom_margin)};
  const double cell_px = map.resolution_m() * px_per_m;
  for (int row = 0; row < map.height(); ++row)
    for (int col = 0; col < map.width(); ++col)
      if (map.at(col, row) > 50) {
        const figure::Px p = view(map.origin_x_m() + col * map.resolution_m(), map.origin_y_m() + (row + 1) * map.resolution_m());
        // One pixel more than a cell, so rounding never leaves gaps between cells.
        canvas.fill_rect(static_cast<int>(p.x), static_cast<int>(p.y), static_cast<int>(std::ceil(cell_px)) + 1,
                         static_cast<int>(std::ceil(cell_px)) + 1, {60, 60, 60});
      }
  for (std::size_t i = 0; i < site.site.areas.size(); ++i) {
    const ssc::Area& a = site.site.areas[i];
    std::vector<figure::Px> outline;
    for (const ssc::Point& p : a.outline) outline.push_back(view(p.x_m, p.y_m));
    canvas.outline_polygon(outline, area_colour(a.type), 3);
    canvas.text(view(a.outline[0].x_m + 0.1, a.outline[0].y_m + 0.15),
                site.area_names[i] + " (" + std::string(ssc::to_string(a.type)) + ")",
                {150, 60, 60}, 0.45, 1, true);
  }
  for (const AgvPlan& plan : plans) {
    std::vector<figure::Px> route;
    for (const msg::Point2D& p : plan.route) route.push_back(view(p.x_m, p.y_m));
    canvas.dashed_polyline(route, {120, 120, 255}, 2, 10, 6);
  }
  const figure::Rgb robot_colours[] = {{0, 140, 0}, {0, 110, 200}, {170, 0, 170}};
  for (std::size_t i = 0; i < robots.size(); ++i) {
    std::vector<figure::Px> trail;
    for (const msg::Point2D& p : robots[i].trail) trail.push_back(view(p.x_m, p.y_m));
    if (trail.size() > 1) canvas.polyline(trail, robot_colours[i % 3], 2);
    if (i < shot.robots.size()) {
      const msg::Pose2D& r = shot.robots[i];
      canvas.disc(view(r.x_m, r.y_m), 0.26 * px_per_m, robot_colours[i % 3]);
      canvas.line(view(r.x_m, r.y_m), view(r.x_m + 0.4 * std::cos(r.theta_rad), r.y_m + 0.4 * std::sin(r.theta_rad)), {255, 255, 255}, 2);
      canvas.text(view(r.x_m + 0.3, r.y_m + 0.3), robots[i].serial, robot_colours[i % 3], 0.45, 1, true);
    }
  }
  for (std::size_t i = 0; i < shot.agvs.size(); ++i) {
    const msg::Pose2D& a = shot.agvs[i];
    const figure::Px c = view(a.x_m, a.y_m);
    canvas.fill_rect(static_cast<int>(c.x - 0.5 * px_per_m), static_cast<int>(c.y - 0.35 * px_per_m), static_cast<int>(px_per_m),
                     static_cast<int>(0.7 * px_per_m), {60, 60, 230});
    canvas.text(view(a.x_m - 0.4, a.y_m + 0.5), plans[i].serial, {60, 60, 230}, 0.45, 1, true);
  }
  for (const msg::Point2D& p : shot.people) canvas.disc(view(p.x_m, p.y_m), 0.22 * px_per_m, {230, 120, 0});
  // Axes in metres.
  canvas.line(view(0, 0), view(width_m, 0), {0, 0, 0}, 1);
  canvas.line(view(0, 0), view(0, height_m), {0, 0, 0}, 1);
  for (int x = 0; x <= static_cast<int>(width_m); x += 2) {
    canvas.line(view(x, 0), {view(x, 0).x, view(x, 0).y + 6}, {0, 0, 0}, 1);
    canvas.text({view(x, 0).x - 6, view(x, 0).y + 22}, std::to_string(x), {0, 0, 0}, 0.4);
  }
  for (int y = 0; y <= static_cast<int>(height_m); y += 2) {
    canvas.line(view(0, y), {view(0, y).x - 6, view(0, y).y}, {0, 0, 0}, 1);
    canvas.text({view(0, y).x - 30, view(0, y).y + 5}, std::to_string(y), {0, 0, 0}, 0.4);
  }
  canvas.text({view(width_m / 2, 0).x - 20, static_cast<double>(h - 12)}, "x (m)", {0, 0, 0}, 0.5);
  canvas.text({8, static_cast<double>(top) - 10}, "y (m)", {0, 0, 0}, 0.5);
  canvas.text({static_cast<double>(left), 28}, title, {0, 0, 0}, 0.6, 1);
  char when[64];
  std::snprintf(when, sizeof when, "t = %.1f s: %s", shot.t_s, shot.label.c_str());
  canvas.text({static_cast<double>(left), 54}, when, {60, 60, 60}, 0.5);
  // Legend.
  const double lx = left + width_m * px_per_m + 20;
  double ly = top + 20;
  auto entry = [&](figure::Rgb colour, const std::string& text, bool square) {
    if (square) {
      canvas.fill_rect(static_cast<int>(lx), static_cast<int>(ly - 10), 20, 14, colour);
    } else {
      canvas.disc({lx + 10, ly - 4}, 8, colour);
    }
    canvas.text({lx + 30, ly}, text, {0, 0, 0}, 0.42);
    ly += 26;
  };
  entry({0, 140, 0}, "Sen3Bot (and trail)", false);
  entry({60, 60, 230}, "AGV", true);
  entry({120, 120, 255}, "AGV route (dashed)", true);
  entry({230, 120, 0}, "person", false);
  entry({255, 200, 200}, "area 1.1 (critical)", true);
  entry({255, 230, 180}, "area 1.2 (critical)", true);
  entry({210, 230, 255}, "area 2 (workstation)", true);
  entry({60, 60, 60}, "walls and racks", true);
  return canvas.write_png(path);
}

// The plant's master control's order for one AGV: its route as a VDA 5050 order ("" when it
// does not encode).
std::string plant_order_text(const AgvPlan& plan, const ssc::SiteFile& site, std::int64_t unix_ns) {
  auto order = std::make_unique<vda5050::Order>();
  order->header.timestamp = vda5050::iso8601(unix_ns);
  (void)order->header.manufacturer.assign("PlantAGV");
  (void)order->header.serial_number.assign(plan.serial);
  (void)order->order_id.assign(std::string("plant-") + plan.serial);
  for (std::size_t i = 0; i < plan.route.size(); ++i) {
    vda5050::Node node;
    (void)node.node_id.assign("p" + std::to_string(i));
    node.sequence_id = static_cast<std::uint32_t>(2 * i);
    node.released = true;
    node.position = vda5050::NodePosition{plan.route[i].x_m, plan.route[i].y_m, std::nullopt, 0.1, 0.0, {}};
    (void)node.position->map_id.assign(site.service.map_id);
    (void)order->nodes.push_back(node);
    if (i + 1 < plan.route.size()) {
      vda5050::Edge edge;
      (void)edge.edge_id.assign("e" + std::to_string(i));
      edge.sequence_id = static_cast<std::uint32_t>(2 * i + 1);
      edge.released = true;
      (void)edge.start_node_id.assign("p" + std::to_string(i));
      (void)edge.end_node_id.assign("p" + std::to_string(i + 1));
      (void)order->edges.push_back(edge);
    }
  }
  std::vector<char> text(64 * 1024);
  auto encoded = vda5050::encode_order(*order, site.service.version, text);
  if (!encoded) return {};
  return std::string(*encoded);
}

std::string plant_topic(const AgvPlan& plan, const char* leaf) { return "uagv/v2/PlantAGV/" + std::string(plan.serial) + "/" + leaf; }

// The AGV as it would have driven without the centre: its route at its speed from its order.
msg::Pose2D unadvised_pose(const AgvPlan& plan, double t_s) {
  double left = std::max(0.0, t_s - plan.order_s) * plan.speed_m_s;
  for (std::size_t k = 0; k + 1 < plan.route.size(); ++k) {
    const msg::Point2D a = plan.route[k], b = plan.route[k + 1];
    const double length = std::hypot(b.x_m - a.x_m, b.y_m - a.y_m);
    const double heading = std::atan2(b.y_m - a.y_m, b.x_m - a.x_m);
    if (left <= length || k + 2 == plan.route.size()) {
      const double f = std::min(1.0, left / length);
      return msg::Pose2D{a.x_m + f * (b.x_m - a.x_m), a.y_m + f * (b.y_m - a.y_m), heading};
    }
    left -= length;
  }
  return msg::Pose2D{plan.route.front().x_m, plan.route.front().y_m, 0.0};
}

int fail(std::FILE* err, const std::string& message, int code) {
  std::fprintf(err, "sen3bot-sim fleet-sim: %s\n", message.c_str());
  return code;
}


// The scenario's own checks, the same in lockstep and in real time: no AGV within 1 m of a
// person, and what the scenario is about (net-1: the advice beats the AGV's scanner; net-2: both
// robots at the blind intersection; net-3: a robot released and sent on).
std::vector<std::string> scenario_failures(const FleetScenario& scenario, const std::vector<std::string>& events, double first_advice_s,
                                           double own_sensor_s, double unadvised_sensor_s, double min_agv_person_m) {
  auto count_events = [&](const char* type, const char* area, const char* robot = nullptr) {
    std::size_t n = 0;
    for (const std::string& line : events) {
      if (line.find(std::string("\"type\":\"") + type + "\"") == std::string::npos) continue;
      if (area != nullptr && line.find(std::string("\"area\":\"") + area + "\"") == std::string::npos) continue;
      if (robot != nullptr && line.find(std::string("\"") + robot + "\"") == std::string::npos) continue;
      ++n;
    }
    return n;
  };
  std::vector<std::string> failures;
  if (min_agv_person_m < 1.0) failures.push_back("an AGV came within 1 m of a person");
  if (scenario.name == std::string("net-1")) {
    if (first_advice_s < 0) failures.push_back("the AGV was never advised");
    if (first_advice_s >= 0 && own_sensor_s >= 0 && first_advice_s >= own_sensor_s)
      failures.push_back("the advice came after the AGV's own scanner could have seen the person");
    if (unadvised_sensor_s < 0) failures.push_back("unadvised, the AGV would never have met the person: the scenario shows nothing");
    if (first_advice_s >= 0 && unadvised_sensor_s >= 0 && first_advice_s >= unadvised_sensor_s)
      failures.push_back("the advice came after the unadvised AGV's scanner would have seen the person");
  } else if (scenario.name == std::string("net-2")) {
    if (count_events("allocation", "cross", "r1") == 0 || count_events("allocation", "cross", "r2") == 0)
      failures.push_back("both robots should have gone to the blind intersection");
  } else if (scenario.name == std::string("net-3")) {
    if (count_events("release", "bench") == 0) failures.push_back("no robot was released from the workstation");
    if (count_events("allocation", "dock") == 0) failures.push_back("no robot went to the next monitoring request");
  }
  return failures;
}

void write_report_head(json::Writer& w, const ReportHead& h) {
  w.begin_object().line(2).member("scenario", h.scenario);
  if (h.realtime) w.line(2).member("mode", "realtime");
  w.line(2).member_bool("ok", h.failures->empty()).line(2).key("failures").begin_array();
  for (const std::string& f : *h.failures) w.string(f);
  w.end_array().line(2).key("min_agv_person_distance_m").fixed_or_null(h.min_agv_person_m, 3);
  const auto time_or_null = [&](std::string_view key, bool known, double value) {
    w.line(2).key(key);
    if (known) w.fixed_or_null(value, 2);
    else w.null();
  };
  time_or_null("first_advice_s", h.first_advice_s >= 0, h.first_advice_s);
  time_or_null("agv_own_sensor_first_s", !h.never_in_range, h.own_sensor_s);
  time_or_null("advice_lead_s", h.first_advice_s >= 0 && !h.never_in_range, h.lead_s);
  time_or_null("unadvised_own_sensor_first_s", h.unadvised_sensor_s >= 0, h.unadvised_sensor_s);
}

// The centre's event lines (JSON objects), one a line.
void write_timeline(json::Writer& w, const std::vector<std::string>& events) {
  w.line(2).key("timeline").begin_array();
  for (const std::string& e : events) w.line(4).raw(e);
  w.line(2).end_array();
}

void write_agv_samples(json::Writer& w, const FleetScenario& scenario, const std::vector<std::vector<AgvSample>>& samples) {
  w.line(2).key("agvs").begin_array();
  for (std::size_t i = 0; i < samples.size(); ++i) {
    w.line(4).begin_object().member("serial", scenario.agvs[i].serial).key("samples").begin_array();
    for (const AgvSample& s : samples[i]) {
      w.begin_object()
          .key("t_s").fixed_or_null(s.t_s, 1)
          .key("x").fixed_or_null(s.x, 2)
          .key("y").fixed_or_null(s.y, 2)
          .key("speed_m_s").fixed_or_null(s.speed, 3)
          .member("advice", vda5050::to_string(s.advice))
          .end_object();
    }
    w.end_array().end_object();
  }
  w.line(2).end_array();
}

}  // namespace sen3bot::sim::fleet
