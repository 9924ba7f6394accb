#include <gtest/gtest.h>

#include <array>
#include <string>
#include <string_view>

#include "sen3bot/hal/candump.hpp"

namespace sen3bot::hal {
namespace {

std::string formatted(const CandumpLine& line) {
  std::array<char, kMaxCandumpLine> out{};
  const std::size_t n = format_candump_line(line, out);
  return std::string(out.data(), n);
}

TEST(Candump, ReadsTheLinesCandumpWrites) {
  // A CiA 401 node's TPDO1 (inputs), a heartbeat, an extended id and a remote request.
  Result<CandumpLine> tpdo = parse_candump_line("(1700000000.123456) can0 185#0100000000000000\n");
  ASSERT_TRUE(tpdo) << tpdo.error().message();
  EXPECT_EQ(tpdo->unix_ns, 1'700'000'000'123'456'000);
  EXPECT_EQ(tpdo->interface_name(), "can0");
  EXPECT_EQ(tpdo->frame.id, 0x185u);
  EXPECT_FALSE(tpdo->frame.extended);
  EXPECT_FALSE(tpdo->error_frame);
  ASSERT_EQ(tpdo->frame.dlc, 8);
  EXPECT_EQ(tpdo->frame.data[0], 0x01);

  Result<CandumpLine> boot = parse_candump_line("(0.000001) vcan0 705#00");
  ASSERT_TRUE(boot);
  EXPECT_EQ(boot->unix_ns, 1000);
  EXPECT_EQ(boot->frame.dlc, 1);

  Result<CandumpLine> ext = parse_candump_line("(12.5) can1 18FEF100#");
  ASSERT_TRUE(ext);
  EXPECT_TRUE(ext->frame.extended);
  EXPECT_EQ(ext->frame.id, 0x18FEF100u);
  EXPECT_EQ(ext->frame.dlc, 0);
  EXPECT_EQ(ext->unix_ns, 12'500'000'000);

  Result<CandumpLine> rtr = parse_candump_line("(1.000000) can0 705#R1");
  ASSERT_TRUE(rtr);
  EXPECT_TRUE(rtr->frame.rtr);
  EXPECT_EQ(rtr->frame.dlc, 1);
}

TEST(Candump, AnErrorFrameCarriesItsClassesWithoutTheFlag) {
  // Bus-off and a controller problem: error passive on transmit.
  Result<CandumpLine> e = parse_candump_line("(1700000001.000000) can0 20000044#0020000000000000");
  ASSERT_TRUE(e) << e.error().message();
  EXPECT_TRUE(e->error_frame);
  EXPECT_EQ(e->frame.id, can_error::kBusOff | can_error::kController);
  EXPECT_EQ(e->frame.data[1], can_error::kTxPassive);
  EXPECT_EQ(formatted(*e), "(1700000001.000000) can0 20000044#0020000000000000\n");
}

TEST(Candump, WritesWhatItReadsByteForByte) {
  for (const std::string_view text : {"(1700000000.123456) can0 185#0100000000000000\n", "(0.000001) vcan0 705#00\n",
                                      "(3.000000) can0 000#0105\n", "(4.250000) can0 1ABCDEF0#DEADBEEF\n",
                                      "(5.000000) can0 705#R1\n", "(6.000000) can0 080#\n"}) {
    Result<CandumpLine> line = parse_candump_line(text);
    ASSERT_TRUE(line) << text << ": " << line.error().message();
    EXPECT_EQ(formatted(*line), text);
  }
}

TEST(Candump, MalformedLinesSayWhatIsWrongAndWhere) {
  const struct {
    std::string_view line;
    std::string_view says;
  } cases[] = {
      {"", "expected '(' and the time"},
      {"1700000000.1 can0 185#01", "expected '('"},
      {"(1700000000) can0 185#01", "expected '.' in the time"},
      {"(1700000000.1can0 185#01", "expected ')'"},
      {"(1.1) can0", "expected a space and the frame"},
      {"(1.1)  185#01", "expected the interface's name"},
      {"(1.1) averyveryverylongname 185#01", "longer than 15"},
      {"(1.1) can0 18G#01", "not hexadecimal"},
      {"(1.1) can0 18#01", "3 hex digits (standard) or 8"},
      {"(1.1) can0 800#01", "above 0x7FF"},
      {"(1.1) can0 185", "expected '#'"},
      {"(1.1) can0 185#010", "odd number"},
      {"(1.1) can0 185#010203040506070809", "more than 8 data bytes"},
      {"(1.1) can0 185#0x", "not hexadecimal"},
      {"(1.1) can0 185#R9", "one digit 0..8"},
      {"(1.1) can0 40000000#", "bits above 29"},
      {"(1.1) can0 20000040#R", "cannot be a remote request"},
      {"(1.1234567891) can0 185#", "more than 9 digits"},
  };
  for (const auto& c : cases) {
    Result<CandumpLine> r = parse_candump_line(c.line);
    ASSERT_FALSE(r) << c.line;
    EXPECT_EQ(r.error().code(), Errc::protocol) << c.line;
    EXPECT_NE(r.error().message().find(c.says), std::string_view::npos) << c.line << ": " << r.error().message();
    EXPECT_NE(r.error().message().find("column"), std::string_view::npos) << c.line;
  }
  Result<CandumpLine> fd = parse_candump_line("(1.1) can0 185##1000102");
  ASSERT_FALSE(fd);
  EXPECT_EQ(fd.error().code(), Errc::not_supported);
}

TEST(Candump, RefusesToWriteWhatCannotBeRead) {
  CandumpLine line;
  line.frame.id = 0x185;
  line.frame.dlc = 1;
  EXPECT_EQ(formatted(line), "");  // no interface
  line.interface = {'c', 'a', 'n', '0'};
  EXPECT_EQ(formatted(line), "(0.000000) can0 185#00\n");
  line.frame.dlc = 9;
  EXPECT_EQ(formatted(line), "");
  line.frame.dlc = 1;
  std::array<char, 8> small{};
  EXPECT_EQ(format_candump_line(line, small), 0u);
}

}  // namespace
}  // namespace sen3bot::hal
