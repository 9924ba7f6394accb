#pragma once
// RTSP URLs and SDP control-URL resolution (RFC 2326 Appendix C.1.1). Pure functions.
#include <cstdint>
#include <string>
#include <string_view>

#include "sen3bot/hal/result.hpp"

namespace sen3bot::camera {

// RFC 2326 §3.2: the default port of the rtsp scheme.
constexpr std::uint16_t kDefaultRtspPort = 554;

struct RtspUrl {
  std::string user;      // percent-decoded userinfo, empty when absent
  std::string password;
  std::string host;      // IPv6 without brackets
  std::uint16_t port = kDefaultRtspPort;
  std::string path;      // starts with '/', includes any query; "/" when the URL has none

  // "rtsp://host[:port]/path" with no userinfo: credentials never go on the wire in a URI.
  [[nodiscard]] std::string request_uri() const;
};

// Strict enough to reject the broken Content-Base values seen from real cameras
// ("rtsp://rtsp://h/", "192.168.1.10:554/x" without a scheme). Errc::invalid_argument.
Result<RtspUrl> parse_rtsp_url(std::string_view url);

// The URL with any "user:pass@" removed; unchanged when it does not parse.
std::string strip_userinfo(std::string_view url);

// Base for relative controls: Content-Base, then Content-Location, then the request URL.
// A header value that does not parse as an rtsp:// URL is ignored.
std::string choose_base_url(std::string_view content_base, std::string_view content_location,
                            std::string_view request_url);

// An absolute control is used as is; "*" or empty is the base itself; a relative control is
// appended to the base with one '/' between (what FFmpeg does, which cameras expect;
// strict RFC 3986 resolution would drop the base's last path segment).
std::string resolve_control(std::string_view base, std::string_view control);

// Replaces scheme-relative host and port of url with the configured camera's, keeping
// path and query. A device may report a private or loopback address it cannot be reached on.
std::string rewrite_host(std::string_view url, std::string_view host, std::uint16_t port);

}  // namespace sen3bot::camera
