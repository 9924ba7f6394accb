#include <netdb.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <cerrno>
#include <charconv>
#include <chrono>
#include <cstdio>

#include "posix_error.hpp"
#include "sen3bot/hal/tcp.hpp"

namespace sen3bot::hal {

namespace {

constexpr std::string_view kTcpScheme = "tcp://";

// Keep-alive timing: a peer that vanished without a FIN or RST (cable pulled, bridge power
// lost) is reported after about idle + count * interval = 5 s instead of hours.
constexpr int kKeepAliveIdle_s = 2;
constexpr int kKeepAliveInterval_s = 1;
constexpr int kKeepAliveProbeCount = 3;

struct AddrInfoDeleter {
  void operator()(addrinfo* list) const { ::freeaddrinfo(list); }
};
using AddrInfoList = std::unique_ptr<addrinfo, AddrInfoDeleter>;

Status set_stream_options(int fd, const char* name) {
  const int on = 1;
  if (::setsockopt(fd, IPPROTO_TCP, TCP_NODELAY, &on, sizeof on) != 0) {
    const int err = errno;
    return posix::errno_error(Errc::io, err, "%s: setsockopt(TCP_NODELAY)", name);
  }
  // Keep-alive is best effort: a platform without the Linux knobs still gets the default.
  ::setsockopt(fd, SOL_SOCKET, SO_KEEPALIVE, &on, sizeof on);
#if defined(TCP_KEEPIDLE) && defined(TCP_KEEPINTVL) && defined(TCP_KEEPCNT)
  ::setsockopt(fd, IPPROTO_TCP, TCP_KEEPIDLE, &kKeepAliveIdle_s, sizeof kKeepAliveIdle_s);
  ::setsockopt(fd, IPPROTO_TCP, TCP_KEEPINTVL, &kKeepAliveInterval_s, sizeof kKeepAliveInterval_s);
  ::setsockopt(fd, IPPROTO_TCP, TCP_KEEPCNT, &kKeepAliveProbeCount, sizeof kKeepAliveProbeCount);
#endif
  return {};
}

std::string format_url(std::string_view host, std::uint16_t port) {
  const bool ipv6 = host.find(':') != std::string_view::npos;
  std::string url(kTcpScheme);
  if (ipv6) url += '[';
  url += host;
  if (ipv6) url += ']';
  url += ':';
  url += std::to_string(port);
  return url;
}

std::string format_peer(const sockaddr_storage& address, socklen_t length) {
  char host[NI_MAXHOST] = {};
  char service[NI_MAXSERV] = {};
  if (::getnameinfo(reinterpret_cast<const sockaddr*>(&address), length, host, sizeof host, service, sizeof service,
                    NI_NUMERICHOST | NI_NUMERICSERV) != 0) {
    return "tcp://(unknown peer)";
  }
  unsigned port = 0;
  std::from_chars(service, service + std::char_traits<char>::length(service), port);
  return format_url(host, static_cast<std::uint16_t>(port));
}

std::uint16_t bound_port(int fd) {
  sockaddr_storage address{};
  socklen_t length = sizeof address;
  if (::getsockname(fd, reinterpret_cast<sockaddr*>(&address), &length) != 0) return 0;
  if (address.ss_family == AF_INET) return ntohs(reinterpret_cast<const sockaddr_in*>(&address)->sin_port);
  if (address.ss_family == AF_INET6) return ntohs(reinterpret_cast<const sockaddr_in6*>(&address)->sin6_port);
  return 0;
}

Result<AddrInfoList> resolve(const std::string& host, std::uint16_t port, int flags, const char* purpose) {
  addrinfo hints{};
  hints.ai_family = AF_UNSPEC;
  hints.ai_socktype = SOCK_STREAM;
  hints.ai_flags = flags | AI_NUMERICSERV;
  const std::string service = std::to_string(port);
  addrinfo* list = nullptr;
  const int rc = ::getaddrinfo(host.empty() ? nullptr : host.c_str(), service.c_str(), &hints, &list);
  if (rc != 0) {
    if (rc == EAI_SYSTEM) {
      const int err = errno;
      return posix::errno_error(Errc::io, err, "%s: resolving '%s'", purpose, host.c_str());
    }
    const Errc code = (rc == EAI_NONAME || rc == EAI_FAIL
#ifdef EAI_NODATA
                       || rc == EAI_NODATA
#endif
                       )
                          ? Errc::not_found
                          : Errc::io;
    return Error::format(code, "%s: resolving '%s': %s", purpose, host.c_str(), ::gai_strerror(rc));
  }
  return AddrInfoList(list);
}

int remaining_ms(std::chrono::steady_clock::time_point deadline) {
  const auto left = std::chrono::duration_cast<std::chrono::milliseconds>(deadline - std::chrono::steady_clock::now());
  return left.count() <= 0 ? 0 : static_cast<int>(left.count());
}

}  // namespace

bool is_tcp_url(std::string_view spec) noexcept {
  // URL schemes are case-insensitive (RFC 3986 section 3.1).
  if (spec.size() < kTcpScheme.size()) return false;
  for (std::size_t i = 0; i < kTcpScheme.size(); ++i) {
    const char c = spec[i];
    const char lower = (c >= 'A' && c <= 'Z') ? static_cast<char>(c - 'A' + 'a') : c;
    if (lower != kTcpScheme[i]) return false;
  }
  return true;
}

Result<TcpEndpoint> parse_tcp_url(std::string_view url) {
  const int url_length = static_cast<int>(url.size());
  if (!is_tcp_url(url)) {
    return Error::format(Errc::invalid_argument, "'%.*s' is not a tcp:// URL (expected tcp://host[:port])", url_length,
                         url.data());
  }
  std::string_view rest = url.substr(kTcpScheme.size());
  std::string_view host;
  std::string_view after_host;
  if (rest.starts_with('[')) {
    const std::size_t close = rest.find(']');
    if (close == std::string_view::npos) {
      return Error::format(Errc::invalid_argument, "'%.*s': '[' without a closing ']'", url_length, url.data());
    }
    host = rest.substr(1, close - 1);
    after_host = rest.substr(close + 1);
  } else {
    const std::size_t colon = rest.find(':');
    if (colon != std::string_view::npos && rest.find(':', colon + 1) != std::string_view::npos) {
      return Error::format(Errc::invalid_argument, "'%.*s': an IPv6 address needs brackets (tcp://[::1]:8101)",
                           url_length, url.data());
    }
    host = rest.substr(0, colon);
    after_host = colon == std::string_view::npos ? std::string_view{} : rest.substr(colon);
  }
  if (host.empty()) return Error::format(Errc::invalid_argument, "'%.*s': missing host", url_length, url.data());
  if (host.find_first_of("/?#@ ") != std::string_view::npos) {
    return Error::format(Errc::invalid_argument, "'%.*s': unexpected character in host '%.*s'", url_length, url.data(),
                         static_cast<int>(host.size()), host.data());
  }
  TcpEndpoint endpoint;
  endpoint.host = std::string(host);
  if (after_host.empty()) return endpoint;  // default port
  if (after_host.front() != ':') {
    return Error::format(Errc::invalid_argument, "'%.*s': unexpected '%.*s' after the host", url_length, url.data(),
                         static_cast<int>(after_host.size()), after_host.data());
  }
  const std::string_view port_text = after_host.substr(1);
  if (port_text.empty()) return Error::format(Errc::invalid_argument, "'%.*s': missing port after ':'", url_length, url.data());
  unsigned long port = 0;
  const auto [end, ec] = std::from_chars(port_text.data(), port_text.data() + port_text.size(), port);
  if (ec == std::errc() && end != port_text.data() + port_text.size()) {
    return Error::format(Errc::invalid_argument, "'%.*s': unexpected '%.*s' after the port", url_length, url.data(),
                         static_cast<int>(port_text.data() + port_text.size() - end), end);
  }
  if (ec != std::errc() || port == 0 || port > 65535) {
    return Error::format(Errc::invalid_argument, "'%.*s': port must be a number from 1 to 65535", url_length,
                         url.data());
  }
  endpoint.port = static_cast<std::uint16_t>(port);
  return endpoint;
}

TcpStream::TcpStream(UniqueFd fd, std::string name) : fd_(std::move(fd)), name_(std::move(name)) {}

Result<std::unique_ptr<TcpStream>> TcpStream::connect(std::string_view host, std::uint16_t port, int timeout_ms) {
  const std::string host_text(host);
  std::string name = format_url(host, port);
  if (port == 0) return Error::format(Errc::invalid_argument, "%s: port 0 cannot be connected to", name.c_str());
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms < 0 ? 0 : timeout_ms);
  Result<AddrInfoList> addresses = resolve(host_text, port, 0, name.c_str());
  if (!addresses) return addresses.error();

  Error last_error(Errc::not_found, "no address to connect to");
  for (const addrinfo* a = addresses->get(); a != nullptr; a = a->ai_next) {
    UniqueFd fd(::socket(a->ai_family, a->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, a->ai_protocol));
    if (!fd) {
      const int err = errno;
      last_error = posix::errno_error(Errc::io, err, "%s: socket", name.c_str());
      continue;
    }
    if (::connect(fd.get(), a->ai_addr, a->ai_addrlen) != 0) {
      int err = errno;
      if (err == EINPROGRESS || err == EINTR) {
        pollfd p{fd.get(), POLLOUT, 0};
        int ready = 0;
        do {
          ready = ::poll(&p, 1, remaining_ms(deadline));
        } while (ready < 0 && errno == EINTR);
        if (ready == 0) {
          return Error::format(Errc::timeout, "%s: connect timed out after %d ms", name.c_str(), timeout_ms);
        }
        socklen_t length = sizeof err;
        if (ready < 0 || ::getsockopt(fd.get(), SOL_SOCKET, SO_ERROR, &err, &length) != 0) err = errno;
      }
      if (err != 0) {
        last_error = posix::errno_error(err == ETIMEDOUT ? Errc::timeout : Errc::io, err, "%s: connect", name.c_str());
        continue;
      }
    }
    if (Status options = set_stream_options(fd.get(), name.c_str()); !options) return options.error();
    return std::unique_ptr<TcpStream>(new TcpStream(std::move(fd), std::move(name)));
  }
  return last_error;
}

Result<std::size_t> TcpStream::read(std::span<std::uint8_t> out) {
  if (out.empty()) return std::size_t{0};
  for (;;) {
    const ssize_t n = ::recv(fd_.get(), out.data(), out.size(), MSG_DONTWAIT);
    if (n > 0) return static_cast<std::size_t>(n);
    if (n == 0) return Error::format(Errc::disconnected, "%s: peer closed the connection", name_.c_str());
    const int err = errno;
    if (err == EINTR) continue;
    if (err == EAGAIN || err == EWOULDBLOCK) return std::size_t{0};
    return posix::errno_error(posix::classify_io_errno(err), err, "%s: recv", name_.c_str());
  }
}

Result<std::size_t> TcpStream::write(std::span<const std::uint8_t> data) {
  if (data.empty()) return std::size_t{0};
  for (;;) {
    const ssize_t n = ::send(fd_.get(), data.data(), data.size(), MSG_DONTWAIT | MSG_NOSIGNAL);
    if (n >= 0) return static_cast<std::size_t>(n);
    const int err = errno;
    if (err == EINTR) continue;
    if (err == EAGAIN || err == EWOULDBLOCK) return std::size_t{0};
    return posix::errno_error(posix::classify_io_errno(err), err, "%s: send", name_.c_str());
  }
}

Status TcpStream::shutdown_write() {
  if (::shutdown(fd_.get(), SHUT_WR) != 0) {
    const int err = errno;
    return posix::errno_error(posix::classify_io_errno(err), err, "%s: shutdown(SHUT_WR)", name_.c_str());
  }
  return {};
}

std::uint16_t TcpStream::local_port() const { return bound_port(fd_.get()); }

TcpListener::TcpListener(UniqueFd fd, std::uint16_t port, std::string name)
    : fd_(std::move(fd)), port_(port), name_(std::move(name)) {}

Result<std::unique_ptr<TcpListener>> TcpListener::listen(std::string_view bind_address, std::uint16_t port,
                                                        int backlog) {
  const std::string host(bind_address);
  const std::string what = "tcp listen on " + (host.empty() ? std::string("*") : host) + ":" + std::to_string(port);
  Result<AddrInfoList> addresses = resolve(host, port, AI_PASSIVE, what.c_str());
  if (!addresses) return addresses.error();

  Error last_error(Errc::not_found, "no address to bind");
  for (const addrinfo* a = addresses->get(); a != nullptr; a = a->ai_next) {
    UniqueFd fd(::socket(a->ai_family, a->ai_socktype | SOCK_NONBLOCK | SOCK_CLOEXEC, a->ai_protocol));
    if (!fd) {
      const int err = errno;
      last_error = posix::errno_error(Errc::io, err, "%s: socket", what.c_str());
      continue;
    }
    const int on = 1;
    ::setsockopt(fd.get(), SOL_SOCKET, SO_REUSEADDR, &on, sizeof on);
    if (::bind(fd.get(), a->ai_addr, a->ai_addrlen) != 0 || ::listen(fd.get(), backlog) != 0) {
      const int err = errno;
      last_error = posix::errno_error(err == EACCES ? Errc::permission : Errc::io, err, "%s: bind/listen", what.c_str());
      continue;
    }
    const std::uint16_t actual_port = bound_port(fd.get());
    std::string name = "tcp listen on " + (host.empty() ? std::string("*") : host) + ":" + std::to_string(actual_port);
    return std::unique_ptr<TcpListener>(new TcpListener(std::move(fd), actual_port, std::move(name)));
  }
  return last_error;
}

Result<std::unique_ptr<TcpStream>> TcpListener::accept() {
  for (;;) {
    sockaddr_storage peer{};
    socklen_t length = sizeof peer;
    UniqueFd fd(::accept4(fd_.get(), reinterpret_cast<sockaddr*>(&peer), &length, SOCK_NONBLOCK | SOCK_CLOEXEC));
    if (!fd) {
      const int err = errno;
      if (err == EINTR) continue;
      // ECONNABORTED: a client gave up while queued; there is nothing to hand out now.
      if (err == EAGAIN || err == EWOULDBLOCK || err == ECONNABORTED) return std::unique_ptr<TcpStream>();
      return posix::errno_error(Errc::io, err, "%s: accept", name_.c_str());
    }
    std::string peer_name = format_peer(peer, length);
    if (Status options = set_stream_options(fd.get(), peer_name.c_str()); !options) return options.error();
    return std::unique_ptr<TcpStream>(new TcpStream(std::move(fd), std::move(peer_name)));
  }
}

}  // namespace sen3bot::hal
