// The detection datagram: the codec round trip and every refusal counted by its reason.
#include <gtest/gtest.h>

#include <cstdint>
#include <cstdio>
#include <string>
#include <vector>

#include "sen3bot/detector/protocol.hpp"

namespace sen3bot::detector {
namespace {

constexpr std::int64_t kUnix = 1'764'000'000'000'000'000;  // the gate's wall clock in these tests
constexpr hal::Nanos kNow = 50'000'000'000;                 // and its firmware clock

Datagram frame(std::uint32_t sequence, std::int64_t capture_unix_ns, std::uint8_t count = 2) {
  Datagram d;
  d.source = 7;
  d.sequence = sequence;
  d.capture_unix_ns = capture_unix_ns;
  d.width_px = 1280;
  d.height_px = 720;
  d.count = count;
  for (std::size_t b = 0; b < count; ++b)
    d.boxes[b] = {static_cast<float>(10 + 70 * b), 20.0f, static_cast<float>(60 + 70 * b), 700.0f, 0.75f,
                  static_cast<std::uint16_t>(b)};
  return d;
}

std::vector<std::uint8_t> bytes_of(const Datagram& d) {
  std::vector<std::uint8_t> out(kMaxDatagramBytes);
  out.resize(encode(d, out));
  return out;
}

TEST(DetectorDatagram, EncodeThenDecodeGivesTheFrameBack) {
  const Datagram d = frame(42, kUnix - 30'000'000, 16);
  const std::vector<std::uint8_t> wire = bytes_of(d);
  ASSERT_EQ(wire.size(), kMaxDatagramBytes);
  EXPECT_EQ(std::string(wire.begin(), wire.begin() + 4), "S3PD");
  Datagram back;
  Reject why = Reject::too_short;
  ASSERT_TRUE(decode(wire, back, why)) << to_string(why);
  EXPECT_EQ(back.source, 7u);
  EXPECT_EQ(back.sequence, 42u);
  EXPECT_EQ(back.capture_unix_ns, kUnix - 30'000'000);
  ASSERT_EQ(back.count, 16);
  for (std::size_t b = 0; b < 16; ++b) {
    EXPECT_EQ(back.boxes[b].u0, d.boxes[b].u0);
    EXPECT_EQ(back.boxes[b].v1, 700.0f);
    EXPECT_FLOAT_EQ(back.boxes[b].confidence, 0.75f);
    EXPECT_EQ(back.boxes[b].class_id, b);
  }
  // The CRC is IEEE 802.3's: "123456789" gives 0xCBF43926.
  const std::string check = "123456789";
  EXPECT_EQ(crc32(std::span(reinterpret_cast<const std::uint8_t*>(check.data()), check.size())), 0xCBF43926u);
  Datagram too_many = d;
  too_many.count = 17;
  std::vector<std::uint8_t> out(kMaxDatagramBytes + 12);
  EXPECT_EQ(encode(too_many, out), 0u);
}

TEST(DetectorDatagram, MalformedDatagramsAreRefusedAndCounted) {
  const std::vector<std::uint8_t> good = bytes_of(frame(1, kUnix));
  struct Case {
    std::vector<std::uint8_t> bytes;
    Reject expected;
  };
  std::vector<Case> cases;
  cases.push_back({std::vector<std::uint8_t>(good.begin(), good.begin() + 31), Reject::too_short});
  cases.push_back({std::vector<std::uint8_t>(kMaxDatagramBytes + 1, 0), Reject::too_long});
  auto flipped = [&](std::size_t at, std::uint8_t value) {
    std::vector<std::uint8_t> b = good;
    b[at] = value;
    return b;
  };
  cases.push_back({flipped(0, 'X'), Reject::bad_magic});
  cases.push_back({flipped(4, 2), Reject::bad_version});
  cases.push_back({flipped(5, 1), Reject::bad_version});  // flags
  cases.push_back({flipped(6, 3), Reject::bad_length});   // says 3 boxes, carries 2
  cases.push_back({std::vector<std::uint8_t>(good.begin(), good.end() - 1), Reject::bad_length});  // truncated
  cases.push_back({flipped(30, static_cast<std::uint8_t>(good[30] ^ 1)), Reject::bad_crc});
  Datagram inverted = frame(1, kUnix);
  inverted.boxes[1].u1 = inverted.boxes[1].u0;
  cases.push_back({bytes_of(inverted), Reject::bad_box});
  Datagram outside = frame(1, kUnix);
  outside.boxes[0].v1 = 721.0f;
  cases.push_back({bytes_of(outside), Reject::bad_box});
  Datagram other_camera = frame(1, kUnix);
  other_camera.width_px = 1920;
  other_camera.height_px = 1080;
  cases.push_back({bytes_of(other_camera), Reject::wrong_image});
  cases.push_back({bytes_of(frame(1, kUnix - 600'000'000)), Reject::stale});   // 0.6 s old
  cases.push_back({bytes_of(frame(1, kUnix + 60'000'000)), Reject::future});   // 60 ms ahead
  cases.push_back({bytes_of(frame(1, INT64_MIN)), Reject::stale});   // times at the ends of the range
  cases.push_back({bytes_of(frame(1, INT64_MAX)), Reject::future});
  for (const Case& c : cases) {
    DetectionGate gate;
    detector::Detections out;
    EXPECT_FALSE(gate.accept(c.bytes, kNow, kUnix, out)) << to_string(c.expected);
    EXPECT_EQ(gate.rejected(c.expected), 1u) << to_string(c.expected);
    EXPECT_EQ(gate.accepted(), 0u);
  }
  // Confidence above 1 (10001 / 10000), written by hand with a valid CRC.
  std::vector<std::uint8_t> bad = good;
  bad[28 + 8] = 0x11;
  bad[28 + 9] = 0x27;
  const std::uint32_t crc = crc32(std::span(bad).first(bad.size() - 4));
  for (int i = 0; i < 4; ++i) bad[bad.size() - 4 + static_cast<std::size_t>(i)] = static_cast<std::uint8_t>(crc >> (8 * i));
  Datagram d;
  Reject why = Reject::too_short;
  EXPECT_FALSE(decode(bad, d, why));
  EXPECT_EQ(why, Reject::bad_box);
}

TEST(DetectorDatagram, ReplaysAreRefusedARestartIsNotAndTheCaptureTimeComesOnTheFirmwareClock) {
  DetectionGate gate;
  detector::Detections out;
  // 0.1 s old: its capture on the firmware's clock is 0.1 s before now.
  ASSERT_TRUE(gate.accept(bytes_of(frame(10, kUnix - 100'000'000)), kNow, kUnix, out));
  EXPECT_EQ(out.capture_ns, kNow - 100'000'000);
  EXPECT_EQ(out.count, 2);
  EXPECT_EQ(out.sequence, 10u);
  EXPECT_FALSE(gate.accept(bytes_of(frame(10, kUnix - 100'000'000)), kNow, kUnix, out));  // the same again
  EXPECT_FALSE(gate.accept(bytes_of(frame(9, kUnix - 50'000'000)), kNow, kUnix, out));    // an older number
  EXPECT_EQ(gate.rejected(Reject::replayed), 2u);
  EXPECT_TRUE(gate.accept(bytes_of(frame(11, kUnix - 50'000'000)), kNow, kUnix, out));
  // The detector restarted: its count begins again, with frames newer than the last by more
  // than max_age_s.
  EXPECT_TRUE(gate.accept(bytes_of(frame(0xFFFFFFFEu, kUnix + 600'000'000)), kNow + 650'000'000, kUnix + 650'000'000,
                          out));
  // The sequence wraps around 2^32.
  EXPECT_TRUE(gate.accept(bytes_of(frame(0xFFFFFFFFu, kUnix + 700'000'000)), kNow + 700'000'000, kUnix + 700'000'000, out));
  EXPECT_TRUE(gate.accept(bytes_of(frame(0, kUnix + 710'000'000)), kNow + 710'000'000, kUnix + 710'000'000, out));
  EXPECT_EQ(gate.accepted(), 5u);
  // Four sources at most.
  for (std::uint32_t s = 100; s < 104; ++s) {
    Datagram d = frame(1, kUnix);
    d.source = s;
    const bool ok = gate.accept(bytes_of(d), kNow, kUnix, out);
    EXPECT_EQ(ok, s < 103) << s;
  }
  EXPECT_EQ(gate.rejected(Reject::too_many_sources), 1u);
}

}  // namespace
}  // namespace sen3bot::detector
