#include <fcntl.h>
#include <linux/gpio.h>
#include <sys/ioctl.h>
#include <unistd.h>

#include <charconv>
#include <cstring>
#include <string>

#include "posix_error.hpp"
#include "sen3bot/hal/board.hpp"
#include "sen3bot/hal/fd.hpp"
#include "sen3bot/hal/serial.hpp"
#include "sen3bot/hal/udp.hpp"

namespace sen3bot::hal {

// One line of a GPIO character device (the kernel's v2 uAPI), requested as input or output.
class PosixBoard::GpioLine final : public DigitalInput, public DigitalOutput {
 public:
  // `spec` is "/dev/gpiochipN:LINE".
  static Result<std::unique_ptr<GpioLine>> open(std::string_view spec, bool output, const char* consumer) {
    const std::size_t colon = spec.rfind(':');
    unsigned line = 0;
    // No colon: the line is empty (computing data() + npos + 1 would be undefined).
    const char* last = spec.data() + spec.size();
    const char* first = colon == std::string_view::npos ? last : spec.data() + colon + 1;
    if (colon == std::string_view::npos || colon == 0 || first == last ||
        std::from_chars(first, last, line).ptr != last)
      return Error::format(Errc::config, "gpio: '%.*s': expected /dev/gpiochipN:LINE", static_cast<int>(spec.size()),
                           spec.data());
    const std::string chip(spec.substr(0, colon));
    UniqueFd chip_fd(::open(chip.c_str(), O_RDWR | O_CLOEXEC));
    if (!chip_fd.valid())
      return posix::errno_error(posix::classify_open_errno(errno), errno, "gpio: open %s", chip.c_str());
    gpio_v2_line_request request{};
    request.offsets[0] = line;
    request.num_lines = 1;
    std::strncpy(request.consumer, consumer, sizeof request.consumer - 1);
    request.config.flags = output ? GPIO_V2_LINE_FLAG_OUTPUT : GPIO_V2_LINE_FLAG_INPUT;
    if (::ioctl(chip_fd.get(), GPIO_V2_GET_LINE_IOCTL, &request) != 0)
      return posix::errno_error(Errc::io, errno, "gpio: request line %u of %s", line, chip.c_str());
    return std::unique_ptr<GpioLine>(new GpioLine(UniqueFd(request.fd)));
  }

  Result<bool> read() override {
    gpio_v2_line_values values{};
    values.mask = 1;
    if (::ioctl(fd_.get(), GPIO_V2_LINE_GET_VALUES_IOCTL, &values) != 0)
      return posix::errno_error(Errc::io, errno, "gpio: read");
    return (values.bits & 1) != 0;
  }

  Status write(bool on) override {
    gpio_v2_line_values values{};
    values.mask = 1;
    values.bits = on ? 1 : 0;
    if (::ioctl(fd_.get(), GPIO_V2_LINE_SET_VALUES_IOCTL, &values) != 0)
      return posix::errno_error(Errc::io, errno, "gpio: write");
    return Status::success();
  }

 private:
  explicit GpioLine(UniqueFd fd) : fd_(std::move(fd)) {}
  UniqueFd fd_;
};

PosixBoard::PosixBoard() = default;
PosixBoard::PosixBoard(const Lines& lines) : lines_(lines) {}
PosixBoard::~PosixBoard() = default;

Status PosixBoard::open_lines() {
  if (!lines_.estop_input.empty()) {
    Result<std::unique_ptr<GpioLine>> line = GpioLine::open(lines_.estop_input, false, "sen3bot-estop");
    if (!line) return Error::format(line.error().code(), "board: estop input: %s", line.error().c_str());
    estop_ = std::move(*line);
  }
  if (!lines_.light_output.empty()) {
    Result<std::unique_ptr<GpioLine>> line = GpioLine::open(lines_.light_output, true, "sen3bot-light");
    if (!line) return Error::format(line.error().code(), "board: light output: %s", line.error().c_str());
    light_ = std::move(*line);
  }
  return Status::success();
}

Result<Link> PosixBoard::open_link(std::string_view link, const LinkRequest& request) {
  Result<std::unique_ptr<ByteStream>> stream = open_byte_stream(request.port, request.baud, request.connect_timeout_ms);
  if (!stream)
    return Error::format(stream.error().code(), "%.*s link: %s", static_cast<int>(link.size()), link.data(),
                         stream.error().c_str());
  Link opened;
  opened.stream = std::move(*stream);
  if (auto* serial = dynamic_cast<SerialPort*>(opened.stream.get())) {
    opened.baud_control = serial;
    opened.baud = request.baud;
  }
  return opened;
}

Result<std::unique_ptr<DatagramPort>> Board::open_datagram(std::string_view name, std::string_view address) {
  return Error::format(Errc::not_supported, "%.*s: this board has no datagram channel '%.*s'", static_cast<int>(name.size()),
                       name.data(), static_cast<int>(address.size()), address.data());
}

Result<std::unique_ptr<CanBus>> Board::open_can(std::string_view name, std::string_view interface) {
  return Error::format(Errc::not_supported, "%.*s: this board has no CAN bus '%.*s'", static_cast<int>(name.size()),
                       name.data(), static_cast<int>(interface.size()), interface.data());
}

Result<std::unique_ptr<CanBus>> PosixBoard::open_can(std::string_view name, std::string_view interface) {
  Result<std::unique_ptr<SocketCanBus>> bus = SocketCanBus::open(interface);
  if (!bus)
    return Error::format(bus.error().code(), "%.*s: %s", static_cast<int>(name.size()), name.data(), bus.error().c_str());
  return std::unique_ptr<CanBus>(std::move(*bus));
}

Result<std::unique_ptr<PubSub>> Board::open_pubsub(std::string_view name, const PubSubOptions& options) {
  return Error::format(Errc::not_supported, "%.*s: this board has no publish/subscribe link to '%s'", static_cast<int>(name.size()),
                       name.data(), options.url.c_str());
}

Result<std::unique_ptr<PubSub>> PosixBoard::open_pubsub(std::string_view name, const PubSubOptions& options) {
  Result<std::unique_ptr<PubSub>> client = open_mqtt(options);
  if (!client)
    return Error::format(client.error().code(), "%.*s: %s", static_cast<int>(name.size()), name.data(), client.error().c_str());
  return client;
}

namespace {

// A bound UDP socket as a DatagramPort.
class UdpDatagramPort final : public DatagramPort {
 public:
  explicit UdpDatagramPort(std::unique_ptr<UdpSocket> socket) : socket_(std::move(socket)) {}
  Result<std::optional<std::size_t>> receive(std::span<std::uint8_t> out) override {
    Result<std::optional<UdpReceived>> r = socket_->recv_from(out);
    if (!r) return r.error();
    if (!r->has_value()) return std::optional<std::size_t>{};
    if ((*r)->truncated) return Error(Errc::protocol, "a datagram larger than the receive buffer was dropped");
    return std::optional<std::size_t>{(*r)->size};
  }

 private:
  std::unique_ptr<UdpSocket> socket_;
};

}  // namespace

Result<std::unique_ptr<DatagramPort>> PosixBoard::open_datagram(std::string_view name, std::string_view address) {
  const auto fail = [&](const char* problem) {
    return Error::format(Errc::config, "%.*s: '%.*s': %s", static_cast<int>(name.size()), name.data(),
                         static_cast<int>(address.size()), address.data(), problem);
  };
  constexpr std::string_view kScheme = "udp://";
  if (!address.starts_with(kScheme)) return fail("expected udp://ADDRESS:PORT");
  const std::string_view rest = address.substr(kScheme.size());
  const std::size_t colon = rest.rfind(':');
  if (colon == std::string_view::npos) return fail("expected udp://ADDRESS:PORT");
  unsigned port = 0;
  const std::string_view digits = rest.substr(colon + 1);
  if (digits.empty() || digits.size() > 5) return fail("the port must be 1..65535");
  for (const char c : digits) {
    if (c < '0' || c > '9') return fail("the port must be 1..65535");
    port = port * 10 + static_cast<unsigned>(c - '0');
  }
  if (port == 0 || port > 65535) return fail("the port must be 1..65535");
  const std::string_view host = rest.substr(0, colon);
  Result<std::unique_ptr<UdpSocket>> socket = UdpSocket::bind(host == "0.0.0.0" ? "" : host, static_cast<std::uint16_t>(port));
  if (!socket)
    return Error::format(socket.error().code(), "%.*s: %s", static_cast<int>(name.size()), name.data(), socket.error().c_str());
  return std::unique_ptr<DatagramPort>(std::make_unique<UdpDatagramPort>(std::move(*socket)));
}

DigitalInput* PosixBoard::input(std::string_view name) noexcept { return name == "estop" ? estop_.get() : nullptr; }
DigitalOutput* PosixBoard::output(std::string_view name) noexcept { return name == "light" ? light_.get() : nullptr; }

}  // namespace sen3bot::hal
