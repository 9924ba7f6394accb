#pragma once
// ONVIF (Core, Media, PTZ) and WS-Discovery messages: SOAP 1.2 envelope and body builders,
// WS-UsernameToken PasswordDigest, and response parsers that match elements by local name
// (cameras and servers disagree on prefixes: tt:Uri vs trt:Uri, SOAP-ENV vs s vs env).
// Pure; XML is parsed with pugixml, which expands no external entities and no DTD.
#include <cstdint>
#include <optional>
#include <span>
#include <string>
#include <string_view>
#include <vector>

#include "sen3bot/hal/result.hpp"

namespace sen3bot::camera::onvif {

constexpr std::size_t kMaxSoapBytes = 512 * 1024;  // GetProfiles of a multi-stream camera fits
constexpr std::string_view kDeviceNs = "http://www.onvif.org/ver10/device/wsdl";
constexpr std::string_view kMediaNs = "http://www.onvif.org/ver10/media/wsdl";
constexpr std::string_view kPtzNs = "http://www.onvif.org/ver20/ptz/wsdl";
// WS-Discovery 2005/04 over SOAP-over-UDP (ONVIF Core §7).
constexpr std::string_view kDiscoveryAddress = "239.255.255.250";
constexpr std::uint16_t kDiscoveryPort = 3702;

struct UsernameToken {
  std::string username;
  std::string password_digest;  // Base64(SHA1(nonce ‖ created ‖ password))
  std::string nonce_base64;
  std::string created;          // exactly the string that was hashed
};

// OASIS UsernameToken Profile 1.0 §3.1: hashes the nonce's bytes, not its base64 text.
std::string password_digest(std::span<const std::uint8_t> nonce, std::string_view created, std::string_view password);
UsernameToken make_username_token(std::string_view user, std::string_view password,
                                  std::span<const std::uint8_t> nonce, std::int64_t utc_ms);
// "YYYY-MM-DDTHH:MM:SS.mmmZ"
std::string format_utc(std::int64_t utc_ms);

// A SOAP 1.2 envelope around body, with a Security header when token is given.
std::string envelope(std::string_view body, const UsernameToken* token);

std::string get_system_date_and_time_body();
std::string get_services_body();
std::string get_capabilities_body();
std::string get_profiles_body();
std::string get_stream_uri_body(std::string_view profile_token);
std::string get_snapshot_uri_body(std::string_view profile_token);
// Velocities in the generic space, each clamped to [-1, 1]; timeout_s > 0 adds <Timeout>.
std::string continuous_move_body(std::string_view profile_token, double pan, double tilt, double zoom, double timeout_s);
std::string stop_body(std::string_view profile_token);
std::string goto_preset_body(std::string_view profile_token, std::string_view preset_token);
std::string probe_message(std::string_view message_id);

struct Fault {
  std::string code;     // e.g. "env:Sender"
  std::string subcode;  // e.g. "ter:NotAuthorized"
  std::string reason;
};
// A SOAP Fault in the body, if there is one. Malformed XML is an error.
Result<std::optional<Fault>> parse_fault(std::string_view xml);

// UTC from GetSystemDateAndTimeResponse, as milliseconds since the epoch.
Result<std::int64_t> parse_system_date_and_time(std::string_view xml);

struct ServiceAddresses {
  std::string device;
  std::string media;
  std::string ptz;  // empty: no PTZ service
};
Result<ServiceAddresses> parse_services(std::string_view xml);
Result<ServiceAddresses> parse_capabilities(std::string_view xml);

struct Profile {
  std::string token;
  std::string name;
  std::string encoding;  // "H264", "JPEG", ...; a hint only: the SDP decides
  int width_px = 0;
  int height_px = 0;
  bool has_ptz = false;  // a PTZConfiguration: only such profiles can move
};
Result<std::vector<Profile>> parse_profiles(std::string_view xml);
// The profile for streaming: the wanted encoding and size if present, preferring PTZ ones.
const Profile* choose_profile(const std::vector<Profile>& profiles, std::string_view encoding, int width_px, int height_px);

// MediaUri/Uri from GetStreamUri or GetSnapshotUri (entities such as &amp; decoded).
Result<std::string> parse_media_uri(std::string_view xml);

struct ProbeMatch {
  std::string endpoint;             // urn:uuid:..., the camera's identity across IP changes
  std::vector<std::string> xaddrs;  // device service URLs
  std::string types;
  std::string scopes;
};
Result<std::vector<ProbeMatch>> parse_probe_matches(std::string_view xml);

// For "http://host[:port]/path": the URL with host and port replaced (a device behind NAT or
// with wrong firmware settings reports an address we cannot reach).
std::string rewrite_http_host(std::string_view url, std::string_view host, std::uint16_t port);

// xs:duration as used by ONVIF ("PT1S", "PT1093754.348S", "PT1M30S"); nullopt when malformed.
std::optional<double> parse_duration_s(std::string_view text);

}  // namespace sen3bot::camera::onvif
