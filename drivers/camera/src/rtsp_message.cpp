#include "sen3bot/camera/rtsp_message.hpp"

#include <cctype>
#include <charconv>
#include <cstring>

namespace sen3bot::camera {
namespace {

constexpr std::string_view kVersion = "RTSP/1.0";

bool parse_uint(std::string_view text, std::uint64_t& out, int base = 10) {
  if (text.empty()) return false;
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), out, base);
  return ec == std::errc() && end == text.data() + text.size();
}

// A method token: upper-case letters and '_' (GET_PARAMETER), then a space.
bool looks_like_request(std::string_view text, bool& need_more) {
  need_more = false;
  std::size_t i = 0;
  while (i < text.size() && i < 32) {
    const char c = text[i];
    if (c == ' ') return i > 0;
    if (!((c >= 'A' && c <= 'Z') || c == '_')) return false;
    ++i;
  }
  need_more = i == text.size() && i < 32;
  return false;
}

std::size_t find_header_end(std::string_view text) {
  const std::size_t crlf = text.find("\r\n\r\n");
  const std::size_t lf = text.find("\n\n");
  if (crlf == std::string_view::npos && lf == std::string_view::npos) return std::string_view::npos;
  if (crlf == std::string_view::npos) return lf + 2;
  if (lf == std::string_view::npos) return crlf + 4;
  return crlf < lf ? crlf + 4 : lf + 2;
}

}  // namespace

bool iequals(std::string_view a, std::string_view b) {
  if (a.size() != b.size()) return false;
  for (std::size_t i = 0; i < a.size(); ++i) {
    if (std::tolower(static_cast<unsigned char>(a[i])) != std::tolower(static_cast<unsigned char>(b[i]))) return false;
  }
  return true;
}

std::string_view trim(std::string_view s) {
  while (!s.empty() && (s.front() == ' ' || s.front() == '\t' || s.front() == '\r' || s.front() == '\n')) s.remove_prefix(1);
  while (!s.empty() && (s.back() == ' ' || s.back() == '\t' || s.back() == '\r' || s.back() == '\n')) s.remove_suffix(1);
  return s;
}

std::optional<std::string_view> RtspMessage::header(std::string_view name) const {
  for (const RtspHeader& h : headers) {
    if (iequals(h.name, name)) return h.value;
  }
  return std::nullopt;
}

std::optional<std::uint32_t> RtspMessage::cseq() const {
  const auto value = header("CSeq");
  std::uint64_t n = 0;
  if (!value || !parse_uint(trim(*value), n) || n > 0xFFFFFFFFu) return std::nullopt;
  return static_cast<std::uint32_t>(n);
}

Result<RtspMessage> parse_message(std::string_view text, std::size_t* consumed) {
  const std::size_t header_end = find_header_end(text.substr(0, kMaxRtspHeaderBytes + 4));
  if (header_end == std::string_view::npos) {
    if (text.size() > kMaxRtspHeaderBytes) return Error(Errc::protocol, "RTSP header exceeds 16 KiB");
    return Error(Errc::would_block, "incomplete RTSP header");
  }
  RtspMessage msg;
  std::string_view head = text.substr(0, header_end);
  const std::size_t first_eol = head.find('\n');
  std::string_view start_line = trim(head.substr(0, first_eol));
  head = head.substr(first_eol + 1);
  if (start_line.starts_with(kVersion)) {
    msg.is_response = true;
    std::string_view rest = start_line.substr(kVersion.size());
    if (rest.size() < 4 || rest[0] != ' ') return Error(Errc::protocol, "malformed RTSP status line");
    std::uint64_t status = 0;
    if (!parse_uint(rest.substr(1, 3), status) || status < 100 || status > 999) {
      return Error(Errc::protocol, "malformed RTSP status code");
    }
    msg.status = static_cast<int>(status);
    msg.reason = trim(rest.substr(4));
  } else {
    const std::size_t sp1 = start_line.find(' ');
    const std::size_t sp2 = start_line.rfind(' ');
    if (sp1 == std::string_view::npos || sp2 == sp1 || start_line.substr(sp2 + 1) != kVersion) {
      return Error(Errc::protocol, "malformed RTSP start line");
    }
    msg.method = start_line.substr(0, sp1);
    msg.uri = trim(start_line.substr(sp1 + 1, sp2 - sp1 - 1));
  }
  while (!head.empty()) {
    const std::size_t eol = head.find('\n');
    std::string_view line = head.substr(0, eol);
    head = eol == std::string_view::npos ? std::string_view() : head.substr(eol + 1);
    if (!line.empty() && line.back() == '\r') line.remove_suffix(1);
    if (line.empty()) break;
    if ((line.front() == ' ' || line.front() == '\t') && !msg.headers.empty()) continue;  // obsolete folding: ignored
    const std::size_t colon = line.find(':');
    if (colon == std::string_view::npos || colon == 0) return Error(Errc::protocol, "RTSP header line without a name");
    if (!msg.headers.push_back(RtspHeader{trim(line.substr(0, colon)), trim(line.substr(colon + 1))})) {
      return Error(Errc::protocol, "too many RTSP header lines");
    }
  }
  std::size_t body_bytes = 0;
  if (const auto length = msg.header("Content-Length")) {
    std::uint64_t n = 0;
    if (!parse_uint(trim(*length), n)) return Error(Errc::protocol, "malformed Content-Length");
    if (n > kMaxRtspBodyBytes) return Error::format(Errc::protocol, "Content-Length %llu exceeds the 64 KiB limit", static_cast<unsigned long long>(n));
    body_bytes = static_cast<std::size_t>(n);
  }
  if (text.size() < header_end + body_bytes) return Error(Errc::would_block, "incomplete RTSP body");
  msg.body = text.substr(header_end, body_bytes);
  *consumed = header_end + body_bytes;
  return msg;
}

Result<DemuxItem> demux_next(std::span<const std::uint8_t> buf) {
  DemuxItem item;
  if (buf.empty()) return item;
  if (buf[0] == kInterleavedMagic) {
    if (buf.size() < kInterleavedHeaderBytes) return item;
    const std::size_t length = (std::size_t{buf[2]} << 8) | buf[3];
    if (buf.size() < kInterleavedHeaderBytes + length) return item;
    item.kind = DemuxKind::interleaved;
    item.channel = buf[1];
    item.payload = buf.subspan(kInterleavedHeaderBytes, length);
    item.consumed = kInterleavedHeaderBytes + length;
    return item;
  }
  const std::string_view text(reinterpret_cast<const char*>(buf.data()), buf.size());
  bool need_more = false;
  const bool is_response = text.starts_with(kVersion);
  const bool response_prefix = text.size() < kVersion.size() && kVersion.starts_with(text);
  const bool is_request = !is_response && looks_like_request(text, need_more);
  if (response_prefix || need_more) return item;
  if (is_response || is_request) {
    std::size_t consumed = 0;
    auto msg = parse_message(text, &consumed);
    if (!msg) {
      if (msg.error().code() == Errc::would_block) return item;
      return msg.error();
    }
    item.kind = DemuxKind::message;
    item.consumed = consumed;
    item.message = *msg;
    return item;
  }
  // Resynchronise: skip to the next '$' or 'R' that may start an item (§1.4 of the brief:
  // live555 cameras corrupt the framing when their send buffer fills).
  std::size_t skip = 1;
  while (skip < buf.size() && buf[skip] != kInterleavedMagic && buf[skip] != 'R') ++skip;
  item.kind = DemuxKind::garbage;
  item.consumed = skip;
  return item;
}

Result<SessionHeader> parse_session(std::string_view value) {
  SessionHeader out;
  value = trim(value);
  const std::size_t semi = value.find(';');
  out.id = trim(value.substr(0, semi));
  if (out.id.empty()) return Error(Errc::protocol, "empty Session id");
  std::string_view params = semi == std::string_view::npos ? std::string_view() : value.substr(semi + 1);
  while (!params.empty()) {
    const std::size_t next = params.find(';');
    const std::string_view param = trim(params.substr(0, next));
    params = next == std::string_view::npos ? std::string_view() : params.substr(next + 1);
    if (param.size() > 8 && iequals(param.substr(0, 8), "timeout=")) {
      std::uint64_t n = 0;
      if (parse_uint(trim(param.substr(8)), n) && n > 0 && n < 86400) out.timeout_s = static_cast<int>(n);
    }
  }
  return out;
}

namespace {

bool parse_pair(std::string_view text, int& a, int& b) {
  const std::size_t dash = text.find('-');
  std::uint64_t x = 0;
  std::uint64_t y = 0;
  if (!parse_uint(trim(text.substr(0, dash)), x) || x > 65535) return false;
  if (dash == std::string_view::npos) {
    y = x + 1;
  } else if (!parse_uint(trim(text.substr(dash + 1)), y) || y > 65535) {
    return false;
  }
  a = static_cast<int>(x);
  b = static_cast<int>(y);
  return true;
}

std::optional<std::uint32_t> parse_ssrc(std::string_view text) {
  text = trim(text);
  if (text.size() > 2 && (text.substr(0, 2) == "0x" || text.substr(0, 2) == "0X")) text.remove_prefix(2);
  std::uint64_t n = 0;
  // Cameras send hex (the RFC), but some send decimal; hex parses both digit sets, and a
  // value over 32 bits in hex is treated as decimal.
  if (parse_uint(text, n, 16) && n <= 0xFFFFFFFFu) return static_cast<std::uint32_t>(n);
  if (parse_uint(text, n, 10) && n <= 0xFFFFFFFFu) return static_cast<std::uint32_t>(n);
  return std::nullopt;
}

}  // namespace

Result<TransportReply> parse_transport(std::string_view value) {
  TransportReply out;
  value = trim(value);
  const std::size_t comma = value.find(',');  // the server picks one; take the first
  value = value.substr(0, comma);
  const std::size_t semi = value.find(';');
  const std::string_view spec = trim(value.substr(0, semi));
  if (iequals(spec, "RTP/AVP/TCP")) {
    out.tcp = true;
  } else if (!iequals(spec, "RTP/AVP") && !iequals(spec, "RTP/AVP/UDP")) {
    return Error(Errc::protocol, "Transport is not RTP/AVP");
  }
  std::string_view params = semi == std::string_view::npos ? std::string_view() : value.substr(semi + 1);
  while (!params.empty()) {
    const std::size_t next = params.find(';');
    const std::string_view param = trim(params.substr(0, next));
    params = next == std::string_view::npos ? std::string_view() : params.substr(next + 1);
    const std::size_t eq = param.find('=');
    const std::string_view key = trim(param.substr(0, eq));
    const std::string_view val = eq == std::string_view::npos ? std::string_view() : trim(param.substr(eq + 1));
    if (iequals(key, "interleaved")) {
      if (!parse_pair(val, out.rtp_channel, out.rtcp_channel) || out.rtp_channel > 255 || out.rtcp_channel > 255) {
        return Error(Errc::protocol, "bad interleaved= in Transport");
      }
    } else if (iequals(key, "server_port")) {
      if (!parse_pair(val, out.server_rtp_port, out.server_rtcp_port)) return Error(Errc::protocol, "bad server_port= in Transport");
    } else if (iequals(key, "ssrc")) {
      out.ssrc = parse_ssrc(val);
    }
  }
  if (out.tcp && out.rtp_channel < 0) return Error(Errc::protocol, "TCP Transport without interleaved=");
  return out;
}

RtpInfo parse_rtp_info(std::string_view value) {
  RtpInfo out;
  const std::size_t comma = value.find(',');
  std::string_view params = value.substr(0, comma);
  while (!params.empty()) {
    const std::size_t next = params.find(';');
    const std::string_view param = trim(params.substr(0, next));
    params = next == std::string_view::npos ? std::string_view() : params.substr(next + 1);
    const std::size_t eq = param.find('=');
    if (eq == std::string_view::npos) continue;
    const std::string_view key = trim(param.substr(0, eq));
    const std::string_view val = trim(param.substr(eq + 1));
    std::uint64_t n = 0;
    if (iequals(key, "seq") && parse_uint(val, n) && n <= 0xFFFF) out.seq = static_cast<std::uint16_t>(n);
    if (iequals(key, "rtptime") && parse_uint(val, n) && n <= 0xFFFFFFFFu) out.rtptime = static_cast<std::uint32_t>(n);
  }
  return out;
}

bool method_listed(std::string_view public_value, std::string_view method) {
  while (!public_value.empty()) {
    const std::size_t next = public_value.find_first_of(", ");
    if (iequals(trim(public_value.substr(0, next)), method)) return true;
    if (next == std::string_view::npos) break;
    public_value.remove_prefix(next + 1);
  }
  return false;
}

}  // namespace sen3bot::camera
