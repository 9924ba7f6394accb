// The tag payload: round trips, and every way a code is refused.
#include <gtest/gtest.h>

#include <string>

#include "sen3bot/cobot/tag.hpp"

namespace sen3bot::cobot {
namespace {

std::string payload_of(std::uint32_t id, msg::TagSide side) {
  Result<TagPayload> p = encode_tag(Tag{id, side});
  EXPECT_TRUE(p.ok()) << (p.ok() ? "" : p.error().c_str());
  return p.ok() ? std::string(p->text()) : std::string();
}

TagRefusal refusal_of(std::string_view text) {
  Tag tag{7, msg::TagSide::back};
  TagRefusal why = TagRefusal::foreign;
  EXPECT_FALSE(check_tag(text, tag, why)) << text;
  EXPECT_EQ(tag.operator_id, 7u) << "a refusal leaves the output alone";
  return why;
}

TEST(TagPayload, KnownLayoutAndCheck) {
  const std::string p = payload_of(42, msg::TagSide::front);
  ASSERT_EQ(p.size(), kTagPayloadLength);
  EXPECT_EQ(p.substr(0, 14), "S3B1:F:000042:");
  // CRC-16/CCITT-FALSE's check value over "123456789" is 0x29B1.
  EXPECT_EQ(tag_check("123456789"), 0x29B1);
  char expected[8];
  std::snprintf(expected, sizeof expected, "%04X", tag_check("S3B1:F:000042"));
  EXPECT_EQ(p.substr(14), expected);
  EXPECT_EQ(payload_of(999999, msg::TagSide::back).substr(0, 14), "S3B1:B:999999:");
}

TEST(TagPayload, RoundTripsEveryIdShape) {
  for (const std::uint32_t id : {1u, 9u, 10u, 42u, 1000u, 123456u, 999998u, 999999u}) {
    for (const msg::TagSide side : {msg::TagSide::front, msg::TagSide::back}) {
      const std::string p = payload_of(id, side);
      Result<Tag> back = parse_tag(p);
      ASSERT_TRUE(back.ok()) << p << ": " << back.error().c_str();
      EXPECT_EQ(back->operator_id, id);
      EXPECT_EQ(back->side, side);
    }
  }
}

TEST(TagPayload, EncodeRefusesIdsOutOfRange) {
  for (const std::uint32_t id : {0u, 1'000'000u, 4'000'000'000u}) {
    Result<TagPayload> p = encode_tag(Tag{id, msg::TagSide::front});
    ASSERT_FALSE(p.ok()) << id;
    EXPECT_EQ(p.error().code(), Errc::invalid_argument);
    EXPECT_NE(p.error().message().find("outside 1..999999"), std::string_view::npos) << p.error().c_str();
  }
}

TEST(TagPayload, EveryRefusalHasItsReasonAndMessage) {
  const std::string good = payload_of(42, msg::TagSide::front);
  EXPECT_EQ(refusal_of(""), TagRefusal::foreign);
  EXPECT_EQ(refusal_of("https://plant.example/rack/17"), TagRefusal::foreign);
  EXPECT_EQ(refusal_of("s3b1:F:000042:0000"), TagRefusal::foreign);  // lower case is not ours
  EXPECT_EQ(refusal_of("S3B2:F:000042:0000"), TagRefusal::unknown_version);
  EXPECT_EQ(refusal_of("S3B"), TagRefusal::malformed);
  EXPECT_EQ(refusal_of("S3BX:F:000042:0000"), TagRefusal::malformed);
  EXPECT_EQ(refusal_of(good.substr(0, 17)), TagRefusal::malformed);      // one short
  EXPECT_EQ(refusal_of(good + "0"), TagRefusal::malformed);              // one long
  std::string bad = good;
  bad[6] = '-';
  EXPECT_EQ(refusal_of(bad), TagRefusal::malformed);                     // separator
  bad = good;
  bad[17] = 'g';
  EXPECT_EQ(refusal_of(bad), TagRefusal::malformed);                     // not a hex digit
  bad = good;
  bad[5] = 'L';
  EXPECT_EQ(refusal_of(bad), TagRefusal::bad_side);
  bad = good;
  bad[9] = 'A';
  EXPECT_EQ(refusal_of(bad), TagRefusal::bad_operator);
  EXPECT_EQ(refusal_of("S3B1:F:000000:" + good.substr(14)), TagRefusal::bad_operator);
  bad = good;
  bad[12] = bad[12] == '3' ? '4' : '3';                                  // another operator, old check
  EXPECT_EQ(refusal_of(bad), TagRefusal::bad_check);
  bad = good;
  bad[14] = bad[14] == 'A' ? 'B' : 'A';
  EXPECT_EQ(refusal_of(bad), TagRefusal::bad_check);

  struct Case {
    std::string text;
    Errc code;
    std::string_view says;
  };
  const Case cases[] = {
      {"PLANT RACK 17", Errc::protocol, "is not a Sen3Bot tag"},
      {"S3B7:F:000042:0000", Errc::not_supported, "format version 7; this firmware reads 1"},
      {"S3B1:F:42", Errc::protocol, "is not laid out as"},
      {"S3B1:X:000042:0000", Errc::protocol, "side 'X' is neither F nor B"},
      {"S3B1:F:00004Z:0000", Errc::protocol, "operator id '00004Z' is not 000001..999999"},
      {bad, Errc::protocol, "does not match"},
  };
  for (const Case& c : cases) {
    Result<Tag> r = parse_tag(c.text);
    ASSERT_FALSE(r.ok()) << c.text;
    EXPECT_EQ(r.error().code(), c.code) << c.text;
    EXPECT_NE(r.error().message().find(c.says), std::string_view::npos) << r.error().c_str();
  }
  // A long foreign payload is cut in the message.
  Result<Tag> r = parse_tag(std::string(300, 'x'));
  ASSERT_FALSE(r.ok());
  EXPECT_NE(r.error().message().find("..."), std::string_view::npos);
}

TEST(TagPayload, EverySingleCharacterChangeIsRefused) {
  // The check catches each single substitution by any character of QR's alphanumeric set.
  const std::string good = payload_of(271828, msg::TagSide::back);
  const std::string_view alphabet = "0123456789ABCDEFGHIJKLMNOPQRSTUVWXYZ $%*+-./:";
  for (std::size_t at = 0; at < good.size(); ++at) {
    for (const char c : alphabet) {
      if (c == good[at]) continue;
      std::string changed = good;
      changed[at] = c;
      Tag tag;
      TagRefusal why = TagRefusal::foreign;
      EXPECT_FALSE(check_tag(changed, tag, why)) << changed;
    }
  }
}

TEST(TagPayload, RefusalNamesAreDistinct) {
  for (std::size_t a = 0; a < kTagRefusals; ++a) {
    for (std::size_t b = a + 1; b < kTagRefusals; ++b) {
      EXPECT_STRNE(to_string(static_cast<TagRefusal>(a)), to_string(static_cast<TagRefusal>(b)));
    }
  }
  EXPECT_STREQ(side_name(msg::TagSide::front), "FRONT");
  EXPECT_STREQ(side_name(msg::TagSide::back), "BACK");
}

}  // namespace
}  // namespace sen3bot::cobot
