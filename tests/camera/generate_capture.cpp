// camera_capture_generate OUT.pcap OUT.expected RTSP_URL SECONDS
// Plays an RTSP stream through a recording TCP proxy and writes the conversation as pcap,
// plus what our depacketizer and decoder made of it (the replay test must match).
#include <chrono>
#include <cstdio>
#include <fstream>
#include <string>
#include <thread>

#include "pcap_io.hpp"
#include "replay_decode.hpp"
#include "sen3bot/camera/rtsp_client.hpp"
#include "sen3bot/hal/clock.hpp"
#include "sen3bot/hal/tcp.hpp"

using namespace sen3bot;

namespace {
struct NullSink : camera::EncodedFrameSink {
  void on_frame(const camera::EncodedFrame&) override {}
};
}  // namespace

int main(int argc, char** argv) {
  if (argc != 5) {
    std::fprintf(stderr, "usage: camera_capture_generate OUT.pcap OUT.expected RTSP_URL SECONDS\n");
    return 2;
  }
  auto target = camera::parse_rtsp_url(argv[3]);
  if (!target) return 2;
  auto listener = hal::TcpListener::listen("127.0.0.1", 0);
  const std::string via = "rtsp://127.0.0.1:" + std::to_string((*listener)->port()) + target->path;
  std::vector<camera::testing::PcapSegment> segments;
  std::thread proxy([&] {
    std::unique_ptr<hal::TcpStream> client;
    while (!client) {
      if (auto s = (*listener)->accept(); s && *s) client = std::move(*s);
      std::this_thread::sleep_for(std::chrono::milliseconds(1));
    }
    auto server = std::move(hal::TcpStream::connect(target->host, target->port, 2000).value());
    const auto start = std::chrono::steady_clock::now();
    const auto end = start + std::chrono::duration<double>(std::atof(argv[4]));
    std::uint8_t buf[65536];
    while (std::chrono::steady_clock::now() < end) {
      const auto t = std::chrono::duration_cast<std::chrono::microseconds>(std::chrono::steady_clock::now() - start).count();
      for (bool from_server : {false, true}) {
        hal::TcpStream& src = from_server ? *server : *client;
        hal::TcpStream& dst = from_server ? *client : *server;
        auto n = src.read(buf);
        if (!n || *n == 0) continue;
        segments.push_back({from_server, 1'700'000'000'000'000 + t, std::vector<std::uint8_t>(buf, buf + *n)});
        std::size_t sent = 0;
        while (sent < *n) {
          auto w = dst.write(std::span<const std::uint8_t>(buf + sent, *n - sent));
          if (!w) break;
          sent += *w;
        }
      }
      std::this_thread::sleep_for(std::chrono::microseconds(200));
    }
  });
  camera::RtspClientConfig config;
  config.url = via;
  NullSink sink;
  auto client = camera::RtspClient::create(config, sink);
  hal::PosixClock clock;
  const hal::Nanos deadline = clock.now() + hal::seconds(static_cast<std::int64_t>(std::atof(argv[4])) + 1);
  while (clock.now() < deadline) {
    (*client)->step(clock.now());
    std::this_thread::sleep_for(std::chrono::milliseconds(1));
  }
  proxy.join();
  camera::testing::PcapWriter writer(argv[1]);
  std::vector<std::uint8_t> server_stream;
  for (const auto& s : segments) {
    writer.add(s);
    if (s.from_server) server_stream.insert(server_stream.end(), s.payload.begin(), s.payload.end());
  }
  const auto summary = camera::testing::replay_decode(server_stream);
  std::ofstream(argv[2]) << summary.to_text();
  std::printf("%s", summary.to_text().c_str());
  return writer.ok() && summary.frames_decoded > 0 ? 0 : 1;
}
