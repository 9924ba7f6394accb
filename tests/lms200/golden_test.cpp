// Request builders and reply decoders against the golden telegrams of the protocol brief.
#include <gtest/gtest.h>

#include <cmath>
#include <vector>

#include "sen3bot/hal/clock.hpp"
#include "sen3bot/lms200/parser.hpp"
#include "sen3bot/lms200/protocol.hpp"

namespace sen3bot::lms200 {
namespace {

using Bytes = std::vector<std::uint8_t>;

Bytes bytes(const Request& r) { return Bytes(r.span().begin(), r.span().end()); }

// Parses exactly one telegram from `wire` (device side unless told otherwise).
FrameView parse_one(TelegramParser& parser, const Bytes& wire) {
  EXPECT_EQ(parser.push(wire), wire.size());
  TelegramParser::Event e;
  EXPECT_TRUE(parser.next(e));
  EXPECT_EQ(e.kind, TelegramParser::Kind::frame);
  return e.frame;
}

TEST(Lms200Crc, WorkedExample) {
  const Bytes head = {0x02, 0x00, 0x02, 0x00, 0x20, 0x24};
  EXPECT_EQ(crc16(head), 0x0834);
}

TEST(Lms200Golden, HostRequestsAreByteExact) {
  EXPECT_EQ(bytes(request_status()), (Bytes{0x02, 0x00, 0x01, 0x00, 0x31, 0x15, 0x12}));
  EXPECT_EQ(bytes(request_type()), (Bytes{0x02, 0x00, 0x01, 0x00, 0x3A, 0x1E, 0x12}));
  EXPECT_EQ(bytes(request_read_config()), (Bytes{0x02, 0x00, 0x01, 0x00, 0x74, 0x50, 0x12}));
  EXPECT_EQ(bytes(request_errors()), (Bytes{0x02, 0x00, 0x01, 0x00, 0x32, 0x16, 0x12}));
  EXPECT_EQ(bytes(request_mode(OperatingMode::continuous_all)), (Bytes{0x02, 0x00, 0x02, 0x00, 0x20, 0x24, 0x34, 0x08}));
  EXPECT_EQ(bytes(request_mode(OperatingMode::monitoring)), (Bytes{0x02, 0x00, 0x02, 0x00, 0x20, 0x25, 0x35, 0x08}));
  EXPECT_EQ(bytes(request_baud(38400)), (Bytes{0x02, 0x00, 0x02, 0x00, 0x20, 0x40, 0x50, 0x08}));
  EXPECT_EQ(bytes(request_baud(19200)), (Bytes{0x02, 0x00, 0x02, 0x00, 0x20, 0x41, 0x51, 0x08}));
  EXPECT_EQ(bytes(request_baud(9600)), (Bytes{0x02, 0x00, 0x02, 0x00, 0x20, 0x42, 0x52, 0x08}));
  EXPECT_EQ(bytes(request_baud(500000)), (Bytes{0x02, 0x00, 0x02, 0x00, 0x20, 0x48, 0x58, 0x08}));
  EXPECT_EQ(bytes(request_installation_mode()),
            (Bytes{0x02, 0x00, 0x0A, 0x00, 0x20, 0x00, 0x53, 0x49, 0x43, 0x4B, 0x5F, 0x4C, 0x4D, 0x53, 0xBE, 0xC5}));
  EXPECT_EQ(bytes(request_variant({180, 100})), (Bytes{0x02, 0x00, 0x05, 0x00, 0x3B, 0xB4, 0x00, 0x64, 0x00, 0x97, 0x49}));
  EXPECT_EQ(bytes(request_variant({180, 50})), (Bytes{0x02, 0x00, 0x05, 0x00, 0x3B, 0xB4, 0x00, 0x32, 0x00, 0x3B, 0x1F}));
  EXPECT_EQ(bytes(request_variant({100, 25})), (Bytes{0x02, 0x00, 0x05, 0x00, 0x3B, 0x64, 0x00, 0x19, 0x00, 0xE7, 0x72}));
  EXPECT_EQ(bytes(request_variant({100, 50})), (Bytes{0x02, 0x00, 0x05, 0x00, 0x3B, 0x64, 0x00, 0x32, 0x00, 0xB1, 0x59}));
  EXPECT_EQ(bytes(request_variant({100, 100})), (Bytes{0x02, 0x00, 0x05, 0x00, 0x3B, 0x64, 0x00, 0x64, 0x00, 0x1D, 0x0F}));
}

TEST(Lms200Golden, WriteConfigAndSingleScanFrames) {
  std::array<std::uint8_t, kConfigBytes> block{};
  block[config_offset::kUnits] = 1;
  const Request r = request_write_config(block);
  ASSERT_EQ(r.size, 41);
  EXPECT_EQ(r.bytes[2], 0x23);  // LEN 35: 0x77 + 34 bytes, as the public clients send it
  EXPECT_EQ(r.bytes[4], 0x77);
  EXPECT_EQ(crc16(r.span().first(39)), static_cast<std::uint16_t>(r.bytes[39] | (r.bytes[40] << 8)));
  const Request s = request_single_scan();
  EXPECT_EQ(s.size, 8);
  EXPECT_EQ(s.bytes[4], 0x30);
  EXPECT_EQ(s.bytes[5], 0x01);
}

TEST(Lms200Golden, ModeChangeReplies) {
  TelegramParser parser(Side::from_device);
  const FrameView f = parse_one(parser, {0x02, 0x80, 0x03, 0x00, 0xA0, 0x00, 0x10, 0x16, 0x0A});
  const Result<ModeChangeReply> r = decode_mode_change(f);
  ASSERT_TRUE(r.ok());
  EXPECT_EQ(r->result, kModeChangeOk);
  EXPECT_EQ(r->status, 0x10);

  // The same reply from LMS address 1 is only accepted by a parser configured for address 1.
  const Bytes from1 = {0x02, 0x81, 0x03, 0x00, 0xA0, 0x00, 0x10, 0x36, 0x1A};
  TelegramParser wrong(Side::from_device, 0);
  wrong.push(from1);
  TelegramParser::Event e;
  EXPECT_FALSE(wrong.next(e));
  TelegramParser right(Side::from_device, 1);
  const FrameView f1 = parse_one(right, from1);
  EXPECT_TRUE(decode_mode_change(f1).ok());
}

TEST(Lms200Golden, ResetAndPowerOnTelegramsFrame) {
  TelegramParser parser(Side::from_device);
  const FrameView reset = parse_one(parser, {0x02, 0x80, 0x02, 0x00, 0x91, 0x10, 0x79, 0x30});
  EXPECT_EQ(reset.code(), kReplyReset);
  EXPECT_EQ(reset.reply_status(), 0x10);

  Bytes power_on = {0x02, 0x81, 0x17, 0x00, 0x90};
  for (char c : std::string_view("LMS200;301063;V02.06 ")) power_on.push_back(static_cast<std::uint8_t>(c));
  power_on.insert(power_on.end(), {0x13, 0x64, 0x5A});
  TelegramParser p1(Side::from_device, 1);
  const FrameView f = parse_one(p1, power_on);
  EXPECT_EQ(f.code(), kReplyPowerOn);
  EXPECT_EQ(f.reply_status(), 0x13);
}

TEST(Lms200Golden, RequestsParseOnTheHostSide) {
  TelegramParser parser(Side::from_host);
  const Bytes wire = bytes(request_installation_mode());
  const FrameView f = parse_one(parser, wire);
  EXPECT_EQ(f.code(), 0x20);
  EXPECT_EQ(f.payload().size(), 10u);
}

TEST(Lms200Decode, StatusTypeVariantConfig) {
  std::array<std::uint8_t, 1024> out{};
  // B1 with a few fields set.
  std::array<std::uint8_t, kStatusDataBytes> d{};
  d[status_offset::kOperatingMode - 1] = 0x25;
  d[status_offset::kScanAngle - 1] = 180;
  d[status_offset::kResolution - 1] = 50;
  d[status_offset::kBaud - 1] = 0x19;
  d[status_offset::kBaud] = 0x80;
  d[status_offset::kUnits - 1] = 1;
  d[status_offset::kMeasuringMode - 1] = 6;
  std::size_t n = make_reply(kReplyStatus, d, 0x10, out);
  ASSERT_EQ(n, 160u);
  Result<StatusReply> s = decode_status(FrameView{{out.data(), n}});
  ASSERT_TRUE(s.ok()) << s.error().c_str();
  EXPECT_EQ(s->operating_mode, 0x25);
  EXPECT_EQ(s->variant, (Variant{180, 50}));
  EXPECT_EQ(s->baud, 38400u);
  EXPECT_EQ(s->units, 1);
  EXPECT_EQ(s->measuring_mode, 6);

  const std::string_view type = "LMS200;301063;V02.10 ";
  n = make_reply(kReplyType, {reinterpret_cast<const std::uint8_t*>(type.data()), type.size()}, 0x10, out);
  EXPECT_EQ(n, 29u);  // the fixed length clients read
  Result<TypeReply> t = decode_type(FrameView{{out.data(), n}});
  ASSERT_TRUE(t.ok());
  EXPECT_EQ(std::string_view(t->type.data()), type);

  const std::uint8_t bb[] = {1, 0x64, 0x00, 0x19, 0x00};
  n = make_reply(kReplyVariant, bb, 0x10, out);
  EXPECT_EQ(n, 13u);
  Result<VariantReply> v = decode_variant(FrameView{{out.data(), n}});
  ASSERT_TRUE(v.ok());
  EXPECT_TRUE(v->accepted);
  EXPECT_EQ(v->variant, (Variant{100, 25}));

  for (std::size_t size : {kConfigBytesShort, kConfigBytes}) {
    std::array<std::uint8_t, kConfigBytes> c{};
    c[config_offset::kUnits] = 1;
    c[config_offset::kMeasuringMode] = 6;
    n = make_reply(kReplyReadConfig, {c.data(), size}, 0x10, out);
    EXPECT_EQ(n, size + 8);  // 40 or 42 bytes
    Result<ConfigReply> r = decode_read_config(FrameView{{out.data(), n}});
    ASSERT_TRUE(r.ok());
    EXPECT_EQ(r->block.size, size);
    EXPECT_EQ(r->block.units(), 1);
    EXPECT_EQ(r->block.measuring_mode(), 6);
  }
  const std::uint8_t bad[] = {1, 2, 3};
  n = make_reply(kReplyReadConfig, bad, 0x10, out);
  EXPECT_FALSE(decode_read_config(FrameView{{out.data(), n}}).ok());
}

TEST(Lms200Decode, BaudWords) {
  EXPECT_EQ(status_baud_word(9600), 0x8067);
  EXPECT_EQ(status_baud_word(19200), 0x8033);
  EXPECT_EQ(status_baud_word(38400), 0x8019);
  EXPECT_EQ(status_baud_word(500000), 0x8001);
  for (std::uint32_t b : kSupportedBauds) EXPECT_EQ(baud_of_status_word(status_baud_word(b)), b);
  EXPECT_EQ(baud_of_status_word(0x1234), 0u);
}

// Builds a B0 telegram from value words.
std::size_t make_scan(std::span<const std::uint16_t> words, std::uint16_t count_high_bits, bool indices,
                      std::span<std::uint8_t> out) {
  std::vector<std::uint8_t> d;
  const auto count = static_cast<std::uint16_t>(words.size() | count_high_bits);
  d.push_back(static_cast<std::uint8_t>(count & 0xFF));
  d.push_back(static_cast<std::uint8_t>(count >> 8));
  for (std::uint16_t w : words) {
    d.push_back(static_cast<std::uint8_t>(w & 0xFF));
    d.push_back(static_cast<std::uint8_t>(w >> 8));
  }
  if (indices) d.insert(d.end(), {7, 9});
  return make_reply(kReplyScan, d, 0x10, out);
}

TEST(Lms200Decode, ScanCountWordUnitsPartialAndIndices) {
  std::array<std::uint8_t, 1024> out{};
  std::vector<std::uint16_t> words(101, 1234);
  // mm, partial scan, offset 0.5 deg, with indices.
  std::size_t n = make_scan(words, 0x4000 | 0x2000 | (2 << 11), true, out);
  Result<ScanTelegram> s = decode_scan(FrameView{{out.data(), n}});
  ASSERT_TRUE(s.ok()) << s.error().c_str();
  EXPECT_EQ(s->count, 101);
  EXPECT_EQ(s->units, Units::mm);
  EXPECT_TRUE(s->partial);
  EXPECT_EQ(s->partial_offset_qdeg, 2);
  EXPECT_TRUE(s->has_indices);
  EXPECT_EQ(s->scan_index, 7);
  EXPECT_EQ(s->telegram_index, 9);
  EXPECT_EQ(s->words[100], 1234);

  // 401 values with indices is the largest telegram an LMS200 sends: 814 bytes, LEN 808.
  std::vector<std::uint16_t> big(401, 55);
  n = make_scan(big, 0, true, out);
  EXPECT_EQ(n, 814u);
  TelegramParser parser(Side::from_device);
  const FrameView f = parse_one(parser, Bytes(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(n)));
  s = decode_scan(f);
  ASSERT_TRUE(s.ok());
  EXPECT_EQ(s->count, 401);
  EXPECT_EQ(s->units, Units::cm);

  // A count that does not fit LEN, and a count above 401, are errors.
  n = make_scan(words, 0, false, out);
  out[5] = 102;
  EXPECT_FALSE(decode_scan(FrameView{{out.data(), n}}).ok());
  out[5] = 0xFF;
  out[6] = 0x03;
  EXPECT_FALSE(decode_scan(FrameView{{out.data(), n}}).ok());
}

TEST(Lms200Decode, ValuesAtOrAbove8183AreInvalidWithReason) {
  const auto mode = MeasuringMode::range8_fields_dazzle;
  EXPECT_EQ(decode_value(8182, mode).reason, InvalidReason::none);
  EXPECT_TRUE(decode_value(8182, mode).flags & value_flag::kValid);
  EXPECT_EQ(decode_value(8183, mode).reason, InvalidReason::over_maximum);
  EXPECT_EQ(decode_value(8186, mode).reason, InvalidReason::channel1_error);
  EXPECT_EQ(decode_value(8187, mode).reason, InvalidReason::snr_too_small);
  EXPECT_EQ(decode_value(8188, mode).reason, InvalidReason::reserved_code);
  EXPECT_EQ(decode_value(8189, mode).reason, InvalidReason::operation_overflow);
  EXPECT_EQ(decode_value(8190, mode).reason, InvalidReason::dazzling);
  EXPECT_EQ(decode_value(8191, mode).reason, InvalidReason::not_valid);
  for (std::uint16_t v = 8183; v <= 8191; ++v) EXPECT_FALSE(decode_value(v, mode).flags & value_flag::kValid) << v;
  // Flag bits do not hide a code.
  EXPECT_EQ(decode_value(0x8000 | 8191, mode).reason, InvalidReason::not_valid);
}

TEST(Lms200Decode, EveryMeasuringModeSplitsFlagsFromDistance) {
  using M = MeasuringMode;
  struct Case {
    M mode;
    std::uint16_t word;
    std::uint16_t distance;
    std::uint8_t flags;  // without kValid
  };
  using namespace value_flag;
  const Case cases[] = {
      {M::range8_fields_dazzle, 0x2000 | 100, 100, kFieldA},
      {M::range8_fields_dazzle, 0x4000 | 100, 100, kFieldB},
      {M::range8_fields_dazzle, 0x8000 | 100, 100, kDazzle},
      {M::range8_fields_abc, 0x8000 | 0x2000 | 5, 5, kFieldC | kFieldA},
      {M::range8_reflector8, 0xA000 | 8000, 8000, 5 << kReflectorShift},
      {M::range16_reflector4, 0xC000 | 16000, 16000, 3 << kReflectorShift},
      {M::range16_fields_ab, 0x8000 | 0x4000 | 9, 9, kFieldA | kFieldB},
      {M::range32_reflector2, 0x8000 | 30000, 30000, 1 << kReflectorShift},
      {M::range32_field_a, 0x8000 | 32000, 32000, kFieldA},
      {M::range32_immediate, 65000, 65000, 0},
      {M::reflectivity, 200, 200, 0},
  };
  for (const Case& c : cases) {
    const ScanValue v = decode_value(c.word, c.mode);
    EXPECT_EQ(v.distance, c.distance) << static_cast<int>(c.mode);
    EXPECT_EQ(v.flags, c.flags | kValid) << static_cast<int>(c.mode);
    EXPECT_EQ(v.reason, InvalidReason::none);
    EXPECT_EQ(encode_value(v.distance, v.flags, c.mode), c.word) << static_cast<int>(c.mode);
  }
  // Codes of the wider modes sit below their own maximum.
  EXPECT_EQ(decode_value(16383, M::range16_fields_ab).reason, InvalidReason::not_valid);
  EXPECT_EQ(decode_value(16375, M::range16_fields_ab).reason, InvalidReason::over_maximum);
  EXPECT_EQ(decode_value(16374, M::range16_fields_ab).reason, InvalidReason::none);
  EXPECT_EQ(decode_value(32767, M::range32_field_a).reason, InvalidReason::not_valid);
  EXPECT_EQ(decode_value(65535, M::range32_immediate).reason, InvalidReason::not_valid);
}

TEST(Lms200Decode, VariantsAndPeriods) {
  EXPECT_EQ(value_count({180, 100}), 181);
  EXPECT_EQ(value_count({180, 50}), 361);
  EXPECT_EQ(value_count({100, 100}), 101);
  EXPECT_EQ(value_count({100, 50}), 201);
  EXPECT_EQ(value_count({100, 25}), 401);
  EXPECT_FALSE(valid_variant({180, 25}));
  EXPECT_NEAR(hal::to_seconds(scan_period_ns({180, 100})), 1.0 / 75, 1e-8);
  EXPECT_NEAR(hal::to_seconds(scan_period_ns({180, 50})), 2.0 / 75, 1e-8);
  EXPECT_NEAR(hal::to_seconds(scan_period_ns({100, 25})), 4.0 / 75, 1e-8);
}

}  // namespace
}  // namespace sen3bot::lms200
