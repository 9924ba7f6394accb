// The steady-state I/O paths allocate nothing: read/write, poll, send/receive, including
// the error values they return. Counted with the shared allocator from tests/support.
#include <gtest/gtest.h>
#include <poll.h>

#include "alloc_counter.hpp"
#include "sen3bot/hal/can.hpp"
#include "sen3bot/hal/memory_stream.hpp"
#include "sen3bot/hal/poller.hpp"
#include "sen3bot/hal/pty.hpp"
#include "sen3bot/hal/serial.hpp"
#include "sen3bot/hal/tcp.hpp"
#include "sen3bot/hal/udp.hpp"

namespace sen3bot::hal {
namespace {

using mem::testing::AllocationScope;

constexpr int kRounds = 500;

TEST(HalNoAllocation, MemoryPipeIncludingDisconnect) {
  MemoryPipe pipe(64);
  std::uint8_t out[16] = {1, 2, 3};
  std::uint8_t in[16];
  std::size_t moved = 0;
  AllocationScope scope;
  for (int i = 0; i < kRounds; ++i) {
    moved += *pipe.a().write(out);
    moved += *pipe.b().read(in);
  }
  pipe.a().disconnect();
  for (int i = 0; i < kRounds; ++i) {
    Result<std::size_t> n = pipe.b().read(in);
    moved += n.ok() ? *n : 1;
  }
  EXPECT_EQ(scope.allocations(), 0U);
  EXPECT_GT(moved, 0U);
}

TEST(HalNoAllocation, SerialPortAndPtyAndPoller) {
  Result<std::unique_ptr<PtyPair>> device = PtyPair::open();
  ASSERT_TRUE(device.ok());
  Result<std::unique_ptr<SerialPort>> port = SerialPort::open((*device)->slave_path(), 115200);
  ASSERT_TRUE(port.ok());
  Poller poller;
  ASSERT_TRUE(poller.add((*port)->poll_fd(), 1).ok());
  ASSERT_TRUE(poller.add((*device)->poll_fd(), 2).ok());
  const std::uint8_t packet[] = {0xFA, 0xFB, 0x03, 0x01, 0x00, 0x01};
  std::uint8_t buffer[64];
  std::size_t received = 0;
  AllocationScope scope;
  for (int i = 0; i < kRounds; ++i) {
    (void)(*port)->write(packet);
    (void)poller.wait(100);
    Result<std::size_t> n = (*device)->read(buffer);
    received += n.ok() ? *n : 0;
    (void)(*device)->write(packet);
    (void)poller.wait(100);
    n = (*port)->read(buffer);
    received += n.ok() ? *n : 0;
  }
  device->reset();  // the error path too
  for (int i = 0; i < 10; ++i) (void)(*port)->read(buffer);
  EXPECT_EQ(scope.allocations(), 0U);
  EXPECT_GT(received, 0U);
}

TEST(HalNoAllocation, TcpStream) {
  Result<std::unique_ptr<TcpListener>> listener = TcpListener::listen("127.0.0.1", 0);
  ASSERT_TRUE(listener.ok());
  Result<std::unique_ptr<TcpStream>> client = TcpStream::connect("127.0.0.1", (*listener)->port(), 2000);
  ASSERT_TRUE(client.ok());
  pollfd p{(*listener)->poll_fd(), POLLIN, 0};
  ASSERT_EQ(::poll(&p, 1, 2000), 1);
  Result<std::unique_ptr<TcpStream>> server = (*listener)->accept();
  ASSERT_TRUE(server.ok() && *server);
  const std::uint8_t packet[32] = {};
  std::uint8_t buffer[64];
  std::size_t received = 0;
  AllocationScope scope;
  for (int i = 0; i < kRounds; ++i) {
    (void)(*client)->write(packet);
    Result<std::size_t> n = (*server)->read(buffer);
    received += n.ok() ? *n : 0;
  }
  EXPECT_EQ(scope.allocations(), 0U);
  EXPECT_GT(received, 0U);
}

TEST(HalNoAllocation, UdpSocket) {
  Result<std::unique_ptr<UdpSocket>> a = UdpSocket::bind("127.0.0.1", 0);
  Result<std::unique_ptr<UdpSocket>> b = UdpSocket::bind("127.0.0.1", 0);
  ASSERT_TRUE(a.ok() && b.ok());
  const UdpEndpoint to{{127, 0, 0, 1}, (*b)->local_port()};
  const std::uint8_t datagram[48] = {};
  std::uint8_t buffer[64];
  std::size_t received = 0;
  AllocationScope scope;
  for (int i = 0; i < kRounds; ++i) {
    (void)(*a)->send_to(datagram, to);
    Result<std::optional<UdpReceived>> got = (*b)->recv_from(buffer);
    received += got.ok() && *got ? (*got)->size : 0;
  }
  EXPECT_EQ(scope.allocations(), 0U);
  EXPECT_GT(received, 0U);
}

TEST(HalNoAllocation, MemoryCanBus) {
  MemoryCanBus bus;
  MemoryCanNode* a = *bus.attach("a");
  MemoryCanNode* b = *bus.attach("b");
  const CanFilter filter{0x100, 0x700};
  CanFrame frame;
  frame.id = 0x123;
  frame.dlc = 8;
  std::size_t received = 0;
  AllocationScope scope;
  ASSERT_TRUE(b->set_filters({&filter, 1}).ok());
  for (int i = 0; i < kRounds; ++i) {
    (void)a->send(frame);
    Result<std::optional<CanFrame>> got = b->receive();
    received += got.ok() && *got ? 1 : 0;
  }
  CanFrame invalid;
  invalid.dlc = 9;
  (void)a->send(invalid);
  EXPECT_EQ(scope.allocations(), 0U);
  EXPECT_EQ(received, static_cast<std::size_t>(kRounds));
}

}  // namespace
}  // namespace sen3bot::hal
