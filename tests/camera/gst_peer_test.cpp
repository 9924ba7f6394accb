// Our client against Debian's gst-rtsp-server (tests/camera/peers/rtsp_server.py), started
// here on 127.0.0.1: H.264 (incl. 1280x720 with FU-A) and MJPEG types 0/1, TCP and UDP,
// Basic and Digest auth, session expiry and keep-alive, and ffprobe as a cross-check.
#include <gtest/gtest.h>

#include <array>
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <thread>

#include <unistd.h>

#include "peer_process.hpp"
#include "udp_impair_proxy.hpp"
#include "sen3bot/camera/camera.hpp"

namespace sen3bot::camera {
namespace {

using testing::PeerProcess;

const std::string kServerScript = std::string(SEN3BOT_SOURCE_DIR) + "/tests/camera/peers/rtsp_server.py";
// The system interpreter has python3-gi; a pyenv one on PATH may not.
const std::string kPython = "/usr/bin/python3";

[[maybe_unused]] std::unique_ptr<PeerProcess> start_server(std::vector<std::string> extra = {}) {
  std::vector<std::string> args = {kServerScript};
  args.insert(args.end(), extra.begin(), extra.end());
  auto peer = std::make_unique<PeerProcess>(kPython, args);
  EXPECT_TRUE(peer->ready()) << peer->error();
  return peer;
}

[[maybe_unused]] std::string url(const PeerProcess& peer, const std::string& path, const std::string& userinfo = "") {
  return "rtsp://" + userinfo + "127.0.0.1:" + std::to_string(peer.port()) + path;
}

struct RunResult {
  CameraStatus status;
  std::uint64_t frames = 0;
  std::uint32_t width_px = 0;
  std::uint32_t height_px = 0;
  bool pixels_nonzero = false;
};

[[maybe_unused]] RunResult run_camera(CameraConfig config, std::uint64_t want_frames, int timeout_ms) {
  hal::PosixClock clock;
  auto camera = Camera::create(std::move(config), clock);
  EXPECT_TRUE(camera.ok()) << camera.error().message();
  RunResult result;
  if (!camera) return result;
  EXPECT_TRUE((*camera)->start().ok());
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::milliseconds(timeout_ms);
  while (std::chrono::steady_clock::now() < deadline && (*camera)->frames().latest_sequence() < want_frames) {
    std::this_thread::sleep_for(std::chrono::milliseconds(20));
  }
  if (FrameHandle frame = (*camera)->frames().acquire_latest()) {
    result.frames = frame.ref().sequence;
    result.width_px = frame.ref().width_px;
    result.height_px = frame.ref().height_px;
    const std::size_t bytes = std::size_t{frame.ref().stride_bytes} * frame.ref().height_px;
    for (std::size_t i = 0; i < bytes && !result.pixels_nonzero; i += 97) result.pixels_nonzero = frame.ref().data[i] != 0;
  }
  result.status = (*camera)->status();
  (*camera)->stop();
  return result;
}

[[maybe_unused]] CameraConfig config_for(const std::string& rtsp_url, RtpTransport transport = RtpTransport::tcp_interleaved) {
  CameraConfig c;
  c.rtsp.url = rtsp_url;
  c.rtsp.transport = transport;
  return c;
}

#if !defined(SEN3BOT_CAMERA_SLOW_TESTS)
TEST(GstPeer, H264OverTcp) {
  auto peer = start_server();
  ASSERT_TRUE(peer->ready());
  const auto r = run_camera(config_for(url(*peer, "/h264")), 20, 20000);
  EXPECT_GE(r.frames, 20u) << r.status.last_error;
  EXPECT_EQ(r.width_px, 640u);
  EXPECT_EQ(r.height_px, 360u);
  EXPECT_TRUE(r.pixels_nonzero);
  EXPECT_EQ(r.status.stream.codec, VideoCodec::h264);
  EXPECT_EQ(r.status.stream.setup_url, url(*peer, "/h264/stream=0"));
  EXPECT_EQ(r.status.stream.play_url, url(*peer, "/h264/"));
  EXPECT_EQ(r.status.decoder.decode_errors, 0u);
  EXPECT_EQ(r.status.rtsp.rtp_lost, 0u);
}

TEST(GstPeer, H264At1280x720WithFuAOverTcp) {
  auto peer = start_server();
  ASSERT_TRUE(peer->ready());
  const auto r = run_camera(config_for(url(*peer, "/h264_fua")), 15, 25000);
  EXPECT_GE(r.frames, 15u) << r.status.last_error;
  EXPECT_EQ(r.width_px, 1280u);
  EXPECT_EQ(r.height_px, 720u);
  EXPECT_EQ(r.status.decoder.decode_errors, 0u);
}

TEST(GstPeer, H264At1280x720OverUdpWithLargeBuffer) {
  auto peer = start_server();
  ASSERT_TRUE(peer->ready());
  const auto r = run_camera(config_for(url(*peer, "/h264_fua"), RtpTransport::udp), 15, 25000);
  EXPECT_GE(r.frames, 15u) << r.status.last_error;
  EXPECT_EQ(r.status.stream.transport, RtpTransport::udp);
  EXPECT_EQ(r.width_px, 1280u);
  // With 4 MiB of SO_RCVBUF the I-frame bursts fit (0 lost in 3 of 3 runs in the brief);
  // Linux's default 208 KiB lost packets in 2 of 3.
  EXPECT_EQ(r.status.rtsp.rtp_lost, 0u);
  EXPECT_EQ(r.status.decoder.decode_errors, 0u);
}

TEST(GstPeer, MjpegType1And0OverTcpAndUdp) {
  auto peer = start_server();
  ASSERT_TRUE(peer->ready());
  for (const char* mount : {"/mjpeg", "/mjpeg422"}) {
    for (RtpTransport t : {RtpTransport::tcp_interleaved, RtpTransport::udp}) {
      const auto r = run_camera(config_for(url(*peer, mount), t), 15, 20000);
      EXPECT_GE(r.frames, 15u) << mount << " " << to_string(t) << ": " << r.status.last_error;
      EXPECT_EQ(r.width_px, 640u) << mount;
      EXPECT_EQ(r.height_px, 360u) << mount;
      EXPECT_EQ(r.status.stream.codec, VideoCodec::jpeg);
      EXPECT_EQ(r.status.decoder.decode_errors, 0u) << mount;
    }
  }
}

// JPEG type 65: restart markers (DRI), from JPEGs made by cjpeg -restart, as the brief's peer.
TEST(GstPeer, MjpegType65WithRestartMarkers) {
  const std::string dir = "/tmp/sen3bot_camera_dri_" + std::to_string(::getpid());
  const std::string make =
      "set -e; mkdir -p " + dir + " && cd " + dir +
      " && ffmpeg -v error -y -f lavfi -i testsrc=size=640x352:rate=15 -frames:v 15 -pix_fmt rgb24 -f image2 f%03d.ppm"
      " && for f in f*.ppm; do cjpeg -quality 75 -sample 2x2 -restart 4 -outfile ${f%.ppm}.jpg $f; done"
      " && ffmpeg -v error -y -stream_loop 20 -framerate 15 -i f%03d.jpg -c copy dri.mkv";
  ASSERT_EQ(std::system(make.c_str()), 0) << "needs ffmpeg and cjpeg (libjpeg-turbo-progs)";
  auto peer = start_server({"--dri-file", dir + "/dri.mkv"});
  ASSERT_TRUE(peer->ready());
  const auto r = run_camera(config_for(url(*peer, "/mjpeg_dri")), 10, 20000);
  EXPECT_GE(r.frames, 10u) << r.status.last_error;
  EXPECT_EQ(r.width_px, 640u);
  EXPECT_EQ(r.height_px, 352u);
  EXPECT_EQ(r.status.decoder.decode_errors, 0u);
  (void)std::system(("rm -rf " + dir).c_str());
}

TEST(GstPeer, GreyAndDownscaledOutput) {
  auto peer = start_server();
  ASSERT_TRUE(peer->ready());
  CameraConfig c = config_for(url(*peer, "/h264_fua"));
  c.format = PixelFormat::gray8;
  c.downscale = 2;
  const auto r = run_camera(c, 5, 20000);
  EXPECT_GE(r.frames, 5u);
  EXPECT_EQ(r.width_px, 640u);
  EXPECT_EQ(r.height_px, 360u);
}

TEST(GstPeer, DigestAndBasicAuth) {
  for (const char* mode : {"digest", "basic"}) {
    auto peer = start_server({"--auth", mode});
    ASSERT_TRUE(peer->ready());
    const auto ok = run_camera(config_for(url(*peer, "/mjpeg", "admin:secret@")), 5, 15000);
    EXPECT_GE(ok.frames, 5u) << mode << ": " << ok.status.last_error;
    EXPECT_GE(ok.status.rtsp.auth_retries, 1u);
    CameraConfig wrong = config_for(url(*peer, "/mjpeg", "admin:nope@"));
    const auto bad = run_camera(wrong, 1, 1500);
    EXPECT_EQ(bad.frames, 0u) << mode;
    EXPECT_NE(bad.status.last_error.find("401"), std::string::npos) << mode << ": " << bad.status.last_error;
    // Rejected credentials will be rejected again: one connection, then the client gives up.
    EXPECT_TRUE(bad.status.failed()) << mode << ": " << to_string(bad.status.state);
    EXPECT_NE(bad.status.last_error.find("rejected the credentials of user 'admin'"), std::string::npos)
        << mode << ": " << bad.status.last_error;
    EXPECT_EQ(bad.status.rtsp.connects, 1u) << mode;
    EXPECT_EQ(bad.status.rtsp.reconnects, 0u) << mode;
  }
}

TEST(GstPeer, SessionExpiresWithoutKeepAliveAndTheClientReconnects) {
  auto peer = start_server({"--session-timeout", "2"});
  ASSERT_TRUE(peer->ready());
  // Over UDP, as seen on the wire here: with nothing from the client the server expires
  // the session (timeout + its 5 s grace) and stops sending.
  CameraConfig c = config_for(url(*peer, "/mjpeg"), RtpTransport::udp);
  c.rtsp.keepalive = false;
  c.rtsp.no_media_timeout_ms = 1500;
  hal::PosixClock clock;
  auto camera = Camera::create(c, clock);
  ASSERT_TRUE(camera.ok());
  ASSERT_TRUE((*camera)->start().ok());
  const auto deadline = std::chrono::steady_clock::now() + std::chrono::seconds(20);
  while (std::chrono::steady_clock::now() < deadline && (*camera)->status().rtsp.reconnects == 0) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  const auto status = (*camera)->status();
  EXPECT_GE(status.rtsp.reconnects, 1u);
  EXPECT_EQ(status.stream.session_timeout_s, 2);
  // And it plays again after reconnecting.
  const std::uint64_t before = (*camera)->frames().latest_sequence();
  const auto again = std::chrono::steady_clock::now() + std::chrono::seconds(10);
  while (std::chrono::steady_clock::now() < again && (*camera)->frames().latest_sequence() < before + 5) {
    std::this_thread::sleep_for(std::chrono::milliseconds(50));
  }
  EXPECT_GE((*camera)->frames().latest_sequence(), before + 5);
}

#endif

#if defined(SEN3BOT_CAMERA_SLOW_TESTS)
// Slow: keep-alive holds a 10 s-timeout session for 30 s without a reconnect.
TEST(GstPeerSlow, KeepAliveHoldsAShortSessionFor30Seconds) {
  auto peer = start_server({"--session-timeout", "10"});
  ASSERT_TRUE(peer->ready());
  CameraConfig c = config_for(url(*peer, "/mjpeg"));
  c.rtsp.no_media_timeout_ms = 3000;
  hal::PosixClock clock;
  auto camera = Camera::create(c, clock);
  ASSERT_TRUE(camera.ok());
  ASSERT_TRUE((*camera)->start().ok());
  std::this_thread::sleep_for(std::chrono::seconds(30));
  const auto status = (*camera)->status();
  EXPECT_EQ(status.rtsp.reconnects, 0u) << status.last_error;
  EXPECT_EQ(status.rtsp.connects, 1u);
  EXPECT_GE(status.rtsp.keepalives_sent, 5u);
  EXPECT_GE(status.rtsp.receiver_reports_sent, 5u);
  EXPECT_EQ(status.state, ClientState::playing);
  // 15 fps for 30 s; allow for start-up.
  EXPECT_GE((*camera)->frames().latest_sequence(), 350u);
}
#else

[[maybe_unused]] std::string run_ffprobe(const std::string& rtsp_url) {
  const std::string cmd = "timeout 20 ffprobe -v error -rtsp_transport tcp -show_entries stream=codec_name,width,height "
                          "-of compact=p=0:nk=1 '" + rtsp_url + "'";
  std::string out;
  FILE* pipe = ::popen(cmd.c_str(), "r");
  if (pipe == nullptr) return out;
  std::array<char, 256> buf{};
  while (std::fgets(buf.data(), buf.size(), pipe) != nullptr) out += buf.data();
  ::pclose(pipe);
  while (!out.empty() && (out.back() == '\n' || out.back() == '\r')) out.pop_back();
  return out;
}

// Loss, duplicates and reordering between server and client: no crash, loss counted, frames
// with holes dropped, and decoding resumes at the next IDR.
TEST(GstPeer, H264OverUdpThroughALossyProxy) {
  auto peer = start_server();
  ASSERT_TRUE(peer->ready());
  testing::UdpImpairProxy proxy(peer->port(), testing::Impairment{});
  CameraConfig c = config_for("rtsp://127.0.0.1:" + std::to_string(proxy.port()) + "/h264", RtpTransport::udp);
  c.rtsp.transport_fallback = false;
  const auto r = run_camera(c, 40, 20000);
  EXPECT_GE(r.frames, 40u) << r.status.last_error;
  EXPECT_GT(proxy.dropped.load(), 0u);
  EXPECT_GT(proxy.duplicated.load(), 0u);
  EXPECT_GT(proxy.swapped.load(), 0u);
  EXPECT_GT(r.status.rtsp.rtp_lost, 0u);
  EXPECT_GT(r.status.rtsp.rtp_late_or_duplicate, 0u);
  EXPECT_GT(r.status.depacketizer.frames_dropped_damaged + r.status.depacketizer.frames_dropped_no_idr, 0u);
  EXPECT_EQ(r.status.rtsp.reconnects, 0u);
}

TEST(GstPeer, FfprobeAgreesOnCodecAndSize) {
  auto peer = start_server();
  ASSERT_TRUE(peer->ready());
  for (const char* mount : {"/h264_fua", "/mjpeg"}) {
    const std::string reference = run_ffprobe(url(*peer, mount));
    ASSERT_FALSE(reference.empty()) << "ffprobe gave no answer for " << mount;
    const auto r = run_camera(config_for(url(*peer, mount)), 3, 15000);
    const std::string ours = std::string(to_string(r.status.stream.codec)) + "|" + std::to_string(r.status.decoder.source_width_px) +
                             "|" + std::to_string(r.status.decoder.source_height_px);
    EXPECT_EQ(ours, reference) << mount;
  }
}

#endif

}  // namespace
}  // namespace sen3bot::camera
