#pragma once
// An RTSP + RTP proxy of ours on 127.0.0.1 that damages the UDP media on its way to the client:
// it rewrites client_port= in SETUP so the server sends RTP to the proxy, then forwards each
// datagram to the client's real port, dropping, duplicating and swapping some (fixed seed).
#include <atomic>
#include <chrono>
#include <cstdint>
#include <memory>
#include <optional>
#include <random>
#include <string>
#include <thread>
#include <vector>

#include "sen3bot/hal/tcp.hpp"
#include "sen3bot/hal/udp.hpp"

namespace sen3bot::camera::testing {

struct Impairment {
  double drop = 0.03;
  double duplicate = 0.03;
  double swap = 0.05;  // hold a packet and send it after the next one
  std::uint32_t seed = 1;
};

class UdpImpairProxy {
 public:
  UdpImpairProxy(std::uint16_t server_port, Impairment impairment) : server_port_(server_port), impairment_(impairment), rng_(impairment.seed) {
    listener_ = std::move(hal::TcpListener::listen("127.0.0.1", 0).value());
    for (int attempt = 0; attempt < 32 && !rtcp_; ++attempt) {
      auto rtp = hal::UdpSocket::bind("127.0.0.1", 0);
      if (!rtp || (*rtp)->local_port() % 2 != 0) continue;
      auto rtcp = hal::UdpSocket::bind("127.0.0.1", static_cast<std::uint16_t>((*rtp)->local_port() + 1));
      if (!rtcp) continue;
      rtp_ = std::move(*rtp);
      rtcp_ = std::move(*rtcp);
    }
    (void)rtp_->set_receive_buffer(4 * 1024 * 1024);
    thread_ = std::thread([this] { run(); });
  }
  ~UdpImpairProxy() {
    stop_ = true;
    thread_.join();
  }
  [[nodiscard]] std::uint16_t port() const { return listener_->port(); }
  std::atomic<std::uint64_t> dropped{0};
  std::atomic<std::uint64_t> duplicated{0};
  std::atomic<std::uint64_t> swapped{0};
  std::atomic<std::uint64_t> forwarded{0};

 private:
  void pump_tcp() {
    std::uint8_t buf[65536];
    if (auto n = client_->read(buf); n && *n > 0) {
      to_server_.append(reinterpret_cast<const char*>(buf), *n);
      std::size_t end = 0;
      while ((end = to_server_.find("\r\n\r\n")) != std::string::npos) {
        std::string request = to_server_.substr(0, end + 4);
        to_server_.erase(0, end + 4);
        const std::size_t at = request.find("client_port=");
        if (at != std::string::npos) {
          const std::size_t start = at + 12;
          const std::size_t stop = request.find_first_of(";\r", start);
          const std::string ports = request.substr(start, stop - start);
          client_rtp_port_ = static_cast<std::uint16_t>(std::stoi(ports.substr(0, ports.find('-'))));
          const unsigned p = rtp_->local_port();
          request.replace(start, stop - start, std::to_string(p) + "-" + std::to_string(p + 1));
        }
        write_all(*server_, request);
      }
    }
    if (auto n = server_->read(buf); n && *n > 0) {
      write_all(*client_, std::string(reinterpret_cast<const char*>(buf), *n));
    }
  }
  static void write_all(hal::TcpStream& s, const std::string& data) {
    std::size_t sent = 0;
    for (int spins = 0; sent < data.size() && spins < 10000; ++spins) {
      auto w = s.write(std::span(reinterpret_cast<const std::uint8_t*>(data.data()) + sent, data.size() - sent));
      if (!w) return;
      sent += *w;
    }
  }
  void pump_udp() {
    if (client_rtp_port_ == 0) return;
    auto to = hal::resolve_udp_endpoint("127.0.0.1", client_rtp_port_);
    std::vector<std::uint8_t> buf(65536);
    std::uniform_real_distribution<double> u(0.0, 1.0);
    for (int i = 0; i < 512; ++i) {
      auto got = rtp_->recv_from(buf);
      if (!got || !got->has_value()) break;
      const std::span<const std::uint8_t> packet(buf.data(), (*got)->size);
      if (u(rng_) < impairment_.drop) {
        ++dropped;
        continue;
      }
      if (!held_.empty()) {
        (void)rtp_->send_to(packet, *to);
        (void)rtp_->send_to(held_, *to);
        held_.clear();
        forwarded += 2;
        continue;
      }
      if (u(rng_) < impairment_.swap) {
        held_.assign(packet.begin(), packet.end());
        ++swapped;
        continue;
      }
      (void)rtp_->send_to(packet, *to);
      ++forwarded;
      if (u(rng_) < impairment_.duplicate) {
        (void)rtp_->send_to(packet, *to);
        ++duplicated;
      }
    }
    while (true) {  // server RTCP: not needed by the client
      auto got = rtcp_->recv_from(buf);
      if (!got || !got->has_value()) break;
    }
  }
  void run() {
    while (!stop_) {
      if (!client_) {
        if (auto s = listener_->accept(); s && *s) {
          client_ = std::move(*s);
          server_ = std::move(hal::TcpStream::connect("127.0.0.1", server_port_, 2000).value());
        }
      } else {
        pump_tcp();
        pump_udp();
      }
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  }

  std::uint16_t server_port_;
  Impairment impairment_;
  std::mt19937 rng_;
  std::unique_ptr<hal::TcpListener> listener_;
  std::unique_ptr<hal::UdpSocket> rtp_;
  std::unique_ptr<hal::UdpSocket> rtcp_;
  std::unique_ptr<hal::TcpStream> client_;
  std::unique_ptr<hal::TcpStream> server_;
  std::string to_server_;
  std::uint16_t client_rtp_port_ = 0;
  std::vector<std::uint8_t> held_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
};

}  // namespace sen3bot::camera::testing
