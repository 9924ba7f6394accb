// ARIA compatibility, kept true: the checked-in capture of what an ARIA client sends on one
// TCP connection (tests/data/captures/aria_session.s3bcap, written by p2os_generate) is
// replayed with its own timing against the emulator's TCP runner over a real socket, and the
// robot's answers are checked the way ARIA reads them.
#include <gtest/gtest.h>

#include <fstream>
#include <sstream>
#include <string>
#include <vector>

#include "sen3bot/capture/reader.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/tcp.hpp"
#include "sen3bot/p2os/codec.hpp"
#include "sen3bot/p2os/describe.hpp"
#include "sen3bot/sim/p2os/emulator_runner.hpp"

namespace sen3bot::p2os {
namespace {

const std::string kCapture = std::string(SEN3BOT_SOURCE_DIR) + "/tests/data/captures/aria_session.s3bcap";
const std::string kDecoded = std::string(SEN3BOT_SOURCE_DIR) + "/tests/data/captures/aria_session.jsonl";

struct Sent {
  hal::Nanos t_ns = 0;  // since the connection, when it was written
  std::uint8_t command = 0;
  CommandArgument arg;
};

struct Got {
  hal::Nanos t_ns = 0;  // since the connection, when it was read
  std::uint8_t type = 0;
  std::vector<std::uint8_t> raw;
};

template <typename F>
auto with_frame(const Got& g, F&& f) {
  FrameParser parser;
  std::optional<decltype(f(std::declval<const Frame&>()))> out;
  parser.feed(g.raw, 0, [&](const Frame& frame) { out = f(frame); });
  return out;
}

constexpr std::uint8_t cmd(Command c) { return static_cast<std::uint8_t>(c); }

std::vector<std::uint8_t> bytes_of(const Packet& p) { return {p.view().begin(), p.view().end()}; }

struct Replay {
  std::vector<Sent> sent;
  std::vector<Got> got;
  hal::Nanos eof_ns = -1;  // when the robot closed the connection; -1 if it did not
  std::string error;

  [[nodiscard]] hal::Nanos sent_at(std::uint8_t command, int occurrence = 0) const {
    for (const Sent& s : sent)
      if (s.command == command && occurrence-- == 0) return s.t_ns;
    return -1;
  }
  [[nodiscard]] std::vector<std::pair<hal::Nanos, Sip>> sips() const {
    std::vector<std::pair<hal::Nanos, Sip>> out;
    for (const Got& g : got) {
      if (g.type != kTypeSipStopped && g.type != kTypeSipMoving) continue;
      if (auto sip = with_frame(g, [](const Frame& f) { return decode_sip(f); }); sip && *sip)
        out.emplace_back(g.t_ns, **sip);
    }
    return out;
  }
};

// Writes each tx record of the capture when it is due (relative to the connection), reading
// and parsing the robot's answers all the while, then waits up to `linger` for the close.
Replay replay(const capture::CaptureFile& capture, TcpEmulatorRunner& runner, hal::Nanos linger) {
  Replay r;
  const capture::ChannelDecl* channel = capture.find_channel("p2os");
  if (channel == nullptr) {
    r.error = "no p2os channel";
    return r;
  }
  auto stream = hal::TcpStream::connect("127.0.0.1", runner.port(), 2000);
  if (!stream) {
    r.error = stream.error().c_str();
    return r;
  }
  hal::PosixClock clock;
  const hal::Nanos start = clock.now();
  FrameParser parser;
  auto pump = [&](hal::Nanos until_ns) {
    while (clock.now() < until_ns && r.eof_ns < 0) {
      std::uint8_t chunk[512];
      const Result<std::size_t> got = (*stream)->read(chunk);
      const hal::Nanos t = clock.now() - start;
      if (!got) {
        if (got.error().code() == Errc::disconnected) r.eof_ns = t;
        else r.error = got.error().c_str();
        return;
      }
      if (*got == 0) {
        clock.sleep_until(std::min(until_ns, clock.now() + hal::millis(1)));
        continue;
      }
      parser.feed(std::span<const std::uint8_t>(chunk, *got), t, [&](const Frame& f) {
        r.got.push_back(Got{t, f.type, std::vector<std::uint8_t>(f.raw.begin(), f.raw.end())});
      });
    }
  };
  for (const capture::Record& record : capture.records()) {
    if (record.channel != channel->id || record.kind != capture::RecordKind::tx) continue;
    pump(start + record.t_ns);
    if (r.eof_ns >= 0 || !r.error.empty()) return r;
    const Result<std::size_t> wrote = (*stream)->write(record.payload);
    if (!wrote || *wrote != record.payload.size()) {
      r.error = "short write";
      return r;
    }
    FrameParser sent_parser;
    sent_parser.feed(record.payload, 0, [&](const Frame& f) {
      r.sent.push_back(Sent{clock.now() - start, f.type, decode_argument(f.payload)});
    });
  }
  pump(clock.now() + linger);
  return r;
}

TEST(P2osAria, CaptureDecodesToTheCheckedInLines) {
  auto capture = capture::CaptureFile::load(kCapture);
  ASSERT_TRUE(capture) << capture.error().c_str();
  std::ostringstream decoded;
  ASSERT_TRUE(decode_capture(*capture, "", [&](const std::string& line) { decoded << line << '\n'; }));
  std::ifstream in(kDecoded);
  std::stringstream expected;
  expected << in.rdbuf();
  ASSERT_FALSE(expected.str().empty());
  EXPECT_EQ(decoded.str(), expected.str());
}

TEST(P2osAria, SessionReplayedOverTcpGetsTheAnswersAriaExpects) {
  auto capture = capture::CaptureFile::load(kCapture);
  ASSERT_TRUE(capture) << capture.error().c_str();
  EmulatorConfig config;  // the P3-DX defaults
  auto runner = TcpEmulatorRunner::start(config, 0);
  ASSERT_TRUE(runner) << runner.error().c_str();
  const Replay r = replay(*capture, **runner, hal::seconds(1));
  ASSERT_TRUE(r.error.empty()) << r.error;
  ASSERT_GE(r.got.size(), 3u);

  // Handshake: byte-exact echoes of SYNC0 and SYNC1, then name/class/subclass, each at once.
  const hal::Nanos sync0 = r.sent_at(0), sync1 = r.sent_at(1), sync2 = r.sent_at(2);
  ASSERT_TRUE(sync0 >= 0 && sync1 > sync0 && sync2 > sync1);
  EXPECT_EQ(r.got[0].raw, bytes_of(encode_command(Command::sync0)));
  EXPECT_EQ(r.got[1].raw, bytes_of(encode_command(Command::sync1)));
  EXPECT_EQ(r.got[2].type, kTypeSync2);
  // ARIA waits up to 1 s for each; half of that leaves room for sanitizers, qemu and a busy
  // machine, whose pauses stamp an answer late (the time is when this test read it).
  EXPECT_LT(r.got[0].t_ns - sync0, hal::millis(500));
  EXPECT_LT(r.got[1].t_ns - sync1, hal::millis(500));
  EXPECT_LT(r.got[2].t_ns - sync2, hal::millis(500));
  const auto reply = with_frame(r.got[2], [](const Frame& f) { return decode_sync2_reply(f); });
  ASSERT_TRUE(reply && *reply);
  EXPECT_STREQ((*reply)->name.data(), config.name.c_str());
  EXPECT_STREQ((*reply)->robot_class.data(), "Pioneer");
  EXPECT_STREQ((*reply)->subclass.data(), "p3dx-sh");  // ARIA has parameters for this one

  // OPEN (the second command 1) starts SIPs every SipCycle; none before it.
  const hal::Nanos open = r.sent_at(1, 1);
  const hal::Nanos close = r.sent_at(2, 1);
  ASSERT_GT(open, 0);
  ASSERT_GT(close, open);
  const auto sips = r.sips();
  ASSERT_FALSE(sips.empty());
  EXPECT_GT(sips.front().first, open);
  EXPECT_LT(sips.front().first - open, hal::millis(500));
  const double expected_sips = static_cast<double>(close - open) / 1e8;  // one per 100 ms
  EXPECT_NEAR(static_cast<double>(sips.size()), expected_sips, 0.2 * expected_sips);
  bool config_reply = false;
  for (const Got& g : r.got) config_reply = config_reply || g.type == kTypeConfig;
  EXPECT_TRUE(config_reply);

  // Motors on after ENABLE 1; moving forward after VEL 250, turning left after RVEL 20;
  // stopped after stop(); motors off after ENABLE 0.
  const hal::Nanos enable = r.sent_at(cmd(Command::enable), 0), disable = r.sent_at(cmd(Command::enable), 1);
  const hal::Nanos vel = r.sent_at(cmd(Command::vel), 0), stop = r.sent_at(cmd(Command::vel), 4);
  const hal::Nanos rvel = r.sent_at(cmd(Command::rvel), 2);  // the first non-zero one
  ASSERT_GT(vel, enable);
  ASSERT_GT(stop, rvel);
  bool drove = false, turned = false;
  int disabled_sips = 0;
  std::uint16_t x_at_vel = 0;
  for (const auto& [t, s] : sips) {
    const bool motors = (s.flags & flags::kMotorsEnabled) != 0;
    if (t > enable + hal::millis(150) && t < disable) {
      EXPECT_TRUE(motors) << "SIP at " << t;
    }
    if (t > disable + hal::millis(25)) {
      EXPECT_FALSE(motors) << "SIP at " << t;
      disabled_sips += 1;
    }
    if (t < vel) x_at_vel = s.x_raw;
    if (t > vel + hal::millis(300) && t < stop) {
      EXPECT_TRUE(s.moving);
      EXPECT_GT(s.left_vel_mm_s + s.right_vel_mm_s, 0);
      drove = drove || s.x_raw > x_at_vel + 200;
    }
    if (t > rvel + hal::millis(500) && t < stop) turned = turned || s.theta_raw > 0;
    if (t > stop + hal::millis(900) && t < close) {  // braking from 250 mm/s takes 0.83 s
      EXPECT_FALSE(s.moving);
      EXPECT_EQ(s.left_vel_mm_s, 0);
      EXPECT_EQ(s.right_vel_mm_s, 0);
    }
    EXPECT_LT(t, close + hal::millis(300)) << "a SIP after CLOSE";
  }
  EXPECT_TRUE(drove);
  EXPECT_TRUE(turned);
  EXPECT_GE(disabled_sips, 1);  // the capture puts a SIP between ENABLE 0 and CLOSE

  // CLOSE ends the session and the connection: ARIA reads EOF rather than a silent socket.
  ASSERT_GE(r.eof_ns, 0) << "the connection stayed open after CLOSE";
  EXPECT_LT(r.eof_ns - close, hal::millis(1000));
  EXPECT_EQ((*runner)->connections_closed(), 1u);
  EXPECT_EQ((*runner)->clients_served(), 1u);
  const EmulatorStats stats = (*runner)->with_emulator([](P2osEmulator& e) { return e.stats(); });
  EXPECT_EQ(stats.bad_checksums, 0u);
  EXPECT_EQ(stats.packets_received, r.sent.size());
  EXPECT_EQ(stats.sessions_opened, 1u);
  EXPECT_EQ(stats.sessions_closed, 1u);
  EXPECT_EQ(stats.watchdog_stops, 0u);
  const Pose2 truth = (*runner)->with_emulator([](P2osEmulator& e) { return e.ground_truth(); });
  EXPECT_GT(truth.x_m, 0.4);
  EXPECT_GT(truth.theta_rad, 0.1);
}

}  // namespace
}  // namespace sen3bot::p2os
