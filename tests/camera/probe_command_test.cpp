// `sen3bot camera probe` run through its command function (firmware/cmd_camera.cpp), as the
// robot's command line runs it: against Debian's gst-rtsp-server, against a recorded GStreamer
// session replayed in one burst, and against a fake camera that offers only H.265.
#include <gtest/gtest.h>

#include <chrono>
#include <cstdio>
#include <string>
#include <thread>
#include <vector>

#include "commands.hpp"
#include "camera_test_util.hpp"
#include "fake_camera.hpp"
#include "pcap_io.hpp"
#include "peer_process.hpp"
#include "sen3bot/camera/rtsp_message.hpp"
#include "sen3bot/hal/tcp.hpp"

namespace sen3bot::camera {
namespace {

struct ProbeRun {
  int exit_code = -1;
  std::string out;
  std::string err;
  double seconds = 0;
};

std::string read_back(std::FILE* f) {
  std::fflush(f);
  std::rewind(f);
  std::string text;
  char buf[4096];
  while (std::size_t n = std::fread(buf, 1, sizeof buf, f)) text.append(buf, n);
  std::fclose(f);
  return text;
}

ProbeRun probe(std::vector<std::string> args) {
  args.insert(args.begin(), "probe");
  std::vector<char*> argv;
  for (std::string& a : args) argv.push_back(a.data());
  std::FILE* out = std::tmpfile();
  std::FILE* err = std::tmpfile();
  ProbeRun run;
  const auto start = std::chrono::steady_clock::now();
  run.exit_code = firmware::camera_command(static_cast<int>(argv.size()), argv.data(), out, err);
  run.seconds = std::chrono::duration<double>(std::chrono::steady_clock::now() - start).count();
  run.out = read_back(out);
  run.err = read_back(err);
  return run;
}

// The number after "key": in the probe's summary line, or -1.
long long json_number(const std::string& text, const std::string& key) {
  const std::string needle = "\"" + key + "\":";
  const std::size_t at = text.rfind(needle);
  if (at == std::string::npos) return -1;
  return std::stoll(text.substr(at + needle.size()));
}

TEST(ProbeCommand, DecodesExactlyTheFramesAskedForFromGstreamer) {
  testing::PeerProcess peer("/usr/bin/python3", {SEN3BOT_SOURCE_DIR "/tests/camera/peers/rtsp_server.py"});
  ASSERT_TRUE(peer.ready()) << peer.error();
  for (const char* path : {"/h264", "/mjpeg"}) {
    for (const char* transport : {"tcp", "udp"}) {
      const std::string url = "rtsp://127.0.0.1:" + std::to_string(peer.port()) + path;
      const ProbeRun run = probe({url, "--transport", transport, "--frames", "30", "--timeout", "20"});
      EXPECT_EQ(run.exit_code, 0) << path << " " << transport << ": " << run.err;
      EXPECT_EQ(json_number(run.out, "frames_decoded"), 30) << path << " " << transport << ": " << run.out;
      EXPECT_NE(run.out.find("\"event\":\"playing\""), std::string::npos) << run.out;
    }
  }
}

// Replays the server's side of tests/data/camera/capture/gst_h264_tcp.pcap (43 frames): each
// request gets the next recorded reply, and after the reply to PLAY every recorded frame is
// sent at once, so the client decodes many frames in one pass.
class BurstServer {
 public:
  BurstServer() {
    EXPECT_TRUE(testing::read_pcap_server_stream(
        std::string(SEN3BOT_SOURCE_DIR) + "/tests/data/camera/capture/gst_h264_tcp.pcap", stream_));
    std::size_t pos = 0;
    while (pos < stream_.size()) {
      auto item = demux_next(std::span<const std::uint8_t>(stream_.data() + pos, stream_.size() - pos));
      if (!item || item->kind == DemuxKind::need_more) break;
      pos += item->consumed;
      if (item->kind == DemuxKind::message) reply_ends_.push_back(pos);
    }
    auto listener = hal::TcpListener::listen("127.0.0.1", 0);
    EXPECT_TRUE(listener.ok());
    listener_ = std::move(*listener);
    thread_ = std::thread([this] { run(); });
  }
  ~BurstServer() {
    stop_ = true;
    thread_.join();
  }
  [[nodiscard]] std::uint16_t port() const { return listener_->port(); }
  [[nodiscard]] std::size_t replies() const { return reply_ends_.size(); }

 private:
  void run() {
    std::unique_ptr<hal::TcpStream> client;
    std::string buf;
    std::size_t sent = 0;
    std::size_t answered = 0;
    while (!stop_) {
      if (auto s = listener_->accept(); s && *s && !client) client = std::move(*s);
      if (client) {
        std::uint8_t tmp[4096];
        auto n = client->read(tmp);
        if (n && *n > 0) buf.append(reinterpret_cast<const char*>(tmp), *n);
        std::size_t end = 0;
        while ((end = buf.find("\r\n\r\n")) != std::string::npos) {
          buf.erase(0, end + 4);
          if (answered >= reply_ends_.size()) continue;  // keep-alive, TEARDOWN: the recording is over
          ++answered;
          const std::size_t until = answered == reply_ends_.size() ? stream_.size() : reply_ends_[answered - 1];
          while (sent < until) {
            auto w = client->write(std::span<const std::uint8_t>(stream_.data() + sent, until - sent));
            if (!w) return;
            sent += *w;
            if (*w == 0) std::this_thread::sleep_for(std::chrono::milliseconds(1));
          }
        }
      }
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
  }

  std::vector<std::uint8_t> stream_;
  std::vector<std::size_t> reply_ends_;  // offset after each recorded reply
  std::unique_ptr<hal::TcpListener> listener_;
  std::thread thread_;
  std::atomic<bool> stop_{false};
};

TEST(ProbeCommand, DecodesExactlyTheFramesAskedForWhenTheyArriveInABurst) {
  BurstServer server;
  ASSERT_EQ(server.replies(), 4u);  // OPTIONS, DESCRIBE, SETUP, PLAY
  const std::string url = "rtsp://127.0.0.1:" + std::to_string(server.port()) + "/h264";
  const ProbeRun run = probe({url, "--frames", "30", "--timeout", "10"});
  EXPECT_EQ(run.exit_code, 0) << run.err;
  EXPECT_EQ(json_number(run.out, "frames_decoded"), 30) << run.out;
  EXPECT_NE(run.out.find("{\"event\":\"playing\",\"codec\":\"h264\""), std::string::npos) << run.out;
}

TEST(ProbeCommand, AnH265OnlyCameraEndsTheProbeAtOnceNamingTheCodec) {
  testing::FakeCamera fake({{"DESCRIBE", testing::read_fixture("rtsp/anjvision_describe.txt")}});
  const std::string url = "rtsp://127.0.0.1:" + std::to_string(fake.port()) + "/stream0";
  const ProbeRun run = probe({url, "--frames", "30", "--timeout", "20"});
  EXPECT_EQ(run.exit_code, 1);
  EXPECT_NE(run.err.find("the camera offers only H265 video (rtpmap H265/90000); supported: H264, JPEG (not retrying)"),
            std::string::npos)
      << run.err;
  EXPECT_LT(run.seconds, 2.0);  // not the 20 s timeout
  EXPECT_EQ(fake.accepted(), 1);
  EXPECT_EQ(json_number(run.out, "frames_decoded"), 0) << run.out;
}

TEST(ProbeCommand, FramesMustBeAWholeNumber) {
  const ProbeRun run = probe({"rtsp://127.0.0.1:9/x", "--frames", "2.5"});
  EXPECT_EQ(run.exit_code, 2);
  EXPECT_NE(run.err.find("--frames needs a whole number"), std::string::npos) << run.err;
}

}  // namespace
}  // namespace sen3bot::camera
