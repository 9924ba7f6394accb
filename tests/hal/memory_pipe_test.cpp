#include <gtest/gtest.h>

#include <random>
#include <thread>
#include <vector>

#include "hal_test_util.hpp"
#include "sen3bot/hal/memory_stream.hpp"

namespace sen3bot::hal {
namespace {

std::vector<std::uint8_t> bytes(std::initializer_list<int> values) {
  std::vector<std::uint8_t> out;
  for (const int v : values) out.push_back(static_cast<std::uint8_t>(v));
  return out;
}

TEST(HalMemoryPipe, BothDirectionsCarryEveryByteValue) {
  MemoryPipe pipe(512, "driver", "emulator");
  const std::vector<std::uint8_t> all = testing::every_byte_value();
  EXPECT_EQ(*pipe.a().write(all), all.size());
  EXPECT_EQ(testing::read_exactly(pipe.b(), all.size(), 100), all);
  EXPECT_EQ(*pipe.b().write(all), all.size());
  EXPECT_EQ(testing::read_exactly(pipe.a(), all.size(), 100), all);
  EXPECT_EQ(pipe.a().name(), "driver");
  EXPECT_EQ(pipe.b().name(), "emulator");
  EXPECT_EQ(pipe.a().poll_fd(), -1);
}

TEST(HalMemoryPipe, NothingToReadIsZeroBytes) {
  MemoryPipe pipe(16);
  std::uint8_t buffer[4];
  EXPECT_EQ(*pipe.a().read(buffer), 0U);
  EXPECT_EQ(*pipe.a().read({}), 0U);
  EXPECT_EQ(*pipe.a().write({}), 0U);
  EXPECT_TRUE(pipe.a().connected());
}

TEST(HalMemoryPipe, FullRingAcceptsPartialWrites) {
  MemoryPipe pipe(8);
  const std::vector<std::uint8_t> ten = bytes({0, 1, 2, 3, 4, 5, 6, 7, 8, 9});
  EXPECT_EQ(*pipe.a().write(ten), 8U);
  EXPECT_EQ(pipe.a().writable_bytes(), 0U);
  EXPECT_EQ(pipe.b().readable_bytes(), 8U);
  EXPECT_EQ(*pipe.a().write(ten), 0U);  // full: nothing accepted, no error
  std::uint8_t three[3];
  EXPECT_EQ(*pipe.b().read(three), 3U);
  EXPECT_EQ(*pipe.a().write(std::span(ten).subspan(8)), 2U);
  std::uint8_t rest[16];
  ASSERT_EQ(*pipe.b().read(rest), 7U);
  EXPECT_EQ(std::vector<std::uint8_t>(rest, rest + 7), bytes({3, 4, 5, 6, 7, 8, 9}));
}

TEST(HalMemoryPipe, WrapAroundKeepsTheByteOrder) {
  // A capacity that is not a power of two, and chunk sizes from a fixed seed, so writes and
  // reads straddle the end of the buffer in every possible way.
  MemoryPipe pipe(7);
  std::mt19937 random(1234);
  std::uniform_int_distribution<std::size_t> chunk(0, 9);
  std::uint8_t next_to_write = 0;
  std::uint8_t next_expected = 0;
  std::size_t total = 0;
  for (int step = 0; step < 10'000; ++step) {
    std::uint8_t out[9];
    const std::size_t offer = chunk(random);
    for (std::size_t i = 0; i < offer; ++i) out[i] = static_cast<std::uint8_t>(next_to_write + i);
    const std::size_t accepted = *pipe.a().write(std::span(out, offer));
    EXPECT_LE(accepted, offer);
    next_to_write = static_cast<std::uint8_t>(next_to_write + accepted);

    std::uint8_t in[9];
    const std::size_t got = *pipe.b().read(std::span(in, chunk(random)));
    for (std::size_t i = 0; i < got; ++i) {
      ASSERT_EQ(in[i], next_expected) << "step " << step;
      ++next_expected;
    }
    total += got;
    EXPECT_LE(pipe.b().readable_bytes(), 7U);
  }
  EXPECT_GT(total, 10'000U);
}

TEST(HalMemoryPipe, DisconnectDrainsThenReportsDisconnected) {
  MemoryPipe pipe(32, "lms200", "driver");
  ASSERT_EQ(*pipe.a().write(bytes({0x06, 0x02, 0x80})), 3U);
  pipe.a().disconnect();
  EXPECT_FALSE(pipe.a().connected());
  EXPECT_FALSE(pipe.b().connected());

  std::uint8_t buffer[2];
  EXPECT_EQ(*pipe.b().read(buffer), 2U);  // what was sent before the unplug still arrives
  EXPECT_EQ(*pipe.b().read(buffer), 1U);
  Result<std::size_t> drained = pipe.b().read(buffer);
  ASSERT_FALSE(drained.ok());
  EXPECT_EQ(drained.error().code(), Errc::disconnected);
  EXPECT_TRUE(testing::contains(drained.error().message(), "driver"));

  Result<std::size_t> to_gone_peer = pipe.b().write(bytes({1}));
  ASSERT_FALSE(to_gone_peer.ok());
  EXPECT_EQ(to_gone_peer.error().code(), Errc::disconnected);

  Result<std::size_t> own_read = pipe.a().read(buffer);
  ASSERT_FALSE(own_read.ok());
  EXPECT_EQ(own_read.error().code(), Errc::disconnected);
  Result<std::size_t> own_write = pipe.a().write(bytes({1}));
  ASSERT_FALSE(own_write.ok());
  EXPECT_EQ(own_write.error().code(), Errc::disconnected);

  pipe.reset();  // the device is plugged back in
  EXPECT_TRUE(pipe.a().connected());
  EXPECT_EQ(*pipe.b().read(buffer), 0U);
  EXPECT_EQ(*pipe.b().write(bytes({7})), 1U);
  EXPECT_EQ(*pipe.a().read(buffer), 1U);
  EXPECT_EQ(buffer[0], 7);
}

TEST(HalMemoryPipe, EitherEndMayDisconnect) {
  MemoryPipe pipe(8);
  pipe.b().disconnect();
  Result<std::size_t> write = pipe.a().write(bytes({1}));
  ASSERT_FALSE(write.ok());
  EXPECT_EQ(write.error().code(), Errc::disconnected);
  std::uint8_t buffer[1];
  Result<std::size_t> read = pipe.a().read(buffer);
  ASSERT_FALSE(read.ok());
  EXPECT_EQ(read.error().code(), Errc::disconnected);
}

TEST(HalSpscByteRing, CapacityOneAndClear) {
  SpscByteRing ring(1);
  EXPECT_EQ(ring.capacity(), 1U);
  const std::uint8_t two[] = {1, 2};
  EXPECT_EQ(ring.write(two), 1U);
  EXPECT_EQ(ring.write(two), 0U);
  EXPECT_EQ(ring.size(), 1U);
  ring.clear();
  EXPECT_EQ(ring.size(), 0U);
  EXPECT_EQ(ring.free_space(), 1U);
  SpscByteRing zero(0);  // clamped to 1 so the ring is usable
  EXPECT_EQ(zero.capacity(), 1U);
}

TEST(HalMemoryPipe, EmulatorThreadEchoesADriverThread) {
  // The emulator echoes every byte back; the driver checks 1 MiB of a counting pattern both
  // ways through a small ring, so the rings wrap and fill constantly under contention.
  constexpr std::size_t kTotalBytes = 1 << 20;
  MemoryPipe pipe(61);
  std::thread emulator([&pipe] {
    std::uint8_t buffer[37];
    std::size_t echoed = 0;
    while (echoed < kTotalBytes) {
      Result<std::size_t> n = pipe.b().read(buffer);
      if (!n.ok()) return;
      std::size_t sent = 0;
      while (sent < *n) {
        Result<std::size_t> w = pipe.b().write(std::span(buffer, *n).subspan(sent));
        if (!w.ok()) return;
        sent += *w;
        if (*w == 0) std::this_thread::yield();
      }
      echoed += *n;
      if (*n == 0) std::this_thread::yield();
    }
  });
  std::size_t written = 0;
  std::size_t checked = 0;
  bool ok = true;
  while (checked < kTotalBytes && ok) {
    std::uint8_t out[53];
    std::size_t offer = std::min(sizeof out, kTotalBytes - written);
    for (std::size_t i = 0; i < offer; ++i) out[i] = static_cast<std::uint8_t>((written + i) * 7);
    written += *pipe.a().write(std::span(out, offer));
    std::uint8_t in[41];
    const std::size_t got = *pipe.a().read(in);
    for (std::size_t i = 0; i < got; ++i) {
      if (in[i] != static_cast<std::uint8_t>((checked + i) * 7)) ok = false;
    }
    checked += got;
    if (got == 0) std::this_thread::yield();
  }
  emulator.join();
  EXPECT_TRUE(ok);
  EXPECT_EQ(checked, kTotalBytes);
}

TEST(HalMemoryPipe, DisconnectFromAnotherThreadIsSeenAfterTheLastBytes) {
  for (int round = 0; round < 200; ++round) {
    MemoryPipe pipe(64);
    std::thread device([&pipe] {
      const std::uint8_t last[] = {1, 2, 3, 4, 5};
      (void)pipe.b().write(last);
      pipe.b().disconnect();
    });
    std::size_t received = 0;
    for (;;) {
      std::uint8_t buffer[8];
      Result<std::size_t> n = pipe.a().read(buffer);
      if (!n.ok()) {
        EXPECT_EQ(n.error().code(), Errc::disconnected);
        break;
      }
      received += *n;
    }
    device.join();
    ASSERT_EQ(received, 5U) << "round " << round;  // never "disconnected" before the data
  }
}

}  // namespace
}  // namespace sen3bot::hal
