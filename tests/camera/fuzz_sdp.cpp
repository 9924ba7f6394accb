// Fuzz target: the SDP parser, then control resolution of what it found and the reason
// given when it holds no video we decode.
#include <cstddef>
#include <cstdint>
#include <string_view>

#include "sen3bot/camera/rtsp_url.hpp"
#include "sen3bot/camera/sdp.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sen3bot::camera;
  auto sd = parse_sdp(std::string_view(reinterpret_cast<const char*>(data), size));
  if (!sd) return 0;
  if (sd->media.size() > kMaxSdpMedia) __builtin_trap();
  for (const SdpMedia& m : sd->media) (void)resolve_control("rtsp://h/base/", m.control);
  (void)resolve_control("rtsp://h/base", sd->session_control);
  if (sd->first_supported_video() == nullptr && no_supported_video(*sd).message().empty()) __builtin_trap();
  return 0;
}
