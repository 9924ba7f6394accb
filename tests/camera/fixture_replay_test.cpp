// The recorded real-camera responses (tests/data/camera/rtsp/) replayed by a small fake
// server of ours on 127.0.0.1: the client must send SETUP and PLAY to the URLs those cameras
// expect, and must stay on the one connection it opened whatever hosts the replies name. And
// failures are classified: what retrying cannot cure ends the client for good, on one
// connection; what may pass (503, a dropped connection, no server) keeps it reconnecting.
#include <gtest/gtest.h>

#include <atomic>
#include <chrono>
#include <functional>
#include <map>
#include <mutex>
#include <string>
#include <thread>
#include <vector>

#include "camera_test_util.hpp"
#include "fake_camera.hpp"
#include "sen3bot/camera/rtsp_client.hpp"
#include "sen3bot/camera/rtsp_message.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/tcp.hpp"

namespace sen3bot::camera {
namespace {

using testing::FakeCamera;

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

// Failure classification. Backoff starts at 50 ms and stops doubling at 100 ms, so a client
// that kept retrying would connect at least five times in the 1 s window these tests watch.
constexpr int kWindowMs = 1000;

RtspClientConfig quick_retry_config(std::uint16_t port, const std::string& userinfo = "") {
  RtspClientConfig config;
  config.url = "rtsp://" + userinfo + "127.0.0.1:" + std::to_string(port) + "/stream";
  config.backoff_initial_ms = 50;
  config.backoff_max_ms = 100;
  config.response_timeout_ms = 1000;
  return config;
}

struct Watched {
  bool ever_failed = false;
  std::uint64_t connects = 0;
  std::string last_error;
};

// Steps the client for the whole window, whatever state it reaches. A test of retries passes
// `enough` instead: the client is stepped until it holds (or 20 s go by), so a slow machine
// makes the test take longer, not fail.
Watched watch(RtspClient& client, const std::function<bool()>& enough = {}) {
  hal::PosixClock clock;
  Watched w;
  const hal::Nanos end = clock.now() + hal::millis(enough ? 20'000 : kWindowMs);
  while (clock.now() < end && !(enough && enough())) {
    client.step(clock.now());
    w.ever_failed = w.ever_failed || client.failed();
    std::this_thread::sleep_for(std::chrono::milliseconds(2));
  }
  w.connects = client.stats().connects;
  w.last_error = std::string(client.last_error());
  return w;
}

std::map<std::string, std::string> describe_reply(std::string reply) { return {{"DESCRIBE", std::move(reply)}}; }

std::string as_describe_reply(const std::string& sdp) {
  return "RTSP/1.0 200 OK\r\nCSeq: 1\r\nContent-Type: application/sdp\r\n\r\n" + sdp;
}

TEST(FailureClassification, H265OnlyCamerasAreNamedAndNotRetried) {
  // Anjvision sends an RTSP reply; the TP-Link recording is the SDP alone (H.265, PCMA audio
  // and a vendor track).
  const std::string replies[] = {testing::read_fixture("rtsp/anjvision_describe.txt"),
                                 as_describe_reply(testing::read_fixture("rtsp/tplink_sdp.txt"))};
  for (const std::string& describe : replies) {
    FakeCamera fake(describe_reply(describe));
    NullSink sink;
    auto client = RtspClient::create(quick_retry_config(fake.port()), sink);
    ASSERT_TRUE(client.ok());
    const Watched w = watch(**client);
    EXPECT_EQ((*client)->state(), ClientState::failed) << to_string((*client)->state());
    EXPECT_EQ(w.last_error, "the camera offers only H265 video (rtpmap H265/90000); supported: H264, JPEG");
    EXPECT_EQ(fake.accepted(), 1);
    EXPECT_EQ(w.connects, 1u);
    EXPECT_EQ(fake.count("DESCRIBE"), 1);
    EXPECT_EQ(fake.count("SETUP"), 0);
  }
}

TEST(FailureClassification, AnAudioOnlyCameraHasNoVideoTrack) {
  FakeCamera fake(describe_reply(as_describe_reply("v=0\r\no=- 0 0 IN IP4 127.0.0.1\r\ns=x\r\nt=0 0\r\n"
                                                  "m=audio 0 RTP/AVP 8\r\na=rtpmap:8 PCMA/8000\r\na=control:track2\r\n")));
  NullSink sink;
  auto client = RtspClient::create(quick_retry_config(fake.port()), sink);
  ASSERT_TRUE(client.ok());
  const Watched w = watch(**client);
  EXPECT_EQ((*client)->state(), ClientState::failed) << to_string((*client)->state());
  EXPECT_EQ(w.last_error, "the SDP has no video track (media: audio PCMA/8000)");
  EXPECT_EQ(fake.accepted(), 1);
}

TEST(FailureClassification, RejectedCredentialsAreNotRetried) {
  // Every DESCRIBE, with or without Authorization, gets a fresh Digest challenge.
  FakeCamera fake(describe_reply("RTSP/1.0 401 Unauthorized\r\nCSeq: 1\r\n"
                                "WWW-Authenticate: Digest realm=\"cam\", nonce=\"5e1f\"\r\n\r\n"));
  NullSink sink;
  auto client = RtspClient::create(quick_retry_config(fake.port(), "admin:wrong@"), sink);
  ASSERT_TRUE(client.ok());
  const Watched w = watch(**client);
  EXPECT_EQ((*client)->state(), ClientState::failed) << to_string((*client)->state());
  EXPECT_NE(w.last_error.find("401"), std::string::npos) << w.last_error;
  EXPECT_NE(w.last_error.find("rejected the credentials of user 'admin'"), std::string::npos) << w.last_error;
  EXPECT_EQ(fake.accepted(), 1);
  EXPECT_EQ(fake.count("DESCRIBE"), 2);  // the challenge, then the credentials once
  EXPECT_EQ(fake.authorized(), 1);
}

TEST(FailureClassification, AStaleNonceIsNotARejection) {
  const std::string challenge = "RTSP/1.0 401 Unauthorized\r\nCSeq: 1\r\nWWW-Authenticate: Digest realm=\"cam\", nonce=\"a1\"\r\n\r\n";
  const std::string stale =
      "RTSP/1.0 401 Unauthorized\r\nCSeq: 1\r\nWWW-Authenticate: Digest realm=\"cam\", nonce=\"b2\", stale=true\r\n\r\n";
  {
    // Challenge, stale nonce, then the stream: the client plays.
    FakeCamera fake({{"SETUP", testing::read_fixture("rtsp/hikvision_setup.txt")},
                     {"PLAY", testing::read_fixture("rtsp/hikvision_play.txt")}});
    fake.set_sequence("DESCRIBE", {challenge, stale, testing::read_fixture("rtsp/hikvision_describe.txt")});
    NullSink sink;
    auto client = RtspClient::create(quick_retry_config(fake.port(), "admin:secret@"), sink);
    ASSERT_TRUE(client.ok());
    const Watched w = watch(**client);
    EXPECT_EQ((*client)->state(), ClientState::playing) << to_string((*client)->state()) << ": " << w.last_error;
    EXPECT_EQ((*client)->stats().auth_retries, 2u);
    EXPECT_EQ(fake.count("DESCRIBE"), 3);
    EXPECT_EQ(fake.accepted(), 1);
  }
  {
    // Stale again after the stale retry: that is a rejection.
    FakeCamera fake(describe_reply(""));
    fake.set_sequence("DESCRIBE", {challenge, stale});
    NullSink sink;
    auto client = RtspClient::create(quick_retry_config(fake.port(), "admin:secret@"), sink);
    ASSERT_TRUE(client.ok());
    const Watched w = watch(**client);
    EXPECT_EQ((*client)->state(), ClientState::failed) << to_string((*client)->state());
    EXPECT_NE(w.last_error.find("rejected the credentials"), std::string::npos) << w.last_error;
    EXPECT_EQ(fake.count("DESCRIBE"), 3);
    EXPECT_EQ(fake.accepted(), 1);
  }
}

TEST(FailureClassification, AuthenticationWithoutCredentialsIsNotRetried) {
  FakeCamera fake(describe_reply("RTSP/1.0 401 Unauthorized\r\nCSeq: 1\r\nWWW-Authenticate: Basic realm=\"cam\"\r\n\r\n"));
  NullSink sink;
  auto client = RtspClient::create(quick_retry_config(fake.port()), sink);
  ASSERT_TRUE(client.ok());
  const Watched w = watch(**client);
  EXPECT_EQ((*client)->state(), ClientState::failed) << to_string((*client)->state());
  EXPECT_NE(w.last_error.find("none are configured"), std::string::npos) << w.last_error;
  EXPECT_EQ(fake.accepted(), 1);
  EXPECT_EQ(fake.authorized(), 0);
}

TEST(FailureClassification, AStreamThatDoesNotExistIsNotRetried) {
  FakeCamera fake(describe_reply("RTSP/1.0 404 Stream Not Found\r\nCSeq: 1\r\n\r\n"));
  NullSink sink;
  auto client = RtspClient::create(quick_retry_config(fake.port()), sink);
  ASSERT_TRUE(client.ok());
  const Watched w = watch(**client);
  EXPECT_EQ((*client)->state(), ClientState::failed) << to_string((*client)->state());
  EXPECT_NE(w.last_error.find("404 Stream Not Found"), std::string::npos) << w.last_error;
  EXPECT_NE(w.last_error.find("/stream"), std::string::npos) << w.last_error;
  EXPECT_EQ(fake.accepted(), 1);
}

TEST(FailureClassification, AnOverloadedCameraIsRetried) {
  FakeCamera fake(describe_reply("RTSP/1.0 503 Service Unavailable\r\nCSeq: 1\r\n\r\n"));
  NullSink sink;
  auto client = RtspClient::create(quick_retry_config(fake.port()), sink);
  ASSERT_TRUE(client.ok());
  const Watched w = watch(**client, [&] { return fake.accepted() >= 5 && (*client)->stats().connects >= 5; });
  EXPECT_FALSE(w.ever_failed) << w.last_error;
  EXPECT_GE(fake.accepted(), 5);
  EXPECT_GE(w.connects, 5u);
  EXPECT_NE(w.last_error.find("503 Service Unavailable"), std::string::npos) << w.last_error;
}

TEST(FailureClassification, ADroppedConnectionIsRetried) {
  // The camera closes the connection on DESCRIBE (a reboot, a Wi-Fi drop at its end).
  FakeCamera fake(describe_reply(""));
  NullSink sink;
  auto client = RtspClient::create(quick_retry_config(fake.port()), sink);
  ASSERT_TRUE(client.ok());
  const Watched w = watch(**client, [&] { return fake.accepted() >= 5 && fake.count("DESCRIBE") >= 5; });
  EXPECT_FALSE(w.ever_failed) << w.last_error;
  EXPECT_GE(fake.accepted(), 5);
  EXPECT_GE(fake.count("DESCRIBE"), 5);
}

TEST(FailureClassification, NoServerAtAllIsRetried) {
  std::uint16_t port = 0;
  {
    auto listener = hal::TcpListener::listen("127.0.0.1", 0);
    ASSERT_TRUE(listener.ok());
    port = (*listener)->port();
  }  // closed: connecting is refused
  NullSink sink;
  auto client = RtspClient::create(quick_retry_config(port), sink);
  ASSERT_TRUE(client.ok());
  const Watched w = watch(**client, [&] { return (*client)->stats().reconnects >= 5; });
  EXPECT_FALSE(w.ever_failed) << w.last_error;
  EXPECT_EQ((*client)->state(), ClientState::backoff);
  EXPECT_GE((*client)->stats().reconnects, 5u);
}

}  // namespace
}  // namespace sen3bot::camera
