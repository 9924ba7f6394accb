// The e-stop chain end to end, in lockstep on the simulated robot (config/sim.yaml): the
// CANopen I/O node's emulator on the board's CAN bus, the CAN I/O task, the safety task's
// latch and the base driver, measured on the P2OS wire. An e-stop pressed while driving must
// put VEL 0 on the wire within two control periods; releasing it alone keeps the robot
// stopped; a reset lets it go on. A silent node and a bus that goes off stop it too.
#include <gtest/gtest.h>

#include <algorithm>
#include <cstdio>
#include <vector>

#include "firmware.hpp"
#include "sim_rig.hpp"
#include "task_table.hpp"
#include "vel_recorder.hpp"
#include "stats.hpp"

namespace sen3bot {
namespace {

using testing::VelPacket;
using testing::VelRecorder;

// config/sim.yaml's wiring: the chain on input 1 (active-low), reset on 2, bumpers on 3 and 4;
// light outputs idle 1, driving 2, wait4col 3, fault 4; buzzer 5.
constexpr std::uint8_t kChainClosed = 0x01;
constexpr std::uint8_t kPressed = 0x00;
constexpr std::uint8_t kResetButton = 0x02;
constexpr std::uint8_t kBumper = 0x04;
constexpr std::uint8_t kLightIdle = 0x01, kLightDriving = 0x02, kLightFault = 0x08, kBuzzer = 0x10;

constexpr hal::Nanos kControlPeriodNs = hal::micros(firmware::row("safety").period_us);

class EstopRig {
 public:
  EstopRig() : rig_(testing::load_sim_rig()) {
    sink_ = std::fopen("/dev/null", "w");
    fw_ = std::make_unique<firmware::Firmware>(rig_.config, *rig_.board, sink_);
    recorder_ = std::make_unique<VelRecorder>(*fw_);
    rig_.board->set_wire_tap(recorder_.get());
  }
  ~EstopRig() {
    fw_->shutdown();
    std::fclose(sink_);
  }
  [[nodiscard]] Status init() { return fw_->init(); }

  void run_for(hal::Nanos duration) {
    const hal::Nanos end = now() + duration;
    while (now() < end) ASSERT_TRUE(fw_->scheduler().run_lockstep(rig_.clock(), hal::millis(1)));
  }
  // Runs in 1 ms slices until the newest VEL on the wire moves the robot (false after `limit`).
  bool run_until_driving(hal::Nanos limit) {
    const hal::Nanos end = now() + limit;
    while (now() < end) {
      if (!fw_->scheduler().run_lockstep(rig_.clock(), hal::millis(1))) return false;
      if (!packets().empty() && packets().back().vel_mm_s > 50) return true;
    }
    return false;
  }
  // The first VEL 0 on the wire at or after t_ns, running on until it comes (or `limit`).
  const VelPacket* first_stop_after(hal::Nanos t_ns, hal::Nanos limit) {
    const hal::Nanos end = now() + limit;
    for (;;) {
      for (const VelPacket& p : packets())
        if (p.t_ns >= t_ns && p.vel_mm_s == 0) return &p;
      if (now() >= end) return nullptr;
      if (!fw_->scheduler().run_lockstep(rig_.clock(), hal::millis(1))) return nullptr;
    }
  }
  // The wheels were told to stand at `from` and told nothing else until `to` (the driver
  // writes a VEL when the speed changes).
  bool all_stopped(hal::Nanos from, hal::Nanos to) const {
    const VelPacket* last = nullptr;
    for (const VelPacket& p : packets()) {
      if (p.t_ns >= to) break;
      if (p.t_ns >= from && p.vel_mm_s != 0) return false;
      last = &p;
    }
    return last != nullptr && last->vel_mm_s == 0;
  }
  void press_reset() {
    node().set_inputs(kChainClosed | kResetButton);
    run_for(hal::millis(100));
    node().set_inputs(kChainClosed);
  }

  hal::Nanos now() { return rig_.clock().now(); }
  const std::vector<VelPacket>& packets() const { return recorder_->packets; }
  canopen::IoNodeEmulator& node() { return *rig_.board->io_node(); }
  sim::SimBoard& board() { return *rig_.board; }
  firmware::Firmware& fw() { return *fw_; }
  const firmware::FirmwareConfig& config() const { return rig_.config; }
  std::uint32_t reasons() const {
    tasks::Sample<msg::SafetyOutput> s;
    return fw_->safety_output().read(s) ? s.value.reasons : 0;
  }

 private:
  testing::SimRig rig_;
  std::FILE* sink_ = nullptr;
  std::unique_ptr<firmware::Firmware> fw_;
  std::unique_ptr<VelRecorder> recorder_;
};

TEST(EstopChain, PressWhileDrivingStopsWithinTwoControlPeriodsAndHoldsUntilReset) {
  EstopRig rig;
  ASSERT_TRUE(rig.board().io_node() != nullptr) << "config/sim.yaml has sim.io_node";
  ASSERT_TRUE(rig.init());
  ASSERT_NE(rig.fw().can_io(), nullptr);
  rig.run_for(hal::seconds(1));
  EXPECT_EQ(rig.fw().can_io()->master().state(), canopen::IoNodeState::operational);
  EXPECT_EQ(rig.node().outputs(), kLightIdle) << "standing: the idle light";

  // Presses at different phases of the 10 ms control grid and the node's 5 ms grid.
  std::vector<double> latency_ms;
  for (int press = 0; press < 8; ++press) {
    ASSERT_TRUE(rig.run_until_driving(hal::seconds(10))) << "press " << press;
    rig.run_for(hal::millis(300 + 7 * press));
    EXPECT_EQ(rig.node().outputs(), kLightDriving);
    const hal::Nanos pressed_ns = rig.now();
    rig.node().set_inputs(kPressed);
    const VelPacket* stop = rig.first_stop_after(pressed_ns, hal::millis(200));
    ASSERT_NE(stop, nullptr) << "no VEL 0 after the e-stop";
    latency_ms.push_back(static_cast<double>(stop->t_ns - pressed_ns) * 1e-6);
    EXPECT_NE(stop->safety.value.reasons & msg::kSafetyEstopChain, 0u);
    rig.run_for(hal::millis(500));
    EXPECT_TRUE(rig.all_stopped(stop->t_ns, rig.now()));
    EXPECT_EQ(rig.node().outputs() & kLightFault, kLightFault) << "held: the fault light";

    // Released without a reset: stays stopped (and says why).
    const hal::Nanos released_ns = rig.now();
    rig.node().set_inputs(kChainClosed);
    rig.run_for(hal::seconds(2));
    EXPECT_TRUE(rig.all_stopped(released_ns, rig.now())) << "released without a reset must stay stopped";
    EXPECT_EQ(rig.reasons() & msg::kSafetyResetNeeded, msg::kSafetyResetNeeded);
    rig.press_reset();
    EXPECT_EQ(rig.reasons() & (msg::kSafetyResetNeeded | msg::kSafetyEstopChain), 0u);
  }
  ASSERT_TRUE(rig.run_until_driving(hal::seconds(10))) << "a reset lets the robot go on";
  const double worst = *std::max_element(latency_ms.begin(), latency_ms.end());
  std::printf("e-stop edge -> VEL 0 on the P2OS wire: %zu presses, median %.1f ms, max %.1f ms (2 control periods: %.1f ms)\n",
              latency_ms.size(), test::median(latency_ms), worst, 2 * hal::to_seconds(kControlPeriodNs) * 1e3);
  EXPECT_LE(worst, 2 * hal::to_seconds(kControlPeriodNs) * 1e3);
  ASSERT_NE(rig.fw().safety(), nullptr);
  ASSERT_NE(rig.fw().safety()->latch(), nullptr);
  EXPECT_EQ(rig.fw().safety()->latch()->trips(), 8u);
}

TEST(EstopChain, TheBuzzerSoundsInFaultAndTheLightShowsIt) {
  EstopRig rig;
  ASSERT_TRUE(rig.init());
  rig.run_for(hal::seconds(1));
  rig.node().set_inputs(kPressed);
  int buzzing = 0, silent = 0;
  for (int i = 0; i < 200; ++i) {
    rig.run_for(hal::millis(10));
    if (i < 5) continue;
    EXPECT_EQ(rig.node().outputs() & ~kBuzzer, kLightFault);
    ((rig.node().outputs() & kBuzzer) != 0 ? buzzing : silent)++;
  }
  // On for half of each second.
  EXPECT_NEAR(buzzing, silent, 20);
}

TEST(EstopChain, ABumperStopsAndHoldsLikeTheEstop) {
  EstopRig rig;
  ASSERT_TRUE(rig.init());
  ASSERT_TRUE(rig.run_until_driving(hal::seconds(10)));
  const hal::Nanos hit_ns = rig.now();
  rig.node().set_inputs(kChainClosed | kBumper);
  const VelPacket* stop = rig.first_stop_after(hit_ns, hal::millis(200));
  ASSERT_NE(stop, nullptr);
  EXPECT_LE(stop->t_ns - hit_ns, 2 * kControlPeriodNs);
  EXPECT_NE(stop->safety.value.reasons & msg::kSafetyBumper, 0u);
  rig.node().set_inputs(kChainClosed);
  const hal::Nanos released_ns = rig.now();
  rig.run_for(hal::seconds(1));
  EXPECT_TRUE(rig.all_stopped(released_ns, rig.now()));
  rig.press_reset();
  EXPECT_TRUE(rig.run_until_driving(hal::seconds(10)));
}

TEST(EstopChain, ASilentNodeStopsTheRobotAfterTheHeartbeatTimeout) {
  EstopRig rig;
  ASSERT_TRUE(rig.init());
  ASSERT_TRUE(rig.run_until_driving(hal::seconds(10)));
  const hal::Nanos cut_ns = rig.now();
  rig.node().set_silent(true);
  const VelPacket* stop = rig.first_stop_after(cut_ns, hal::seconds(1));
  ASSERT_NE(stop, nullptr);
  // The master declares the node lost heartbeat_timeout_s after its last heartbeat.
  const double timeout_s = rig.config().devices.io_node.master.heartbeat_timeout_s;
  const hal::Nanos bound = static_cast<hal::Nanos>(timeout_s * 1e9) + 2 * kControlPeriodNs;
  EXPECT_LE(stop->t_ns - cut_ns, bound);
  EXPECT_NE(stop->safety.value.reasons & msg::kSafetyIoLost, 0u);
  // The node talks again: it is configured and started again, and the robot still waits for a reset.
  rig.node().set_silent(false);
  const hal::Nanos back_ns = rig.now();
  rig.run_for(hal::seconds(2));
  EXPECT_EQ(rig.fw().can_io()->master().state(), canopen::IoNodeState::operational);
  EXPECT_TRUE(rig.all_stopped(back_ns, rig.now()));
  rig.press_reset();
  EXPECT_TRUE(rig.run_until_driving(hal::seconds(10)));
}

TEST(EstopChain, ABusOffStopsTheRobotWithinTwoControlPeriods) {
  EstopRig rig;
  ASSERT_TRUE(rig.init());
  ASSERT_TRUE(rig.run_until_driving(hal::seconds(10)));
  const hal::Nanos off_ns = rig.now();
  rig.board().can_bus().set_link_state(hal::CanLinkState::bus_off);
  const VelPacket* stop = rig.first_stop_after(off_ns, hal::millis(200));
  ASSERT_NE(stop, nullptr);
  EXPECT_LE(stop->t_ns - off_ns, 2 * kControlPeriodNs);
  EXPECT_NE(stop->safety.value.reasons & msg::kSafetyIoLost, 0u);
  rig.board().can_bus().set_link_state(hal::CanLinkState::active);
  const hal::Nanos on_ns = rig.now();
  rig.run_for(hal::seconds(1));
  EXPECT_TRUE(rig.all_stopped(on_ns, rig.now()));
  rig.press_reset();
  EXPECT_TRUE(rig.run_until_driving(hal::seconds(10)));
}

}  // namespace
}  // namespace sen3bot
