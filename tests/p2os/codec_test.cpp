// Codec: golden packets from the protocol brief, argument encodings, SIP/CONFIG/ENCODER
// round trips, and the frame parser under byte-by-byte, chunked and hostile input.
#include <gtest/gtest.h>

#include <cstdint>
#include <random>
#include <vector>

#include "sen3bot/p2os/codec.hpp"

namespace sen3bot::p2os {
namespace {

using Bytes = std::vector<std::uint8_t>;

Bytes bytes_of(const Packet& p) { return Bytes(p.view().begin(), p.view().end()); }

struct Collected {
  std::vector<Bytes> raw;
  std::vector<std::uint8_t> types;
};

Collected parse_in_chunks(FrameParser& parser, const Bytes& stream, std::mt19937& rng, std::size_t max_chunk) {
  Collected out;
  std::size_t pos = 0;
  while (pos < stream.size()) {
    const std::size_t n = std::min<std::size_t>(stream.size() - pos, 1 + rng() % max_chunk);
    parser.feed(std::span<const std::uint8_t>(stream.data() + pos, n), 0, [&](const Frame& f) {
      out.raw.emplace_back(f.raw.begin(), f.raw.end());
      out.types.push_back(f.type);
    });
    pos += n;
  }
  return out;
}

Collected parse_all(const Bytes& stream) {
  FrameParser parser;
  Collected out;
  parser.feed(stream, 0, [&](const Frame& f) {
    out.raw.emplace_back(f.raw.begin(), f.raw.end());
    out.types.push_back(f.type);
  });
  return out;
}

TEST(P2osGolden, Sync0AndPulse) {
  EXPECT_EQ(bytes_of(encode_command(Command::sync0)), (Bytes{0xFA, 0xFB, 0x03, 0x00, 0x00, 0x00}));
  EXPECT_EQ(bytes_of(encode_command(kPulse)), (Bytes{0xFA, 0xFB, 0x03, 0x00, 0x00, 0x00}));
}

TEST(P2osGolden, Sync1BareOpenAndSync2) {
  EXPECT_EQ(bytes_of(encode_command(kOpen)), (Bytes{0xFA, 0xFB, 0x03, 0x01, 0x00, 0x01}));
  EXPECT_EQ(bytes_of(encode_command(Command::sync2)), (Bytes{0xFA, 0xFB, 0x03, 0x02, 0x00, 0x02}));
}

TEST(P2osGolden, Enable1) {
  EXPECT_EQ(bytes_of(encode_command_int(Command::enable, 1)),
            (Bytes{0xFA, 0xFB, 0x06, 0x04, 0x3B, 0x01, 0x00, 0x05, 0x3B}));
}

TEST(P2osGolden, VelocityBothSigns) {
  EXPECT_EQ(bytes_of(encode_command_int(Command::vel, 200)),
            (Bytes{0xFA, 0xFB, 0x06, 0x0B, 0x3B, 0xC8, 0x00, 0xD3, 0x3B}));
  EXPECT_EQ(bytes_of(encode_command_int(Command::vel, -200)),
            (Bytes{0xFA, 0xFB, 0x06, 0x0B, 0x1B, 0xC8, 0x00, 0xD3, 0x1B}));
  EXPECT_EQ(bytes_of(encode_command_int(Command::rvel, -30)),
            (Bytes{0xFA, 0xFB, 0x06, 0x15, 0x1B, 0x1E, 0x00, 0x33, 0x1B}));
}

TEST(P2osGolden, AriaOpenWithArgument) {
  EXPECT_EQ(bytes_of(encode_command_int(kOpen, 1)), (Bytes{0xFA, 0xFB, 0x06, 0x01, 0x3B, 0x01, 0x00, 0x02, 0x3B}));
}

TEST(P2osGolden, EncoderPacketOddLength) {
  const Bytes golden{0xFA, 0xFB, 0x0B, 0x90, 0xE8, 0x03, 0x00, 0x00, 0x18, 0xFC, 0xFF, 0xFF, 0x90, 0x00};
  EXPECT_EQ(bytes_of(encode_encoder(EncoderPacket{1000, -1000})), golden);
  const Collected got = parse_all(golden);
  ASSERT_EQ(got.raw.size(), 1u);
  FrameParser parser;
  std::optional<EncoderPacket> decoded;
  parser.feed(golden, 0, [&](const Frame& f) { decoded = decode_encoder(f); });
  ASSERT_TRUE(decoded);
  EXPECT_EQ(decoded->left_ticks, 1000);
  EXPECT_EQ(decoded->right_ticks, -1000);
}

TEST(P2osGolden, SayAsAriaSendsIt) {
  // ARIA appends a NUL the length byte does not count; the string decodes by the length.
  const Bytes aria{0xFA, 0xFB, 0x08, 0x0F, 0x2B, 0x02, 0x61, 0x62, 0x00, 0x73, 0x8C};
  std::optional<CommandArgument> arg;
  FrameParser parser;
  parser.feed(aria, 0, [&](const Frame& f) { arg = decode_argument(f.payload); });
  ASSERT_TRUE(arg);
  ASSERT_EQ(arg->kind, ArgKind::string);
  ASSERT_EQ(arg->text.size(), 2u);
  EXPECT_EQ(arg->text[0], 'a');
  EXPECT_EQ(arg->text[1], 'b');
  const std::uint8_t ab[] = {'a', 'b'};
  // Ours: no NUL. 0x0F2B + 0x0261 = 0x118C, then 0x62 xor-ed in: 0x11EE.
  EXPECT_EQ(bytes_of(encode_command_string(Command::say, ab)),
            (Bytes{0xFA, 0xFB, 0x07, 0x0F, 0x2B, 0x02, 0x61, 0x62, 0x11, 0xEE}));
}

TEST(P2osGolden, Sync2Reply) {
  const Bytes golden{0xFA, 0xFB, 0x17, 0x02, 0x45, 0x4D, 0x55, 0x00, 0x50, 0x69, 0x6F, 0x6E, 0x65,
                     0x65, 0x72, 0x00, 0x70, 0x33, 0x64, 0x78, 0x2D, 0x73, 0x68, 0x00, 0xAC, 0x99};
  EXPECT_EQ(bytes_of(encode_sync2_reply("EMU", "Pioneer", "p3dx-sh")), golden);
  std::optional<SyncReply> reply;
  FrameParser parser;
  parser.feed(golden, 0, [&](const Frame& f) { reply = decode_sync2_reply(f); });
  ASSERT_TRUE(reply);
  EXPECT_STREQ(reply->name.data(), "EMU");
  EXPECT_STREQ(reply->robot_class.data(), "Pioneer");
  EXPECT_STREQ(reply->subclass.data(), "p3dx-sh");
}

TEST(P2osGolden, AmrisimStandingSip) {
  // The 89-byte SIP AMRISim sends standing still with 16 sonar at 5000 mm; only the
  // checksum is recomputed here (the brief prints E7 2B for it).
  Bytes body{0x32, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0x82, 0, 0, 0, 0, 0x1E, 0x00, 0x00, 0x10};
  for (std::uint8_t i = 0; i < 16; ++i) {
    body.push_back(i);
    body.push_back(0x88);
    body.push_back(0x13);
  }
  for (int b : {0x00, 0x00, 0x00, 0xFF, 0xFF, 0x82, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x00, 0x81, 0x00})
    body.push_back(static_cast<std::uint8_t>(b));
  const Packet p = make_packet(body[0], std::span<const std::uint8_t>(body).subspan(1));
  EXPECT_EQ(p.size, 89);
  EXPECT_EQ(p.bytes[2], 0x56);
  EXPECT_EQ(p.bytes[87], 0xE7);
  EXPECT_EQ(p.bytes[88], 0x2B);
  std::optional<Sip> sip;
  FrameParser parser;
  parser.feed(p.view(), 0, [&](const Frame& f) { sip = decode_sip(f); });
  ASSERT_TRUE(sip);
  EXPECT_FALSE(sip->moving);
  EXPECT_EQ(sip->battery_dv, 130);
  EXPECT_EQ(sip->flags, 0x1E);
  ASSERT_EQ(sip->sonar_count, 16);
  EXPECT_EQ(sip->sonar[15].disc, 15);
  EXPECT_EQ(sip->sonar[15].range_mm, 5000);
  EXPECT_EQ(sip->digin, 0xFF);
  EXPECT_TRUE(sip->has_battery_x10);
  EXPECT_EQ(sip->battery_x10, 130);
  EXPECT_TRUE(sip->has_rot_vel);
  EXPECT_TRUE(sip->has_soc);
  EXPECT_EQ(sip->temperature_c, -127);
  // Our encoder produces the same bytes from the decoded fields.
  EXPECT_EQ(bytes_of(encode_sip(*sip)), bytes_of(p));
}

TEST(P2osArguments, LenientDecoding) {
  // ROS p2os SETO: a type byte with no value.
  const std::uint8_t bare_int[] = {0x3B};
  CommandArgument a = decode_argument(bare_int);
  EXPECT_EQ(a.kind, ArgKind::integer);
  EXPECT_EQ(a.value, 0);
  const std::uint8_t one_byte[] = {0x1B, 0x05};
  a = decode_argument(one_byte);
  EXPECT_EQ(a.value, -5);
  const std::uint8_t extra[] = {0x3B, 0x10, 0x00, 0x99, 0x98};
  EXPECT_EQ(decode_argument(extra).value, 16);
  EXPECT_EQ(decode_argument({}).kind, ArgKind::none);
  const std::uint8_t unknown[] = {0x77, 1, 2};
  EXPECT_EQ(decode_argument(unknown).kind, ArgKind::none);
  const std::uint8_t short_string[] = {0x2B, 10, 'h', 'i'};
  a = decode_argument(short_string);
  EXPECT_EQ(a.kind, ArgKind::string);
  EXPECT_EQ(a.text.size(), 2u);
}

TEST(P2osArguments, Vel2BothSignEncodings) {
  // left -3, right +5 (x20 mm/s): Player sends raw bytes under 0x3B.
  const Packet player = encode_vel2(-3, 5);
  const CommandArgument pa = decode_argument(player.body().subspan(1));
  Vel2Units u = decode_vel2(pa);
  EXPECT_EQ(u.left, -3);
  EXPECT_EQ(u.right, 5);
  // ARIA: short v = (left << 8) + (right & 0xff) = 0xFD05 = -763, sent as 0x1B + 763.
  const Packet aria = encode_command_int(Command::vel2, static_cast<std::int16_t>(0xFD05));
  EXPECT_EQ(aria.bytes[4], kArgNegInt);
  u = decode_vel2(decode_argument(aria.body().subspan(1)));
  EXPECT_EQ(u.left, -3);
  EXPECT_EQ(u.right, 5);
}

TEST(P2osArguments, EveryFirmwareCommandRoundTrips) {
  struct Case {
    Command command;
    std::int32_t value;
  };
  const Case cases[] = {{Command::enable, 0},   {Command::seta, -300},  {Command::seta, 300},   {Command::setv, 1200},
                        {Command::setrv, 300},  {Command::setra, -100}, {Command::vel, -1500},  {Command::rvel, 45},
                        {Command::head, -180},  {Command::dhead, 90},   {Command::sonar, 0},    {Command::encoder, 2},
                        {Command::hostbaud, 2}, {Command::bumpstall, 3}, {kOpen, 1},            {kClose, 1}};
  for (const Case& c : cases) {
    const Packet p = encode_command_int(c.command, c.value);
    FrameParser parser;
    int frames = 0;
    parser.feed(p.view(), 0, [&](const Frame& f) {
      ++frames;
      EXPECT_EQ(f.type, static_cast<std::uint8_t>(c.command));
      const CommandArgument a = decode_argument(f.payload);
      EXPECT_EQ(a.kind, ArgKind::integer);
      EXPECT_EQ(a.value, c.value) << command_name(f.type);
    });
    EXPECT_EQ(frames, 1);
  }
  for (Command bare : {Command::sync0, Command::sync1, Command::sync2, Command::stop, Command::estop, Command::config}) {
    const Packet p = encode_command(bare);
    EXPECT_EQ(p.size, 6);
    EXPECT_EQ(decode_argument(p.body().subspan(1)).kind, ArgKind::none);
  }
}

TEST(P2osArguments, IntClampsAtSixteenBits) {
  const Packet p = encode_command_int(Command::vel, 100000);
  EXPECT_EQ(decode_argument(p.body().subspan(1)).value, 0xFFFF);
}

TEST(P2osSip, RoundTripAllFieldsAndOptionalTail) {
  Sip s;
  s.moving = true;
  s.x_raw = 0x7FFF;
  s.y_raw = 0x1234;
  s.theta_raw = -2048;
  s.left_vel_mm_s = -300;
  s.right_vel_mm_s = 450;
  s.battery_dv = 121;
  s.stall_bumpers = 0x0302;
  s.control_raw = 77;
  s.flags = 0x0021;
  s.compass_2deg = 90;
  s.sonar_count = 3;
  s.sonar[0] = {1, 500};
  s.sonar[1] = {7, 65535};
  s.sonar[2] = {15, 0};
  s.grip_state = 1;
  s.anport = 2;
  s.analog = 3;
  s.digin = 4;
  s.digout = 5;
  for (int tail = 0; tail <= 7; ++tail) {
    Sip t = s;
    t.has_battery_x10 = tail >= 1;
    t.battery_x10 = 1210;
    t.has_charge_state = tail >= 2;
    t.charge_state = -1;
    t.has_rot_vel = tail >= 3;
    t.rot_vel_ddeg_s = -200;
    t.has_fault_flags = tail >= 4;
    t.fault_flags = 2;
    t.has_lat_vel = tail >= 5;
    t.lat_vel_mm_s = 9;
    t.has_temperature = tail >= 6;
    t.temperature_c = 35;
    t.has_soc = tail >= 7;
    t.soc_pct = 88;
    const Packet p = encode_sip(t);
    std::optional<Sip> d;
    FrameParser parser;
    parser.feed(p.view(), 0, [&](const Frame& f) { d = decode_sip(f); });
    ASSERT_TRUE(d) << tail;
    EXPECT_EQ(d->x_raw, 0x7FFF);
    EXPECT_EQ(d->theta_raw, -2048);
    EXPECT_EQ(d->left_vel_mm_s, -300);
    EXPECT_EQ(d->stall_bumpers, 0x0302);
    EXPECT_EQ(d->sonar[1].range_mm, 65535);
    EXPECT_EQ(d->digout, 5);
    EXPECT_EQ(d->has_battery_x10, tail >= 1);
    EXPECT_EQ(d->has_rot_vel, tail >= 3);
    EXPECT_EQ(d->has_soc, tail >= 7);
    if (tail >= 3) {
      EXPECT_EQ(d->rot_vel_ddeg_s, -200);
    }
    if (tail >= 7) {
      EXPECT_EQ(d->soc_pct, 88);
    }
  }
}

TEST(P2osSip, TooShortForAnnouncedSonarIsRejected) {
  Bytes body(20, 0);
  body[0] = 0x32;
  body[19] = 5;  // five readings announced, none present
  const Packet p = make_packet(0x32, std::span<const std::uint8_t>(body).subspan(1));
  int frames = 0;
  FrameParser parser;
  parser.feed(p.view(), 0, [&](const Frame& f) {
    ++frames;
    EXPECT_FALSE(decode_sip(f));
  });
  EXPECT_EQ(frames, 1);
}

TEST(P2osConfigPacket, RoundTripAndShortPacket) {
  ConfigPacket c;
  std::snprintf(c.robot_class.data(), c.robot_class.size(), "Pioneer");
  std::snprintf(c.subclass.data(), c.subclass.size(), "p3dx-sh");
  std::snprintf(c.name.data(), c.name.size(), "Sen3Bot");
  std::snprintf(c.firmware_version.data(), c.firmware_version.size(), "E.1");
  c.trans_vel_max_mm_s = 1200;
  c.rot_vel_max_deg_s = 300;
  c.watchdog_ms = 2000;
  c.auto_baud = 2;
  c.ticks_mm = 128;
  c.drift_factor = -5;
  c.high_temperature_shutdown_c = 70;
  const Packet p = encode_config(c);
  EXPECT_LE(p.size, kMaxEmitFrameBytes);
  std::optional<ConfigPacket> d;
  FrameParser parser;
  parser.feed(p.view(), 0, [&](const Frame& f) { d = decode_config(f); });
  ASSERT_TRUE(d);
  EXPECT_STREQ(d->subclass.data(), "p3dx-sh");
  EXPECT_STREQ(d->name.data(), "Sen3Bot");
  EXPECT_STREQ(d->firmware_version.data(), "E.1");
  EXPECT_EQ(d->trans_vel_max_mm_s, 1200);
  EXPECT_EQ(d->watchdog_ms, 2000);
  EXPECT_EQ(d->auto_baud, 2);
  EXPECT_EQ(d->ticks_mm, 128);
  EXPECT_EQ(d->drift_factor, -5);
  EXPECT_EQ(d->high_temperature_shutdown_c, 70);
  // A simulator's shorter packet: missing fields read as zero.
  const std::uint8_t shortened[] = {'P', 0, 'x', 0};
  const Packet s = make_packet(kTypeConfig, shortened);
  parser.feed(s.view(), 0, [&](const Frame& f) { d = decode_config(f); });
  ASSERT_TRUE(d);
  EXPECT_STREQ(d->robot_class.data(), "P");
  EXPECT_EQ(d->watchdog_ms, 0);
}

// ---- Parser ----

Bytes sample_stream() {
  Bytes s;
  for (const Packet& p : {encode_command(Command::sync0), encode_command_int(Command::vel, -200),
                          encode_sync2_reply("EMU", "Pioneer", "p3dx-sh"), encode_encoder({1000, -1000}),
                          encode_command_int(Command::enable, 1)}) {
    s.insert(s.end(), p.view().begin(), p.view().end());
  }
  return s;
}

TEST(P2osParser, EmptyInputDoesNothing) {
  FrameParser parser;
  int frames = 0;
  parser.feed({}, 0, [&](const Frame&) { ++frames; });
  EXPECT_EQ(frames, 0);
  EXPECT_EQ(parser.pending_bytes(), 0u);
}

TEST(P2osParser, BackToBackFramesByteByByteAndInRandomChunks) {
  const Bytes stream = sample_stream();
  const Collected whole = parse_all(stream);
  ASSERT_EQ(whole.raw.size(), 5u);
  std::mt19937 rng(12345);
  for (std::size_t max_chunk : {1u, 2u, 3u, 7u, 64u}) {
    FrameParser parser;
    const Collected got = parse_in_chunks(parser, stream, rng, max_chunk);
    EXPECT_EQ(got.raw, whole.raw) << "max chunk " << max_chunk;
    EXPECT_EQ(parser.stats().discarded_bytes, 0u);
  }
}

TEST(P2osParser, GarbageBetweenFramesIsSkipped) {
  const Bytes stream = sample_stream();
  std::mt19937 rng(7);
  Bytes noisy{'W', 'M', 'S', '2', '\r', 0xFA, 0x00, 0xFB, 0xFA};  // ARIA's radio-modem string too
  noisy.insert(noisy.end(), stream.begin(), stream.end());
  for (int i = 0; i < 10; ++i) noisy.push_back(static_cast<std::uint8_t>(rng()) & 0x7F);
  noisy.insert(noisy.end(), stream.begin(), stream.end());
  FrameParser parser;
  const Collected got = parse_in_chunks(parser, noisy, rng, 5);
  EXPECT_EQ(got.raw.size(), 10u);
}

TEST(P2osParser, BadChecksumDroppedAndCounted) {
  Bytes stream = bytes_of(encode_command_int(Command::enable, 1));
  stream.back() ^= 0x01;
  const Bytes good = bytes_of(encode_command(Command::sync0));
  stream.insert(stream.end(), good.begin(), good.end());
  FrameParser parser;
  std::vector<std::uint8_t> types;
  parser.feed(stream, 0, [&](const Frame& f) { types.push_back(f.type); });
  EXPECT_EQ(types, (std::vector<std::uint8_t>{0x00}));
  EXPECT_EQ(parser.stats().bad_checksums, 1u);
}

TEST(P2osParser, LengthBelowThreeRejected) {
  for (int n : {0, 1, 2}) {
    Bytes stream{0xFA, 0xFB, static_cast<std::uint8_t>(n), 0x00, 0x00, 0x00};
    const Bytes good = bytes_of(encode_command(Command::sync1));
    stream.insert(stream.end(), good.begin(), good.end());
    FrameParser parser;
    std::vector<std::uint8_t> types;
    parser.feed(stream, 0, [&](const Frame& f) { types.push_back(f.type); });
    EXPECT_EQ(types, (std::vector<std::uint8_t>{0x01})) << int(n);
    EXPECT_EQ(parser.stats().bad_lengths, 1u);
  }
}

TEST(P2osParser, OversizeHeaderDoesNotSwallowFollowingFrames) {
  // A corrupt header claiming 255 bytes, followed by real frames filling that length: the
  // rescan after the bad checksum still finds every real frame.
  Bytes stream{0xFA, 0xFB, 0xFF};
  while (stream.size() < 300) {
    const Bytes good = bytes_of(encode_command_int(Command::vel, 100));
    stream.insert(stream.end(), good.begin(), good.end());
  }
  const std::size_t real_frames = (stream.size() - 3) / 9;
  FrameParser parser;
  std::size_t frames = 0;
  parser.feed(stream, 0, [&](const Frame&) { ++frames; });
  EXPECT_EQ(frames, real_frames);
}

TEST(P2osParser, TruncatedFrameThenGapIsDropped) {
  const Bytes full = bytes_of(encode_command_int(Command::vel, 200));
  FrameParser parser;
  int frames = 0;
  parser.feed(std::span<const std::uint8_t>(full).first(5), 0, [&](const Frame&) { ++frames; });
  // 50 ms later the rest arrives: still within the 100 ms inter-byte allowance.
  parser.feed(std::span<const std::uint8_t>(full).subspan(5), hal::millis(50), [&](const Frame&) { ++frames; });
  EXPECT_EQ(frames, 1);
  // A truncated frame, then silence past the gap, then a whole new frame.
  parser.feed(std::span<const std::uint8_t>(full).first(5), hal::millis(100), [&](const Frame&) { ++frames; });
  parser.feed(full, hal::millis(300), [&](const Frame&) { ++frames; });
  EXPECT_EQ(frames, 2);
  EXPECT_EQ(parser.stats().gap_timeouts, 1u);
}

TEST(P2osParser, SplitAcrossManyReadsWithRandomCorruption) {
  // Fixed-seed soak: every intact frame comes out exactly once, corrupt ones never do.
  std::mt19937 rng(2024);
  Bytes stream;
  std::size_t intact = 0;
  for (int i = 0; i < 500; ++i) {
    Bytes f = bytes_of(encode_command_int(Command::vel, static_cast<std::int32_t>(rng() % 2000) - 1000));
    if (rng() % 5 == 0) {
      f[3 + rng() % (f.size() - 3)] ^= static_cast<std::uint8_t>(1 + rng() % 255);
    } else {
      ++intact;
    }
    stream.insert(stream.end(), f.begin(), f.end());
  }
  FrameParser parser;
  const Collected got = parse_in_chunks(parser, stream, rng, 17);
  // A corrupted length byte can make a frame unparseable together with its neighbour, but
  // never produce a frame that was not sent.
  EXPECT_LE(got.raw.size(), intact);
  EXPECT_GE(got.raw.size(), intact * 9 / 10);
  for (const Bytes& raw : got.raw) {
    ASSERT_EQ(raw.size(), 9u);
    EXPECT_EQ(raw[3], static_cast<std::uint8_t>(Command::vel));
  }
}

}  // namespace
}  // namespace sen3bot::p2os
