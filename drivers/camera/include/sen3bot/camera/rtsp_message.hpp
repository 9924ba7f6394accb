#pragma once
// RTSP 1.0 messages (RFC 2326 §4-§12) and the interleaved '$' framing (§10.12) that shares
// the TCP connection with them. Pure: views into the caller's buffer, no allocation.
#include <cstddef>
#include <cstdint>
#include <optional>
#include <span>
#include <string_view>

#include "sen3bot/hal/result.hpp"
#include "sen3bot/mem/static_vector.hpp"

namespace sen3bot::camera {

// Bounds on what a peer may send us; anything larger is a protocol error, not a buffer grow.
constexpr std::size_t kMaxRtspHeaderBytes = 16 * 1024;
constexpr std::size_t kMaxRtspBodyBytes = 64 * 1024;  // an SDP is a few hundred bytes
constexpr std::size_t kMaxRtspHeaders = 40;
// §10.12: '$', channel, 16-bit big-endian length.
constexpr std::uint8_t kInterleavedMagic = 0x24;
constexpr std::size_t kInterleavedHeaderBytes = 4;

struct RtspHeader {
  std::string_view name;
  std::string_view value;  // trimmed
};

struct RtspMessage {
  bool is_response = false;
  int status = 0;              // responses
  std::string_view reason;     // responses
  std::string_view method;     // requests sent by the server (§D.1: we must answer them)
  std::string_view uri;        // requests
  mem::StaticVector<RtspHeader, kMaxRtspHeaders> headers;
  std::string_view body;

  // First header with this name, compared case-insensitively (VLC sends "Cseq").
  [[nodiscard]] std::optional<std::string_view> header(std::string_view name) const;
  // CSeq as a number; nullopt when absent or not numeric.
  [[nodiscard]] std::optional<std::uint32_t> cseq() const;
};

enum class DemuxKind : std::uint8_t {
  need_more,    // the buffer holds an incomplete item; read more and call again
  message,      // a response or a server request
  interleaved,  // one '$' frame
  garbage,      // bytes that are neither; skip `consumed` bytes to resynchronise
};

struct DemuxItem {
  DemuxKind kind = DemuxKind::need_more;
  std::size_t consumed = 0;  // bytes of the buffer this item covers
  std::uint8_t channel = 0;  // interleaved
  std::span<const std::uint8_t> payload;  // interleaved
  RtspMessage message;       // message
};

// Looks at the start of buf and says what is there. Errors (oversize header or body,
// malformed status line, bad Content-Length) are Errc::protocol: the connection is unusable.
Result<DemuxItem> demux_next(std::span<const std::uint8_t> buf);

// Parses one complete message (header and body) from the start of text.
// need_more is reported as Errc::would_block.
Result<RtspMessage> parse_message(std::string_view text, std::size_t* consumed);

// --- header values --------------------------------------------------------------------------

struct SessionHeader {
  std::string_view id;
  int timeout_s = 60;  // RFC 2326 §12.37 default when ";timeout=" is absent
};
Result<SessionHeader> parse_session(std::string_view value);

struct TransportReply {
  bool tcp = false;
  int rtp_channel = -1;   // interleaved=a-b
  int rtcp_channel = -1;
  int server_rtp_port = -1;  // server_port=a-b
  int server_rtcp_port = -1;
  std::optional<std::uint32_t> ssrc;  // lenient: hex, "0x" hex, spaces; absent when unparsable
};
Result<TransportReply> parse_transport(std::string_view value);

struct RtpInfo {
  std::optional<std::uint16_t> seq;
  std::optional<std::uint32_t> rtptime;  // absent for "rtptime=-1" and other junk
};
// First entry of "url=..;seq=N;rtptime=T[,url=..]"; never fails, fields are optional.
RtpInfo parse_rtp_info(std::string_view value);

// True when a comma/space separated method list (Public:) contains method.
bool method_listed(std::string_view public_value, std::string_view method);

bool iequals(std::string_view a, std::string_view b);
std::string_view trim(std::string_view s);

}  // namespace sen3bot::camera
