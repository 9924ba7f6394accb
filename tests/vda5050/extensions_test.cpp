// Sen3Bot's own fleet messages: the people report, the advisory and the formation command,
// round trips and refusals.
#include <gtest/gtest.h>

#include <array>
#include <cmath>
#include <memory>
#include <string>

#include "sen3bot/vda5050/extensions.hpp"

namespace sen3bot::vda5050 {
namespace {

TEST(PeopleMessage, RoundTripsEveryField) {
  auto scratch = std::make_unique<DecodeScratch>();
  PeopleMessage m;
  m.header_id = 7;
  (void)m.timestamp.assign("2026-12-03T15:04:13.25Z");
  (void)m.manufacturer.assign("Sen3Bot");
  (void)m.serial_number.assign("r1");
  (void)m.map_id.assign("lab");
  m.robot_valid = true;
  m.robot_x = 2.5;
  m.robot_y = -1.25;
  m.robot_theta = 3.0;
  (void)m.people.push_back(PersonReport{4, 1.5, 2.5, 0.3, -0.1, 0.45, 0.95, true, 0.2, 17});
  (void)m.people.push_back(PersonReport{9, -3.0, 0.0, 0.0, 0.0, 0.5, 1.0, false, 0.0, 4});
  m.people[1].hidden = true;
  m.people[1].position_sigma = 0.75;
  std::array<char, 4096> out{};
  auto text = encode_people(m, out);
  ASSERT_TRUE(text.ok()) << text.error().c_str();
  PeopleMessage back;
  ASSERT_TRUE(decode_people(*text, back, *scratch).ok());
  EXPECT_EQ(back.header_id, 7u);
  EXPECT_EQ(back.serial_number, "r1");
  EXPECT_TRUE(back.robot_valid);
  EXPECT_DOUBLE_EQ(back.robot_y, -1.25);
  ASSERT_EQ(back.people.size(), 2u);
  EXPECT_EQ(back.people[0].id, 4u);
  EXPECT_DOUBLE_EQ(back.people[0].vx, 0.3);
  EXPECT_TRUE(back.people[0].dynamic);
  EXPECT_FALSE(back.people[1].dynamic);
  EXPECT_EQ(back.people[1].laser_points, 4u);
  EXPECT_FALSE(back.people[0].hidden);
  EXPECT_TRUE(back.people[1].hidden);
  EXPECT_DOUBLE_EQ(back.people[1].position_sigma, 0.75);
}

TEST(PeopleMessage, RefusesWhatTheSchemaDoesNot) {
  auto scratch = std::make_unique<DecodeScratch>();
  PeopleMessage m;
  const std::string head =
      R"({"schemaVersion":"1.0.0","headerId":1,"timestamp":"t","manufacturer":"m","serialNumber":"s","mapId":"lab",)"
      R"("robot":{"positionInitialized":true,"x":0,"y":0,"theta":0},"people":)";
  EXPECT_TRUE(decode_people(head + "[]}", m, *scratch).ok());
  const Status other_major = decode_people(R"({"schemaVersion":"2.0.0"})", m, *scratch);
  ASSERT_FALSE(other_major.ok());
  EXPECT_EQ(other_major.error().code(), Errc::not_supported);
  const Status bad_state = decode_people(
      head + R"([{"id":1,"x":0,"y":0,"vx":0,"vy":0,"width":0,"cageRadius":0,"state":"RUNNING","ageS":0,"laserPoints":0}]})", m,
      *scratch);
  EXPECT_FALSE(bad_state.ok());
  // A 1.0 person (no hidden, no positionSigma) reads as seen; 1.1's fields of the wrong type do not read.
  const std::string person = R"({"id":1,"x":0,"y":0,"vx":0,"vy":0,"width":0,"cageRadius":0,"state":"STATIC","ageS":0,"laserPoints":0)";
  ASSERT_TRUE(decode_people(head + "[" + person + "}]}", m, *scratch).ok());
  ASSERT_EQ(m.people.size(), 1u);
  EXPECT_FALSE(m.people[0].hidden);
  EXPECT_EQ(m.people[0].position_sigma, 0.0);
  const Status bad_hidden = decode_people(head + "[" + person + R"(,"hidden":"yes"}]})", m, *scratch);
  ASSERT_FALSE(bad_hidden.ok());
  EXPECT_NE(std::string(bad_hidden.error().c_str()).find("'hidden'"), std::string::npos) << bad_hidden.error().c_str();
  EXPECT_FALSE(decode_people(head + "[" + person + R"(,"positionSigma":true}]})", m, *scratch).ok());
  const Status missing = decode_people(head + R"([{"id":1}]})", m, *scratch);
  ASSERT_FALSE(missing.ok());
  EXPECT_NE(std::string(missing.error().c_str()).find("'x'"), std::string::npos) << missing.error().c_str();
  std::string many = head + "[";
  for (int i = 0; i < 17; ++i)
    many += std::string(i ? "," : "") +
            R"({"id":1,"x":0,"y":0,"vx":0,"vy":0,"width":0,"cageRadius":0,"state":"STATIC","ageS":0,"laserPoints":0})";
  const Status too_many = decode_people(many + "]}", m, *scratch);
  ASSERT_FALSE(too_many.ok());
  EXPECT_EQ(too_many.error().code(), Errc::capacity);
  EXPECT_FALSE(decode_people("{not json", m, *scratch).ok());
}

TEST(AdvisoryMessage, RoundTripsAndChecksTheAdviceAndFactor) {
  auto scratch = std::make_unique<DecodeScratch>();
  AdvisoryMessage m;
  m.header_id = 3;
  (void)m.timestamp.assign("2026-12-03T15:04:13.25Z");
  (void)m.agv_manufacturer.assign("PlantAGV");
  (void)m.agv_serial_number.assign("agv1");
  m.advice = AdviceKind::slow;
  m.speed_factor = 0.3;
  (void)m.area_id.assign("cross-1");
  (void)m.area_type.assign("1.1");
  m.people = 2;
  m.dynamic_people = 1;
  m.distance_to_area_m = 7.5;
  (void)m.reason.assign("2 people in 1.1 area cross-1, 7.5 m ahead");
  std::array<char, 2048> out{};
  auto text = encode_advisory(m, out);
  ASSERT_TRUE(text.ok());
  AdvisoryMessage back;
  ASSERT_TRUE(decode_advisory(*text, back, *scratch).ok());
  EXPECT_EQ(back.advice, AdviceKind::slow);
  EXPECT_DOUBLE_EQ(back.speed_factor, 0.3);
  EXPECT_EQ(back.area_type, "1.1");
  EXPECT_EQ(back.dynamic_people, 1u);
  EXPECT_EQ(back.reason, m.reason.view());
  std::string wrong(*text);
  wrong.replace(wrong.find("SLOW"), 4, "FAST");
  EXPECT_FALSE(decode_advisory(wrong, back, *scratch).ok());
  std::string factor(*text);
  factor.replace(factor.find("0.3"), 3, "1.5");
  EXPECT_FALSE(decode_advisory(factor, back, *scratch).ok());
  EXPECT_EQ(advisory_topic("PlantAGV", "agv1"), "sen3bot/v1/advisory/PlantAGV/agv1");
  EXPECT_EQ(people_topic("Sen3Bot", "r1"), "sen3bot/v1/people/Sen3Bot/r1");
}

FormationCommand formation_sample() {
  FormationCommand m;
  m.header_id = 12;
  (void)m.timestamp.assign("2026-12-03T15:04:13.25Z");
  (void)m.manufacturer.assign("Sen3Bot");
  (void)m.serial_number.assign("r2");
  m.v = 0.35;
  m.omega = -0.125;
  m.hold_s = 0.5;
  return m;
}

TEST(FormationCommand, RoundTripsEveryFieldAndNamesItsTopic) {
  auto scratch = std::make_unique<DecodeScratch>();
  const FormationCommand m = formation_sample();
  std::array<char, 512> out{};
  auto text = encode_formation(m, out);
  ASSERT_TRUE(text.ok()) << text.error().c_str();
  EXPECT_EQ(*text,
            R"({"schemaVersion":"1.0.0","headerId":12,"timestamp":"2026-12-03T15:04:13.25Z","manufacturer":"Sen3Bot",)"
            R"("serialNumber":"r2","v":0.35,"omega":-0.125,"holdS":0.5})");
  FormationCommand back;
  ASSERT_TRUE(decode_formation(*text, back, *scratch).ok());
  EXPECT_EQ(back.header_id, 12u);
  EXPECT_EQ(back.timestamp, m.timestamp.view());
  EXPECT_EQ(back.manufacturer, "Sen3Bot");
  EXPECT_EQ(back.serial_number, "r2");
  EXPECT_EQ(back.v, 0.35);
  EXPECT_EQ(back.omega, -0.125);
  EXPECT_EQ(back.hold_s, 0.5);
  std::array<char, 512> again{};
  EXPECT_EQ(*encode_formation(back, again), *text);
  // The hold's ends: 2 s is allowed, members in any order, unknown ones ignored.
  ASSERT_TRUE(decode_formation(R"({"holdS":2,"omega":0,"v":-0.1,"serialNumber":"r","manufacturer":"m","timestamp":"t",)"
                               R"("headerId":0,"schemaVersion":"1.4.0","note":"later minor"})",
                               back, *scratch)
                  .ok());
  EXPECT_EQ(back.hold_s, 2.0);
  EXPECT_EQ(back.v, -0.1);
  EXPECT_EQ(formation_topic("Sen3Bot", "r2"), "sen3bot/v1/formation/Sen3Bot/r2");
  std::array<char, 16> small{};
  EXPECT_EQ(encode_formation(m, small).error().code(), Errc::capacity);
}

// Every member missing, of the wrong type or out of range is refused with its name.
TEST(FormationCommand, RefusesEachMissingOrInvalidMemberNamingIt) {
  auto scratch = std::make_unique<DecodeScratch>();
  FormationCommand back;
  const std::string members[][2] = {
      {"schemaVersion", R"("1.0.0")"}, {"headerId", "3"}, {"timestamp", R"("2026-12-03T15:04:13.25Z")"},
      {"manufacturer", R"("Sen3Bot")"}, {"serialNumber", R"("r1")"}, {"v", "0.2"}, {"omega", "0.1"}, {"holdS", "0.5"}};
  const auto message = [&](std::string_view skip, std::string_view replace_with) {
    std::string text = "{";
    for (const auto& [key, value] : members) {
      if (key == skip && replace_with.empty()) continue;
      text += (text.size() > 1 ? "," : "") + std::string("\"") + key + "\":" + (key == skip ? std::string(replace_with) : value);
    }
    return text + "}";
  };
  ASSERT_TRUE(decode_formation(message("", ""), back, *scratch).ok());
  const auto refused = [&](const std::string& text, std::string_view field) {
    const Status s = decode_formation(text, back, *scratch);
    ASSERT_FALSE(s.ok()) << text;
    EXPECT_NE(std::string(s.error().c_str()).find(field), std::string::npos) << s.error().c_str() << "\n" << text;
  };
  for (const auto& [key, value] : members) {
    SCOPED_TRACE(key);
    refused(message(key, ""), key);  // missing
    // Of the wrong type: a string for a number, a number for a string.
    refused(message(key, key == "v" || key == "omega" || key == "holdS" || key == "headerId" ? R"("1")" : "1"), key);
    refused(message(key, "null"), key);
  }
  refused(message("headerId", "-1"), "headerId");
  refused(message("headerId", "4294967296"), "headerId");
  refused(message("headerId", "1.5"), "headerId");
  refused(message("holdS", "0"), "holdS");
  refused(message("holdS", "-0.5"), "holdS");
  refused(message("holdS", "2.0001"), "holdS");
  refused(message("schemaVersion", R"("2.0.0")"), "schemaVersion");
  EXPECT_EQ(decode_formation(message("schemaVersion", R"("2.0.0")"), back, *scratch).error().code(), Errc::not_supported);
  // Numbers beyond a double's range have no finite value: the reader refuses them.
  EXPECT_FALSE(decode_formation(message("v", "1e999"), back, *scratch).ok());
  EXPECT_FALSE(decode_formation(message("omega", "-1e400"), back, *scratch).ok());
  EXPECT_FALSE(decode_formation(message("v", "NaN"), back, *scratch).ok());
  EXPECT_FALSE(decode_formation(message("v", "Infinity"), back, *scratch).ok());
  std::string long_serial(kIdCapacity + 1, 's');
  refused(message("serialNumber", "\"" + long_serial + "\""), "serialNumber");
  EXPECT_FALSE(decode_formation("[]", back, *scratch).ok());
  EXPECT_FALSE(decode_formation("{\"v\":", back, *scratch).ok());
  EXPECT_FALSE(decode_formation("", back, *scratch).ok());
}

TEST(FormationCommand, TheEncoderRefusesWhatARobotWould) {
  std::array<char, 512> out{};
  FormationCommand m = formation_sample();
  m.v = std::nan("");
  EXPECT_EQ(encode_formation(m, out).error().code(), Errc::invalid_argument);
  m = formation_sample();
  m.omega = HUGE_VAL;
  EXPECT_NE(std::string(encode_formation(m, out).error().c_str()).find("omega"), std::string::npos);
  for (double hold : {0.0, -1.0, 2.5, std::nan("")}) {
    m = formation_sample();
    m.hold_s = hold;
    auto text = encode_formation(m, out);
    ASSERT_FALSE(text.ok()) << hold;
    EXPECT_NE(std::string(text.error().c_str()).find("holdS"), std::string::npos);
  }
}

}  // namespace
}  // namespace sen3bot::vda5050
