#pragma once
// Pseudo-terminal pairs for device emulators and tests: the emulator owns the master side
// (this ByteStream), the driver under test opens slave_path() as an ordinary serial port.
#include <cstddef>
#include <cstdint>
#include <memory>
#include <span>
#include <string>
#include <string_view>

#include "sen3bot/hal/byte_stream.hpp"
#include "sen3bot/hal/fd.hpp"
#include "sen3bot/hal/result.hpp"
#include "sen3bot/hal/serial.hpp"

namespace sen3bot::hal {

struct PtyOptions {
  // Hold an fd on the slave ourselves. Without it the master reads EIO and polls HUP
  // (a busy poll loop) after a client closed the slave until the next one opens it, and on
  // some kernels also before the first client.
  bool keep_slave_open = true;
};

class PtyPair final : public ByteStream {
 public:
  // Master opened O_RDWR|O_NOCTTY|O_NONBLOCK|O_CLOEXEC; the slave's line is set raw so
  // nothing is echoed or translated before a client configures it.
  static Result<std::unique_ptr<PtyPair>> open(PtyOptions options = {});
  ~PtyPair() override;
  PtyPair(const PtyPair&) = delete;
  PtyPair& operator=(const PtyPair&) = delete;

  // Master side. EIO (no process has the slave open) is Errc::disconnected; a later client
  // opening the slave makes the master usable again.
  Result<std::size_t> read(std::span<std::uint8_t> out) override;
  Result<std::size_t> write(std::span<const std::uint8_t> data) override;
  [[nodiscard]] int poll_fd() const override { return master_.get(); }
  [[nodiscard]] std::string_view name() const override { return name_; }

  // "/dev/pts/N": what a client passes to SerialPort::open().
  [[nodiscard]] std::string_view slave_path() const { return slave_path_; }

  // The rate the slave side is currently set to (on Linux, TCGETS2 on the master returns
  // the slave's termios). An emulator garbles bytes when this differs from the device's rate.
  [[nodiscard]] Result<std::uint32_t> slave_baud() const;
  [[nodiscard]] Result<SerialLineSettings> slave_line_settings() const;

  // Closes our own slave fd; from then on the master sees EIO/HUP when no client is there.
  void release_slave() { slave_keeper_.reset(); }
  [[nodiscard]] bool holds_slave() const { return slave_keeper_.valid(); }

  // Creates a symlink link_path -> slave_path() (a stable name for configuration files,
  // e.g. /tmp/sen3bot-lms200). A stale symlink is replaced; the link is removed on destruction.
  Status link_slave(std::string_view link_path);

 private:
  PtyPair(UniqueFd master, UniqueFd slave_keeper, std::string slave_path);

  UniqueFd master_;
  UniqueFd slave_keeper_;
  std::string slave_path_;
  std::string name_;
  std::string link_path_;
};

}  // namespace sen3bot::hal
