#pragma once
// ONVIF device client over HTTP (libcurl: chunked and close-delimited bodies, HTTP Digest)
// and WS-Discovery. Blocking calls bounded by timeouts: run them at start-up or from the
// command line, never from a real-time task. Every URL the device reports is rewritten to
// the configured host, so the client never connects anywhere else.
#include <cstdint>
#include <memory>
#include <string>
#include <vector>

#include "sen3bot/camera/auth.hpp"
#include "sen3bot/camera/onvif.hpp"
#include "sen3bot/hal/result.hpp"

namespace sen3bot::camera::onvif {

struct OnvifConfig {
  std::string host;                          // the camera as the robot reaches it
  std::uint16_t port = 80;
  std::string device_path = "/onvif/device_service";  // Core §5.1.1 entry point
  Credentials credentials;
  int timeout_ms = 5000;                     // per HTTP exchange
};

enum class AuthMode : std::uint8_t { none, ws_username_token, http_digest };
const char* to_string(AuthMode mode);

class OnvifClient {
 public:
  static Result<std::unique_ptr<OnvifClient>> create(OnvifConfig config);
  ~OnvifClient();
  OnvifClient(const OnvifClient&) = delete;
  OnvifClient& operator=(const OnvifClient&) = delete;

  // GetSystemDateAndTime without auth (clock offset), then GetServices, falling back to
  // GetCapabilities; service addresses are rewritten to the configured host.
  Status connect();
  Result<std::vector<Profile>> profiles();
  // The RTSP URI with its host replaced by the configured one (port and path kept).
  Result<std::string> stream_uri(const std::string& profile_token);
  Result<std::string> snapshot_uri(const std::string& profile_token);
  Status continuous_move(const std::string& profile_token, double pan, double tilt, double zoom, double timeout_s);
  Status stop(const std::string& profile_token);
  Status goto_preset(const std::string& profile_token, const std::string& preset_token);

  [[nodiscard]] std::int64_t clock_offset_ms() const { return clock_offset_ms_; }
  [[nodiscard]] AuthMode auth_mode() const { return auth_mode_; }
  [[nodiscard]] const ServiceAddresses& services() const { return services_; }

 private:
  explicit OnvifClient(OnvifConfig config);
  struct HttpReply {
    long status = 0;
    std::string body;
  };
  Result<HttpReply> post(const std::string& url, std::string_view action, const std::string& soap, bool http_digest);
  // Authenticated call with the WS-UsernameToken -> HTTP Digest fallback (Core §5.9).
  Result<std::string> call(const std::string& url, std::string_view action, const std::string& body, bool authenticate);
  std::int64_t device_utc_ms() const;

  OnvifConfig config_;
  std::string device_url_;
  ServiceAddresses services_;
  std::int64_t clock_offset_ms_ = 0;
  AuthMode auth_mode_ = AuthMode::ws_username_token;
  void* curl_ = nullptr;
};

// Sends a WS-Discovery Probe (three times, 150 ms apart) to destination (the multicast group
// by default) and collects ProbeMatches for timeout_ms, de-duplicated by endpoint reference.
// Replies come from arbitrary ports, so they are read on the socket that sent the probe.
struct DiscoveryOptions {
  std::string destination = std::string(kDiscoveryAddress);
  std::uint16_t port = kDiscoveryPort;
  std::string interface_address;  // outgoing multicast interface; "" = the system's choice
  int timeout_ms = 2000;
};
Result<std::vector<ProbeMatch>> discover(const DiscoveryOptions& options);

}  // namespace sen3bot::camera::onvif
