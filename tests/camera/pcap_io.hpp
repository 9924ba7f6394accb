#pragma once
// Minimal libpcap-format writer and reader for one RTSP-over-TCP conversation, so a recorded
// session is readable by tshark/Wireshark (Ethernet + IPv4 + TCP, the server on port 554 so
// the RTSP dissector picks it up) and replayable by our tests without extra libraries.
#include <array>
#include <cstdint>
#include <cstring>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace sen3bot::camera::testing {

constexpr std::uint16_t kPcapRtspPort = 554;
constexpr std::uint16_t kPcapClientPort = 40000;

struct PcapSegment {
  bool from_server = false;
  std::int64_t time_us = 0;
  std::vector<std::uint8_t> payload;
};

class PcapWriter {
 public:
  explicit PcapWriter(const std::string& path) : out_(path, std::ios::binary) {
    const std::uint32_t header[6] = {0xa1b2c3d4, 0x00040002, 0, 0, 65535, 1};  // v2.4, Ethernet
    out_.write(reinterpret_cast<const char*>(header), sizeof header);
  }
  void add(const PcapSegment& s) {
    for (std::size_t off = 0; off < s.payload.size(); off += kMss) {
      const std::size_t n = std::min(kMss, s.payload.size() - off);
      write_packet(s, s.payload.data() + off, n);
    }
  }
  [[nodiscard]] bool ok() const { return static_cast<bool>(out_); }

 private:
  static constexpr std::size_t kMss = 1400;
  static void put16(std::uint8_t* p, std::uint32_t v) {
    p[0] = static_cast<std::uint8_t>(v >> 8);
    p[1] = static_cast<std::uint8_t>(v);
  }
  static void put32(std::uint8_t* p, std::uint32_t v) {
    put16(p, v >> 16);
    put16(p + 2, v & 0xFFFF);
  }
  void write_packet(const PcapSegment& s, const std::uint8_t* data, std::size_t n) {
    std::vector<std::uint8_t> frame(14 + 20 + 20 + n, 0);
    std::uint8_t* eth = frame.data();
    eth[5] = s.from_server ? 1 : 2;  // locally administered dummy MACs
    eth[11] = s.from_server ? 2 : 1;
    eth[0] = eth[6] = 0x02;
    put16(eth + 12, 0x0800);
    std::uint8_t* ip = eth + 14;
    ip[0] = 0x45;
    put16(ip + 2, static_cast<std::uint32_t>(20 + 20 + n));
    ip[8] = 64;
    ip[9] = 6;  // TCP
    const std::array<std::uint8_t, 4> server = {10, 0, 0, 2};
    const std::array<std::uint8_t, 4> client = {10, 0, 0, 1};
    std::memcpy(ip + 12, (s.from_server ? server : client).data(), 4);
    std::memcpy(ip + 16, (s.from_server ? client : server).data(), 4);
    std::uint32_t sum = 0;
    for (int i = 0; i < 20; i += 2) sum += (ip[i] << 8) | ip[i + 1];
    while (sum >> 16) sum = (sum & 0xFFFF) + (sum >> 16);
    put16(ip + 10, ~sum & 0xFFFF);
    std::uint8_t* tcp = ip + 20;
    put16(tcp, s.from_server ? kPcapRtspPort : kPcapClientPort);
    put16(tcp + 2, s.from_server ? kPcapClientPort : kPcapRtspPort);
    std::uint32_t& seq = s.from_server ? server_seq_ : client_seq_;
    put32(tcp + 4, seq);
    put32(tcp + 8, s.from_server ? client_seq_ : server_seq_);
    seq += static_cast<std::uint32_t>(n);
    tcp[12] = 0x50;
    tcp[13] = 0x18;  // PSH, ACK
    put16(tcp + 14, 65535);
    std::memcpy(tcp + 20, data, n);
    const std::uint32_t record[4] = {static_cast<std::uint32_t>(s.time_us / 1000000), static_cast<std::uint32_t>(s.time_us % 1000000),
                                     static_cast<std::uint32_t>(frame.size()), static_cast<std::uint32_t>(frame.size())};
    out_.write(reinterpret_cast<const char*>(record), sizeof record);
    out_.write(reinterpret_cast<const char*>(frame.data()), static_cast<std::streamsize>(frame.size()));
  }
  std::ofstream out_;
  std::uint32_t server_seq_ = 1000;
  std::uint32_t client_seq_ = 5000;
};

// The TCP payload bytes sent by the server (source port 554), in capture order.
inline bool read_pcap_server_stream(const std::string& path, std::vector<std::uint8_t>& out) {
  std::ifstream in(path, std::ios::binary);
  const std::vector<std::uint8_t> file((std::istreambuf_iterator<char>(in)), std::istreambuf_iterator<char>());
  if (file.size() < 24) return false;
  std::uint32_t magic = 0;
  std::memcpy(&magic, file.data(), 4);
  if (magic != 0xa1b2c3d4) return false;
  std::size_t pos = 24;
  while (pos + 16 <= file.size()) {
    std::uint32_t incl = 0;
    std::memcpy(&incl, file.data() + pos + 8, 4);
    pos += 16;
    if (pos + incl > file.size() || incl < 54) return false;
    const std::uint8_t* f = file.data() + pos;
    const std::size_t ihl = (f[14] & 0x0F) * 4u;
    const std::uint8_t* tcp = f + 14 + ihl;
    const std::size_t thl = (tcp[12] >> 4) * 4u;
    const std::uint16_t src_port = static_cast<std::uint16_t>((tcp[0] << 8) | tcp[1]);
    const std::size_t header = 14 + ihl + thl;
    if (src_port == kPcapRtspPort && incl > header) out.insert(out.end(), f + header, f + incl);
    pos += incl;
  }
  return true;
}

}  // namespace sen3bot::camera::testing
