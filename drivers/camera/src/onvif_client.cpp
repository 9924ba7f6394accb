#include "sen3bot/camera/onvif_client.hpp"

#include <curl/curl.h>

#include <chrono>
#include <random>
#include <thread>

#include "sen3bot/camera/rtsp_url.hpp"
#include "sen3bot/hal/udp.hpp"

namespace sen3bot::camera::onvif {
namespace {

std::int64_t utc_now_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

struct Body {
  std::string data;
  bool overflow = false;
};

std::size_t on_body(char* ptr, std::size_t size, std::size_t count, void* user) {
  auto* body = static_cast<Body*>(user);
  const std::size_t n = size * count;
  if (body->data.size() + n > kMaxSoapBytes) {
    body->overflow = true;
    return 0;  // aborts the transfer
  }
  body->data.append(ptr, n);
  return n;
}

bool is_not_authorized(const std::string& xml) {
  auto fault = parse_fault(xml);
  return fault && fault->has_value() && (*fault)->subcode.find("NotAuthorized") != std::string::npos;
}

std::string rewrite_rtsp(const std::string& uri, const std::string& host) {
  auto parsed = parse_rtsp_url(uri);
  if (!parsed) return uri;
  return rewrite_host(uri, host, parsed->port);
}

}  // namespace

const char* to_string(AuthMode mode) {
  switch (mode) {
    case AuthMode::none: return "none";
    case AuthMode::ws_username_token: return "ws-usernametoken";
    case AuthMode::http_digest: return "http-digest";
  }
  return "?";
}

Result<std::unique_ptr<OnvifClient>> OnvifClient::create(OnvifConfig config) {
  if (config.host.empty()) return Error(Errc::config, "ONVIF host is empty");
  static const CURLcode global = curl_global_init(CURL_GLOBAL_DEFAULT);
  if (global != CURLE_OK) return Error(Errc::io, "curl_global_init failed");
  std::unique_ptr<OnvifClient> client(new OnvifClient(std::move(config)));
  client->curl_ = curl_easy_init();
  if (client->curl_ == nullptr) return Error(Errc::io, "curl_easy_init failed");
  return client;
}

OnvifClient::OnvifClient(OnvifConfig config) : config_(std::move(config)) {
  device_url_ = "http://" + config_.host + ":" + std::to_string(config_.port) + config_.device_path;
  if (config_.credentials.empty()) auth_mode_ = AuthMode::none;
}

OnvifClient::~OnvifClient() {
  if (curl_ != nullptr) curl_easy_cleanup(static_cast<CURL*>(curl_));
}

std::int64_t OnvifClient::device_utc_ms() const { return utc_now_ms() + clock_offset_ms_; }

Result<OnvifClient::HttpReply> OnvifClient::post(const std::string& url, std::string_view action, const std::string& soap,
                                                bool http_digest) {
  CURL* curl = static_cast<CURL*>(curl_);
  curl_easy_reset(curl);
  Body body;
  const std::string content_type =
      "Content-Type: application/soap+xml; charset=utf-8; action=\"" + std::string(action) + "\"";
  curl_slist* headers = curl_slist_append(nullptr, content_type.c_str());
  curl_easy_setopt(curl, CURLOPT_URL, url.c_str());
  curl_easy_setopt(curl, CURLOPT_HTTPHEADER, headers);
  curl_easy_setopt(curl, CURLOPT_POSTFIELDS, soap.c_str());
  curl_easy_setopt(curl, CURLOPT_POSTFIELDSIZE, static_cast<long>(soap.size()));
  curl_easy_setopt(curl, CURLOPT_WRITEFUNCTION, on_body);
  curl_easy_setopt(curl, CURLOPT_WRITEDATA, &body);
  curl_easy_setopt(curl, CURLOPT_TIMEOUT_MS, static_cast<long>(config_.timeout_ms));
  curl_easy_setopt(curl, CURLOPT_CONNECTTIMEOUT_MS, static_cast<long>(config_.timeout_ms));
  curl_easy_setopt(curl, CURLOPT_NOSIGNAL, 1L);
  curl_easy_setopt(curl, CURLOPT_FOLLOWLOCATION, 0L);  // a redirect could lead elsewhere
  curl_easy_setopt(curl, CURLOPT_PROTOCOLS_STR, "http,https");
  if (http_digest) {
    curl_easy_setopt(curl, CURLOPT_HTTPAUTH, static_cast<long>(CURLAUTH_DIGEST));
    curl_easy_setopt(curl, CURLOPT_USERNAME, config_.credentials.user.c_str());
    curl_easy_setopt(curl, CURLOPT_PASSWORD, config_.credentials.password.c_str());
  }
  const CURLcode rc = curl_easy_perform(curl);
  curl_slist_free_all(headers);
  if (body.overflow) return Error(Errc::protocol, "ONVIF reply exceeds 512 KiB");
  if (rc != CURLE_OK) return Error::format(Errc::io, "%s: %s", url.c_str(), curl_easy_strerror(rc));
  HttpReply reply;
  curl_easy_getinfo(curl, CURLINFO_RESPONSE_CODE, &reply.status);
  reply.body = std::move(body.data);
  return reply;
}

Result<std::string> OnvifClient::call(const std::string& url, std::string_view action, const std::string& body,
                                      bool authenticate) {
  const bool use_token = authenticate && auth_mode_ == AuthMode::ws_username_token;
  std::string soap;
  if (use_token) {
    std::uint8_t nonce[16];
    std::random_device rd;
    for (auto& b : nonce) b = static_cast<std::uint8_t>(rd());
    // Created in the device's clock: cameras reject tokens a few seconds out of their window.
    const UsernameToken token = make_username_token(config_.credentials.user, config_.credentials.password, nonce, device_utc_ms());
    soap = envelope(body, &token);
  } else {
    soap = envelope(body, nullptr);
  }
  auto reply = post(url, action, soap, authenticate && auth_mode_ == AuthMode::http_digest);
  if (!reply) return reply.error();
  if (use_token && (reply->status == 401 || is_not_authorized(reply->body))) {
    // Core §5.9.1: HTTP Digest is the required scheme; send it without the WS header.
    auth_mode_ = AuthMode::http_digest;
    reply = post(url, action, envelope(body, nullptr), true);
    if (!reply) return reply.error();
  }
  if (reply->status == 401) return Error(Errc::permission, "ONVIF: 401 Unauthorized");
  if (reply->status != 200) {
    auto fault = parse_fault(reply->body);
    if (fault && fault->has_value()) {
      return Error::format(Errc::protocol, "ONVIF fault %s %s: %s", (*fault)->code.c_str(), (*fault)->subcode.c_str(),
                           (*fault)->reason.c_str());
    }
    return Error::format(Errc::protocol, "ONVIF: HTTP %ld", reply->status);
  }
  return std::move(reply->body);
}

Status OnvifClient::connect() {
  // PRE_AUTH (Core §8.3.6); some devices want auth anyway, so retry with it.
  const std::string action_time = std::string(kDeviceNs) + "/GetSystemDateAndTime";
  auto time_xml = call(device_url_, action_time, get_system_date_and_time_body(), false);
  if (!time_xml && auth_mode_ != AuthMode::none) time_xml = call(device_url_, action_time, get_system_date_and_time_body(), true);
  if (!time_xml) return time_xml.error();
  const std::int64_t local_ms = utc_now_ms();
  if (auto device_ms = parse_system_date_and_time(*time_xml)) clock_offset_ms_ = *device_ms - local_ms;

  auto services_xml = call(device_url_, std::string(kDeviceNs) + "/GetServices", get_services_body(), true);
  Result<ServiceAddresses> services = services_xml ? parse_services(*services_xml) : Result<ServiceAddresses>(services_xml.error());
  // Merge with GetCapabilities: some devices list PTZ only there.
  if (!services || services->ptz.empty()) {
    auto caps_xml = call(device_url_, std::string(kDeviceNs) + "/GetCapabilities", get_capabilities_body(), true);
    if (caps_xml) {
      auto caps = parse_capabilities(*caps_xml);
      if (caps && !services) services = *caps;
      if (caps && services && services->ptz.empty()) services->ptz = caps->ptz;
    }
  }
  if (!services) return services.error();
  services_ = *services;
  // Addresses behind NAT or from misconfigured firmware: keep path and any explicit port, use
  // our host (no explicit port: the one we reach the device on).
  auto fix = [this](std::string& url) {
    if (url.empty()) return;
    const std::size_t scheme = url.find("://");
    const std::size_t start = scheme == std::string::npos ? 0 : scheme + 3;
    const std::size_t end = url.find('/', start);
    const std::string authority = url.substr(start, end == std::string::npos ? std::string::npos : end - start);
    const std::size_t colon = authority.rfind(':');
    const std::uint16_t port = colon == std::string::npos ? config_.port
                                                          : static_cast<std::uint16_t>(std::atoi(authority.c_str() + colon + 1));
    url = rewrite_http_host(url, config_.host, port == 0 ? config_.port : port);
  };
  fix(services_.device);
  fix(services_.media);
  fix(services_.ptz);
  return {};
}

Result<std::vector<Profile>> OnvifClient::profiles() {
  auto xml = call(services_.media, std::string(kMediaNs) + "/GetProfiles", get_profiles_body(), true);
  if (!xml) return xml.error();
  return parse_profiles(*xml);
}

Result<std::string> OnvifClient::stream_uri(const std::string& profile_token) {
  auto xml = call(services_.media, std::string(kMediaNs) + "/GetStreamUri", get_stream_uri_body(profile_token), true);
  if (!xml) return xml.error();
  auto uri = parse_media_uri(*xml);
  if (!uri) return uri.error();
  return rewrite_rtsp(*uri, config_.host);
}

Result<std::string> OnvifClient::snapshot_uri(const std::string& profile_token) {
  auto xml = call(services_.media, std::string(kMediaNs) + "/GetSnapshotUri", get_snapshot_uri_body(profile_token), true);
  if (!xml) return xml.error();
  auto uri = parse_media_uri(*xml);
  if (!uri) return uri.error();
  return rewrite_http_host(*uri, config_.host, config_.port);
}

Status OnvifClient::continuous_move(const std::string& profile_token, double pan, double tilt, double zoom, double timeout_s) {
  if (services_.ptz.empty()) return Error(Errc::not_supported, "the camera offers no PTZ service");
  auto xml = call(services_.ptz, std::string(kPtzNs) + "/ContinuousMove",
                  continuous_move_body(profile_token, pan, tilt, zoom, timeout_s), true);
  if (!xml) return xml.error();
  return {};
}

Status OnvifClient::stop(const std::string& profile_token) {
  if (services_.ptz.empty()) return Error(Errc::not_supported, "the camera offers no PTZ service");
  auto xml = call(services_.ptz, std::string(kPtzNs) + "/Stop", stop_body(profile_token), true);
  if (!xml) return xml.error();
  return {};
}

Status OnvifClient::goto_preset(const std::string& profile_token, const std::string& preset_token) {
  if (services_.ptz.empty()) return Error(Errc::not_supported, "the camera offers no PTZ service");
  auto xml = call(services_.ptz, std::string(kPtzNs) + "/GotoPreset", goto_preset_body(profile_token, preset_token), true);
  if (!xml) return xml.error();
  return {};
}

Result<std::vector<ProbeMatch>> discover(const DiscoveryOptions& options) {
  auto socket = hal::UdpSocket::bind(options.interface_address, 0);
  if (!socket) return socket.error();
  if (!options.interface_address.empty()) (void)(*socket)->set_multicast_interface(options.interface_address);
  auto destination = hal::resolve_udp_endpoint(options.destination, options.port);
  if (!destination) return destination.error();
  std::random_device rd;
  char id[64];
  std::snprintf(id, sizeof id, "urn:uuid:%08x-%04x-4%03x-a%03x-%08x%04x", rd(), rd() & 0xFFFF, rd() & 0xFFF, rd() & 0xFFF, rd(),
                rd() & 0xFFFF);
  const std::string probe = probe_message(id);
  const std::span<const std::uint8_t> bytes(reinterpret_cast<const std::uint8_t*>(probe.data()), probe.size());
  std::vector<ProbeMatch> found;
  std::vector<std::uint8_t> buf(65536);
  const auto start = std::chrono::steady_clock::now();
  int sent = 0;
  auto next_send = start;
  // UDP loses datagrams: send three times, 150 ms apart.
  while (std::chrono::steady_clock::now() - start < std::chrono::milliseconds(options.timeout_ms)) {
    if (sent < 3 && std::chrono::steady_clock::now() >= next_send) {
      (void)(*socket)->send_to(bytes, *destination);
      ++sent;
      next_send += std::chrono::milliseconds(150);
    }
    auto got = (*socket)->recv_from(buf);
    if (!got || !got->has_value()) {
      std::this_thread::sleep_for(std::chrono::milliseconds(5));
      continue;
    }
    auto matches = parse_probe_matches(std::string_view(reinterpret_cast<const char*>(buf.data()), (*got)->size));
    if (!matches) continue;
    for (ProbeMatch& m : *matches) {
      bool seen = false;
      for (const ProbeMatch& f : found) seen = seen || f.endpoint == m.endpoint;
      if (!seen) found.push_back(std::move(m));
    }
  }
  return found;
}

}  // namespace sen3bot::camera::onvif
