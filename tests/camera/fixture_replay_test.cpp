// The recorded real-camera responses (tests/data/camera/rtsp/) replayed by a small fake
// server of ours on 127.0.0.1: the client must send SETUP and PLAY to the URLs those cameras
// expect, and must stay on the one connection it opened whatever hosts the replies name.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "camera_test_util.hpp"
#include "sen3bot/camera/rtsp_client.hpp"
#include "sen3bot/camera/rtsp_message.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/tcp.hpp"

namespace sen3bot::camera {
namespace {

// Puts the request's CSeq into a recorded reply and makes Content-Length match the body.
std::string adapt_reply(const std::string& recorded, std::uint32_t cseq) {
  const std::size_t split = recorded.find("\r\n\r\n");
  const std::string head = recorded.substr(0, split);
  const std::string body = split == std::string::npos ? "" : recorded.substr(split + 4);
  std::string out;
  std::size_t pos = 0;
  while (pos < head.size()) {
    std::size_t eol = head.find("\r\n", pos);
    if (eol == std::string::npos) eol = head.size();
    const std::string line = head.substr(pos, eol - pos);
    pos = eol + 2;
    const std::string lower = [&] {
      std::string l = line.substr(0, line.find(':'));
      for (char& c : l) c = static_cast<char>(std::tolower(static_cast<unsigned char>(c)));
      return l;
    }();
    if (lower == "cseq" || lower == "content-length") continue;
    out += line + "\r\n";
  }
  out += "CSeq: " + std::to_string(cseq) + "\r\n";
  if (!body.empty()) out += "Content-Length: " + std::to_string(body.size()) + "\r\n";
  return out + "\r\n" + body;
}

class FakeCamera {
 public:
  explicit FakeCamera(std::map<std::string, std::string> replies) : replies_(std::move(replies)) {
    auto listener = hal::TcpListener::listen("127.0.0.1", 0);
    EXPECT_TRUE(listener.ok());
    listener_ = std::move(*listener);
    thread_ = std::thread([this] { run(); });
  }
  ~FakeCamera() {
    stop_ = true;
    thread_.join();
  }
  std::uint16_t port() const { return listener_->port(); }
  std::vector<std::string> requests() {
    std::lock_guard lock(mutex_);
    return requests_;
  }
  int accepted() const { return accepted_.load(); }

 private:
  void run() {
    std::vector<std::unique_ptr<hal::TcpStream>> clients;
    std::string buf;
    while (!stop_) {
      if (auto s = listener_->accept(); s && *s) {
        ++accepted_;
        clients.push_back(std::move(*s));
      }
      for (auto& c : clients) {
        std::uint8_t tmp[4096];
        auto n = c->read(tmp);
        if (!n || *n == 0) continue;
        buf.append(reinterpret_cast<const char*>(tmp), *n);
        std::size_t consumed = 0;
        while (true) {
          auto msg = parse_message(buf, &consumed);
          if (!msg) break;
          const std::string method(msg->method);
          {
            std::lock_guard lock(mutex_);
            requests_.push_back(method + " " + std::string(msg->uri));
          }
          std::string reply;
          if (auto it = replies_.find(method); it != replies_.end()) {
            reply = adapt_reply(it->second, msg->cseq().value_or(0));
          } else {
            reply = "RTSP/1.0 200 OK\r\nCSeq: " + std::to_string(msg->cseq().value_or(0)) +
                    "\r\nPublic: OPTIONS, DESCRIBE, SETUP, PLAY, TEARDOWN\r\n\r\n";
          }
          (void)c->write(std::span(reinterpret_cast<const std::uint8_t*>(reply.data()), reply.size()));
          buf.erase(0, consumed);
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
  }

  std::map<std::string, std::string> replies_;
  std::unique_ptr<hal::TcpListener> listener_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
  std::atomic<int> accepted_{0};
  std::mutex mutex_;
  std::vector<std::string> requests_;
};

struct NullSink : EncodedFrameSink {
  void on_frame(const EncodedFrame&) override {}
};

struct Case {
  const char* name;
  const char* path;
  const char* describe;
  const char* setup;
  const char* play;
  RtpTransport transport;
  const char* expected_setup;  // %P = the fake server's port
  const char* expected_play;
};

std::string with_port(std::string s, std::uint16_t port) {
  if (const std::size_t at = s.find("%P"); at != std::string::npos) s.replace(at, 2, std::to_string(port));
  return s;
}

TEST(FixtureReplay, SetupAndPlayUrlsMatchWhatEachCameraExpects) {
  const Case cases[] = {
      {"hikvision", "/Streaming/Channels/101", "hikvision_describe.txt", "hikvision_setup.txt", "hikvision_play.txt",
       RtpTransport::tcp_interleaved,
       "rtsp://192.168.5.106:554/Streaming/Channels/101/trackID=1?transportmode=unicast&profile=Profile_1",
       "rtsp://192.168.5.106:554/Streaming/Channels/101/?transportmode=unicast&profile=Profile_1"},
      {"wowza", "/vod/mp4:BigBuckBunny_115k.mov", "bunny_describe.txt", "bunny_setup.txt", "bunny_play.txt",
       RtpTransport::tcp_interleaved, "rtsp://wowzaec2demo.streamlock.net/vod/mp4:BigBuckBunny_115k.mov/trackID=2",
       "rtsp://wowzaec2demo.streamlock.net/vod/mp4:BigBuckBunny_115k.mov/"},
      {"wowza bad rtptime", "/vod/x", "bunny_describe.txt", "bunny_setup.txt", "bad_rtptime.txt",
       RtpTransport::tcp_interleaved, "rtsp://wowzaec2demo.streamlock.net/vod/mp4:BigBuckBunny_115k.mov/trackID=2",
       "rtsp://wowzaec2demo.streamlock.net/vod/mp4:BigBuckBunny_115k.mov/"},
      {"h264dvr", "/camera", "h264dvr_describe.txt", "h264dvr_setup_video.txt", "h264dvr_play.txt", RtpTransport::udp,
       "rtsp://127.0.0.1:554/camera/trackID=3", "rtsp://127.0.0.1:554/camera"},
      {"foscam", "/videoMain", "foscam_describe.txt", "hikvision_setup.txt", "hikvision_play.txt",
       RtpTransport::tcp_interleaved, "rtsp://192.168.5.107:65534/videoMain/track1", "rtsp://192.168.5.107:65534/videoMain/"},
      // No Content-Base, no Content-Type, no session control: concatenate, PLAY the request URL.
      {"no content type", "/live", "missing_content_type_describe.txt", "hikvision_setup.txt", "hikvision_play.txt",
       RtpTransport::tcp_interleaved, "rtsp://127.0.0.1:%P/live/streamid=0", "rtsp://127.0.0.1:%P/live"},
  };
  for (const Case& c : cases) {
    FakeCamera fake({{"DESCRIBE", testing::read_fixture(std::string("rtsp/") + c.describe)},
                     {"SETUP", testing::read_fixture(std::string("rtsp/") + c.setup)},
                     {"PLAY", testing::read_fixture(std::string("rtsp/") + c.play)}});
    RtspClientConfig config;
    config.url = "rtsp://127.0.0.1:" + std::to_string(fake.port()) + c.path;
    config.transport = c.transport;
    config.transport_fallback = false;
    NullSink sink;
    auto client = RtspClient::create(config, sink);
    ASSERT_TRUE(client.ok());
    hal::PosixClock clock;
    const hal::Nanos deadline = clock.now() + hal::seconds(5);
    while (clock.now() < deadline && (*client)->state() != ClientState::playing) {
      (*client)->step(clock.now());
      std::this_thread::sleep_for(std::chrono::milliseconds(2));
    }
    EXPECT_EQ((*client)->state(), ClientState::playing) << c.name << ": " << (*client)->last_error();
    const auto requests = fake.requests();
    const std::string expected_setup = "SETUP " + with_port(c.expected_setup, fake.port());
    const std::string expected_play = "PLAY " + with_port(c.expected_play, fake.port());
    EXPECT_NE(std::find(requests.begin(), requests.end(), expected_setup), requests.end()) << c.name;
    EXPECT_NE(std::find(requests.begin(), requests.end(), expected_play), requests.end()) << c.name;
    EXPECT_EQ(fake.accepted(), 1) << c.name;
    EXPECT_EQ((*client)->stats().connects, 1u) << c.name;
    (*client)->stop(clock.now());
  }
}

TEST(FixtureReplay, H265OnlyCameraIsAClearError) {
  FakeCamera fake({{"DESCRIBE", testing::read_fixture("rtsp/anjvision_describe.txt")}});
  RtspClientConfig config;
  config.url = "rtsp://127.0.0.1:" + std::to_string(fake.port()) + "/h265";
  NullSink sink;
  auto client = RtspClient::create(config, sink);
  ASSERT_TRUE(client.ok());
  hal::PosixClock clock;
  const hal::Nanos deadline = clock.now() + hal::seconds(3);
  while (clock.now() < deadline && (*client)->state() != ClientState::backoff) {
    (*client)->step(clock.now());
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  EXPECT_EQ((*client)->state(), ClientState::backoff);
  EXPECT_NE((*client)->last_error().find("no H.264 or JPEG"), std::string::npos) << (*client)->last_error();
}

}  // namespace
}  // namespace sen3bot::camera
