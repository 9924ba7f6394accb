// SocketCAN needs AF_CAN in the kernel and a (v)can interface. Where either is missing the
// tests check the error and skip with its reason.
#include <gtest/gtest.h>
#include <poll.h>

#include <cstdlib>

#include "hal_test_util.hpp"
#include "sen3bot/hal/can.hpp"
#include "sen3bot/hal/clock.hpp"

namespace sen3bot::hal {
namespace {

constexpr const char* kInterface = "vcan0";  // `ip link add vcan0 type vcan && ip link set vcan0 up`

// Opens the test interface, or returns the reason to skip.
Result<std::unique_ptr<SocketCanBus>> open_test_bus(SocketCanOptions options = {}) {
  return SocketCanBus::open(kInterface, options);
}

bool skip_reason(const Result<std::unique_ptr<SocketCanBus>>& bus, std::string& reason) {
  if (bus.ok()) return false;
  reason = std::string(bus.error().message());
  return bus.error().code() == Errc::not_supported || bus.error().code() == Errc::not_found;
}

TEST(HalSocketCan, UnavailableKernelSupportIsAClearError) {
  Result<std::unique_ptr<SocketCanBus>> bus = SocketCanBus::open("can0");
  if (bus.ok()) GTEST_SKIP() << "this kernel has SocketCAN and a can0 interface";
  if (bus.error().code() == Errc::not_supported) {
    EXPECT_EQ(bus.error().message(),
              "SocketCAN unavailable: the kernel has no AF_CAN support (socket(PF_CAN): Address family not "
              "supported by protocol)");
    GTEST_SKIP() << bus.error().c_str();
  }
  // AF_CAN exists but can0 does not: the message names the interface.
  EXPECT_EQ(bus.error().code(), Errc::not_found) << bus.error().c_str();
  EXPECT_TRUE(testing::contains(bus.error().message(), "can0")) << bus.error().c_str();
  GTEST_SKIP() << bus.error().c_str();
}

TEST(HalSocketCan, InterfaceNameIsCheckedFirst) {
  Result<std::unique_ptr<SocketCanBus>> empty = SocketCanBus::open("");
  ASSERT_FALSE(empty.ok());
  EXPECT_EQ(empty.error().code(), Errc::invalid_argument);
  Result<std::unique_ptr<SocketCanBus>> too_long = SocketCanBus::open("a-very-long-can-interface-name");
  ASSERT_FALSE(too_long.ok());
  EXPECT_EQ(too_long.error().code(), Errc::invalid_argument);
}

TEST(HalSocketCan, FramesBetweenTwoSocketsOnVcan) {
  Result<std::unique_ptr<SocketCanBus>> a = open_test_bus();
  std::string reason;
  if (skip_reason(a, reason)) GTEST_SKIP() << reason;
  ASSERT_TRUE(a.ok()) << a.error().c_str();
  Result<std::unique_ptr<SocketCanBus>> b = open_test_bus();
  ASSERT_TRUE(b.ok()) << b.error().c_str();

  const CanFilter only_0x123{0x123, CanFrame::kMaxStandardId, CanFilter::Format::standard};
  ASSERT_TRUE((*b)->set_filters({&only_0x123, 1}).ok());
  const std::uint8_t payload[] = {1, 2, 3, 4, 5, 6, 7, 8};
  ASSERT_TRUE((*a)->send(*CanFrame::make(0x124, payload)).ok());
  ASSERT_TRUE((*a)->send(*CanFrame::make(0x123, payload)).ok());
  EXPECT_EQ((*b)->last_receive_unix_ns(), -1);  // nothing received yet
  pollfd p{(*b)->poll_fd(), POLLIN, 0};
  ASSERT_EQ(::poll(&p, 1, 1000), 1);
  Result<std::optional<CanFrame>> received = (*b)->receive();
  ASSERT_TRUE(received.ok() && received->has_value());
  EXPECT_EQ((*received)->id, 0x123U);
  EXPECT_EQ((*received)->dlc, 8);
  // The kernel's receive time (SO_TIMESTAMPNS), on the wall clock, a moment ago.
  const std::int64_t stamped = (*b)->last_receive_unix_ns();
  const std::int64_t now = PosixClock().unix_now_ns();
  EXPECT_GT(stamped, 0);
  EXPECT_LE(std::llabs(now - stamped), seconds(1)) << "stamped " << stamped << ", now " << now;
  // vcan has no controller: no error frames, the link stays active, nothing waits to be sent.
  EXPECT_EQ((*b)->link_state(), CanLinkState::active);
  EXPECT_EQ((*b)->error_frames(), 0U);
  EXPECT_EQ((*a)->tx_queued(), 0U);
  EXPECT_EQ((*a)->tx_dropped(), 0U);
  EXPECT_TRUE((*a)->flush().ok());
  Result<std::optional<CanFrame>> nothing_else = (*b)->receive();
  ASSERT_TRUE(nothing_else.ok());
  EXPECT_FALSE(nothing_else->has_value());

  CanFrame invalid;
  invalid.dlc = 9;
  EXPECT_EQ((*a)->send(invalid).error().code(), Errc::invalid_argument);
}

}  // namespace
}  // namespace sen3bot::hal
