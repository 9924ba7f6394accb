#pragma once
// The board: everything the firmware needs from the machine it runs on, behind one interface.
// The firmware composes its tasks against a Board and never learns what is on the far side: the
// POSIX board opens real serial ports and sockets on the robot computer; the simulated board
// (sim/board) answers the same requests with device emulators driven by a ground-truth world.
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "sen3bot/hal/byte_stream.hpp"
#include "sen3bot/hal/can.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/pubsub.hpp"
#include "sen3bot/hal/result.hpp"

namespace sen3bot::hal {

// What a driver asks for: its configured port and the rate to open it at.
struct LinkRequest {
  std::string_view port;             // a device path, tcp://host:port, or a name the board knows
  std::uint32_t baud = 0;            // 0: not a serial line (or keep the line's rate)
  int connect_timeout_ms = 2000;     // TCP only
};

// An open link. `baud_control` points into the stream's owner and lives as long as `stream`;
// null when the rate cannot change (TCP, a fixed simulated line).
struct Link {
  std::unique_ptr<ByteStream> stream;
  BaudControl* baud_control = nullptr;
  std::uint32_t baud = 0;  // the rate it was opened at, 0 when not a serial line
};

// The receiving end of a datagram channel (a remote person detector's boxes): a UDP port on
// the robot, the simulated detector's queue on the simulated board.
class DatagramPort {
 public:
  virtual ~DatagramPort() = default;
  // The next waiting datagram into out: its size, or nullopt when none waits. A datagram larger
  // than out is dropped and reported as an error. Never blocks, never allocates.
  virtual Result<std::optional<std::size_t>> receive(std::span<std::uint8_t> out) = 0;
};

// Discrete I/O: an e-stop chain input, a warning light output.
class DigitalInput {
 public:
  virtual ~DigitalInput() = default;
  // True when the input is active (for an e-stop: pressed or the chain is open).
  virtual Result<bool> read() = 0;
};

class DigitalOutput {
 public:
  virtual ~DigitalOutput() = default;
  virtual Status write(bool on) = 0;
};

class Board {
 public:
  virtual ~Board() = default;
  // Human-readable name for logs ("posix", "sim").
  [[nodiscard]] virtual std::string_view name() const = 0;
  [[nodiscard]] virtual Clock& clock() = 0;
  // Non-null when time moves only when the firmware's lockstep loop advances this clock (the
  // same object as clock()); null when time runs on its own.
  [[nodiscard]] virtual SimClock* lockstep_clock() noexcept { return nullptr; }
  // Opens the link a driver calls `link` ("base", "laser") at the configured port. Reopening
  // after a failure is another call: the old stream is dropped by its owner. Allocates; call at
  // start-up and on reconnects only.
  virtual Result<Link> open_link(std::string_view link, const LinkRequest& request) = 0;
  // Opens the datagram channel `name` ("detector") at `address`: "udp://ADDRESS:PORT" on the
  // robot (ADDRESS "0.0.0.0" for every interface), or a name the board knows ("sim").
  // Allocates; call at start-up.
  virtual Result<std::unique_ptr<DatagramPort>> open_datagram(std::string_view name, std::string_view address);
  // Opens the CAN bus `name` ("io_node") on `interface`: a SocketCAN interface ("can0") on
  // the robot, or a name the board knows ("sim"). Allocates; call at start-up.
  virtual Result<std::unique_ptr<CanBus>> open_can(std::string_view name, std::string_view interface);
  // Opens the publish/subscribe link `name` ("fleet"): an MQTT broker on the robot
  // (options.url mqtt:// or mqtts://), the site's in-process broker in simulation ("sim").
  // Allocates; call at start-up. Reconnecting is the link's own business.
  virtual Result<std::unique_ptr<PubSub>> open_pubsub(std::string_view name, const PubSubOptions& options);
  // Named discrete I/O ("estop", "light"), or null when this board has no such line.
  [[nodiscard]] virtual DigitalInput* input(std::string_view name) noexcept {
    (void)name;
    return nullptr;
  }
  [[nodiscard]] virtual DigitalOutput* output(std::string_view name) noexcept {
    (void)name;
    return nullptr;
  }
  // Called before the firmware's threads start and after they stopped: a board may run its
  // own thread (a simulated world in real time).
  virtual Status start() { return Status::success(); }
  virtual void stop() noexcept {}
};

// The robot computer: CLOCK_MONOTONIC, links opened with open_byte_stream (serial ports with
// their rate control, TCP), discrete I/O on Linux GPIO lines given as "/dev/gpiochipN:LINE".
class PosixBoard final : public Board {
 public:
  struct Lines {
    std::string estop_input;   // empty: none
    std::string light_output;  // empty: none
  };
  PosixBoard();
  explicit PosixBoard(const Lines& lines);
  ~PosixBoard() override;
  // Opens the configured GPIO lines; a line that cannot be opened is an error naming it.
  Status open_lines();

  [[nodiscard]] std::string_view name() const override { return "posix"; }
  [[nodiscard]] Clock& clock() override { return clock_; }
  Result<Link> open_link(std::string_view link, const LinkRequest& request) override;
  Result<std::unique_ptr<DatagramPort>> open_datagram(std::string_view name, std::string_view address) override;
  Result<std::unique_ptr<CanBus>> open_can(std::string_view name, std::string_view interface) override;
  Result<std::unique_ptr<PubSub>> open_pubsub(std::string_view name, const PubSubOptions& options) override;
  [[nodiscard]] DigitalInput* input(std::string_view name) noexcept override;
  [[nodiscard]] DigitalOutput* output(std::string_view name) noexcept override;

 private:
  class GpioLine;
  PosixClock clock_;
  Lines lines_;
  std::unique_ptr<GpioLine> estop_;
  std::unique_ptr<GpioLine> light_;
};

}  // namespace sen3bot::hal
