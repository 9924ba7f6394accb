#include <gtest/gtest.h>
#include <poll.h>

#include <string>
#include <thread>

#include "hal_test_util.hpp"
#include "sen3bot/hal/serial.hpp"
#include "sen3bot/hal/tcp.hpp"

namespace sen3bot::hal {
namespace {

using testing::contains;
using testing::every_byte_value;
using testing::read_exactly;
using testing::write_all;

constexpr int kSocketTimeout_ms = 2000;

std::unique_ptr<TcpStream> accept_within(TcpListener& listener, int timeout_ms) {
  const auto deadline = testing::Clock::now() + std::chrono::milliseconds(timeout_ms);
  while (testing::Clock::now() < deadline) {
    Result<std::unique_ptr<TcpStream>> accepted = listener.accept();
    if (!accepted.ok()) {
      ADD_FAILURE() << accepted.error().c_str();
      return nullptr;
    }
    if (*accepted) return std::move(accepted).value();
    pollfd p{listener.poll_fd(), POLLIN, 0};
    ::poll(&p, 1, 10);
  }
  return nullptr;
}

struct Connection {
  std::unique_ptr<TcpListener> listener;
  std::unique_ptr<TcpStream> client;
  std::unique_ptr<TcpStream> server;
};

Connection connect_loopback() {
  Connection c;
  Result<std::unique_ptr<TcpListener>> listener = TcpListener::listen("127.0.0.1", 0);
  EXPECT_TRUE(listener.ok()) << (listener.ok() ? "" : listener.error().c_str());
  if (!listener.ok()) return c;
  c.listener = std::move(listener).value();
  Result<std::unique_ptr<TcpStream>> client = TcpStream::connect("127.0.0.1", c.listener->port(), kSocketTimeout_ms);
  EXPECT_TRUE(client.ok()) << (client.ok() ? "" : client.error().c_str());
  if (!client.ok()) return c;
  c.client = std::move(client).value();
  c.server = accept_within(*c.listener, kSocketTimeout_ms);
  return c;
}

TEST(HalTcp, EphemeralListenerConnectAndExchange) {
  Connection c = connect_loopback();
  ASSERT_TRUE(c.client && c.server);
  EXPECT_NE(c.listener->port(), 0);
  EXPECT_EQ(c.client->name(), "tcp://127.0.0.1:" + std::to_string(c.listener->port()));
  EXPECT_EQ(c.server->name(), "tcp://127.0.0.1:" + std::to_string(c.client->local_port()));
  EXPECT_TRUE(contains(c.listener->name(), std::to_string(c.listener->port())));

  const std::vector<std::uint8_t> bytes = every_byte_value();
  ASSERT_TRUE(write_all(*c.client, bytes, kSocketTimeout_ms));
  EXPECT_EQ(read_exactly(*c.server, bytes.size(), kSocketTimeout_ms), bytes);
  ASSERT_TRUE(write_all(*c.server, bytes, kSocketTimeout_ms));
  EXPECT_EQ(read_exactly(*c.client, bytes.size(), kSocketTimeout_ms), bytes);

  std::uint8_t buffer[8];
  EXPECT_EQ(*c.client->read(buffer), 0U);  // nothing pending: 0 bytes, not an error
  EXPECT_EQ(*c.client->read({}), 0U);
  EXPECT_EQ(*c.client->write({}), 0U);
}

TEST(HalTcp, AcceptWithNothingPendingReturnsNull) {
  Result<std::unique_ptr<TcpListener>> listener = TcpListener::listen("127.0.0.1", 0);
  ASSERT_TRUE(listener.ok());
  Result<std::unique_ptr<TcpStream>> accepted = (*listener)->accept();
  ASSERT_TRUE(accepted.ok());
  EXPECT_EQ(*accepted, nullptr);
}

TEST(HalTcp, PeerCloseIsDisconnectedAndNeverSigpipe) {
  Connection c = connect_loopback();
  ASSERT_TRUE(c.client && c.server);
  const std::uint8_t last_words[] = {0xDE, 0xAD};
  ASSERT_TRUE(write_all(*c.server, last_words, kSocketTimeout_ms));
  c.server.reset();

  // What the peer sent before closing is still delivered, then EOF is "disconnected".
  Error error;
  EXPECT_EQ(read_exactly(*c.client, 3, kSocketTimeout_ms, &error), std::vector<std::uint8_t>({0xDE, 0xAD}));
  EXPECT_EQ(error.code(), Errc::disconnected) << error.c_str();
  EXPECT_TRUE(contains(error.message(), c.client->name())) << error.c_str();

  // Writing into a closed connection: EPIPE/ECONNRESET become "disconnected" (a SIGPIPE
  // would kill this test process).
  const std::vector<std::uint8_t> chunk(1024, 0x55);
  bool saw_disconnect = false;
  for (int i = 0; i < 1000 && !saw_disconnect; ++i) {
    Result<std::size_t> n = c.client->write(chunk);
    if (!n.ok()) {
      EXPECT_EQ(n.error().code(), Errc::disconnected) << n.error().c_str();
      saw_disconnect = true;
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_TRUE(saw_disconnect);
}

TEST(HalTcp, ShutdownWriteSendsEofButKeepsReading) {
  Connection c = connect_loopback();
  ASSERT_TRUE(c.client && c.server);
  ASSERT_TRUE(c.client->shutdown_write().ok());
  Error error;
  EXPECT_TRUE(read_exactly(*c.server, 1, kSocketTimeout_ms, &error).empty());
  EXPECT_EQ(error.code(), Errc::disconnected);
  const std::uint8_t reply[] = {1, 2, 3};
  ASSERT_TRUE(write_all(*c.server, reply, kSocketTimeout_ms));
  EXPECT_EQ(read_exactly(*c.client, 3, kSocketTimeout_ms), std::vector<std::uint8_t>({1, 2, 3}));
}

TEST(HalTcp, ConnectToAClosedPortIsAClearError) {
  std::uint16_t port = 0;
  {
    Result<std::unique_ptr<TcpListener>> listener = TcpListener::listen("127.0.0.1", 0);
    ASSERT_TRUE(listener.ok());
    port = (*listener)->port();
  }  // closed again: nobody listens there now
  Result<std::unique_ptr<TcpStream>> stream = TcpStream::connect("127.0.0.1", port, kSocketTimeout_ms);
  ASSERT_FALSE(stream.ok());
  EXPECT_EQ(stream.error().code(), Errc::io);
  EXPECT_TRUE(contains(stream.error().message(), "tcp://127.0.0.1:" + std::to_string(port))) << stream.error().c_str();
  EXPECT_TRUE(contains(stream.error().message(), "refused")) << stream.error().c_str();
}

TEST(HalTcp, UnknownHostIsAnErrorNamingIt) {
  Result<std::unique_ptr<TcpStream>> stream = TcpStream::connect("sen3bot-no-such-host.invalid", 8101, 500);
  ASSERT_FALSE(stream.ok());
  EXPECT_TRUE(contains(stream.error().message(), "sen3bot-no-such-host.invalid")) << stream.error().c_str();
}

TEST(HalTcp, ConnectTimeoutIsBounded) {
  // 192.0.2.0/24 is TEST-NET-1 (RFC 5737): never routed, so the connect either times out or
  // fails at once on a machine without a route.
  const auto start = testing::Clock::now();
  Result<std::unique_ptr<TcpStream>> stream = TcpStream::connect("192.0.2.1", 8101, 200);
  const auto elapsed = testing::Clock::now() - start;
  ASSERT_FALSE(stream.ok());
  EXPECT_TRUE(stream.error().code() == Errc::timeout || stream.error().code() == Errc::io) << stream.error().c_str();
  EXPECT_LT(elapsed, std::chrono::seconds(2));
}

TEST(HalTcp, PortZeroCannotBeConnected) {
  Result<std::unique_ptr<TcpStream>> stream = TcpStream::connect("127.0.0.1", 0, 100);
  ASSERT_FALSE(stream.ok());
  EXPECT_EQ(stream.error().code(), Errc::invalid_argument);
}

TEST(HalTcp, ListenOnABadAddressFails) {
  Result<std::unique_ptr<TcpListener>> listener = TcpListener::listen("203.0.113.77", 0);  // not ours
  ASSERT_FALSE(listener.ok());
  EXPECT_TRUE(contains(listener.error().message(), "203.0.113.77")) << listener.error().c_str();
}

TEST(HalTcp, Ipv6LoopbackWhenAvailable) {
  Result<std::unique_ptr<TcpListener>> listener = TcpListener::listen("::1", 0);
  if (!listener.ok()) GTEST_SKIP() << "no IPv6 loopback: " << listener.error().c_str();
  Result<std::unique_ptr<TcpStream>> client = TcpStream::connect("::1", (*listener)->port(), kSocketTimeout_ms);
  ASSERT_TRUE(client.ok()) << client.error().c_str();
  EXPECT_EQ((*client)->name(), "tcp://[::1]:" + std::to_string((*listener)->port()));
  auto server = accept_within(**listener, kSocketTimeout_ms);
  ASSERT_TRUE(server);
  const std::uint8_t ping[] = {'p'};
  ASSERT_TRUE(write_all(**client, ping, kSocketTimeout_ms));
  EXPECT_EQ(read_exactly(*server, 1, kSocketTimeout_ms), std::vector<std::uint8_t>({'p'}));
}

TEST(HalTcpUrl, GoodUrls) {
  struct Case {
    const char* url;
    const char* host;
    std::uint16_t port;
  };
  const Case cases[] = {
      {"tcp://localhost:8101", "localhost", 8101},
      {"tcp://192.168.1.5", "192.168.1.5", kDefaultRobotTcpPort},
      {"tcp://robot.local:1", "robot.local", 1},
      {"tcp://host:65535", "host", 65535},
      {"tcp://[::1]:9000", "::1", 9000},
      {"tcp://[fe80::1%eth0]", "fe80::1%eth0", kDefaultRobotTcpPort},
      {"TCP://Robot:8102", "Robot", 8102},  // schemes are case-insensitive
  };
  for (const Case& c : cases) {
    Result<TcpEndpoint> endpoint = parse_tcp_url(c.url);
    ASSERT_TRUE(endpoint.ok()) << c.url << ": " << endpoint.error().c_str();
    EXPECT_EQ(endpoint->host, c.host) << c.url;
    EXPECT_EQ(endpoint->port, c.port) << c.url;
  }
  EXPECT_EQ(kDefaultRobotTcpPort, 8101);
  EXPECT_TRUE(is_tcp_url("tcp://x"));
  EXPECT_FALSE(is_tcp_url("/dev/ttyS0"));
}

TEST(HalTcpUrl, BadUrlsSayWhatIsWrong) {
  struct Case {
    const char* url;
    const char* complaint;
  };
  const Case cases[] = {
      {"", "not a tcp:// URL"},
      {"localhost:8101", "not a tcp:// URL"},
      {"udp://host:1", "not a tcp:// URL"},
      {"tcp://", "missing host"},
      {"tcp://:8101", "missing host"},
      {"tcp://host:", "missing port"},
      {"tcp://host:0", "1 to 65535"},
      {"tcp://host:65536", "1 to 65535"},
      {"tcp://host:99999999999999999999", "1 to 65535"},
      {"tcp://host:-1", "1 to 65535"},
      {"tcp://host:abc", "1 to 65535"},
      {"tcp://host:80x", "after the port"},
      {"tcp://host:80/path", "after the port"},
      {"tcp://host/path", "unexpected character"},
      {"tcp://user@host:1", "unexpected character"},
      {"tcp://[::1", "closing ']'"},
      {"tcp://::1:80", "brackets"},
      {"tcp://[::1]x", "after the host"},
      {"tcp://[]:80", "missing host"},
  };
  for (const Case& c : cases) {
    Result<TcpEndpoint> endpoint = parse_tcp_url(c.url);
    ASSERT_FALSE(endpoint.ok()) << c.url;
    EXPECT_EQ(endpoint.error().code(), Errc::invalid_argument) << c.url;
    EXPECT_TRUE(contains(endpoint.error().message(), c.complaint)) << c.url << ": " << endpoint.error().c_str();
    EXPECT_TRUE(contains(endpoint.error().message(), c.url)) << endpoint.error().c_str();
  }
}

TEST(HalOpenByteStream, TcpUrlConnects) {
  Result<std::unique_ptr<TcpListener>> listener = TcpListener::listen("127.0.0.1", 0);
  ASSERT_TRUE(listener.ok());
  const std::string url = "tcp://127.0.0.1:" + std::to_string((*listener)->port());
  Result<std::unique_ptr<ByteStream>> stream = open_byte_stream(url, 9600);
  ASSERT_TRUE(stream.ok()) << stream.error().c_str();
  EXPECT_EQ((*stream)->name(), url);
  auto server = accept_within(**listener, kSocketTimeout_ms);
  ASSERT_TRUE(server);
  const std::uint8_t sync0[] = {0xFA, 0xFB, 0x03, 0x00, 0x00, 0x00};  // a P2OS SYNC0 packet
  ASSERT_TRUE(write_all(**stream, sync0, kSocketTimeout_ms));
  EXPECT_EQ(read_exactly(*server, sizeof sync0, kSocketTimeout_ms), std::vector<std::uint8_t>(sync0, sync0 + 6));
}

TEST(HalOpenByteStream, BadSpecsFailClearly) {
  Result<std::unique_ptr<ByteStream>> bad_url = open_byte_stream("tcp://host:", 9600);
  ASSERT_FALSE(bad_url.ok());
  EXPECT_EQ(bad_url.error().code(), Errc::invalid_argument);
  Result<std::unique_ptr<ByteStream>> bad_path = open_byte_stream("/dev/sen3bot-nothing", 9600);
  ASSERT_FALSE(bad_path.ok());
  EXPECT_TRUE(contains(bad_path.error().message(), "/dev/sen3bot-nothing"));
}

}  // namespace
}  // namespace sen3bot::hal
