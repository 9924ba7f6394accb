#include <gtest/gtest.h>

#include "sen3bot/ssc/coalition.hpp"

namespace sen3bot::ssc {
namespace {

// Table 2.1, every area type against every people state.
TEST(SscCoalition, Table21) {
  const struct {
    AreaType type;
    PeopleState people;
    std::uint8_t initial;
    std::uint8_t final_size;
  } cases[] = {
      {AreaType::blind_intersection, PeopleState::none, 2, 2},
      {AreaType::blind_intersection, PeopleState::static_people, 2, 2},
      {AreaType::blind_intersection, PeopleState::dynamic_people, 2, 2},
      {AreaType::transition, PeopleState::none, 2, 2},
      {AreaType::transition, PeopleState::static_people, 2, 1},
      {AreaType::transition, PeopleState::dynamic_people, 2, 2},
      {AreaType::workstation, PeopleState::none, 1, 1},
      {AreaType::workstation, PeopleState::static_people, 1, 1},
      {AreaType::workstation, PeopleState::dynamic_people, 1, 2},
      {AreaType::not_monitored, PeopleState::none, 0, 0},
      {AreaType::not_monitored, PeopleState::static_people, 0, 0},
      {AreaType::not_monitored, PeopleState::dynamic_people, 0, 0},
  };
  for (const auto& c : cases) {
    SCOPED_TRACE(::testing::Message() << to_string(c.type) << " / " << to_string(c.people));
    EXPECT_EQ(initial_size(c.type), c.initial);
    EXPECT_EQ(final_size(c.type, c.people), c.final_size);
    // A coalition that has seen this state wants the final size (the initial one with nobody).
    Coalition coalition;
    coalition.type = c.type;
    EXPECT_EQ(coalition.wanted(), c.initial);
    coalition.observe(c.people);
    EXPECT_EQ(coalition.wanted(), c.final_size);
  }
}

TEST(SscCoalition, PeopleStateFromTheArea) {
  EXPECT_EQ(people_state({0, 0}), PeopleState::none);
  EXPECT_EQ(people_state({3, 0}), PeopleState::static_people);
  EXPECT_EQ(people_state({3, 1}), PeopleState::dynamic_people);
}

TEST(SscCoalition, PeopleStateIsLatchedForTheCoalitionsLife) {
  Coalition c;
  c.type = AreaType::transition;
  EXPECT_EQ(c.wanted(), 2);
  EXPECT_TRUE(c.observe(PeopleState::static_people));
  EXPECT_EQ(c.wanted(), 1);
  EXPECT_FALSE(c.observe(PeopleState::none));  // the people left: stays at the final size
  EXPECT_EQ(c.wanted(), 1);
  EXPECT_TRUE(c.observe(PeopleState::dynamic_people));
  EXPECT_EQ(c.wanted(), 2);
  EXPECT_FALSE(c.observe(PeopleState::static_people));
  EXPECT_EQ(c.wanted(), 2);
}

TEST(SscCoalition, MonitoringPriority) {
  EXPECT_EQ(monitoring_priority(AreaType::blind_intersection), 0);
  EXPECT_EQ(monitoring_priority(AreaType::transition), 1);
  EXPECT_EQ(monitoring_priority(AreaType::workstation), 1);
}

}  // namespace
}  // namespace sen3bot::ssc
