// Servers that misbehave: a huge Content-Length, a header that never ends, a reply that never
// comes, a connection closed in the middle of an interleaved frame, garbage between frames.
// The client must report a clear error and reconnect, never crash, hang or hand out data.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <string>
#include <thread>

#include "sen3bot/camera/rtsp_client.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/tcp.hpp"

namespace sen3bot::camera {
namespace {

// Answers each request with what script(method, cseq) returns; an empty string closes.
class ScriptedServer {
 public:
  using Script = std::function<std::string(const std::string& method, std::uint32_t cseq)>;
  explicit ScriptedServer(Script script) : script_(std::move(script)) {
    auto listener = hal::TcpListener::listen("127.0.0.1", 0);
    EXPECT_TRUE(listener.ok());
    listener_ = std::move(*listener);
    thread_ = std::thread([this] { run(); });
  }
  ~ScriptedServer() {
    stop_ = true;
    thread_.join();
  }
  [[nodiscard]] std::uint16_t port() const { return listener_->port(); }

 private:
  void run() {
    std::unique_ptr<hal::TcpStream> client;
    std::string buf;
    while (!stop_) {
      if (auto s = listener_->accept(); s && *s) {
        client = std::move(*s);
        buf.clear();
      }
      if (client) {
        std::uint8_t tmp[4096];
        auto n = client->read(tmp);
        if (!n) {
          client.reset();
        } else if (*n > 0) {
          buf.append(reinterpret_cast<const char*>(tmp), *n);
          std::size_t end = 0;
          while ((end = buf.find("\r\n\r\n")) != std::string::npos) {
            const std::string request = buf.substr(0, end);
            buf.erase(0, end + 4);
            const std::string method = request.substr(0, request.find(' '));
            const std::size_t c = request.find("CSeq: ");
            const auto cseq = static_cast<std::uint32_t>(std::stoul(request.substr(c + 6)));
            const std::string reply = script_(method, cseq);
            if (reply.empty()) {
              client.reset();
              break;
            }
            std::size_t sent = 0;
            while (sent < reply.size() && client) {
              auto w = client->write(std::span(reinterpret_cast<const std::uint8_t*>(reply.data()) + sent, reply.size() - sent));
              if (!w) break;
              sent += *w;
            }
          }
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }
  Script script_;
  std::unique_ptr<hal::TcpListener> listener_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
};

struct CountingSink : EncodedFrameSink {
  int frames = 0;
  void on_frame(const EncodedFrame&) override { ++frames; }
};

std::string ok(std::uint32_t cseq, const std::string& extra = "", const std::string& body = "") {
  std::string r = "RTSP/1.0 200 OK\r\nCSeq: " + std::to_string(cseq) + "\r\n" + extra;
  if (!body.empty()) r += "Content-Length: " + std::to_string(body.size()) + "\r\n";
  return r + "\r\n" + body;
}

const std::string kJpegSdp = "v=0\r\no=- 0 0 IN IP4 127.0.0.1\r\ns=x\r\nt=0 0\r\na=control:*\r\nm=video 0 RTP/AVP 26\r\na=control:stream=0\r\n";

// Runs the client until it reaches backoff (a failure) or time runs out.
std::string run_until_failure(std::uint16_t port, CountingSink& sink, int response_timeout_ms = 1000) {
  RtspClientConfig config;
  config.url = "rtsp://127.0.0.1:" + std::to_string(port) + "/x";
  config.response_timeout_ms = response_timeout_ms;
  auto client = RtspClient::create(config, sink);
  EXPECT_TRUE(client.ok());
  hal::PosixClock clock;
  const hal::Nanos deadline = clock.now() + hal::seconds(5);
  while (clock.now() < deadline && (*client)->state() != ClientState::backoff) {
    (*client)->step(clock.now());
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_EQ((*client)->state(), ClientState::backoff);
  return std::string((*client)->last_error());
}

TEST(HostileServer, HugeContentLength) {
  ScriptedServer server([](const std::string&, std::uint32_t cseq) {
    return "RTSP/1.0 200 OK\r\nCSeq: " + std::to_string(cseq) + "\r\nContent-Length: 99999999999\r\n\r\n";
  });
  CountingSink sink;
  EXPECT_NE(run_until_failure(server.port(), sink).find("Content-Length"), std::string::npos);
}

TEST(HostileServer, HeaderThatNeverEnds) {
  ScriptedServer server([](const std::string&, std::uint32_t) {
    std::string r = "RTSP/1.0 200 OK\r\n";
    while (r.size() < 40000) r += "X-Filler: aaaaaaaaaaaaaaaaaaaaaaaaaaaaaa\r\n";
    return r;  // no blank line, ever
  });
  CountingSink sink;
  EXPECT_NE(run_until_failure(server.port(), sink).find("header"), std::string::npos);
}

TEST(HostileServer, ReplyThatNeverComesTimesOut) {
  ScriptedServer server([](const std::string&, std::uint32_t cseq) {
    return "RTSP/1.0 200 OK\r\nCSeq: " + std::to_string(cseq) + "\r\n";  // header unfinished
  });
  CountingSink sink;
  EXPECT_NE(run_until_failure(server.port(), sink, 300).find("no reply"), std::string::npos);
}

TEST(HostileServer, ClosedMidFrameAndGarbageBetweenFrames) {
  ScriptedServer server([](const std::string& method, std::uint32_t cseq) -> std::string {
    if (method == "DESCRIBE") return ok(cseq, "Content-Base: rtsp://127.0.0.1/x/\r\n", kJpegSdp);
    if (method == "SETUP") return ok(cseq, "Session: s1;timeout=30\r\nTransport: RTP/AVP/TCP;unicast;interleaved=0-1\r\n");
    if (method == "PLAY") {
      std::string r = ok(cseq);
      r += std::string("\x01\x02\x03garbage", 10);  // resynchronised over
      r += std::string("$\x00\x40\x00", 4);           // a 16 KiB frame that is cut short
      r += std::string(100, 'x');
      return r + std::string("\0", 1);  // then the script closes on the next request
    }
    if (method == "OPTIONS") return ok(cseq, "Public: OPTIONS, DESCRIBE, SETUP, PLAY\r\n");
    return "";
  });
  RtspClientConfig config;
  config.url = "rtsp://127.0.0.1:" + std::to_string(server.port()) + "/x";
  config.no_media_timeout_ms = 500;
  CountingSink sink;
  auto client = RtspClient::create(config, sink);
  ASSERT_TRUE(client.ok());
  hal::PosixClock clock;
  const hal::Nanos deadline = clock.now() + hal::seconds(5);
  while (clock.now() < deadline && (*client)->stats().reconnects == 0) {
    (*client)->step(clock.now());
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_GE((*client)->stats().reconnects, 1u);
  EXPECT_GE((*client)->stats().garbage_bytes, 10u);
  EXPECT_EQ(sink.frames, 0);
}

TEST(HostileServer, ServerRequestGets501AndSessionContinues) {
  ScriptedServer server([](const std::string& method, std::uint32_t cseq) -> std::string {
    if (method == "DESCRIBE") return ok(cseq, "", kJpegSdp);
    if (method == "SETUP") return ok(cseq, "Session: s1\r\nTransport: RTP/AVP/TCP;unicast;interleaved=0-1\r\n");
    if (method == "PLAY") return ok(cseq) + "ANNOUNCE rtsp://127.0.0.1/x RTSP/1.0\r\nCSeq: 77\r\n\r\n";
    if (method == "OPTIONS") return ok(cseq);
    return "";
  });
  RtspClientConfig config;
  config.url = "rtsp://127.0.0.1:" + std::to_string(server.port()) + "/x";
  CountingSink sink;
  auto client = RtspClient::create(config, sink);
  ASSERT_TRUE(client.ok());
  hal::PosixClock clock;
  const hal::Nanos deadline = clock.now() + hal::seconds(3);
  while (clock.now() < deadline && (*client)->stats().server_requests == 0) {
    (*client)->step(clock.now());
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_EQ((*client)->stats().server_requests, 1u);
  EXPECT_EQ((*client)->state(), ClientState::playing);
  EXPECT_EQ((*client)->stream().play_url, "rtsp://127.0.0.1:" + std::to_string(server.port()) + "/x");
}

TEST(HostileServer, UnsupportedTransportFallsBackToUdp) {
  // VLC and rtsp-streaming-server refuse TCP with 461: SETUP again over UDP.
  int setups = 0;
  ScriptedServer vlc_like([&setups](const std::string& method, std::uint32_t cseq) -> std::string {
    if (method == "DESCRIBE") return ok(cseq, "", kJpegSdp);
    if (method == "SETUP") {
      if (setups++ == 0) return "RTSP/1.0 461 Unsupported Transport\r\nCSeq: " + std::to_string(cseq) + "\r\n\r\n";
      return ok(cseq, "Session: v1;timeout=60\r\nTransport: RTP/AVP/UDP;unicast;client_port=5000-5001;server_port=6000-6001\r\n");
    }
    return ok(cseq);
  });
  RtspClientConfig config;
  config.url = "rtsp://127.0.0.1:" + std::to_string(vlc_like.port()) + "/x";
  CountingSink sink;
  auto client = RtspClient::create(config, sink);
  ASSERT_TRUE(client.ok());
  hal::PosixClock clock;
  const hal::Nanos deadline = clock.now() + hal::seconds(3);
  while (clock.now() < deadline && (*client)->state() != ClientState::playing) {
    (*client)->step(clock.now());
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  EXPECT_EQ((*client)->state(), ClientState::playing) << (*client)->last_error();
  EXPECT_EQ((*client)->stream().transport, RtpTransport::udp);
  EXPECT_EQ((*client)->stats().transport_fallbacks, 1u);
}

}  // namespace
}  // namespace sen3bot::camera

namespace sen3bot::camera {
namespace {

// rtsp-streaming-server answers GET_PARAMETER with 501 and Thingino with 454-like errors:
// the client must switch to OPTIONS for its keep-alives and keep the session.
TEST(HostileServer, KeepAliveFallsBackToOptionsAfter501) {
  std::atomic<int> get_parameter{0};
  std::atomic<int> options_after_play{0};
  std::atomic<bool> playing{false};
  ScriptedServer server([&](const std::string& method, std::uint32_t cseq) -> std::string {
    if (method == "DESCRIBE") return ok(cseq, "", kJpegSdp);
    if (method == "SETUP") return ok(cseq, "Session: k1;timeout=2\r\nTransport: RTP/AVP/TCP;unicast;interleaved=0-1\r\n");
    if (method == "PLAY") {
      playing = true;
      return ok(cseq);
    }
    if (method == "GET_PARAMETER") {
      ++get_parameter;
      return "RTSP/1.0 501 Not Implemented\r\nCSeq: " + std::to_string(cseq) + "\r\n\r\n";
    }
    if (method == "OPTIONS") {
      if (playing) ++options_after_play;
      return ok(cseq, "Public: OPTIONS, DESCRIBE, SETUP, PLAY, GET_PARAMETER\r\n");
    }
    return "";
  });
  RtspClientConfig config;
  config.url = "rtsp://127.0.0.1:" + std::to_string(server.port()) + "/x";
  config.no_media_timeout_ms = 60000;  // no media in this test; only the keep-alives matter
  CountingSink sink;
  auto client = RtspClient::create(config, sink);
  ASSERT_TRUE(client.ok());
  hal::PosixClock clock;
  const hal::Nanos deadline = clock.now() + hal::millis(3500);
  while (clock.now() < deadline) {
    (*client)->step(clock.now());
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  EXPECT_EQ(get_parameter.load(), 1);  // tried once
  EXPECT_GE(options_after_play.load(), 1);  // then OPTIONS
  EXPECT_EQ((*client)->state(), ClientState::playing);
  EXPECT_EQ((*client)->stats().reconnects, 0u);
}

}  // namespace
}  // namespace sen3bot::camera
