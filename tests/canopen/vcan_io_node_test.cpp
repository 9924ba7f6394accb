// The master and the emulated I/O node over a real SocketCAN bus: two sockets on vcan0, in
// real time. Needs AF_CAN in the kernel and the interface
// (`ip link add vcan0 type vcan && ip link set vcan0 up`); where either is missing the test
// skips and says which.
#include <gtest/gtest.h>

#include <array>
#include <cstdlib>
#include <memory>
#include <string>

#include "sen3bot/canopen/io_node.hpp"
#include "sen3bot/sim/canopen/io_node_emulator.hpp"
#include "sen3bot/hal/can.hpp"
#include "sen3bot/hal/clock.hpp"

namespace sen3bot::canopen {
namespace {

constexpr const char* kInterface = "vcan0";
constexpr hal::Nanos kCycle = 5 * hal::kNanosPerMilli;

// Opens a handle on vcan0; on a machine that cannot, sets `skip` to the reason.
std::unique_ptr<hal::SocketCanBus> open_bus(std::string& skip) {
  Result<std::unique_ptr<hal::SocketCanBus>> bus = hal::SocketCanBus::open(kInterface);
  if (bus.ok()) return std::move(*bus);
  if (bus.error().code() == Errc::not_supported) {
    skip = std::string("this kernel has no AF_CAN (") + bus.error().c_str() + ")";
  } else if (bus.error().code() == Errc::not_found) {
    skip = "no vcan0 interface: ip link add vcan0 type vcan && ip link set vcan0 up";
  } else {
    ADD_FAILURE() << bus.error().c_str();
  }
  return nullptr;
}

// The master on one socket, the node on the other, stepped every 5 ms of real time: each
// side takes what the bus brought, then sends what its poll() gives.
struct VcanRig {
  hal::PosixClock clock;
  std::unique_ptr<hal::SocketCanBus> master_bus;
  std::unique_ptr<hal::SocketCanBus> node_bus;
  IoNodeMaster master{IoNodeConfig{}};
  IoNodeEmulator node{IoNodeEmulatorConfig{}};
  std::uint64_t send_errors = 0;

  static void exchange(hal::CanBus& bus, hal::Nanos now, auto& side, std::uint64_t& errors) {
    for (;;) {
      Result<std::optional<CanFrame>> received = bus.receive();
      if (!received.ok()) {
        ++errors;
        break;
      }
      if (!*received) break;
      side.on_frame(**received, now);
    }
    std::array<CanFrame, 4> out{};
    const std::size_t n = side.poll(now, out);
    for (std::size_t i = 0; i < n; ++i) {
      if (!bus.send(out[i]).ok()) ++errors;
    }
  }

  void cycle() {
    const hal::Nanos now = clock.now();
    exchange(*master_bus, now, master, send_errors);
    exchange(*node_bus, now, node, send_errors);
    clock.sleep_until(now + kCycle);
  }
  // Cycles until `done()` or `limit` of real time; whether it got there.
  template <class Done>
  bool until(Done done, hal::Nanos limit) {
    const hal::Nanos end = clock.now() + limit;
    while (!done()) {
      if (clock.now() > end) return false;
      cycle();
    }
    return true;
  }
};

TEST(VcanIoNode, TheMasterStartsTheNodeAndSeesItsInputsOverVcan) {
  std::string skip;
  VcanRig rig;
  rig.master_bus = open_bus(skip);
  if (!rig.master_bus) {
    if (!skip.empty()) GTEST_SKIP() << skip;
    return;
  }
  rig.node_bus = open_bus(skip);
  ASSERT_TRUE(rig.node_bus) << skip;

  rig.node.power_up(rig.clock.now());
  ASSERT_TRUE(rig.until([&] { return rig.master.state() == IoNodeState::operational; }, hal::seconds(2)))
      << "master stuck in " << to_string(rig.master.state());
  EXPECT_EQ(rig.node.state(), NmtState::operational);
  EXPECT_EQ(rig.master.count(IoNodeEvent::configured), 1U);

  rig.node.set_inputs(0x5A);
  ASSERT_TRUE(rig.until([&] { return rig.master.inputs_valid() && rig.master.inputs() == 0x5A; }, hal::seconds(1)))
      << "inputs 0x" << std::hex << unsigned{rig.master.inputs()} << (rig.master.inputs_valid() ? "" : " (not valid)");
  rig.master.set_outputs(0x81);
  ASSERT_TRUE(rig.until([&] { return rig.node.outputs() == 0x81; }, hal::seconds(1)));

  // The frames carry the kernel's receive time, a moment ago on the wall clock.
  const std::int64_t stamped = rig.master_bus->last_receive_unix_ns();
  EXPECT_GT(stamped, 0);
  EXPECT_LE(std::llabs(rig.clock.unix_now_ns() - stamped), hal::seconds(1));
  EXPECT_EQ(rig.send_errors, 0U);
  EXPECT_EQ(rig.master.count(IoNodeEvent::unexpected_frame), 0U);
  EXPECT_EQ(rig.master.count(IoNodeEvent::heartbeat_lost), 0U);
  EXPECT_EQ(rig.master_bus->link_state(), hal::CanLinkState::active);
  EXPECT_EQ(rig.master_bus->tx_dropped() + rig.node_bus->tx_dropped(), 0U);
}

}  // namespace
}  // namespace sen3bot::canopen
