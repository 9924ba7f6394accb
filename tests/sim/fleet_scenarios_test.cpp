// The fleet's three scenarios end to end (sen3bot-sim fleet-sim): whole robots, plant AGVs and
// the Sensors Synergy Centre on one in-process broker, judged from report.json.
#include <gtest/gtest.h>

#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <vector>

#include "sen3bot/json/json.hpp"
#include "sim_commands.hpp"
#include "text_file.hpp"

namespace sen3bot::sim {
namespace {

using testing::read_file;
namespace json = sen3bot::json;

struct Event {
  double t_s;
  std::string type;
  std::vector<std::string> robots;
  std::string agv;
  std::string area;
  std::string reason;
};

struct Report {
  int code = -1;
  std::string text;
  std::unique_ptr<json::StaticDocument<32768>> doc = std::make_unique<json::StaticDocument<32768>>();
  std::vector<Event> timeline;

  double number(const char* key) const {
    const json::Value v = doc->root().find(key);
    return v.is(json::Type::number) ? *v.number() : -1.0;
  }
  bool is_null(const char* key) const { return doc->root().find(key).is(json::Type::null); }
  // The first event of the type whose reason contains `words` (and area, when given); nullptr if none.
  const Event* find(const std::string& type, const std::string& words, const std::string& area = {}) const {
    for (const Event& e : timeline)
      if (e.type == type && e.reason.find(words) != std::string::npos && (area.empty() || e.area == area)) return &e;
    return nullptr;
  }
};

std::string text_of(const json::Value& v) {
  std::array<char, 512> buf{};
  auto n = v.string(buf);
  return n ? std::string(buf.data(), *n) : std::string();
}

Report run(const char* scenario) {
  Report r;
  char dir[] = "/tmp/sen3bot-fleet-sim-XXXXXX";
  EXPECT_NE(::mkdtemp(dir), nullptr);
  std::string capture = std::string(dir) + "/messages";
  std::vector<char*> argv = {const_cast<char*>("--scenario"), const_cast<char*>(scenario), const_cast<char*>("--report"), dir,
                             const_cast<char*>("--capture"), capture.data()};
  std::FILE* out = std::tmpfile();
  std::FILE* err = std::tmpfile();
  r.code = fleet_command(static_cast<int>(argv.size()), argv.data(), out, err);
  std::fclose(out);
  std::fclose(err);
  r.text = read_file(std::string(dir) + "/report.json");
  const Status parsed = r.doc->parse(r.text);
  EXPECT_TRUE(parsed.ok()) << (parsed.ok() ? "" : parsed.error().c_str());
  if (parsed.ok()) {
    for (json::Value e : r.doc->root().find("timeline").items()) {
      Event event;
      event.t_s = *e.find("timeS").number();
      event.type = text_of(e.find("type"));
      for (json::Value robot : e.find("robots").items()) event.robots.push_back(text_of(robot));
      event.agv = text_of(e.find("agv"));
      event.area = text_of(e.find("area"));
      event.reason = text_of(e.find("reason"));
      r.timeline.push_back(std::move(event));
    }
  }
  EXPECT_NE(read_file(std::string(dir) + "/site_1.png").size(), 0u);
  // Every message anyone sent on the site's broker (robots, AGVs, the centre's orders, cancels
  // and advisories) against the shipped schemas.
  const std::string check = std::string("python3 ") + SEN3BOT_SOURCE_DIR + "/tests/vda5050/validate_messages.py " + capture +
                            " 2.1.0 " + SEN3BOT_SOURCE_DIR + "/docs/vda5050/schemas " + SEN3BOT_SOURCE_DIR + "/docs/fleet";
  EXPECT_EQ(std::system(check.c_str()), 0) << check;
  EXPECT_NE(read_file(capture + "/advisory.1.json").size(), 0u);
  EXPECT_NE(read_file(capture + "/order.1.json").size(), 0u);
  std::system((std::string("rm -rf ") + dir).c_str());
  return r;
}

TEST(FleetScenarios, Net1TheAgvIsAdvisedBeforeItsOwnScannerCouldHaveSeenThePerson) {
  const Report r = run("net-1");
  EXPECT_EQ(r.code, 0);
  const double advised = r.number("first_advice_s");
  const double unadvised = r.number("unadvised_own_sensor_first_s");
  ASSERT_GT(advised, 0);
  ASSERT_GT(unadvised, 0) << "the scenario must bring the unadvised AGV and the person together";
  EXPECT_LT(advised, unadvised);
  EXPECT_GE(r.number("min_agv_person_distance_m"), 1.0);
  const Event* slow = r.find("advisory", "SLOW");
  ASSERT_NE(slow, nullptr);
  EXPECT_EQ(slow->area, "cross");
  const Event* allocated = r.find("allocation", "monitors cross");
  ASSERT_NE(allocated, nullptr);
  EXPECT_LT(allocated->t_s, slow->t_s);
  EXPECT_NE(r.find("advisory", "CLEAR", ""), nullptr);
  EXPECT_NE(r.find("release", "has passed cross"), nullptr);
}

TEST(FleetScenarios, Net2TwoRobotsGoToTheBlindIntersectionAndBothStayUntilTheAgvHasPassed) {
  const Report r = run("net-2");
  EXPECT_EQ(r.code, 0);
  const Event* passed = r.find("release", "has passed cross");
  ASSERT_NE(passed, nullptr);
  int allocated = 0;
  for (const Event& e : r.timeline) {
    if (e.type == "allocation" && e.area == "cross") ++allocated;
    // Nobody leaves the coalition while the AGV still has the area ahead.
    if (e.type == "release" && e.area == "cross" && !e.robots.empty()) {
      EXPECT_GE(e.t_s, passed->t_s) << e.reason;
    }
  }
  EXPECT_EQ(allocated, 2);
  EXPECT_NE(r.find("coalition", "dynamic people"), nullptr);
  EXPECT_NE(r.find("advisory", "STOP"), nullptr);
  EXPECT_GE(r.number("min_agv_person_distance_m"), 1.0);
}

TEST(FleetScenarios, Net3OneRobotIsReleasedFromStaticPeopleAndSentToTheNextRequest) {
  const Report r = run("net-3");
  EXPECT_EQ(r.code, 0);
  const Event* released = r.find("release", "static people", "bench");
  ASSERT_NE(released, nullptr);
  ASSERT_EQ(released->robots.size(), 1u);
  const std::string robot = released->robots[0];
  const Event* passed = r.find("release", "has passed bench");
  ASSERT_NE(passed, nullptr);
  EXPECT_LT(released->t_s, passed->t_s) << "released while the AGV still had the area ahead";
  bool sent_on = false;
  for (const Event& e : r.timeline)
    if (e.type == "allocation" && e.area == "dock" && e.t_s > released->t_s && !e.robots.empty() && e.robots[0] == robot) sent_on = true;
  EXPECT_TRUE(sent_on) << robot << " should have been sent on to the dock";
}

}  // namespace
}  // namespace sen3bot::sim
