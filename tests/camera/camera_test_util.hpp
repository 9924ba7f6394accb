#pragma once
// Helpers shared by the camera tests: fixture files and RTP packet builders.
#include <cstdint>
#include <fstream>
#include <iterator>
#include <string>
#include <vector>

namespace sen3bot::camera::testing {

inline std::string read_fixture(const std::string& relative) {
  std::ifstream in(std::string(SEN3BOT_SOURCE_DIR) + "/tests/data/camera/" + relative, std::ios::binary);
  return std::string(std::istreambuf_iterator<char>(in), std::istreambuf_iterator<char>());
}

inline std::vector<std::uint8_t> rtp_packet(std::uint16_t seq, std::uint32_t ts, bool marker, std::uint8_t pt,
                                            const std::vector<std::uint8_t>& payload, std::uint32_t ssrc = 0x1234) {
  std::vector<std::uint8_t> p = {0x80,
                                 static_cast<std::uint8_t>((marker ? 0x80 : 0) | pt),
                                 static_cast<std::uint8_t>(seq >> 8),
                                 static_cast<std::uint8_t>(seq),
                                 static_cast<std::uint8_t>(ts >> 24),
                                 static_cast<std::uint8_t>(ts >> 16),
                                 static_cast<std::uint8_t>(ts >> 8),
                                 static_cast<std::uint8_t>(ts),
                                 static_cast<std::uint8_t>(ssrc >> 24),
                                 static_cast<std::uint8_t>(ssrc >> 16),
                                 static_cast<std::uint8_t>(ssrc >> 8),
                                 static_cast<std::uint8_t>(ssrc)};
  p.insert(p.end(), payload.begin(), payload.end());
  return p;
}

}  // namespace sen3bot::camera::testing
