// SerialPort against real pseudo-terminals: the PtyPair master plays the device.
#include <gtest/gtest.h>
#include <sys/stat.h>
#include <unistd.h>

#include <algorithm>
#include <string>

#include "hal_test_util.hpp"
#include "sen3bot/hal/pty.hpp"
#include "sen3bot/hal/serial.hpp"

namespace sen3bot::hal {
namespace {

using testing::contains;
using testing::every_byte_value;
using testing::read_exactly;
using testing::write_all;

constexpr int kIoTimeout_ms = 2000;

std::unique_ptr<PtyPair> open_pair(PtyOptions options = {}) {
  Result<std::unique_ptr<PtyPair>> pair = PtyPair::open(options);
  EXPECT_TRUE(pair.ok()) << (pair.ok() ? "" : pair.error().c_str());
  return pair.ok() ? std::move(pair).value() : nullptr;
}

void expect_raw_8n1(const SerialLineSettings& line, std::uint32_t baud) {
  EXPECT_EQ(line.baud, baud);
  EXPECT_EQ(line.input_baud, baud);
  EXPECT_EQ(line.data_bits, 8);
  EXPECT_FALSE(line.parity);
  EXPECT_EQ(line.stop_bits, 1);
  EXPECT_FALSE(line.hardware_flow_control);
  EXPECT_FALSE(line.software_flow_control);
  EXPECT_TRUE(line.ignore_modem_lines);
  EXPECT_TRUE(line.receiver_enabled);
  EXPECT_TRUE(line.raw);
  EXPECT_EQ(line.vmin, 0);
  EXPECT_EQ(line.vtime, 0);
}

// Every byte value both ways: no CR/LF translation, no XON/XOFF eaten, no signals.
void expect_transparent_both_ways(PtyPair& device, SerialPort& port) {
  const std::vector<std::uint8_t> bytes = every_byte_value();
  ASSERT_TRUE(write_all(port, bytes, kIoTimeout_ms));
  EXPECT_EQ(read_exactly(device, bytes.size(), kIoTimeout_ms), bytes);
  std::vector<std::uint8_t> reversed(bytes.rbegin(), bytes.rend());
  ASSERT_TRUE(write_all(device, reversed, kIoTimeout_ms));
  EXPECT_EQ(read_exactly(port, reversed.size(), kIoTimeout_ms), reversed);
}

class HalSerialRate : public ::testing::TestWithParam<std::uint32_t> {};

TEST_P(HalSerialRate, OpensRaw8N1AndExchangesEveryByteValue) {
  const std::uint32_t baud = GetParam();
  if (!testing::runtime_translates_baud(baud)) GTEST_SKIP() << "qemu-user cannot translate " << baud << " baud";
  auto device = open_pair();
  ASSERT_TRUE(device);
  Result<std::unique_ptr<SerialPort>> port = SerialPort::open(device->slave_path(), baud);
  ASSERT_TRUE(port.ok()) << port.error().c_str();

  Result<std::uint32_t> read_back = (*port)->baud();
  ASSERT_TRUE(read_back.ok()) << read_back.error().c_str();
  EXPECT_EQ(*read_back, baud);
  Result<SerialLineSettings> line = (*port)->line_settings();
  ASSERT_TRUE(line.ok()) << line.error().c_str();
  expect_raw_8n1(*line, baud);

  // The emulator's view: the master reports the slave's rate and settings.
  Result<std::uint32_t> seen_by_master = device->slave_baud();
  ASSERT_TRUE(seen_by_master.ok()) << seen_by_master.error().c_str();
  EXPECT_EQ(*seen_by_master, baud);
  Result<SerialLineSettings> master_line = device->slave_line_settings();
  ASSERT_TRUE(master_line.ok());
  expect_raw_8n1(*master_line, baud);

  expect_transparent_both_ways(*device, **port);
}

INSTANTIATE_TEST_SUITE_P(StandardRates, HalSerialRate, ::testing::Values(9600U, 19200U, 38400U, 115200U, 500000U));

TEST(HalSerial, NonStandardRateGoesThroughBother) {
  constexpr std::uint32_t kOddBaud = 250000;  // DMX512's rate: no Bxxx constant
  ASSERT_FALSE(is_standard_baud(kOddBaud));
  auto device = open_pair();
  ASSERT_TRUE(device);
  Result<std::unique_ptr<SerialPort>> port = SerialPort::open(device->slave_path(), kOddBaud);
  if (!port.ok() && port.error().code() == Errc::not_supported) GTEST_SKIP() << port.error().c_str();
  ASSERT_TRUE(port.ok()) << port.error().c_str();
  Result<SerialLineSettings> line = (*port)->line_settings();
  ASSERT_TRUE(line.ok());
  expect_raw_8n1(*line, kOddBaud);
  Result<std::uint32_t> seen_by_master = device->slave_baud();
  ASSERT_TRUE(seen_by_master.ok());
  EXPECT_EQ(*seen_by_master, kOddBaud);
  expect_transparent_both_ways(*device, **port);
}

TEST(HalSerial, SetBaudAtRuntimeIsSeenByTheMaster) {
  auto device = open_pair();
  ASSERT_TRUE(device);
  Result<std::unique_ptr<SerialPort>> port = SerialPort::open(device->slave_path(), 9600);
  ASSERT_TRUE(port.ok()) << port.error().c_str();
  // A baud probe as the LMS200 drivers do it, including a BOTHER rate and back.
  for (const std::uint32_t baud : {19200U, 38400U, 500000U, 250000U, 9600U}) {
    if (!testing::runtime_translates_baud(baud)) continue;
    Status changed = (*port)->set_baud(baud);
    ASSERT_TRUE(changed.ok()) << changed.error().c_str();
    EXPECT_EQ(*(*port)->baud(), baud);
    EXPECT_EQ(*device->slave_baud(), baud);
    Result<SerialLineSettings> line = (*port)->line_settings();
    ASSERT_TRUE(line.ok());
    expect_raw_8n1(*line, baud);  // the input rate follows too (no stale BOTHER input rate)
  }
  expect_transparent_both_ways(*device, **port);
}

TEST(HalSerial, EveryStandardRateIsAccepted) {
  auto device = open_pair();
  ASSERT_TRUE(device);
  Result<std::unique_ptr<SerialPort>> port = SerialPort::open(device->slave_path(), 9600);
  ASSERT_TRUE(port.ok());
  for (const std::uint32_t baud : standard_baud_rates()) {
    if (!testing::runtime_translates_baud(baud)) continue;
    Status changed = (*port)->set_baud(baud);
    EXPECT_TRUE(changed.ok()) << baud << ": " << changed.error().c_str();
    EXPECT_EQ(*device->slave_baud(), baud);
  }
}

TEST(HalSerial, StandardRateTable) {
  const auto rates = standard_baud_rates();
  EXPECT_GE(rates.size(), 15U);
  for (const std::uint32_t baud : {50U, 9600U, 38400U, 115200U, 500000U, 4000000U}) {
    EXPECT_TRUE(is_standard_baud(baud)) << baud;
  }
  EXPECT_FALSE(is_standard_baud(250000));
  EXPECT_FALSE(is_standard_baud(0));
  EXPECT_TRUE(std::is_sorted(rates.begin(), rates.end()));
}

TEST(HalSerial, BaudZeroIsRejected) {
  auto device = open_pair();
  ASSERT_TRUE(device);
  Result<std::unique_ptr<SerialPort>> port = SerialPort::open(device->slave_path(), 0);
  ASSERT_FALSE(port.ok());
  EXPECT_EQ(port.error().code(), Errc::invalid_argument);
}

TEST(HalSerial, ClosingTheMasterIsDisconnectedNotACrashOrHang) {
  auto device = open_pair();
  ASSERT_TRUE(device);
  const std::string slave_path(device->slave_path());
  Result<std::unique_ptr<SerialPort>> port = SerialPort::open(slave_path, 115200);
  ASSERT_TRUE(port.ok());
  device.reset();  // the "USB adapter" is unplugged

  std::uint8_t buffer[16];
  Result<std::size_t> read = (*port)->read(buffer);
  ASSERT_FALSE(read.ok());
  EXPECT_EQ(read.error().code(), Errc::disconnected) << read.error().c_str();
  EXPECT_TRUE(contains(read.error().message(), slave_path)) << read.error().c_str();

  const std::uint8_t payload[] = {1, 2, 3};
  Result<std::size_t> written = (*port)->write(payload);
  ASSERT_FALSE(written.ok());
  EXPECT_EQ(written.error().code(), Errc::disconnected) << written.error().c_str();
  EXPECT_TRUE(contains(written.error().message(), slave_path));

  // Reopening the vanished path fails cleanly; the port then stays "disconnected".
  Status reopened = (*port)->reopen();
  EXPECT_FALSE(reopened.ok());
  EXPECT_TRUE(contains(reopened.error().message(), slave_path)) << reopened.error().c_str();
  Result<std::size_t> after = (*port)->read(buffer);
  ASSERT_FALSE(after.ok());
  EXPECT_EQ(after.error().code(), Errc::disconnected);

  // A new device: opening again works.
  auto replacement = open_pair();
  ASSERT_TRUE(replacement);
  Result<std::unique_ptr<SerialPort>> again = SerialPort::open(replacement->slave_path(), 115200);
  ASSERT_TRUE(again.ok()) << again.error().c_str();
  expect_transparent_both_ways(*replacement, **again);
}

TEST(HalSerial, ReopenOnTheSamePathKeepsWorking) {
  auto device = open_pair();
  ASSERT_TRUE(device);
  Result<std::unique_ptr<SerialPort>> port = SerialPort::open(device->slave_path(), 38400);
  ASSERT_TRUE(port.ok());
  if (!testing::runtime_translates_baud(500000)) GTEST_SKIP() << "qemu-user cannot translate 500000 baud";
  ASSERT_TRUE((*port)->set_baud(500000).ok());
  Status reopened = (*port)->reopen();
  ASSERT_TRUE(reopened.ok()) << reopened.error().c_str();
  EXPECT_EQ(*device->slave_baud(), 500000U);  // reopened at the last requested rate
  expect_transparent_both_ways(*device, **port);
}

TEST(HalSerial, NonexistentPathNamesThePath) {
  const std::string path = "/dev/sen3bot-no-such-tty";
  Result<std::unique_ptr<SerialPort>> port = SerialPort::open(path, 9600);
  ASSERT_FALSE(port.ok());
  EXPECT_TRUE(port.error().code() == Errc::not_found || port.error().code() == Errc::io);
  EXPECT_TRUE(contains(port.error().message(), path)) << port.error().c_str();
}

TEST(HalSerial, NotATerminalIsInvalidArgument) {
  Result<std::unique_ptr<SerialPort>> port = SerialPort::open("/dev/null", 9600);
  ASSERT_FALSE(port.ok());
  EXPECT_EQ(port.error().code(), Errc::invalid_argument);
  EXPECT_TRUE(contains(port.error().message(), "/dev/null")) << port.error().c_str();
}

TEST(HalSerial, SecondExclusiveOpenIsRefused) {
  auto device = open_pair();
  ASSERT_TRUE(device);
  Result<std::unique_ptr<SerialPort>> first = SerialPort::open(device->slave_path(), 9600);
  ASSERT_TRUE(first.ok());
  Result<std::unique_ptr<SerialPort>> second = SerialPort::open(device->slave_path(), 9600);
  ASSERT_FALSE(second.ok());
  EXPECT_TRUE(contains(second.error().message(), "already in use")) << second.error().c_str();
  SerialOptions shared;
  shared.exclusive = false;
  Result<std::unique_ptr<SerialPort>> third = SerialPort::open(device->slave_path(), 9600, shared);
  EXPECT_TRUE(third.ok());
}

TEST(HalSerial, FlushInputDiscardsPendingBytesAndDrainReturns) {
  auto device = open_pair();
  ASSERT_TRUE(device);
  Result<std::unique_ptr<SerialPort>> port = SerialPort::open(device->slave_path(), 9600);
  ASSERT_TRUE(port.ok());
  const std::uint8_t stale[] = {0xAA, 0xBB, 0xCC, 0xDD};
  ASSERT_TRUE(write_all(*device, stale, kIoTimeout_ms));
  for (int i = 0; i < 200 && *(*port)->input_queue_bytes() < sizeof stale; ++i) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_EQ(*(*port)->input_queue_bytes(), sizeof stale);
  ASSERT_TRUE((*port)->flush_input().ok());
  std::uint8_t buffer[8];
  EXPECT_EQ(*(*port)->read(buffer), 0U);

  const std::uint8_t command[] = {0x02, 0x00, 0x02, 0x00, 0x20, 0x25};
  ASSERT_TRUE(write_all(**port, command, kIoTimeout_ms));
  Status drained = (*port)->drain(1000);
  EXPECT_TRUE(drained.ok()) << drained.error().c_str();
  EXPECT_TRUE((*port)->flush_output().ok());
  EXPECT_TRUE((*port)->output_queue_bytes().ok());
}

TEST(HalSerial, EmptyBuffersAreNoOps) {
  auto device = open_pair();
  ASSERT_TRUE(device);
  Result<std::unique_ptr<SerialPort>> port = SerialPort::open(device->slave_path(), 9600);
  ASSERT_TRUE(port.ok());
  EXPECT_EQ(*(*port)->read({}), 0U);
  EXPECT_EQ(*(*port)->write({}), 0U);
  std::uint8_t buffer[4];
  EXPECT_EQ(*(*port)->read(buffer), 0U);  // nothing sent yet: 0 bytes, not an error
  EXPECT_EQ((*port)->name(), device->slave_path());
  EXPECT_GE((*port)->poll_fd(), 0);
}

TEST(HalPty, MasterWithoutKeeperSeesClientsComeAndGo) {
  PtyOptions options;
  options.keep_slave_open = false;
  auto device = open_pair(options);
  ASSERT_TRUE(device);
  EXPECT_FALSE(device->holds_slave());
  std::uint8_t buffer[8];
  // Before the first client: nothing to read (recent kernels) or EIO (older ones).
  Result<std::size_t> before = device->read(buffer);
  EXPECT_TRUE(before.ok() ? *before == 0 : before.error().code() == Errc::disconnected);

  for (int client_number = 0; client_number < 2; ++client_number) {
    {
      Result<std::unique_ptr<SerialPort>> client = SerialPort::open(device->slave_path(), 9600);
      ASSERT_TRUE(client.ok());
      Result<std::size_t> during = device->read(buffer);
      ASSERT_TRUE(during.ok()) << during.error().c_str();
      EXPECT_EQ(*during, 0U);
      expect_transparent_both_ways(*device, **client);
    }
    // The client closed the slave: the emulator is told, and recovers with the next client.
    Result<std::size_t> between = device->read(buffer);
    ASSERT_FALSE(between.ok());
    EXPECT_EQ(between.error().code(), Errc::disconnected);
    EXPECT_TRUE(contains(between.error().message(), device->slave_path())) << between.error().c_str();
  }
}

TEST(HalPty, KeptSlaveHidesClientAbsence) {
  auto device = open_pair();
  ASSERT_TRUE(device);
  EXPECT_TRUE(device->holds_slave());
  std::uint8_t buffer[8];
  Result<std::size_t> nobody = device->read(buffer);
  ASSERT_TRUE(nobody.ok()) << nobody.error().c_str();
  EXPECT_EQ(*nobody, 0U);
  {
    Result<std::unique_ptr<SerialPort>> client = SerialPort::open(device->slave_path(), 9600);
    ASSERT_TRUE(client.ok());
  }
  Result<std::size_t> after_client_left = device->read(buffer);
  ASSERT_TRUE(after_client_left.ok());
  device->release_slave();
  EXPECT_FALSE(device->holds_slave());
  Result<std::size_t> released = device->read(buffer);
  ASSERT_FALSE(released.ok());
  EXPECT_EQ(released.error().code(), Errc::disconnected);
}

TEST(HalPty, SlaveIsRawBeforeAnyClientConfiguresIt) {
  auto device = open_pair();
  ASSERT_TRUE(device);
  Result<SerialLineSettings> line = device->slave_line_settings();
  ASSERT_TRUE(line.ok()) << line.error().c_str();
  EXPECT_TRUE(line->raw);
  EXPECT_GT(line->baud, 0U);
  EXPECT_TRUE(contains(device->name(), device->slave_path()));
  EXPECT_GE(device->poll_fd(), 0);
}

TEST(HalPty, SymlinkGivesAStableNameAndIsRemoved) {
  const std::string link = "/tmp/sen3bot-hal-test-pty-" + std::to_string(::getpid());
  {
    auto device = open_pair();
    ASSERT_TRUE(device);
    Status linked = device->link_slave(link);
    ASSERT_TRUE(linked.ok()) << linked.error().c_str();
    Result<std::unique_ptr<SerialPort>> port = SerialPort::open(link, 38400);
    ASSERT_TRUE(port.ok()) << port.error().c_str();
    expect_transparent_both_ways(*device, **port);
    // A second pair may take over a stale link (an emulator restarted after a crash).
    auto other = open_pair();
    ASSERT_TRUE(other);
    EXPECT_TRUE(other->link_slave(link).ok());
    struct stat info {};
    EXPECT_EQ(::lstat(link.c_str(), &info), 0);
  }
  struct stat info {};
  EXPECT_NE(::lstat(link.c_str(), &info), 0);
}

TEST(HalPty, LinkNeverReplacesARegularFile) {
  const std::string path = "/tmp/sen3bot-hal-test-file-" + std::to_string(::getpid());
  FILE* file = std::fopen(path.c_str(), "w");
  ASSERT_NE(file, nullptr);
  std::fclose(file);
  auto device = open_pair();
  ASSERT_TRUE(device);
  Status linked = device->link_slave(path);
  EXPECT_FALSE(linked.ok());
  struct stat info {};
  EXPECT_EQ(::lstat(path.c_str(), &info), 0);
  EXPECT_TRUE(S_ISREG(info.st_mode));
  ::unlink(path.c_str());
}

TEST(HalOpenByteStream, DevicePathOpensASerialPort) {
  auto device = open_pair();
  ASSERT_TRUE(device);
  Result<std::unique_ptr<ByteStream>> stream = open_byte_stream(device->slave_path(), 38400);
  ASSERT_TRUE(stream.ok()) << stream.error().c_str();
  EXPECT_EQ((*stream)->name(), device->slave_path());
  EXPECT_EQ(*device->slave_baud(), 38400U);
  const std::uint8_t hello[] = {'h', 'i', '\r', '\n'};
  ASSERT_TRUE(write_all(**stream, hello, kIoTimeout_ms));
  EXPECT_EQ(read_exactly(*device, sizeof hello, kIoTimeout_ms), std::vector<std::uint8_t>(hello, hello + 4));
}

}  // namespace
}  // namespace sen3bot::hal
