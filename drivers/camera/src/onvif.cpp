#include "sen3bot/camera/onvif.hpp"

#include <openssl/evp.h>
#include <pugixml.hpp>

#include <algorithm>
#include <cctype>
#include <cstdio>
#include <cstdlib>
#include <ctime>

#include "sen3bot/camera/auth.hpp"

namespace sen3bot::camera::onvif {
namespace {

std::string_view local_name(const char* name) {
  std::string_view n(name);
  const std::size_t colon = n.find(':');
  return colon == std::string_view::npos ? n : n.substr(colon + 1);
}

// First descendant (depth-first) with this local name.
pugi::xml_node find(pugi::xml_node root, std::string_view name) {
  for (pugi::xml_node child : root.children()) {
    if (child.type() != pugi::node_element) continue;
    if (local_name(child.name()) == name) return child;
    if (pugi::xml_node found = find(child, name)) return found;
  }
  return {};
}

void find_all(pugi::xml_node root, std::string_view name, std::vector<pugi::xml_node>& out) {
  for (pugi::xml_node child : root.children()) {
    if (child.type() != pugi::node_element) continue;
    if (local_name(child.name()) == name) out.push_back(child);
    find_all(child, name, out);
  }
}

std::string text_of(pugi::xml_node node) {
  std::string s = node.child_value();
  const auto begin = s.find_first_not_of(" \t\r\n");
  if (begin == std::string::npos) return {};
  const auto end = s.find_last_not_of(" \t\r\n");
  return s.substr(begin, end - begin + 1);
}

Result<pugi::xml_document*> load(std::string_view xml, pugi::xml_document& doc) {
  if (xml.size() > kMaxSoapBytes) return Error(Errc::protocol, "SOAP reply exceeds 512 KiB");
  // parse_default does not process DOCTYPE or entities beyond the five predefined ones.
  const pugi::xml_parse_result r = doc.load_buffer(xml.data(), xml.size(), pugi::parse_default, pugi::encoding_utf8);
  if (!r) return Error::format(Errc::protocol, "malformed XML: %s at offset %td", r.description(), r.offset);
  return &doc;
}

std::string escape(std::string_view s) {
  std::string out;
  for (char c : s) {
    switch (c) {
      case '&': out += "&amp;"; break;
      case '<': out += "&lt;"; break;
      case '>': out += "&gt;"; break;
      case '"': out += "&quot;"; break;
      default: out += c;
    }
  }
  return out;
}

std::string number(double v) {
  char buf[32];
  std::snprintf(buf, sizeof buf, "%.3f", v);
  return buf;
}

int to_int(const std::string& s) { return static_cast<int>(std::strtol(s.c_str(), nullptr, 10)); }

}  // namespace

std::string password_digest(std::span<const std::uint8_t> nonce, std::string_view created, std::string_view password) {
  EVP_MD_CTX* ctx = EVP_MD_CTX_new();
  unsigned char digest[EVP_MAX_MD_SIZE];
  unsigned int length = 0;
  EVP_DigestInit_ex(ctx, EVP_sha1(), nullptr);
  EVP_DigestUpdate(ctx, nonce.data(), nonce.size());
  EVP_DigestUpdate(ctx, created.data(), created.size());
  EVP_DigestUpdate(ctx, password.data(), password.size());
  EVP_DigestFinal_ex(ctx, digest, &length);
  EVP_MD_CTX_free(ctx);
  return base64_encode(std::span<const std::uint8_t>(digest, length));
}

std::string format_utc(std::int64_t utc_ms) {
  const std::time_t seconds = static_cast<std::time_t>(utc_ms / 1000);
  std::tm tm{};
  gmtime_r(&seconds, &tm);
  char buf[96];
  std::snprintf(buf, sizeof buf, "%04d-%02d-%02dT%02d:%02d:%02d.%03dZ", tm.tm_year + 1900, tm.tm_mon + 1, tm.tm_mday,
                tm.tm_hour, tm.tm_min, tm.tm_sec, static_cast<int>(utc_ms % 1000));
  return buf;
}

UsernameToken make_username_token(std::string_view user, std::string_view password, std::span<const std::uint8_t> nonce,
                                  std::int64_t utc_ms) {
  UsernameToken t;
  t.username = std::string(user);
  t.created = format_utc(utc_ms);
  t.nonce_base64 = base64_encode(nonce);
  t.password_digest = password_digest(nonce, t.created, password);
  return t;
}

std::string envelope(std::string_view body, const UsernameToken* token) {
  std::string out =
      "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
      "<s:Envelope xmlns:s=\"http://www.w3.org/2003/05/soap-envelope\" xmlns:tt=\"http://www.onvif.org/ver10/schema\">";
  if (token != nullptr) {
    out += "<s:Header><wsse:Security s:mustUnderstand=\"1\" "
           "xmlns:wsse=\"http://docs.oasis-open.org/wss/2004/01/oasis-200401-wss-wssecurity-secext-1.0.xsd\" "
           "xmlns:wsu=\"http://docs.oasis-open.org/wss/2004/01/oasis-200401-wss-wssecurity-utility-1.0.xsd\">"
           "<wsse:UsernameToken><wsse:Username>" + escape(token->username) +
           "</wsse:Username><wsse:Password Type=\"http://docs.oasis-open.org/wss/2004/01/"
           "oasis-200401-wss-username-token-profile-1.0#PasswordDigest\">" + token->password_digest +
           "</wsse:Password><wsse:Nonce EncodingType=\"http://docs.oasis-open.org/wss/2004/01/"
           "oasis-200401-wss-soap-message-security-1.0#Base64Binary\">" + token->nonce_base64 +
           "</wsse:Nonce><wsu:Created>" + token->created + "</wsu:Created></wsse:UsernameToken></wsse:Security></s:Header>";
  }
  out += "<s:Body xmlns:xsi=\"http://www.w3.org/2001/XMLSchema-instance\" xmlns:xsd=\"http://www.w3.org/2001/XMLSchema\">";
  out += body;
  out += "</s:Body></s:Envelope>";
  return out;
}

std::string get_system_date_and_time_body() { return "<GetSystemDateAndTime xmlns=\"http://www.onvif.org/ver10/device/wsdl\"/>"; }
std::string get_services_body() {
  return "<GetServices xmlns=\"http://www.onvif.org/ver10/device/wsdl\"><IncludeCapability>false</IncludeCapability></GetServices>";
}
std::string get_capabilities_body() {
  return "<GetCapabilities xmlns=\"http://www.onvif.org/ver10/device/wsdl\"><Category>All</Category></GetCapabilities>";
}
std::string get_profiles_body() { return "<GetProfiles xmlns=\"http://www.onvif.org/ver10/media/wsdl\"/>"; }
std::string get_stream_uri_body(std::string_view profile_token) {
  return "<GetStreamUri xmlns=\"http://www.onvif.org/ver10/media/wsdl\"><StreamSetup><tt:Stream>RTP-Unicast</tt:Stream>"
         "<tt:Transport><tt:Protocol>RTSP</tt:Protocol></tt:Transport></StreamSetup><ProfileToken>" +
         escape(profile_token) + "</ProfileToken></GetStreamUri>";
}
std::string get_snapshot_uri_body(std::string_view profile_token) {
  return "<GetSnapshotUri xmlns=\"http://www.onvif.org/ver10/media/wsdl\"><ProfileToken>" + escape(profile_token) +
         "</ProfileToken></GetSnapshotUri>";
}
std::string continuous_move_body(std::string_view profile_token, double pan, double tilt, double zoom, double timeout_s) {
  pan = std::clamp(pan, -1.0, 1.0);
  tilt = std::clamp(tilt, -1.0, 1.0);
  zoom = std::clamp(zoom, -1.0, 1.0);
  std::string out = "<ContinuousMove xmlns=\"http://www.onvif.org/ver20/ptz/wsdl\"><ProfileToken>" + escape(profile_token) +
                    "</ProfileToken><Velocity><tt:PanTilt x=\"" + number(pan) + "\" y=\"" + number(tilt) +
                    "\"/><tt:Zoom x=\"" + number(zoom) + "\"/></Velocity>";
  if (timeout_s > 0) out += "<Timeout>PT" + number(timeout_s) + "S</Timeout>";
  return out + "</ContinuousMove>";
}
std::string stop_body(std::string_view profile_token) {
  return "<Stop xmlns=\"http://www.onvif.org/ver20/ptz/wsdl\"><ProfileToken>" + escape(profile_token) +
         "</ProfileToken><PanTilt>true</PanTilt><Zoom>true</Zoom></Stop>";
}
std::string goto_preset_body(std::string_view profile_token, std::string_view preset_token) {
  return "<GotoPreset xmlns=\"http://www.onvif.org/ver20/ptz/wsdl\"><ProfileToken>" + escape(profile_token) +
         "</ProfileToken><PresetToken>" + escape(preset_token) + "</PresetToken></GotoPreset>";
}
std::string probe_message(std::string_view message_id) {
  return "<?xml version=\"1.0\" encoding=\"UTF-8\"?>\n"
         "<s:Envelope xmlns:s=\"http://www.w3.org/2003/05/soap-envelope\" "
         "xmlns:a=\"http://schemas.xmlsoap.org/ws/2004/08/addressing\" "
         "xmlns:d=\"http://schemas.xmlsoap.org/ws/2005/04/discovery\" "
         "xmlns:dn=\"http://www.onvif.org/ver10/network/wsdl\"><s:Header>"
         "<a:Action s:mustUnderstand=\"1\">http://schemas.xmlsoap.org/ws/2005/04/discovery/Probe</a:Action>"
         "<a:MessageID>" + escape(message_id) + "</a:MessageID>"
         "<a:ReplyTo><a:Address>http://schemas.xmlsoap.org/ws/2004/08/addressing/role/anonymous</a:Address></a:ReplyTo>"
         "<a:To s:mustUnderstand=\"1\">urn:schemas-xmlsoap-org:ws:2005:04:discovery</a:To>"
         "</s:Header><s:Body><d:Probe><d:Types>dn:NetworkVideoTransmitter</d:Types></d:Probe></s:Body></s:Envelope>";
}

Result<std::optional<Fault>> parse_fault(std::string_view xml) {
  pugi::xml_document doc;
  if (auto r = load(xml, doc); !r) return r.error();
  pugi::xml_node fault = find(doc, "Fault");
  if (!fault) return std::optional<Fault>();
  Fault f;
  if (pugi::xml_node code = find(fault, "Code")) {
    if (pugi::xml_node value = code.first_child(); value && local_name(value.name()) == "Value") f.code = text_of(value);
    std::vector<pugi::xml_node> values;
    find_all(code, "Value", values);
    if (values.size() > 1) f.subcode = text_of(values[1]);
    if (f.code.empty() && !values.empty()) f.code = text_of(values[0]);
  }
  if (pugi::xml_node text = find(fault, "Text")) f.reason = text_of(text);
  return std::optional<Fault>(f);
}

Result<std::int64_t> parse_system_date_and_time(std::string_view xml) {
  pugi::xml_document doc;
  if (auto r = load(xml, doc); !r) return r.error();
  pugi::xml_node utc = find(doc, "UTCDateTime");
  if (!utc) return Error(Errc::protocol, "GetSystemDateAndTime reply without UTCDateTime");
  pugi::xml_node date = find(utc, "Date");
  pugi::xml_node time = find(utc, "Time");
  if (!date || !time) return Error(Errc::protocol, "UTCDateTime without Date or Time");
  std::tm tm{};
  tm.tm_year = to_int(text_of(find(date, "Year"))) - 1900;
  tm.tm_mon = to_int(text_of(find(date, "Month"))) - 1;
  tm.tm_mday = to_int(text_of(find(date, "Day")));
  tm.tm_hour = to_int(text_of(find(time, "Hour")));
  tm.tm_min = to_int(text_of(find(time, "Minute")));
  tm.tm_sec = to_int(text_of(find(time, "Second")));
  if (tm.tm_year < 70 || tm.tm_year > 1100 || tm.tm_mon < 0 || tm.tm_mon > 11 || tm.tm_mday < 1 || tm.tm_mday > 31 ||
      tm.tm_hour < 0 || tm.tm_hour > 23 || tm.tm_min < 0 || tm.tm_min > 59 || tm.tm_sec < 0 || tm.tm_sec > 60) {
    return Error(Errc::protocol, "UTCDateTime out of range");
  }
  return static_cast<std::int64_t>(timegm(&tm)) * 1000;
}

Result<ServiceAddresses> parse_services(std::string_view xml) {
  pugi::xml_document doc;
  if (auto r = load(xml, doc); !r) return r.error();
  std::vector<pugi::xml_node> services;
  find_all(doc, "Service", services);
  ServiceAddresses out;
  for (pugi::xml_node s : services) {
    const std::string ns = text_of(find(s, "Namespace"));
    const std::string xaddr = text_of(find(s, "XAddr"));
    if (ns == kDeviceNs) out.device = xaddr;
    if (ns == kMediaNs) out.media = xaddr;
    if (ns == kPtzNs) out.ptz = xaddr;
  }
  if (out.media.empty()) return Error(Errc::protocol, "GetServices lists no media service");
  return out;
}

Result<ServiceAddresses> parse_capabilities(std::string_view xml) {
  pugi::xml_document doc;
  if (auto r = load(xml, doc); !r) return r.error();
  pugi::xml_node caps = find(doc, "Capabilities");
  if (!caps) return Error(Errc::protocol, "GetCapabilities reply without Capabilities");
  ServiceAddresses out;
  for (pugi::xml_node child : caps.children()) {
    const std::string_view name = local_name(child.name());
    const std::string xaddr = text_of(find(child, "XAddr"));
    if (name == "Device") out.device = xaddr;
    if (name == "Media") out.media = xaddr;
    if (name == "PTZ") out.ptz = xaddr;
  }
  if (out.media.empty()) return Error(Errc::protocol, "GetCapabilities lists no media service");
  return out;
}

Result<std::vector<Profile>> parse_profiles(std::string_view xml) {
  pugi::xml_document doc;
  if (auto r = load(xml, doc); !r) return r.error();
  std::vector<pugi::xml_node> nodes;
  find_all(doc, "Profiles", nodes);
  std::vector<Profile> out;
  for (pugi::xml_node n : nodes) {
    Profile p;
    p.token = n.attribute("token").value();
    if (p.token.empty()) continue;
    p.name = text_of(find(n, "Name"));
    if (pugi::xml_node enc = find(n, "VideoEncoderConfiguration")) {
      p.encoding = text_of(find(enc, "Encoding"));
      if (pugi::xml_node res = find(enc, "Resolution")) {
        p.width_px = to_int(text_of(find(res, "Width")));
        p.height_px = to_int(text_of(find(res, "Height")));
      }
    }
    p.has_ptz = static_cast<bool>(find(n, "PTZConfiguration"));
    out.push_back(std::move(p));
  }
  if (out.empty()) return Error(Errc::protocol, "GetProfiles returned no profile");
  return out;
}

const Profile* choose_profile(const std::vector<Profile>& profiles, std::string_view encoding, int width_px, int height_px) {
  const Profile* best = nullptr;
  int best_score = -1;
  for (const Profile& p : profiles) {
    int score = 0;
    if (!encoding.empty() && p.encoding == encoding) score += 4;
    if (p.width_px == width_px && p.height_px == height_px) score += 2;
    if (p.has_ptz) score += 1;
    if (score > best_score) {
      best = &p;
      best_score = score;
    }
  }
  return best;
}

Result<std::string> parse_media_uri(std::string_view xml) {
  pugi::xml_document doc;
  if (auto r = load(xml, doc); !r) return r.error();
  pugi::xml_node media = find(doc, "MediaUri");
  pugi::xml_node uri = media ? find(media, "Uri") : find(doc, "Uri");
  const std::string value = uri ? text_of(uri) : std::string();
  if (value.empty()) return Error(Errc::protocol, "reply without MediaUri/Uri");
  return value;
}

Result<std::vector<ProbeMatch>> parse_probe_matches(std::string_view xml) {
  pugi::xml_document doc;
  if (auto r = load(xml, doc); !r) return r.error();
  std::vector<pugi::xml_node> nodes;
  find_all(doc, "ProbeMatch", nodes);
  std::vector<ProbeMatch> out;
  for (pugi::xml_node n : nodes) {
    ProbeMatch m;
    if (pugi::xml_node epr = find(n, "EndpointReference")) m.endpoint = text_of(find(epr, "Address"));
    m.types = text_of(find(n, "Types"));
    m.scopes = text_of(find(n, "Scopes"));
    const std::string xaddrs = text_of(find(n, "XAddrs"));
    std::size_t pos = 0;
    while (pos < xaddrs.size()) {
      const std::size_t end = xaddrs.find_first_of(" \t\r\n", pos);
      const std::string one = xaddrs.substr(pos, end == std::string::npos ? std::string::npos : end - pos);
      if (!one.empty() && m.xaddrs.size() < 8) m.xaddrs.push_back(one);
      if (end == std::string::npos) break;
      pos = end + 1;
    }
    if (!m.endpoint.empty()) out.push_back(std::move(m));
  }
  return out;
}

std::string rewrite_http_host(std::string_view url, std::string_view host, std::uint16_t port) {
  const std::size_t scheme = url.find("://");
  if (scheme == std::string_view::npos) return std::string(url);
  const std::size_t start = scheme + 3;
  const std::size_t end = url.find('/', start);
  std::string out(url.substr(0, start));
  out += host;
  out += ':';
  out += std::to_string(port);
  if (end != std::string_view::npos) out += url.substr(end);
  return out;
}

std::optional<double> parse_duration_s(std::string_view text) {
  if (!text.starts_with("PT")) return std::nullopt;
  text.remove_prefix(2);
  double total = 0;
  bool any = false;
  while (!text.empty()) {
    std::size_t i = 0;
    while (i < text.size() && (std::isdigit(static_cast<unsigned char>(text[i])) != 0 || text[i] == '.')) ++i;
    if (i == 0 || i == text.size()) return std::nullopt;
    const double v = std::strtod(std::string(text.substr(0, i)).c_str(), nullptr);
    const char unit = text[i];
    if (unit == 'H') total += v * 3600;
    else if (unit == 'M') total += v * 60;
    else if (unit == 'S') total += v;
    else return std::nullopt;
    any = true;
    text.remove_prefix(i + 1);
  }
  if (!any) return std::nullopt;
  return total;
}

}  // namespace sen3bot::camera::onvif
