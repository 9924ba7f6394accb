// The committed candump log of the e-stop scenario (tests/data/can/io_node_estop.log, see
// estop_log.hpp) replayed through a fresh master at the log's times: every frame on the bus
// is fed to it (its own included, as a bus log holds them; it must ignore them), and it is
// polled on its 10 ms grid with the robot's light rule applied, as the recorded master was.
// The master's timeline is checked against the scenario, and what it sends against what the
// log says the master sent. A log recorded on a real bus replays the same way.
#include <gtest/gtest.h>

#include <array>
#include <fstream>
#include <optional>
#include <sstream>
#include <string>
#include <vector>

#include "text_file.hpp"
#include "estop_log.hpp"
#include "sen3bot/canopen/codec.hpp"
#include "sen3bot/canopen/io_node.hpp"
#include "sen3bot/hal/candump.hpp"

namespace sen3bot::canopen {
namespace {

using namespace estop_log;

const std::string kLogPath = std::string(SEN3BOT_SOURCE_DIR) + "/tests/data/can/io_node_estop.log";

using sen3bot::testing::read_file;

std::vector<hal::CandumpLine> read_log() {
  std::vector<hal::CandumpLine> lines;
  std::istringstream in(read_file(kLogPath));
  std::string text;
  for (int number = 1; std::getline(in, text); ++number) {
    Result<hal::CandumpLine> line = hal::parse_candump_line(text);
    EXPECT_TRUE(line) << "line " << number << ": " << (line ? "" : line.error().c_str());
    if (line) lines.push_back(*line);
  }
  return lines;
}

// Seconds since the scenario's start, for messages and comparisons.
double at_s(hal::Nanos unix_ns) { return hal::to_seconds(unix_ns - kStartUnixNs); }

struct Sent {
  hal::Nanos unix_ns;
  CanFrame frame;
};

// What the replay saw: the first time each thing happened (-1: never).
struct Timeline {
  hal::Nanos boot_up = -1;
  hal::Nanos operational = -1;
  hal::Nanos inputs_valid = -1;
  hal::Nanos pressed = -1;    // input 1 low while valid
  hal::Nanos released = -1;   // input 1 high again, after the press
  hal::Nanos emergency = -1;
  hal::Nanos lost = -1;
  hal::Nanos last_heartbeat = -1;  // the node's last heartbeat line before the loss
  bool inputs_dropped = false;     // inputs went invalid between becoming valid and the loss
  std::vector<Sent> master_sent;   // what the replayed master sent
  std::vector<Sent> master_logged; // the master's frames in the log
};

class EstopReplay : public ::testing::Test {
 protected:
  static void SetUpTestSuite() {
    lines_ = new std::vector<hal::CandumpLine>(read_log());
    timeline_ = new Timeline(replay(*lines_));
  }
  static void TearDownTestSuite() {
    delete lines_;
    delete timeline_;
  }

  static Timeline replay(const std::vector<hal::CandumpLine>& lines) {
    Timeline t;
    IoNodeConfig config;
    config.node = kNode;
    master_ = new IoNodeMaster(config);
    IoNodeMaster& m = *master_;
    // After every step: note what changed.
    const auto observe = [&](hal::Nanos now) {
      if (t.lost < 0 && m.count(IoNodeEvent::heartbeat_lost) > 0) t.lost = now;
      if (t.operational < 0 && m.state() == IoNodeState::operational) t.operational = now;
      if (t.inputs_valid < 0 && m.inputs_valid()) t.inputs_valid = now;
      if (t.inputs_valid >= 0 && t.lost < 0 && !m.inputs_valid()) t.inputs_dropped = true;
      if (m.inputs_valid() && t.pressed < 0 && (m.inputs() & 0x01) == 0) t.pressed = now;
      if (m.inputs_valid() && t.pressed >= 0 && t.released < 0 && (m.inputs() & 0x01) != 0) t.released = now;
      if (t.emergency < 0 && m.count(IoNodeEvent::emergency) > 0) t.emergency = now;
    };
    hal::Nanos cycle = kStartUnixNs;
    const auto run_cycle = [&] {
      m.set_outputs(light_for(m));
      std::array<CanFrame, 4> out{};
      const std::size_t n = m.poll(cycle, out);
      for (std::size_t i = 0; i < n; ++i) t.master_sent.push_back({cycle, out[i]});
      observe(cycle);
      cycle += kMasterCycle;
    };
    for (const hal::CandumpLine& line : lines) {
      // The cycles before this frame; a frame stamped on a cycle's instant came before its poll.
      while (cycle < line.unix_ns) run_cycle();
      const Classified c = classify(line.frame);
      const bool from_master = c.kind == Kind::nmt || c.kind == Kind::sdo_request || c.kind == Kind::rpdo;
      if (from_master) t.master_logged.push_back({line.unix_ns, line.frame});
      if (c.kind == Kind::heartbeat && c.node == kNode) {
        if (line.frame.dlc >= 1 && line.frame.data[0] == 0x00 && t.boot_up < 0) t.boot_up = line.unix_ns;
        if (t.lost < 0) t.last_heartbeat = line.unix_ns;
      }
      m.on_frame(line.frame, line.unix_ns);
      observe(line.unix_ns);
    }
    while (cycle <= kStartUnixNs + kEnd) run_cycle();
    return t;
  }

  static std::vector<hal::CandumpLine>* lines_;
  static Timeline* timeline_;
  static IoNodeMaster* master_;
};
std::vector<hal::CandumpLine>* EstopReplay::lines_ = nullptr;
Timeline* EstopReplay::timeline_ = nullptr;
IoNodeMaster* EstopReplay::master_ = nullptr;

TEST_F(EstopReplay, TheLogIsACandumpLogOfCan0InTimeOrder) {
  const std::vector<hal::CandumpLine>& lines = *lines_;
  ASSERT_GT(lines.size(), 150u);
  hal::Nanos previous = 0;
  for (const hal::CandumpLine& l : lines) {
    EXPECT_EQ(l.interface_name(), "can0");
    EXPECT_FALSE(l.error_frame);
    EXPECT_GE(l.unix_ns, previous);
    previous = l.unix_ns;
  }
  EXPECT_GE(lines.front().unix_ns, kStartUnixNs);
  EXPECT_LE(lines.back().unix_ns, kStartUnixNs + kEnd + hal::millis(2));
}

TEST_F(EstopReplay, TheNodeBootsAndIsOperationalWithValidInputs) {
  const Timeline& t = *timeline_;
  ASSERT_GE(t.boot_up, 0) << "no boot-up in the log";
  EXPECT_GE(t.boot_up, kStartUnixNs + kPowerUp);
  EXPECT_LE(t.boot_up, kStartUnixNs + kPowerUp + hal::millis(2));
  ASSERT_GE(t.operational, 0) << "never operational";
  // Four SDO writes one master cycle apart, NMT start, then the next heartbeat (100 ms).
  EXPECT_GT(t.operational, t.boot_up + hal::millis(40)) << at_s(t.operational);
  EXPECT_LE(t.operational, t.boot_up + hal::millis(200)) << at_s(t.operational);
  // TPDO1's event timer (100 ms) brings the inputs after the start.
  ASSERT_GE(t.inputs_valid, t.operational);
  EXPECT_LE(t.inputs_valid, t.operational + hal::millis(110)) << at_s(t.inputs_valid);
  EXPECT_EQ(master_->count(IoNodeEvent::boot_up), 1u);
  EXPECT_EQ(master_->count(IoNodeEvent::configured), 1u);
  EXPECT_EQ(master_->count(IoNodeEvent::sdo_abort), 0u);
  EXPECT_EQ(master_->count(IoNodeEvent::sdo_timeout), 0u);
  // Its own frames, SDO requests and RPDOs among them, were all ignored.
  EXPECT_EQ(master_->count(IoNodeEvent::unexpected_frame), 0u);
}

TEST_F(EstopReplay, HeartbeatsCome100MsApartUntilTheCableIsPulled) {
  std::vector<hal::Nanos> beats;
  for (const hal::CandumpLine& l : *lines_) {
    const Classified c = classify(l.frame);
    if (c.kind == Kind::heartbeat && l.frame.dlc == 1 && l.frame.data[0] != 0x00) beats.push_back(l.unix_ns);
  }
  ASSERT_GT(beats.size(), 70u);
  for (std::size_t i = 1; i < beats.size(); ++i) {
    EXPECT_GE(beats[i] - beats[i - 1], hal::millis(99)) << at_s(beats[i]);
    EXPECT_LE(beats[i] - beats[i - 1], hal::millis(101)) << at_s(beats[i]);
  }
  EXPECT_LT(beats.back(), kStartUnixNs + kUnplug);
  EXPECT_GT(beats.back(), kStartUnixNs + kUnplug - hal::millis(101));
}

TEST_F(EstopReplay, TheEstopPressIsInput1LowAndTheReleaseHigh) {
  const Timeline& t = *timeline_;
  ASSERT_GE(t.pressed, 0) << "the press was not seen";
  EXPECT_GE(t.pressed, kStartUnixNs + kPress);
  EXPECT_LE(t.pressed, kStartUnixNs + kPress + hal::millis(20)) << at_s(t.pressed);
  ASSERT_GE(t.released, 0) << "the release was not seen";
  EXPECT_GE(t.released, kStartUnixNs + kRelease);
  EXPECT_LE(t.released, kStartUnixNs + kRelease + hal::millis(20)) << at_s(t.released);
  // The inputs stayed valid from the start to the loss: the press is a value, not a gap.
  EXPECT_FALSE(t.inputs_dropped);
}

TEST_F(EstopReplay, TheEmergencyIsCountedAndDecoded) {
  const Timeline& t = *timeline_;
  ASSERT_GE(t.emergency, 0);
  EXPECT_GE(t.emergency, kStartUnixNs + kEmergency);
  EXPECT_LE(t.emergency, kStartUnixNs + kEmergency + hal::millis(10));
  EXPECT_EQ(master_->count(IoNodeEvent::emergency), 1u);
  EXPECT_EQ(master_->count(IoNodeEvent::emergency_reset), 0u);
  EXPECT_EQ(master_->last_emergency().code, kEmergencyCode);
  EXPECT_EQ(master_->last_emergency().error_register, kEmergencyRegister);
  EXPECT_STREQ(describe_emergency(master_->last_emergency().code), "current");
}

TEST_F(EstopReplay, TheSilentNodeIsLostAtTheHeartbeatTimeout) {
  const Timeline& t = *timeline_;
  ASSERT_GE(t.lost, 0) << "never lost";
  // 0.35 s after the last heartbeat, at the first master cycle past it.
  EXPECT_GT(t.lost - t.last_heartbeat, hal::millis(350)) << at_s(t.lost);
  EXPECT_LE(t.lost - t.last_heartbeat, hal::millis(350) + kMasterCycle) << at_s(t.lost);
  EXPECT_GT(t.lost, kStartUnixNs + kUnplug);
  EXPECT_EQ(master_->count(IoNodeEvent::heartbeat_lost), 1u);
  EXPECT_NE(master_->state(), IoNodeState::operational);
  EXPECT_FALSE(master_->inputs_valid());
}

TEST_F(EstopReplay, TheReplayedMasterSendsWhatTheLoggedMasterSent) {
  const Timeline& t = *timeline_;
  ASSERT_EQ(t.master_sent.size(), t.master_logged.size());
  for (std::size_t i = 0; i < t.master_sent.size(); ++i) {
    EXPECT_EQ(t.master_sent[i].frame, t.master_logged[i].frame)
        << "frame " << i << " at " << at_s(t.master_sent[i].unix_ns);
    // The log stamps a frame at the end of its transmission, shortly after the poll.
    EXPECT_GE(t.master_logged[i].unix_ns, t.master_sent[i].unix_ns);
    EXPECT_LE(t.master_logged[i].unix_ns, t.master_sent[i].unix_ns + hal::millis(2));
  }
  // The light: red until the inputs are valid, green, red while pressed, green after.
  std::vector<std::uint8_t> lights;
  for (const Sent& s : t.master_logged) {
    const Classified c = classify(s.frame);
    if (c.kind == Kind::rpdo && (lights.empty() || lights.back() != s.frame.data[0])) lights.push_back(s.frame.data[0]);
  }
  EXPECT_EQ(lights, (std::vector<std::uint8_t>{kRed, kGreen, kRed, kGreen}));
}

TEST(EstopLog, TheGeneratorWritesTheCommittedLog) {
  // The log is the emulator's and the master's traffic: if this fails, their behaviour changed;
  // regenerate with canopen_generate_estop_log (tests/data/can/README.md) and review the diff.
  EXPECT_EQ(make_log(), read_file(kLogPath));
}

}  // namespace
}  // namespace sen3bot::canopen
