#include <arpa/inet.h>
#include <net/if.h>
#include <netdb.h>
#include <netinet/in.h>
#include <sys/socket.h>

#include <cerrno>
#include <cstdio>
#include <cstring>

#include "posix_error.hpp"
#include "sen3bot/hal/udp.hpp"

namespace sen3bot::hal {

namespace {

sockaddr_in to_sockaddr(const UdpEndpoint& endpoint) {
  sockaddr_in address{};
  address.sin_family = AF_INET;
  address.sin_port = htons(endpoint.port);
  std::memcpy(&address.sin_addr, endpoint.address.data(), endpoint.address.size());
  return address;
}

UdpEndpoint from_sockaddr(const sockaddr_in& address) {
  UdpEndpoint endpoint;
  std::memcpy(endpoint.address.data(), &address.sin_addr, endpoint.address.size());
  endpoint.port = ntohs(address.sin_port);
  return endpoint;
}

// A numeric IPv4 address, or a failure naming the text.
Result<in_addr> parse_ipv4(std::string_view text, const char* what) {
  char buffer[INET_ADDRSTRLEN] = {};
  in_addr address{};
  if (text.size() >= sizeof buffer) {
    return Error::format(Errc::invalid_argument, "%s: '%.*s' is not an IPv4 address", what,
                         static_cast<int>(text.size()), text.data());
  }
  std::memcpy(buffer, text.data(), text.size());
  if (::inet_pton(AF_INET, buffer, &address) != 1) {
    return Error::format(Errc::invalid_argument, "%s: '%.*s' is not an IPv4 address", what,
                         static_cast<int>(text.size()), text.data());
  }
  return address;
}

}  // namespace

std::array<char, 22> UdpEndpoint::to_chars() const noexcept {
  std::array<char, 22> text{};
  std::snprintf(text.data(), text.size(), "%u.%u.%u.%u:%u", address[0], address[1], address[2], address[3],
                static_cast<unsigned>(port));
  return text;
}

Result<UdpEndpoint> resolve_udp_endpoint(std::string_view host, std::uint16_t port) {
  const std::string host_text(host);
  addrinfo hints{};
  hints.ai_family = AF_INET;
  hints.ai_socktype = SOCK_DGRAM;
  addrinfo* list = nullptr;
  const int rc = ::getaddrinfo(host_text.c_str(), nullptr, &hints, &list);
  if (rc != 0 || list == nullptr) {
    return Error::format(rc == EAI_NONAME ? Errc::not_found : Errc::io, "resolving '%s' (IPv4): %s",
                         host_text.c_str(), rc != 0 ? ::gai_strerror(rc) : "no address");
  }
  sockaddr_in address{};
  std::memcpy(&address, list->ai_addr, sizeof address);
  ::freeaddrinfo(list);
  address.sin_port = htons(port);
  return from_sockaddr(address);
}

UdpSocket::UdpSocket(UniqueFd fd, std::uint16_t port, std::string name)
    : fd_(std::move(fd)), port_(port), name_(std::move(name)) {}

Result<std::unique_ptr<UdpSocket>> UdpSocket::bind(std::string_view address, std::uint16_t port) {
  const std::string label = "udp " + (address.empty() ? std::string("*") : std::string(address)) + ":";
  const std::string what = label + std::to_string(port);
  sockaddr_in local{};
  local.sin_family = AF_INET;
  local.sin_port = htons(port);
  local.sin_addr.s_addr = htonl(INADDR_ANY);
  if (!address.empty()) {
    Result<in_addr> parsed = parse_ipv4(address, what.c_str());
    if (!parsed) return parsed.error();
    local.sin_addr = *parsed;
  }
  UniqueFd fd(::socket(AF_INET, SOCK_DGRAM | SOCK_NONBLOCK | SOCK_CLOEXEC, 0));
  if (!fd) {
    const int err = errno;
    return posix::errno_error(Errc::io, err, "%s: socket", what.c_str());
  }
  const int on = 1;
  ::setsockopt(fd.get(), SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
  if (::bind(fd.get(), reinterpret_cast<const sockaddr*>(&local), sizeof local) != 0) {
    const int err = errno;
    return posix::errno_error(err == EACCES ? Errc::permission : Errc::io, err, "%s: bind", what.c_str());
  }
  sockaddr_in bound{};
  socklen_t length = sizeof bound;
  ::getsockname(fd.get(), reinterpret_cast<sockaddr*>(&bound), &length);
  const std::uint16_t actual_port = ntohs(bound.sin_port);
  return std::unique_ptr<UdpSocket>(new UdpSocket(std::move(fd), actual_port, label + std::to_string(actual_port)));
}

Result<std::size_t> UdpSocket::send_to(std::span<const std::uint8_t> datagram, const UdpEndpoint& destination) {
  const sockaddr_in to = to_sockaddr(destination);
  for (;;) {
    const ssize_t n = ::sendto(fd_.get(), datagram.data(), datagram.size(), MSG_DONTWAIT | MSG_NOSIGNAL,
                               reinterpret_cast<const sockaddr*>(&to), sizeof to);
    if (n >= 0) return static_cast<std::size_t>(n);
    const int err = errno;
    if (err == EINTR) continue;
    if (err == EAGAIN || err == EWOULDBLOCK || err == ENOBUFS) return std::size_t{0};
    const auto text = destination.to_chars();
    return posix::errno_error(err == EACCES ? Errc::permission : Errc::io, err, "%s: sendto %s", name_.c_str(),
                              text.data());
  }
}

Result<std::optional<UdpReceived>> UdpSocket::recv_from(std::span<std::uint8_t> out) {
  for (;;) {
    sockaddr_in from{};
    socklen_t length = sizeof from;
    // MSG_TRUNC makes recvfrom return the datagram's real length, so truncation is visible.
    const ssize_t n = ::recvfrom(fd_.get(), out.data(), out.size(), MSG_DONTWAIT | MSG_TRUNC,
                                 reinterpret_cast<sockaddr*>(&from), &length);
    if (n >= 0) {
      UdpReceived received;
      received.truncated = static_cast<std::size_t>(n) > out.size();
      received.size = received.truncated ? out.size() : static_cast<std::size_t>(n);
      received.sender = from_sockaddr(from);
      return std::optional<UdpReceived>(received);
    }
    const int err = errno;
    if (err == EINTR) continue;
    if (err == EAGAIN || err == EWOULDBLOCK) return std::optional<UdpReceived>();
    return posix::errno_error(Errc::io, err, "%s: recvfrom", name_.c_str());
  }
}

Result<std::size_t> UdpSocket::set_receive_buffer(std::size_t bytes) {
  const int requested = bytes > 0x7fffffff ? 0x7fffffff : static_cast<int>(bytes);
  if (::setsockopt(fd_.get(), SOL_SOCKET, SO_RCVBUF, &requested, sizeof requested) != 0) {
    const int err = errno;
    return posix::errno_error(Errc::io, err, "%s: setsockopt(SO_RCVBUF, %d)", name_.c_str(), requested);
  }
  int granted = 0;
  socklen_t length = sizeof granted;
  if (::getsockopt(fd_.get(), SOL_SOCKET, SO_RCVBUF, &granted, &length) != 0) {
    const int err = errno;
    return posix::errno_error(Errc::io, err, "%s: getsockopt(SO_RCVBUF)", name_.c_str());
  }
  return static_cast<std::size_t>(granted < 0 ? 0 : granted);
}

Status UdpSocket::change_membership(int option, std::string_view group, std::string_view interface) {
  const char* action = option == IP_ADD_MEMBERSHIP ? "join" : "leave";
  Result<in_addr> group_address = parse_ipv4(group, name_.c_str());
  if (!group_address) return group_address.error();
  if (!IN_MULTICAST(ntohl(group_address->s_addr))) {
    return Error::format(Errc::invalid_argument, "%s: %.*s is not a multicast group (224.0.0.0/4)", name_.c_str(),
                         static_cast<int>(group.size()), group.data());
  }
  ip_mreqn request{};
  request.imr_multiaddr = *group_address;
  request.imr_address.s_addr = htonl(INADDR_ANY);
  if (!interface.empty()) {
    if (Result<in_addr> local = parse_ipv4(interface, name_.c_str())) {
      request.imr_address = *local;
    } else {
      const std::string interface_name(interface);
      const unsigned index = ::if_nametoindex(interface_name.c_str());
      if (index == 0) {
        return Error::format(Errc::not_found, "%s: %s multicast %.*s: no interface or local address '%s'",
                             name_.c_str(), action, static_cast<int>(group.size()), group.data(),
                             interface_name.c_str());
      }
      request.imr_ifindex = static_cast<int>(index);
    }
  }
  if (::setsockopt(fd_.get(), IPPROTO_IP, option, &request, sizeof request) != 0) {
    const int err = errno;
    return posix::errno_error(Errc::io, err, "%s: %s multicast %.*s on '%.*s'", name_.c_str(), action,
                              static_cast<int>(group.size()), group.data(), static_cast<int>(interface.size()),
                              interface.data());
  }
  return {};
}

Status UdpSocket::join_multicast(std::string_view group, std::string_view interface) {
  return change_membership(IP_ADD_MEMBERSHIP, group, interface);
}

Status UdpSocket::leave_multicast(std::string_view group, std::string_view interface) {
  return change_membership(IP_DROP_MEMBERSHIP, group, interface);
}

Status UdpSocket::set_multicast_interface(std::string_view interface) {
  ip_mreqn request{};
  if (Result<in_addr> local = parse_ipv4(interface, name_.c_str())) {
    request.imr_address = *local;
  } else {
    const std::string interface_name(interface);
    const unsigned index = ::if_nametoindex(interface_name.c_str());
    if (index == 0) {
      return Error::format(Errc::not_found, "%s: no interface or local address '%s'", name_.c_str(),
                           interface_name.c_str());
    }
    request.imr_ifindex = static_cast<int>(index);
  }
  if (::setsockopt(fd_.get(), IPPROTO_IP, IP_MULTICAST_IF, &request, sizeof request) != 0) {
    const int err = errno;
    return posix::errno_error(Errc::io, err, "%s: IP_MULTICAST_IF", name_.c_str());
  }
  return {};
}

Status UdpSocket::set_multicast_loopback(bool enabled) {
  const unsigned char value = enabled ? 1 : 0;
  if (::setsockopt(fd_.get(), IPPROTO_IP, IP_MULTICAST_LOOP, &value, sizeof value) != 0) {
    const int err = errno;
    return posix::errno_error(Errc::io, err, "%s: IP_MULTICAST_LOOP", name_.c_str());
  }
  return {};
}

Status UdpSocket::set_multicast_ttl(int hops) {
  if (hops < 0 || hops > 255) {
    return Error::format(Errc::invalid_argument, "%s: multicast TTL %d outside 0..255", name_.c_str(), hops);
  }
  const unsigned char value = static_cast<unsigned char>(hops);
  if (::setsockopt(fd_.get(), IPPROTO_IP, IP_MULTICAST_TTL, &value, sizeof value) != 0) {
    const int err = errno;
    return posix::errno_error(Errc::io, err, "%s: IP_MULTICAST_TTL", name_.c_str());
  }
  return {};
}

Status UdpSocket::set_broadcast(bool enabled) {
  const int value = enabled ? 1 : 0;
  if (::setsockopt(fd_.get(), SOL_SOCKET, SO_BROADCAST, &value, sizeof value) != 0) {
    const int err = errno;
    return posix::errno_error(Errc::io, err, "%s: SO_BROADCAST", name_.c_str());
  }
  return {};
}

}  // namespace sen3bot::hal
