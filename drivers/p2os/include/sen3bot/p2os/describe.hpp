#pragma once
// One JSON object per packet, for `sen3bot decode p2os` and the replay test. Not for
// real-time code (builds strings).
#include <cstdint>
#include <functional>
#include <string>
#include <string_view>

#include "sen3bot/capture/reader.hpp"
#include "sen3bot/hal/result.hpp"

#include "sen3bot/p2os/codec.hpp"

namespace sen3bot::p2os {

enum class PacketDirection : std::uint8_t {
  from_robot,  // server packets: echoes, SYNC2 reply, SIP, CONFIGpac, ENCODERpac
  to_robot,    // client commands
};

// {"t_s":..,"dir":"rx"|"tx","type":"SIP",...fields...}; no trailing newline.
std::string describe_packet_json(double t_s, PacketDirection direction, const Frame& frame);

// Decodes one channel of a wire capture (rx = from the robot, tx = to it) into JSON lines,
// in record order, each stamped with the time of the record that completed the packet.
// `channel_name` empty: the channel named "p2os", else the only channel. A trailing line
// reports what the parsers dropped:
//   {"summary":true,"rx_packets":..,"tx_packets":..,"rx_bad_checksums":..,...}
Status decode_capture(const capture::CaptureFile& capture, std::string_view channel_name,
                      const std::function<void(const std::string& line)>& emit);

}  // namespace sen3bot::p2os
