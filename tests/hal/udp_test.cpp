#include <gtest/gtest.h>
#include <poll.h>

#include <cstring>
#include <string>

#include "hal_test_util.hpp"
#include "sen3bot/hal/udp.hpp"

namespace sen3bot::hal {
namespace {

using testing::contains;

constexpr UdpEndpoint kLoopback{{127, 0, 0, 1}, 0};
constexpr int kDatagramTimeout_ms = 2000;

std::unique_ptr<UdpSocket> bind_or_fail(std::string_view address, std::uint16_t port) {
  Result<std::unique_ptr<UdpSocket>> socket = UdpSocket::bind(address, port);
  EXPECT_TRUE(socket.ok()) << (socket.ok() ? "" : socket.error().c_str());
  return socket.ok() ? std::move(socket).value() : nullptr;
}

UdpEndpoint at(UdpEndpoint endpoint, std::uint16_t port) {
  endpoint.port = port;
  return endpoint;
}

std::optional<UdpReceived> receive_within(UdpSocket& socket, std::span<std::uint8_t> out, int timeout_ms) {
  const auto deadline = testing::Clock::now() + std::chrono::milliseconds(timeout_ms);
  while (testing::Clock::now() < deadline) {
    Result<std::optional<UdpReceived>> received = socket.recv_from(out);
    if (!received.ok()) {
      ADD_FAILURE() << received.error().c_str();
      return std::nullopt;
    }
    if (*received) return *received;
    pollfd p{socket.poll_fd(), POLLIN, 0};
    ::poll(&p, 1, 10);
  }
  return std::nullopt;
}

TEST(HalUdp, LoopbackSendAndReceiveReportsTheSender) {
  auto a = bind_or_fail("127.0.0.1", 0);
  auto b = bind_or_fail("127.0.0.1", 0);
  ASSERT_TRUE(a && b);
  EXPECT_NE(a->local_port(), 0);
  EXPECT_TRUE(contains(a->name(), std::to_string(a->local_port())));

  const std::uint8_t datagram[] = {0, 1, 2, 0xFF, 0x0A, 0x0D};
  Result<std::size_t> sent = a->send_to(datagram, at(kLoopback, b->local_port()));
  ASSERT_TRUE(sent.ok()) << sent.error().c_str();
  EXPECT_EQ(*sent, sizeof datagram);

  std::uint8_t buffer[64];
  std::optional<UdpReceived> received = receive_within(*b, buffer, kDatagramTimeout_ms);
  ASSERT_TRUE(received);
  EXPECT_EQ(received->size, sizeof datagram);
  EXPECT_FALSE(received->truncated);
  EXPECT_EQ(std::memcmp(buffer, datagram, sizeof datagram), 0);
  EXPECT_EQ(received->sender, at(kLoopback, a->local_port()));

  // Reply to whoever sent it.
  const std::uint8_t reply[] = {'o', 'k'};
  ASSERT_TRUE(b->send_to(reply, received->sender).ok());
  std::optional<UdpReceived> answer = receive_within(*a, buffer, kDatagramTimeout_ms);
  ASSERT_TRUE(answer);
  EXPECT_EQ(answer->size, 2U);
  EXPECT_EQ(answer->sender.port, b->local_port());
}

TEST(HalUdp, NothingWaitingIsNullopt) {
  auto socket = bind_or_fail("127.0.0.1", 0);
  ASSERT_TRUE(socket);
  std::uint8_t buffer[16];
  Result<std::optional<UdpReceived>> received = socket->recv_from(buffer);
  ASSERT_TRUE(received.ok());
  EXPECT_FALSE(received->has_value());
}

TEST(HalUdp, OversizedDatagramIsMarkedTruncated) {
  auto a = bind_or_fail("127.0.0.1", 0);
  auto b = bind_or_fail("127.0.0.1", 0);
  ASSERT_TRUE(a && b);
  const std::vector<std::uint8_t> big(100, 0x42);
  ASSERT_TRUE(a->send_to(big, at(kLoopback, b->local_port())).ok());
  std::uint8_t small[10];
  std::optional<UdpReceived> received = receive_within(*b, small, kDatagramTimeout_ms);
  ASSERT_TRUE(received);
  EXPECT_TRUE(received->truncated);
  EXPECT_EQ(received->size, sizeof small);
}

TEST(HalUdp, EmptyDatagramIsReceivedAsZeroBytes) {
  auto a = bind_or_fail("127.0.0.1", 0);
  auto b = bind_or_fail("127.0.0.1", 0);
  ASSERT_TRUE(a && b);
  ASSERT_TRUE(a->send_to({}, at(kLoopback, b->local_port())).ok());
  std::uint8_t buffer[8];
  std::optional<UdpReceived> received = receive_within(*b, buffer, kDatagramTimeout_ms);
  ASSERT_TRUE(received);  // distinguishable from "nothing waiting"
  EXPECT_EQ(received->size, 0U);
}

TEST(HalUdp, ReceiveBufferSizeIsReadBack) {
  auto socket = bind_or_fail("", 0);
  ASSERT_TRUE(socket);
  Result<std::size_t> granted = socket->set_receive_buffer(64 * 1024);
  ASSERT_TRUE(granted.ok()) << granted.error().c_str();
  EXPECT_GT(*granted, 0U);  // Linux grants double the request, capped by rmem_max
}

TEST(HalUdp, ReuseAddressLetsTwoSocketsShareAPort) {
  auto first = bind_or_fail("", 0);
  ASSERT_TRUE(first);
  Result<std::unique_ptr<UdpSocket>> second = UdpSocket::bind("", first->local_port());
  EXPECT_TRUE(second.ok()) << second.error().c_str();
}

TEST(HalUdp, MulticastJoinAndLoopbackWhenTheMachineAllowsIt) {
  // WS-Discovery's group; port 0 keeps the test away from a real 3702 listener.
  auto receiver = bind_or_fail("", 0);
  auto sender = bind_or_fail("127.0.0.1", 0);
  ASSERT_TRUE(receiver && sender);
  Status joined = receiver->join_multicast("239.255.255.250", "127.0.0.1");
  if (!joined.ok()) {
    EXPECT_FALSE(joined.error().message().empty());
    EXPECT_TRUE(contains(joined.error().message(), "239.255.255.250")) << joined.error().c_str();
    GTEST_SKIP() << "multicast unavailable here: " << joined.error().c_str();
  }
  ASSERT_TRUE(sender->set_multicast_interface("127.0.0.1").ok());
  ASSERT_TRUE(sender->set_multicast_loopback(true).ok());
  ASSERT_TRUE(sender->set_multicast_ttl(1).ok());
  const std::uint8_t probe[] = {'<', 'P', 'r', 'o', 'b', 'e', '/', '>'};
  ASSERT_TRUE(sender->send_to(probe, UdpEndpoint{{239, 255, 255, 250}, receiver->local_port()}).ok());
  std::uint8_t buffer[32];
  std::optional<UdpReceived> received = receive_within(*receiver, buffer, kDatagramTimeout_ms);
  ASSERT_TRUE(received);
  EXPECT_EQ(received->size, sizeof probe);
  EXPECT_EQ(received->sender.port, sender->local_port());
  EXPECT_TRUE(receiver->leave_multicast("239.255.255.250", "127.0.0.1").ok());
}

TEST(HalUdp, BadMulticastArgumentsAreRejected) {
  auto socket = bind_or_fail("", 0);
  ASSERT_TRUE(socket);
  Status unicast = socket->join_multicast("10.0.0.1");
  ASSERT_FALSE(unicast.ok());
  EXPECT_EQ(unicast.error().code(), Errc::invalid_argument);
  EXPECT_TRUE(contains(unicast.error().message(), "not a multicast group"));
  Status garbage = socket->join_multicast("not-an-address");
  ASSERT_FALSE(garbage.ok());
  EXPECT_EQ(garbage.error().code(), Errc::invalid_argument);
  Status no_interface = socket->join_multicast("239.255.255.250", "sen3bot-nonexistent0");
  ASSERT_FALSE(no_interface.ok());
  EXPECT_EQ(no_interface.error().code(), Errc::not_found);
  EXPECT_FALSE(socket->set_multicast_ttl(256).ok());
  EXPECT_TRUE(socket->set_broadcast(true).ok());
}

TEST(HalUdp, BindErrors) {
  Result<std::unique_ptr<UdpSocket>> bad = UdpSocket::bind("999.1.1.1", 0);
  ASSERT_FALSE(bad.ok());
  EXPECT_EQ(bad.error().code(), Errc::invalid_argument);
  Result<std::unique_ptr<UdpSocket>> foreign = UdpSocket::bind("203.0.113.77", 0);
  ASSERT_FALSE(foreign.ok());
  EXPECT_TRUE(contains(foreign.error().message(), "203.0.113.77"));
}

TEST(HalUdp, EndpointsResolveAndFormat) {
  Result<UdpEndpoint> numeric = resolve_udp_endpoint("192.168.10.20", 3702);
  ASSERT_TRUE(numeric.ok()) << numeric.error().c_str();
  EXPECT_EQ(*numeric, (UdpEndpoint{{192, 168, 10, 20}, 3702}));
  EXPECT_STREQ(numeric->to_chars().data(), "192.168.10.20:3702");
  EXPECT_STREQ((UdpEndpoint{{255, 255, 255, 255}, 65535}).to_chars().data(), "255.255.255.255:65535");
  Result<UdpEndpoint> named = resolve_udp_endpoint("localhost", 9);
  ASSERT_TRUE(named.ok()) << named.error().c_str();
  EXPECT_EQ(named->address[0], 127);
  EXPECT_FALSE(resolve_udp_endpoint("sen3bot-no-such-host.invalid", 1).ok());
}

}  // namespace
}  // namespace sen3bot::hal
