#pragma once
// The one interface every byte-oriented link implements: serial ports, pseudo-terminals,
// TCP streams, in-memory pipes, capture replays. Drivers see only this.
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "sen3bot/hal/result.hpp"

namespace sen3bot::hal {

class ByteStream {
 public:
  virtual ~ByteStream() = default;

  // Non-blocking. Returns the number of bytes read; 0 means nothing is available now.
  // A vanished peer or device is Errc::disconnected (recoverable by reopening).
  virtual Result<std::size_t> read(std::span<std::uint8_t> out) = 0;

  // Non-blocking. Returns the number of bytes accepted, which may be fewer than offered.
  virtual Result<std::size_t> write(std::span<const std::uint8_t> data) = 0;

  // A file descriptor to poll for readability, or -1 for streams that are not fd-backed
  // (in-memory pipes, replays); those are polled by calling read().
  [[nodiscard]] virtual int poll_fd() const { return -1; }

  // Human-readable endpoint name for logs and errors ("/dev/ttyUSB0", "tcp://host:8101").
  [[nodiscard]] virtual std::string_view name() const = 0;
};

// Changes the host side's line rate of an open link (a serial port, or a simulated line).
class BaudControl {
 public:
  virtual ~BaudControl() = default;
  virtual Status set_baud(std::uint32_t baud) = 0;
};

}  // namespace sen3bot::hal
