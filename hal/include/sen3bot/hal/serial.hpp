#pragma once
// Serial ports (RS-232/RS-422 through a UART or USB adapter) as hal::ByteStream.
// The implementation is termios in hal/posix; nothing here needs <termios.h>, so drivers
// never include it.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "sen3bot/hal/byte_stream.hpp"
#include "sen3bot/hal/fd.hpp"
#include "sen3bot/hal/result.hpp"

namespace sen3bot::hal {

// The line as the kernel reports it (read back, not as requested).
struct SerialLineSettings {
  std::uint32_t baud = 0;        // output rate in bit/s
  std::uint32_t input_baud = 0;  // input rate in bit/s (equal to baud unless split rates)
  std::uint8_t data_bits = 0;    // 5..8
  bool parity = false;
  std::uint8_t stop_bits = 0;           // 1 or 2
  bool hardware_flow_control = false;   // CRTSCTS
  bool software_flow_control = false;   // IXON, IXOFF or IXANY
  bool ignore_modem_lines = false;      // CLOCAL
  bool receiver_enabled = false;        // CREAD
  bool raw = false;  // no canonical mode, echo, signals, or CR/LF/strip translation either way
  std::uint8_t vmin = 0;   // VMIN
  std::uint8_t vtime = 0;  // VTIME, tenths of a second
};

struct SerialOptions {
  // Take an advisory flock(LOCK_EX) so a second process (or a second driver instance) that
  // opens the same port fails at open() instead of stealing half the bytes.
  bool exclusive = true;
  // Discard whatever the kernel buffered before we opened (stale bytes from an earlier
  // session would otherwise look like a corrupt frame).
  bool flush_on_open = true;
};

// Raw 8N1, no flow control, CLOCAL|CREAD, VMIN=0/VTIME=0, O_NONBLOCK|O_NOCTTY|O_CLOEXEC.
// Every configuration is one tcsetattr (or TCSETS2 for non-standard rates) followed by a
// read-back that is compared with what was asked; a mismatch is an Error naming the port
// and the setting that differs.
class SerialPort final : public ByteStream, public BaudControl {
 public:
  static Result<std::unique_ptr<SerialPort>> open(std::string_view path, std::uint32_t baud,
                                                  SerialOptions options = {});
  ~SerialPort() override = default;
  SerialPort(const SerialPort&) = delete;
  SerialPort& operator=(const SerialPort&) = delete;

  // Non-blocking; 0 bytes means nothing available. EIO/ENODEV/ENXIO or a hung-up line
  // (poll HUP) is Errc::disconnected. No allocation.
  Result<std::size_t> read(std::span<std::uint8_t> out) override;
  Result<std::size_t> write(std::span<const std::uint8_t> data) override;
  [[nodiscard]] int poll_fd() const override { return fd_.get(); }
  [[nodiscard]] std::string_view name() const override { return path_; }

  // Reconfigures the line to a new rate (drivers probe baud rates). Applies immediately
  // (TCSANOW): call drain() first if output is still queued at the old rate.
  Status set_baud(std::uint32_t baud) override;
  // The output rate the kernel currently reports for this port.
  [[nodiscard]] Result<std::uint32_t> baud() const;
  [[nodiscard]] Result<SerialLineSettings> line_settings() const;

  // Waits (sleeping in 1 ms steps) until the kernel's output queue is empty and the UART
  // has sent its last byte; Errc::timeout if that takes longer than timeout_ms.
  Status drain(int timeout_ms);
  Status flush_input();   // discard received, unread bytes
  Status flush_output();  // discard written, unsent bytes
  [[nodiscard]] Result<std::size_t> input_queue_bytes() const;   // FIONREAD
  [[nodiscard]] Result<std::size_t> output_queue_bytes() const;  // TIOCOUTQ

  // Closes and reopens the same path at the last requested rate (a USB adapter that came
  // back under the same name). On failure the port stays closed and I/O reports
  // Errc::disconnected until a later reopen() succeeds.
  Status reopen();

 private:
  SerialPort(UniqueFd fd, std::string path, std::uint32_t baud, SerialOptions options);

  UniqueFd fd_;
  std::string path_;
  std::uint32_t requested_baud_;
  SerialOptions options_;
};

// Rates that have a Bxxx constant on this platform (50 .. 4000000 on Linux, including
// 500000 for the LMS200's RS-422 mode). Any other rate goes through termios2/BOTHER.
std::span<const std::uint32_t> standard_baud_rates() noexcept;
[[nodiscard]] bool is_standard_baud(std::uint32_t baud) noexcept;

// A ByteStream for a configuration string: "tcp://host:port" (a simulator such as
// MobileSim/AMRISim, or a serial-to-Ethernet bridge) connects over TCP with connect_timeout_ms;
// anything else is a serial device path opened at baud.
Result<std::unique_ptr<ByteStream>> open_byte_stream(std::string_view spec, std::uint32_t baud,
                                                     int connect_timeout_ms = 2000);

}  // namespace sen3bot::hal
