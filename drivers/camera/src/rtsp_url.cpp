#include "sen3bot/camera/rtsp_url.hpp"

#include <cctype>
#include <charconv>

namespace sen3bot::camera {
namespace {

bool iequals_prefix(std::string_view text, std::string_view prefix) {
  if (text.size() < prefix.size()) return false;
  for (std::size_t i = 0; i < prefix.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(text[i])) != prefix[i]) return false;
  }
  return true;
}

int hex_value(char c) {
  if (c >= '0' && c <= '9') return c - '0';
  if (c >= 'a' && c <= 'f') return c - 'a' + 10;
  if (c >= 'A' && c <= 'F') return c - 'A' + 10;
  return -1;
}

std::string percent_decode(std::string_view in) {
  std::string out;
  out.reserve(in.size());
  for (std::size_t i = 0; i < in.size(); ++i) {
    if (in[i] == '%' && i + 2 < in.size()) {
      const int hi = hex_value(in[i + 1]);
      const int lo = hex_value(in[i + 2]);
      if (hi >= 0 && lo >= 0) {
        out.push_back(static_cast<char>(hi * 16 + lo));
        i += 2;
        continue;
      }
    }
    out.push_back(in[i]);
  }
  return out;
}

bool valid_host_char(char c) {
  return std::isalnum(static_cast<unsigned char>(c)) != 0 || c == '.' || c == '-' || c == '_' || c == ':';
}

}  // namespace

std::string RtspUrl::request_uri() const {
  std::string out = "rtsp://";
  if (host.find(':') != std::string::npos) {
    out += '[';
    out += host;
    out += ']';
  } else {
    out += host;
  }
  if (port != kDefaultRtspPort) {
    out += ':';
    out += std::to_string(port);
  }
  out += path;
  return out;
}

Result<RtspUrl> parse_rtsp_url(std::string_view url) {
  constexpr std::string_view kScheme = "rtsp://";
  if (!iequals_prefix(url, kScheme)) return Error(Errc::invalid_argument, "URL does not start with rtsp://");
  std::string_view rest = url.substr(kScheme.size());
  const std::size_t slash = rest.find('/');
  std::string_view authority = rest.substr(0, slash);
  std::string_view path = slash == std::string_view::npos ? std::string_view("/") : rest.substr(slash);
  RtspUrl out;
  if (const std::size_t at = authority.rfind('@'); at != std::string_view::npos) {
    const std::string_view userinfo = authority.substr(0, at);
    const std::size_t colon = userinfo.find(':');
    out.user = percent_decode(userinfo.substr(0, colon));
    if (colon != std::string_view::npos) out.password = percent_decode(userinfo.substr(colon + 1));
    authority = authority.substr(at + 1);
  }
  std::string_view host = authority;
  std::string_view port_text;
  if (!authority.empty() && authority.front() == '[') {
    const std::size_t close = authority.find(']');
    if (close == std::string_view::npos) return Error(Errc::invalid_argument, "unterminated IPv6 host");
    host = authority.substr(1, close - 1);
    const std::string_view after = authority.substr(close + 1);
    if (!after.empty()) {
      if (after.front() != ':') return Error(Errc::invalid_argument, "junk after IPv6 host");
      port_text = after.substr(1);
      if (port_text.empty()) return Error(Errc::invalid_argument, "empty port");
    }
  } else if (const std::size_t colon = authority.find(':'); colon != std::string_view::npos) {
    host = authority.substr(0, colon);
    port_text = authority.substr(colon + 1);
    if (port_text.empty()) return Error(Errc::invalid_argument, "empty port");
  }
  if (host.empty()) return Error(Errc::invalid_argument, "empty host");
  for (char c : host) {
    if (!valid_host_char(c)) return Error(Errc::invalid_argument, "invalid character in host");
  }
  if (!port_text.empty()) {
    unsigned value = 0;
    const auto [end, ec] = std::from_chars(port_text.data(), port_text.data() + port_text.size(), value);
    if (ec != std::errc() || end != port_text.data() + port_text.size() || value == 0 || value > 65535) {
      return Error(Errc::invalid_argument, "invalid port");
    }
    out.port = static_cast<std::uint16_t>(value);
  }
  out.host = std::string(host);
  out.path = std::string(path);
  return out;
}

std::string strip_userinfo(std::string_view url) {
  constexpr std::string_view kSep = "://";
  const std::size_t scheme_end = url.find(kSep);
  if (scheme_end == std::string_view::npos) return std::string(url);
  const std::size_t auth_start = scheme_end + kSep.size();
  const std::size_t auth_end = url.find('/', auth_start);
  const std::string_view authority = url.substr(auth_start, auth_end == std::string_view::npos ? std::string_view::npos : auth_end - auth_start);
  const std::size_t at = authority.rfind('@');
  if (at == std::string_view::npos) return std::string(url);
  std::string out(url.substr(0, auth_start));
  out += url.substr(auth_start + at + 1);
  return out;
}

std::string choose_base_url(std::string_view content_base, std::string_view content_location,
                            std::string_view request_url) {
  for (std::string_view candidate : {content_base, content_location}) {
    if (!candidate.empty() && parse_rtsp_url(candidate).ok()) return strip_userinfo(candidate);
  }
  return strip_userinfo(request_url);
}

std::string resolve_control(std::string_view base, std::string_view control) {
  if (control.empty() || control == "*") return std::string(base);
  if (iequals_prefix(control, "rtsp://") || iequals_prefix(control, "rtsps://")) return strip_userinfo(control);
  std::string out(base);
  if (out.empty() || out.back() != '/') out += '/';
  out += control;
  return out;
}

std::string rewrite_host(std::string_view url, std::string_view host, std::uint16_t port) {
  constexpr std::string_view kSep = "://";
  const std::size_t scheme_end = url.find(kSep);
  if (scheme_end == std::string_view::npos) return std::string(url);
  const std::size_t auth_start = scheme_end + kSep.size();
  const std::size_t auth_end = url.find('/', auth_start);
  std::string out(url.substr(0, auth_start));
  const std::string_view authority = url.substr(auth_start, auth_end == std::string_view::npos ? std::string_view::npos : auth_end - auth_start);
  if (const std::size_t at = authority.rfind('@'); at != std::string_view::npos) out += authority.substr(0, at + 1);
  if (host.find(':') != std::string_view::npos) {
    out += '[';
    out += host;
    out += ']';
  } else {
    out += host;
  }
  out += ':';
  out += std::to_string(port);
  if (auth_end != std::string_view::npos) out += url.substr(auth_end);
  return out;
}

}  // namespace sen3bot::camera
