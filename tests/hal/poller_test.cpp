#include <gtest/gtest.h>
#include <fcntl.h>
#include <unistd.h>

#include <vector>

#include "hal_test_util.hpp"
#include "sen3bot/hal/fd.hpp"
#include "sen3bot/hal/poller.hpp"
#include "sen3bot/hal/pty.hpp"
#include "sen3bot/hal/serial.hpp"

namespace sen3bot::hal {
namespace {

struct Pipe {
  UniqueFd read_end;
  UniqueFd write_end;
};

Pipe make_pipe() {
  int fds[2] = {-1, -1};
  EXPECT_EQ(::pipe2(fds, O_CLOEXEC | O_NONBLOCK), 0);
  return Pipe{UniqueFd(fds[0]), UniqueFd(fds[1])};
}

const PollEvent* find(std::span<const PollEvent> events, int fd) {
  for (const PollEvent& event : events) {
    if (event.fd == fd) return &event;
  }
  return nullptr;
}

TEST(HalPoller, TimeoutWithNothingReadyIsEmpty) {
  Pipe pipe = make_pipe();
  Poller poller;
  ASSERT_TRUE(poller.add(pipe.read_end.get(), 7).ok());
  const auto start = testing::Clock::now();
  Result<std::span<const PollEvent>> ready = poller.wait(20);
  ASSERT_TRUE(ready.ok());
  EXPECT_TRUE(ready->empty());
  EXPECT_GE(testing::Clock::now() - start, std::chrono::milliseconds(15));
}

TEST(HalPoller, ReadableCarriesTheTag) {
  Pipe first = make_pipe();
  Pipe second = make_pipe();
  Poller poller;
  ASSERT_TRUE(poller.add(first.read_end.get(), 100).ok());
  ASSERT_TRUE(poller.add(second.read_end.get(), 200).ok());
  const char byte = 'x';
  ASSERT_EQ(::write(second.write_end.get(), &byte, 1), 1);
  Result<std::span<const PollEvent>> ready = poller.wait(1000);
  ASSERT_TRUE(ready.ok());
  ASSERT_EQ(ready->size(), 1U);
  EXPECT_EQ((*ready)[0].fd, second.read_end.get());
  EXPECT_EQ((*ready)[0].tag, 200U);
  EXPECT_TRUE((*ready)[0].readable);
  EXPECT_FALSE((*ready)[0].hangup);
}

TEST(HalPoller, HangupWhenTheOtherSideCloses) {
  Pipe pipe = make_pipe();
  Poller poller;
  ASSERT_TRUE(poller.add(pipe.read_end.get(), 1).ok());
  pipe.write_end.reset();
  Result<std::span<const PollEvent>> ready = poller.wait(1000);
  ASSERT_TRUE(ready.ok());
  ASSERT_EQ(ready->size(), 1U);
  EXPECT_TRUE((*ready)[0].hangup);
}

TEST(HalPoller, SerialPortSeesDataThenHangupWhenThePtyMasterCloses) {
  Result<std::unique_ptr<PtyPair>> device = PtyPair::open();
  ASSERT_TRUE(device.ok());
  Result<std::unique_ptr<SerialPort>> port = SerialPort::open((*device)->slave_path(), 38400);
  ASSERT_TRUE(port.ok());
  Poller poller;
  ASSERT_TRUE(poller.add((*port)->poll_fd(), 42).ok());
  ASSERT_TRUE(poller.add((*device)->poll_fd(), 43).ok());

  const std::uint8_t byte[] = {0x06};  // an LMS200 ACK
  ASSERT_TRUE(testing::write_all(**device, byte, 1000));
  Result<std::span<const PollEvent>> ready = poller.wait(1000);
  ASSERT_TRUE(ready.ok());
  const PollEvent* port_event = find(*ready, (*port)->poll_fd());
  ASSERT_NE(port_event, nullptr);
  EXPECT_TRUE(port_event->readable);
  EXPECT_EQ(port_event->tag, 42U);
  std::uint8_t buffer[4];
  EXPECT_EQ(*(*port)->read(buffer), 1U);

  ASSERT_TRUE(poller.remove((*device)->poll_fd()).ok());
  device->reset();
  ready = poller.wait(1000);
  ASSERT_TRUE(ready.ok());
  port_event = find(*ready, (*port)->poll_fd());
  ASSERT_NE(port_event, nullptr);
  EXPECT_TRUE(port_event->hangup);
  Result<std::size_t> read = (*port)->read(buffer);
  ASSERT_FALSE(read.ok());
  EXPECT_EQ(read.error().code(), Errc::disconnected);
}

TEST(HalPoller, WritableInterest) {
  Pipe pipe = make_pipe();
  Poller poller;
  ASSERT_TRUE(poller.add(pipe.write_end.get(), 5, PollInterest::writable).ok());
  Result<std::span<const PollEvent>> ready = poller.wait(0);
  ASSERT_TRUE(ready.ok());
  ASSERT_EQ(ready->size(), 1U);
  EXPECT_TRUE((*ready)[0].writable);
  ASSERT_TRUE(poller.set_interest(pipe.write_end.get(), PollInterest::readable).ok());
  ready = poller.wait(0);
  ASSERT_TRUE(ready.ok());
  EXPECT_TRUE(ready->empty());
}

TEST(HalPoller, ClosedWithoutRemoveIsReportedInvalid) {
  Poller poller;
  Pipe pipe = make_pipe();
  const int fd = pipe.read_end.get();
  ASSERT_TRUE(poller.add(fd, 9).ok());
  pipe.read_end.reset();
  Result<std::span<const PollEvent>> ready = poller.wait(0);
  ASSERT_TRUE(ready.ok());
  ASSERT_EQ(ready->size(), 1U);
  EXPECT_TRUE((*ready)[0].invalid);
}

TEST(HalPoller, RegistrationRules) {
  Pipe pipe = make_pipe();
  Poller poller;
  Status negative = poller.add(-1, 0);
  ASSERT_FALSE(negative.ok());
  EXPECT_EQ(negative.error().code(), Errc::invalid_argument);
  ASSERT_TRUE(poller.add(pipe.read_end.get(), 0).ok());
  Status duplicate = poller.add(pipe.read_end.get(), 1);
  ASSERT_FALSE(duplicate.ok());
  EXPECT_EQ(duplicate.error().code(), Errc::invalid_argument);
  EXPECT_TRUE(poller.contains(pipe.read_end.get()));
  ASSERT_TRUE(poller.remove(pipe.read_end.get()).ok());
  EXPECT_FALSE(poller.contains(pipe.read_end.get()));
  Status missing = poller.remove(pipe.read_end.get());
  ASSERT_FALSE(missing.ok());
  EXPECT_EQ(missing.error().code(), Errc::not_found);
  EXPECT_FALSE(poller.set_interest(pipe.read_end.get(), PollInterest::writable).ok());
}

TEST(HalPoller, FixedCapacityAndRemovalKeepsTheOthers) {
  Pipe pipe = make_pipe();
  std::vector<UniqueFd> fds;
  Poller poller;
  for (std::size_t i = 0; i < Poller::kCapacity; ++i) {
    fds.emplace_back(::dup(pipe.read_end.get()));
    ASSERT_TRUE(poller.add(fds.back().get(), i).ok()) << i;
  }
  EXPECT_EQ(poller.size(), Poller::kCapacity);
  UniqueFd one_more(::dup(pipe.read_end.get()));
  Status full = poller.add(one_more.get(), 99);
  ASSERT_FALSE(full.ok());
  EXPECT_EQ(full.error().code(), Errc::capacity);

  // Remove one in the middle: every other fd still reports with its own tag.
  ASSERT_TRUE(poller.remove(fds[3].get()).ok());
  const char byte = 'z';
  ASSERT_EQ(::write(pipe.write_end.get(), &byte, 1), 1);
  Result<std::span<const PollEvent>> ready = poller.wait(1000);
  ASSERT_TRUE(ready.ok());
  EXPECT_EQ(ready->size(), Poller::kCapacity - 1);
  for (const PollEvent& event : *ready) {
    EXPECT_NE(event.fd, fds[3].get());
    EXPECT_EQ(fds[event.tag].get(), event.fd);
  }
  EXPECT_TRUE(poller.add(one_more.get(), 99).ok());
}

}  // namespace
}  // namespace sen3bot::hal
