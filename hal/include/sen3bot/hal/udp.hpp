#pragma once
// IPv4 UDP sockets: camera discovery (WS-Discovery multicast on 239.255.255.250:3702),
// RTP, and the fleet's datagrams. Addresses are plain values so the receive path never
// allocates.
#include <array>
#include <cstddef>
#include <cstdint>
#include <memory>
#include <optional>
#include <span>
#include <string>
#include <string_view>

#include "sen3bot/hal/fd.hpp"
#include "sen3bot/hal/result.hpp"

namespace sen3bot::hal {

struct UdpEndpoint {
  std::array<std::uint8_t, 4> address{};  // a.b.c.d in that order
  std::uint16_t port = 0;

  friend bool operator==(const UdpEndpoint&, const UdpEndpoint&) = default;
  // "a.b.c.d:port", NUL-terminated, in a fixed buffer.
  [[nodiscard]] std::array<char, 22> to_chars() const noexcept;
};

// A dotted quad, or a host name resolved to its first IPv4 address (resolution blocks and
// allocates: do it at start-up, not in a loop).
Result<UdpEndpoint> resolve_udp_endpoint(std::string_view host, std::uint16_t port);

struct UdpReceived {
  std::size_t size = 0;  // bytes stored in the caller's buffer
  UdpEndpoint sender;
  bool truncated = false;  // the datagram was larger than the buffer; the rest is lost
};

class UdpSocket {
 public:
  // address "" binds every local address; port 0 picks an ephemeral port. Non-blocking,
  // SO_REUSEADDR (several listeners may share a multicast port such as 3702).
  static Result<std::unique_ptr<UdpSocket>> bind(std::string_view address, std::uint16_t port);
  UdpSocket(const UdpSocket&) = delete;
  UdpSocket& operator=(const UdpSocket&) = delete;

  // Returns the bytes sent: all of the datagram, or 0 (with a non-empty datagram) when the
  // socket buffer is full and nothing was sent. No allocation.
  Result<std::size_t> send_to(std::span<const std::uint8_t> datagram, const UdpEndpoint& destination);
  // One datagram, or std::nullopt when none is waiting. No allocation.
  Result<std::optional<UdpReceived>> recv_from(std::span<std::uint8_t> out);

  // Asks for SO_RCVBUF of bytes and returns what the kernel granted (Linux reports double
  // the request, for its bookkeeping, capped by net.core.rmem_max).
  Result<std::size_t> set_receive_buffer(std::size_t bytes);
  // interface: "" (the kernel's choice), a local IPv4 address, or an interface name ("eth0").
  Status join_multicast(std::string_view group, std::string_view interface = "");
  Status leave_multicast(std::string_view group, std::string_view interface = "");
  Status set_multicast_interface(std::string_view interface);  // for outgoing multicast
  Status set_multicast_loopback(bool enabled);
  Status set_multicast_ttl(int hops);
  Status set_broadcast(bool enabled);

  [[nodiscard]] std::uint16_t local_port() const { return port_; }
  [[nodiscard]] int poll_fd() const { return fd_.get(); }
  [[nodiscard]] std::string_view name() const { return name_; }

 private:
  UdpSocket(UniqueFd fd, std::uint16_t port, std::string name);
  Status change_membership(int option, std::string_view group, std::string_view interface);

  UniqueFd fd_;
  std::uint16_t port_;
  std::string name_;
};

}  // namespace sen3bot::hal
