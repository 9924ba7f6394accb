// Camera decode throughput and latency. Records encoded frames from an RTSP source (the
// GStreamer test peer, started here unless --url is given), then decodes them repeatedly
// into the frame pool and prints one JSON line per stream:
//   camera_bench [--url rtsp://...] [--frames N] [--repeat R]
#include <chrono>
#include <cstdio>
#include <cstdlib>
#include <memory>
#include <string>
#include <string_view>
#include <thread>
#include <vector>

#include "../camera/peer_process.hpp"
#include "sen3bot/camera/camera.hpp"
#include "sen3bot/camera/decoder.hpp"
#include "sen3bot/camera/rtsp_client.hpp"

namespace {

using namespace sen3bot;
using namespace sen3bot::camera;

struct Recorder : EncodedFrameSink {
  std::vector<std::vector<std::uint8_t>> frames;
  VideoCodec codec = VideoCodec::unknown;
  std::size_t wanted = 0;
  void on_frame(const EncodedFrame& f) override {
    if (frames.size() < wanted) frames.emplace_back(f.data.begin(), f.data.end());
    codec = f.codec;
  }
};

void bench(const std::string& url, std::size_t frames_wanted, int repeat) {
  Recorder rec;
  rec.wanted = frames_wanted;
  RtspClientConfig config;
  config.url = url;
  auto client = RtspClient::create(config, rec);
  if (!client) {
    std::fprintf(stderr, "%s: %s\n", url.c_str(), client.error().c_str());
    return;
  }
  hal::PosixClock clock;
  const hal::Nanos deadline = clock.now() + hal::seconds(30);
  while (clock.now() < deadline && rec.frames.size() < frames_wanted) {
    (*client)->step(clock.now());
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  (*client)->stop(clock.now());
  if (rec.frames.empty()) {
    std::fprintf(stderr, "%s: no frames recorded: %s\n", url.c_str(), std::string((*client)->last_error()).c_str());
    return;
  }
  auto pool = FramePool::create(4, 1280, 720, PixelFormat::bgr8);
  double best_fps = 0;
  std::uint32_t w = 0;
  std::uint32_t h = 0;
  std::uint64_t bytes = 0;
  for (const auto& f : rec.frames) bytes += f.size();
  for (int r = 0; r < repeat; ++r) {
    auto decoder = FrameDecoder::create(rec.codec, DecoderOptions{});
    const auto t0 = std::chrono::steady_clock::now();
    for (const auto& f : rec.frames) {
      EncodedFrame e;
      e.codec = rec.codec;
      e.data = f;
      (void)(*decoder)->decode(e, **pool, 0);
    }
    const double s = std::chrono::duration<double>(std::chrono::steady_clock::now() - t0).count();
    best_fps = std::max(best_fps, static_cast<double>((*decoder)->stats().frames_decoded) / s);
    w = (*decoder)->stats().source_width_px;
    h = (*decoder)->stats().source_height_px;
  }
  // End-to-end latency on a live run: last RTP packet of a frame -> frame readable.
  CameraConfig cc;
  cc.rtsp.url = url;
  auto cam = Camera::create(cc, clock);
  (void)(*cam)->start();
  std::this_thread::sleep_for(std::chrono::seconds(4));
  const auto status = (*cam)->status();
  (*cam)->stop();
  std::printf(
      "{\"url\":\"%s\",\"codec\":\"%s\",\"width\":%u,\"height\":%u,\"frames\":%zu,\"mean_frame_bytes\":%llu,"
      "\"decode_fps_bgr\":%.1f,\"latency_ms_p50\":%.2f,\"latency_ms_max\":%.2f,\"pool_bytes\":%zu}\n",
      url.c_str(), to_string(rec.codec), w, h, rec.frames.size(),
      static_cast<unsigned long long>(bytes / rec.frames.size()), best_fps, status.latency_ms_p50, status.latency_ms_max,
      (*pool)->bytes());
}

}  // namespace

int main(int argc, char** argv) {
  std::string url;
  std::size_t frames = 60;
  int repeat = 3;
  for (int i = 1; i + 1 < argc; i += 2) {
    const std::string_view a = argv[i];
    if (a == "--url") url = argv[i + 1];
    if (a == "--frames") frames = static_cast<std::size_t>(std::atoi(argv[i + 1]));
    if (a == "--repeat") repeat = std::atoi(argv[i + 1]);
  }
  if (!url.empty()) {
    bench(url, frames, repeat);
    return 0;
  }
  sen3bot::camera::testing::PeerProcess peer(
      "/usr/bin/python3", {std::string(SEN3BOT_SOURCE_DIR) + "/tests/camera/peers/rtsp_server.py"});
  if (!peer.ready()) {
    std::fprintf(stderr, "camera_bench: %s\n", peer.error().c_str());
    return 1;
  }
  const std::string base = "rtsp://127.0.0.1:" + std::to_string(peer.port());
  bench(base + "/h264_fua", frames, repeat);
  bench(base + "/mjpeg720", frames, repeat);
  return 0;
}
