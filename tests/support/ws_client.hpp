#pragma once
// A minimal WebSocket client over a plain socket, for the live view's tests and benchmark: the
// HTTP upgrade, masked client frames, and a frame reader that takes whatever the server sends.
// Its read loop allocates nothing, so it can run beside a zero-allocation proof.
#include <arpa/inet.h>
#include <netinet/in.h>
#include <netinet/tcp.h>
#include <poll.h>
#include <sys/socket.h>
#include <unistd.h>

#include <array>
#include <atomic>
#include <cstdint>
#include <cstring>
#include <random>
#include <string>
#include <string_view>
#include <vector>

namespace sen3bot::testing {

class WsClient {
 public:
  struct Frame {
    int opcode = -1;  // 1 text, 2 binary, 8 close; -1: nothing (timeout or closed)
    std::string_view payload;  // valid until the next read
  };

  WsClient() = default;
  ~WsClient() { close(); }
  WsClient(const WsClient&) = delete;
  WsClient& operator=(const WsClient&) = delete;

  // Connects and sends the upgrade; returns the server's status line and headers (empty on a
  // connection failure). `extra` is appended to the request's headers.
  std::string connect(const std::string& host, int port, std::string_view path = "/",
                      std::string_view protocol = "foxglove.websocket.v1", std::string_view extra = "") {
    fd_ = ::socket(host.find(':') != std::string::npos ? AF_INET6 : AF_INET, SOCK_STREAM, 0);
    if (fd_ < 0) return {};
    int rc = -1;
    if (host.find(':') != std::string::npos) {
      sockaddr_in6 a{};
      a.sin6_family = AF_INET6;
      a.sin6_port = htons(static_cast<std::uint16_t>(port));
      inet_pton(AF_INET6, host.c_str(), &a.sin6_addr);
      rc = ::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a);
    } else {
      sockaddr_in a{};
      a.sin_family = AF_INET;
      a.sin_port = htons(static_cast<std::uint16_t>(port));
      inet_pton(AF_INET, host.c_str(), &a.sin_addr);
      rc = ::connect(fd_, reinterpret_cast<sockaddr*>(&a), sizeof a);
    }
    if (rc != 0) {
      close();
      return {};
    }
    std::string request = "GET " + std::string(path) + " HTTP/1.1\r\nHost: " + host + "\r\nUpgrade: websocket\r\n" +
                          "Connection: Upgrade\r\nSec-WebSocket-Key: dGhlIHNhbXBsZSBub25jZQ==\r\n" +
                          "Sec-WebSocket-Version: 13\r\n";
    if (!protocol.empty()) request += "Sec-WebSocket-Protocol: " + std::string(protocol) + "\r\n";
    request += std::string(extra) + "\r\n";
    send_all(request.data(), request.size());
    std::string head;
    while (head.find("\r\n\r\n") == std::string::npos) {
      if (!fill(2000)) break;
      head.append(buffer_.data() + begin_, end_ - begin_);
      begin_ = end_;
    }
    const std::size_t cut = head.find("\r\n\r\n");
    if (cut != std::string::npos) {
      // What came after the headers is the first frames.
      const std::string rest = head.substr(cut + 4);
      std::memcpy(buffer_.data(), rest.data(), rest.size());
      begin_ = 0;
      end_ = rest.size();
      head.resize(cut);
    }
    return head;
  }

  // A plain HTTP GET: the status code and the body.
  static std::pair<int, std::string> http_get(const std::string& host, int port, const std::string& path,
                                              const std::string& extra = "") {
    WsClient c;
    c.fd_ = ::socket(AF_INET, SOCK_STREAM, 0);
    sockaddr_in a{};
    a.sin_family = AF_INET;
    a.sin_port = htons(static_cast<std::uint16_t>(port));
    inet_pton(AF_INET, host.c_str(), &a.sin_addr);
    if (::connect(c.fd_, reinterpret_cast<sockaddr*>(&a), sizeof a) != 0) return {0, {}};
    const std::string request = "GET " + path + " HTTP/1.1\r\nHost: " + host + "\r\nConnection: close\r\n" + extra + "\r\n";
    c.send_all(request.data(), request.size());
    std::string all;
    while (c.fill(3000)) {
      all.append(c.buffer_.data() + c.begin_, c.end_ - c.begin_);
      c.begin_ = c.end_;
    }
    int status = 0;
    if (all.size() > 12) status = std::atoi(all.c_str() + 9);
    const std::size_t cut = all.find("\r\n\r\n");
    return {status, cut == std::string::npos ? std::string() : all.substr(cut + 4)};
  }

  void send_text(std::string_view text) { send_frame(0x1, text); }
  void send_binary(std::string_view data) { send_frame(0x2, data); }
  // A frame exactly as given (for malformed ones).
  void send_raw(std::string_view bytes) { send_all(bytes.data(), bytes.size()); }

  void send_frame(int opcode, std::string_view data, bool fin = true) {
    std::vector<char> frame;
    frame.push_back(static_cast<char>((fin ? 0x80 : 0) | opcode));
    const std::size_t n = data.size();
    if (n < 126) {
      frame.push_back(static_cast<char>(0x80 | n));
    } else if (n < 65536) {
      frame.push_back(static_cast<char>(0x80 | 126));
      frame.push_back(static_cast<char>(n >> 8));
      frame.push_back(static_cast<char>(n & 0xff));
    } else {
      frame.push_back(static_cast<char>(0x80 | 127));
      for (int i = 7; i >= 0; --i) frame.push_back(static_cast<char>((static_cast<std::uint64_t>(n) >> (8 * i)) & 0xff));
    }
    const char mask[4] = {0x12, 0x34, 0x56, 0x78};
    frame.insert(frame.end(), mask, mask + 4);
    for (std::size_t i = 0; i < n; ++i) frame.push_back(static_cast<char>(data[i] ^ mask[i % 4]));
    send_all(frame.data(), frame.size());
  }

  // The next whole frame, waiting up to timeout_ms for it.
  Frame read(int timeout_ms = 2000) {
    for (;;) {
      const std::size_t have = end_ - begin_;
      const auto* b = reinterpret_cast<const unsigned char*>(buffer_.data() + begin_);
      if (have >= 2) {
        std::size_t n = b[1] & 0x7f, off = 2;
        if (n == 126 && have >= 4) {
          n = (static_cast<std::size_t>(b[2]) << 8) | b[3];
          off = 4;
        } else if (n == 127 && have >= 10) {
          n = 0;
          for (int i = 0; i < 8; ++i) n = (n << 8) | b[2 + i];
          off = 10;
        } else if (n >= 126) {
          n = SIZE_MAX;
        }
        if (n != SIZE_MAX && n + off > buffer_.size()) return {};  // larger than the reader takes
        if (n != SIZE_MAX && have >= off + n) {
          Frame f{b[0] & 0x0f, std::string_view(buffer_.data() + begin_ + off, n)};
          begin_ += off + n;
          return f;
        }
      }
      if (begin_ > 0) {  // keep the partial frame at the front
        std::memmove(buffer_.data(), buffer_.data() + begin_, end_ - begin_);
        end_ -= begin_;
        begin_ = 0;
      }
      if (!fill(timeout_ms)) return {};
    }
  }

  [[nodiscard]] bool connected() const { return fd_ >= 0; }
  // The server closed the connection (a read saw its end).
  [[nodiscard]] bool peer_closed() const { return peer_closed_; }
  void close() {
    if (fd_ >= 0) ::close(fd_);
    fd_ = -1;
  }
  // Shrinks the kernel's receive buffer, so a client that stops reading stalls the sender soon.
  void small_receive_buffer() {
    int size = 4096;
    setsockopt(fd_, SOL_SOCKET, SO_RCVBUF, &size, sizeof size);
  }

 private:
  bool fill(int timeout_ms) {
    if (fd_ < 0) return false;
    pollfd p{fd_, POLLIN, 0};
    if (::poll(&p, 1, timeout_ms) <= 0) return false;
    if (end_ == buffer_.size()) return false;
    const ssize_t n = ::recv(fd_, buffer_.data() + end_, buffer_.size() - end_, 0);
    if (n <= 0) {
      peer_closed_ = true;
      return false;
    }
    end_ += static_cast<std::size_t>(n);
    return true;
  }
  void send_all(const char* data, std::size_t size) {
    while (size > 0 && fd_ >= 0) {
      const ssize_t n = ::send(fd_, data, size, MSG_NOSIGNAL);
      if (n <= 0) return;
      data += n;
      size -= static_cast<std::size_t>(n);
    }
  }

  int fd_ = -1;
  bool peer_closed_ = false;
  std::array<char, 1 << 20> buffer_{};
  std::size_t begin_ = 0;
  std::size_t end_ = 0;
};

}  // namespace sen3bot::testing
