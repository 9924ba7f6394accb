// Fuzz target: the RTSP/interleaved demultiplexer and the header-value parsers the client
// applies to every response (Session, Transport, RTP-Info, WWW-Authenticate, Public).
#include <cstddef>
#include <cstdint>
#include <span>
#include <string_view>

#include "sen3bot/camera/auth.hpp"
#include "sen3bot/camera/rtsp_message.hpp"
#include "sen3bot/camera/rtsp_url.hpp"

extern "C" int LLVMFuzzerTestOneInput(const std::uint8_t* data, std::size_t size) {
  using namespace sen3bot::camera;
  std::span<const std::uint8_t> buf(data, size);
  while (!buf.empty()) {
    auto item = demux_next(buf);
    if (!item || item->kind == DemuxKind::need_more) break;
    if (item->consumed == 0 || item->consumed > buf.size()) __builtin_trap();
    if (item->kind == DemuxKind::message) {
      const RtspMessage& m = item->message;
      (void)m.cseq();
      for (const RtspHeader& h : m.headers) {
        if (iequals(h.name, "Session")) (void)parse_session(h.value);
        if (iequals(h.name, "Transport")) (void)parse_transport(h.value);
        if (iequals(h.name, "RTP-Info")) (void)parse_rtp_info(h.value);
        if (iequals(h.name, "WWW-Authenticate")) (void)parse_challenge(h.value);
        if (iequals(h.name, "Public")) (void)method_listed(h.value, "GET_PARAMETER");
        if (iequals(h.name, "Content-Base")) (void)resolve_control(choose_base_url(h.value, "", "rtsp://h/x"), "t=1");
      }
    }
    buf = buf.subspan(item->consumed);
  }
  return 0;
}
