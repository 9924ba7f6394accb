#pragma once
// Session descriptions (RFC 4566) as RTSP cameras send them in DESCRIBE replies, reduced to
// what a video client needs. Pure; allocates (runs once per connection, never per frame).
#include <cstdint>
#include <string>
#include <string_view>
#include <vector>

#include "sen3bot/hal/result.hpp"

namespace sen3bot::camera {

constexpr std::size_t kMaxSdpBytes = 64 * 1024;
constexpr std::size_t kMaxSdpMedia = 16;
constexpr std::size_t kMaxParameterSetBytes = 1024;
// RFC 3551 table 5: static payload type 26 is JPEG/90000 and needs no rtpmap.
constexpr int kStaticJpegPayloadType = 26;
constexpr std::uint32_t kVideoClockHz = 90'000;

enum class VideoCodec : std::uint8_t { unknown, h264, jpeg };
const char* to_string(VideoCodec codec);

struct SdpMedia {
  std::string media;        // "video", "audio", "application"
  int payload_type = -1;    // the first format on the m= line
  std::string encoding;     // from rtpmap ("H264", "JPEG"), or implied by a static type
  std::uint32_t clock_rate_hz = 0;
  std::string control;      // a=control, unresolved
  VideoCodec codec = VideoCodec::unknown;
  int packetization_mode = 0;  // H.264 fmtp
  std::vector<std::vector<std::uint8_t>> parameter_sets;  // decoded sprop-parameter-sets (raw NALs)
  int width_px = 0;         // a=x-dimensions, 0 when absent
  int height_px = 0;
  double framerate_hz = 0;
};

struct SessionDescription {
  std::string session_control;  // session-level a=control (aggregate URL), may be empty
  std::vector<SdpMedia> media;

  // The first video medium we can depacketize (H.264 or JPEG), or nullptr.
  [[nodiscard]] const SdpMedia* first_supported_video() const;
};

// Why first_supported_video() found nothing, naming what the camera offers: "the camera offers
// only H265 video (rtpmap H265/90000); supported: H264, JPEG" or "the SDP has no video track
// (media: audio PCMA/8000)". Errc::not_supported.
Error no_supported_video(const SessionDescription& sd);

// Lenient about what varies between cameras (attribute order, spaces after ';', missing
// rtpmap for static types, unknown lines); strict about size and structure (must begin
// with v=, bounded line count and media count). Bad base64 in sprop is ignored, never fatal.
Result<SessionDescription> parse_sdp(std::string_view text);

}  // namespace sen3bot::camera
