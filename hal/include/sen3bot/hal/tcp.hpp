#pragma once
// TCP byte streams: a simulator (MobileSim/AMRISim serve the robot on tcp://host:8101), a
// serial-to-Ethernet bridge, or our own emulators listening for a driver under test.
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

// MobileSim and AMRISim listen for the first robot on this port (ARIA's ArTcpConnection
// default); "tcp://host" without a port means this one.
constexpr std::uint16_t kDefaultRobotTcpPort = 8101;

struct TcpEndpoint {
  std::string host;  // name or address; IPv6 without the URL's brackets
  std::uint16_t port = kDefaultRobotTcpPort;
};

// "tcp://host", "tcp://host:port", "tcp://[v6addr]:port". Anything else (no scheme, empty
// host, port 0, >65535 or not numeric, trailing characters) is Errc::invalid_argument with
// a message saying what is wrong.
Result<TcpEndpoint> parse_tcp_url(std::string_view url);
[[nodiscard]] bool is_tcp_url(std::string_view spec) noexcept;

// A connected stream: non-blocking, TCP_NODELAY (protocol packets are small and latency
// matters more than throughput), keep-alive probes so a silently vanished peer is noticed
// within seconds, and MSG_NOSIGNAL so a closed peer never raises SIGPIPE.
class TcpStream final : public ByteStream {
 public:
  // Resolves host, then a non-blocking connect bounded by timeout_ms in total.
  // Refused -> Errc::io, no answer in time -> Errc::timeout, unknown host -> Errc::not_found.
  static Result<std::unique_ptr<TcpStream>> connect(std::string_view host, std::uint16_t port, int timeout_ms);
  ~TcpStream() override = default;
  TcpStream(const TcpStream&) = delete;
  TcpStream& operator=(const TcpStream&) = delete;

  // 0 bytes = nothing now. EOF, ECONNRESET, EPIPE -> Errc::disconnected. No allocation.
  Result<std::size_t> read(std::span<std::uint8_t> out) override;
  Result<std::size_t> write(std::span<const std::uint8_t> data) override;
  [[nodiscard]] int poll_fd() const override { return fd_.get(); }
  [[nodiscard]] std::string_view name() const override { return name_; }

  // Half-close: the peer reads EOF, we can still read what it sends.
  Status shutdown_write();
  [[nodiscard]] std::uint16_t local_port() const;

 private:
  friend class TcpListener;
  TcpStream(UniqueFd fd, std::string name);

  UniqueFd fd_;
  std::string name_;
};

class TcpListener {
 public:
  // bind_address "" means every local address; port 0 picks a free (ephemeral) port.
  // SO_REUSEADDR, so a restarted emulator can bind while old connections sit in TIME_WAIT.
  static Result<std::unique_ptr<TcpListener>> listen(std::string_view bind_address, std::uint16_t port,
                                                     int backlog = 8);
  TcpListener(const TcpListener&) = delete;
  TcpListener& operator=(const TcpListener&) = delete;

  // Non-blocking: nullptr when no connection is pending. Allocates the accepted stream.
  Result<std::unique_ptr<TcpStream>> accept();

  [[nodiscard]] std::uint16_t port() const { return port_; }  // the bound port, also when 0 was asked
  [[nodiscard]] int poll_fd() const { return fd_.get(); }
  [[nodiscard]] std::string_view name() const { return name_; }

 private:
  TcpListener(UniqueFd fd, std::uint16_t port, std::string name);

  UniqueFd fd_;
  std::uint16_t port_;
  std::string name_;
};

}  // namespace sen3bot::hal
