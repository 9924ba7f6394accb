// Serial ports over termios. Standard rates use the Bxxx constants; any other rate goes
// through serial_termios2.cpp (BOTHER), which cannot share this file's <termios.h>.
#include <fcntl.h>
#include <poll.h>
#include <sys/file.h>
#include <sys/ioctl.h>
#include <termios.h>
#include <unistd.h>

#include <algorithm>
#include <array>
#include <cerrno>
#include <chrono>
#include <cstdarg>
#include <cstdio>
#include <optional>
#include <thread>

#include "posix_error.hpp"
#include "sen3bot/hal/serial.hpp"
#include "serial_internal.hpp"
#include "serial_termios2.hpp"

namespace sen3bot::hal {

namespace {

struct BaudCode {
  std::uint32_t baud;
  speed_t code;
};

// Every Bxxx constant Linux defines (asm-generic/termbits.h); guarded because a few
// architectures stop at B460800.
constexpr BaudCode kBaudCodes[] = {
    {50, B50},         {75, B75},         {110, B110},       {134, B134},
    {150, B150},       {200, B200},       {300, B300},       {600, B600},
    {1200, B1200},     {1800, B1800},     {2400, B2400},     {4800, B4800},
    {9600, B9600},     {19200, B19200},   {38400, B38400},
#ifdef B57600
    {57600, B57600},
#endif
#ifdef B115200
    {115200, B115200},
#endif
#ifdef B230400
    {230400, B230400},
#endif
#ifdef B460800
    {460800, B460800},
#endif
#ifdef B500000
    {500000, B500000},  // SICK LMS200 over RS-422
#endif
#ifdef B576000
    {576000, B576000},
#endif
#ifdef B921600
    {921600, B921600},
#endif
#ifdef B1000000
    {1000000, B1000000},
#endif
#ifdef B1152000
    {1152000, B1152000},
#endif
#ifdef B1500000
    {1500000, B1500000},
#endif
#ifdef B2000000
    {2000000, B2000000},
#endif
#ifdef B2500000
    {2500000, B2500000},
#endif
#ifdef B3000000
    {3000000, B3000000},
#endif
#ifdef B3500000
    {3500000, B3500000},
#endif
#ifdef B4000000
    {4000000, B4000000},
#endif
};

constexpr auto kStandardRates = [] {
  std::array<std::uint32_t, std::size(kBaudCodes)> rates{};
  for (std::size_t i = 0; i < rates.size(); ++i) rates[i] = kBaudCodes[i].baud;
  return rates;
}();

std::optional<speed_t> code_for_baud(std::uint32_t baud) {
  for (const BaudCode& entry : kBaudCodes) {
    if (entry.baud == baud) return entry.code;
  }
  return std::nullopt;
}

std::uint32_t baud_for_code(speed_t code) {
  for (const BaudCode& entry : kBaudCodes) {
    if (entry.code == code) return entry.baud;
  }
  return 0;
}

// What raw 8N1 without flow control clears, and must find cleared on read-back.
constexpr tcflag_t kRawInputClear = IGNBRK | BRKINT | PARMRK | ISTRIP | INLCR | IGNCR | ICRNL |
                                    IXON | IXOFF | IXANY | INPCK | IMAXBEL
#ifdef IUCLC
                                    | IUCLC
#endif
    ;
constexpr tcflag_t kRawOutputClear = OPOST;
constexpr tcflag_t kRawLocalClear = ECHO | ECHOE | ECHOK | ECHONL | ICANON | ISIG | IEXTEN;
constexpr tcflag_t kControlWanted = CS8 | CLOCAL | CREAD;

void make_raw_8n1(termios& t) {
  t.c_iflag &= ~kRawInputClear;
  t.c_oflag &= ~kRawOutputClear;
  t.c_lflag &= ~kRawLocalClear;
  t.c_cflag &= ~(CSIZE | PARENB | PARODD | CSTOPB | CRTSCTS);
#ifdef CMSPAR
  t.c_cflag &= ~CMSPAR;
#endif
#ifdef CIBAUD
  // Input rate field 0 = "same as output", so an earlier split or BOTHER input rate is gone.
  t.c_cflag &= ~CIBAUD;
#endif
  t.c_cflag |= kControlWanted;
  // Pure polling: read() returns at once with whatever is there.
  t.c_cc[VMIN] = 0;
  t.c_cc[VTIME] = 0;
}

posix::LineFlags flags_of(const termios& t) {
  posix::LineFlags f;
  f.iflag = t.c_iflag;
  f.oflag = t.c_oflag;
  f.cflag = t.c_cflag;
  f.lflag = t.c_lflag;
  f.vmin = t.c_cc[VMIN];
  f.vtime = t.c_cc[VTIME];
  return f;
}

// Bounded, truncating text builder for error messages (no allocation).
class MessageBuilder {
 public:
  [[gnu::format(printf, 2, 3)]] void append(const char* fmt, ...) {
    if (length_ >= sizeof text_ - 1) return;
    std::va_list args;
    va_start(args, fmt);
    const int n = std::vsnprintf(text_ + length_, sizeof text_ - length_, fmt, args);
    va_end(args);
    if (n > 0) length_ = std::min(sizeof text_ - 1, length_ + static_cast<std::size_t>(n));
  }
  [[nodiscard]] std::string_view view() const { return {text_, length_}; }

 private:
  char text_[Error::kMessageCapacity] = {};
  std::size_t length_ = 0;
};

// The kernel itself treats rates within 2% as "close enough" when it encodes what a
// UART actually achieves (tty_termios_encode_baud_rate), and a UART frame tolerates that.
bool baud_close_enough(std::uint32_t actual, std::uint32_t requested) {
  const std::uint64_t difference = actual > requested ? actual - requested : requested - actual;
  return difference * 50U <= requested;
}

Status verify_line(std::string_view name, std::uint32_t baud, const posix::LineState& got) {
  MessageBuilder differences;
  int count = 0;
  auto note = [&](const char* what) {
    differences.append("%s%s", count++ == 0 ? "" : ", ", what);
  };
  const posix::LineFlags& f = got.flags;
  if ((f.cflag & CSIZE) != CS8) note("not 8 data bits");
  if ((f.cflag & PARENB) != 0) note("parity still on");
  if ((f.cflag & CSTOPB) != 0) note("2 stop bits");
  if ((f.cflag & CRTSCTS) != 0) note("CRTSCTS still set");
  if ((f.cflag & CLOCAL) == 0) note("CLOCAL not set");
  if ((f.cflag & CREAD) == 0) note("CREAD not set");
  if ((f.iflag & (IXON | IXOFF | IXANY)) != 0) note("XON/XOFF still on");
  if ((f.iflag & (kRawInputClear & ~(IXON | IXOFF | IXANY))) != 0) note("input translation still on");
  if ((f.oflag & kRawOutputClear) != 0) note("OPOST still on");
  if ((f.lflag & kRawLocalClear) != 0) note("canonical/echo/signals still on");
  if (f.vmin != 0 || f.vtime != 0) note("VMIN/VTIME not 0");
  if (!baud_close_enough(got.output_baud, baud) ||
      (got.input_baud != 0 && !baud_close_enough(got.input_baud, baud))) {
    char text[64];
    std::snprintf(text, sizeof text, "baud reads back as %u/%u", static_cast<unsigned>(got.output_baud),
                  static_cast<unsigned>(got.input_baud));
    note(text);
  }
  if (count == 0) return {};
  const std::string_view what = differences.view();
  return Error::format(Errc::io, "%.*s: line settings for %u baud 8N1 raw did not stick: %.*s",
                       static_cast<int>(name.size()), name.data(), static_cast<unsigned>(baud),
                       static_cast<int>(what.size()), what.data());
}

int tcsetattr_retry(int fd, const termios& t) {
  for (;;) {
    if (::tcsetattr(fd, TCSANOW, &t) == 0) return 0;
    if (errno != EINTR) return errno;
  }
}

// Reads flags (tcgetattr) and numeric rates (TCGETS2 where available, which also covers
// drivers that re-encode an inexact rate as BOTHER).
int read_line_state(int fd, posix::LineState& state) {
  termios t{};
  if (::tcgetattr(fd, &t) != 0) return errno;
  state.flags = flags_of(t);
  if (posix::termios2_available()) {
    posix::LineState numeric;
    const int err = posix::termios2_read(fd, numeric);
    if (err == 0) {
      state.input_baud = numeric.input_baud;
      state.output_baud = numeric.output_baud;
      return 0;
    }
    // ENOSYS/ENOTTY: the kernel interface is there but this runtime lacks the ioctl
    // (qemu-user 7.2 does not translate TCGETS2); the standard codes still tell the rate.
    if (err != ENOSYS && err != ENOTTY && err != EINVAL) return err;
  }
  state.output_baud = baud_for_code(::cfgetospeed(&t));
  state.input_baud = baud_for_code(::cfgetispeed(&t));
  return 0;
}

Error query_error(std::string_view name, int err, const char* what) {
  const Errc code = (err == ENOTTY || err == EINVAL) ? Errc::invalid_argument : posix::classify_io_errno(err);
  return posix::errno_error(code, err, "%.*s: %s", static_cast<int>(name.size()), name.data(), what);
}

// A tty that was hung up (USB adapter unplugged, pty master closed) reads as 0 bytes, the
// same as "nothing yet" with VMIN=0/VTIME=0; poll() tells them apart.
bool hung_up(int fd) {
  pollfd p{fd, POLLIN, 0};
  if (::poll(&p, 1, 0) < 0) return false;
  return (p.revents & (POLLHUP | POLLERR | POLLNVAL)) != 0;
}

Error port_closed(const std::string& path) {
  return Error::format(Errc::disconnected, "%s: port is closed (the last reopen failed)", path.c_str());
}

}  // namespace

namespace posix {

Status configure_raw_line(int fd, std::string_view name, std::uint32_t baud) {
  const int name_length = static_cast<int>(name.size());
  if (baud == 0) {
    return Error::format(Errc::invalid_argument, "%.*s: baud 0 is not a rate (B0 means hang up)",
                         name_length, name.data());
  }
  termios t{};
  if (::tcgetattr(fd, &t) != 0) {
    const int err = errno;
    if (err == ENOTTY || err == EINVAL) {
      return errno_error(Errc::invalid_argument, err, "%.*s is not a serial port (tcgetattr)",
                         name_length, name.data());
    }
    return errno_error(classify_io_errno(err), err, "%.*s: tcgetattr", name_length, name.data());
  }
  make_raw_8n1(t);

  LineState readback;
  if (const std::optional<speed_t> code = code_for_baud(baud)) {
    ::cfsetispeed(&t, *code);
    ::cfsetospeed(&t, *code);
    if (const int err = tcsetattr_retry(fd, t); err != 0) {
      return errno_error(classify_io_errno(err) == Errc::disconnected ? Errc::disconnected : Errc::io, err,
                         "%.*s: tcsetattr raw 8N1 %u baud", name_length, name.data(),
                         static_cast<unsigned>(baud));
    }
  } else {
    if (!termios2_available()) {
      return Error::format(Errc::not_supported,
                           "%.*s: %u baud is not a standard rate and this platform has no termios2/BOTHER",
                           name_length, name.data(), static_cast<unsigned>(baud));
    }
    LineFlags flags = flags_of(t);
    if (const int err = termios2_apply(fd, flags, baud); err != 0) {
      return errno_error(err == EINVAL || err == ENOSYS || err == ENOTTY ? Errc::not_supported : classify_io_errno(err), err,
                         "%.*s: TCSETS2 raw 8N1 %u baud (BOTHER)", name_length, name.data(),
                         static_cast<unsigned>(baud));
    }
  }
  if (const int err = read_line_state(fd, readback); err != 0) {
    return errno_error(classify_io_errno(err), err, "%.*s: reading back the line settings",
                       name_length, name.data());
  }
  return verify_line(name, baud, readback);
}

Result<SerialLineSettings> query_line_settings(int fd, std::string_view name) {
  LineState state;
  if (const int err = read_line_state(fd, state); err != 0) return query_error(name, err, "reading line settings");
  const LineFlags& f = state.flags;
  SerialLineSettings s;
  s.baud = state.output_baud;
  s.input_baud = state.input_baud;
  switch (f.cflag & CSIZE) {
    case CS5: s.data_bits = 5; break;
    case CS6: s.data_bits = 6; break;
    case CS7: s.data_bits = 7; break;
    default: s.data_bits = 8; break;
  }
  s.parity = (f.cflag & PARENB) != 0;
  s.stop_bits = (f.cflag & CSTOPB) != 0 ? 2 : 1;
  s.hardware_flow_control = (f.cflag & CRTSCTS) != 0;
  s.software_flow_control = (f.iflag & (IXON | IXOFF | IXANY)) != 0;
  s.ignore_modem_lines = (f.cflag & CLOCAL) != 0;
  s.receiver_enabled = (f.cflag & CREAD) != 0;
  s.raw = (f.lflag & (ICANON | ECHO | ISIG | IEXTEN)) == 0 && (f.oflag & OPOST) == 0 &&
          (f.iflag & (ICRNL | INLCR | IGNCR | ISTRIP | PARMRK)) == 0;
  s.vmin = f.vmin;
  s.vtime = f.vtime;
  return s;
}

Result<std::uint32_t> query_baud(int fd, std::string_view name) {
  LineState state;
  if (const int err = read_line_state(fd, state); err != 0) return query_error(name, err, "reading the baud rate");
  return state.output_baud;
}

}  // namespace posix

std::span<const std::uint32_t> standard_baud_rates() noexcept { return kStandardRates; }

bool is_standard_baud(std::uint32_t baud) noexcept { return code_for_baud(baud).has_value(); }

SerialPort::SerialPort(UniqueFd fd, std::string path, std::uint32_t baud, SerialOptions options)
    : fd_(std::move(fd)), path_(std::move(path)), requested_baud_(baud), options_(options) {}

namespace {

Result<UniqueFd> open_configured(const std::string& path, std::uint32_t baud, SerialOptions options) {
  UniqueFd fd(::open(path.c_str(), O_RDWR | O_NOCTTY | O_NONBLOCK | O_CLOEXEC));
  if (!fd) {
    const int err = errno;
    return posix::errno_error(posix::classify_open_errno(err), err, "open serial port %s", path.c_str());
  }
  if (options.exclusive && ::flock(fd.get(), LOCK_EX | LOCK_NB) != 0) {
    const int err = errno;
    if (err == EWOULDBLOCK) {
      return Error::format(Errc::io, "%s: already in use by another process or driver (flock)", path.c_str());
    }
    return posix::errno_error(Errc::io, err, "%s: flock", path.c_str());
  }
  if (Status configured = posix::configure_raw_line(fd.get(), path, baud); !configured) {
    return configured.error();
  }
  if (options.flush_on_open && ::tcflush(fd.get(), TCIOFLUSH) != 0) {
    const int err = errno;
    return posix::errno_error(Errc::io, err, "%s: tcflush", path.c_str());
  }
  return fd;
}

}  // namespace

Result<std::unique_ptr<SerialPort>> SerialPort::open(std::string_view path, std::uint32_t baud,
                                                     SerialOptions options) {
  std::string path_text(path);
  Result<UniqueFd> fd = open_configured(path_text, baud, options);
  if (!fd) return fd.error();
  return std::unique_ptr<SerialPort>(new SerialPort(std::move(fd).value(), std::move(path_text), baud, options));
}

Status SerialPort::reopen() {
  fd_.reset();  // release our flock before taking it again
  Result<UniqueFd> fd = open_configured(path_, requested_baud_, options_);
  if (!fd) return fd.error();
  fd_ = std::move(fd).value();
  return {};
}

Result<std::size_t> SerialPort::read(std::span<std::uint8_t> out) {
  if (!fd_) return port_closed(path_);
  if (out.empty()) return std::size_t{0};
  for (;;) {
    const ssize_t n = ::read(fd_.get(), out.data(), out.size());
    if (n > 0) return static_cast<std::size_t>(n);
    if (n == 0) {
      if (hung_up(fd_.get())) {
        return Error::format(Errc::disconnected, "%s: device disconnected (line hung up)", path_.c_str());
      }
      return std::size_t{0};
    }
    const int err = errno;
    if (err == EINTR) continue;
    if (err == EAGAIN || err == EWOULDBLOCK) return std::size_t{0};
    const Errc code = posix::classify_io_errno(err);
    return posix::errno_error(code, err, code == Errc::disconnected ? "%s: device disconnected (read)" : "%s: read",
                              path_.c_str());
  }
}

Result<std::size_t> SerialPort::write(std::span<const std::uint8_t> data) {
  if (!fd_) return port_closed(path_);
  if (data.empty()) return std::size_t{0};
  for (;;) {
    const ssize_t n = ::write(fd_.get(), data.data(), data.size());
    if (n >= 0) return static_cast<std::size_t>(n);
    const int err = errno;
    if (err == EINTR) continue;
    if (err == EAGAIN || err == EWOULDBLOCK) return std::size_t{0};
    const Errc code = posix::classify_io_errno(err);
    return posix::errno_error(code, err, code == Errc::disconnected ? "%s: device disconnected (write)" : "%s: write",
                              path_.c_str());
  }
}

Status SerialPort::set_baud(std::uint32_t baud) {
  if (!fd_) return port_closed(path_);
  if (Status configured = posix::configure_raw_line(fd_.get(), path_, baud); !configured) return configured;
  requested_baud_ = baud;
  return {};
}

Result<std::uint32_t> SerialPort::baud() const {
  if (!fd_) return port_closed(path_);
  return posix::query_baud(fd_.get(), path_);
}

Result<SerialLineSettings> SerialPort::line_settings() const {
  if (!fd_) return port_closed(path_);
  return posix::query_line_settings(fd_.get(), path_);
}

Status SerialPort::drain(int timeout_ms) {
  if (!fd_) return port_closed(path_);
  using std::chrono::steady_clock;
  const steady_clock::time_point deadline = steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  // Poll the queue length instead of calling tcdrain() straight away: tcdrain() has no
  // timeout and would block for as long as the line cannot send.
  for (;;) {
    int queued_bytes = 0;
    if (::ioctl(fd_.get(), TIOCOUTQ, &queued_bytes) != 0) {
      const int err = errno;
      if (err == ENOTTY || err == EINVAL) break;  // no queue count; tcdrain() below still waits
      return posix::errno_error(posix::classify_io_errno(err), err, "%s: TIOCOUTQ", path_.c_str());
    }
    if (queued_bytes <= 0) break;
    if (steady_clock::now() >= deadline) {
      return Error::format(Errc::timeout, "%s: %d bytes still queued after %d ms", path_.c_str(), queued_bytes,
                           timeout_ms);
    }
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  // Queue empty: this only waits for the UART FIFO and shift register.
  while (::tcdrain(fd_.get()) != 0) {
    const int err = errno;
    if (err != EINTR) return posix::errno_error(posix::classify_io_errno(err), err, "%s: tcdrain", path_.c_str());
  }
  return {};
}

Status SerialPort::flush_input() {
  if (!fd_) return port_closed(path_);
  if (::tcflush(fd_.get(), TCIFLUSH) != 0) {
    const int err = errno;
    return posix::errno_error(posix::classify_io_errno(err), err, "%s: tcflush(TCIFLUSH)", path_.c_str());
  }
  return {};
}

Status SerialPort::flush_output() {
  if (!fd_) return port_closed(path_);
  if (::tcflush(fd_.get(), TCOFLUSH) != 0) {
    const int err = errno;
    return posix::errno_error(posix::classify_io_errno(err), err, "%s: tcflush(TCOFLUSH)", path_.c_str());
  }
  return {};
}

Result<std::size_t> SerialPort::input_queue_bytes() const {
  if (!fd_) return port_closed(path_);
  int bytes = 0;
  if (::ioctl(fd_.get(), FIONREAD, &bytes) != 0) {
    const int err = errno;
    return posix::errno_error(posix::classify_io_errno(err), err, "%s: FIONREAD", path_.c_str());
  }
  return static_cast<std::size_t>(bytes < 0 ? 0 : bytes);
}

Result<std::size_t> SerialPort::output_queue_bytes() const {
  if (!fd_) return port_closed(path_);
  int bytes = 0;
  if (::ioctl(fd_.get(), TIOCOUTQ, &bytes) != 0) {
    const int err = errno;
    return posix::errno_error(posix::classify_io_errno(err), err, "%s: TIOCOUTQ", path_.c_str());
  }
  return static_cast<std::size_t>(bytes < 0 ? 0 : bytes);
}

}  // namespace sen3bot::hal
