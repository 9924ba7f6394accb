#pragma once
// One JSON object per packet, for `sen3bot decode p2os` and the replay test. Not for
// real-time code (builds strings).
#include <cstdint>
#include <string>

#include "sen3bot/p2os/codec.hpp"

namespace sen3bot::p2os {

enum class PacketDirection : std::uint8_t {
  from_robot,  // server packets: echoes, SYNC2 reply, SIP, CONFIGpac, ENCODERpac
  to_robot,    // client commands
};

// {"t_s":..,"dir":"rx"|"tx","type":"SIP",...fields...}; no trailing newline.
std::string describe_packet_json(double t_s, PacketDirection direction, const Frame& frame);

}  // namespace sen3bot::p2os
