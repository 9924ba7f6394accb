// The mean-value (20 26 -> B6) and sub-range (20 27 -> B7) telegrams: request bytes, decode
// round trips through the parser, and clear errors for malformed or truncated telegrams.
#include <gtest/gtest.h>

#include <string>
#include <vector>

#include "sen3bot/lms200/parser.hpp"
#include "sen3bot/lms200/protocol.hpp"

namespace sen3bot::lms200 {
namespace {

using Bytes = std::vector<std::uint8_t>;

Bytes request_bytes(const Request& r) { return Bytes(r.span().begin(), r.span().end()); }

void put(Bytes& b, std::uint16_t v) {
  b.push_back(static_cast<std::uint8_t>(v & 0xFF));
  b.push_back(static_cast<std::uint8_t>(v >> 8));
}

// Reply data after the code: `header`, the count word (count | flags), the values, [indices].
Bytes scan_data(const Bytes& header, const std::vector<std::uint16_t>& words, std::uint16_t count_flags,
                bool indices) {
  Bytes d = header;
  put(d, static_cast<std::uint16_t>(words.size() | count_flags));
  for (std::uint16_t w : words) put(d, w);
  if (indices) d.insert(d.end(), {0x21, 0x42});
  return d;
}

Bytes frame(std::uint8_t code, const Bytes& data, std::uint8_t status = kStatusNormal) {
  std::array<std::uint8_t, kMaxFrameBytes + 8> out{};
  const std::size_t n = make_reply(code, data, status, out);
  return Bytes(out.begin(), out.begin() + static_cast<std::ptrdiff_t>(n));
}

// The telegrams the parser finds in `wire`, scanner side.
std::vector<Bytes> parse(const Bytes& wire) {
  TelegramParser p(Side::from_device);
  std::vector<Bytes> frames;
  std::size_t at = 0;
  while (at < wire.size()) {
    at += p.push({wire.data() + at, wire.size() - at});
    TelegramParser::Event e;
    while (p.next(e))
      if (e.kind == TelegramParser::Kind::frame) frames.emplace_back(e.frame.bytes.begin(), e.frame.bytes.end());
  }
  // The line goes quiet: what is still incomplete is abandoned, as the device does after a gap.
  while (p.size() > 0) {
    p.drop_partial();
    TelegramParser::Event e;
    while (p.next(e))
      if (e.kind == TelegramParser::Kind::frame) frames.emplace_back(e.frame.bytes.begin(), e.frame.bytes.end());
  }
  return frames;
}

std::vector<std::uint16_t> ramp(std::size_t n, std::uint16_t from) {
  std::vector<std::uint16_t> w(n);
  for (std::size_t i = 0; i < n; ++i) w[i] = static_cast<std::uint16_t>(from + 3 * i);
  return w;
}

std::string error_of(const Result<ScanTelegram>& r) { return r.ok() ? std::string("(decoded)") : r.error().c_str(); }

TEST(Lms200MeanValues, RequestBytes) {
  Result<Request> r = request_mean_values(10);
  ASSERT_TRUE(r.ok());
  const Bytes b = request_bytes(*r);
  ASSERT_EQ(b.size(), 9u);
  EXPECT_EQ(Bytes(b.begin(), b.begin() + 7), (Bytes{0x02, 0x00, 0x03, 0x00, 0x20, 0x26, 0x0A}));
  EXPECT_EQ(b[7] | (b[8] << 8), crc16({b.data(), 7}));
  // The scanner's side parses it as one CRC-valid request.
  TelegramParser host(Side::from_host);
  host.push(b);
  TelegramParser::Event e;
  ASSERT_TRUE(host.next(e));
  EXPECT_EQ(e.kind, TelegramParser::Kind::frame);
  EXPECT_TRUE(request_mean_values(kMinMeanSamples).ok());
  EXPECT_TRUE(request_mean_values(kMaxMeanSamples).ok());
  for (const std::uint8_t bad : std::initializer_list<std::uint8_t>{0, 1, 251, 255}) {
    Result<Request> refused = request_mean_values(bad);
    ASSERT_FALSE(refused.ok()) << int(bad);
    EXPECT_NE(std::string(refused.error().c_str()).find("2 to 250"), std::string::npos) << refused.error().c_str();
  }
}

TEST(Lms200Subrange, RequestBytesAndBounds) {
  // sicktoolbox's example: 180/0.5, the first 10.5 degrees are values 1..22.
  Result<Request> r = request_subrange(1, 22, {180, 50});
  ASSERT_TRUE(r.ok());
  const Bytes b = request_bytes(*r);
  ASSERT_EQ(b.size(), 12u);
  EXPECT_EQ(Bytes(b.begin(), b.begin() + 10), (Bytes{0x02, 0x00, 0x06, 0x00, 0x20, 0x27, 0x01, 0x00, 0x16, 0x00}));
  EXPECT_EQ(b[10] | (b[11] << 8), crc16({b.data(), 10}));
  EXPECT_TRUE(request_subrange(361, 361, {180, 50}).ok());
  EXPECT_TRUE(request_subrange(1, 401, {100, 25}).ok());
  struct Bad {
    std::uint16_t first, last;
    Variant v;
  };
  for (const Bad& c : {Bad{0, 10, {180, 50}}, Bad{11, 10, {180, 50}}, Bad{1, 362, {180, 50}},
                       Bad{1, 182, {180, 100}}, Bad{1, 402, {100, 25}}, Bad{1, 10, {180, 25}}}) {
    Result<Request> refused = request_subrange(c.first, c.last, c.v);
    ASSERT_FALSE(refused.ok()) << c.first << ".." << c.last;
    EXPECT_EQ(refused.error().code(), Errc::invalid_argument);
  }
  EXPECT_NE(std::string(request_subrange(1, 362, {180, 50}).error().c_str()).find("<= 361"), std::string::npos);
}

TEST(Lms200MeanValues, DecodeRoundTrip) {
  for (const bool indices : {false, true}) {
    const std::vector<std::uint16_t> words = ramp(361, 500);
    const Bytes wire = frame(kReplyMeanScan, scan_data({25}, words, 0x4000, indices));
    EXPECT_EQ(wire.size(), 2 * 361 + 11u + (indices ? 2u : 0u));
    const std::vector<Bytes> frames = parse(wire);
    ASSERT_EQ(frames.size(), 1u);
    for (Result<ScanTelegram> s : {decode_mean_scan(FrameView{frames[0]}), decode_any_scan(FrameView{frames[0]})}) {
      ASSERT_TRUE(s.ok()) << s.error().c_str();
      EXPECT_EQ(s->code, kReplyMeanScan);
      EXPECT_EQ(s->mean_samples, 25);
      EXPECT_EQ(s->count, 361);
      EXPECT_EQ(s->first_index, 1);
      EXPECT_EQ(s->last_index, 361);
      EXPECT_EQ(s->units, Units::mm);
      EXPECT_FALSE(s->partial);
      EXPECT_EQ(s->has_indices, indices);
      if (indices) {
        EXPECT_EQ(s->scan_index, 0x21);
        EXPECT_EQ(s->telegram_index, 0x42);
      }
      EXPECT_EQ(s->status, kStatusNormal);
      EXPECT_EQ(std::vector<std::uint16_t>(s->words.begin(), s->words.begin() + 361), words);
    }
  }
}

TEST(Lms200Subrange, DecodeRoundTripUpToTheLargestTelegram) {
  struct Case {
    std::uint16_t first, last;
    bool indices;
  };
  for (const Case& c : {Case{10, 30, false}, Case{181, 181, true}, Case{1, 401, true}}) {
    const std::size_t n = c.last - c.first + 1u;
    const std::vector<std::uint16_t> words = ramp(n, 100);
    Bytes header;
    put(header, c.first);
    put(header, c.last);
    const Bytes wire = frame(kReplySubrangeScan, scan_data(header, words, 0x0000, c.indices));
    // 401 values with indices: LEN 812, still within the 814 every LMS200 telegram keeps to.
    EXPECT_EQ(wire.size(), 2 * n + 14u + (c.indices ? 2u : 0u));
    const std::vector<Bytes> frames = parse(wire);
    ASSERT_EQ(frames.size(), 1u) << c.first << ".." << c.last;
    for (Result<ScanTelegram> s : {decode_subrange_scan(FrameView{frames[0]}), decode_any_scan(FrameView{frames[0]})}) {
      ASSERT_TRUE(s.ok()) << s.error().c_str();
      EXPECT_EQ(s->code, kReplySubrangeScan);
      EXPECT_EQ(s->first_index, c.first);
      EXPECT_EQ(s->last_index, c.last);
      EXPECT_EQ(s->count, n);
      EXPECT_EQ(s->units, Units::cm);
      EXPECT_EQ(s->mean_samples, 0);
      EXPECT_EQ(s->has_indices, c.indices);
      EXPECT_EQ(std::vector<std::uint16_t>(s->words.begin(), s->words.begin() + static_cast<std::ptrdiff_t>(n)), words);
    }
  }
}

TEST(Lms200Subrange, MalformedTelegramsAreRejectedWithTheirReason) {
  auto b7 = [](std::uint16_t first, std::uint16_t last, std::size_t values, std::uint16_t flags = 0) {
    Bytes header;
    put(header, first);
    put(header, last);
    return frame(kReplySubrangeScan, scan_data(header, ramp(values, 1), flags, false));
  };
  struct Case {
    Bytes wire;
    const char* reason;
  };
  const Case cases[] = {
      {b7(0, 5, 6), "not 1 <= first <= last"},
      {b7(6, 5, 0), "not 1 <= first <= last"},
      {b7(1, 402, 402), "not 1 <= first <= last"},
      {b7(1, 10, 9), "but 9 values"},
      {b7(1, 10, 10, 0xC000), "reserved"},
      {frame(kReplySubrangeScan, {1, 0, 2, 0}), "too short"},     // LEN 6: no count word
      {frame(kReplySubrangeScan, {1, 0, 2, 0, 2}), "too short"},  // LEN 7: half a count word
  };
  for (const Case& c : cases) {
    const Result<ScanTelegram> s = decode_subrange_scan(FrameView{c.wire});
    EXPECT_NE(error_of(s).find(c.reason), std::string::npos) << error_of(s);
  }
  // A count that does not fit LEN.
  Bytes wire = b7(1, 10, 10);
  wire[9] = 11;
  EXPECT_NE(error_of(decode_subrange_scan(FrameView{wire})).find("does not fit"), std::string::npos);
}

TEST(Lms200MeanValues, MalformedTelegramsAreRejectedWithTheirReason) {
  struct Case {
    Bytes wire;
    const char* reason;
  };
  const Case cases[] = {
      {frame(kReplyMeanScan, scan_data({1}, ramp(5, 1), 0, false)), "outside 2..250"},
      {frame(kReplyMeanScan, scan_data({251}, ramp(5, 1), 0, false)), "outside 2..250"},
      {frame(kReplyMeanScan, scan_data({4}, ramp(5, 1), 0xC000, false)), "reserved"},
      {frame(kReplyMeanScan, {4, 5}), "too short"},
      {frame(kReplyMeanScan, {4}), "too short"},
  };
  for (const Case& c : cases) {
    const Result<ScanTelegram> s = decode_mean_scan(FrameView{c.wire});
    EXPECT_NE(error_of(s).find(c.reason), std::string::npos) << error_of(s);
  }
  Bytes wire = frame(kReplyMeanScan, scan_data({4}, ramp(5, 1), 0, false));
  wire[6] = 6;  // count 6, five values sent
  EXPECT_NE(error_of(decode_mean_scan(FrameView{wire})).find("does not fit"), std::string::npos);
}

TEST(Lms200StreamModes, DecodersKeepToTheirCode) {
  const Bytes b0 = frame(kReplyScan, scan_data({}, ramp(3, 1), 0, false));
  const Bytes b6 = frame(kReplyMeanScan, scan_data({3}, ramp(3, 1), 0, false));
  Bytes header;
  put(header, 1);
  put(header, 3);
  const Bytes b7 = frame(kReplySubrangeScan, scan_data(header, ramp(3, 1), 0, false));
  const Bytes a0 = frame(kReplyModeChange, {0});
  EXPECT_FALSE(decode_mean_scan(FrameView{b0}).ok());
  EXPECT_FALSE(decode_subrange_scan(FrameView{b6}).ok());
  EXPECT_FALSE(decode_scan(FrameView{b7}).ok());
  EXPECT_EQ(decode_any_scan(FrameView{b0})->code, kReplyScan);
  EXPECT_EQ(decode_any_scan(FrameView{b6})->code, kReplyMeanScan);
  EXPECT_EQ(decode_any_scan(FrameView{b7})->code, kReplySubrangeScan);
  EXPECT_NE(error_of(decode_any_scan(FrameView{a0})).find("not a scan reply"), std::string::npos);
  EXPECT_NE(error_of(decode_mean_scan(FrameView{b0})).find("not a B6"), std::string::npos);
}

TEST(Lms200StreamModes, TruncatedAndGarbledTelegramsNeverReachTheDecoder) {
  Bytes header;
  put(header, 5);
  put(header, 104);
  const Bytes b7 = frame(kReplySubrangeScan, scan_data(header, ramp(100, 7), 0x4000, true));
  const Bytes b6 = frame(kReplyMeanScan, scan_data({2}, ramp(181, 9), 0, false));
  // Cut short: the parser waits for the rest and hands out nothing.
  EXPECT_TRUE(parse(Bytes(b7.begin(), b7.begin() + 100)).empty());
  // One flipped bit: the CRC fails.
  Bytes flipped = b6;
  flipped[40] ^= 0x04;
  EXPECT_TRUE(parse(flipped).empty());
  // Garbage, a truncated telegram and a false header in front: both real telegrams survive.
  Bytes wire = {0x13, 0x02, 0x80, 0xD6, 0x02, 0x99};
  wire.insert(wire.end(), b6.begin(), b6.begin() + 50);
  wire.insert(wire.end(), b7.begin(), b7.end());
  wire.insert(wire.end(), b6.begin(), b6.end());
  const std::vector<Bytes> frames = parse(wire);
  ASSERT_EQ(frames.size(), 2u);
  EXPECT_EQ(decode_any_scan(FrameView{frames[0]})->first_index, 5);
  EXPECT_EQ(decode_any_scan(FrameView{frames[1]})->mean_samples, 2);
}

TEST(Lms200Status, LevelBits) {
  EXPECT_EQ(status_level(0x10), StatusLevel::ok);
  EXPECT_EQ(status_level(0x13), StatusLevel::error);
  EXPECT_EQ(status_level(0x14), StatusLevel::fatal);
  EXPECT_EQ(status_level(0x17), StatusLevel::reserved);
  EXPECT_EQ(with_status_level(0x10, StatusLevel::error), 0x13);
  EXPECT_EQ(with_status_level(0x97, StatusLevel::ok), 0x90);
}

}  // namespace
}  // namespace sen3bot::lms200
