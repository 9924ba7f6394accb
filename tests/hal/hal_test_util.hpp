#pragma once
#include <cstdlib>
// Helpers for the HAL tests: bounded waits over non-blocking ByteStreams.
#include <poll.h>

#include <chrono>
#include <cstdint>
#include <span>
#include <string_view>
#include <thread>
#include <vector>

#include "sen3bot/hal/byte_stream.hpp"
#include "sen3bot/hal/serial.hpp"

namespace sen3bot::hal::testing {

using Clock = std::chrono::steady_clock;

// Waits until the stream's fd is readable (or just sleeps a little for fd-less streams).
inline void wait_readable(const ByteStream& stream, int timeout_ms) {
  if (stream.poll_fd() < 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
    return;
  }
  pollfd p{stream.poll_fd(), POLLIN, 0};
  ::poll(&p, 1, timeout_ms);
}

// Reads until `count` bytes arrived, an error, or the timeout. Returns what was read and
// stores the first error (if any) in error_out.
inline std::vector<std::uint8_t> read_exactly(ByteStream& stream, std::size_t count, int timeout_ms,
                                              Error* error_out = nullptr) {
  std::vector<std::uint8_t> out(count);
  std::size_t got = 0;
  const auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms);
  while (got < count && Clock::now() < deadline) {
    Result<std::size_t> n = stream.read(std::span(out).subspan(got));
    if (!n) {
      if (error_out != nullptr) *error_out = n.error();
      break;
    }
    got += *n;
    if (*n == 0) wait_readable(stream, 10);
  }
  out.resize(got);
  return out;
}

// Writes everything (retrying on a full buffer) or stops at an error or the timeout.
inline bool write_all(ByteStream& stream, std::span<const std::uint8_t> data, int timeout_ms) {
  std::size_t sent = 0;
  const auto deadline = Clock::now() + std::chrono::milliseconds(timeout_ms);
  while (sent < data.size() && Clock::now() < deadline) {
    Result<std::size_t> n = stream.write(data.subspan(sent));
    if (!n) return false;
    sent += *n;
    if (*n == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  return sent == data.size();
}

inline std::vector<std::uint8_t> every_byte_value() {
  std::vector<std::uint8_t> bytes(256);
  for (std::size_t i = 0; i < bytes.size(); ++i) bytes[i] = static_cast<std::uint8_t>(i);
  return bytes;
}

inline bool contains(std::string_view text, std::string_view part) { return text.find(part) != std::string_view::npos; }


// qemu-user 7.2 (the cross suite's runtime) translates termios rates only up to 460800 and has
// no TCGETS2/TCSETS2, so higher and non-standard rates cannot be exercised under it. The
// cross toolchain files set SEN3BOT_QEMU_USER for test programs run through qemu.
inline bool runtime_translates_baud(std::uint32_t baud) {
  return std::getenv("SEN3BOT_QEMU_USER") == nullptr || (sen3bot::hal::is_standard_baud(baud) && baud <= 460800);
}

}  // namespace sen3bot::hal::testing
