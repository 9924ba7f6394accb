#include "sen3bot/camera/sdp.hpp"

#include <algorithm>
#include <charconv>
#include <cstdlib>

#include "sen3bot/camera/auth.hpp"
#include "sen3bot/camera/rtsp_message.hpp"

namespace sen3bot::camera {
namespace {

constexpr std::size_t kMaxSdpLines = 512;

bool parse_int(std::string_view text, int& out) {
  text = trim(text);
  const auto [end, ec] = std::from_chars(text.data(), text.data() + text.size(), out);
  return ec == std::errc() && end == text.data() + text.size();
}

// "a=fmtp:96 k=v;k=v" parameters; spaces after ';' vary by packetizer.
void apply_fmtp(SdpMedia& m, std::string_view params) {
  while (!params.empty()) {
    const std::size_t next = params.find(';');
    const std::string_view param = trim(params.substr(0, next));
    params = next == std::string_view::npos ? std::string_view() : params.substr(next + 1);
    const std::size_t eq = param.find('=');
    if (eq == std::string_view::npos) continue;
    const std::string_view key = trim(param.substr(0, eq));
    const std::string_view val = trim(param.substr(eq + 1));
    if (iequals(key, "packetization-mode")) {
      int mode = 0;
      if (parse_int(val, mode)) m.packetization_mode = mode;
    } else if (iequals(key, "sprop-parameter-sets")) {
      m.parameter_sets.clear();
      std::string_view sets = val;
      while (!sets.empty()) {
        const std::size_t comma = sets.find(',');
        const std::string_view one = trim(sets.substr(0, comma));
        sets = comma == std::string_view::npos ? std::string_view() : sets.substr(comma + 1);
        auto decoded = base64_decode(one);
        // Bad sprop happens in the field; in-band parameter sets then take over.
        if (decoded && !decoded->empty() && decoded->size() <= kMaxParameterSetBytes && m.parameter_sets.size() < 8) {
          m.parameter_sets.push_back(std::move(*decoded));
        }
      }
    }
  }
}

VideoCodec codec_of(std::string_view encoding) {
  if (iequals(encoding, "H264")) return VideoCodec::h264;
  if (iequals(encoding, "JPEG")) return VideoCodec::jpeg;
  return VideoCodec::unknown;
}

}  // namespace

const char* to_string(VideoCodec codec) {
  switch (codec) {
    case VideoCodec::h264: return "h264";
    case VideoCodec::jpeg: return "mjpeg";
    case VideoCodec::unknown: break;
  }
  return "unknown";
}

const SdpMedia* SessionDescription::first_supported_video() const {
  for (const SdpMedia& m : media) {
    if (m.media == "video" && m.codec != VideoCodec::unknown) return &m;
  }
  return nullptr;
}

namespace {

// "H265/90000" from the rtpmap, else "payload type 96 without rtpmap".
std::string format_of(const SdpMedia& m) {
  if (m.encoding.empty()) return "payload type " + std::to_string(m.payload_type) + " without rtpmap";
  std::string out = m.encoding;
  if (m.clock_rate_hz > 0) out += "/" + std::to_string(m.clock_rate_hz);
  return out;
}

}  // namespace

Error no_supported_video(const SessionDescription& sd) {
  std::vector<std::string> names;  // each video codec once: "H265", "MP4V-ES"
  std::string formats;             // "rtpmap H265/90000"
  std::string others;              // non-video media, for the no-video case
  for (const SdpMedia& m : sd.media) {
    if (m.media == "video") {
      std::string name = m.encoding.empty() ? "unknown" : m.encoding;
      if (std::find(names.begin(), names.end(), name) == names.end()) names.push_back(std::move(name));
      formats += (formats.empty() ? "" : "; ") + std::string(m.encoding.empty() ? "" : "rtpmap ") + format_of(m);
    } else {
      others += (others.empty() ? "" : ", ") + m.media + (m.encoding.empty() ? "" : " " + format_of(m));
    }
  }
  std::string codecs;
  for (const std::string& name : names) codecs += (codecs.empty() ? "" : ", ") + name;
  if (!codecs.empty()) {
    return Error::format(Errc::not_supported, "the camera offers only %s video (%s); supported: H264, JPEG",
                         codecs.c_str(), formats.c_str());
  }
  if (others.empty()) return Error(Errc::not_supported, "the SDP has no media at all (no m= line)");
  return Error::format(Errc::not_supported, "the SDP has no video track (media: %s)", others.c_str());
}

Result<SessionDescription> parse_sdp(std::string_view text) {
  if (text.size() > kMaxSdpBytes) return Error(Errc::protocol, "SDP exceeds 64 KiB");
  std::string_view rest = text;
  while (!rest.empty() && (rest.front() == '\r' || rest.front() == '\n' || rest.front() == ' ')) rest.remove_prefix(1);
  if (!rest.starts_with("v=")) return Error(Errc::protocol, "SDP does not start with v=");
  SessionDescription sd;
  std::size_t lines = 0;
  while (!rest.empty()) {
    if (++lines > kMaxSdpLines) return Error(Errc::protocol, "SDP has too many lines");
    const std::size_t eol = rest.find('\n');
    std::string_view line = rest.substr(0, eol);
    rest = eol == std::string_view::npos ? std::string_view() : rest.substr(eol + 1);
    line = trim(line);
    if (line.size() < 2 || line[1] != '=') continue;
    const char type = line[0];
    const std::string_view value = line.substr(2);
    if (type == 'm') {
      if (sd.media.size() >= kMaxSdpMedia) return Error(Errc::protocol, "SDP has too many media");
      SdpMedia m;
      // m=<media> <port> <proto> <fmt> ...
      std::string_view fields = value;
      std::string_view parts[4];
      for (auto& part : parts) {
        fields = trim(fields);
        const std::size_t sp = fields.find(' ');
        part = fields.substr(0, sp);
        fields = sp == std::string_view::npos ? std::string_view() : fields.substr(sp + 1);
      }
      if (parts[0].empty() || parts[3].empty()) return Error(Errc::protocol, "malformed m= line");
      m.media = std::string(parts[0]);
      if (!parse_int(parts[3], m.payload_type) || m.payload_type < 0 || m.payload_type > 127) {
        m.payload_type = -1;
      }
      if (m.payload_type == kStaticJpegPayloadType) {
        m.encoding = "JPEG";
        m.clock_rate_hz = kVideoClockHz;
        m.codec = VideoCodec::jpeg;
      }
      sd.media.push_back(std::move(m));
      continue;
    }
    if (type != 'a') continue;
    const std::size_t colon = value.find(':');
    const std::string_view name = value.substr(0, colon);
    const std::string_view attr = colon == std::string_view::npos ? std::string_view() : trim(value.substr(colon + 1));
    if (sd.media.empty()) {
      if (name == "control") sd.session_control = std::string(attr);
      continue;
    }
    SdpMedia& m = sd.media.back();
    if (name == "control") {
      m.control = std::string(attr);
    } else if (name == "rtpmap" || name == "fmtp") {
      const std::size_t sp = attr.find(' ');
      int pt = -1;
      if (sp == std::string_view::npos || !parse_int(attr.substr(0, sp), pt) || pt != m.payload_type) continue;
      const std::string_view rhs = trim(attr.substr(sp + 1));
      if (name == "rtpmap") {
        const std::size_t slash = rhs.find('/');
        m.encoding = std::string(rhs.substr(0, slash));
        int rate = 0;
        if (slash != std::string_view::npos) {
          std::string_view rate_text = rhs.substr(slash + 1);
          rate_text = rate_text.substr(0, rate_text.find('/'));
          if (parse_int(rate_text, rate) && rate > 0) m.clock_rate_hz = static_cast<std::uint32_t>(rate);
        }
        m.codec = m.media == "video" ? codec_of(m.encoding) : VideoCodec::unknown;
      } else {
        apply_fmtp(m, rhs);
      }
    } else if (name == "x-dimensions") {
      const std::size_t comma = attr.find(',');
      int w = 0;
      int h = 0;
      if (comma != std::string_view::npos && parse_int(attr.substr(0, comma), w) && parse_int(attr.substr(comma + 1), h) &&
          w > 0 && h > 0 && w <= 16384 && h <= 16384) {
        m.width_px = w;
        m.height_px = h;
      }
    } else if (name == "framerate") {
      const std::string s(attr.substr(0, 32));
      char* end = nullptr;
      const double fps = std::strtod(s.c_str(), &end);
      if (end != s.c_str() && fps > 0 && fps < 1000) m.framerate_hz = fps;
    }
  }
  return sd;
}

}  // namespace sen3bot::camera
