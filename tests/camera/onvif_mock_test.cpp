// ONVIF client against a mock device of ours serving the recorded real-camera replies
// (tests/data/camera/onvif/) by operation, checking WS-UsernameToken (with a skewed clock and
// a ±5 s window) or HTTP Digest, with chunked replies, unreachable XAddrs and no PTZ; and
// WS-Discovery against two responders replying from their own ports.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <cstdio>
#include <ctime>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "camera_test_util.hpp"
#include "sen3bot/camera/auth.hpp"
#include "sen3bot/camera/onvif_client.hpp"
#include "sen3bot/hal/tcp.hpp"
#include "sen3bot/hal/udp.hpp"

namespace sen3bot::camera::onvif {
namespace {

constexpr const char* kUser = "admin";
constexpr const char* kPassword = "secret";

std::string between(const std::string& s, const std::string& open, const std::string& close) {
  const std::size_t a = s.find(open);
  if (a == std::string::npos) return {};
  const std::size_t start = s.find('>', a) + 1;
  const std::size_t b = s.find(close, start);
  return b == std::string::npos ? std::string() : s.substr(start, b - start);
}

std::int64_t now_ms() {
  return std::chrono::duration_cast<std::chrono::milliseconds>(std::chrono::system_clock::now().time_since_epoch()).count();
}

struct MockOptions {
  enum class Auth { none, ws_token, http_digest } auth = Auth::ws_token;
  std::int64_t clock_skew_ms = 0;
  bool chunked = false;
  bool ptz = true;
};

class MockDevice {
 public:
  explicit MockDevice(MockOptions options) : options_(options) {
    listener_ = std::move(hal::TcpListener::listen("127.0.0.1", 0).value());
    thread_ = std::thread([this] { run(); });
  }
  ~MockDevice() {
    stop_ = true;
    thread_.join();
  }
  [[nodiscard]] std::uint16_t port() const { return listener_->port(); }
  std::vector<std::string> operations() {
    std::lock_guard lock(mutex_);
    return operations_;
  }
  std::vector<std::string> bodies() {
    std::lock_guard lock(mutex_);
    return bodies_;
  }

 private:
  std::string reply_for(const std::string& op) {
    if (op == "GetSystemDateAndTime") {
      const std::time_t t = static_cast<std::time_t>((now_ms() + options_.clock_skew_ms) / 1000);
      std::tm tm{};
      gmtime_r(&t, &tm);
      char xml[1024];
      std::snprintf(xml, sizeof xml,
                    "<?xml version=\"1.0\"?><SOAP-ENV:Envelope xmlns:SOAP-ENV=\"http://www.w3.org/2003/05/soap-envelope\" "
                    "xmlns:tds=\"http://www.onvif.org/ver10/device/wsdl\" xmlns:tt=\"http://www.onvif.org/ver10/schema\">"
                    "<SOAP-ENV:Body><tds:GetSystemDateAndTimeResponse><tds:SystemDateAndTime><tt:UTCDateTime><tt:Time>"
                    "<tt:Hour>%d</tt:Hour><tt:Minute>%d</tt:Minute><tt:Second>%d</tt:Second></tt:Time><tt:Date>"
                    "<tt:Year>%d</tt:Year><tt:Month>%d</tt:Month><tt:Day>%d</tt:Day></tt:Date></tt:UTCDateTime>"
                    "</tds:SystemDateAndTime></tds:GetSystemDateAndTimeResponse></SOAP-ENV:Body></SOAP-ENV:Envelope>",
                    tm.tm_hour, tm.tm_min, tm.tm_sec, tm.tm_year + 1900, tm.tm_mon + 1, tm.tm_mday);
      return xml;
    }
    if (!options_.ptz && op == "GetServices") {
      return "<env:Envelope xmlns:env=\"http://www.w3.org/2003/05/soap-envelope\"><env:Body><tds:GetServicesResponse "
             "xmlns:tds=\"http://www.onvif.org/ver10/device/wsdl\"><tds:Service><tds:Namespace>"
             "http://www.onvif.org/ver10/media/wsdl</tds:Namespace><tds:XAddr>http://192.168.68.111/onvif/media"
             "</tds:XAddr></tds:Service></tds:GetServicesResponse></env:Body></env:Envelope>";
    }
    if (!options_.ptz && op == "GetCapabilities") return fault("env:Receiver", "ter:ActionNotSupported");
    const char* file = op == "GetServices"        ? "GetServices.xml"
                       : op == "GetCapabilities"  ? "GetCapabilities.xml"
                       : op == "GetProfiles"      ? "GetProfiles.xml"
                       : op == "GetStreamUri"     ? "GetStreamUri.xml"
                       : op == "GetSnapshotUri"   ? "GetSnapshotUri.xml"
                       : op == "ContinuousMove"   ? "ptz.ContinuousMove.xml"
                       : op == "Stop"             ? "ptz.Stop.xml"
                       : op == "GotoPreset"       ? "ptz.GotoPreset.xml"
                                                  : nullptr;
    return file ? camera::testing::read_fixture(std::string("onvif/") + file) : fault("env:Receiver", "ter:ActionNotSupported");
  }
  static std::string fault(const std::string& code, const std::string& subcode) {
    return "<soap:Envelope xmlns:soap=\"http://www.w3.org/2003/05/soap-envelope\"><soap:Body><soap:Fault><soap:Code><soap:Value>" +
           code + "</soap:Value><soap:Subcode><soap:Value>" + subcode +
           "</soap:Value></soap:Subcode></soap:Code><soap:Reason><soap:Text xml:lang=\"en\">refused</soap:Text>"
           "</soap:Reason></soap:Fault></soap:Body></soap:Envelope>";
  }
  // WS-UsernameToken: right digest, Created within ±5 s of the device's (skewed) clock.
  bool token_ok(const std::string& body) {
    const std::string digest = between(body, "<wsse:Password", "</wsse:Password>");
    const std::string nonce = between(body, "<wsse:Nonce", "</wsse:Nonce>");
    const std::string created = between(body, "<wsu:Created", "</wsu:Created>");
    if (between(body, "<wsse:Username>", "</wsse:Username>") != kUser || digest.empty()) return false;
    auto raw = base64_decode(nonce);
    if (!raw || password_digest(*raw, created, kPassword) != digest) return false;
    std::tm tm{};
    int ms = 0;
    if (std::sscanf(created.c_str(), "%d-%d-%dT%d:%d:%d.%dZ", &tm.tm_year, &tm.tm_mon, &tm.tm_mday, &tm.tm_hour, &tm.tm_min,
                    &tm.tm_sec, &ms) < 6) {
      return false;
    }
    tm.tm_year -= 1900;
    tm.tm_mon -= 1;
    const std::int64_t created_ms = static_cast<std::int64_t>(timegm(&tm)) * 1000 + ms;
    return std::llabs(created_ms - (now_ms() + options_.clock_skew_ms)) <= 5000;
  }
  bool digest_ok(const std::string& headers) {
    const std::size_t at = headers.find("Authorization: Digest ");
    if (at == std::string::npos) return false;
    const std::string line = headers.substr(at + 22, headers.find("\r\n", at) - at - 22);
    auto field = [&](const std::string& key) {
      const std::size_t k = line.find(key + "=");
      if (k == std::string::npos) return std::string();
      std::size_t v = k + key.size() + 1;
      if (line[v] == '"') return line.substr(v + 1, line.find('"', v + 1) - v - 1);
      return line.substr(v, line.find(',', v) - v);
    };
    return field("response") == digest_response(kUser, "onvif", kPassword, "POST", field("uri"), "n0nce", field("qop"),
                                                 field("nc"), field("cnonce"));
  }
  void send(hal::TcpStream& c, const std::string& text) {
    std::size_t sent = 0;
    for (int spins = 0; sent < text.size() && spins < 100000; ++spins) {
      auto w = c.write(std::span(reinterpret_cast<const std::uint8_t*>(text.data()) + sent, text.size() - sent));
      if (!w) return;
      sent += *w;
    }
  }
  void respond(hal::TcpStream& c, int status, const std::string& extra, const std::string& body) {
    std::string head = "HTTP/1.1 " + std::to_string(status) + (status == 200 ? " OK" : " Error") +
                       "\r\nContent-Type: application/soap+xml; charset=utf-8\r\nConnection: close\r\n" + extra;
    if (options_.chunked) {
      std::string out = head + "Transfer-Encoding: chunked\r\n\r\n";
      for (std::size_t i = 0; i < body.size(); i += 100) {
        const std::string piece = body.substr(i, 100);
        char size[16];
        std::snprintf(size, sizeof size, "%zx\r\n", piece.size());
        out += size + piece + "\r\n";
      }
      send(c, out + "0\r\n\r\n");
    } else {
      send(c, head + "Content-Length: " + std::to_string(body.size()) + "\r\n\r\n" + body);
    }
  }
  void serve(hal::TcpStream& c) {
    std::string data;
    const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(3);
    std::size_t header_end = std::string::npos;
    std::size_t want = 0;
    while (std::chrono::steady_clock::now() < deadline) {
      std::uint8_t buf[8192];
      auto n = c.read(buf);
      if (!n) return;
      data.append(reinterpret_cast<const char*>(buf), *n);
      if (header_end == std::string::npos && (header_end = data.find("\r\n\r\n")) != std::string::npos) {
        const std::size_t cl = data.find("Content-Length: ");
        want = header_end + 4 + (cl == std::string::npos ? 0 : std::stoul(data.substr(cl + 16)));
      }
      if (header_end != std::string::npos && data.size() >= want) break;
      if (*n == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    if (header_end == std::string::npos) return;
    const std::string headers = data.substr(0, header_end);
    const std::string body = data.substr(header_end + 4);
    std::string op;
    for (const char* candidate : {"GetSystemDateAndTime", "GetServices", "GetCapabilities", "GetProfiles", "GetStreamUri",
                                  "GetSnapshotUri", "ContinuousMove", "GotoPreset", "Stop"}) {
      if (body.find(std::string("<") + candidate) != std::string::npos) {
        op = candidate;
        break;
      }
    }
    {
      std::lock_guard lock(mutex_);
      operations_.push_back(op);
      bodies_.push_back(body);
    }
    const bool pre_auth = op == "GetSystemDateAndTime";
    if (!pre_auth && options_.auth == MockOptions::Auth::ws_token && !token_ok(body)) {
      respond(c, 400, "", fault("env:Sender", "ter:NotAuthorized"));
      return;
    }
    if (!pre_auth && options_.auth == MockOptions::Auth::http_digest && !digest_ok(headers)) {
      if (body.find("UsernameToken") != std::string::npos) {
        respond(c, 400, "", fault("env:Sender", "ter:NotAuthorized"));
      } else {
        respond(c, 401, "WWW-Authenticate: Digest realm=\"onvif\", nonce=\"n0nce\", qop=\"auth\"\r\n", "");
      }
      return;
    }
    respond(c, 200, "", reply_for(op));
  }
  void run() {
    while (!stop_) {
      if (auto s = listener_->accept(); s && *s) {
        serve(**s);
      } else {
        std::this_thread::sleep_for(std::chrono::milliseconds(1));
      }
    }
  }

  MockOptions options_;
  std::unique_ptr<hal::TcpListener> listener_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::mutex mutex_;
  std::vector<std::string> operations_;
  std::vector<std::string> bodies_;
};

std::unique_ptr<OnvifClient> client_for(const MockDevice& mock, const char* password = kPassword) {
  OnvifConfig config;
  config.host = "127.0.0.1";
  config.port = mock.port();
  config.credentials = {kUser, password};
  config.timeout_ms = 2000;
  return std::move(OnvifClient::create(config).value());
}

TEST(OnvifMock, UsernameTokenWithSkewedClockAndRewrittenAddresses) {
  MockOptions o;
  o.clock_skew_ms = 3'600'000;  // the camera's clock is an hour ahead
  MockDevice mock(o);
  auto client = client_for(mock);
  { const Status c = client->connect(); ASSERT_TRUE(c.ok()) << c.error().message(); }
  EXPECT_NEAR(static_cast<double>(client->clock_offset_ms()), 3'600'000.0, 2000.0);
  // The recorded XAddrs name 192.168.68.111: every request must still come here.
  EXPECT_EQ(client->services().media, "http://127.0.0.1:" + std::to_string(mock.port()) + "/onvif/services");
  auto profiles = client->profiles();
  ASSERT_TRUE(profiles.ok()) << profiles.error().message();
  const Profile* p = choose_profile(*profiles, "H264", 1280, 720);
  ASSERT_NE(p, nullptr);
  EXPECT_EQ(p->token, "main");
  auto uri = client->stream_uri(p->token);
  ASSERT_TRUE(uri.ok()) << uri.error().message();
  EXPECT_EQ(*uri, "rtsp://127.0.0.1:554/h264main");
  auto snapshot = client->snapshot_uri(p->token);
  ASSERT_TRUE(snapshot.ok());
  EXPECT_EQ(snapshot->find("http://127.0.0.1:"), 0u);
  EXPECT_EQ(client->auth_mode(), AuthMode::ws_username_token);
  const auto ops = mock.operations();
  EXPECT_EQ(ops.front(), "GetSystemDateAndTime");
  EXPECT_EQ(mock.bodies().front().find("Security"), std::string::npos);  // sent without auth
}

TEST(OnvifMock, FallsBackToHttpDigestOnNotAuthorized) {
  MockOptions o;
  o.auth = MockOptions::Auth::http_digest;
  MockDevice mock(o);
  auto client = client_for(mock);
  { const Status c = client->connect(); ASSERT_TRUE(c.ok()) << c.error().message(); }
  EXPECT_EQ(client->auth_mode(), AuthMode::http_digest);
  auto profiles = client->profiles();
  ASSERT_TRUE(profiles.ok()) << profiles.error().message();
  EXPECT_EQ((*profiles)[0].token, "main");
}

TEST(OnvifMock, ChunkedRepliesAndPtzMoveStop) {
  MockOptions o;
  o.chunked = true;
  MockDevice mock(o);
  auto client = client_for(mock);
  { const Status c = client->connect(); ASSERT_TRUE(c.ok()) << c.error().message(); }
  ASSERT_TRUE(client->continuous_move("main", 0.5, 0, 0, 1.0).ok());
  ASSERT_TRUE(client->stop("main").ok());
  ASSERT_TRUE(client->goto_preset("main", "1").ok());
  const auto bodies = mock.bodies();
  bool moved = false;
  for (const auto& b : bodies) moved = moved || b.find("<tt:PanTilt x=\"0.500\" y=\"0.000\"/>") != std::string::npos;
  EXPECT_TRUE(moved);
  const auto ops = mock.operations();
  EXPECT_NE(std::find(ops.begin(), ops.end(), "Stop"), ops.end());
}

TEST(OnvifMock, NoPtzIsAClearError) {
  MockOptions o;
  o.ptz = false;
  MockDevice mock(o);
  auto client = client_for(mock);
  { const Status c = client->connect(); ASSERT_TRUE(c.ok()) << c.error().message(); }
  const Status s = client->continuous_move("main", 0.5, 0, 0, 1.0);
  ASSERT_FALSE(s.ok());
  EXPECT_EQ(s.error().code(), Errc::not_supported);
}

TEST(OnvifMock, WrongPasswordIsAClearError) {
  MockDevice mock(MockOptions{});
  auto client = client_for(mock, "wrong");
  const Status s = client->connect();
  EXPECT_FALSE(s.ok());
}

// Two responders answer a Probe from ports of their own; one answers twice.
TEST(WsDiscovery, TwoRespondersDeduplicated) {
  auto listen = hal::UdpSocket::bind("127.0.0.1", 0);
  ASSERT_TRUE(listen.ok());
  const std::uint16_t port = (*listen)->local_port();
  std::atomic<bool> stop{false};
  std::thread responder([&] {
    std::vector<std::uint8_t> buf(65536);
    const std::string fixture = camera::testing::read_fixture("onvif/Probe.xml");
    int answered = 0;
    while (!stop && answered < 2) {
      auto got = (*listen)->recv_from(buf);
      if (!got || !got->has_value()) {
        std::this_thread::sleep_for(std::chrono::milliseconds(2));
        continue;
      }
      const hal::UdpEndpoint to = (*got)->sender;
      for (const char* uuid : {"uuid:c9790c3a-701b-464d-a189-0060351c8ada", "uuid:00000000-0000-4000-8000-000000000002"}) {
        std::string reply = fixture;
        const std::size_t at = reply.find("uuid:c9790c3a-701b-464d-a189-0060351c8ada");
        reply.replace(at, 41, uuid);
        auto from = hal::UdpSocket::bind("127.0.0.1", 0);  // a fresh, random source port
        (void)(*from)->send_to(std::span(reinterpret_cast<const std::uint8_t*>(reply.data()), reply.size()), to);
      }
      ++answered;
    }
  });
  DiscoveryOptions options;
  options.destination = "127.0.0.1";
  options.port = port;
  options.timeout_ms = 700;
  auto found = discover(options);
  stop = true;
  responder.join();
  ASSERT_TRUE(found.ok()) << found.error().message();
  ASSERT_EQ(found->size(), 2u);
  EXPECT_EQ((*found)[0].xaddrs.size(), 1u);
}

}  // namespace
}  // namespace sen3bot::camera::onvif
